//! Method `reference`: soft shadows by averaging hard shadows from points on
//! the light (Herf 3.4 and 4.2; Schwarzler et al. Eq. 1-2), the in-engine
//! reference that converges to the light's true visibility as `n_samples`
//! grows.
//!
//! The samples are a stratified, jittered grid (Herf 4.5.1; `n_samples` is
//! rounded up to a full grid of `ceil(sqrt(n))` columns), placed by
//! `sampling`:
//!
//! - `sphere` (default): on the part of the light's sphere that any point of
//!   the scene can see, equal-area strata, each sample weighted per receiver
//!   by the solid angle its patch subtends (Herf 4.1's form-factor weights,
//!   without its equal-weight assumption): `cos(theta_s) / |p - s|^2`, zero
//!   for the far side. The weighted mean is the solid-angle fraction of the
//!   sphere that `p` sees, the ground truth's visibility, for every receiver.
//! - `disk`: on the disk through the light's centre facing the scene, equal
//!   weights (Herf 4.2, 4.5.1, as for a planar light). From a receiver off the
//!   disk's axis the disk is an ellipse, not the sphere's circle, so this
//!   converges to a slightly different visibility (measured in the README).
//!
//! `jitter = False` puts the samples on a regular grid through the corners
//! of the unit square (`i / (k - 1)`, the centre alone for one sample):
//! with `sampling = "disk"` and `n_samples = 289` the paper's ground truth of
//! 17 x 17 regular samples (Schwarzler 4.1), and exactly the full grid that
//! method `adaptive` reaches at `max_depth = 4`.
//!
//! Each sample gets its own fitted shadow map and the shadow-map test of
//! `hard`, accumulated (weighted sum and sum of weights) into one buffer
//! (Schwarzler 3.4.2's accumulation variant): two passes per sample, one
//! resolve. Samples below a receiver's horizon count as hidden, as in the
//! ground truth. A point light needs one sample.

use glam::DVec3;

use crate::error::Result;
use crate::frame::Frame;
use crate::gpu::layout;
use crate::gpu::pool::{Binding, ResourcePool};
use crate::gpu::pool::PooledTexture;
use crate::light_frustum::light_sample_error;
use crate::light_sampling::{camera_basis, light_samples, scene_axis, scene_sphere_samples, LightSample, Strata};
use crate::method::{Method, MethodOutput};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::passes::screen::ScreenPass;
use crate::passes::shadow_map::ShadowMapPass;
use crate::passes::shadow_test::{ShadowMapSettings, ShadowTestUniform};

/// Where the light samples lie (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LightSampling {
    Sphere,
    Disk,
}

impl LightSampling {
    pub const NAMES: [&'static str; 2] = ["sphere", "disk"];

    pub fn name(self) -> &'static str {
        match self {
            LightSampling::Sphere => "sphere",
            LightSampling::Disk => "disk",
        }
    }

    fn parse(name: &str) -> Self {
        match name {
            "disk" => LightSampling::Disk,
            _ => LightSampling::Sphere,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceParams {
    pub shadow: ShadowMapSettings,
    pub n_samples: u32,
    pub seed: u64,
    pub sampling: LightSampling,
    pub jitter: bool,
}


crate::gpu_type! {
    pub struct SampleWeightUniform => "SampleWeight" in "methods/reference/visibility.wgsl" {
        /// The sphere's outward unit normal at the sample; w = 1 for solid-angle weights.
        pub(crate) normal: [f32; 4],
        /// The light's centre (xyz).
        pub(crate) light_center: [f32; 4],
    }
}

pub struct ReferenceShadows {
    pass: ScreenPass,
}

impl MethodParams for ReferenceParams {
    fn specs() -> Vec<ParamSpec> {
        ShadowMapSettings::specs_and([
            ParamSpec::int("n_samples", 256, 1, 4096, "light samples (rounded up to a full stratified grid)"),
            ParamSpec::seed(i64::MAX, "fixes the samples' jitter"),
            ParamSpec::choice(
                "sampling",
                "sphere",
                &LightSampling::NAMES,
                "samples on the visible sphere (converges to the ground truth) or on Herf's facing disk",
            ),
            ParamSpec::bool("jitter", true, "jitter each sample in its stratum (False: a regular grid through the domain's corners, adaptive's full grid)"),
        ])
    }

    fn parse(p: &ParamSet) -> Result<ReferenceParams> {
        Ok(ReferenceParams {
            shadow: ShadowMapSettings::from_params(p),
            n_samples: p.int("n_samples") as u32,
            seed: p.int("seed") as u64,
            sampling: LightSampling::parse(p.choice("sampling")),
            jitter: p.bool("jitter"),
        })
    }
}

impl Method for ReferenceShadows {
    const NAME: &'static str = "reference";
    const PAPER: &'static str = "accumulation of hard shadows from n light samples (Herf 3.4, 4.2; Schwarzler et al. Eq. 1-2)";
    type Params = ReferenceParams;

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let bindings = [layout::depth_array, layout::parameters, layout::storage_buffer_rw, layout::visibility_storage, layout::parameters];
        Self { pass: ScreenPass::new(device, pool, "reference::pass", crate::shader!("visibility.wgsl"), &bindings, &["accumulate", "resolve"]) }
    }

    /// Every sample's shadow map and accumulation, and the resolve, as one
    /// named pass `light_samples`.
    fn record(&self, frame: &mut Frame<'_>, params: &ReferenceParams) -> Result<MethodOutput> {
        params.shadow.check_limits(frame.ctx.max_texture_side())?;
        let visibility = frame.ctx.screen_texture("reference::visibility");
        let used = frame.pass("light_samples", |ctx, encoder, timestamps| -> Result<(usize, usize, usize)> {
            let (center, radius) = (ctx.light.center, ctx.light.radius);
            let scene = ctx.prepared;
            let strata = if params.jitter { Strata::Jittered(params.seed) } else { Strata::Centred };
            let samples = match params.sampling {
                LightSampling::Disk => {
                    // The disk's frame turns with the camera (and the scene): adaptive's.
                    let points = light_samples(center, radius, camera_basis(scene_axis(center, scene, ctx.camera), ctx.camera), params.n_samples, strata);
                    let weight = 1.0 / points.len() as f64;
                    points.into_iter().map(|position| LightSample { position, normal: None, weight }).collect()
                }
                LightSampling::Sphere => scene_sphere_samples(center, radius, scene, ctx.camera, params.n_samples, strata),
            };
            let (w, h) = ctx.size;
            // Per pixel: the weighted sum of visibilities and the sum of weights.
            let accumulated = ctx.buffer(
                "reference::accumulated",
                (w as u64 * h as u64 * 8).max(8),
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            );
            encoder.clear_buffer(&accumulated, 0, None);
            let depth = params.shadow.bias.map_depth();
            // Every sample's projection (its own fitted frustum, or cube faces
            // where one frustum cannot cover the scene from it) and parameter
            // blocks, in two buffers bound at one aligned block per sample.
            let positions: Vec<glam::Vec3> = samples.iter().map(|s| s.position.as_vec3()).collect();
            let projections = ctx
                .fit_projections(&positions, 0.0, params.shadow.projection)
                .into_iter()
                .zip(&positions)
                .enumerate()
                .map(|(i, (fitted, &position))| fitted.map_err(|e| light_sample_error(e, "reference", i + 1, samples.len(), position)))
                .collect::<Result<Vec<_>>>()?;
            let align = ctx.device.limits().min_storage_buffer_offset_alignment as usize;
            let stride = |size: usize| size.div_ceil(align) * align;
            let (test_stride, weight_stride) = (stride(std::mem::size_of::<ShadowTestUniform>()), stride(std::mem::size_of::<SampleWeightUniform>()));
            let mut tests = vec![0u8; test_stride * samples.len()];
            let mut weights = vec![0u8; weight_stride * samples.len()];
            for (i, (sample, projection)) in samples.iter().zip(&projections).enumerate() {
                let mut test = params.shadow.uniform(projection, sample.position.as_vec3().to_array(), 0.0, 0);
                test.set_center_w(sample.weight as f32);
                let normal = sample.normal.unwrap_or(DVec3::ZERO).as_vec3();
                let weight = SampleWeightUniform {
                    normal: [normal.x, normal.y, normal.z, if sample.normal.is_some() { 1.0 } else { 0.0 }],
                    light_center: [center.x as f32, center.y as f32, center.z as f32, 0.0],
                };
                tests[i * test_stride..][..std::mem::size_of::<ShadowTestUniform>()].copy_from_slice(bytemuck::bytes_of(&test));
                weights[i * weight_stride..][..std::mem::size_of::<SampleWeightUniform>()].copy_from_slice(bytemuck::bytes_of(&weight));
            }
            let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
            let test_buffer = ctx.buffer("reference::sample_uniforms", tests.len() as u64, usage);
            let weight_buffer = ctx.buffer("reference::sample_weights", weights.len() as u64, usage);
            ctx.queue.write_buffer(&test_buffer, 0, &tests);
            ctx.queue.write_buffer(&weight_buffer, 0, &weights);
            // One map per layer count, reused sample after sample.
            let mut maps: Vec<(u32, PooledTexture)> = Vec::new();
            let mut faces = 0;
            let last = samples.len() - 1;
            for (i, projection) in projections.iter().enumerate() {
                let layers = projection.layers();
                if !maps.iter().any(|(l, _)| *l == layers) {
                    maps.push((layers, ShadowMapPass::create_map(ctx, params.shadow.map_size, layers)));
                }
                let map = &maps.iter().find(|(l, _)| *l == layers).expect("made above").1;
                faces += projection.active_faces() as usize;
                ShadowMapPass::shared(ctx.device, ctx.pool).record(ctx, encoder, map, projection, depth, timestamps, (i == 0, false));
                let bind_group = self.pass.bind_group(
                    ctx,
                    &[
                        Binding::Texture(map),
                        Binding::BufferRange(&test_buffer, (i * test_stride) as u64, std::mem::size_of::<ShadowTestUniform>() as u64),
                        Binding::Buffer(&accumulated),
                        Binding::Texture(&visibility),
                        Binding::BufferRange(&weight_buffer, (i * weight_stride) as u64, std::mem::size_of::<SampleWeightUniform>() as u64),
                    ],
                );
                self.pass.dispatch(ctx, encoder, "accumulate", &bind_group, None);
                if i == last {
                    self.pass.dispatch(ctx, encoder, "resolve", &bind_group, timestamps.and_then(|t| t.compute_part(false, true)));
                }
            }
            Ok((samples.len(), faces, projections.iter().filter(|p| p.is_cube()).count()))
        })??;
        let (used, faces, cubes) = used;
        frame.stat("light_samples", used as i64);
        frame.stat("shadow_maps_rendered", used as i64);
        frame.stat("shadow_map_faces", faces as i64);
        frame.stat("cube_maps", cubes as i64);
        frame.stat("map_size", params.shadow.map_size as i64);
        Ok(MethodOutput { visibility })
    }
}
