//! Method `reference`: soft shadows by averaging hard shadows from points on
//! the light (Herf 3.4 and 4.2; Schwarzler et al. Eq. 1-2), the in-engine
//! reference that converges to the light's true visibility as `n_samples`
//! grows.
//!
//! The samples are a stratified, jittered grid on the light's disk facing the
//! scene (Herf 4.5.1): `n_samples` is rounded up to a full grid of
//! `ceil(sqrt(n))` columns. Each sample gets its own fitted shadow map and the
//! shadow-map test of `hard`, added with weight 1/n into one accumulation
//! buffer (Schwarzler 3.4.2's accumulation variant): two passes per sample,
//! one resolve. Samples below a receiver's horizon count as hidden, as in the
//! ground truth. A point light needs one sample.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3, Vec3};
use wgpu::util::DeviceExt;

use crate::error::Result;
use crate::gpu::{layout, PassTimestamps};
use crate::light_frustum::LightFrustum;
use crate::methods::hard::ShadowMapSettings;
use crate::methods::{ParamReader, ParamValue};
use crate::passes::gbuffer::GBuffer;
use crate::passes::shading::VISIBILITY_FORMAT;
use crate::passes::shadow_map::ShadowMapPass;
use crate::scene::PreparedScene;

#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceParams {
    pub shadow: ShadowMapSettings,
    pub n_samples: u32,
    pub seed: u64,
}

impl ReferenceParams {
    pub fn read(r: &mut ParamReader<'_>) -> Result<Self> {
        Ok(Self {
            shadow: ShadowMapSettings::read(r)?,
            n_samples: r.int("n_samples", 256, 1, 4096)? as u32,
            seed: r.int("seed", 0, 0, i64::MAX)? as u64,
        })
    }

    pub fn effective(&self) -> BTreeMap<String, ParamValue> {
        let mut out = self.shadow.effective();
        out.insert("n_samples".into(), ParamValue::Int(self.n_samples as i64));
        out.insert("seed".into(), ParamValue::Int(self.seed as i64));
        out
    }
}

/// SplitMix64: a small, well-mixed generator; the samples only need to be
/// deterministic for a seed and uncorrelated across cells.
struct SplitMix(u64);

impl SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Shirley and Chiu's concentric map from the unit square to the unit disk:
/// area-preserving, so a stratified square stays stratified on the disk.
fn concentric_disk(u: DVec2) -> DVec2 {
    let a = 2.0 * u - DVec2::ONE;
    if a == DVec2::ZERO {
        return DVec2::ZERO;
    }
    let (r, phi) = if a.x.abs() > a.y.abs() {
        (a.x, std::f64::consts::FRAC_PI_4 * (a.y / a.x))
    } else {
        (a.y, std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (a.x / a.y))
    };
    DVec2::new(r * phi.cos(), r * phi.sin())
}

/// Stratified jittered points on the disk of `radius` around `center`
/// perpendicular to `axis` (a unit vector towards the scene). A radius of 0
/// gives the centre once.
pub fn light_samples(center: DVec3, radius: f64, axis: DVec3, n: u32, seed: u64) -> Vec<DVec3> {
    if radius == 0.0 {
        return vec![center];
    }
    let columns = (n as f64).sqrt().ceil().max(1.0) as u32;
    let rows = n.div_ceil(columns);
    let (e1, e2) = axis.any_orthonormal_pair();
    let mut rng = SplitMix(seed ^ 0x005E_ED0F_9E37);
    let mut out = Vec::with_capacity((columns * rows) as usize);
    for j in 0..rows {
        for i in 0..columns {
            let u = DVec2::new(
                (i as f64 + rng.next_f64()) / columns as f64,
                (j as f64 + rng.next_f64()) / rows as f64,
            );
            let d = concentric_disk(u) * radius;
            out.push(center + e1 * d.x + e2 * d.y);
        }
    }
    out
}

pub struct ReferenceShadows {
    layout: wgpu::BindGroupLayout,
    accumulate: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
}

impl ReferenceShadows {
    pub fn new(device: &wgpu::Device) -> Self {
        let layout = layout::bind_group_layout(
            device,
            "reference::layout",
            &[
                layout::float_texture(0),
                layout::float_texture(1),
                layout::depth_texture(2),
                layout::uniform(3),
                layout::storage_buffer_rw(4),
                layout::storage_texture(5, VISIBILITY_FORMAT),
            ],
        );
        let module = crate::shaders::module(device, "reference::shader", crate::shaders::reference());
        Self {
            accumulate: layout::compute_pipeline_entry(device, "reference::accumulate_pipeline", &module, &layout, "accumulate"),
            resolve: layout::compute_pipeline_entry(device, "reference::resolve_pipeline", &module, &layout, "resolve"),
            layout,
        }
    }

    /// Records every sample's shadow map and accumulation, and the resolve,
    /// as one named pass. Returns the number of samples used.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        shadow_pass: &ShadowMapPass,
        params: &ReferenceParams,
        scene: &PreparedScene,
        light: (DVec3, f64),
        vertices: (&wgpu::Buffer, u32),
        gbuffer: &GBuffer,
        visibility: &wgpu::Texture,
        timestamps: Option<PassTimestamps<'_>>,
    ) -> Result<usize> {
        let (center, radius) = light;
        let scene_center = ((scene.bounds_min + scene.bounds_max) * 0.5).as_dvec3();
        let axis = (scene_center - center).try_normalize().unwrap_or(DVec3::NEG_Y);
        let samples = light_samples(center, radius, axis, params.n_samples, params.seed);
        let points: Vec<Vec3> = scene.meshes.iter().flat_map(|m| m.vertices.iter().map(|v| v.as_vec3())).collect();
        let (w, h) = gbuffer.size;
        let accumulated = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("reference::accumulated"),
            size: (w as u64 * h as u64 * 4).max(4),
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let map = ShadowMapPass::create_map(device, params.shadow.map_size);
        let (map_view, visibility_view) = (layout::view(&map), layout::view(visibility));
        let weight = 1.0 / samples.len() as f32;
        let depth = params.shadow.bias.map_depth();
        let last = samples.len() - 1;
        for (i, s) in samples.iter().enumerate() {
            let frustum = LightFrustum::fit(s.as_vec3(), points.iter().copied())?;
            let first = i == 0;
            shadow_pass.record_part(device, encoder, &map, &frustum, depth, vertices, timestamps, (first, false));
            let mut test = params.shadow.uniform(&frustum, s.as_vec3().to_array(), 0.0, 0);
            test.set_center_w(weight);
            let uniforms = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("reference::sample_uniforms"),
                contents: bytemuck::bytes_of(&test),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let bind_group = self.bind_group(device, gbuffer, &map_view, &uniforms, &accumulated, &visibility_view);
            layout::dispatch_per_pixel_writes(encoder, "reference::accumulate_pass", &self.accumulate, &bind_group, gbuffer.size, None);
            if i == last {
                layout::dispatch_per_pixel_writes(
                    encoder,
                    "reference::resolve_pass",
                    &self.resolve,
                    &bind_group,
                    gbuffer.size,
                    timestamps.and_then(|t| t.compute_part(false, true)),
                );
            }
        }
        Ok(samples.len())
    }

    fn bind_group(
        &self,
        device: &wgpu::Device,
        gbuffer: &GBuffer,
        map_view: &wgpu::TextureView,
        uniforms: &wgpu::Buffer,
        accumulated: &wgpu::Buffer,
        visibility_view: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        layout::bind_group(
            device,
            "reference::bind_group",
            &self.layout,
            &[
                wgpu::BindingResource::TextureView(&gbuffer.position_view),
                wgpu::BindingResource::TextureView(&gbuffer.normal_view),
                wgpu::BindingResource::TextureView(map_view),
                uniforms.as_entire_binding(),
                accumulated.as_entire_binding(),
                wgpu::BindingResource::TextureView(visibility_view),
            ],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_fill_the_disk_evenly_and_deterministically() {
        let c = DVec3::new(1.0, 5.0, 0.0);
        let axis = DVec3::NEG_Y;
        let s = light_samples(c, 0.5, axis, 256, 7);
        assert_eq!(s.len(), 256);
        assert!(s.iter().all(|p| (*p - c).length() <= 0.5 + 1e-12 && (*p - c).dot(axis).abs() < 1e-12));
        // Stratified: the mean is near the centre and each quadrant holds a quarter.
        let mean = s.iter().copied().sum::<DVec3>() / 256.0;
        assert!((mean - c).length() < 0.01, "{mean}");
        let q = s.iter().filter(|p| p.x > c.x && p.z > c.z).count();
        assert!((56..=72).contains(&q), "{q}");
        assert_eq!(s, light_samples(c, 0.5, axis, 256, 7));
        assert_ne!(s, light_samples(c, 0.5, axis, 256, 8));
        assert_eq!(light_samples(c, 0.0, axis, 256, 7), vec![c]);
        assert_eq!(light_samples(c, 0.5, axis, 10, 7).len(), 12, "rounded up to a 4 x 3 grid");
    }
}
