//! The manifest's size and dispatch formulas (`generator/MANIFEST.md`, "Formulas"): an
//! integer (`8`), a parameter (`rectified.width`), a product (`16 * rectified.height`),
//! `ceil(a / b)` (integer division rounding up) or a sum (`ceil(screen.width / 2) + 1`),
//! nested freely. [`Params`] holds the values
//! of the parameters; [`eval`] parses and evaluates in one go, in `u64` with overflow and
//! division by zero reported as errors. Also the parameters' `lo..=hi` constraints
//! ([`check_constraint`]).

use crate::EngineError;

/// Parameter values by name (`screen.width` -> 1280).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Params {
    values: Vec<(String, u64)>,
}

impl Params {
    /// Sets (or replaces) a parameter.
    pub fn set(&mut self, name: &str, value: u64) {
        match self.values.iter_mut().find(|(n, _)| n == name) {
            Some(slot) => slot.1 = value,
            None => self.values.push((name.to_owned(), value)),
        }
    }

    /// A parameter's value.
    pub fn get(&self, name: &str) -> Option<u64> {
        self.values.iter().find(|(n, _)| n == name).map(|&(_, v)| v)
    }

    /// Parameter names, comma-separated (for messages).
    pub fn names(&self) -> String {
        self.values
            .iter()
            .map(|(n, _)| n.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Evaluates `formula`; `context` says where it appears (for messages).
///
/// # Errors
///
/// [`EngineError::UnknownSymbol`] for a name that is not in `params`;
/// [`EngineError::Formula`] for a syntax error, an overflow or a division by zero.
pub fn eval(formula: &str, params: &Params, context: &str) -> Result<u64, EngineError> {
    let mut p = Parser {
        src: formula,
        pos: 0,
        params,
        context,
    };
    let value = p.sum()?;
    p.skip_ws();
    if p.pos != formula.len() {
        return Err(p.error(format!("unexpected {:?}", &formula[p.pos..])));
    }
    Ok(value)
}

/// [`eval`], narrowed to `u32` (texture sizes, workgroup counts).
///
/// # Errors
///
/// As [`eval`]; [`EngineError::Formula`] when the value does not fit in 32 bits.
pub fn eval_u32(formula: &str, params: &Params, context: &str) -> Result<u32, EngineError> {
    let v = eval(formula, params, context)?;
    u32::try_from(v).map_err(|_| EngineError::Formula {
        formula: formula.to_owned(),
        context: context.to_owned(),
        reason: format!("{v} does not fit in 32 bits"),
    })
}

struct Parser<'a> {
    src: &'a str,
    pos: usize,
    params: &'a Params,
    context: &'a str,
}

impl Parser<'_> {
    fn error(&self, reason: String) -> EngineError {
        EngineError::Formula {
            formula: self.src.to_owned(),
            context: self.context.to_owned(),
            reason,
        }
    }

    fn skip_ws(&mut self) {
        while self.src[self.pos..].starts_with(' ') {
            self.pos += 1;
        }
    }

    fn eat(&mut self, token: &str) -> bool {
        self.skip_ws();
        if self.src[self.pos..].starts_with(token) {
            self.pos += token.len();
            true
        } else {
            false
        }
    }

    /// `product ('+' product)*`
    fn sum(&mut self) -> Result<u64, EngineError> {
        let mut value = self.product()?;
        while self.eat("+") {
            let rhs = self.product()?;
            value = value
                .checked_add(rhs)
                .ok_or_else(|| self.error(format!("{value} + {rhs} overflows")))?;
        }
        Ok(value)
    }

    /// `factor ('*' factor)*`
    fn product(&mut self) -> Result<u64, EngineError> {
        let mut value = self.factor()?;
        while self.eat("*") {
            let rhs = self.factor()?;
            value = value
                .checked_mul(rhs)
                .ok_or_else(|| self.error(format!("{value} * {rhs} overflows")))?;
        }
        Ok(value)
    }

    /// `integer | name | 'ceil' '(' sum '/' sum ')'`
    fn factor(&mut self) -> Result<u64, EngineError> {
        self.skip_ws();
        let rest = &self.src[self.pos..];
        let len = rest
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '.'))
            .unwrap_or(rest.len());
        let word = &rest[..len];
        if word.is_empty() {
            return Err(self.error(if rest.is_empty() {
                "ends where a number, a parameter or ceil(...) was expected".to_owned()
            } else {
                format!("unexpected {rest:?}")
            }));
        }
        self.pos += len;
        if word == "ceil" {
            if !self.eat("(") {
                return Err(self.error("`ceil` must be followed by `(`".to_owned()));
            }
            let a = self.sum()?;
            if !self.eat("/") {
                return Err(self.error("`ceil(` takes `a / b`".to_owned()));
            }
            let b = self.sum()?;
            if !self.eat(")") {
                return Err(self.error("`ceil(a / b` lacks its `)`".to_owned()));
            }
            if b == 0 {
                return Err(self.error(format!("ceil({a} / 0) divides by zero")));
            }
            return Ok(a.div_ceil(b));
        }
        if word.starts_with(|c: char| c.is_ascii_digit()) {
            return word
                .parse()
                .map_err(|_| self.error(format!("{word:?} is not an integer")));
        }
        self.params
            .get(word)
            .ok_or_else(|| EngineError::UnknownSymbol {
                formula: self.src.to_owned(),
                context: self.context.to_owned(),
                symbol: word.to_owned(),
                known: self.params.names(),
            })
    }
}

/// Checks `value` against a parameter's constraint `lo..=hi`, optionally written after an
/// expression (`regions^2 = 9..=max_texture_dimension_2d`); `hi` is an integer or a device
/// limit named as in WebGPU (`max_texture_dimension_2d`, ...).
///
/// # Errors
///
/// [`EngineError::Constraint`] when the value is out of range;
/// [`EngineError::Unsupported`] for a constraint this engine cannot read.
pub fn check_constraint(
    name: &str,
    value: u64,
    constraint: &str,
    limits: &wgpu::Limits,
) -> Result<(), EngineError> {
    let range = constraint
        .rsplit_once(" = ")
        .map_or(constraint, |(_, r)| r)
        .trim();
    let unsupported = || EngineError::Unsupported {
        context: format!("constraint of parameter {name}"),
        what: "constraint",
        value: constraint.to_owned(),
    };
    let (lo, hi) = range.split_once("..=").ok_or_else(unsupported)?;
    let lo: u64 = lo.trim().parse().map_err(|_| unsupported())?;
    let hi_text = hi.trim();
    let hi: u64 = match hi_text.parse() {
        Ok(v) => v,
        Err(_) => limit(limits, hi_text).ok_or_else(unsupported)?,
    };
    let fail = |reason: String| {
        Err(EngineError::Constraint {
            name: name.to_owned(),
            value,
            constraint: constraint.to_owned(),
            reason,
        })
    };
    if value < lo {
        return fail(format!("below {lo}"));
    }
    if value > hi {
        return fail(format!("above {hi_text} = {hi} on this device"));
    }
    Ok(())
}

/// A device limit by its WebGPU name.
fn limit(limits: &wgpu::Limits, name: &str) -> Option<u64> {
    Some(match name {
        "max_texture_dimension_1d" => limits.max_texture_dimension_1d.into(),
        "max_texture_dimension_2d" => limits.max_texture_dimension_2d.into(),
        "max_texture_dimension_3d" => limits.max_texture_dimension_3d.into(),
        "max_texture_array_layers" => limits.max_texture_array_layers.into(),
        "max_compute_workgroups_per_dimension" => {
            limits.max_compute_workgroups_per_dimension.into()
        }
        "max_storage_buffer_binding_size" => limits.max_storage_buffer_binding_size,
        "max_uniform_buffer_binding_size" => limits.max_uniform_buffer_binding_size,
        "max_buffer_size" => limits.max_buffer_size,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> Params {
        let mut p = Params::default();
        p.set("screen.width", 1280);
        p.set("rectified.height", 1000);
        p
    }

    #[test]
    fn evaluates_the_grammar() {
        let p = params();
        assert_eq!(eval("8", &p, "t").ok(), Some(8));
        assert_eq!(eval("screen.width", &p, "t").ok(), Some(1280));
        assert_eq!(eval("16 * rectified.height", &p, "t").ok(), Some(16_000));
        assert_eq!(eval("ceil(rectified.height / 64)", &p, "t").ok(), Some(16));
        assert_eq!(eval("ceil(screen.width / 8)", &p, "t").ok(), Some(160));
        assert_eq!(eval("2 * ceil(7 / 2) * 3", &p, "t").ok(), Some(24));
        assert_eq!(eval("ceil(screen.width / 2) + 1", &p, "t").ok(), Some(641));
        assert_eq!(eval("1 + 2 * 3 + 4", &p, "t").ok(), Some(11));
        assert_eq!(eval("ceil(screen.width + 1 / 2)", &p, "t").ok(), Some(641));
    }

    #[test]
    fn reports_unknown_symbols_and_syntax_errors() {
        let p = params();
        let e = eval("ceil(screen.depth / 8)", &p, "pass x").unwrap_err();
        assert!(
            matches!(&e, EngineError::UnknownSymbol { symbol, .. } if symbol == "screen.depth"),
            "{e}"
        );
        assert!(
            e.to_string().contains("screen.width, rectified.height"),
            "{e}"
        );
        for bad in [
            "",
            "ceil(8)",
            "ceil(8 / 0)",
            "8 +",
            "3 *",
            "ceil(8 / 2",
            "-1",
        ] {
            let e = eval(bad, &p, "t").unwrap_err();
            assert!(matches!(e, EngineError::Formula { .. }), "{bad}: {e}");
        }
        let e = eval("4294967296 * 4294967296", &p, "t").unwrap_err();
        assert!(e.to_string().contains("overflows"), "{e}");
        let e = eval("18446744073709551615 + 1", &p, "t").unwrap_err();
        assert!(e.to_string().contains("overflows"), "{e}");
    }

    #[test]
    fn checks_constraints() {
        let limits = wgpu::Limits::default();
        let max = u64::from(limits.max_texture_dimension_2d);
        assert!(check_constraint("a", 1, "1..=max_texture_dimension_2d", &limits).is_ok());
        assert!(check_constraint("a", max + 1, "1..=max_texture_dimension_2d", &limits).is_err());
        assert!(check_constraint("a", 0, "1..=max_texture_dimension_2d", &limits).is_err());
        assert!(
            check_constraint("w", 8, "regions^2 = 9..=max_texture_dimension_2d", &limits).is_err()
        );
        assert!(check_constraint("w", 9, "regions^2 = 9..=16", &limits).is_ok());
        assert!(matches!(
            check_constraint("w", 9, "positive", &limits),
            Err(EngineError::Unsupported { .. })
        ));
    }
}
