//! Soft-shadow methods (SPEC section 4): names, parameters and their checks.
//! Each method lives in its own module with its WGSL beside it.

use std::collections::BTreeMap;

use crate::error::{Error, Result};

pub mod hard;
pub mod pcf;
pub mod pcss;
pub mod pvm;
pub mod pvmf;
pub mod reference;


pub use hard::{BiasMode, HardParams, ShadowMapSettings};
pub use pcf::PcfParams;
pub use pcss::PcssParams;
pub use pvm::PvmParams;
pub use pvmf::PvmfParams;
pub use reference::ReferenceParams;

/// A parameter value as it arrives from Python or the CLI.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(String),
}

/// As Python writes the value (`True`, `256`, `256.0`, `'abc'`): the form
/// the caller typed, for messages.
impl std::fmt::Display for ParamValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamValue::Bool(b) => f.write_str(if *b { "True" } else { "False" }),
            ParamValue::Int(i) => write!(f, "{i}"),
            ParamValue::Float(x) if !x.is_finite() => write!(f, "{x}"),
            ParamValue::Float(x) if *x != 0.0 && !(1e-4..1e16).contains(&x.abs()) => write!(f, "{x:e}"),
            ParamValue::Float(x) if x.fract() == 0.0 => write!(f, "{x:.1}"),
            ParamValue::Float(x) => write!(f, "{x}"),
            ParamValue::Str(s) => write!(f, "'{}'", s.replace('\\', "\\\\").replace('\'', "\\'")),
        }
    }
}

impl ParamValue {
    fn type_name(&self) -> &'static str {
        match self {
            ParamValue::Bool(_) => "bool",
            ParamValue::Int(_) => "int",
            ParamValue::Float(_) => "float",
            ParamValue::Str(_) => "str",
        }
    }
}

/// Every method name SPEC section 4 defines, and whether it is implemented.
pub const METHODS: &[(&str, bool)] = &[
    ("hard", true),
    ("pcf", true),
    ("pcss", true),
    ("reference", true),
    ("adaptive", false),
    ("pvm", true),
    ("pvmf", true),
    ("wedges", false),
    ("backprojection", false),
];

/// A method with its checked parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum MethodConfig {
    Hard(HardParams),
    Pcf(PcfParams),
    Pcss(PcssParams),
    Pvm(PvmParams),
    Pvmf(PvmfParams),
    Reference(ReferenceParams),
}

impl MethodConfig {
    pub fn parse(method: &str, params: &BTreeMap<String, ParamValue>) -> Result<Self> {
        let mut reader = ParamReader::new(method, params);
        let config = match method {
            "hard" => MethodConfig::Hard(HardParams::read(&mut reader)?),
            "pcf" => MethodConfig::Pcf(PcfParams::read(&mut reader)?),
            "pcss" => MethodConfig::Pcss(PcssParams::read(&mut reader)?),
            "pvm" => MethodConfig::Pvm(PvmParams::read(&mut reader)?),
            "pvmf" => MethodConfig::Pvmf(PvmfParams::read(&mut reader)?),
            "reference" => MethodConfig::Reference(ReferenceParams::read(&mut reader)?),
            _ => {
                let implemented: Vec<&str> = METHODS.iter().filter(|m| m.1).map(|m| m.0).collect();
                return Err(Error::InvalidParameter(
                    if METHODS.iter().any(|m| m.0 == method) {
                        format!("method '{method}' is not implemented yet; available: {implemented:?}")
                    } else {
                        format!("unknown method '{method}'; available: {implemented:?}")
                    },
                ));
            }
        };
        reader.finish()?;
        Ok(config)
    }

    pub fn name(&self) -> &'static str {
        match self {
            MethodConfig::Hard(_) => "hard",
            MethodConfig::Pcf(_) => "pcf",
            MethodConfig::Pcss(_) => "pcss",
            MethodConfig::Pvm(_) => "pvm",
            MethodConfig::Pvmf(_) => "pvmf",
            MethodConfig::Reference(_) => "reference",
        }
    }

    /// The parameters in effect, defaults included, for the result's record.
    pub fn effective_params(&self) -> BTreeMap<String, ParamValue> {
        match self {
            MethodConfig::Hard(p) => p.effective(),
            MethodConfig::Pcf(p) => p.effective(),
            MethodConfig::Pcss(p) => p.effective(),
            MethodConfig::Pvm(p) => p.effective(),
            MethodConfig::Pvmf(p) => p.effective(),
            MethodConfig::Reference(p) => p.effective(),
        }
    }

    /// The shadow maps this method renders (from the light centre, or from
    /// each light sample for `reference`).
    pub fn shadow_map(&self) -> &ShadowMapSettings {
        match self {
            MethodConfig::Hard(p) => p,
            MethodConfig::Pcf(p) => &p.shadow,
            MethodConfig::Pcss(p) => &p.shadow,
            MethodConfig::Pvm(p) => &p.shadow,
            MethodConfig::Pvmf(p) => &p.shadow,
            MethodConfig::Reference(p) => &p.shadow,
        }
    }
}

/// Reads named parameters with defaults and ranges; `finish` refuses the rest.
pub struct ParamReader<'a> {
    method: &'a str,
    params: &'a BTreeMap<String, ParamValue>,
    known: Vec<&'static str>,
}

impl<'a> ParamReader<'a> {
    pub fn new(method: &'a str, params: &'a BTreeMap<String, ParamValue>) -> Self {
        Self { method, params, known: Vec::new() }
    }

    fn wrong_type(&self, name: &str, expected: &str, got: &ParamValue) -> Error {
        Error::InvalidParameter(format!(
            "parameter '{name}' of method '{}' must be {expected}, got {} {got}",
            self.method,
            got.type_name()
        ))
    }

    fn out_of_range(&self, name: &str, value: impl std::fmt::Display, range: &str) -> Error {
        Error::InvalidParameter(format!(
            "parameter '{name}' of method '{}' must be in {range}, got {value}",
            self.method
        ))
    }

    pub fn int(&mut self, name: &'static str, default: i64, min: i64, max: i64) -> Result<i64> {
        self.known.push(name);
        let value = match self.params.get(name) {
            None => default,
            Some(ParamValue::Int(v)) => *v,
            Some(other) => return Err(self.wrong_type(name, "an integer", other)),
        };
        if value < min || value > max {
            return Err(self.out_of_range(name, value, &format!("[{min}, {max}]")));
        }
        Ok(value)
    }

    pub fn float(&mut self, name: &'static str, default: f64, min: f64, max: f64) -> Result<f64> {
        self.known.push(name);
        let value = match self.params.get(name) {
            None => default,
            Some(ParamValue::Float(v)) => *v,
            Some(ParamValue::Int(v)) => *v as f64,
            Some(other) => return Err(self.wrong_type(name, "a number", other)),
        };
        if !value.is_finite() || value < min || value > max {
            return Err(self.out_of_range(name, value, &format!("[{min}, {max}]")));
        }
        Ok(value)
    }

    pub fn bool(&mut self, name: &'static str, default: bool) -> Result<bool> {
        self.known.push(name);
        match self.params.get(name) {
            None => Ok(default),
            Some(ParamValue::Bool(b)) => Ok(*b),
            Some(other) => Err(self.wrong_type(name, "a bool", other)),
        }
    }

    pub fn choice(&mut self, name: &'static str, default: &'static str, choices: &[&'static str]) -> Result<&'static str> {
        self.known.push(name);
        match self.params.get(name) {
            None => Ok(default),
            Some(ParamValue::Str(s)) => choices.iter().copied().find(|c| c == s).ok_or_else(|| {
                Error::InvalidParameter(format!(
                    "parameter '{name}' of method '{}' must be one of {choices:?}, got {s:?}",
                    self.method
                ))
            }),
            Some(other) => Err(self.wrong_type(name, &format!("one of {choices:?}"), other)),
        }
    }

    pub fn finish(self) -> Result<()> {
        let unknown: Vec<&String> = self.params.keys().filter(|k| !self.known.contains(&k.as_str())).collect();
        if unknown.is_empty() {
            Ok(())
        } else {
            Err(Error::InvalidParameter(format!(
                "unknown parameter(s) {unknown:?} for method '{}'; it takes {:?}",
                self.method, self.known
            )))
        }
    }
}
