//! Property tests of the foreign engine's readers (`examples/foreign_engine`): its
//! `manifest.json` reader and everything that interprets the manifest's text without a GPU
//! (the variant's knobs, parameter constraints, size and dispatch formulas, per-frame
//! conditions), and the binary's input files (`frame.json`, PFM).
//!
//! Inputs: arbitrary bytes, and a real manifest (`scatter-gen` run in-process on two
//! variants) and a real `frame.json` with values replaced, keys deleted or added, and text
//! cut short. Properties: nothing panics; every rejection is one printable line; an
//! accepted frame file gives finite uniforms. Fixed RNG seeds; the case counts are printed.

use std::cell::Cell;
use std::io::Write as _;
use std::path::Path;
use std::time::Instant;

use glam::DVec3;
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};
use scatter_foreign_engine::condition::Condition;
use scatter_foreign_engine::files::{FrameFile, knobs_of, read_pfm};
use scatter_foreign_engine::formula::{Params, check_constraint, eval};
use scatter_foreign_engine::prefiltered::Sizes;
use scatter_foreign_engine::{EngineError, Manifest};
use scatter_frame::frame::{
    CameraDesc, FrameSettings, LightDesc, MediumDesc, ShadowMapDesc, ShadowProjectionDesc,
};
use scatter_gen::{FamilyVariant, Request, Target, generate};
use scatter_shaderlib::prefiltered::{LightKind, PrefilteredVariant, Rectification};
use serde_json::Value;

/// Cases of `Manifest::parse` on arbitrary bytes.
const RAW_MANIFEST_CASES: u32 = 1000;
/// Cases of the manifest reader and interpreters on edited real manifests.
const EDITED_MANIFEST_CASES: u32 = 2500;
/// Cases of `formula::eval` and `check_constraint` on arbitrary text.
const FORMULA_CASES: u32 = 1500;
/// Cases of `Condition::parse` on arbitrary text.
const CONDITION_CASES: u32 = 1000;
/// Cases of `read_pfm` on arbitrary and edited files.
const PFM_CASES: u32 = 1000;
/// Cases of `frame.json` parsing and set-up on edited files.
const FRAME_FILE_CASES: u32 = 2000;

fn run<S: Strategy>(
    name: &str,
    cases: u32,
    seed: u64,
    strategy: S,
    test: impl Fn(S::Value) -> Result<(), TestCaseError>,
) {
    let config = Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        max_shrink_iters: 4096,
        ..Config::default()
    };
    let mut runner = TestRunner::new(config);
    let start = Instant::now();
    TALLY.with(|t| t.set([0, 0]));
    if let Err(e) = runner.run(&strategy, test) {
        panic!("{name}: {e}");
    }
    let [accepted, rejected] = TALLY.with(Cell::get);
    // Past libtest's capture (it only catches print!/eprint!): the counts show in every run.
    let _ = writeln!(
        std::io::stderr().lock(),
        "fuzz_manifest::{name}: {cases} cases ({accepted} accepted, {rejected} rejected with \
         a clear error), 0 panics, {:.2} s",
        start.elapsed().as_secs_f64()
    );
}

thread_local! {
    /// Accepted and rejected cases of the running test (each test runs on its own thread).
    static TALLY: Cell<[u32; 2]> = const { Cell::new([0, 0]) };
}

fn tally(accepted: bool) {
    TALLY.with(|t| {
        let mut v = t.get();
        v[usize::from(!accepted)] += 1;
        t.set(v);
    });
}

/// A rejection: non-empty, one printable line.
fn one_line(e: &EngineError) -> Result<(), TestCaseError> {
    let m = e.to_string();
    prop_assert!(!m.trim().is_empty(), "empty error message");
    prop_assert!(
        !m.chars().any(char::is_control),
        "error message is not one printable line: {m:?}"
    );
    Ok(())
}

/// A JSON value to put somewhere it does not belong.
fn json_value() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        any::<i64>().prop_map(Value::from),
        any::<u64>().prop_map(Value::from),
        prop::sample::select(vec![
            0i64,
            1,
            -1,
            2,
            3,
            4,
            7,
            8,
            64,
            65_535,
            65_536,
            1 << 32
        ])
        .prop_map(Value::from),
        any::<f64>()
            .prop_map(|x| serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)),
        prop::sample::select(vec![
            "",
            "0",
            "1",
            "x",
            "screen.width",
            "rectified.height",
            "ceil(",
            "ceil(screen.width / 0)",
            "ceil(screen.width / 8",
            "18446744073709551615 * 2",
            "4294967296",
            "screen.width * screen.width * screen.width * screen.width * screen.width",
            "1..=max_texture_dimension_2d",
            "0..=max_compute_workgroups_per_dimension",
            "5..=3",
            "..=",
            "frame.proj.x > 0.5",
            "frame.proj.q > 0.5",
            "frame.proj > 0.5",
            "frame.proj.x.y > 0.5",
            "frame.nope.x > 0.5",
            "frame.proj.x >> 0.5",
            "frame.proj.x > zero",
            "frame. > 1",
            "frame.sizes.x == 3 (remark)",
            "frame.proj.x > 0.5 (",
            "slices.x > 1",
            "r32float",
            "rgba9unorm",
            "2d_array",
            "cube",
            "storage_texture",
            "read_write",
            "uniform_buffer",
            "engine",
            "prefiltered",
            "raymarch",
            "scatter-gen-manifest",
            "../../etc/passwd",
            "/abs/path",
            "a\nb",
            "\u{0}",
            "é",
            "ﬀ",
        ])
        .prop_map(|s| Value::String(s.to_owned())),
        any::<String>().prop_map(Value::String),
        Just(Value::Array(vec![])),
        Just(serde_json::json!([1, 2, 3, 4])),
        Just(serde_json::json!({})),
    ]
}

/// One edit of a JSON tree.
#[derive(Clone, Debug)]
enum Edit {
    Replace(Value),
    Delete,
    AddKey(String, Value),
    /// Duplicate an array element (more passes, bindings, resources).
    Duplicate,
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        4 => json_value().prop_map(Edit::Replace),
        2 => Just(Edit::Delete),
        1 => ("[a-z_]{1,8}", json_value()).prop_map(|(k, v)| Edit::AddKey(k, v)),
        1 => Just(Edit::Duplicate),
    ]
}

/// Applies `edit` at the node reached by following `path` (each index picks a child; the
/// walk stops at a leaf).
fn apply(root: &mut Value, path: &[Index], edit: Edit) {
    let mut node = root;
    for (depth, step) in path.iter().enumerate() {
        let last = depth + 1 == path.len();
        let n = match node {
            Value::Object(m) => m.len(),
            Value::Array(a) => a.len(),
            _ => 0,
        };
        if n == 0 {
            break;
        }
        let k = step.index(n);
        if last {
            match (&mut *node, &edit) {
                (Value::Object(m), Edit::Delete) => {
                    let key = m.keys().nth(k).cloned().unwrap_or_default();
                    m.remove(&key);
                    return;
                }
                (Value::Array(a), Edit::Delete) => {
                    a.remove(k);
                    return;
                }
                (Value::Array(a), Edit::Duplicate) => {
                    let v = a[k].clone();
                    a.insert(k, v);
                    return;
                }
                _ => {}
            }
        }
        node = match node {
            Value::Object(m) => match m.values_mut().nth(k) {
                Some(v) => v,
                None => return,
            },
            Value::Array(a) => &mut a[k],
            _ => return,
        };
    }
    match edit {
        Edit::Replace(v) => *node = v,
        Edit::AddKey(k, v) => match node {
            Value::Object(m) => {
                m.insert(k, v);
            }
            other => *other = v,
        },
        Edit::Delete | Edit::Duplicate => *node = Value::Null,
    }
}

/// A JSON number, hostile or ordinary.
fn json_number() -> impl Strategy<Value = Value> {
    let f = |x: f64| serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number);
    prop_oneof![
        2 => any::<f64>().prop_map(f),
        2 => (-100.0..100.0f64).prop_map(f),
        2 => prop::sample::select(vec![
            0.0, -0.0, 1.0, -1.0, 1e-320, 1e-30, 1e30, 1e300, -1e300, f64::MAX, 180.0, 90.0,
            89.0, 1e9, 1e10, 4294967295.0, 4294967296.0, 16384.0, 16385.0, 0.5, 2.0,
        ])
        .prop_map(f),
        1 => prop::sample::select(vec![0u64, 1, 3, 4, 16384, 16385, 4294967295, 4294967296, u64::MAX])
            .prop_map(Value::from),
    ]
}

/// Where an edit applies: a random walk from the root (each index picks a child), or one
/// node of the original tree picked uniformly (so deep leaves, such as a binding's
/// `struct_name` or a parameter's `name`, are hit as often as the top).
#[derive(Clone, Debug)]
enum At {
    Walk(Vec<Index>),
    Node(Index),
}

fn at() -> impl Strategy<Value = At> {
    prop_oneof![
        prop::collection::vec(any::<Index>(), 0..8).prop_map(At::Walk),
        any::<Index>().prop_map(At::Node),
    ]
}

/// JSON pointers of every node of `v`.
fn pointers(v: &Value, here: String, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            for (k, c) in m {
                let p = format!("{here}/{}", k.replace('~', "~0").replace('/', "~1"));
                pointers(c, p, out);
            }
        }
        Value::Array(a) => {
            for (i, c) in a.iter().enumerate() {
                pointers(c, format!("{here}/{i}"), out);
            }
        }
        _ => {}
    }
    out.push(here);
}

/// Applies `edit` at the node `pointer` names, if it still exists.
fn apply_at(root: &mut Value, pointer: &str, edit: Edit) {
    let (parent, last) = pointer.rsplit_once('/').unwrap_or(("", ""));
    match edit {
        Edit::Delete | Edit::Duplicate if !pointer.is_empty() => {
            let last = last.replace("~1", "/").replace("~0", "~");
            match root.pointer_mut(parent) {
                Some(Value::Object(m)) => {
                    m.remove(&last);
                }
                Some(Value::Array(a)) => {
                    if let Some(i) = last.parse::<usize>().ok().filter(|&i| i < a.len()) {
                        if matches!(edit, Edit::Duplicate) {
                            let v = a[i].clone();
                            a.insert(i, v);
                        } else {
                            a.remove(i);
                        }
                    }
                }
                _ => {}
            }
        }
        Edit::AddKey(k, v) => match root.pointer_mut(pointer) {
            Some(Value::Object(m)) => {
                m.insert(k, v);
            }
            Some(other) => *other = v,
            None => {}
        },
        Edit::Replace(v) => {
            if let Some(node) = root.pointer_mut(pointer) {
                *node = v;
            }
        }
        Edit::Delete | Edit::Duplicate => *root = Value::Null,
    }
}

type Edits = (Vec<(At, Edit)>, Option<Index>);

/// Up to three edits that mostly replace one number of the file, sometimes anything.
fn number_edits() -> impl Strategy<Value = Edits> {
    (
        prop::collection::vec(
            (
                at(),
                prop_oneof![6 => json_number().prop_map(Edit::Replace), 1 => edit()],
            ),
            1..4,
        ),
        prop::option::weighted(0.05, any::<Index>()),
    )
}

/// Up to four edits, then optionally cut the text short.
fn edits() -> impl Strategy<Value = Edits> {
    (
        prop::collection::vec((at(), edit()), 1..5),
        prop::option::weighted(0.15, any::<Index>()),
    )
}

fn edited(real: &Value, (list, cut): Edits) -> Vec<u8> {
    let mut nodes = Vec::new();
    pointers(real, String::new(), &mut nodes);
    let mut v = real.clone();
    for (at, e) in list {
        match at {
            At::Walk(path) => apply(&mut v, &path, e),
            At::Node(i) => apply_at(&mut v, &nodes[i.index(nodes.len())], e),
        }
    }
    let mut b = serde_json::to_vec_pretty(&v).unwrap_or_default();
    if let Some(i) = cut {
        b.truncate(i.index(b.len() + 1));
    }
    b
}

/// A real manifest: the default variant and a projective spot variant (skip conditions and
/// alternatives), WGSL and SPIR-V.
fn real_manifest() -> Value {
    let spot = PrefilteredVariant {
        light: LightKind::Spot,
        rectification: Rectification::Projective,
        regions: 2,
        ..PrefilteredVariant::default()
    };
    let generated = generate(&Request {
        variants: vec![
            FamilyVariant::Prefiltered(PrefilteredVariant::default()),
            FamilyVariant::Prefiltered(spot),
        ],
        targets: vec![Target::Wgsl, Target::Spirv],
    })
    .unwrap_or_else(|e| panic!("{e}"));
    serde_json::from_slice(&generated.manifest).unwrap_or_else(|e| panic!("{e}"))
}

/// Everything the engine reads from a parsed manifest before it touches a device: each
/// variant's knobs, its parameters' constraints (for several sizes), every size and
/// dispatch formula, every condition. Returns whether all of it was accepted.
fn interpret(m: &Manifest) -> Result<bool, TestCaseError> {
    let limits = scatter_runtime::wgpu::Limits::default();
    let mut all_ok = true;
    let mut check = |r: Result<(), EngineError>| -> Result<(), TestCaseError> {
        if let Err(e) = r {
            all_ok = false;
            one_line(&e)?;
        }
        Ok(())
    };
    let sizes = Sizes {
        screen: [64, 36],
        rectified: [64, 64],
        shadow_map: 128,
    };
    for v in &m.variants {
        check(knobs_of(m, &v.id).map(drop))?;
        check(m.variant(&v.id).map(drop))?;
        let mut params = sizes.params();
        for p in &v.parameters {
            // The sizes this test evaluates the formulas with must pass.
            let value = params.get(&p.name).unwrap_or(7);
            check(check_constraint(&p.name, value, &p.constraint, &limits))?;
            params.set(&p.name, value);
            // Sizes out of range: a rejection naming the parameter, never a panic.
            for value in [0, u64::MAX] {
                if let Err(e) = check_constraint(&p.name, value, &p.constraint, &limits) {
                    one_line(&e)?;
                }
            }
        }
        for r in &v.resources {
            if let Some(t) = &r.texture {
                for f in [&t.width, &t.height, &t.layers] {
                    check(eval(f, &params, &r.name).map(drop))?;
                }
            }
            if let Some(b) = &r.buffer {
                check(eval(&b.size_bytes, &params, &r.name).map(drop))?;
            }
        }
        for pass in &v.passes {
            for d in &pass.dispatch {
                check(eval(&d.workgroups, &params, &pass.kernel).map(drop))?;
            }
            if let Some(s) = &pass.skip_when {
                check(Condition::parse(s, m, v, "skip_when").map(drop))?;
            }
            for b in &pass.bindings {
                if let Some(a) = &b.alternative {
                    check(Condition::parse(&a.when, m, v, "alternative").map(drop))?;
                }
            }
        }
    }
    if let Err(e) = m.variant("no-such-variant") {
        one_line(&e)?;
    }
    Ok(all_ok)
}

fn parse_and_interpret(bytes: &[u8]) -> Result<(), TestCaseError> {
    match Manifest::parse(bytes, Path::new("shaders/manifest.json")) {
        Ok(m) => {
            let ok = interpret(&m)?;
            tally(ok);
        }
        Err(e) => {
            tally(false);
            one_line(&e)?;
            prop_assert!(
                e.to_string().contains("manifest.json"),
                "{e} does not name the file"
            );
        }
    }
    Ok(())
}

#[test]
fn manifest_on_arbitrary_bytes() {
    run(
        "manifest_bytes",
        RAW_MANIFEST_CASES,
        0x3a41_0001,
        prop_oneof![
            prop::collection::vec(any::<u8>(), 0..400),
            any::<String>().prop_map(String::into_bytes),
            Just(br#"{"schema":"scatter-gen-manifest","schema_version":1}"#.to_vec()),
            Just(br#"{"schema":"scatter-gen-manifest","schema_version":2}"#.to_vec()),
            Just(br#"{"schema":"x\ny"}"#.to_vec()),
            Just(br#"[]"#.to_vec()),
        ],
        |bytes| parse_and_interpret(&bytes),
    );
}

#[test]
fn manifest_on_edited_manifests() {
    let real = real_manifest();
    // The unedited manifest is accepted whole.
    let bytes = serde_json::to_vec(&real).unwrap_or_default();
    let m = Manifest::parse(&bytes, Path::new("manifest.json")).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        interpret(&m).unwrap_or_else(|e| panic!("{e}")),
        "the real manifest is not accepted whole"
    );
    run(
        "manifest_edited",
        EDITED_MANIFEST_CASES,
        0x3a41_0002,
        edits(),
        |e| parse_and_interpret(&edited(&real, e)),
    );
}

#[test]
fn formulas_and_constraints_on_arbitrary_text() {
    let text = prop_oneof![
        3 => "(ceil\\(|[0-9]{1,21}|screen\\.width|rectified\\.height|x| |\\*|/|\\)|\\(){0,14}",
        1 => any::<String>(),
        1 => "[0-9]{0,21}\\.\\.=([0-9]{0,21}|max_[a-z_0-9]{0,30})",
        1 => "[a-z^0-9]{0,8} = [0-9]{1,3}\\.\\.=[0-9a-z_]{0,30}",
    ];
    run(
        "formulas",
        FORMULA_CASES,
        0x3a41_0003,
        (text, any::<u64>(), any::<u64>()),
        |(f, a, b)| {
            let mut p = Params::default();
            p.set("screen.width", a);
            p.set("rectified.height", b);
            p.set("x", 0);
            let r = eval(&f, &p, "fuzz");
            tally(r.is_ok());
            if let Err(e) = &r {
                one_line(e)?;
            }
            let limits = scatter_runtime::wgpu::Limits::default();
            if let Err(e) = check_constraint("fuzz", a, &f, &limits) {
                one_line(&e)?;
            }
            Ok(())
        },
    );
}

#[test]
fn conditions_on_arbitrary_text() {
    let real = real_manifest();
    let m: Manifest = serde_json::from_value(real).unwrap_or_else(|e| panic!("{e}"));
    let text = prop_oneof![
        3 => "(frame|slices|depth|x)(\\.(proj|sizes|theta|eye|nope|x|y|z|w|)){0,3} (>|>=|<|<=|==|!=|=>|) ([0-9.e+-]{0,8}|nan|inf|x)( \\(.{0,10}\\)?)?",
        1 => any::<String>(),
    ];
    run(
        "conditions",
        CONDITION_CASES,
        0x3a41_0004,
        (text, any::<Index>()),
        |(t, v)| {
            let variant = &m.variants[v.index(m.variants.len())];
            let r = Condition::parse(&t, &m, variant, "fuzz");
            tally(r.is_ok());
            match r {
                Ok(c) => {
                    // Evaluating against too-short or absent bytes is an error, not a panic.
                    for bytes in [&[][..], &[0u8; 3][..], &[0u8; 4096][..]] {
                        if let Err(e) = c.eval(|_| Some(bytes)) {
                            one_line(&e)?;
                        }
                    }
                    if let Err(e) = c.eval(|_| None) {
                        one_line(&e)?;
                    }
                }
                Err(e) => one_line(&e)?,
            }
            Ok(())
        },
    );
}

/// A PFM: arbitrary bytes, or a header with hostile fields over some data.
fn pfm() -> impl Strategy<Value = Vec<u8>> {
    let token = |options: Vec<&'static str>| {
        prop_oneof![
            3 => prop::sample::select(options).prop_map(str::to_owned),
            1 => "[0-9a-zA-Z.+-]{0,12}",
        ]
    };
    prop_oneof![
        1 => prop::collection::vec(any::<u8>(), 0..200),
        // Valid files (either endianness), some with a byte too many or too few.
        2 => (1..6u32, 1..6u32, any::<bool>(), -1..=1i32).prop_map(|(w, h, little, extra)| {
            let scale = if little { "-1.0" } else { "1.0" };
            let mut b = format!("Pf\n{w} {h}\n{scale}\n").into_bytes();
            let n = (4 * w * h) as i32 + extra;
            b.extend((0..n).map(|i| i as u8));
            b
        }),
        // Sizes whose byte count overflows.
        1 => prop::sample::select(vec![
            "Pf\n2147483648 2147483648\n-1.0\n",
            "Pf\n4294967295 4294967295\n-1.0\n",
            "Pf\n4294967295 1073741825\n-1.0\n",
            "Pf\n1073741824 4\n-1.0\n",
            "Pf\n65536 65536\n-1.0\n",
        ])
        .prop_map(|h| h.as_bytes().to_vec()),
        4 => (
            token(vec!["Pf", "PF", "pf", "P5", ""]),
            token(vec![
                "0", "1", "2", "3", "-1", "4294967295", "4294967296", "2147483648", "65536",
            ]),
            token(vec![
                "0", "1", "2", "3", "-1", "4294967295", "4294967296", "2147483648", "65536",
            ]),
            token(vec!["-1.0", "1.0", "0", "-0", "nan", "inf", "-inf", "x", ""]),
            prop::sample::select(vec![" ", "\n", "\t", "\r\n", ""]),
            prop::collection::vec(any::<u8>(), 0..64),
        )
            .prop_map(|(magic, w, h, scale, sep, data)| {
                let mut b = format!("{magic}{sep}{w} {h}{sep}{scale}\n").into_bytes();
                b.extend_from_slice(&data);
                b
            }),
    ]
}

#[test]
fn pfm_reader_on_hostile_files() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz_manifest_pfm");
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let path = dir.join("input.pfm");
    run("pfm", PFM_CASES, 0x3a41_0005, pfm(), |bytes| {
        std::fs::write(&path, &bytes).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let r = read_pfm(&path);
        tally(r.is_ok());
        match r {
            Ok((w, h, v)) => prop_assert_eq!(v.len() as u64, u64::from(w) * u64::from(h)),
            Err(e) => {
                one_line(&e)?;
                prop_assert!(e.to_string().contains("input.pfm"), "{e}");
            }
        }
        Ok(())
    });
}

/// A valid `frame.json` of a frame with `light` (its shadow map of that light's kind).
fn real_frame_file(light: LightKind) -> Value {
    let forward = DVec3::new(0.1, -0.2, -1.0).normalize();
    let right = forward.cross(DVec3::Y).normalize();
    let up = right.cross(forward);
    let camera = CameraDesc {
        position: DVec3::new(0.0, 2.0, 8.0),
        forward,
        right,
        up,
        tan_half_fov_y: 0.5,
        near: 0.1,
        far: 50.0,
    };
    let travel = DVec3::new(0.3, -1.0, 0.2).normalize();
    let basis = {
        let r = travel.cross(DVec3::X).normalize();
        [r, r.cross(travel), travel]
    };
    let light = match light {
        LightKind::Directional => LightDesc::Directional {
            direction: travel,
            color: [1.0, 1.0, 1.0],
        },
        LightKind::Spot => LightDesc::Spot {
            position: DVec3::new(2.0, 10.0, 0.0),
            direction: travel,
            inner_deg: 20.0,
            outer_deg: 30.0,
            color: [50.0; 3],
        },
        LightKind::Area => LightDesc::Area(scatter_frame::area_light::AreaLightDesc {
            position: DVec3::new(2.0, 10.0, 0.0),
            direction: travel,
            up: None,
            shape: scatter_frame::area_light::AreaShapeDesc::Disk { radius: 0.5 },
            inner_deg: 20.0,
            outer_deg: 30.0,
            radiance: [50.0; 3],
            two_sided: false,
        }),
    };
    // The light's kind of map: orthographic for the sun, perspective from a spot's position.
    let (origin, projection) = match light {
        LightDesc::Directional { .. } => (
            DVec3::new(0.0, 20.0, 0.0),
            ShadowProjectionDesc::Orthographic {
                x0: -20.0,
                x1: 20.0,
                y0: -20.0,
                y1: 20.0,
            },
        ),
        _ => (
            DVec3::new(2.0, 10.0, 0.0),
            ShadowProjectionDesc::Perspective {
                tan_half: 30f64.to_radians().tan(),
            },
        ),
    };
    let shadow = ShadowMapDesc {
        origin,
        basis,
        projection,
        near: 0.0,
        far: 60.0,
        size: 64,
        bias_texels: 1.5,
    };
    let file = FrameFile::new(
        Sizes {
            screen: [32, 18],
            rectified: [64, 32],
            shadow_map: 64,
        },
        &camera,
        &light,
        &MediumDesc {
            sigma_t: 0.1,
            albedo: 0.8,
            g: 0.3,
        },
        &shadow,
        &FrameSettings::for_screen(32, 18),
    );
    serde_json::to_value(file).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn frame_file_on_edited_files() {
    let files = [
        (
            real_frame_file(LightKind::Directional),
            PrefilteredVariant::default(),
        ),
        (
            real_frame_file(LightKind::Spot),
            PrefilteredVariant {
                light: LightKind::Spot,
                rectification: Rectification::Projective,
                ..PrefilteredVariant::default()
            },
        ),
    ];
    for (f, v) in &files {
        let file: FrameFile = serde_json::from_value(f.clone()).unwrap_or_else(|e| panic!("{e}"));
        file.prepare(v)
            .unwrap_or_else(|e| panic!("the unedited frame.json: {e}"));
    }
    run(
        "frame_file",
        FRAME_FILE_CASES,
        0x3a41_0006,
        (any::<Index>(), number_edits()),
        |(which, e)| {
            let (real, variant) = &files[which.index(files.len())];
            let bytes = edited(real, e);
            let file = match serde_json::from_slice::<FrameFile>(&bytes) {
                Ok(f) => f,
                Err(e) => {
                    tally(false);
                    // What files::run_dir reports: serde's one-line message.
                    let e = EngineError::InputFile {
                        path: "frame.json".into(),
                        reason: e.to_string(),
                    };
                    return one_line(&e);
                }
            };
            let r = file.prepare(variant);
            tally(r.is_ok());
            match r {
                Ok(frame) => {
                    let bytes: &[u8] = bytemuck::bytes_of(&frame.uniforms);
                    let floats: Vec<f32> = bytes
                        .chunks_exact(4)
                        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                        .collect();
                    // sizes and sizes2 (vectors 19 and 20) hold integers.
                    for (i, x) in floats.iter().enumerate() {
                        if !(76..84).contains(&i) {
                            prop_assert!(x.is_finite(), "uniform float {i} = {x}");
                        }
                    }
                }
                Err(e) => one_line(&e)?,
            }
            Ok(())
        },
    );
}
