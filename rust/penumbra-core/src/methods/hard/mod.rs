//! Method `hard`: one shadow map from the light centre (Williams 1978) and
//! its test per pixel, with the bias schemes of `passes/shadow_test.rs`.

use crate::error::Result;
use crate::frame::Frame;
use crate::gpu::layout;
use crate::gpu::pool::{Binding, ResourcePool};
use crate::method::{Method, MethodOutput};
use crate::pass_cache::CachedPass;
use crate::passes::centre_map::{self, CENTRE_MAP};
use crate::passes::screen::ScreenPass;
use crate::passes::shadow_test::ShadowMapSettings;

/// `hard` is the shadow-map test alone.
pub type HardParams = ShadowMapSettings;

pub struct HardShadow {
    visibility: ScreenPass,
}

impl Method for HardShadow {
    const NAME: &'static str = "hard";
    const PAPER: &'static str = "shadow mapping (Williams 1978), from the light centre";
    type Params = HardParams;

    fn cached_passes() -> &'static [CachedPass] {
        &[CENTRE_MAP]
    }

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let bindings = [layout::depth_array, layout::parameters, layout::visibility_storage];
        Self { visibility: ScreenPass::per_pixel(device, pool, "hard::visibility_pass", crate::shader!("visibility.wgsl"), &bindings) }
    }

    /// The shadow-map test per G-buffer pixel.
    fn record(&self, frame: &mut Frame<'_>, params: &HardParams) -> Result<MethodOutput> {
        let (map, projection) = centre_map::centre_map(frame, params)?;
        let visibility = frame.ctx.screen_texture("hard::visibility");
        frame.pass("visibility", |ctx, encoder, ts| {
            let uniforms = ctx.parameters("hard::uniforms", &params.uniform(&projection, ctx.light.center_f32, 0.0, 0));
            self.visibility.run(ctx, encoder, &[Binding::Texture(&map), Binding::Buffer(&uniforms), Binding::Texture(&visibility)], ts);
        })?;
        Ok(MethodOutput { visibility })
    }
}
