//! Soft-shadow methods (SPEC section 4), each in its own folder with its
//! WGSL beside it behind the trait of [`crate::method`], and the registry
//! that lists them. Adding a method is its folder and one line in
//! [`REGISTRY`]; the renderer and the pass cache know no method by name.

use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;
use std::any::Any;

use crate::error::{Error, Result};
use crate::method::{entry, Registered};
use crate::params::{ParamKind, ParamSet, ParamValue};

pub mod adaptive;
pub mod backprojection;
pub mod hard;
pub mod pcf;
pub mod pcss;
pub mod pvm;
pub mod pvmf;
pub mod raytraced;
pub mod reference;
pub mod triangle_masks;
pub mod wedges;

/// Every implemented method, in the order of SPEC section 4.
pub static REGISTRY: &[Registered] = &[
    entry::<hard::HardShadow>(),
    entry::<pcf::PercentageCloserFiltering>(),
    entry::<pcss::PercentageCloserSoftShadows>(),
    entry::<reference::ReferenceShadows>(),
    entry::<adaptive::AdaptiveShadows>(),
    entry::<pvm::PenumbraVolumeMaps>(),
    entry::<pvmf::PenumbraVolumeMaskFiltering>(),
    entry::<wedges::PenumbraWedges>(),
    entry::<backprojection::SoftShadowBackprojection>(),
    entry::<raytraced::RaytracedShadows>(),
    entry::<triangle_masks::TriangleMasks>(),
];

/// Every registered method's name with whether it is implemented (all are:
/// the registry is the one list of methods; the flag keeps the binding's
/// `methods(implemented_only=...)` form).
pub fn methods() -> Vec<(&'static str, bool)> {
    REGISTRY.iter().map(|r| (r.name, true)).collect()
}

/// The registry entry of `name`.
pub fn registered(name: &str) -> Result<(usize, &'static Registered)> {
    REGISTRY.iter().enumerate().find(|(_, r)| r.name == name).ok_or_else(|| {
        let implemented: Vec<&str> = REGISTRY.iter().map(|r| r.name).collect();
        Error::InvalidParameter(format!("unknown method '{name}'; available: {}", implemented.join(", ")))
    })
}

/// A method with its checked parameters.
#[derive(Clone)]
pub struct MethodConfig {
    entry: &'static Registered,
    set: ParamSet,
    typed: Arc<dyn Any + Send + Sync>,
}

impl MethodConfig {
    /// A registered method (by name) with `params` checked against its specs.
    pub fn parse(method: &str, params: &BTreeMap<String, ParamValue>) -> Result<Self> {
        Self::of(registered(method)?.1, params)
    }

    /// The method of registry entry `entry` (`method::entry::<M>()`, in
    /// [`REGISTRY`] or not: a method a crate defines outside it renders
    /// alike) with `params` checked against its specs.
    pub fn of(entry: &'static Registered, params: &BTreeMap<String, ParamValue>) -> Result<Self> {
        let set = ParamSet::parse(entry.name, &(entry.specs)(), params)?;
        let typed = (entry.parse)(&set)?;
        Ok(Self { entry, set, typed })
    }

    pub fn name(&self) -> &'static str {
        self.entry.name
    }

    /// The method's registry entry.
    pub fn entry(&self) -> &'static Registered {
        self.entry
    }

    /// The parameters in effect, defaults included, for the result's record.
    pub fn effective_params(&self) -> BTreeMap<String, ParamValue> {
        self.set.effective()
    }

    /// The parameter of kind [`ParamKind::MapSize`] set to `"auto"`, if
    /// any, and the projection its maps use (the method's `projection`, else
    /// `auto`): the renderer then resolves the size ([`crate::map_size`])
    /// with [`Self::with_map_size`] before the method records.
    pub fn auto_map_size(&self) -> Option<(&'static str, crate::light_frustum::ProjectionMode)> {
        let spec = (self.entry.specs)().into_iter().find(|s| matches!(s.kind, ParamKind::MapSize { .. }) && self.set.int_or_auto(s.name).is_none())?;
        let projection = if self.set.has("projection") { self.set.choice("projection") } else { "auto" };
        Some((spec.name, crate::light_frustum::ProjectionMode::parse(projection)))
    }

    /// This configuration with map-size parameter `name` set to `map_size`
    /// texels (the effective parameters keep what was asked: `"auto"`).
    pub fn with_map_size(&self, name: &'static str, map_size: u32) -> Result<Self> {
        let set = self.set.with(name, ParamValue::Int(map_size as i64));
        let typed = (self.entry.parse)(&set)?;
        Ok(Self { entry: self.entry, set: self.set.clone(), typed })
    }

    pub(crate) fn typed(&self) -> &(dyn Any + Send + Sync) {
        &*self.typed
    }
}

impl fmt::Debug for MethodConfig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MethodConfig").field("method", &self.name()).field("params", &self.set).finish()
    }
}

impl PartialEq for MethodConfig {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self.entry, other.entry) && self.set == other.set
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_is_registered_once_and_declares_distinct_parameters() {
        for r in REGISTRY {
            assert_eq!(REGISTRY.iter().filter(|o| o.name == r.name).count(), 1, "{} registered twice", r.name);
            let specs = (r.specs)();
            for (i, s) in specs.iter().enumerate() {
                assert!(specs[..i].iter().all(|t| t.name != s.name), "{}: '{}' declared twice", r.name, s.name);
                assert!(!s.doc.is_empty(), "{}: '{}' has no doc", r.name, s.name);
            }
            // The defaults pass the method's own checks.
            MethodConfig::parse(r.name, &BTreeMap::new()).unwrap();
        }
    }

    #[test]
    fn unknown_methods_are_named_with_the_registered_ones() {
        let e = MethodConfig::parse("magic", &BTreeMap::new()).unwrap_err().to_string();
        assert!(e.starts_with("unknown method 'magic'; available: hard"), "{e}");
        assert_eq!(methods().len(), REGISTRY.len());
        assert!(methods().iter().all(|(_, implemented)| *implemented));
    }
}
