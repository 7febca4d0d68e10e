//! Method `pcf`: percentage-closer filtering with a fixed kernel (Reeves et
//! al. 1987; Cournia 3.4).
//!
//! Visibility is the fraction of shadow-map tests that pass over a square of
//! `kernel` texels centred on the receiver's map coordinates, estimated with
//! an n x n jittered grid (`samples` = n; the jitter is fixed by `seed` and
//! the pixel). Each tap is `pcf_tap` of `shaders/pcf.wgsl`: the comparison
//! against the receiver's tangent plane along the tap's ray, through a
//! comparison sampler (`filter`: `bilinear` is the hardware's 2x2 PCF,
//! `nearest` one texel). A zero-width nearest kernel is the single test of
//! `hard`, and is computed by the same function, bias included.

use std::collections::BTreeMap;


use crate::error::Result;
use crate::gpu::{layout, PassTimestamps};
use crate::light_frustum::LightFrustum;
use crate::methods::hard::ShadowMapSettings;
use crate::methods::{ParamReader, ParamValue};
use crate::passes::gbuffer::GBuffer;
use crate::passes::shading::VISIBILITY_FORMAT;

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

    pub fn read(r: &mut ParamReader<'_>) -> Result<Self> {
        Ok(match r.choice("filter", "bilinear", &Self::NAMES)? {
            "nearest" => Filter::Nearest,
            _ => Filter::Bilinear,
        })
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
    bilinear: wgpu::Sampler,
    nearest: wgpu::Sampler,
}

impl ComparisonSamplers {
    pub fn new(device: &wgpu::Device) -> Self {
        Self {
            bilinear: layout::create_comparison_sampler(device, true),
            nearest: layout::create_comparison_sampler(device, false),
        }
    }

    pub fn get(&self, filter: Filter) -> &wgpu::Sampler {
        match filter {
            Filter::Bilinear => &self.bilinear,
            Filter::Nearest => &self.nearest,
        }
    }
}

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

impl PcfParams {
    pub fn read(r: &mut ParamReader<'_>) -> Result<Self> {
        Ok(Self {
            shadow: ShadowMapSettings::read(r)?,
            kernel: r.float("kernel", 5.0, 0.0, 256.0)? as f32,
            samples: r.int("samples", 4, 1, 32)? as u32,
            seed: r.int("seed", 0, 0, u32::MAX as i64)? as u32,
            filter: Filter::read(r)?,
        })
    }

    pub fn effective(&self) -> BTreeMap<String, ParamValue> {
        let mut out = self.shadow.effective();
        out.insert("kernel".into(), ParamValue::Float(self.kernel as f64));
        out.insert("samples".into(), ParamValue::Int(self.samples as i64));
        out.insert("seed".into(), ParamValue::Int(self.seed as i64));
        out.insert("filter".into(), ParamValue::Str(self.filter.name().into()));
        out
    }
}

/// Uniform layout of `PcfKernel` in `methods/pcf/visibility.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PcfUniform {
    kernel: f32,
    samples: u32,
    seed: u32,
    nearest: u32,
}

pub struct PercentageCloserFiltering {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl PercentageCloserFiltering {
    pub fn new(device: &wgpu::Device) -> Self {
        let layout = layout::bind_group_layout(
            device,
            "pcf::layout",
            &[
                layout::float_texture(0),
                layout::float_texture(1),
                layout::depth_texture(2),
                layout::comparison_sampler(3),
                layout::parameters(4),
                layout::parameters(5),
                layout::storage_texture(6, VISIBILITY_FORMAT),
            ],
        );
        let pipeline = layout::compute_pipeline(device, "pcf::visibility_pipeline", crate::shaders::pcf(), &layout);
        Self { pipeline, layout }
    }

    /// Records the visibility pass: the filtered test per G-buffer pixel.
    #[allow(clippy::too_many_arguments)]
    pub fn record_visibility(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        params: &PcfParams,
        samplers: &ComparisonSamplers,
        gbuffer: &GBuffer,
        shadow_map: &wgpu::Texture,
        frustum: &LightFrustum,
        light_center: [f32; 3],
        visibility: &wgpu::Texture,
        timestamps: Option<PassTimestamps<'_>>,
    ) {
        let test = layout::parameter_buffer(device, "pcf::shadow_test_uniforms", &params.shadow.uniform(frustum, light_center, 0.0, 0));
        let kernel = PcfUniform {
            kernel: params.kernel,
            samples: params.samples,
            seed: params.seed,
            nearest: u32::from(params.filter == Filter::Nearest),
        };
        let kernel = layout::parameter_buffer(device, "pcf::kernel_uniforms", &kernel);
        let map_view = layout::view(shadow_map);
        let visibility_view = layout::view(visibility);
        let bind_group = layout::bind_group(
            device,
            "pcf::bind_group",
            &self.layout,
            &[
                wgpu::BindingResource::TextureView(&gbuffer.position_view),
                wgpu::BindingResource::TextureView(&gbuffer.normal_view),
                wgpu::BindingResource::TextureView(&map_view),
                wgpu::BindingResource::Sampler(samplers.get(params.filter)),
                test.as_entire_binding(),
                kernel.as_entire_binding(),
                wgpu::BindingResource::TextureView(&visibility_view),
            ],
        );
        layout::dispatch_per_pixel(encoder, "pcf::visibility_pass", &self.pipeline, &bind_group, gbuffer.size, timestamps);
    }
}
