//! Method parameters, declared once per method: name, type, range, default
//! and a line of documentation. The declaration serves the parser
//! ([`ParamSet::parse`]), the command line and the Python docstrings
//! (`penumbra.method_params`) and the docs table (`docs/methods/README.md`,
//! checked against it by a test).

use std::collections::BTreeMap;
use std::fmt;

use crate::error::{Error, Result};

/// A method's parameters in typed form: every parameter it takes, and their
/// reading from a checked set (`Method::Params`).
pub trait MethodParams: Sized + Send + Sync + 'static {
    /// Every parameter, with type, range, default and a line of docs.
    fn specs() -> Vec<ParamSpec>;

    /// The typed form of a checked set; rules between parameters are
    /// checked here ([`Error::InvalidParameter`]).
    fn parse(set: &ParamSet) -> Result<Self>;
}

/// A parameter value as it arrives from Python or the CLI.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(String),
}

impl ParamValue {
    pub fn type_name(&self) -> &'static str {
        match self {
            ParamValue::Bool(_) => "bool",
            ParamValue::Int(_) => "int",
            ParamValue::Float(_) => "float",
            ParamValue::Str(_) => "str",
        }
    }
}

/// Values as a user writes them: `true`, `3`, `0.5`, `'grid'`.
impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Bool(b) => write!(f, "{}", if *b { "True" } else { "False" }),
            ParamValue::Int(i) => write!(f, "{i}"),
            ParamValue::Float(x) => write!(f, "{x:?}"),
            ParamValue::Str(s) => write!(f, "'{s}'"),
        }
    }
}

/// The value of an `IntOrAuto` parameter that leaves the choice to each render.
pub const AUTO: &str = "auto";

/// What values a parameter takes.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamKind {
    Bool,
    /// An integer in `[min, max]`.
    Int { min: i64, max: i64 },
    /// A shadow map's side in texels, an integer in `[min, max]`, or
    /// `"auto"`: the renderer chooses it per render from the image
    /// (`crate::map_size`; `MethodConfig::auto_map_size` finds it by this kind).
    MapSize { min: i64, max: i64 },
    /// A finite number in `[min, max]`, or `(min, max]` when `min_exclusive`.
    Float { min: f64, max: f64, min_exclusive: bool },
    /// One of the names.
    Choice(&'static [&'static str]),
}

/// One declared parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamSpec {
    pub name: &'static str,
    pub kind: ParamKind,
    pub default: ParamValue,
    /// One line for the docs table and the docstrings.
    pub doc: &'static str,
}

impl ParamSpec {
    pub fn int(name: &'static str, default: i64, min: i64, max: i64, doc: &'static str) -> Self {
        Self { name, kind: ParamKind::Int { min, max }, default: ParamValue::Int(default), doc }
    }

    /// `seed`: an integer in `[0, max]`, 0 by default, that fixes a method's jitter.
    pub fn seed(max: i64, doc: &'static str) -> Self {
        Self::int("seed", 0, 0, max, doc)
    }

    /// A shadow map's side (`ParamKind::MapSize`): `"auto"` or an integer in
    /// `[min, max]`, `default` by default.
    pub fn map_size(name: &'static str, default: i64, min: i64, max: i64, doc: &'static str) -> Self {
        Self { name, kind: ParamKind::MapSize { min, max }, default: ParamValue::Int(default), doc }
    }

    pub fn float(name: &'static str, default: f64, min: f64, max: f64, doc: &'static str) -> Self {
        Self { name, kind: ParamKind::Float { min, max, min_exclusive: false }, default: ParamValue::Float(default), doc }
    }

    /// A number in `(min, max]`.
    pub fn float_above(name: &'static str, default: f64, min: f64, max: f64, doc: &'static str) -> Self {
        Self { name, kind: ParamKind::Float { min, max, min_exclusive: true }, default: ParamValue::Float(default), doc }
    }

    pub fn bool(name: &'static str, default: bool, doc: &'static str) -> Self {
        Self { name, kind: ParamKind::Bool, default: ParamValue::Bool(default), doc }
    }

    pub fn choice(name: &'static str, default: &'static str, choices: &'static [&'static str], doc: &'static str) -> Self {
        debug_assert!(choices.contains(&default));
        Self { name, kind: ParamKind::Choice(choices), default: ParamValue::Str(default.into()), doc }
    }

    /// The same parameter with another default (e.g. `pvmf`'s bias).
    pub fn with_default(mut self, default: ParamValue) -> Self {
        self.default = default;
        self
    }

    /// The accepted values in words: `an integer in [16, 16384]`.
    pub fn range(&self) -> String {
        match &self.kind {
            ParamKind::Bool => "a bool".into(),
            ParamKind::Int { min, max } => format!("an integer in [{min}, {max}]"),
            ParamKind::MapSize { min, max } => format!("'{AUTO}' or an integer in [{min}, {max}]"),
            ParamKind::Float { min, max, min_exclusive: false } => format!("a number in [{min}, {max}]"),
            ParamKind::Float { min, max, min_exclusive: true } => format!("a number in ({min}, {max}]"),
            ParamKind::Choice(choices) => {
                let quoted: Vec<String> = choices.iter().map(|c| format!("'{c}'")).collect();
                format!("one of {}", quoted.join(", "))
            }
        }
    }

    /// `value` checked against the declaration, converted where lossless
    /// (an integer for a float parameter).
    fn check(&self, method: &str, value: &ParamValue) -> Result<ParamValue> {
        let wrong = || {
            Error::InvalidParameter(format!(
                "parameter '{}' of method '{method}' must be {}, got {} {value}",
                self.name,
                self.range(),
                value.type_name()
            ))
        };
        let out = match (&self.kind, value) {
            (ParamKind::Bool, ParamValue::Bool(_)) => value.clone(),
            (ParamKind::MapSize { .. }, ParamValue::Str(s)) if s == AUTO => value.clone(),
            (ParamKind::Int { min, max } | ParamKind::MapSize { min, max }, ParamValue::Int(v)) => {
                if v < min || v > max {
                    return Err(wrong());
                }
                value.clone()
            }
            (ParamKind::Float { min, max, min_exclusive }, ParamValue::Float(_) | ParamValue::Int(_)) => {
                let v = match value {
                    ParamValue::Float(v) => *v,
                    ParamValue::Int(i) => *i as f64,
                    _ => unreachable!(),
                };
                let below = if *min_exclusive { v <= *min } else { v < *min };
                if !v.is_finite() || below || v > *max {
                    return Err(wrong());
                }
                ParamValue::Float(v)
            }
            (ParamKind::Choice(choices), ParamValue::Str(s)) => {
                if !choices.contains(&s.as_str()) {
                    return Err(wrong());
                }
                value.clone()
            }
            _ => return Err(wrong()),
        };
        Ok(out)
    }
}

/// A method's parameters, checked, with every default filled in: what a
/// render used (`RenderResult::params`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParamSet {
    values: BTreeMap<&'static str, ParamValue>,
}

impl ParamSet {
    /// Checks `given` against `specs`: unknown names, wrong types and values
    /// out of range are [`Error::InvalidParameter`] naming the parameter.
    pub fn parse(method: &str, specs: &[ParamSpec], given: &BTreeMap<String, ParamValue>) -> Result<Self> {
        let unknown: Vec<&String> = given.keys().filter(|k| !specs.iter().any(|s| s.name == k.as_str())).collect();
        if !unknown.is_empty() {
            let names: Vec<&str> = specs.iter().map(|s| s.name).collect();
            let unknown: Vec<String> = unknown.iter().map(|k| format!("'{k}'")).collect();
            return Err(Error::InvalidParameter(format!(
                "unknown parameter(s) {} for method '{method}'; it takes {}",
                unknown.join(", "),
                names.join(", ")
            )));
        }
        let mut values = BTreeMap::new();
        for spec in specs {
            let value = match given.get(spec.name) {
                Some(v) => spec.check(method, v)?,
                None => spec.default.clone(),
            };
            values.insert(spec.name, value);
        }
        Ok(Self { values })
    }

    fn get(&self, name: &str) -> &ParamValue {
        self.values.get(name).unwrap_or_else(|| panic!("parameter '{name}' is not declared"))
    }

    /// A declared integer parameter (panics on an undeclared name: a bug).
    pub fn int(&self, name: &str) -> i64 {
        match self.get(name) {
            ParamValue::Int(v) => *v,
            other => panic!("parameter '{name}' is declared {}, read as int", other.type_name()),
        }
    }

    /// A declared `"auto"`-or-integer parameter: `None` for `"auto"`.
    pub fn int_or_auto(&self, name: &str) -> Option<i64> {
        match self.get(name) {
            ParamValue::Int(v) => Some(*v),
            ParamValue::Str(s) if s == AUTO => None,
            other => panic!("parameter '{name}' is declared {}, read as int or auto", other.type_name()),
        }
    }

    /// Whether the set declares `name` (a method's parameters differ).
    pub fn has(&self, name: &str) -> bool {
        self.values.contains_key(name)
    }

    /// The same set with `name` (declared) set to `value`, unchecked: for a
    /// value the renderer resolves (an `"auto"` map size).
    pub fn with(&self, name: &'static str, value: ParamValue) -> Self {
        let mut values = self.values.clone();
        values.insert(name, value);
        Self { values }
    }

    pub fn float(&self, name: &str) -> f64 {
        match self.get(name) {
            ParamValue::Float(v) => *v,
            other => panic!("parameter '{name}' is declared {}, read as float", other.type_name()),
        }
    }

    pub fn bool(&self, name: &str) -> bool {
        match self.get(name) {
            ParamValue::Bool(v) => *v,
            other => panic!("parameter '{name}' is declared {}, read as bool", other.type_name()),
        }
    }

    pub fn choice(&self, name: &str) -> &str {
        match self.get(name) {
            ParamValue::Str(v) => v,
            other => panic!("parameter '{name}' is declared {}, read as str", other.type_name()),
        }
    }

    /// Every parameter in effect, defaults included, by name.
    pub fn effective(&self) -> BTreeMap<String, ParamValue> {
        self.values.iter().map(|(k, v)| ((*k).to_owned(), v.clone())).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn specs() -> Vec<ParamSpec> {
        vec![
            ParamSpec::int("n", 4, 1, 32, "taps"),
            ParamSpec::float("w", 0.5, 0.0, 1.0, "weight"),
            ParamSpec::float_above("s", 0.5, 0.0, 1.0, "scale"),
            ParamSpec::bool("on", true, "switch"),
            ParamSpec::choice("mode", "a", &["a", "b"], "mode"),
        ]
    }

    fn given(pairs: &[(&str, ParamValue)]) -> BTreeMap<String, ParamValue> {
        pairs.iter().map(|(k, v)| ((*k).to_owned(), v.clone())).collect()
    }

    #[test]
    fn defaults_fill_in_and_integers_widen_to_floats() {
        let set = ParamSet::parse("m", &specs(), &given(&[("w", ParamValue::Int(1))])).unwrap();
        assert_eq!(set.int("n"), 4);
        assert_eq!(set.float("w"), 1.0);
        assert!(set.bool("on"));
        assert_eq!(set.choice("mode"), "a");
        assert_eq!(set.effective().len(), 5);
    }

    #[test]
    fn errors_name_the_parameter_in_the_users_words() {
        let err = |pairs: &[(&str, ParamValue)]| ParamSet::parse("m", &specs(), &given(pairs)).unwrap_err().to_string();
        let e = err(&[("n", ParamValue::Str("abc".into()))]);
        assert_eq!(e, "parameter 'n' of method 'm' must be an integer in [1, 32], got str 'abc'");
        let e = err(&[("n", ParamValue::Float(256.0))]);
        assert_eq!(e, "parameter 'n' of method 'm' must be an integer in [1, 32], got float 256.0");
        assert!(err(&[("n", ParamValue::Int(33))]).contains("got int 33"));
        assert!(err(&[("s", ParamValue::Float(0.0))]).contains("(0, 1]"));
        assert!(err(&[("w", ParamValue::Float(f64::NAN))]).contains("[0, 1]"));
        assert!(err(&[("mode", ParamValue::Str("c".into()))]).contains("one of 'a', 'b', got str 'c'"));
        assert!(err(&[("on", ParamValue::Int(1))]).contains("must be a bool, got int 1"));
        let e = err(&[("x", ParamValue::Int(1)), ("y", ParamValue::Int(1))]);
        assert_eq!(e, "unknown parameter(s) 'x', 'y' for method 'm'; it takes n, w, s, on, mode");
    }

    #[test]
    fn a_map_size_takes_auto_or_an_integer_in_range() {
        let specs = vec![ParamSpec::map_size("map_size", 2048, 16, 16384, "size")];
        let set = ParamSet::parse("m", &specs, &given(&[])).unwrap();
        assert_eq!(set.int_or_auto("map_size"), Some(2048));
        let auto = ParamSet::parse("m", &specs, &given(&[("map_size", ParamValue::Str("auto".into()))])).unwrap();
        assert_eq!(auto.int_or_auto("map_size"), None);
        assert_eq!(auto.with("map_size", ParamValue::Int(512)).int_or_auto("map_size"), Some(512));
        for bad in [ParamValue::Str("big".into()), ParamValue::Int(8), ParamValue::Float(512.0), ParamValue::Bool(true)] {
            let e = ParamSet::parse("m", &specs, &given(&[("map_size", bad)])).unwrap_err().to_string();
            assert!(e.contains("'auto' or an integer in [16, 16384]"), "{e}");
        }
    }
}
