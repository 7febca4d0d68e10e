//! Method `backprojection`: soft shadow mapping by contour backprojection
//! (G. Guennebaud, L. Barthe, M. Paulin, *High-Quality Adaptive Soft Shadow
//! Mapping*, Eurographics 2007).
//!
//! Pass 1 is the shadow map of `hard` from the light's centre. Then:
//! - `hierarchy` (section 3, cached with the map): the min/max hierarchy of
//!   each map layer, one level per dispatch (`hierarchy.wgsl`).
//! - `classification` (section 3, 5.1, 5.2, 6): with the screen-space
//!   strategy on, the discontinuity buffer (`discontinuity.wgsl`); then per
//!   pixel the kernel of Eq. 1 refined through the local minimum, the class
//!   (lit, umbra, penumbra) from the kernel's depth bounds, the level of
//!   Eq. 2-3 and the dithered selection of Eq. 4-6; selected penumbra
//!   pixels join a list (`classify.wgsl`).
//! - `visibility` (4.1, 4.2, 5.1): one invocation per listed pixel through an
//!   indirect dispatch: marching-squares contour edges of the level's
//!   samples, backprojected from the receiver onto the disk of the light it
//!   sees and integrated radially in closed form, blended with the next
//!   level near a transition (`visibility.wgsl`, `contour.wgsl`).
//! - `pull_push` (5.2): the skipped pixels reconstructed from the others
//!   (`pull_push.wgsl`).
//!
//! Departures from the paper, each for a reason given where it is coded and
//! in docs/methods/backprojection.md: the light is the sphere's disk as seen
//! from the receiver (the paper: a square); the occluder test compares with
//! the receiver's plane rather than its depth; the horizon cuts the disk; the
//! kernel is capped at `MAX_KERNEL_FACTOR` t_k samples by going up levels.

use std::sync::Arc;

use crate::error::{Error, Result};
use crate::frame::{Frame, FrameContext, Intermediate};
use crate::gpu::formats;
use crate::gpu::layout;
use crate::gpu::pool::{Binding, Layout, PooledBuffer, PooledTexture, ResourcePool};
use crate::light_frustum::LightProjection;
use crate::method::{Method, MethodOutput};
use crate::params::{MethodParams, ParamSet, ParamSpec, ParamValue};
use crate::pass_cache::{CachedPass, PassKey};
use crate::passes::centre_map::{self, CENTRE_MAP};
use crate::passes::object_map::{self, OBJECT_MAP};
use crate::passes::screen::ScreenPass;
use crate::passes::shadow_test::ShadowMapSettings;
use crate::passes::volumes::VolumePass;

/// The min/max hierarchy of the centre map, as the pass cache keeps it.
pub const HIERARCHY: CachedPass = CachedPass { name: "hierarchy", capacity: 3 };

/// With 5.1 on, the conservative kernel (Eq. 1 from the local minimum) may
/// span at most this many times `t_k` samples at its level; beyond, the
/// level goes up (the pixel counts as `capped_kernels`). Eq. 3 alone picks
/// the level from the smooth z_occ, whose kernel can be far smaller than the
/// conservative one.
pub const MAX_KERNEL_FACTOR: f32 = 4.0;
/// With 5.1 off, kernels wider than this many level-0 texels still go up
/// levels, so that no pixel runs away with the GPU (`capped_kernels`).
pub const MAX_LEVEL0_KERNEL: f32 = 256.0;
/// Hierarchy levels the uniform block describes (map sides up to 2^15).
const MAX_LEVELS: usize = 16;

#[derive(Debug, Clone, PartialEq)]
pub struct BackprojectionParams {
    pub shadow: ShadowMapSettings,
    /// 4.1: the contour's offset, in [-1, 1].
    pub t: f32,
    /// 5.1, Eq. 2-3: the kernel threshold, samples.
    pub t_k: f32,
    /// 5.1: width of the level-blending region, in levels.
    pub beta: f32,
    /// 5.2, Eq. 6: penumbra width in pixels from which pixels are skipped.
    pub s_min: f32,
    /// 5.1 on.
    pub light_adaptive: bool,
    /// 5.2 on.
    pub screen_adaptive: bool,
    /// Coarse levels' contour crossings found on level 0 (true), or 5.1's
    /// (t = 1: the occluders' centres, at their footprints' minimum depth).
    pub refined_contour: bool,
    /// How many times the kernel cap a kernel may span where a pixel goes
    /// finer than the cap allows: a steep receiver goes no finer, and a
    /// centre-test fallback walks its kernel cut to that width. 1 bounds
    /// every pixel's work by the cap's.
    pub descent: f32,
}

crate::gpu_type! {
    pub struct BackprojectionUniform => "Backprojection" in "methods/backprojection/contour.wgsl" {
        pub(crate) t: f32,
        pub(crate) t_k: f32,
        pub(crate) beta: f32,
        pub(crate) s_min: f32,
        pub(crate) eye: [f32; 4],
        pub(crate) flags: u32,
        pub(crate) levels: u32,
        pub(crate) max_kernel: f32,
        pub(crate) descent: f32,
        pub(crate) level_offset: [[u32; 4]; 4],
        pub(crate) level_size: [[u32; 4]; 4],
    }
}

crate::gpu_type! {
    pub struct HierarchyLevelUniform => "HierarchyLevel" in "methods/backprojection/hierarchy.wgsl" {
        pub(crate) level: u32,
        pub(crate) size: u32,
        pub(crate) below_size: u32,
        pub(crate) offset: u32,
        pub(crate) below_offset: u32,
        pub(crate) layers: u32,
        pub(crate) active_layers: u32,
        pub(crate) far: f32,
    }
}

crate::gpu_type! {
    pub struct PullPushUniform => "PullPushStep" in "methods/backprojection/pull_push.wgsl" {
        pub(crate) mode: u32,
        pub(crate) width: u32,
        pub(crate) height: u32,
        pub(crate) offset: u32,
        pub(crate) other_width: u32,
        pub(crate) other_height: u32,
        pub(crate) other_offset: u32,
        pub(crate) pad: u32,
    }
}

/// Names of the counters, in the order of the shaders' `counters`: pixels
/// per class, penumbra pixels computed and skipped (5.2), computed only for
/// lying on a discontinuity, contour edges processed (every level computed),
/// pixels blended between two levels (5.1), pixels whose kernel forced a
/// coarser level, computed penumbra pixels per level (7: 7 and up), and
/// pixels computed at a finer level than chosen because the chosen level's
/// centre test disagreed with the map's (`visibility.wgsl`), and pixels
/// whose receiver, steep in the map, forced a finer level (`classify.wgsl`),
/// and computed pixels whose kernel crosses a cube face's edge (each goes
/// down `CROSSING_LEVELS` levels in `visibility.wgsl`), and the blocks of
/// 2 x 2 samples the visibility pass walked (its work, which `descent`
/// bounds; tiles skipped whole are not counted).
pub const COUNTER_NAMES: &[&str] = &[
    "lit_pixels",
    "umbra_pixels",
    "penumbra_pixels",
    "penumbra_computed",
    "penumbra_skipped",
    "penumbra_on_discontinuities",
    "contour_edges",
    "blended_pixels",
    "capped_kernels",
    "level_0_pixels",
    "level_1_pixels",
    "level_2_pixels",
    "level_3_pixels",
    "level_4_pixels",
    "level_5_pixels",
    "level_6_pixels",
    "level_7_pixels",
    "level_fallbacks",
    "steep_receivers",
    "face_crossings",
    "blocks_read",
];

/// Sizes and places of the hierarchy's levels: level 0 is the map; level
/// l >= 1 has side ceil(side_{l-1} / 2), all layers of a level stored one
/// after the other, levels one after the other.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HierarchyLayout {
    pub layers: u32,
    /// Side of each level, level 0 first, down to 1.
    pub sizes: Vec<u32>,
    /// First texel of each level in the buffer (0 for level 0, not stored).
    pub offsets: Vec<u32>,
    /// Texels stored (levels 1 and up).
    pub texels: u64,
}

impl HierarchyLayout {
    pub fn new(map_size: u32, layers: u32) -> Self {
        let mut sizes = vec![map_size.max(1)];
        while *sizes.last().unwrap() > 1 {
            let s = *sizes.last().unwrap();
            sizes.push(s.div_ceil(2));
        }
        let mut offsets = vec![0u32];
        let mut texels = 0u64;
        for &s in &sizes[1..] {
            offsets.push(texels as u32);
            texels += layers as u64 * s as u64 * s as u64;
        }
        Self { layers, sizes, offsets, texels }
    }

    pub fn levels(&self) -> u32 {
        self.sizes.len() as u32
    }

    /// Bytes of the buffer: two floats per texel (at least one texel, for
    /// a 1-texel map that has no level above 0).
    pub fn bytes(&self) -> u64 {
        8 * self.texels.max(1)
    }
}

/// The min/max hierarchy (levels 1 and up) of one centre map.
pub struct MinMaxHierarchy {
    pub buffer: PooledBuffer,
    pub layout: HierarchyLayout,
}

pub struct SoftShadowBackprojection {
    hierarchy_layout: Layout,
    hierarchy: wgpu::ComputePipeline,
    discontinuity: ScreenPass,
    classify: ScreenPass,
    visibility: ScreenPass,
    pull_push_layout: Layout,
    pull_push: wgpu::ComputePipeline,
    object_pass: VolumePass,
}

impl MethodParams for BackprojectionParams {
    fn specs() -> Vec<ParamSpec> {
        // The paper's maps are 1k x 1k (section 7.1: the hierarchy of a 1k x 1k
        // map in under 1 ms); its reference averages 2k x 2k maps.
        let mut specs: Vec<ParamSpec> = ShadowMapSettings::specs()
            .into_iter()
            .map(|s| if s.name == "map_size" { s.with_default(ParamValue::Int(1024)) } else { s })
            .collect();
        specs.extend([
            ParamSpec::float("t", 0.0, -1.0, 1.0, "contour offset of 4.1: 0 joins the samples' borders, 1 the occluders' centres, -1 the background samples' centres"),
            ParamSpec::float_above("t_k", 8.0, 0.0, 64.0, "kernel threshold of 5.1 (Eq. 2-3), samples: the smooth kernel spans t_k to 2 t_k samples at its level"),
            ParamSpec::float("beta", 0.05, 0.0, 0.5, "width of 5.1's blending region around a level transition, in levels (0: no blending)"),
            ParamSpec::float_above("s_min", 16.0, 0.0, 1024.0, "5.2 (Eq. 6): screen penumbra width, pixels, from which penumbra pixels are skipped"),
            ParamSpec::bool("light_adaptive", true, "light-space multi-resolution (5.1); off: level 0 only"),
            ParamSpec::bool("screen_adaptive", true, "screen-space multi-resolution with pull-push reconstruction (5.2)"),
            ParamSpec::choice(
                "coarse_contour",
                "refined",
                &["centres", "refined"],
                "contours on coarse levels (5.1): refined (beyond the paper: each crossing of a sample side found on the map by bisection, at the depth found there), centres (the paper's: shrunk onto the occluding samples' centres, t = 1, at their footprints' minimum depths)",
            ),
            ParamSpec::float(
                "descent",
                1.0,
                1.0,
                16.0,
                "beyond the paper: how many times the kernel cap (4 t_k samples) a kernel may span where a pixel goes to a finer level than the cap allows: a steep receiver goes no finer, and a pixel whose coarse level's centre test disagrees with level 0's goes down until they agree and walks its kernel cut to that width (1: every pixel's work within the cap's; up to issue 30 both stopped at 4 caps)",
            ),
        ]);
        specs
    }

    fn parse(p: &ParamSet) -> Result<BackprojectionParams> {
        Ok(BackprojectionParams {
            shadow: ShadowMapSettings::from_params(p),
            t: p.float("t") as f32,
            t_k: p.float("t_k") as f32,
            beta: p.float("beta") as f32,
            s_min: p.float("s_min") as f32,
            light_adaptive: p.bool("light_adaptive"),
            screen_adaptive: p.bool("screen_adaptive"),
            refined_contour: p.choice("coarse_contour") == "refined",
            descent: p.float("descent") as f32,
        })
    }
}

impl Method for SoftShadowBackprojection {
    const NAME: &'static str = "backprojection";
    const PAPER: &'static str = "soft shadow mapping by contour backprojection (Guennebaud, Barthe, Paulin 2007): \
        min/max shadow-map hierarchy, marching-squares contours, radial area integration, light- and screen-space multi-resolution";
    type Params = BackprojectionParams;

    fn cached_passes() -> &'static [CachedPass] {
        &[CENTRE_MAP, HIERARCHY, OBJECT_MAP]
    }

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let hierarchy_layout = pool.layout(
            device,
            "backprojection::hierarchy_layout",
            &[layout::depth_array(0), layout::parameters(1), layout::storage_buffer_rw(2)],
        );
        let module = crate::shaders::module(
            device,
            "backprojection::hierarchy_shader",
            crate::shader!("hierarchy.wgsl"),
        );
        let hierarchy = layout::compute_pipeline_entry(device, "backprojection::hierarchy_pipeline", &module, &hierarchy_layout, "main");
        let storage = layout::visibility_storage;
        let bindings = [layout::storage_buffer_rw as crate::passes::screen::LayoutEntry];
        let discontinuity = ScreenPass::per_pixel(device, pool, "backprojection::discontinuity_pass", crate::shader!("discontinuity.wgsl"), &bindings);
        // Reads the map, the hierarchy, two parameter blocks and the
        // discontinuity marks; writes visibility, class, kernel, level, the
        // pixel list and the counters; after the object map, the widened
        // marks (intermediates).
        let mut bindings = object_map::with_bindings(&[
            layout::depth_array, layout::storage_buffer, layout::parameters, layout::parameters, layout::storage_buffer,
            storage, storage, storage, storage, layout::storage_buffer_rw, layout::storage_buffer_rw,
        ]);
        bindings.push(storage);
        let classify = ScreenPass::per_pixel(device, pool, "backprojection::classify_pass", crate::shader!("classify.wgsl"), &bindings);
        // Reads the map, the hierarchy, two parameter blocks, the kernel and
        // level images and the pixel list; writes visibility and the counters.
        let bindings = [
            layout::depth_array, layout::storage_buffer, layout::parameters, layout::parameters, layout::float_texture, layout::float_texture, layout::storage_buffer,
            storage, layout::storage_buffer_rw,
        ];
        let visibility = ScreenPass::per_pixel(device, pool, "backprojection::visibility_pass", crate::shader!("visibility.wgsl"), &bindings);
        let pull_push_layout = pool.layout(
            device,
            "backprojection::pull_push_layout",
            &[
                layout::float_texture(0),
                layout::float_texture(1),
                layout::parameters(2),
                layout::storage_buffer_rw(3),
                layout::visibility_storage(4),
            ],
        );
        let module = crate::shaders::module(
            device,
            "backprojection::pull_push_shader",
            crate::shader!("pull_push.wgsl"),
        );
        let pull_push = layout::compute_pipeline_entry(device, "backprojection::pull_push_pipeline", &module, &pull_push_layout, "main");
        Self { hierarchy_layout, hierarchy, discontinuity, classify, visibility, pull_push_layout, pull_push, object_pass: object_map::pass(device, pool) }
    }

    fn record(&self, frame: &mut Frame<'_>, params: &BackprojectionParams) -> Result<MethodOutput> {
        let (map, projection) = centre_map::centre_map(frame, &params.shadow)?;
        let layout = HierarchyLayout::new(params.shadow.map_size, projection.layers());
        frame.ctx.check_buffer("backprojection", "the min/max hierarchy", layout.bytes(), "map_size")?;
        let (w, h) = frame.ctx.size;
        let list_bytes = 16 + 4 * w as u64 * h as u64;
        frame.ctx.check_buffer("backprojection", "the list of penumbra pixels", list_bytes, "the image size")?;

        let mut key = PassKey::new(HIERARCHY.name);
        key.key(&centre_map::centre_map_key(&frame.ctx, &params.shadow, &projection));
        let hierarchy = frame.cached(HIERARCHY.name, key.finish(), |frame| {
            let buffer = frame.ctx.buffer("backprojection::hierarchy", layout.bytes(), wgpu::BufferUsages::STORAGE);
            frame.pass(HIERARCHY.name, |ctx, encoder, ts| self.record_hierarchy(ctx, encoder, &map, &projection, &layout, &buffer, ts))?;
            Ok(Arc::new(MinMaxHierarchy { buffer, layout: layout.clone() }))
        })?;

        let objects = object_map::record_if(frame, frame.ctx.light.radius > 0.0, &self.object_pass, &projection, params.shadow.map_size)?;
        // The widened discontinuity marks as an image: for intermediates only.
        let write_lines = params.screen_adaptive && frame.wants_intermediates();
        let uniform = self.uniform(&frame.ctx, params, &hierarchy.layout, write_lines)?;
        let raw = frame.ctx.screen_texture("backprojection::visibility_sparse");
        let classes = frame.ctx.screen_texture("backprojection::class");
        let kernel = frame.ctx.screen_texture("backprojection::kernel");
        let level = frame.ctx.screen_texture("backprojection::level");
        let lines_image = if write_lines {
            frame.ctx.screen_texture("backprojection::discontinuities")
        } else {
            // Not written; the binding still needs an image.
            let usage = wgpu::TextureUsages::STORAGE_BINDING;
            frame.ctx.texture("backprojection::no_discontinuities", (1, 1), formats::VISIBILITY, usage)
        };
        // 5.2's marks, a bit a pixel, rows of whole 32-bit words (a word
        // where 5.2 is off: not read then).
        let line_bytes = if params.screen_adaptive { 4 * u64::from(w.div_ceil(32)) * u64::from(h) } else { 4 };
        frame.ctx.check_buffer("backprojection", "the discontinuity marks", line_bytes, "the image size")?;
        let lines = frame.ctx.buffer("backprojection::discontinuity_marks", line_bytes, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
        let list = frame.ctx.buffer(
            "backprojection::pixel_list",
            list_bytes,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
        );
        let counters = frame.pass("classification", |ctx, encoder, ts| {
            let counters = ctx.counters("backprojection::counters", COUNTER_NAMES.len(), encoder);
            encoder.clear_buffer(&list, 0, Some(16));
            let test = ctx.parameters(
                "backprojection::shadow_test_uniforms",
                &params.shadow.uniform(&projection, ctx.light.center_f32, ctx.light.radius_f32, 0),
            );
            let bp = ctx.parameters("backprojection::uniforms", &uniform);
            let mut first = true;
            if params.screen_adaptive {
                encoder.clear_buffer(&lines, 0, None);
                let bind_group = self.discontinuity.bind_group(ctx, &[Binding::Buffer(&lines)]);
                self.discontinuity.dispatch(ctx, encoder, "main", &bind_group, ts.and_then(|t| t.compute_part(true, false)));
                first = false;
            }
            let resources = [
                Binding::Texture(&map),
                Binding::Buffer(&hierarchy.buffer),
                Binding::Buffer(&test),
                Binding::Buffer(&bp),
                Binding::Buffer(&lines),
                Binding::Texture(&raw),
                Binding::Texture(&classes),
                Binding::Texture(&kernel),
                Binding::Texture(&level),
                Binding::Buffer(&list),
                Binding::Buffer(&counters),
            ];
            let mut resources = objects.after(&resources);
            resources.push(Binding::Texture(&lines_image));
            let bind_group = self.classify.bind_group(ctx, &resources);
            self.classify.dispatch(ctx, encoder, "main", &bind_group, ts.and_then(|t| t.compute_part(first, true)));
            (counters, test, bp)
        })?;
        let (counters, test, bp) = counters;
        frame.pass("visibility", |ctx, encoder, ts| {
            let resources = [
                Binding::Texture(&map),
                Binding::Buffer(&hierarchy.buffer),
                Binding::Buffer(&test),
                Binding::Buffer(&bp),
                Binding::Texture(&kernel),
                Binding::Texture(&level),
                Binding::Buffer(&list),
                Binding::Texture(&raw),
                Binding::Buffer(&counters),
            ];
            let bind_group = self.visibility.bind_group(ctx, &resources);
            self.visibility.dispatch_indirect(encoder, "main", &bind_group, &list, 0, ts.map(|t| t.compute()));
        })?;
        let visibility = if params.screen_adaptive {
            let visibility = frame.ctx.screen_texture("backprojection::visibility");
            frame.pass("pull_push", |ctx, encoder, ts| self.record_pull_push(ctx, encoder, &raw, &classes, &visibility, ts))?;
            visibility
        } else {
            raw.clone()
        };

        frame.stat("hierarchy_levels", hierarchy.layout.levels() as i64);
        frame.counters(&counters, COUNTER_NAMES);
        frame.intermediate(Intermediate::color("backprojection_class", &classes, 1))?;
        frame.intermediate(Intermediate::color("backprojection_kernel", &kernel, 1))?;
        frame.intermediate(Intermediate::color("backprojection_level", &level, 1))?;
        frame.intermediate(Intermediate::color("backprojection_visibility_sparse", &raw, 1))?;
        if write_lines {
            frame.intermediate(Intermediate::color("backprojection_discontinuities", &lines_image, 1))?;
        }
        Ok(MethodOutput { visibility })
    }
}

impl SoftShadowBackprojection {
    fn uniform(&self, ctx: &FrameContext<'_>, params: &BackprojectionParams, layout: &HierarchyLayout, write_lines: bool) -> Result<BackprojectionUniform> {
        let camera = ctx.camera;
        // Eq. 5's eta: pixels per world unit at unit view depth. fov_y is in (0, 180) (camera validation).
        let eta = camera.height as f32 / (2.0 * (0.5 * camera.fov_y_degrees.to_radians()).tan());
        let levels = layout.levels();
        if levels as usize > MAX_LEVELS {
            return Err(Error::InvalidParameter(format!(
                "method 'backprojection' takes map_size up to 2^{} (its hierarchy has at most {MAX_LEVELS} levels)",
                MAX_LEVELS - 1
            )));
        }
        let mut level_offset = [[0u32; 4]; 4];
        let mut level_size = [[0u32; 4]; 4];
        for l in 0..levels as usize {
            level_offset[l / 4][l % 4] = layout.offsets[l];
            level_size[l / 4][l % 4] = layout.sizes[l];
        }
        let max_kernel = if params.light_adaptive { MAX_KERNEL_FACTOR * params.t_k } else { MAX_LEVEL0_KERNEL };
        Ok(BackprojectionUniform {
            t: params.t,
            t_k: params.t_k,
            beta: params.beta,
            s_min: params.s_min,
            eye: [camera.eye[0], camera.eye[1], camera.eye[2], eta],
            flags: u32::from(params.light_adaptive)
                | (u32::from(params.screen_adaptive) << 1)
                | (u32::from(params.refined_contour) << 2)
                | (u32::from(write_lines) << 3),
            levels,
            max_kernel,
            descent: params.descent,
            level_offset,
            level_size,
        })
    }

    /// Levels 1 and up of every layer, each from the one below.
    #[allow(clippy::too_many_arguments)]
    fn record_hierarchy(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        map: &PooledTexture,
        projection: &LightProjection,
        layout: &HierarchyLayout,
        buffer: &PooledBuffer,
        timestamps: Option<crate::gpu::PassTimestamps<'_>>,
    ) {
        let levels = layout.levels() as usize;
        for l in 1..levels {
            let uniform = HierarchyLevelUniform {
                level: l as u32,
                size: layout.sizes[l],
                below_size: layout.sizes[l - 1],
                offset: layout.offsets[l],
                below_offset: layout.offsets[l - 1],
                layers: layout.layers,
                active_layers: projection.active,
                far: projection.far(),
            };
            let uniform = ctx.parameters("backprojection::hierarchy_level", &uniform);
            let bind_group = ctx.pool.bind_group(
                ctx.device,
                "backprojection::hierarchy_bind_group",
                &self.hierarchy_layout,
                &[Binding::Texture(map), Binding::Buffer(&uniform), Binding::Buffer(buffer)],
            );
            let writes = timestamps.and_then(|t| t.compute_part(l == 1, l + 1 == levels));
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("backprojection::hierarchy"), timestamp_writes: writes });
            pass.set_pipeline(&self.hierarchy);
            pass.set_bind_group(0, &bind_group, &[]);
            let groups = layout.sizes[l].div_ceil(8);
            pass.dispatch_workgroups(groups, groups, layout.layers);
        }
    }

    /// 5.2's pull-push reconstruction into `visibility`.
    #[allow(clippy::too_many_arguments)]
    fn record_pull_push(
        &self,
        ctx: &FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        raw: &PooledTexture,
        classes: &PooledTexture,
        visibility: &PooledTexture,
        timestamps: Option<crate::gpu::PassTimestamps<'_>>,
    ) {
        let mut sizes = vec![ctx.size];
        while sizes.last().is_some_and(|&(w, h)| w > 1 || h > 1) {
            let (w, h) = *sizes.last().unwrap();
            sizes.push((w.div_ceil(2), h.div_ceil(2)));
        }
        // Levels 1 and up in `pyramid` (level 0 is the image itself).
        let mut offsets = vec![0u32; sizes.len()];
        let mut total = 0u64;
        for (l, &(w, h)) in sizes.iter().enumerate().skip(1) {
            offsets[l] = total as u32;
            total += w as u64 * h as u64;
        }
        let pyramid = ctx.buffer("backprojection::pyramid", 8 * total.max(1), wgpu::BufferUsages::STORAGE);
        let top = sizes.len() - 1;
        // (mode, level, other level): level 1 pulled from the image, the
        // levels above it each from the one below, pushed down to level 1,
        // and the image resolved from level 1.
        let mut steps = Vec::with_capacity(2 * sizes.len());
        steps.extend((1..sizes.len()).map(|l| (if l == 1 { 0u32 } else { 1 }, l, l - 1)));
        steps.extend((1..top).rev().map(|l| (2, l, l + 1)));
        steps.push((3, 0, top.min(1)));
        let count = steps.len();
        for (k, (mode, l, o)) in steps.into_iter().enumerate() {
            // A 1 x 1 image has no level 1: the resolve reads none (other_width 0).
            let other_width = if o == 0 && mode == 3 { 0 } else { sizes[o].0 };
            let uniform = PullPushUniform {
                mode,
                width: sizes[l].0,
                height: sizes[l].1,
                offset: offsets[l],
                other_width,
                other_height: sizes[o].1,
                other_offset: offsets[o],
                pad: 0,
            };
            let uniform = ctx.parameters("backprojection::pull_push_step", &uniform);
            let bind_group = ctx.pool.bind_group(
                ctx.device,
                "backprojection::pull_push_bind_group",
                &self.pull_push_layout,
                &[Binding::Texture(raw), Binding::Texture(classes), Binding::Buffer(&uniform), Binding::Buffer(&pyramid), Binding::Texture(visibility)],
            );
            let writes = timestamps.and_then(|t| t.compute_part(k == 0, k + 1 == count));
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("backprojection::pull_push"), timestamp_writes: writes });
            pass.set_pipeline(&self.pull_push);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(sizes[l].0.div_ceil(8), sizes[l].1.div_ceil(8), 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hierarchy_levels_halve_down_to_one_texel() {
        let l = HierarchyLayout::new(2048, 1);
        assert_eq!(l.levels(), 12);
        assert_eq!(l.sizes[1], 1024);
        assert_eq!(*l.sizes.last().unwrap(), 1);
        assert_eq!(l.offsets[2], 1024 * 1024);
        let odd = HierarchyLayout::new(100, 6);
        assert_eq!(odd.sizes, vec![100, 50, 25, 13, 7, 4, 2, 1]);
        assert_eq!(odd.offsets[2], 6 * 50 * 50);
        assert_eq!(odd.texels, 6 * (50 * 50 + 25 * 25 + 13 * 13 + 7 * 7 + 16 + 4 + 1));
    }

    #[test]
    fn the_visibility_pass_calls_each_large_function_once() {
        // Drivers inline every call: with a call of `centre_inside` per
        // centre test and two of `visibility`, the pass's pipeline took 38 s
        // to compile on NVIDIA's driver and 53-59 s on lavapipe without its
        // shader cache; with one call site each, 5 s and 12-13 s
        // (docs/gpu_timings.md).
        let code: String = include_str!("visibility.wgsl").lines().map(|l| l.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n");
        for f in ["centre_inside(", "visibility(r"] {
            assert_eq!(code.matches(f).count(), 1, "{f}");
        }
    }
}
