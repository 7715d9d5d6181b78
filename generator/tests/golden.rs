//! Golden files: the complete output for the canonical variants (the paper's default, a
//! small spot-light variant with average visibility and rgba16float, the moment basis with
//! 6 moments, an interleaved raymarch variant, the spot-light minmax variant, raymarch
//! with `sampling = lowres`, scale 4, raymarch with `sampling = epipolar`, 256 slices, and
//! the spot-light partial-sum-tree variant at rank 8, the spot-light hybrid_volume variant,
//! the interleaved area_ivsv variant with 16 VPLs) in every target, kept
//! as reviewable text in `tests/golden/` (SPIR-V as `spirv-dis` text; its exact bytes are
//! pinned by the sha256 in the golden `manifest.json`). Any change to a template, to naga or
//! to the generator shows up here as a diff.
//!
//! Update on purpose with `SCATTER_BLESS=1 cargo test -p scatter-gen --test golden`.
//!
//! Also compile-checks the emitted C header (C11 and C++11, when a compiler is available)
//! and the Rust module (rustc), static layout asserts included.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use scatter_gen::{Family, FamilyCli, Generated, Request, Target, generate};

use common::{have, require, scratch};

fn canonical() -> Generated {
    let spot = Family::Prefiltered
        .variant(&[
            ("bases".into(), "16".into()),
            ("bases_per_thread".into(), "4".into()),
            ("regions".into(), "1".into()),
            ("visibility".into(), "average".into()),
            ("light".into(), "spot".into()),
            ("storage".into(), "rgba16float".into()),
        ])
        .unwrap_or_else(|e| panic!("{e}"));
    let moments = Family::Prefiltered
        .variant(&[
            ("basis".into(), "moments".into()),
            ("moments".into(), "6".into()),
        ])
        .unwrap_or_else(|e| panic!("{e}"));
    let march = Family::Raymarch
        .variant(&[
            ("samples".into(), "64".into()),
            ("interleave".into(), "4".into()),
            ("jitter".into(), "true".into()),
        ])
        .unwrap_or_else(|e| panic!("{e}"));
    let minmax = Family::Minmax
        .variant(&[("light".into(), "spot".into())])
        .unwrap_or_else(|e| panic!("{e}"));
    let lowres = Family::Raymarch
        .variant(&[
            ("sampling".into(), "lowres".into()),
            ("scale".into(), "4".into()),
        ])
        .unwrap_or_else(|e| panic!("{e}"));
    let epipolar = Family::Raymarch
        .variant(&[
            ("sampling".into(), "epipolar".into()),
            ("slices".into(), "256".into()),
        ])
        .unwrap_or_else(|e| panic!("{e}"));
    let pst = Family::PartialSumTree
        .variant(&[("light".into(), "spot".into()), ("rank".into(), "8".into())])
        .unwrap_or_else(|e| panic!("{e}"));
    let hybrid = Family::HybridVolume
        .variant(&[("light".into(), "spot".into())])
        .unwrap_or_else(|e| panic!("{e}"));
    let area = Family::AreaIvsv
        .variant(&[
            ("vpls".into(), "16".into()),
            ("interleave".into(), "2".into()),
        ])
        .unwrap_or_else(|e| panic!("{e}"));
    generate(&Request {
        variants: vec![
            Family::Prefiltered.default_variant(),
            spot,
            moments,
            march,
            minmax,
            lowres,
            epipolar,
            pst,
            hybrid,
            area,
        ],
        targets: Target::ALL.to_vec(),
    })
    .unwrap_or_else(|e| panic!("{e}"))
}

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

/// `spirv-dis` text of a SPIR-V binary.
fn disassemble(bytes: &[u8], name: &str) -> Vec<u8> {
    let dir = scratch("golden_spirv_dis");
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{e}"));
    let out = Command::new("spirv-dis")
        .arg("--no-color")
        .arg(&path)
        .output()
        .unwrap_or_else(|e| panic!("spirv-dis: {e}"));
    assert!(
        out.status.success(),
        "spirv-dis {name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

#[test]
fn canonical_variants_match_golden_files() {
    let bless = std::env::var("SCATTER_BLESS").is_ok_and(|v| v == "1");
    let spirv_dis = require(
        "spirv-dis",
        "spirv-tools",
        "canonical_variants_match_golden_files",
    );
    let generated = canonical();
    let mut expected: Vec<(String, Vec<u8>)> = Vec::new();
    for (path, bytes) in generated.all_files() {
        match path.strip_suffix(".spv") {
            Some(stem) if spirv_dis => {
                expected.push((format!("{stem}.spvasm"), disassemble(bytes, path)));
            }
            Some(_) => {}
            None => expected.push((path.to_owned(), bytes.to_vec())),
        }
    }
    let dir = golden_dir();
    if bless {
        std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{e}")) {
            let path = entry.unwrap_or_else(|e| panic!("{e}")).path();
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
            let keep = name.as_deref() == Some("README.md")
                || expected
                    .iter()
                    .any(|(p, _)| Some(p.as_str()) == name.as_deref());
            let spvasm_without_dis =
                !spirv_dis && name.as_deref().is_some_and(|n| n.ends_with(".spvasm"));
            if !keep && !spvasm_without_dis {
                std::fs::remove_file(&path).unwrap_or_else(|e| panic!("{e}"));
            }
        }
        for (path, bytes) in &expected {
            std::fs::write(dir.join(path), bytes).unwrap_or_else(|e| panic!("{e}"));
        }
        eprintln!(
            "blessed {} golden files in {}",
            expected.len(),
            dir.display()
        );
        return;
    }
    let mut problems = Vec::new();
    for (path, bytes) in &expected {
        match std::fs::read(dir.join(path)) {
            Err(_) => problems.push(format!("{path}: no golden file")),
            Ok(golden) if golden != *bytes => {
                let (g, n) = (
                    String::from_utf8_lossy(&golden),
                    String::from_utf8_lossy(bytes),
                );
                let line = g
                    .lines()
                    .zip(n.lines())
                    .position(|(a, b)| a != b)
                    .unwrap_or_else(|| g.lines().count().min(n.lines().count()));
                problems.push(format!(
                    "{path}: differs from line {}:\n  golden: {}\n  now:    {}",
                    line + 1,
                    g.lines().nth(line).unwrap_or("<end>"),
                    n.lines().nth(line).unwrap_or("<end>")
                ));
            }
            Ok(_) => {}
        }
    }
    for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{e}")) {
        let name = entry
            .unwrap_or_else(|e| panic!("{e}"))
            .file_name()
            .to_string_lossy()
            .into_owned();
        let spvasm_unchecked = !spirv_dis && name.ends_with(".spvasm");
        if name != "README.md" && !spvasm_unchecked && !expected.iter().any(|(p, _)| *p == name) {
            problems.push(format!("{name}: golden file no longer generated"));
        }
    }
    assert!(
        problems.is_empty(),
        "{}\n\nIf the change is intended, review it and rerun with \
         SCATTER_BLESS=1 cargo test -p scatter-gen --test golden",
        problems.join("\n")
    );
}

/// The C header compiles as C11 and C++11 with every warning an error, static asserts
/// included, and a program that includes it prints the sizes the manifest states.
#[test]
fn c_header_compiles_with_static_asserts() {
    let test = "c_header_compiles_with_static_asserts";
    let generated = canonical();
    let dir = scratch(test);
    for (path, bytes) in generated.all_files() {
        std::fs::write(dir.join(path), bytes).unwrap_or_else(|e| panic!("{e}"));
    }
    // The size the manifest states for the frame block.
    let manifest: serde_json::Value =
        serde_json::from_slice(&generated.manifest).unwrap_or_else(|e| panic!("{e}"));
    let frame_size = manifest["structs"]
        .as_array()
        .and_then(|s| s.iter().find(|s| s["c_type"] == "ScatterPrefilteredFrame"))
        .and_then(|s| s["size"].as_u64())
        .unwrap_or_else(|| panic!("no ScatterPrefilteredFrame in the manifest"));
    let c = dir.join("check.c");
    std::fs::write(
        &c,
        format!(
            "#include \"scatter_uniforms.h\"\nint main(void) {{ return sizeof(ScatterPrefilteredFrame) == {frame_size} ? 0 : 1; }}\n"
        ),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut compiled = 0;
    for (compiler, std, source) in [
        ("cc", "-std=c11", "check.c"),
        ("c++", "-std=c++11", "check.cc"),
    ] {
        if !have(compiler) {
            assert!(
                std::env::var_os("CI").is_none(),
                "{test}: `{compiler}` not found"
            );
            eprintln!(
                "\n!!! {test}: `{compiler}` not found, not compiling the header with it !!!\n"
            );
            continue;
        }
        if source == "check.cc" {
            std::fs::copy(&c, dir.join(source)).unwrap_or_else(|e| panic!("{e}"));
        }
        let exe = dir.join(format!("{source}.out"));
        let out = Command::new(compiler)
            .args([
                std,
                "-Wall",
                "-Wextra",
                "-Werror",
                "-pedantic",
                source,
                "-o",
            ])
            .arg(&exe)
            .current_dir(&dir)
            .output()
            .unwrap_or_else(|e| panic!("{compiler}: {e}"));
        assert!(
            out.status.success(),
            "{compiler} rejects scatter_uniforms.h:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let run = Command::new(&exe)
            .output()
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            run.status.success(),
            "sizeof(ScatterPrefilteredFrame) != {frame_size}"
        );
        compiled += 1;
    }
    if compiled == 0 {
        eprintln!("\n!!! SKIPPED {test}: no C or C++ compiler !!!\n");
    }

    // A wrong offset must fail to compile: the asserts are real.
    if have("cc") {
        let header = std::fs::read_to_string(dir.join("scatter_uniforms.h")).unwrap_or_default();
        let broken = header.replacen(
            "== 16, \"ScatterPrefilteredFrame.axis",
            "== 20, \"ScatterPrefilteredFrame.axis",
            1,
        );
        assert_ne!(header, broken, "the header has no assert on `axis`");
        std::fs::write(dir.join("broken.h"), broken).unwrap_or_else(|e| panic!("{e}"));
        let out = Command::new("cc")
            .args(["-std=c11", "-fsyntax-only", "-x", "c", "broken.h"])
            .current_dir(&dir)
            .output()
            .unwrap_or_else(|e| panic!("cc: {e}"));
        assert!(!out.status.success(), "a wrong offset assert compiled");
    }
}

/// The Rust module compiles with `-D warnings` (its `const` layout asserts run at compile
/// time), both as a module file and through `include!`.
#[test]
fn rust_module_compiles_with_layout_asserts() {
    let test = "rust_module_compiles_with_layout_asserts";
    if !require("rustc", "rustc", test) {
        return;
    }
    let generated = canonical();
    let dir = scratch(test);
    for (path, bytes) in generated.all_files() {
        std::fs::write(dir.join(path), bytes).unwrap_or_else(|e| panic!("{e}"));
    }
    let lib = dir.join("lib.rs");
    std::fs::write(
        &lib,
        "//! Uses the generated module.\n#![deny(missing_docs)]\n\n\
         /// As a module file.\npub mod uniforms;\n\n\
         /// Through include!.\npub mod included {\n    include!(\"scatter_uniforms.rs\");\n}\n\n\
         /// Size of the frame block.\npub const FRAME: usize = size_of::<uniforms::prefiltered::Frame>() + size_of::<included::prefiltered::Frame>();\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    std::fs::copy(dir.join("scatter_uniforms.rs"), dir.join("uniforms.rs"))
        .unwrap_or_else(|e| panic!("{e}"));
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let out = Command::new(rustc)
        .args([
            "--edition",
            "2024",
            "--crate-type",
            "lib",
            "--emit",
            "metadata",
            "-D",
            "warnings",
            "--out-dir",
        ])
        .arg(&dir)
        .arg(&lib)
        .output()
        .unwrap_or_else(|e| panic!("rustc: {e}"));
    assert!(
        out.status.success(),
        "rustc rejects scatter_uniforms.rs:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A wrong offset must fail to compile.
    let module = std::fs::read_to_string(dir.join("scatter_uniforms.rs")).unwrap_or_default();
    let broken = module.replacen(
        "offset_of!(Frame, axis) == 16",
        "offset_of!(Frame, axis) == 20",
        1,
    );
    assert_ne!(module, broken, "the module has no assert on `axis`");
    std::fs::write(dir.join("uniforms.rs"), broken).unwrap_or_else(|e| panic!("{e}"));
    let out = Command::new(std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into()))
        .args([
            "--edition",
            "2024",
            "--crate-type",
            "lib",
            "--emit",
            "metadata",
            "--out-dir",
        ])
        .arg(&dir)
        .arg(&lib)
        .output()
        .unwrap_or_else(|e| panic!("rustc: {e}"));
    assert!(!out.status.success(), "a wrong offset assert compiled");
}
