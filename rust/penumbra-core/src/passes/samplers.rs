//! The comparison samplers of the percentage-closer methods (`pcf`, `pcss`,
//! `pvmf`) and the `filter` parameter that picks one. The taps themselves
//! are `pcf_taps.wgsl` beside this file.

use crate::gpu::layout;
use crate::gpu::pool::{Binding, ResourcePool};
use crate::params::{ParamSet, ParamSpec};

/// How each percentage-closer tap reads the map.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Filter {
    /// The comparison sampler's 2x2 bilinear PCF.
    Bilinear,
    /// The nearest texel's test.
    Nearest,
}

impl Filter {
    pub const NAMES: [&'static str; 2] = ["bilinear", "nearest"];

    pub fn spec() -> ParamSpec {
        ParamSpec::choice("filter", "bilinear", &Self::NAMES, "each tap: the hardware's 2x2 bilinear comparison, or the nearest texel")
    }

    pub fn from_params(p: &ParamSet) -> Self {
        match p.choice("filter") {
            "nearest" => Filter::Nearest,
            _ => Filter::Bilinear,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Filter::Bilinear => "bilinear",
            Filter::Nearest => "nearest",
        }
    }
}

/// Both comparison samplers, built once; a render binds the one it asks for.
pub struct ComparisonSamplers {
    bilinear: (u64, wgpu::Sampler),
    nearest: (u64, wgpu::Sampler),
}

impl ComparisonSamplers {
    pub fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        Self {
            bilinear: (pool.new_id(), layout::create_comparison_sampler(device, true)),
            nearest: (pool.new_id(), layout::create_comparison_sampler(device, false)),
        }
    }

    /// The pool's one pair (built on first use, shared by every method).
    pub fn shared(device: &wgpu::Device, pool: &ResourcePool) -> std::sync::Arc<Self> {
        pool.shared(|| Self::new(device, pool))
    }

    pub fn get(&self, filter: Filter) -> &wgpu::Sampler {
        match filter {
            Filter::Bilinear => &self.bilinear.1,
            Filter::Nearest => &self.nearest.1,
        }
    }

    /// The sampler as a (cacheable) binding.
    pub fn binding(&self, filter: Filter) -> Binding<'_> {
        let (id, sampler) = match filter {
            Filter::Bilinear => &self.bilinear,
            Filter::Nearest => &self.nearest,
        };
        Binding::Other(*id, wgpu::BindingResource::Sampler(sampler))
    }
}
