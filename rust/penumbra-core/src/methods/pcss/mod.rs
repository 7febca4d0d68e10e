//! Method `pcss`: percentage-closer soft shadows (Fernando 2005; Cournia
//! ch. 3 surveys it, and 5.2 builds PVMF's filter on it).
//!
//! Pass 1 is the shadow map of `hard`. Pass 2, per camera pixel: a blocker
//! search over the region of the map that can hold occluders of the light
//! (its radius is the light's, scaled by `(d_r - z_near) / d_r` onto the
//! near plane), averaging the raw depths nearer than the receiver's plane;
//! no blocker means fully lit (the paper's early exit); otherwise the
//! penumbra width `w_p = (d_r - d_b) w_light / d_b` sets the diameter of a
//! percentage-closer filter (`shaders/pcf.wgsl` taps). Taps are disk
//! samples, since the light seen from a receiver is a disk: `sampling` =
//! `grid` is a jittered n x n grid through Shirley and Chiu's concentric map,
//! `poisson` the first n x n points of a fixed 64-point Poisson-disk set
//! (so n <= 8); both rotated per pixel by an angle fixed by `seed`. A point
//! light (radius 0) skips the search: the test of `hard`.

use std::collections::BTreeMap;

use wgpu::util::DeviceExt;

use crate::error::{Error, Result};
use crate::gpu::{layout, PassTimestamps};
use crate::light_frustum::LightFrustum;
use crate::methods::hard::ShadowMapSettings;
use crate::methods::pcf::{ComparisonSamplers, Filter};
use crate::methods::{ParamReader, ParamValue};
use crate::passes::gbuffer::GBuffer;
use crate::passes::shading::{ShadingPass, VISIBILITY_FORMAT};

/// Points in the Poisson-disk set of `methods/pcss/visibility.wgsl`.
pub const POISSON_POINTS: u32 = 64;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampling {
    Grid,
    Poisson,
}

impl Sampling {
    const NAMES: [&'static str; 2] = ["grid", "poisson"];

    pub fn name(self) -> &'static str {
        match self {
            Sampling::Grid => "grid",
            Sampling::Poisson => "poisson",
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct PcssParams {
    pub shadow: ShadowMapSettings,
    /// Taps per axis of the blocker search.
    pub blocker_samples: u32,
    /// Taps per axis of the percentage-closer filter.
    pub filter_samples: u32,
    pub seed: u32,
    pub filter: Filter,
    pub sampling: Sampling,
}

impl PcssParams {
    pub fn read(r: &mut ParamReader<'_>) -> Result<Self> {
        let params = Self {
            shadow: ShadowMapSettings::read(r)?,
            blocker_samples: r.int("blocker_samples", 4, 1, 32)? as u32,
            filter_samples: r.int("filter_samples", 6, 1, 32)? as u32,
            seed: r.int("seed", 0, 0, u32::MAX as i64)? as u32,
            filter: Filter::read(r)?,
            sampling: match r.choice("sampling", "grid", &Sampling::NAMES)? {
                "poisson" => Sampling::Poisson,
                _ => Sampling::Grid,
            },
        };
        if params.sampling == Sampling::Poisson {
            for (name, n) in [("blocker_samples", params.blocker_samples), ("filter_samples", params.filter_samples)] {
                if n * n > POISSON_POINTS {
                    return Err(Error::InvalidParameter(format!(
                        "parameter '{name}' of method 'pcss' must be at most 8 with sampling 'poisson' \
                         (its set has {POISSON_POINTS} points), got {n}"
                    )));
                }
            }
        }
        Ok(params)
    }

    pub fn effective(&self) -> BTreeMap<String, ParamValue> {
        let mut out = self.shadow.effective();
        out.insert("blocker_samples".into(), ParamValue::Int(self.blocker_samples as i64));
        out.insert("filter_samples".into(), ParamValue::Int(self.filter_samples as i64));
        out.insert("seed".into(), ParamValue::Int(self.seed as i64));
        out.insert("filter".into(), ParamValue::Str(self.filter.name().into()));
        out.insert("sampling".into(), ParamValue::Str(self.sampling.name().into()));
        out
    }
}

/// Uniform layout of `PcssSampling` in `methods/pcss/visibility.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PcssUniform {
    blocker_samples: u32,
    filter_samples: u32,
    seed: u32,
    poisson: u32,
}

/// What one render's pass leaves behind: the intermediates and the counters.
pub struct PcssFrame {
    /// Estimated penumbra width in map texels (camera space, 0 where unfiltered).
    pub penumbra_width: wgpu::Texture,
    /// Mean blocker depth in world units (camera space, 0 where none).
    pub blocker_depth: wgpu::Texture,
    /// Two u32: pixels that ran the blocker search, pixels that ran the filter.
    pub counters: wgpu::Buffer,
}

/// Names of the counters in [`PcssFrame::counters`], in order.
pub const COUNTER_NAMES: &[&str] = &["blocker_search_pixels", "filtered_pixels"];

pub struct PercentageCloserSoftShadows {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

impl PercentageCloserSoftShadows {
    pub fn new(device: &wgpu::Device) -> Self {
        let layout = layout::bind_group_layout(
            device,
            "pcss::layout",
            &[
                layout::float_texture(0),
                layout::float_texture(1),
                layout::depth_texture(2),
                layout::comparison_sampler(3),
                layout::parameters(4),
                layout::parameters(5),
                layout::storage_texture(6, VISIBILITY_FORMAT),
                layout::storage_texture(7, VISIBILITY_FORMAT),
                layout::storage_texture(8, VISIBILITY_FORMAT),
                layout::storage_buffer_rw(9),
            ],
        );
        let pipeline = layout::compute_pipeline(device, "pcss::visibility_pipeline", crate::shaders::pcss(), &layout);
        Self { pipeline, layout }
    }

    /// Records the visibility pass: blocker search, penumbra estimate and
    /// filter per G-buffer pixel.
    #[allow(clippy::too_many_arguments)]
    pub fn record_visibility(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        params: &PcssParams,
        samplers: &ComparisonSamplers,
        gbuffer: &GBuffer,
        shadow_map: &wgpu::Texture,
        frustum: &LightFrustum,
        light: ([f32; 3], f32),
        visibility: &wgpu::Texture,
        timestamps: Option<PassTimestamps<'_>>,
    ) -> PcssFrame {
        let frame = PcssFrame {
            penumbra_width: ShadingPass::create_visibility(device, gbuffer.size),
            blocker_depth: ShadingPass::create_visibility(device, gbuffer.size),
            counters: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("pcss::counters"),
                contents: &[0u8; 8],
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            }),
        };
        let test = layout::parameter_buffer(device, "pcss::shadow_test_uniforms", &params.shadow.uniform(frustum, light.0, light.1, 0));
        let sampling = PcssUniform {
            blocker_samples: params.blocker_samples,
            filter_samples: params.filter_samples,
            seed: params.seed,
            poisson: u32::from(params.sampling == Sampling::Poisson),
        };
        let sampling = layout::parameter_buffer(device, "pcss::sampling_uniforms", &sampling);
        let views = [shadow_map, visibility, &frame.penumbra_width, &frame.blocker_depth].map(layout::view);
        let bind_group = layout::bind_group(
            device,
            "pcss::bind_group",
            &self.layout,
            &[
                wgpu::BindingResource::TextureView(&gbuffer.position_view),
                wgpu::BindingResource::TextureView(&gbuffer.normal_view),
                wgpu::BindingResource::TextureView(&views[0]),
                wgpu::BindingResource::Sampler(samplers.get(params.filter)),
                test.as_entire_binding(),
                sampling.as_entire_binding(),
                wgpu::BindingResource::TextureView(&views[1]),
                wgpu::BindingResource::TextureView(&views[2]),
                wgpu::BindingResource::TextureView(&views[3]),
                frame.counters.as_entire_binding(),
            ],
        );
        layout::dispatch_per_pixel(encoder, "pcss::visibility_pass", &self.pipeline, &bind_group, gbuffer.size, timestamps);
        frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Poisson-disk set as the shader holds it.
    fn poisson_disk() -> Vec<[f32; 2]> {
        let src = include_str!("visibility.wgsl");
        let start = src.find("var<private> poisson_disk").expect("the set is in the shader");
        let body = &src[start..src[start..].find(");").unwrap() + start];
        body.split("vec2<f32>(")
            .skip(1)
            .map(|s| {
                let mut xy = s.split(')').next().unwrap().split(',').map(|v| v.trim().parse::<f32>().unwrap());
                [xy.next().unwrap(), xy.next().unwrap()]
            })
            .collect()
    }

    #[test]
    fn poisson_disk_prefixes_are_spread_in_the_unit_disk() {
        let points = poisson_disk();
        assert_eq!(points.len(), POISSON_POINTS as usize);
        assert!(points.iter().all(|p| p[0].hypot(p[1]) <= 1.0));
        // Every n x n prefix keeps its points apart by a fair share of the
        // disk: at least 0.6 / n (a hexagonal packing of n^2 points in the unit
        // disk spaces them about 1.9 / n apart).
        for n in 2..=8usize {
            let prefix = &points[..n * n];
            let min = prefix
                .iter()
                .enumerate()
                .flat_map(|(i, a)| prefix[i + 1..].iter().map(move |b| (a[0] - b[0]).hypot(a[1] - b[1])))
                .fold(f32::INFINITY, f32::min);
            assert!(min > 0.6 / n as f32, "n = {n}: nearest pair {min}");
        }
    }

    #[test]
    fn poisson_sampling_is_limited_to_its_set() {
        let mut params = BTreeMap::new();
        params.insert("sampling".to_string(), ParamValue::Str("poisson".into()));
        params.insert("filter_samples".to_string(), ParamValue::Int(9));
        let mut reader = ParamReader::new("pcss", &params);
        let err = PcssParams::read(&mut reader).unwrap_err().to_string();
        assert!(err.contains("filter_samples") && err.contains("at most 8"), "{err}");
        params.insert("filter_samples".to_string(), ParamValue::Int(8));
        let mut reader = ParamReader::new("pcss", &params);
        assert_eq!(PcssParams::read(&mut reader).unwrap().filter_samples, 8);
    }
}
