//! The `scatter-gen` binary end to end: bad input (exit 2, one line, nothing written), an
//! unwritable output directory, `--check`, determinism, ownership of files, config files,
//! `list` and `--help`.

mod common;

use std::fs;

use common::{files, scatter_gen, scratch, text};

const DEFAULT_ID: &str = "m32-t16-r4-weighted-directional-rgba8unorm-epipolar";

/// Runs scatter-gen expecting failure with `code`; returns the single stderr line.
fn fails(args: &[&str], code: i32) -> String {
    let out = scatter_gen(args);
    let (stdout, stderr) = text(&out);
    assert_eq!(
        out.status.code(),
        Some(code),
        "{args:?}: stdout {stdout} stderr {stderr}"
    );
    let lines: Vec<_> = stderr.lines().collect();
    assert_eq!(
        lines.len(),
        1,
        "{args:?}: expected one line, got {stderr:?}"
    );
    lines[0].to_owned()
}

#[test]
fn bad_knobs_exit_2_with_one_line_and_write_nothing() {
    let dir = scratch("bad_knobs");
    let out = dir.join("out");
    let o = out.to_str().unwrap_or_default();
    let cases: &[(&[&str], &str)] = &[
        (
            &["--bases", "30"],
            "bases must be a multiple of 4 in 4..=128, got 30",
        ),
        (
            &["--bases", "132"],
            "bases must be a multiple of 4 in 4..=128, got 132",
        ),
        (
            &["--bases", "abc"],
            "bases must be a multiple of 4 in 4..=128, got abc",
        ),
        (
            &["--bases", "16", "--bases-per-thread", "12"],
            "bases_per_thread must be a multiple of 4 that divides bases = 16, got 12",
        ),
        (&["--regions", "17"], "regions must be in 1..=16, got 17"),
        (&["--regions", "0"], "regions must be in 1..=16, got 0"),
        (
            &["--regions", "9", "--rectification", "projective"],
            "regions must be in 1..=8 with rectification = projective (its frame holds 9 \
             region boundaries; up to 16 with epipolar), got 9",
        ),
        (
            &["--visibility", "median"],
            "visibility must be average | weighted, got median",
        ),
        (
            &["--light", "area"],
            "light must be directional | spot (an area light is rendered by the area_ivsv family, or as its point limit, a spot), got area",
        ),
        (
            &["--storage", "rgba8"],
            "storage must be rgba16float | rgba32float | rgba8unorm, got rgba8",
        ),
        (
            &["--target", "wgsl,dxil"],
            "target must be wgsl | glsl | spirv | hlsl | msl, got dxil",
        ),
        (
            &["--target", "wgsl,wgsl"],
            "target wgsl is named twice: name each target once",
        ),
        (
            &["--target", "spirv", "--target", "glsl,spirv"],
            "target spirv is named twice: name each target once",
        ),
        (
            &["--family", "raytrace"],
            "family must be area_ivsv | hybrid_volume | minmax | partial_sum_tree | prefiltered | raymarch, got raytrace",
        ),
    ];
    for (args, message) in cases {
        let mut all = args.to_vec();
        all.extend(["--out", o]);
        let line = fails(&all, 2);
        assert_eq!(line, format!("error: {message}"), "{args:?}");
        assert!(!out.exists(), "{args:?} created {}", out.display());
    }
    // Whatever the variant says about a knob passes through unchanged (projective
    // rectification may or may not be implemented).
    let projective = dir.join("projective");
    let p = projective.to_str().unwrap_or_default();
    let out_p = scatter_gen(&["--rectification", "projective", "--out", p]);
    if out_p.status.code() == Some(2) {
        let (_, stderr) = text(&out_p);
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            stderr.starts_with("error: rectification must be"),
            "{stderr}"
        );
        assert!(!projective.exists());
    } else {
        assert!(out_p.status.success(), "{:?}", text(&out_p));
    }
    // clap's own errors are cut to one line too.
    let line = fails(&["--colour", "red", "--out", o], 2);
    assert!(line.contains("--colour"), "{line}");
    let line = fails(&["--bases", "32"], 2);
    assert!(line.contains("--out"), "{line}");
    assert!(!out.exists());
}

#[test]
fn unwritable_out_dir_fails_with_one_line() {
    let dir = scratch("unwritable");
    let file = dir.join("a_file");
    fs::write(&file, "not a directory").unwrap_or_else(|e| panic!("{e}"));
    let out = file.join("shaders");
    let line = fails(&["--out", out.to_str().unwrap_or_default()], 1);
    assert!(line.starts_with("error: "), "{line}");
    assert!(line.contains("a_file"), "{line}");
    // The out path itself is a file.
    let line = fails(&["--out", file.to_str().unwrap_or_default()], 1);
    assert!(line.contains("not a directory"), "{line}");
    assert_eq!(
        fs::read_to_string(&file).unwrap_or_default(),
        "not a directory"
    );
}

#[test]
fn same_input_same_bytes_and_nothing_rewritten() {
    let dir = scratch("determinism");
    let (a, b) = (dir.join("a"), dir.join("b"));
    for d in [&a, &b] {
        let out = scatter_gen(&[
            "--target",
            "wgsl,glsl,spirv,hlsl,msl",
            "--light",
            "spot",
            "--out",
            d.to_str().unwrap_or_default(),
        ]);
        assert!(out.status.success(), "{:?}", text(&out));
    }
    let (fa, fb) = (files(&a), files(&b));
    assert_eq!(
        fa.len(),
        5 * 5 + 3,
        "{:?}",
        fa.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    assert!(fa == fb, "two runs differ");
    // A third run into the same directory rewrites nothing.
    let out = scatter_gen(&[
        "--target",
        "msl,hlsl,spirv,glsl,wgsl",
        "--light",
        "spot",
        "--out",
        a.to_str().unwrap_or_default(),
    ]);
    let (stdout, _) = text(&out);
    assert!(
        stdout.contains(": 0 written, 28 unchanged, 0 removed"),
        "{stdout}"
    );
    assert!(files(&a) == fb);
}

#[test]
fn check_names_stale_files() {
    let dir = scratch("check");
    let out = dir.join("shaders");
    let o = out.to_str().unwrap_or_default();
    // An empty directory: everything is missing.
    let r = scatter_gen(&["--out", o, "--check"]);
    assert_eq!(r.status.code(), Some(1));
    assert!(text(&r).0.contains("(missing)"));
    assert!(!out.exists(), "--check wrote something");

    assert!(scatter_gen(&["--out", o]).status.success());
    let r = scatter_gen(&["--out", o, "--check"]);
    assert_eq!(r.status.code(), Some(0), "{:?}", text(&r));
    assert!(
        text(&r).0.contains("up to date (18 files)"),
        "{:?}",
        text(&r)
    );

    // One edited file, one deleted file.
    let wgsl = format!("scatter.{DEFAULT_ID}.wgsl");
    let spv = format!("rectify.{DEFAULT_ID}.spv");
    fs::write(out.join(&wgsl), "// edited\n").unwrap_or_else(|e| panic!("{e}"));
    fs::remove_file(out.join(&spv)).unwrap_or_else(|e| panic!("{e}"));
    let r = scatter_gen(&["--out", o, "--check"]);
    let (stdout, _) = text(&r);
    assert_eq!(r.status.code(), Some(1), "{stdout}");
    let stale: Vec<_> = stdout.lines().collect();
    assert_eq!(stale.len(), 2, "{stdout}");
    assert!(
        stale
            .iter()
            .any(|l| l.contains(&wgsl) && l.ends_with("(differs)"))
    );
    assert!(
        stale
            .iter()
            .any(|l| l.contains(&spv) && l.ends_with("(missing)"))
    );

    // Another variant: every kernel file differs by name; the old ones are left over.
    assert!(scatter_gen(&["--out", o]).status.success());
    let r = scatter_gen(&["--out", o, "--check", "--bases", "16"]);
    let (stdout, _) = text(&r);
    assert_eq!(r.status.code(), Some(1));
    assert!(stdout.contains("manifest.json (differs)"), "{stdout}");
    assert_eq!(
        stdout.matches("(no longer generated)").count(),
        15,
        "{stdout}"
    );
    assert_eq!(stdout.matches("(missing)").count(), 15, "{stdout}");
}

#[test]
fn never_overwrites_or_deletes_foreign_files_without_force() {
    let dir = scratch("foreign");
    let out = dir.join("shaders");
    let o = out.to_str().unwrap_or_default();
    fs::create_dir_all(&out).unwrap_or_else(|e| panic!("{e}"));
    // A file with one of our names but no manifest: foreign.
    fs::write(out.join("scatter_uniforms.h"), "// mine\n").unwrap_or_else(|e| panic!("{e}"));
    fs::write(out.join("notes.txt"), "keep me\n").unwrap_or_else(|e| panic!("{e}"));
    let line = fails(&["--out", o], 1);
    assert!(line.contains("refusing to overwrite"), "{line}");
    assert!(line.contains("scatter_uniforms.h"), "{line}");
    assert!(line.contains("--force"), "{line}");
    let names: Vec<_> = files(&out).into_iter().map(|f| f.0).collect();
    assert_eq!(
        names,
        ["notes.txt", "scatter_uniforms.h"],
        "wrote something"
    );

    // --force takes it over; the unrelated file stays.
    assert!(scatter_gen(&["--out", o, "--force"]).status.success());
    assert_eq!(files(&out).len(), 19);

    // A foreign file with a kernel's name next to our manifest: refused.
    let stray = out.join("prefilter.m16-t16-r4-weighted-directional-rgba8unorm-epipolar.wgsl");
    fs::write(&stray, "// someone else's\n").unwrap_or_else(|e| panic!("{e}"));
    let line = fails(&["--out", o, "--bases", "16"], 1);
    assert!(line.contains("not listed in manifest.json"), "{line}");
    assert_eq!(
        fs::read_to_string(&stray).unwrap_or_default(),
        "// someone else's\n"
    );
    fs::remove_file(&stray).unwrap_or_else(|e| panic!("{e}"));

    // Our own files of an earlier variant are replaced; notes.txt survives.
    let r = scatter_gen(&["--out", o, "--bases", "16"]);
    assert!(r.status.success(), "{:?}", text(&r));
    assert!(text(&r).0.contains("15 removed"), "{:?}", text(&r));
    let names: Vec<_> = files(&out).into_iter().map(|f| f.0).collect();
    assert!(names.contains(&"notes.txt".to_owned()));
    assert!(!names.iter().any(|n| n.contains(DEFAULT_ID)), "{names:?}");
    assert_eq!(
        fs::read_to_string(out.join("notes.txt")).unwrap_or_default(),
        "keep me\n"
    );

    // A manifest.json that is not ours.
    let other = dir.join("other");
    fs::create_dir_all(&other).unwrap_or_else(|e| panic!("{e}"));
    fs::write(other.join("manifest.json"), "{\"name\": \"my-app\"}\n")
        .unwrap_or_else(|e| panic!("{e}"));
    let line = fails(&["--out", other.to_str().unwrap_or_default()], 1);
    assert!(line.contains("not a scatter-gen manifest"), "{line}");
    assert_eq!(files(&other).len(), 1);
}

#[test]
fn config_emits_exactly_its_variants() {
    let dir = scratch("config");
    let config = dir.join("variants.toml");
    fs::write(
        &config,
        "targets = [\"wgsl\", \"spirv\"]\n\n[[variant]]\nlight = \"directional\"\n\n\
         [[variant]]\nlight = \"spot\"\nbases = 16\nregions = 1\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let out = dir.join("shaders");
    let c = config.to_str().unwrap_or_default();
    let o = out.to_str().unwrap_or_default();
    let r = scatter_gen(&["--config", c, "--out", o]);
    assert!(r.status.success(), "{:?}", text(&r));
    let names: Vec<_> = files(&out).into_iter().map(|f| f.0).collect();
    // 2 variants x 5 kernels x 2 targets + manifest + C header + Rust module.
    assert_eq!(names.len(), 2 * 5 * 2 + 3, "{names:?}");
    let spot = "m16-t16-r1-weighted-spot-rgba8unorm-epipolar";
    for k in [
        "depth_columns",
        "slice_fit",
        "rectify",
        "prefilter",
        "scatter",
    ] {
        for id in [DEFAULT_ID, spot] {
            for ext in ["wgsl", "spv"] {
                let name = format!("{k}.{id}.{ext}");
                assert!(names.contains(&name), "{name} missing: {names:?}");
            }
        }
    }
    // --target overrides the file's targets; --check agrees with a fresh run.
    let r = scatter_gen(&["--config", c, "--out", o, "--check"]);
    assert_eq!(r.status.code(), Some(0), "{:?}", text(&r));
    let r = scatter_gen(&["--config", c, "--target", "glsl", "--out", o, "--check"]);
    assert_eq!(r.status.code(), Some(1));

    // Bad config: exit 2, one line naming the file, the table and the knob.
    fs::write(
        &config,
        "[[variant]]\nlight = \"spot\"\n[[variant]]\nregions = 20\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let line = fails(&["--config", c, "--out", o], 2);
    assert!(
        line.contains("variants.toml: variant 2: regions must be in 1..=16, got 20"),
        "{line}"
    );
    // Slips refused with one line naming the file and the table or knob: the same variant
    // twice, a target twice, a number or boolean written as a string.
    let bad: &[(&str, &str)] = &[
        (
            "[[variant]]\nlight = \"spot\"\n[[variant]]\nlight = \"spot\"\nregions = 4\n",
            "variants.toml: variant 2: same variant as variant 1 \
             (prefiltered::m32-t16-r4-weighted-spot-rgba8unorm-epipolar): list each variant once",
        ),
        (
            "targets = [\"wgsl\", \"wgsl\"]\n[[variant]]\n",
            "variants.toml: target wgsl is named twice: name each target once",
        ),
        (
            "[[variant]]\nbases = \"32\"\n",
            "variants.toml: variant 1: bases must be an integer, got the string \"32\" \
             (write bases = 32, without quotes)",
        ),
        (
            "[[variant]]\n[[variant]]\nregions = \"3\"\n",
            "variants.toml: variant 2: regions must be an integer, got the string \"3\" \
             (write regions = 3, without quotes)",
        ),
        (
            "[[variant]]\nfamily = \"raymarch\"\njitter = \"true\"\n",
            "variants.toml: variant 1: jitter must be a boolean (true | false), got the string \
             \"true\" (write jitter = true, without quotes)",
        ),
    ];
    let before = files(&out);
    for (text, message) in bad {
        fs::write(&config, text).unwrap_or_else(|e| panic!("{e}"));
        let line = fails(&["--config", c, "--out", o], 2);
        assert!(
            line.starts_with("error: ") && line.ends_with(message),
            "{line}"
        );
        assert!(files(&out) == before, "{text:?} changed {}", out.display());
    }
    // Knob flags cannot be mixed with --config.
    let line = fails(&["--config", c, "--bases", "16", "--out", o], 2);
    assert!(line.contains("--config"), "{line}");
    let line = fails(
        &[
            "--config",
            dir.join("missing.toml").to_str().unwrap_or_default(),
            "--out",
            o,
        ],
        2,
    );
    assert!(line.contains("missing.toml"), "{line}");
}

#[test]
fn list_and_help_document_every_knob() {
    let r = scatter_gen(&["list"]);
    assert!(r.status.success());
    let (list, _) = text(&r);
    assert!(list.contains("family prefiltered"), "{list}");
    assert!(
        list.contains(
            "kernels (pass order): depth_columns, slice_fit, rectify, prefilter, scatter"
        ),
        "{list}"
    );
    let r = scatter_gen(&["--help"]);
    assert!(r.status.success());
    let (help, _) = text(&r);
    for k in scatter_gen::FamilyCli::knobs(scatter_gen::Family::Prefiltered) {
        let flag = format!("--{}", k.flag());
        assert!(list.contains(&flag), "list lacks {flag}");
        assert!(list.contains(&k.allowed), "list lacks {}", k.allowed);
        assert!(help.contains(&flag), "help lacks {flag}");
        assert!(help.contains(&k.allowed), "help lacks {}", k.allowed);
        assert!(
            help.contains(&format!("[default (paper): {}]", k.default)),
            "help lacks the default of {flag}"
        );
    }
    for t in ["wgsl", "glsl", "spirv", "hlsl", "msl"] {
        assert!(list.contains(t) && help.contains(t), "{t}");
    }
}
