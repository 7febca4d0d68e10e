//! The method interface (SPEC section 4): one type per method behind one
//! trait. A method's typed parameters declare and parse its parameters
//! ([`MethodParams`]); the method builds its pipelines ([`Method::new`]) and
//! records a render against a [`Frame`]; [`entry`] makes its registry line
//! (`methods::REGISTRY`). Nothing here names a method.

use std::any::Any;
use std::sync::Arc;

use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::gpu::pool::{PooledTexture, ResourcePool};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::pass_cache::CachedPass;

/// What a method's passes leave for the renderer: the visibility image
/// (visibility-format, the camera's size) that shading reads and readback returns.
pub struct MethodOutput {
    pub visibility: PooledTexture,
}

/// One soft-shadow method.
///
/// A method declares its parameters once and reads them into its own typed
/// form (its [`Method::Params`]' [`MethodParams`], where rules between
/// parameters are checked), builds its pipelines once ([`Method::new`], on
/// its first render) and records all of its passes for one render against
/// a [`Frame`], returning its visibility; it sets its own stats, counters
/// and intermediate images on the frame.
pub trait Method: Send + Sync + Sized + 'static {
    /// Its name in `render(scene, name)` (SPEC section 4).
    const NAME: &'static str;
    /// The paper and sections it implements, for the docs and `penumbra methods`.
    const PAPER: &'static str;
    /// Its parameters in typed form, with their specs and parsing.
    type Params: MethodParams;

    /// The passes whose outputs the pass cache may keep for it (the
    /// G-buffer is always cacheable; the centre shadow map is
    /// [`crate::passes::centre_map::CENTRE_MAP`]).
    fn cached_passes() -> &'static [CachedPass] {
        &[]
    }

    /// Builds its pipelines.
    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self;

    /// Records every pass of one render.
    fn record(&self, frame: &mut Frame<'_>, params: &Self::Params) -> Result<MethodOutput>;
}

/// A built method, its typed parameters erased.
pub trait DynMethod: Send + Sync {
    fn record(&self, frame: &mut Frame<'_>, params: &(dyn Any + Send + Sync)) -> Result<MethodOutput>;
}

impl<M: Method> DynMethod for M {
    fn record(&self, frame: &mut Frame<'_>, params: &(dyn Any + Send + Sync)) -> Result<MethodOutput> {
        let params = params
            .downcast_ref::<M::Params>()
            .ok_or_else(|| Error::InvalidParameter(format!("parameters given to method '{}' are another method's", M::NAME)))?;
        Method::record(self, frame, params)
    }
}

/// A registry entry: what is known of a method without a GPU, and how to build it.
pub struct Registered {
    pub name: &'static str,
    pub paper: &'static str,
    pub specs: fn() -> Vec<ParamSpec>,
    pub cached_passes: fn() -> &'static [CachedPass],
    pub(crate) parse: fn(&ParamSet) -> Result<Arc<dyn Any + Send + Sync>>,
    pub(crate) build: fn(&wgpu::Device, &ResourcePool) -> Box<dyn DynMethod>,
}

fn parse_typed<M: Method>(set: &ParamSet) -> Result<Arc<dyn Any + Send + Sync>> {
    Ok(Arc::new(M::Params::parse(set)?))
}

fn build<M: Method>(device: &wgpu::Device, pool: &ResourcePool) -> Box<dyn DynMethod> {
    Box::new(M::new(device, pool))
}

/// The registry entry of method `M`.
pub const fn entry<M: Method>() -> Registered {
    Registered {
        name: M::NAME,
        paper: M::PAPER,
        specs: M::Params::specs,
        cached_passes: M::cached_passes,
        parse: parse_typed::<M>,
        build: build::<M>,
    }
}
