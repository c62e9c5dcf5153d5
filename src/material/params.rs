//! Models' parameters: each model (an EOS, a strength model, a damage model) lists its own
//! numeric parameters once, with their meaning, unit, default and valid range, and builds itself
//! from their values with its own cross-checks. The deck reader, the library and `strike
//! materials` all go through this list, so a new model is one new file and one line in its
//! family's list of models.

/// The values a parameter may take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Valid {
    /// Any finite number.
    Any,
    /// > 0.
    Positive,
    /// ≥ 0.
    NonNegative,
    /// In [lo, hi].
    Closed(f64, f64),
    /// In [lo, hi).
    HalfOpen(f64, f64),
}

impl Valid {
    pub fn accepts(self, x: f64) -> bool {
        x.is_finite()
            && match self {
                Valid::Any => true,
                Valid::Positive => x > 0.0,
                Valid::NonNegative => x >= 0.0,
                Valid::Closed(lo, hi) => (lo..=hi).contains(&x),
                Valid::HalfOpen(lo, hi) => x >= lo && x < hi,
            }
    }

    /// "must be …", for an error message.
    pub fn requirement(self) -> String {
        match self {
            Valid::Any => "must be a finite number".into(),
            Valid::Positive => "must be positive".into(),
            Valid::NonNegative => "must be zero or positive".into(),
            Valid::Closed(lo, hi) => format!("must be in [{lo}, {hi}]"),
            Valid::HalfOpen(lo, hi) => format!("must be in [{lo}, {hi})"),
        }
    }
}

/// One numeric parameter of a model.
#[derive(Debug, Clone, Copy)]
pub struct Param {
    /// Its key in the deck.
    pub key: &'static str,
    /// What it is, with its unit and a typical value (for errors and listings).
    pub what: &'static str,
    pub valid: Valid,
    /// Its value where the deck leaves it out; None: required.
    pub default: Option<f64>,
}

impl Param {
    pub const fn required(key: &'static str, what: &'static str, valid: Valid) -> Self {
        Param {
            key,
            what,
            valid,
            default: None,
        }
    }

    pub const fn optional(
        key: &'static str,
        what: &'static str,
        valid: Valid,
        default: f64,
    ) -> Self {
        Param {
            key,
            what,
            valid,
            default: Some(default),
        }
    }
}

/// A model's cross-check failed: which parameter, what is wrong, what would be right.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamError {
    pub key: &'static str,
    pub message: String,
    pub help: String,
}

impl ParamError {
    pub fn new(key: &'static str, message: impl Into<String>, help: impl Into<String>) -> Self {
        ParamError {
            key,
            message: message.into(),
            help: help.into(),
        }
    }
}

/// A model with a parameter list: built from the values of [`Parameters::PARAMS`] in their
/// order (each already checked against its [`Valid`]), and giving them back.
pub trait Parameters: Sized {
    /// Its `type` in the deck.
    const NAME: &'static str;
    const PARAMS: &'static [Param];
    /// Build from the values, with the checks that involve several of them.
    fn from_values(v: &[f64]) -> Result<Self, ParamError>;
    /// The values, in the order of `PARAMS`.
    fn values(&self) -> Vec<f64>;

    /// Build from (key, value) pairs with the defaults filled in, as a library does: panics on
    /// a missing or invalid value, which is a bug in the caller's table, never a user's input.
    fn from_pairs(pairs: &[(&str, f64)]) -> Self {
        let v = values_from_pairs(Self::NAME, Self::PARAMS, pairs);
        Self::from_values(&v).unwrap_or_else(|e| panic!("{}: {}", Self::NAME, e.message))
    }
}

/// The values of `params` from (key, value) pairs, defaults filled in, for a library's table:
/// panics on a missing or invalid value (a bug in the table, never a user's input).
pub fn values_from_pairs(model: &str, params: &[Param], pairs: &[(&str, f64)]) -> Vec<f64> {
    params
        .iter()
        .map(|p| {
            let x = pairs
                .iter()
                .find(|(k, _)| *k == p.key)
                .map(|&(_, x)| x)
                .or(p.default)
                .unwrap_or_else(|| panic!("{model}: no value for `{}`", p.key));
            assert!(p.valid.accepts(x), "{model}: `{}` = {x}", p.key);
            x
        })
        .collect()
}
