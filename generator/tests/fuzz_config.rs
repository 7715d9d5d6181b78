//! Property tests of everything in the generator that reads user input: the knob values of
//! every family (`Family::variant`, what the CLI flags and the config file go through), the
//! enum knobs' `FromStr`, `PrefilteredVariant::validate` / `RaymarchVariant::validate`, the family and
//! target names, `config::parse` on arbitrary text and on valid `variants.toml` files with
//! one fault planted, the ownership manifest reader (`output::owned_files`) on arbitrary and
//! mutated `manifest.json` files, and the `scatter-gen` binary on arbitrary command lines.
//!
//! Properties: nothing panics; what is accepted validates; every rejection is one printable
//! line that names the knob, key or file at fault. Fixed RNG seeds: every run checks the
//! same cases. The case counts are printed.

mod common;

use std::cell::Cell;
use std::io::Write as _;
use std::time::Instant;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};
use scatter_gen::family::{FamilyVariant, KnobType};
use scatter_gen::{Family, FamilyCli, GenError, Request, Target, config, generate, output};
use scatter_shaderlib::prefiltered::variant::printable;
use scatter_shaderlib::prefiltered::{
    LightKind, PrefilteredVariant, Rectification, Storage, VisibilityMode,
};
use scatter_shaderlib::raymarch::RaymarchVariant;
use serde_json::Value;

/// Cases of `Family::variant` on knob lists.
const KNOB_CASES: u32 = 3000;
/// Cases of the enum knobs', family and target parsers on strings.
const NAME_CASES: u32 = 1500;
/// Cases of `validate` on arbitrary knob numbers.
const VALIDATE_CASES: u32 = 1500;
/// Cases of `config::parse` on arbitrary and TOML-like text.
const CONFIG_TEXT_CASES: u32 = 1500;
/// Cases of `config::parse` on generated files, some cut short.
const CONFIG_FILE_CASES: u32 = 2000;
/// Cases of `config::parse` on a valid file with one planted fault (or none).
const CONFIG_FAULT_CASES: u32 = 2000;
/// Cases of `output::owned_files` on arbitrary and mutated manifests.
const OWNED_CASES: u32 = 1000;
/// Cases of the `scatter-gen` binary on arbitrary command lines (a process each).
const CLI_CASES: u32 = 400;

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
        "fuzz_config::{name}: {cases} cases ({accepted} accepted, {rejected} rejected with a \
         clear error), 0 panics, {:.2} s",
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

/// A rejection's message: non-empty and one printable line.
fn one_line(message: &str) -> Result<(), TestCaseError> {
    prop_assert!(!message.trim().is_empty(), "empty error message");
    prop_assert!(
        !message.chars().any(char::is_control),
        "error message is not one printable line: {message:?}"
    );
    Ok(())
}

/// Every knob name of every family, plus `family`.
fn known_names() -> Vec<&'static str> {
    let mut names: Vec<&'static str> = Family::ALL
        .iter()
        .flat_map(|f| f.knobs())
        .map(|k| k.name)
        .collect();
    names.push("family");
    names.sort_unstable();
    names.dedup();
    names
}

fn knob_name() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => prop::sample::select(known_names()).prop_map(str::to_owned),
        1 => prop::sample::select(vec![
            "Bases", "bases ", " bases", "base", "bases-per-thread", "bases_per_thread\n", "",
            "regions\u{0}", "ｂａｓｅｓ", "sample", "jitter\r", "light\u{1b}[31m",
        ])
        .prop_map(str::to_owned),
        1 => "[a-z_]{1,16}",
        1 => any::<String>(),
    ]
}

fn knob_value() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => prop::sample::select(vec![
            "4", "8", "12", "16", "32", "64", "128", "0", "1", "2", "3", "5", "9", "132", "256",
            "1024", "1025", "-4", "+32", " 32", "32 ", "32.0", "3e1", "0x20", "4294967296",
            "18446744073709551616", "", " ", "true", "false", "on", "off", "TRUE", "average",
            "weighted", "directional", "spot", "rgba8unorm", "rgba16float", "rgba32float",
            "epipolar", "projective", "Spot", " spot", "spot\n", "３２", "NaN", "inf",
            "prefiltered", "raymarch", "minmax", "partial_sum_tree", "area", "area_ivsv",
        ])
        .prop_map(str::to_owned),
        2 => (0u32..300).prop_map(|n| n.to_string()),
        1 => any::<u32>().prop_map(|n| n.to_string()),
        1 => any::<i64>().prop_map(|n| n.to_string()),
        2 => any::<String>(),
    ]
}

fn validates(v: &FamilyVariant) -> bool {
    match v {
        FamilyVariant::HybridVolume(v) => v.validate().is_ok(),
        FamilyVariant::Minmax(v) => v.validate().is_ok(),
        FamilyVariant::PartialSumTree(v) => v.validate().is_ok(),
        FamilyVariant::Prefiltered(v) => v.validate().is_ok(),
        FamilyVariant::Raymarch(v) => v.validate().is_ok(),
        FamilyVariant::AreaIvsv(v) => v.validate().is_ok(),
    }
}

/// What the CLI flags and config tables go through: every family on lists of
/// `(knob, value)` pairs.
#[test]
fn family_variant_on_knob_lists() {
    run(
        "family_variant",
        KNOB_CASES,
        0x6e11_0001,
        (
            prop::sample::select(Family::ALL.to_vec()),
            prop::collection::vec((knob_name(), knob_value()), 0..6),
        ),
        |(family, knobs)| {
            let result = family.variant(&knobs);
            tally(result.is_ok());
            match result {
                Ok(v) => {
                    prop_assert_eq!(v.family(), family);
                    prop_assert!(validates(&v), "accepted an invalid variant {v:?}");
                    // Every knob named was one of the family's.
                    let names: Vec<_> = family.knobs().iter().map(|k| k.name).collect();
                    for (k, _) in &knobs {
                        prop_assert!(names.contains(&k.as_str()), "accepted knob {k:?}");
                    }
                }
                Err(e) => {
                    let m = e.to_string();
                    one_line(&m)?;
                    prop_assert_eq!(e.exit_code(), 2, "bad input must exit 2: {}", m);
                    let family_knobs: Vec<_> = family.knobs().iter().map(|k| k.name).collect();
                    let named = knobs.iter().any(|(k, _)| m.contains(&*printable(k)))
                        || family_knobs.iter().any(|k| m.contains(k));
                    prop_assert!(named, "{m:?} names no knob of {knobs:?}");
                }
            }
            Ok(())
        },
    );
}

fn name_text() -> impl Strategy<Value = String> {
    let names: Vec<String> = VisibilityMode::ALL
        .iter()
        .map(|v| v.name())
        .chain(LightKind::ALL.iter().map(|v| v.name()))
        .chain(Storage::ALL.iter().map(|v| v.name()))
        .chain(Rectification::ALL.iter().map(|v| v.name()))
        .chain(Family::ALL.iter().map(|f| f.name()))
        .chain(Target::ALL.iter().map(|t| t.name()))
        .map(str::to_owned)
        .collect();
    let near = names.clone();
    prop_oneof![
        3 => prop::sample::select(names),
        // Near misses: case, blanks, truncation, a suffix, lists.
        3 => (prop::sample::select(near), 0..7u32, any::<char>()).prop_map(|(n, how, c)| {
            match how {
                0 => n.to_uppercase(),
                1 => format!(" {n}"),
                2 => format!("{n}\n"),
                3 => n[..n.len() - 1].to_owned(),
                4 => format!("{n}{c}"),
                5 => format!("{n},{n}, {n}"),
                _ => format!("{n},"),
            }
        }),
        2 => any::<String>(),
    ]
}

/// The enum knobs, the family and the target names on arbitrary strings.
#[test]
fn names_on_arbitrary_strings() {
    run("names", NAME_CASES, 0x6e11_0002, name_text(), |s| {
        fn check<T: std::str::FromStr + std::fmt::Display>(
            s: &str,
            knob: &str,
        ) -> Result<bool, TestCaseError>
        where
            T::Err: std::fmt::Display,
        {
            match s.parse::<T>() {
                Ok(v) => {
                    prop_assert_eq!(v.to_string(), s);
                    Ok(true)
                }
                Err(e) => {
                    let m = e.to_string();
                    one_line(&m)?;
                    prop_assert!(m.contains(knob), "{m:?} does not name {knob}");
                    Ok(false)
                }
            }
        }
        let mut ok = check::<VisibilityMode>(&s, "visibility")?;
        ok |= check::<LightKind>(&s, "light")?;
        ok |= check::<Storage>(&s, "storage")?;
        ok |= check::<Rectification>(&s, "rectification")?;
        ok |= check::<Family>(&s, "family")?;
        match Target::parse_list(&[s.as_str()]) {
            Ok(list) => {
                ok = true;
                prop_assert!(!list.is_empty());
            }
            Err(e) => {
                let m = e.to_string();
                one_line(&m)?;
                prop_assert!(m.contains("target"), "{m:?}");
            }
        }
        tally(ok);
        Ok(())
    });
}

/// `validate` on arbitrary numbers: never a panic or an overflow; what passes is in range.
#[test]
fn validate_on_arbitrary_numbers() {
    let any_or = |s: BoxedStrategy<u32>| prop_oneof![1 => any::<u32>(), 1 => Just(u32::MAX), 1 => Just(0u32), 6 => s];
    let fours = || (1..=34u32).prop_map(|x| x * 4).boxed();
    run(
        "validate",
        VALIDATE_CASES,
        0x6e11_0003,
        (
            any_or(fours()),
            any_or(fours()),
            any_or((0..=10u32).boxed()),
            any_or((0..=1100u32).boxed()),
            any_or((0..=10u32).boxed()),
            any::<bool>(),
        ),
        |(bases, bpt, regions, samples, interleave, jitter)| {
            let v = PrefilteredVariant {
                bases,
                bases_per_thread: bpt,
                regions,
                ..PrefilteredVariant::default()
            };
            let r = RaymarchVariant {
                samples,
                interleave,
                jitter,
                light: LightKind::Spot,
                ..RaymarchVariant::default()
            };
            let (vr, rr) = (v.validate(), r.validate());
            tally(vr.is_ok() || rr.is_ok());
            match vr {
                Ok(()) => {
                    prop_assert!((4..=128).contains(&bases) && bases % 4 == 0);
                    prop_assert!(bpt % 4 == 0 && bases % bpt == 0);
                    prop_assert!((1..=16).contains(&regions));
                    prop_assert!(v.layers() <= 32 && v.threads_per_row_region() >= 1);
                }
                Err(e) => {
                    let m = e.to_string();
                    one_line(&m)?;
                    prop_assert!(m.starts_with(e.knob), "{m}");
                }
            }
            match rr {
                Ok(()) => {
                    prop_assert!((4..=1024).contains(&samples));
                    prop_assert!((1..=8).contains(&interleave));
                    prop_assert!(samples % (interleave * interleave) == 0);
                }
                Err(e) => {
                    let m = e.to_string();
                    one_line(&m)?;
                    prop_assert!(m.starts_with(e.knob), "{m}");
                }
            }
            Ok(())
        },
    );
}

/// Checks one `config::parse` result; `tables` is the number of `[[variant]]` tables the
/// text has when known.
fn check_config(text: &str, tables: Option<usize>) -> Result<(), TestCaseError> {
    let result = config::parse(text);
    tally(result.is_ok());
    match result {
        Ok(c) => {
            prop_assert!(!c.variants.is_empty());
            if let Some(n) = tables {
                prop_assert_eq!(c.variants.len(), n);
            }
            for v in &c.variants {
                prop_assert!(validates(v), "accepted an invalid variant {v:?}");
            }
            if let Some(t) = &c.targets {
                prop_assert!(!t.is_empty(), "accepted an empty target list");
            }
        }
        Err(m) => {
            one_line(&m)?;
            if let (Some(n), Some(rest)) = (tables, m.strip_prefix("variant ")) {
                let k: usize = rest
                    .split(':')
                    .next()
                    .and_then(|k| k.parse().ok())
                    .unwrap_or(0);
                prop_assert!((1..=n).contains(&k), "{m:?} names variant {k} of {n}");
            }
        }
    }
    Ok(())
}

/// `config::parse` on arbitrary text and on TOML-like lines.
#[test]
fn config_on_arbitrary_text() {
    let line = prop_oneof![
        Just("[[variant]]".to_owned()),
        Just("[variant]".to_owned()),
        Just("[[targets]]".to_owned()),
        "[a-z_]{1,10} = (\"[a-z0-9 ]{0,10}\"|-?[0-9]{1,20}|true|false|\\[\\]|\\[1, 2\\]|\\{\\}|[0-9]\\.[0-9]e[0-9]{1,3})",
        "targets = \\[(\"[a-z]{0,6}\"(, )?){0,4}\\]",
        any::<String>(),
    ];
    run(
        "config_text",
        CONFIG_TEXT_CASES,
        0x6e11_0004,
        prop_oneof![
            1 => any::<String>(),
            1 => prop::collection::vec(any::<u8>(), 0..200)
                .prop_map(|b| String::from_utf8_lossy(&b).into_owned()),
            3 => prop::collection::vec(line, 0..12).prop_map(|l| l.join("\n")),
        ],
        |text| check_config(&text, None),
    );
}

/// A TOML value, as source text.
fn toml_value() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => knob_value().prop_map(|v| format!("{v:?}")),
        2 => (0u32..300).prop_map(|n| n.to_string()),
        1 => prop::sample::select(vec![
            "-1", "9223372036854775807", "9223372036854775808", "-9223372036854775809",
            "32.0", "1e400", "nan", "inf", "-0.0", "true", "false", "[32]", "[]",
            "[[1], [2]]", "{ a = 1 }", "{}", "1979-05-27T07:32:00Z", "07:32:00",
            "'spot'", "\"\"\"sp\not\"\"\"", "'''x'''", "\"a\\nb\"", "\"\\u0000\"",
            "0x20", "0o40", "0b100000", "1_000", "+32",
        ])
        .prop_map(str::to_owned),
        1 => (1usize..3000).prop_map(|n| format!("[{}]", vec!["1"; n].join(", "))),
        1 => (1usize..300).prop_map(|n| format!("\"{}\"", "x".repeat(n * 100))),
    ]
}

fn toml_key() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => prop::sample::select(known_names()).prop_map(str::to_owned),
        1 => "[a-z_]{1,10}",
        1 => prop::sample::select(vec![
            "\"bases\"", "'regions'", "\"a\\nb\"", "a.b", "\"\"", "bases.x", "\"\\u001b\"",
        ])
        .prop_map(str::to_owned),
    ]
}

/// `config::parse` on generated files: optional targets, junk keys, up to four variant
/// tables of arbitrary entries, some files cut short or with a byte changed.
#[test]
fn config_on_generated_files() {
    let targets = prop_oneof![
        2 => Just(String::new()),
        2 => prop::collection::vec(
            prop::sample::select(vec!["wgsl", "glsl", "spirv", "hlsl", "msl", "wgsl,spirv", "", "hlsl2", "WGSL"]),
            0..5,
        )
        .prop_map(|t| format!("targets = {t:?}\n")),
        1 => toml_value().prop_map(|v| format!("targets = {v}\n")),
    ];
    let table = prop::collection::vec((toml_key(), toml_value()), 0..6);
    run(
        "config_file",
        CONFIG_FILE_CASES,
        0x6e11_0005,
        (
            targets,
            prop::option::weighted(0.1, (toml_key(), toml_value())),
            prop::collection::vec(table, 0..4),
            prop_oneof![3 => Just(None), 1 => any::<prop::sample::Index>().prop_map(Some)],
            prop::option::weighted(0.1, (any::<prop::sample::Index>(), any::<char>())),
        ),
        |(targets, junk, tables, cut, poke)| {
            let mut text = targets;
            if let Some((k, v)) = &junk {
                text.push_str(&format!("{k} = {v}\n"));
            }
            for t in &tables {
                text.push_str("[[variant]]\n");
                for (k, v) in t {
                    text.push_str(&format!("{k} = {v}\n"));
                }
            }
            let mut exact = true;
            if let Some(i) = cut {
                let mut at = i.index(text.len() + 1);
                while !text.is_char_boundary(at) {
                    at -= 1;
                }
                text.truncate(at);
                exact = false;
            }
            if let Some((i, c)) = poke
                && !text.is_empty()
            {
                let mut at = i.index(text.len());
                while !text.is_char_boundary(at) {
                    at -= 1;
                }
                text.insert(at, c);
                exact = false;
            }
            check_config(&text, exact.then_some(tables.len()))
        },
    );
}

/// One fault planted in a valid config file.
#[derive(Clone, Debug)]
enum Fault {
    /// A key no family has, in table `i`.
    UnknownKnob(String),
    /// A knob of the table's family set to a value of the wrong TOML type.
    WrongType(String, String),
    /// A knob of the table's family set to a bad value.
    BadValue(String, String),
    /// An integer or boolean knob set to a valid value in quotes (`bases = "32"`).
    Quoted(String, String),
    /// `family` set to something that is not a family.
    BadFamily(String),
    /// A top-level key that is not `targets` or `variant`.
    TopLevel(String),
    /// `targets` with a name that is not a target.
    BadTarget(String),
    /// No fault: the file must be accepted.
    None,
}

/// A valid knob value for `family`'s knob `name`, as TOML source.
fn valid_value(family: Family, name: &str, pick: usize) -> String {
    // The sampling knobs only at the family's defaults (`partial_sum_tree` samples epipolar
    // lines with step 1; the others every pixel): set apart from their mode they are
    // rejected.
    if let Some(k) = family
        .knobs()
        .into_iter()
        .find(|k| k.name == name && SAMPLING_KNOB_NAMES.contains(&name))
    {
        return match k.value_type {
            KnobType::Name => format!("\"{}\"", k.default),
            _ => k.default,
        };
    }
    let area = family == Family::AreaIvsv;
    let options: &[&str] = match name {
        "light" if area => &["\"area\""],
        // Multiples of every interleave^2.
        "vpls" => &["16", "64"],
        "alpha" | "theta" => &["2", "64", "256"],
        "segments" => &["1", "8", "32"],
        "basis" => &["\"fourier\""],
        "moments" => &["4"],
        "bases" => &["32"],
        "bases_per_thread" => &["4", "8"],
        "regions" => &["1", "2", "3", "8"],
        "visibility" => &["\"average\"", "\"weighted\""],
        "light" => &["\"directional\"", "\"spot\""],
        "storage" => &["\"rgba8unorm\"", "\"rgba16float\""],
        "rectification" => &["\"epipolar\"", "\"projective\""],
        "samples" => &["64", "128"],
        "interleave" => &["1", "2", "4"],
        "jitter" => &["true", "false"],
        // `cookie = true` needs `light = "spot"`, which another knob picks.
        "cookie" => &["false"],
        // `resume = true` needs `filtered_stride` above 1, which another knob picks.
        "resume" => &["false"],
        _ => &["1"],
    };
    options[pick % options.len()].to_owned()
}

/// The sampling knobs every family has.
const SAMPLING_KNOB_NAMES: [&str; 7] = [
    "sampling",
    "scale",
    "depth_break",
    "light_break",
    "slices",
    "slice_samples",
    "step",
];

/// A bad value for `family`'s knob `name`, as TOML source.
fn bad_value(family: Family, name: &str, pick: usize) -> String {
    let options: &[&str] = match name {
        "light" if family == Family::AreaIvsv => &["\"spot\"", "\"directional\"", "\"Area\""],
        "vpls" => &["0", "257", "\"many\""],
        "alpha" | "theta" => &["1", "4097", "-2"],
        "segments" => &["3", "0", "64"],
        "basis" => &["\"moment\"", "\"Fourier\"", "1"],
        "moments" => &["5", "0", "8", "\"six\""],
        "bases" => &["30", "132", "0", "-4", "\"abc\"", "4294967296", "\"\""],
        "bases_per_thread" => &["3", "0", "12", "256", "\"x\""],
        "regions" => &["0", "17", "-1", "\"three\"", "1.5"],
        "visibility" => &["\"median\"", "\"Average\"", "\"\"", "3"],
        "light" => &["\"area\"", "\" spot\"", "\"spot\\n\"", "1"],
        "storage" => &["\"rgba8\"", "\"r32float\""],
        "rectification" => &["\"projection\"", "\"\""],
        // Bad for raymarch (a power of two in 1..=1024) and hybrid_volume (1..=1024) alike.
        "samples" => &["1025", "0", "\"many\""],
        "bins" => &["0", "1025", "\"many\""],
        "pad" => &["9", "-1", "\"x\""],
        "interleave" => &["0", "9", "\"two\""],
        "jitter" => &["\"maybe\"", "2", "\"yes\""],
        "cookie" => &["\"maybe\"", "2", "\"yes\""],
        "resume" => &["\"maybe\"", "2", "\"yes\""],
        "sampling" => &["\"epipole\"", "\"lowres2\"", "2"],
        "scale" => &["3", "0", "8", "\"two\""],
        "depth_break" => &["0", "51", "\"x\""],
        "light_break" => &["0", "101", "-5"],
        "slices" => &["300", "0", "2048", "\"many\""],
        "slice_samples" => &["100", "1024", "-1"],
        "step" => &["3", "0", "64", "\"x\""],
        "rank" => &["0", "9", "\"four\"", "-1"],
        _ => &["\"?\""],
    };
    options[pick % options.len()].to_owned()
}

#[test]
fn config_with_one_fault() {
    let families = Family::ALL.to_vec();
    run(
        "config_fault",
        CONFIG_FAULT_CASES,
        0x6e11_0006,
        (
            prop::collection::vec(
                (
                    prop::sample::select(families),
                    prop::collection::vec(any::<prop::sample::Index>(), 0..4),
                ),
                1..4,
            ),
            any::<prop::sample::Index>(),
            0..8u32,
            any::<prop::sample::Index>(),
            prop_oneof!["[a-z_]{1,10}", any::<String>()],
            prop::sample::select(vec![
                "[32]",
                "[]",
                "{ a = 1 }",
                "1979-05-27T07:32:00Z",
                "[\"spot\"]",
            ]),
        ),
        |(tables, at, kind, pick, junk, wrong)| {
            let i = at.index(tables.len());
            let (family, _) = &tables[i];
            let knobs = family.knobs();
            let info = &knobs[pick.index(knobs.len())];
            let knob = info.name;
            // A junk name that is no knob or key of anything.
            let junk = format!("x_{junk}");
            let fault = match kind {
                0 => Fault::UnknownKnob(junk),
                1 => Fault::WrongType(knob.to_owned(), wrong.to_owned()),
                2 => Fault::BadValue(knob.to_owned(), bad_value(*family, knob, pick.index(97))),
                3 => Fault::BadFamily(junk),
                4 => Fault::TopLevel(junk),
                5 => Fault::BadTarget(junk),
                6 if info.value_type != KnobType::Name => Fault::Quoted(
                    knob.to_owned(),
                    format!("\"{}\"", valid_value(*family, knob, 0)),
                ),
                _ => Fault::None,
            };
            // Minmax's only knob has no bad number form: every bad value is a bad name.
            let mut text = String::new();
            if let Fault::TopLevel(k) = &fault {
                text.push_str(&format!("{} = 1\n", toml_quote(k)));
            }
            if let Fault::BadTarget(t) = &fault {
                text.push_str(&format!("targets = [\"wgsl\", {}]\n", toml_string(t)));
            }
            // Each table's text, to find the variants that repeat an earlier one.
            let mut table_texts = Vec::new();
            for (j, (family, picks)) in tables.iter().enumerate() {
                let start = text.len();
                text.push_str("[[variant]]\n");
                if j == i
                    && let Fault::BadFamily(f) = &fault
                {
                    text.push_str(&format!("family = {}\n", toml_string(f)));
                } else {
                    text.push_str(&format!("family = \"{family}\"\n"));
                }
                let knobs = family.knobs();
                let mut used = Vec::new();
                for p in picks {
                    let k = knobs[p.index(knobs.len())].name;
                    if used.contains(&k)
                        || (j == i
                            && matches!(&fault, Fault::WrongType(n, _) | Fault::BadValue(n, _) | Fault::Quoted(n, _) if n == k))
                    {
                        continue;
                    }
                    used.push(k);
                    // bases and bases_per_thread depend on each other: keep both valid.
                    text.push_str(&format!("{k} = {}\n", valid_value(*family, k, p.index(12))));
                }
                if j == i {
                    match &fault {
                        Fault::UnknownKnob(k) => {
                            text.push_str(&format!("{} = 1\n", toml_quote(k)));
                        }
                        Fault::WrongType(k, v) | Fault::BadValue(k, v) | Fault::Quoted(k, v) => {
                            text.push_str(&format!("{k} = {v}\n"));
                        }
                        _ => {}
                    }
                }
                table_texts.push(text[start..].to_owned());
            }
            // Without a fault, a table that resolves to the same variant as an earlier one
            // is the only thing refused (naming both tables).
            let repeat = if matches!(fault, Fault::None) {
                let ids: Vec<String> = table_texts
                    .iter()
                    .map(|t| match config::parse(t) {
                        Ok(c) => c.variants[0].to_string(),
                        Err(m) => format!("invalid: {m}"),
                    })
                    .collect();
                (1..ids.len())
                    .find_map(|j| ids[..j].iter().position(|id| *id == ids[j]).map(|i| (i, j)))
            } else {
                None
            };
            let result = config::parse(&text);
            tally(result.is_ok());
            if let Some((first, again)) = repeat {
                let m = result.err().unwrap_or_default();
                prop_assert!(
                    m.starts_with(&format!(
                        "variant {}: same variant as variant {}",
                        again + 1,
                        first + 1
                    )),
                    "tables {} and {} repeat a variant: {m:?}\n{text}",
                    first + 1,
                    again + 1
                );
                one_line(&m)?;
                return Ok(());
            }
            let m = match result {
                Ok(c) if matches!(fault, Fault::None) => {
                    prop_assert_eq!(c.variants.len(), tables.len());
                    for (v, (family, _)) in c.variants.iter().zip(&tables) {
                        prop_assert_eq!(v.family(), *family);
                    }
                    return Ok(());
                }
                Err(m) if matches!(fault, Fault::None) => {
                    return Err(TestCaseError::fail(format!(
                        "a valid file was rejected: {m}\n{text}"
                    )));
                }
                Ok(c) => {
                    return Err(TestCaseError::fail(format!(
                        "fault {fault:?} accepted: {c:?}\n{text}"
                    )));
                }
                Err(m) => m,
            };
            one_line(&m)?;
            let expect: Vec<String> = match &fault {
                Fault::UnknownKnob(k) => {
                    vec![format!("variant {}:", i + 1), printable(k).into_owned()]
                }
                // basic_toml has no date-times: a syntax error at the value's line.
                Fault::WrongType(_, v) if v.contains('T') => vec!["at line".to_owned()],
                Fault::WrongType(k, _) => vec![format!("variant {}:", i + 1), k.clone()],
                Fault::BadValue(k, _) => {
                    // Raising bases can make the default bases_per_thread invalid; the
                    // message then names that knob.
                    let k = if k == "bases" && !m.contains("bases must") {
                        "bases_per_thread".to_owned()
                    } else {
                        k.clone()
                    };
                    vec![format!("variant {}:", i + 1), k]
                }
                Fault::BadFamily(_) => vec![format!("variant {}:", i + 1), "family".to_owned()],
                Fault::Quoted(k, _) => vec![
                    format!("variant {}: {k} must be", i + 1),
                    "without quotes".to_owned(),
                ],
                Fault::TopLevel(k) => vec![printable(k).into_owned()],
                Fault::BadTarget(_) => vec!["target".to_owned()],
                Fault::None => vec![],
            };
            for e in &expect {
                prop_assert!(
                    m.contains(e.as_str()),
                    "fault {fault:?}: {m:?} lacks {e:?}\n{text}"
                );
            }
            Ok(())
        },
    );
}

/// `s` as a TOML basic string.
fn toml_string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push_str(&format!("\\u{:04x}", u32::from(c))),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// `s` as a TOML key: bare when it can be, else quoted.
fn toml_quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        s.to_owned()
    } else {
        toml_string(s)
    }
}

/// A JSON value to put somewhere it does not belong.
fn json_value() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        any::<i64>().prop_map(Value::from),
        any::<f64>()
            .prop_map(|x| serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)),
        prop::sample::select(vec![
            "",
            "..",
            "../x",
            "/etc/passwd",
            "a/../../b",
            "C:\\x",
            "a//b",
            ".",
            "\u{0}",
            "scatter-gen-manifest",
            "x\ny",
        ])
        .prop_map(|s| Value::String(s.to_owned())),
        any::<String>().prop_map(Value::String),
        Just(Value::Array(vec![])),
        Just(serde_json::json!({})),
        Just(serde_json::json!([{"path": "../../etc/passwd", "sha256": "", "bytes": 0}])),
    ]
}

/// One edit of a JSON tree: at the node that `path` picks, replace it, delete a key or an
/// element, or add a key.
#[derive(Clone, Debug)]
enum Edit {
    Replace(Value),
    Delete,
    AddKey(String, Value),
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        3 => json_value().prop_map(Edit::Replace),
        2 => Just(Edit::Delete),
        1 => ("[a-z_]{1,8}", json_value()).prop_map(|(k, v)| Edit::AddKey(k, v)),
    ]
}

/// Applies `edit` at the node reached by following `path` (each index picks a child).
fn apply(root: &mut Value, path: &[prop::sample::Index], edit: Edit) {
    let mut node = root;
    for (depth, step) in path.iter().enumerate() {
        let last = depth + 1 == path.len();
        let child_count = match node {
            Value::Object(m) => m.len(),
            Value::Array(a) => a.len(),
            _ => 0,
        };
        if child_count == 0 {
            break;
        }
        let k = step.index(child_count);
        if last && matches!(edit, Edit::Delete) {
            match node {
                Value::Object(m) => {
                    let key = m.keys().nth(k).cloned().unwrap_or_default();
                    m.remove(&key);
                }
                Value::Array(a) => {
                    a.remove(k);
                }
                _ => {}
            }
            return;
        }
        node = match node {
            Value::Object(m) => m.values_mut().nth(k).unwrap_or_else(|| unreachable!()),
            Value::Array(a) => &mut a[k],
            _ => unreachable!(),
        };
    }
    match edit {
        Edit::Replace(v) => *node = v,
        Edit::AddKey(k, v) => {
            if let Value::Object(m) = node {
                m.insert(k, v);
            } else {
                *node = v;
            }
        }
        Edit::Delete => *node = Value::Null,
    }
}

/// The manifest of the default prefiltered variant (WGSL only: the cheapest to generate).
fn real_manifest() -> Vec<u8> {
    generate(&Request {
        variants: vec![Family::Prefiltered.default_variant()],
        targets: vec![Target::Wgsl],
    })
    .unwrap_or_else(|e| panic!("{e}"))
    .manifest
}

/// The ownership manifest reader, which decides what the generator may overwrite or
/// delete: never a panic, never a path outside the directory, errors one line.
#[test]
fn owned_files_on_mutated_manifests() {
    let dir = common::scratch("fuzz_owned_files");
    let real: Value = serde_json::from_slice(&real_manifest()).unwrap_or_else(|e| panic!("{e}"));
    let manifest = dir.join("manifest.json");
    run(
        "owned_files",
        OWNED_CASES,
        0x6e11_0007,
        prop_oneof![
            1 => prop::collection::vec(any::<u8>(), 0..300).prop_map(Err),
            4 => (
                prop::collection::vec(
                    (prop::collection::vec(any::<prop::sample::Index>(), 0..6), edit()),
                    1..4,
                ),
                prop::option::weighted(0.2, any::<prop::sample::Index>()),
            )
                .prop_map(Ok),
        ],
        |input| {
            let bytes = match input {
                Err(raw) => raw,
                Ok((edits, cut)) => {
                    let mut v = real.clone();
                    for (path, e) in edits {
                        apply(&mut v, &path, e);
                    }
                    let mut b = serde_json::to_vec_pretty(&v).unwrap_or_default();
                    if let Some(i) = cut {
                        b.truncate(i.index(b.len() + 1));
                    }
                    b
                }
            };
            std::fs::write(&manifest, &bytes).map_err(|e| TestCaseError::fail(e.to_string()))?;
            let result = output::owned_files(&dir);
            tally(result.is_ok());
            match result {
                Ok(files) => {
                    for f in files.into_iter().flatten() {
                        let p = std::path::Path::new(&f.path);
                        prop_assert!(
                            !f.path.is_empty()
                                && p.components()
                                    .all(|c| matches!(c, std::path::Component::Normal(_))),
                            "accepted the path {:?}",
                            f.path
                        );
                    }
                }
                Err(e) => {
                    let m = e.to_string();
                    one_line(&m)?;
                    prop_assert!(matches!(e, GenError::Foreign { .. }), "{m}");
                    prop_assert!(m.contains("manifest.json"), "{m}");
                }
            }
            Ok(())
        },
    );
}

/// The binary on arbitrary command lines that cannot generate anything (every case has a
/// bad token): exit 2, one line on stderr naming the flag or value, nothing written.
#[test]
fn cli_on_arbitrary_command_lines() {
    let dir = common::scratch("fuzz_cli");
    let out = dir.join("out");
    let flag = prop_oneof![
        4 => prop::sample::select(known_names())
            .prop_map(|k| format!("--{}", k.replace('_', "-"))),
        1 => prop::sample::select(vec![
            "--target", "--config", "--check", "--force", "--out", "--family", "--bases=",
            "-b", "--", "list", "--Bases",
        ])
        .prop_map(str::to_owned),
        1 => "--[a-z-]{1,10}",
    ];
    let token = prop_oneof![
        flag.clone().prop_map(|f| vec![f]),
        (flag, knob_value()).prop_map(|(f, v)| vec![f, v]),
    ];
    // The bad token: a bad knob value, an unknown flag, an unknown target, a missing
    // config file.
    let bad = prop_oneof![
        (
            prop::sample::select(vec!["--bases", "--regions", "--samples", "--light"]),
            prop::sample::select(vec!["0", "abc", "-1", "", " ", "9\n9", "\u{1b}[31m"])
        )
            .prop_map(|(f, v)| vec![f.to_owned(), v.to_owned()]),
        "--x[a-z]{1,8}".prop_map(|f| vec![f]),
        Just(vec!["--target".to_owned(), "hlsl2".to_owned()]),
        Just(vec![
            "--config".to_owned(),
            "/nonexistent/variants.toml".to_owned()
        ]),
    ];
    run(
        "cli",
        CLI_CASES,
        0x6e11_0008,
        (
            prop::collection::vec(token, 0..4),
            bad,
            any::<prop::sample::Index>(),
        ),
        |(tokens, bad, at)| {
            let mut args: Vec<String> = tokens.into_iter().flatten().collect();
            let i = at.index(args.len() + 1);
            // Keep a flag's value with its flag.
            let i = if i > 0
                && args[i - 1].starts_with("--")
                && !args.get(i).is_some_and(|a| a.starts_with("--"))
            {
                i - 1
            } else {
                i
            };
            for (k, b) in bad.into_iter().enumerate() {
                args.insert(i + k, b);
            }
            args.push("--out".to_owned());
            args.push(out.display().to_string());
            let refs: Vec<&str> = args.iter().map(String::as_str).collect();
            let o = common::scatter_gen(&refs);
            let (stdout, stderr) = common::text(&o);
            let code = o.status.code();
            tally(code == Some(0));
            prop_assert!(
                !stderr.contains("panicked"),
                "{args:?}: scatter-gen panicked: {stderr}"
            );
            prop_assert!(
                matches!(code, Some(0..=2)),
                "{args:?}: exit {code:?}: {stderr}"
            );
            if code != Some(0) {
                let lines: Vec<&str> = stderr.lines().collect();
                prop_assert_eq!(lines.len(), 1, "{:?}: stderr {:?}", args, stderr);
                one_line(lines[0])?;
            }
            if code == Some(2) {
                prop_assert!(
                    !out.exists(),
                    "{args:?}: wrote {} on bad input ({stdout})",
                    out.display()
                );
            }
            let _ = std::fs::remove_dir_all(&out);
            Ok(())
        },
    );
}
