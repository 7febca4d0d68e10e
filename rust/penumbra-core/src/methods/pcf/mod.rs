//! Method `pcf`: percentage-closer filtering with a fixed kernel (Reeves et
//! al. 1987; Cournia 3.4).
//!
//! Visibility is the fraction of shadow-map tests that pass over a square of
//! `kernel` texels centred on the receiver's map coordinates, estimated with
//! an n x n jittered grid (`samples` = n; the jitter is fixed by `seed` and
//! the pixel). Each tap is `pcf_tap` of `passes/pcf_taps.wgsl`: the comparison
//! against the receiver's tangent plane along the tap's ray, through a
//! comparison sampler (`filter`: `bilinear` is the hardware's 2x2 PCF,
//! `nearest` one texel). A zero-width nearest kernel is the single test of
//! `hard`, and is computed by the same function, bias included.

use crate::error::Result;
use crate::frame::Frame;
use crate::gpu::layout;
use crate::gpu::pool::{Binding, ResourcePool};
use crate::method::{Method, MethodOutput};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::pass_cache::CachedPass;
use crate::passes::centre_map::{self, CENTRE_MAP};
use crate::passes::samplers::{ComparisonSamplers, Filter};
use crate::passes::screen::ScreenPass;
use crate::passes::shadow_test::ShadowMapSettings;

#[derive(Debug, Clone, PartialEq)]
pub struct PcfParams {
    pub shadow: ShadowMapSettings,
    /// Kernel width in shadow-map texels.
    pub kernel: f32,
    /// Taps per axis of the jittered grid.
    pub samples: u32,
    pub seed: u32,
    pub filter: Filter,
}

crate::gpu_type! {
    pub struct PcfUniform => "PcfKernel" in "methods/pcf/visibility.wgsl" {
        pub(crate) kernel: f32,
        pub(crate) samples: u32,
        pub(crate) seed: u32,
        pub(crate) nearest: u32,
    }
}

pub struct PercentageCloserFiltering {
    visibility: ScreenPass,
}

impl MethodParams for PcfParams {
    fn specs() -> Vec<ParamSpec> {
        ShadowMapSettings::specs_and([
            ParamSpec::float("kernel", 5.0, 0.0, 256.0, "kernel width in shadow-map texels"),
            ParamSpec::int("samples", 4, 1, 32, "taps per axis of the jittered grid"),
            ParamSpec::seed(u32::MAX as i64, "fixes the taps' jitter"),
            Filter::spec(),
        ])
    }

    fn parse(p: &ParamSet) -> Result<PcfParams> {
        Ok(PcfParams {
            shadow: ShadowMapSettings::from_params(p),
            kernel: p.float("kernel") as f32,
            samples: p.int("samples") as u32,
            seed: p.int("seed") as u32,
            filter: Filter::from_params(p),
        })
    }
}

impl Method for PercentageCloserFiltering {
    const NAME: &'static str = "pcf";
    const PAPER: &'static str = "percentage-closer filtering (Reeves et al. 1987; Cournia 3.4), fixed kernel";
    type Params = PcfParams;

    fn cached_passes() -> &'static [CachedPass] {
        &[CENTRE_MAP]
    }

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let bindings = [layout::depth_array, layout::comparison_sampler, layout::parameters, layout::parameters, layout::visibility_storage];
        Self { visibility: ScreenPass::per_pixel(device, pool, "pcf::visibility_pass", crate::shader!("visibility.wgsl"), &bindings) }
    }

    /// The filtered test per G-buffer pixel.
    fn record(&self, frame: &mut Frame<'_>, params: &PcfParams) -> Result<MethodOutput> {
        let (map, projection) = centre_map::centre_map(frame, &params.shadow)?;
        let visibility = frame.ctx.screen_texture("pcf::visibility");
        frame.pass("visibility", |ctx, encoder, ts| {
            let test = ctx.parameters("pcf::shadow_test_uniforms", &params.shadow.uniform(&projection, ctx.light.center_f32, 0.0, 0));
            let kernel = PcfUniform {
                kernel: params.kernel,
                samples: params.samples,
                seed: params.seed,
                nearest: u32::from(params.filter == Filter::Nearest),
            };
            let kernel = ctx.parameters("pcf::kernel_uniforms", &kernel);
            let samplers = ComparisonSamplers::shared(ctx.device, ctx.pool);
            let resources = [
                Binding::Texture(&map),
                samplers.binding(params.filter),
                Binding::Buffer(&test),
                Binding::Buffer(&kernel),
                Binding::Texture(&visibility),
            ];
            self.visibility.run(ctx, encoder, &resources, ts);
        })?;
        Ok(MethodOutput { visibility })
    }
}
