//! Method `hard`: one shadow map from the light centre (Williams 1978).
//!
//! Bias (Cournia ch. 3 surveys the options). The default, `slope`, offsets the
//! receiver's lookup along its normal by `normal_offset` texels and subtracts
//! `constant_bias + slope_bias * tan(theta)` texels of depth, where a texel is
//! the map's footprint at the receiver's light depth. Both terms scale with
//! the texel, so they remove acne at any map size and scene scale while
//! moving the shadow boundary by about one texel, which is below the visible
//! light leak of a fixed world-space bias. `second_depth` (Wang and Molnar
//! 1994, Cournia 5.5) needs no bias but only works for closed casters;
//! `midpoint` (Woo 1992) compares against the depth half-way between the
//! first and second surfaces, also without bias; `none` shows the raw acne.

use std::collections::BTreeMap;


use crate::error::Result;
use crate::gpu::{layout, PassTimestamps};
use crate::light_frustum::LightFrustum;
use crate::methods::{ParamReader, ParamValue};
use crate::passes::gbuffer::GBuffer;
use crate::passes::shading::VISIBILITY_FORMAT;
use crate::passes::shadow_map::{LightSpaceUniform, MapDepth};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BiasMode {
    Slope,
    SecondDepth,
    Midpoint,
    None,
}

impl BiasMode {
    pub const NAMES: [&'static str; 4] = ["slope", "second_depth", "midpoint", "none"];

    pub fn name(self) -> &'static str {
        match self {
            BiasMode::Slope => "slope",
            BiasMode::SecondDepth => "second_depth",
            BiasMode::Midpoint => "midpoint",
            BiasMode::None => "none",
        }
    }

    /// The surface the shadow map stores for this scheme.
    pub fn map_depth(self) -> MapDepth {
        match self {
            BiasMode::SecondDepth => MapDepth::Second,
            BiasMode::Midpoint => MapDepth::Midpoint,
            _ => MapDepth::First,
        }
    }
}

/// The shadow map and its test, as `hard` and `pvm` take them.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowMapSettings {
    pub map_size: u32,
    pub bias: BiasMode,
    pub normal_offset: f32,
    pub constant_bias: f32,
    pub slope_bias: f32,
}

/// `hard` is the shadow-map test alone.
pub type HardParams = ShadowMapSettings;

/// Largest tan(theta) the slope term uses: beyond ~84 degrees the receiver is
/// nearly edge-on to the light and its irradiance is almost zero anyway.
const MAX_SLOPE: f32 = 10.0;

impl ShadowMapSettings {
    pub fn read(r: &mut ParamReader<'_>) -> Result<Self> {
        Self::read_with_bias(r, "slope")
    }

    /// [`Self::read`] with another default bias scheme (one of `BiasMode::NAMES`).
    pub fn read_with_bias(r: &mut ParamReader<'_>, default_bias: &'static str) -> Result<Self> {
        Ok(Self {
            map_size: r.int("map_size", 2048, 16, 16384)? as u32,
            bias: match r.choice("bias", default_bias, &BiasMode::NAMES)? {
                "second_depth" => BiasMode::SecondDepth,
                "midpoint" => BiasMode::Midpoint,
                "none" => BiasMode::None,
                _ => BiasMode::Slope,
            },
            normal_offset: r.float("normal_offset", 1.0, 0.0, 100.0)? as f32,
            constant_bias: r.float("constant_bias", 0.5, 0.0, 100.0)? as f32,
            slope_bias: r.float("slope_bias", 1.0, 0.0, 100.0)? as f32,
        })
    }

    pub fn effective(&self) -> BTreeMap<String, ParamValue> {
        BTreeMap::from([
            ("map_size".into(), ParamValue::Int(self.map_size as i64)),
            ("bias".into(), ParamValue::Str(self.bias.name().into())),
            ("normal_offset".into(), ParamValue::Float(self.normal_offset as f64)),
            ("constant_bias".into(), ParamValue::Float(self.constant_bias as f64)),
            ("slope_bias".into(), ParamValue::Float(self.slope_bias as f64)),
        ])
    }

    /// The `ShadowTest` uniform of `shaders/shadow_test.wgsl`.
    pub fn uniform(&self, frustum: &LightFrustum, center: [f32; 3], radius: f32, flags: u32) -> ShadowTestUniform {
        let mode = match self.bias {
            BiasMode::Slope => 0,
            BiasMode::SecondDepth => 1,
            BiasMode::None => 2,
            BiasMode::Midpoint => 3,
        };
        ShadowTestUniform {
            light_space: LightSpaceUniform::new(frustum, self.map_size),
            center: [center[0], center[1], center[2], radius],
            bias: [self.normal_offset, self.constant_bias, self.slope_bias, MAX_SLOPE],
            mode: [mode, flags, 0, 0],
        }
    }
}

/// Uniform layout of `ShadowTest` in `shaders/shadow_test.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowTestUniform {
    light_space: LightSpaceUniform,
    center: [f32; 4],
    bias: [f32; 4],
    mode: [u32; 4],
}

impl ShadowTestUniform {
    /// The method-specific fourth component of `center` (PVM: the light's radius;
    /// `reference`: the sample's weight).
    pub fn set_center_w(&mut self, w: f32) {
        self.center[3] = w;
    }
}

pub struct HardShadow {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl HardShadow {
    pub fn new(device: &wgpu::Device) -> Self {
        let layout = layout::bind_group_layout(
            device,
            "hard::layout",
            &[
                layout::float_texture(0),
                layout::float_texture(1),
                layout::depth_texture(2),
                layout::parameters(3),
                layout::storage_texture(4, VISIBILITY_FORMAT),
            ],
        );
        let pipeline = layout::compute_pipeline(device, "hard::visibility_pipeline", crate::shaders::hard(), &layout);
        Self { pipeline, layout }
    }

    /// Records the visibility pass: the shadow-map test per G-buffer pixel.
    #[allow(clippy::too_many_arguments)]
    pub fn record_visibility(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        params: &HardParams,
        gbuffer: &GBuffer,
        shadow_map: &wgpu::Texture,
        frustum: &LightFrustum,
        light_center: [f32; 3],
        visibility: &wgpu::Texture,
        timestamps: Option<PassTimestamps<'_>>,
    ) {
        let uniforms = layout::parameter_buffer(device, "hard::uniforms", &params.uniform(frustum, light_center, 0.0, 0));
        let map_view = layout::view(shadow_map);
        let visibility_view = layout::view(visibility);
        let bind_group = layout::bind_group(
            device,
            "hard::bind_group",
            &self.layout,
            &[
                wgpu::BindingResource::TextureView(&gbuffer.position_view),
                wgpu::BindingResource::TextureView(&gbuffer.normal_view),
                wgpu::BindingResource::TextureView(&map_view),
                uniforms.as_entire_binding(),
                wgpu::BindingResource::TextureView(&visibility_view),
            ],
        );
        layout::dispatch_per_pixel(encoder, "hard::visibility_pass", &self.pipeline, &bind_group, gbuffer.size, timestamps);
    }
}
