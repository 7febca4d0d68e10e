//! Method `raytraced` (beyond the papers; SPEC section 4): the light's
//! visibility by shadow rays through the scene's acceleration structures
//! (wgpu ray queries, `EXPERIMENTAL_RAY_QUERY`), the in-engine exact
//! visibility.
//!
//! Per pixel, one ray from the surface point to each light sample of
//! `reference`'s sphere sampling ([`scene_sphere_samples`]: stratified,
//! solid-angle weighted, fixed by `seed`), weighted as `reference` weights
//! its shadow-map tests: the weighted fraction of rays that reach the light
//! converges to the fraction of the light's solid angle the point sees, what
//! the ground truth measures, with no shadow map and so no bias or
//! resolution limit. Samples below the surface's horizon count as hidden. A
//! point light (radius 0) is one sample: one ray, exact hard shadows.
//!
//! Ray origins are offset along the surface normal by `ray_offset` times the
//! scene's size (its largest absolute coordinate or its extent, whichever is
//! larger: the G-buffer's float32 positions are within a few units in the
//! last place of that of the surface, and so is the traced geometry), and
//! hits closer than that offset are ignored (a wall's pixel where it meets
//! the floor can lie a rounding error below the floor).
//!
//! Adaptive mode (`adaptive=True`): `adaptive_samples` rays per pixel first,
//! to a stratified set of points on the light's disk facing the pixel
//! (`reference`'s disk sampling, placed per pixel, so that every pixel spreads
//! them over the light as it sees it); where they all agree (all reach the
//! light, or none does) and so do those of every pixel within
//! `adaptive_radius` pixels, that estimate (1 or 0) stands; elsewhere the
//! pixel takes the full `n_samples`, exactly as in plain mode. A penumbra
//! narrower than the first rays' spacing and than the radius can be missed:
//! the miss rate against plain mode is measured in docs/methods/raytraced.md.
//!
//! The acceleration structures (`acceleration.rs`) are built once per mesh
//! content and kept between renders; their memory is in the stats.

pub mod acceleration;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::gpu::context::{ray_queries_disabled, RAY_QUERY_ENV};
use crate::gpu::layout;
use crate::gpu::pool::{Binding, ResourcePool};
use crate::light_sampling::{light_samples, scene_sphere_samples, SampleUniform, DEFAULT_RAY_OFFSET};
use crate::method::{Method, MethodOutput};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::passes::screen::ScreenPass;

use acceleration::AccelerationCache;

#[derive(Debug, Clone, PartialEq)]
pub struct RaytracedParams {
    pub n_samples: u32,
    pub seed: u64,
    pub adaptive: bool,
    pub adaptive_samples: u32,
    pub adaptive_radius: u32,
    /// Relative to the scene's size.
    pub ray_offset: f64,
}

crate::gpu_type! {
    pub struct RaySettingsUniform => "RaySettings" in "methods/raytraced/visibility.wgsl" {
        /// The light's centre (xyz) and radius (w).
        pub(crate) light: [f32; 4],
        /// x: the ray origins' offset in world units.
        pub(crate) offset: [f32; 4],
        /// Samples in the full set, points in the coarse set, the classification's radius, unused.
        pub(crate) counts: [u32; 4],
    }
}

/// Counters read back into stats: pixels that took the full sample set, and
/// pixels that took the coarse set (adaptive mode's first pass).
const COUNTERS: &[&str] = &["full_pixels", "coarse_pixels"];

/// The seed of the coarse set, apart from the full set's.
const COARSE_SEED: u64 = 0xC0A5_E5E7_0F1A_5EED;

/// The typed error of an adapter (or a device) without ray queries.
fn missing_ray_queries(device: &wgpu::Device) -> Error {
    let info = device.adapter_info();
    let why = if ray_queries_disabled() {
        format!("{RAY_QUERY_ENV} turns them off")
    } else {
        "the adapter does not offer them".to_owned()
    };
    Error::MissingFeature(format!(
        "method 'raytraced' needs ray queries (wgpu feature EXPERIMENTAL_RAY_QUERY, Vulkan VK_KHR_ray_query), \
         which adapter '{}' ({}) lacks: {why}. Mesa's software adapter (lavapipe) has them from Mesa 24.1 on \
         (scripts/setup.sh installs one on Debian 12), as do Vulkan drivers of GPUs with ray-tracing support; \
         `penumbra info` shows `ray_queries`",
        info.name, info.driver_info
    ))
}

fn acceleration_structure(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::AccelerationStructure { vertex_return: false },
        count: None,
    }
}

pub struct RaytracedShadows {
    /// None on a device without ray queries: every render is the typed error.
    pass: Option<ScreenPass>,
    cache: AccelerationCache,
}

impl MethodParams for RaytracedParams {
    fn specs() -> Vec<ParamSpec> {
        vec![
            ParamSpec::int("n_samples", 256, 1, 65536, "shadow rays per pixel, one per light sample of reference's sphere sampling (rounded up to full stratified grids)"),
            ParamSpec::seed(i64::MAX, "fixes the samples' jitter"),
            ParamSpec::bool("adaptive", false, "a few rays per pixel first, the full count only where they disagree within adaptive_radius pixels"),
            ParamSpec::int("adaptive_samples", 16, 1, 4096, "adaptive mode: rays per pixel of the first pass, to the light's disk facing the pixel (rounded up to a full grid of ceil(sqrt(n)) columns; fewer than n_samples)"),
            ParamSpec::int("adaptive_radius", 2, 0, 16, "adaptive mode: a pixel takes the full count when any pixel this close disagreed"),
            ParamSpec::float(
                "ray_offset",
                DEFAULT_RAY_OFFSET,
                0.0,
                0.01,
                "ray origins' offset along the normal, relative to the scene's size (largest absolute coordinate or extent)",
            ),
        ]
    }

    fn parse(p: &ParamSet) -> Result<RaytracedParams> {
        let params = RaytracedParams {
            n_samples: p.int("n_samples") as u32,
            seed: p.int("seed") as u64,
            adaptive: p.bool("adaptive"),
            adaptive_samples: p.int("adaptive_samples") as u32,
            adaptive_radius: p.int("adaptive_radius") as u32,
            ray_offset: p.float("ray_offset"),
        };
        if params.adaptive && params.adaptive_samples >= params.n_samples {
            return Err(Error::InvalidParameter(format!(
                "parameter 'adaptive_samples' of method 'raytraced' must be below n_samples ({}) in adaptive mode, got {}",
                params.n_samples, params.adaptive_samples
            )));
        }
        Ok(params)
    }
}

impl Method for RaytracedShadows {
    const NAME: &'static str = "raytraced";
    const PAPER: &'static str = "shadow rays through wgpu ray queries (beyond the papers): the in-engine exact visibility, \
        with reference's sphere sampling";
    type Params = RaytracedParams;

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        // Reads the scene, the settings and the samples; writes the coarse
        // estimates, the counters, visibility and the list of pixels to refine.
        let bindings = [
            acceleration_structure, layout::parameters, layout::storage_buffer,
            layout::storage_buffer_rw, layout::storage_buffer_rw, layout::visibility_storage, layout::storage_buffer_rw,
        ];
        let entry_points = ["trace", "classify", "select_pixels", "refine"];
        let pass = device
            .features()
            .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
            .then(|| ScreenPass::new(device, pool, "raytraced::pass", crate::shader!("visibility.wgsl"), &bindings, &entry_points));
        Self { pass, cache: AccelerationCache::default() }
    }

    /// The acceleration structures (pass `acceleration`), then the shadow
    /// rays: pass `shadow_rays`, or `classify` and `refine` in adaptive mode.
    fn record(&self, frame: &mut Frame<'_>, params: &RaytracedParams) -> Result<MethodOutput> {
        let Some(pass) = &self.pass else {
            return Err(missing_ray_queries(frame.ctx.device));
        };
        let acceleration = frame.pass("acceleration", |ctx, _, _| self.cache.prepare(ctx))??;
        frame.stat("blas_built", acceleration.blas_built as i64);
        frame.stat("blas_reused", acceleration.blas_reused as i64);
        frame.stat("tlas_built", i64::from(acceleration.tlas_built));
        frame.stat("acceleration_bytes", acceleration.scene_bytes as i64);
        frame.stat("acceleration_cache_bytes", acceleration.cache_bytes as i64);

        let ctx = &frame.ctx;
        let (center, radius) = (ctx.light.center, ctx.light.radius);
        let scene = ctx.prepared;
        let samples = scene_sphere_samples(center, radius, scene, ctx.camera, params.n_samples, params.seed);
        // A point light is one ray per pixel: nothing to adapt.
        let adaptive = params.adaptive && radius > 0.0;
        // The first pass's points: a stratified set on the unit disk (the
        // shader places it on the light's disk facing each pixel).
        let coarse: Vec<SampleUniform> = if adaptive {
            light_samples(DVec3::ZERO, 1.0, DVec3::Z.any_orthonormal_pair(), params.adaptive_samples, params.seed ^ COARSE_SEED)
                .into_iter()
                .map(|u| SampleUniform { position: [u.x as f32, u.y as f32, 0.0, 0.0], normal: [0.0; 4] })
                .collect()
        } else {
            Vec::new()
        };
        let uploaded: Vec<SampleUniform> = samples.iter().map(SampleUniform::from).chain(coarse.iter().copied()).collect();
        let sample_buffer = ctx.buffer(
            "raytraced::samples",
            std::mem::size_of_val(uploaded.as_slice()) as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        ctx.queue.write_buffer(&sample_buffer, 0, bytemuck::cast_slice(&uploaded));
        // The G-buffer's float32 positions are within rounding of the surface
        // at the scale of the scene's coordinates.
        let extent = (scene.bounds_max - scene.bounds_min).max_element() as f64;
        let coordinate = scene.bounds_min.abs().max(scene.bounds_max.abs()).max_element() as f64;
        let offset = params.ray_offset * coordinate.max(extent);
        let c = ctx.light.center_f32;
        let settings = ctx.parameters(
            "raytraced::settings",
            &RaySettingsUniform {
                light: [c[0], c[1], c[2], ctx.light.radius_f32],
                offset: [offset as f32, 0.0, 0.0, 0.0],
                counts: [samples.len() as u32, coarse.len() as u32, params.adaptive_radius, 0],
            },
        );
        let (w, h) = ctx.size;
        let coarse_buffer = ctx.buffer("raytraced::coarse", (w as u64 * h as u64 * 8).max(8), wgpu::BufferUsages::STORAGE);
        let list = ctx.buffer("raytraced::refine_list", (w as u64 * h as u64 * 4).max(4), wgpu::BufferUsages::STORAGE);
        let visibility = ctx.screen_texture("raytraced::visibility");
        let counters = frame.untimed(|ctx, encoder| ctx.counters("raytraced::counters", COUNTERS.len(), encoder));
        let bind_group = pass.bind_group(
            &frame.ctx,
            &[
                Binding::Other(acceleration.tlas_id, acceleration.tlas.as_binding()),
                Binding::Buffer(&settings),
                Binding::Buffer(&sample_buffer),
                Binding::Buffer(&coarse_buffer),
                Binding::Buffer(&counters),
                Binding::Texture(&visibility),
                Binding::Buffer(&list),
            ],
        );
        if adaptive {
            frame.pass("classify", |ctx, encoder, ts| {
                pass.dispatch(ctx, encoder, "classify", &bind_group, ts.and_then(|t| t.compute_part(true, false)));
                pass.dispatch(ctx, encoder, "select_pixels", &bind_group, ts.and_then(|t| t.compute_part(false, true)));
            })?;
            frame.pass("refine", |ctx, encoder, ts| pass.dispatch(ctx, encoder, "refine", &bind_group, ts.map(|t| t.compute())))?;
        } else {
            frame.pass("shadow_rays", |ctx, encoder, ts| pass.dispatch(ctx, encoder, "trace", &bind_group, ts.map(|t| t.compute())))?;
        }
        frame.counters(&counters, COUNTERS);
        frame.stat("light_samples", samples.len() as i64);
        frame.stat("adaptive_samples", coarse.len() as i64);
        Ok(MethodOutput { visibility })
    }
}

#[cfg(test)]
mod tests {
    use crate::methods::MethodConfig;
    use std::collections::BTreeMap;

    #[test]
    fn adaptive_mode_needs_fewer_first_rays_than_the_full_count() {
        let parse = |pairs: &[(&str, crate::params::ParamValue)]| {
            let given: BTreeMap<String, _> = pairs.iter().map(|(k, v)| ((*k).to_owned(), v.clone())).collect();
            MethodConfig::parse("raytraced", &given)
        };
        use crate::params::ParamValue::{Bool, Int};
        assert!(parse(&[("adaptive", Bool(true))]).is_ok());
        let e = parse(&[("adaptive", Bool(true)), ("n_samples", Int(16))]).unwrap_err().to_string();
        assert!(e.contains("'adaptive_samples'") && e.contains("below n_samples (16)"), "{e}");
        // Plain mode ignores adaptive_samples.
        assert!(parse(&[("n_samples", Int(4))]).is_ok());
    }
}
