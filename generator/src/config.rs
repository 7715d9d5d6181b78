//! `--config variants.toml`: the exact set of variants an engine ships (several lights or
//! qualities at once), and optionally the targets.
//!
//! ```toml
//! targets = ["wgsl", "spirv"]      # optional; --target overrides it
//!
//! [[variant]]                      # knobs not named keep their defaults
//! light = "directional"
//!
//! [[variant]]
//! family = "prefiltered"           # optional, the default family
//! light = "spot"
//! bases = 16
//! regions = 1
//! ```
//!
//! Values have their TOML type: integers and booleans unquoted (`bases = 32`,
//! `jitter = true`), names quoted (`light = "spot"`). A target named twice, or the same
//! variant listed twice, is refused: each is a slip in the file.

use std::collections::BTreeMap;
use std::path::Path;

use scatter_shaderlib::prefiltered::variant::printable;
use serde::Deserialize;
use serde_json::Value;

use crate::GenError;
use crate::family::{Family, FamilyCli, FamilyVariant, KnobInfo, KnobType};
use crate::target::Target;

/// A parsed config file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Config {
    /// `targets`, when the file names them.
    pub targets: Option<Vec<Target>>,
    /// The variants, in file order.
    pub variants: Vec<FamilyVariant>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    targets: Option<Vec<String>>,
    #[serde(default)]
    variant: Vec<BTreeMap<String, Value>>,
}

/// Reads and validates a config file.
///
/// # Errors
///
/// [`GenError::Config`] naming the file, and the variant table and knob where it applies.
pub fn load(path: &Path) -> Result<Config, GenError> {
    let text = std::fs::read_to_string(path).map_err(|e| GenError::Config {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    parse(&text).map_err(|message| GenError::Config {
        path: path.to_owned(),
        message,
    })
}

/// Parses config text; errors are one line without the file name.
///
/// # Errors
///
/// A message naming the variant table (1-based) and the knob.
pub fn parse(text: &str) -> Result<Config, String> {
    let file: File = basic_toml::from_str(text)
        .map_err(|e| printable(&e.to_string().replace('\n', " ")).into_owned())?;
    let targets = file
        .targets
        .map(|t| Target::parse_list(&t).map_err(|e| e.to_string()))
        .transpose()?;
    if targets.as_ref().is_some_and(Vec::is_empty) {
        let all: Vec<_> = Target::ALL.iter().map(|t| t.name()).collect();
        return Err(format!(
            "targets is empty: list at least one of {} (or leave targets out for the default)",
            all.join(" | ")
        ));
    }
    if file.variant.is_empty() {
        return Err("no [[variant]] tables: list the variants to emit".into());
    }
    let mut variants: Vec<FamilyVariant> = Vec::new();
    for (i, table) in file.variant.iter().enumerate() {
        let n = i + 1;
        let family = match table.get("family") {
            None => Family::Prefiltered,
            Some(value) => scalar_text(value)
                .ok_or_else(|| format!("variant {n}: family must be a string, got {value}"))?
                .parse()
                .map_err(|e: scatter_shaderlib::family::UnknownFamily| {
                    format!("variant {n}: {e}")
                })?,
        };
        let known = family.knobs();
        let mut knobs = Vec::new();
        for (key, value) in table.iter().filter(|(k, _)| k.as_str() != "family") {
            let text = match known.iter().find(|k| k.name == key.as_str()) {
                Some(knob) => typed_text(knob, value).map_err(|e| format!("variant {n}: {e}"))?,
                // Not a knob of this family: the family names it and lists its knobs.
                None => scalar_text(value).unwrap_or_default(),
            };
            knobs.push((key.clone(), text));
        }
        let v = family
            .variant(&knobs)
            .map_err(|e| format!("variant {n}: {e}"))?;
        variants.push(v);
    }
    // A table repeated (the same family and variant id) would emit the same files twice:
    // a slip in the file, so it is refused rather than merged.
    for (j, v) in variants.iter().enumerate() {
        if let Some(i) = variants[..j]
            .iter()
            .position(|w| w.family() == v.family() && w.id() == v.id())
        {
            return Err(format!(
                "variant {}: same variant as variant {} ({v}): list each variant once",
                j + 1,
                i + 1
            ));
        }
    }
    Ok(Config { targets, variants })
}

/// A string, number or boolean as text; `None` for arrays and tables.
fn scalar_text(value: &Value) -> Option<String> {
    match value {
        Value::String(s) => Some(s.clone()),
        Value::Number(x) => Some(x.to_string()),
        Value::Bool(b) => Some(b.to_string()),
        _ => None,
    }
}

/// A knob's value as the text its family parses, refusing a value of the wrong TOML type
/// (`bases = "32"`, `jitter = "true"`, `light = 1`) with a message naming the knob and the
/// type it takes.
fn typed_text(knob: &KnobInfo, value: &Value) -> Result<String, String> {
    let name = knob.name;
    let wanted = match knob.value_type {
        KnobType::Name => format!("a string ({})", knob.allowed),
        KnobType::Boolean => "a boolean (true | false)".to_owned(),
        KnobType::Integer => "an integer".to_owned(),
    };
    let got = match (knob.value_type, value) {
        (KnobType::Integer, Value::Number(x)) if x.is_i64() || x.is_u64() => {
            return Ok(x.to_string());
        }
        (KnobType::Boolean, Value::Bool(b)) => return Ok(b.to_string()),
        (KnobType::Name, Value::String(s)) => return Ok(s.clone()),
        (_, Value::String(s)) => {
            // A quoted value that would be right unquoted: say how to write it.
            let fits = match knob.value_type {
                KnobType::Integer => s.parse::<i64>().is_ok(),
                KnobType::Boolean => s == "true" || s == "false",
                KnobType::Name => false,
            };
            let hint = if fits {
                format!(" (write {name} = {s}, without quotes)")
            } else {
                String::new()
            };
            format!("the string \"{}\"{hint}", printable(s))
        }
        (_, other) => other.to_string(),
    };
    Err(format!("{name} must be {wanted}, got {got}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_variants_and_targets() {
        let c = parse(
            "targets = [\"spirv\", \"wgsl\"]\n[[variant]]\nlight = \"spot\"\nbases = 16\n[[variant]]\n",
        )
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(c.targets, Some(vec![Target::Wgsl, Target::Spirv]));
        assert_eq!(c.variants.len(), 2);
        assert_eq!(c.variants[1], Family::Prefiltered.default_variant());
    }

    #[test]
    fn names_the_variant_and_knob() {
        let e = parse("[[variant]]\n[[variant]]\nbases = 30\n").unwrap_err();
        assert_eq!(
            e,
            "variant 2: bases must be a multiple of 4 in 4..=128, got 30"
        );
        let e = parse("[[variant]]\nbasis = 32\n").unwrap_err();
        assert_eq!(
            e,
            "variant 1: basis must be a string (fourier | moments), got 32"
        );
        let e = parse("[[variant]]\nbasse = 32\n").unwrap_err();
        assert!(
            e.starts_with("variant 1: knob `basse` does not apply"),
            "{e}"
        );
        let e = parse("[[variant]]\nbasis = \"moments\"\nbases = 16\n").unwrap_err();
        assert!(
            e.starts_with("variant 1: bases must be 32 (a Fourier knob"),
            "{e}"
        );
        let e = parse("[[variant]]\nbases = [32]\n").unwrap_err();
        assert_eq!(e, "variant 1: bases must be an integer, got [32]");
        assert!(parse("").unwrap_err().contains("no [[variant]]"));
        assert!(parse("colour = 1\n").is_err());
        let e = parse("targets = []\n[[variant]]\n").unwrap_err();
        assert!(e.starts_with("targets is empty"), "{e}");
        // User text in a message stays on one line.
        let e = parse("[[variant]]\n\"a\\nb\" = 1\n").unwrap_err();
        assert!(!e.contains('\n') && e.contains("knob `a\\nb`"), "{e}");
        let e = parse("[[variant]]\nbases = \"3\\n2\"\n").unwrap_err();
        assert_eq!(
            e,
            "variant 1: bases must be an integer, got the string \"3\\n2\""
        );
    }

    #[test]
    fn refuses_values_of_the_wrong_type() {
        let cases = [
            (
                "bases = \"32\"",
                "variant 1: bases must be an integer, got the string \"32\" (write bases = 32, without quotes)",
            ),
            (
                "regions = \"3\"",
                "variant 1: regions must be an integer, got the string \"3\" (write regions = 3, without quotes)",
            ),
            (
                "regions = 1.5",
                "variant 1: regions must be an integer, got 1.5",
            ),
            (
                "regions = true",
                "variant 1: regions must be an integer, got true",
            ),
            (
                "family = \"raymarch\"\njitter = \"true\"",
                "variant 1: jitter must be a boolean (true | false), got the string \"true\" (write jitter = true, without quotes)",
            ),
            (
                "family = \"raymarch\"\njitter = 1",
                "variant 1: jitter must be a boolean (true | false), got 1",
            ),
            (
                "family = \"raymarch\"\nsamples = \"many\"",
                "variant 1: samples must be an integer, got the string \"many\"",
            ),
            (
                "light = 1",
                "variant 1: light must be a string (directional | spot), got 1",
            ),
            (
                "family = 1",
                "variant 1: family must be area_ivsv | hybrid_volume | minmax | partial_sum_tree | prefiltered | raymarch, got 1",
            ),
            (
                "family = [1]",
                "variant 1: family must be a string, got [1]",
            ),
        ];
        for (table, message) in cases {
            let e = parse(&format!("[[variant]]\n{table}\n")).unwrap_err();
            assert_eq!(e, message, "{table}");
        }
        // The right types pass.
        let c = parse("[[variant]]\nfamily = \"raymarch\"\nsamples = 64\njitter = true\n")
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(c.variants[0].id(), "n64-i1-jitter-directional");
    }

    #[test]
    fn refuses_a_repeated_variant_or_target() {
        // The same resolved variant, written two ways.
        let e = parse("[[variant]]\nlight = \"spot\"\n[[variant]]\n[[variant]]\nlight = \"spot\"\nbases = 32\n")
            .unwrap_err();
        assert_eq!(
            e,
            "variant 3: same variant as variant 1 \
             (prefiltered::m32-t16-r4-weighted-spot-rgba8unorm-epipolar): list each variant once"
        );
        let e = parse("[[variant]]\nfamily = \"minmax\"\n[[variant]]\nfamily = \"minmax\"\n")
            .unwrap_err();
        assert!(
            e.starts_with("variant 2: same variant as variant 1 (minmax::"),
            "{e}"
        );
        // The same knobs in different families are different variants.
        assert!(
            parse("[[variant]]\nfamily = \"minmax\"\n[[variant]]\nfamily = \"raymarch\"\n").is_ok()
        );
        let e = parse("targets = [\"wgsl\", \"spirv\", \"wgsl\"]\n[[variant]]\n").unwrap_err();
        assert_eq!(e, "target wgsl is named twice: name each target once");
    }
}
