//! `--config variants.toml`: the exact set of variants an engine ships (several lights or
//! qualities at once), and optionally the targets.
//!
//! ```toml
//! targets = ["wgsl", "spirv"]      # optional; --target overrides it
//!
//! [[variant]]                      # knobs not named keep the paper's defaults
//! light = "directional"
//!
//! [[variant]]
//! family = "prefiltered"           # optional, the default family
//! light = "spot"
//! bases = 16
//! regions = 1
//! ```

use std::collections::BTreeMap;
use std::path::Path;

use scatter_shaderlib::prefiltered::variant::printable;
use serde::Deserialize;
use serde_json::Value;

use crate::GenError;
use crate::family::{Family, FamilyCli, FamilyVariant};
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
    let mut variants = Vec::new();
    for (i, table) in file.variant.iter().enumerate() {
        let n = i + 1;
        let mut family = Family::Prefiltered;
        let mut knobs = Vec::new();
        for (key, value) in table {
            let value = match value {
                Value::String(s) => s.clone(),
                Value::Number(x) => x.to_string(),
                Value::Bool(b) => b.to_string(),
                other => {
                    return Err(format!(
                        "variant {n}: `{}` must be a number or a string, got {other}",
                        printable(key)
                    ));
                }
            };
            if key == "family" {
                family = value
                    .parse()
                    .map_err(|e: scatter_shaderlib::family::UnknownFamily| {
                        format!("variant {n}: {e}")
                    })?;
            } else {
                knobs.push((key.clone(), value));
            }
        }
        let v = family
            .variant(&knobs)
            .map_err(|e| format!("variant {n}: {e}"))?;
        variants.push(v);
    }
    Ok(Config { targets, variants })
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
        assert!(
            e.starts_with("variant 1: knob `basis` does not apply"),
            "{e}"
        );
        let e = parse("[[variant]]\nbases = [32]\n").unwrap_err();
        assert!(e.contains("must be a number or a string"), "{e}");
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
            "variant 1: bases must be a multiple of 4 in 4..=128, got 3\\n2"
        );
    }
}
