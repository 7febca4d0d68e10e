//! Method `pvmf`: penumbra volume mask filtering (Cournia chapter 5).
//!
//! Pass 1 is a depth shadow map from the light centre (5.5 uses a
//! second-depth map; the default here is `hard`'s `slope` bias, see
//! `specs`). Pass 2 builds, on the CPU, an overestimated penumbra
//! volume for every silhouette edge on its own (5.1) and renders them from
//! the light into the penumbra volume mask: depth plus d_e. Pass 3 estimates
//! visibility (5.2): pixels inside a volume, or failing the shadow-map test,
//! take a jittered n_pcf x n_pcf percentage-closer filter of width w_pcf;
//! the rest take no taps. Passes 4 and 5 blur the estimate separably over
//! texels of the same object, only where the blur mask says (5.3). The
//! shared shading composites (5.4).
//!
//! Options beyond the paper, each measured against it (README): `offsets =
//! "radius"` scales the paper's unit extrusion offsets by the light's radius
//! (the paper's volumes do not depend on r at all, so they miss penumbrae of
//! lights larger than one scene unit and waste work for small ones);
//! `kernel = "disk"` samples the disk the light projects to rather than a
//! square; `umbra = "skip"` gives pixels that fail the test outside every
//! volume v = 0 without filtering; `bias = "midpoint"` is the mid-point map
//! the paper names as future work; `occluder_distance = "darker"` (the
//! default) filters a shadowed receiver a second time for the occluder on
//! its centre ray where that lies beyond the mask's edges, and
//! `"farthest_edge"` takes d_o from the farthest enclosing edges (a second,
//! depthless mask pass).

use std::sync::Arc;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::frame::{Frame, Intermediate};
use crate::gpu::layout;
use crate::gpu::pool::{Binding, PooledBuffer, PooledTexture, ResourcePool};
use crate::light_frustum::LightProjection;
use crate::method::{Method, MethodOutput};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::pass_cache::{CachedPass, PassKey};
use crate::passes::centre_map::{self, CENTRE_MAP};
use crate::passes::map_rays::MapBound;
use crate::passes::object_map::{self, OBJECT_MAP};
use crate::passes::solid_layers::{self, SolidLayersPass, SOLID_LAYERS};
use crate::passes::samplers::{ComparisonSamplers, Filter};
use crate::passes::screen::ScreenPass;
use crate::passes::shadow_test::{ShadowMapSettings, ShadowTestUniform};
use crate::passes::volumes::{Keep, VolumePass};
use crate::silhouettes::{OpenEdges, Repairs};

pub mod geometry;
pub use geometry::{mask_volumes, MaskStats, MaskVertex, Offsets};

/// The d_e channel of the mask.
pub const DISTANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// The farthest d_e channel (`occluder_distance = "farthest_edge"`): d_e
/// over the far distance, blended with `Max`, which 32-bit floats need a
/// feature for and 16-bit floats do not.
pub const FARTHEST_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;

/// The penumbra volume mask (pass 2) and the visibility estimate (pass 3),
/// as the pass cache keeps them.
pub const MASK: CachedPass = CachedPass { name: "mask", capacity: 1 };
pub const ESTIMATION: CachedPass = CachedPass { name: "estimation", capacity: 1 };

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kernel {
    /// The paper's n_pcf x n_pcf cells, w_pcf / n_pcf square.
    Square,
    /// The same stratified cells mapped onto the disk inscribed in that square.
    Disk,
}

/// Where d_o (5.2) comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OccluderDistance {
    /// The mask's d_e channel: the volume nearest the light (5.1, 5.2).
    NearestVolume,
    /// The edge farthest from the light whose volume covers the receiver's
    /// texel and which lies nearer the light than the receiver.
    FarthestEdge,
    /// The mask's, and where the receiver fails the shadow-map test behind
    /// an occluder farther from the light than that d_o, a second filter
    /// sized for that occluder's distance; the lower lit fraction is kept.
    Darker,
}

impl OccluderDistance {
    pub const NAMES: [&'static str; 3] = ["nearest_volume", "farthest_edge", "darker"];

    fn parse(name: &str) -> Self {
        match name {
            "farthest_edge" => Self::FarthestEdge,
            "darker" => Self::Darker,
            _ => Self::NearestVolume,
        }
    }

    /// Whether the mask pass also keeps the farthest edge per texel.
    pub fn farthest(self) -> bool {
        self == Self::FarthestEdge
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct PvmfParams {
    pub shadow: ShadowMapSettings,
    /// Overestimation of the volumes, in (0, 1] (5.1).
    pub s_e: f64,
    /// Scale of the filter width (5.2). The paper gives no value; w_pcf is the
    /// radius of the light's projection into the map through the occluder,
    /// so 2 makes the kernel span its diameter (the default).
    pub s_p: f64,
    /// Filter taps per axis (5.2).
    pub n_pcf: u32,
    /// Blur taps per axis beyond the centre (5.3); 0 leaves the raw estimate.
    pub n_blur: u32,
    /// The blur (5.3) takes only pixels whose filter is at least this wide,
    /// in map texels (0: every filtered pixel, the paper's).
    pub blur_min_width: f64,
    /// Fixes the filter's jitter.
    pub seed: u64,
    /// Hardware 2x2 bilinear comparison per tap (5.5), or the nearest texel.
    pub filter: Filter,
    pub offsets: Offsets,
    pub kernel: Kernel,
    /// Weigh each failing tap by the part of the light its occluder hides,
    /// within that occluder's light cone (`estimate = "area"`), rather than
    /// counting the failing taps (5.2, `"pcf"`).
    pub area_estimate: bool,
    /// Count a failing tap only where the receiver lies behind the surface
    /// its texel stores (`blocker_test = "behind"`, `passes/pcf_taps.wgsl`'s
    /// `receiver_behind`), not wherever that texel is nearer the light than
    /// the receiver's plane (5.2, `"plane"`).
    pub behind: bool,
    /// Filter pixels that fail the shadow-map test outside every volume (5.2).
    pub filter_umbra: bool,
    /// Render the mask a texel per pixel on the visible receivers
    /// (`mask_size = "auto"`, `FrameContext::receiver_image_size`: the mask
    /// is read only at the receivers' projections, the volume test and d_o's
    /// taps) rather than at the shadow map's size (`"map"`, the paper's).
    pub mask_auto: bool,
    pub open_edges: OpenEdges,
    /// Departures from the paper for real meshes (`Repairs`: `hidden`, `horizon` and `distance` apply).
    pub repairs: Repairs,
    /// Where d_o (5.2) comes from (`occluder_distance`).
    pub occluder_distance: OccluderDistance,
    /// The map bound (beyond the paper: `map_samples`, `map_bound`,
    /// `map_march`, `map_solids`; passes/map_rays.rs) on the filtered pixels.
    pub map: MapBound,
}

/// `map_samples`' default for pvmf: 16 rays (beyond 5.2, issue 28; 0 is the
/// paper's filter alone). On the generated suite the bound took the misses
/// of issue 28's bar from 5 scenes to 2 and the median penumbra RMSE 0.0553
/// -> 0.0489; it took the bench's median time over `hard` from 2.39 to 3.39
/// at 256x256, and 4.79 to 8.11 at 1920x1080, under `pcss`'s 13.42
/// (docs/methods/pvmf.md). 32 rays misses 1 scene but costs 12.95 there.
pub const MAP_SAMPLES_DEFAULT: i64 = 16;

/// The values of `repairs`: cumulative, in the order docs/real_meshes.md
/// measures them; "all" (the default) adds the local edge distance to the last.
pub const REPAIR_LEVELS: [&str; 4] = ["all", "none", "hidden", "hidden+horizon"];

crate::gpu_type! {
    pub struct SettingsUniform => "PvmfSettings" in "methods/pvmf/estimate.wgsl" {
        pub(crate) s_p: f32,
        pub(crate) n_pcf: u32,
        pub(crate) seed: u32,
        pub(crate) flags: u32,
        pub(crate) blur_min_width: f32,
    }
}

crate::gpu_type! {
    pub struct BlurUniform => "BlurSettings" in "methods/pvmf/blur.wgsl" {
        pub(crate) step: [i32; 2],
        pub(crate) half_width: i32,
        pub(crate) count: u32,
    }
}

/// Named counters, in the order of `methods/pvmf/estimate.wgsl`'s
/// `counters`: the map bound's (`map_samples`) as pvm's and the wedges'.
pub const COUNTERS: [&str; 5] = ["masked_pixels", "filtered_pixels", "blurred_pixels", "map_bounded_pixels", "map_raised_pixels"];

/// The penumbra volume mask (pass 2).
pub struct PvmfMask {
    pub mask_depth: PooledTexture,
    pub edge_distance: PooledTexture,
    /// The largest d_e over the far distance per texel (`farthest_edge`), or
    /// `None`.
    pub farthest_distance: Option<PooledTexture>,
    pub stats: MaskStats,
    /// Meshes whose silhouettes came from the silhouette cache.
    pub silhouette_cache_hits: usize,
}

/// The visibility estimate (pass 3) with what it writes besides: the blur
/// passes read it and write only the frame's visibility and the
/// `blurred_pixels` counter.
pub struct PvmfEstimate {
    /// The raw estimate (the frame's visibility when nothing is blurred).
    pub raw: PooledTexture,
    pub blur_mask: PooledTexture,
    pub filter_width: PooledTexture,
    /// `COUNTERS` as the estimate left them (`blurred_pixels` still 0).
    pub counters: PooledBuffer,
}

/// Whether passes 4 and 5 run: not for n_blur = 0, nor for a point light
/// (nothing is masked, so nothing would be blurred).
pub fn blurs(params: &PvmfParams, radius: f64) -> bool {
    params.n_blur > 0 && radius > 0.0
}

/// What pass 2 reads besides the geometry: the light, the projection, the
/// map size and the volume parameters (appended to the pass-cache key).
pub fn mask_key(params: &PvmfParams, projection: &LightProjection, (l, r): (DVec3, f64), mask_size: u32, key: &mut PassKey) {
    let offsets = if params.offsets == Offsets::Unit { "unit" } else { "radius" };
    key.f64s(&l.to_array())
        .f64s(&[r, params.s_e])
        .bytes(offsets.as_bytes())
        .bytes(params.open_edges.name().as_bytes())
        .bytes(&[u8::from(params.repairs.hidden), u8::from(params.repairs.distance), u8::from(params.occluder_distance.farthest())])
        .projection(projection)
        .u32(params.shadow.map_size)
        .u32(mask_size);
}

/// The uniform blocks of pass 3.
fn estimate_uniforms(params: &PvmfParams, projection: &LightProjection, light: ([f32; 3], f32)) -> (ShadowTestUniform, SettingsUniform) {
    let test = params.shadow.uniform(projection, light.0, light.1, 0);
    let flags = u32::from(params.kernel == Kernel::Disk)
        | (u32::from(!params.filter_umbra) << 1)
        | (u32::from(params.repairs.horizon) << 2)
        | (u32::from(params.area_estimate) << 3)
        | (u32::from(params.behind) << 4)
        | (u32::from(params.occluder_distance == OccluderDistance::FarthestEdge) << 5)
        | (u32::from(params.occluder_distance == OccluderDistance::Darker) << 6)
        | (u32::from(params.map.both) << 7)
        | (u32::from(params.map.solid) << 8);
    let mut test = test;
    [test.mode[2], test.mode[3]] = params.map.mode();
    let settings = SettingsUniform { s_p: params.s_p as f32, n_pcf: params.n_pcf, seed: params.seed as u32, flags, blur_min_width: params.blur_min_width as f32 };
    (test, settings)
}

/// What pass 3 reads besides the G-buffer, the shadow map and the mask: its
/// uniform blocks, bit for bit, the comparison sampler, and whether it reads
/// the solid layers (map_solids; their own key is the centre map's, which
/// the estimate's holds).
pub fn estimate_key(params: &PvmfParams, projection: &LightProjection, light: ([f32; 3], f32), key: &mut PassKey) {
    let (test, settings) = estimate_uniforms(params, projection, light);
    key.pod(&test).pod(&settings).bytes(params.filter.name().as_bytes()).u32(u32::from(params.map.solids));
}

pub struct PenumbraVolumeMaskFiltering {
    mask_pass: VolumePass,
    farthest_pass: VolumePass,
    estimate: ScreenPass,
    blur: ScreenPass,
    object_pass: VolumePass,
    solid_pass: SolidLayersPass,
}

impl MethodParams for PvmfParams {
    fn specs() -> Vec<ParamSpec> {
        // Departure from 5.5 (second-depth maps): `slope`, the default of
        // `hard`. A closed caster thinner than the depth a texel spans along
        // its slope shadowed its own lit face in the second-depth map (a plate
        // 1e-4 thick: visibility 0.70 on its top, issue 22), and an open
        // surface facing the light is culled from it and casts no shadow (the
        // open bunny: penumbra RMSE 0.105 against 0.078). On the closed real
        // meshes the two differ by at most 0.014 (docs/real_meshes.md); a
        // minimum separation added to `second_depth` instead let light leak
        // where a caster meets the ground.
        // Departures from 5.1-5.3 as defaults (issues 28 and 31): the disk
        // kernel, no blur, extrusion offsets scaled by the light's radius,
        // the umbra skipped and s_e 0.02. The paper's settings (square, 12,
        // unit, filter, 0.5; `penumbra.comparison.PAPER["pvmf"]`) measured
        // 0.159 median / 0.287 worst penumbra RMSE over the 40 generated
        // scenes against 0.073 / 0.268 (tests/test_generated_scenes.py), and
        // 23-44% of pixels off the truth in rooms against at most 4.2%
        // (docs/omnidirectional.md): the unit offsets are world units,
        // whatever the scene's scale and the light's size, and the blur is
        // 12 pixels whatever the image's.
        let mut specs = ShadowMapSettings::specs_and([
            ParamSpec::float_above("s_e", 0.02, 0.0, 1.0, "overestimation of the volumes (5.1; the paper's 0.5)"),
            ParamSpec::float("s_p", 2.0, 0.0, 100.0, "scale of the filter width w_pcf (5.2)"),
            ParamSpec::int("n_pcf", 7, 1, 32, "filter taps per axis (5.2)"),
            ParamSpec::int("n_blur", 0, 0, 64, "blur taps per axis beyond the centre (5.3; the paper's 12); 0 leaves the raw estimate"),
            // Departure from 5.3, whose blur takes every filtered pixel: the
            // blur hides the noise of taps jittered over w_pcf, and a filter
            // narrower than a texel reads one bilinear cell, which has none
            // to hide. Blurring there only spreads a hard edge over n_blur
            // pixels: as the light shrinks (w_pcf ~ r) the paper's pvmf
            // kept 0.8-1.0% of the built-in scenes' pixels off `hard` by
            // more than 0.5 at r = 1e-5 (docs/connectivity.md); with 1 texel,
            // none.
            ParamSpec::float("blur_min_width", 1.0, 0.0, 1e6, "blur (5.3) only pixels whose filter w_pcf is at least this wide, in map texels (0: every filtered pixel, the paper's)"),
            ParamSpec::seed(u32::MAX as i64, "fixes the filter's jitter"),
            Filter::spec(),
            ParamSpec::choice("offsets", "radius", &["unit", "radius"], "extrusion offsets of 5.1: unit vectors (the paper), or scaled by the light's radius"),
            ParamSpec::choice("kernel", "disk", &["square", "disk"], "filter taps: the paper's square, or the disk the light projects to"),
            ParamSpec::choice(
                "estimate",
                "pcf",
                &["pcf", "area"],
                "the estimate over the taps: the fraction that fail (5.2), or each failing tap weighted by the part of the light its occluder hides, within its light cone",
            ),
            ParamSpec::choice(
                "blocker_test",
                "plane",
                &["plane", "behind"],
                "which failing taps hide the light: plane (5.2: a texel nearer the light than the receiver's plane), behind (and the receiver lies behind the texel's own surface: walls and floors beside a receiver hide nothing)",
            ),
            ParamSpec::choice("umbra", "skip", &["filter", "skip"], "pixels failing the test outside every volume: filter them (5.2, the paper) or give them 0"),
            // Departure from 5.1, whose mask is the shadow map's size (issue
            // 30): `mask_size` below.
            ParamSpec::choice(
                "mask_size",
                "auto",
                &["map", "auto"],
                "the penumbra volume mask's resolution: the shadow map's (5.1), or auto: a texel per pixel on the visible receivers (map_size's criterion), at most the map's",
            ),
            // Departure from 5.2 (issue 28): `occluder_distance` below.
            ParamSpec::choice(
                "occluder_distance",
                "darker",
                &OccluderDistance::NAMES,
                "where d_o (5.2) comes from: the d_e of the volume nearest the light at the receiver's texel (the mask's channel, 5.1); of the edge farthest from the light whose volume covers that texel and which lies nearer the light than the receiver (a caster near the light then no longer widens the filter of a farther caster's shadow); or darker: the mask's, and where the receiver fails the shadow-map test behind an occluder farther from the light than that d_o, a second filter sized for that occluder's distance, the lower lit fraction kept (docs/methods/pvmf.md)",
            ),
            OpenEdges::spec(),
            ParamSpec::choice(
                "repairs",
                "all",
                &REPAIR_LEVELS,
                "departures from the paper for real meshes, cumulative (docs/real_meshes.md): none, hidden, hidden+horizon, all (+distance)",
            ),
        ]);
        specs.extend(MapBound::specs(
            MAP_SAMPLES_DEFAULT,
            "on the filtered pixels, points of the light's disk whose rays from the pixel are followed through the shadow map (as pvm's and the wedges'): the estimate is at most the fraction seen plus 1.2 n^-0.7 and the texel band at d_o (beyond the paper, the default since issue 28); 0: 5.2's filter alone (the paper)",
        ));
        specs
    }

    fn parse(p: &ParamSet) -> Result<PvmfParams> {
        if p.choice("estimate") == "area" && p.choice("kernel") == "square" {
            return Err(Error::InvalidParameter(
                "pvmf: estimate='area' takes its taps on the disk the light projects to; kernel='square' does not apply (use kernel='disk')".to_owned(),
            ));
        }
        Ok(PvmfParams {
            shadow: ShadowMapSettings::from_params(p),
            s_e: p.float("s_e"),
            s_p: p.float("s_p"),
            n_pcf: p.int("n_pcf") as u32,
            n_blur: p.int("n_blur") as u32,
            blur_min_width: p.float("blur_min_width"),
            seed: p.int("seed") as u64,
            filter: Filter::from_params(p),
            offsets: if p.choice("offsets") == "radius" { Offsets::Radius } else { Offsets::Unit },
            kernel: if p.choice("kernel") == "disk" { Kernel::Disk } else { Kernel::Square },
            area_estimate: p.choice("estimate") == "area",
            behind: p.choice("blocker_test") == "behind",
            filter_umbra: p.choice("umbra") == "filter",
            mask_auto: p.choice("mask_size") == "auto",
            open_edges: OpenEdges::parse(p.choice("open_edges")),
            repairs: Repairs::parse(p.choice("repairs")),
            occluder_distance: OccluderDistance::parse(p.choice("occluder_distance")),
            map: MapBound::parse(p),
        })
    }
}

impl Method for PenumbraVolumeMaskFiltering {
    const NAME: &'static str = "pvmf";
    const PAPER: &'static str = "penumbra volume mask filtering (Cournia ch. 5)";
    type Params = PvmfParams;

    fn cached_passes() -> &'static [CachedPass] {
        &[CENTRE_MAP, MASK, ESTIMATION, OBJECT_MAP, SOLID_LAYERS]
    }

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32, 2 => Float32];
        let source = crate::shader!("mask.wgsl");
        let mask_pass = VolumePass::new::<MaskVertex>(Keep::Nearest, device, pool, "pvmf::mask_pass", source.clone(), ("vs_mask", "fs_mask"), &attributes, &[DISTANCE_FORMAT]);
        // The same volumes, every one kept (occluder_distance "farthest_edge").
        let farthest_pass =
            VolumePass::new::<MaskVertex>(Keep::Max, device, pool, "pvmf::farthest_pass", source, ("vs_mask", "fs_mask_far"), &attributes, &[FARTHEST_FORMAT]);
        let storage = layout::visibility_storage;
        // Reads the map, the mask's depth and d_e, the test and settings blocks;
        // writes the raw estimate, the blur mask, the filter width and the counters.
        let mut bindings = object_map::with_bindings(&[
            layout::depth_array, layout::depth_array, layout::float_array, layout::comparison_sampler, layout::parameters, layout::parameters,
            storage, storage, storage, layout::storage_buffer_rw, layout::float_array,
        ]);
        // The solid layers (map_solids).
        bindings.push(layout::storage_buffer);
        let estimate = ScreenPass::per_pixel(device, pool, "pvmf::estimate_pass", crate::shader!("estimate.wgsl"), &bindings);
        let bindings = [layout::float_texture, layout::float_texture, layout::parameters, storage, layout::storage_buffer_rw];
        let blur = ScreenPass::per_pixel(device, pool, "pvmf::blur_pass", crate::shader!("blur.wgsl"), &bindings);
        Self { mask_pass, farthest_pass, estimate, blur, object_pass: object_map::pass(device, pool), solid_pass: SolidLayersPass::new(device, pool) }
    }

    fn record(&self, frame: &mut Frame<'_>, params: &PvmfParams) -> Result<MethodOutput> {
        let (map, projection) = centre_map::centre_map(frame, &params.shadow)?;
        let light = frame.ctx.light;
        let (l, r) = (light.center, light.radius);
        let map_size = params.shadow.map_size;
        let mask_size = if params.mask_auto { frame.ctx.receiver_image_size(map_size, &projection) } else { map_size };
        let mut mask_key = PassKey::new(MASK.name);
        mask_key.bytes(&frame.ctx.geometry);
        self::mask_key(params, &projection, (l, r), mask_size, &mut mask_key);
        let mask_key = mask_key.finish();
        let mut fresh_mask = false;
        let mask = frame.cached(MASK.name, mask_key.clone(), |frame| {
            fresh_mask = true;
            self.record_mask(frame, params, &projection, mask_size).map(Arc::new)
        })?;
        // The estimate reads the G-buffer, the shadow map and the mask (their
        // keys), and its own uniforms: everything but n_blur.
        let mut key = PassKey::new(ESTIMATION.name);
        key.key(&frame.ctx.gbuffer_key).key(&centre_map::centre_map_key(&frame.ctx, &params.shadow, &projection)).key(&mask_key);
        estimate_key(params, &projection, (light.center_f32, light.radius_f32), &mut key);
        // The solid layers before the estimate's cache, as pvm's and the
        // wedges': their `solid_meshes` stat is then the same whether the
        // estimate is reused or not (tests/test_pass_cache.py).
        let solids = solid_layers::record_if(frame, params.map.solids && params.map.samples > 0 && r > 0.0, &self.solid_pass, &projection, params.shadow.map_size)?;
        // The object map is a function of the centre map's key (geometry,
        // projection, map size), which the estimate's key holds.
        let estimate = frame.cached(ESTIMATION.name, key.finish(), |frame| {
            let objects = object_map::record_if(frame, params.repairs.horizon && r > 0.0, &self.object_pass, &projection, params.shadow.map_size)?;
            let estimate = PvmfEstimate {
                raw: frame.ctx.screen_texture("pvmf::visibility_raw"),
                blur_mask: frame.ctx.screen_texture("pvmf::blur_mask"),
                filter_width: frame.ctx.screen_texture("pvmf::filter_width"),
                counters: frame.ctx.buffer(
                    "pvmf::estimate_counters",
                    4 * COUNTERS.len() as u64,
                    wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                ),
            };
            frame.pass("estimation", |ctx, encoder, ts| {
                encoder.clear_buffer(&estimate.counters, 0, None);
                let (test, settings) = estimate_uniforms(params, &projection, (light.center_f32, light.radius_f32));
                let test = ctx.parameters("pvmf::test_uniforms", &test);
                let settings = ctx.parameters("pvmf::settings", &settings);
                let samplers = ComparisonSamplers::shared(ctx.device, ctx.pool);
                let resources = [
                    Binding::Texture(&map),
                    Binding::Texture(&mask.mask_depth),
                    Binding::Texture(&mask.edge_distance),
                    samplers.binding(params.filter),
                    Binding::Buffer(&test),
                    Binding::Buffer(&settings),
                    Binding::Texture(&estimate.raw),
                    Binding::Texture(&estimate.blur_mask),
                    Binding::Texture(&estimate.filter_width),
                    Binding::Buffer(&estimate.counters),
                    // Without farthest_edge the shader reads no such channel: d_e stands in.
                    Binding::Texture(mask.farthest_distance.as_ref().unwrap_or(&mask.edge_distance)),
                ];
                let mut resources = objects.after(&resources);
                resources.push(Binding::Buffer(&solids.buffer));
                self.estimate.run(ctx, encoder, &resources, ts);
            })?;
            Ok(Arc::new(estimate))
        })?;
        // This frame's counters: the estimate's, to which the blur adds its own.
        let counters = frame.untimed(|ctx, encoder| {
            let size = 4 * COUNTERS.len() as u64;
            let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
            let counters = ctx.buffer("pvmf::counters", size, usage);
            encoder.copy_buffer_to_buffer(&estimate.counters, 0, &counters, 0, size);
            counters
        });
        let visibility = if blurs(params, r) {
            let visibility = frame.ctx.screen_texture("pvmf::visibility");
            frame.pass("blur", |ctx, encoder, ts| self.record_blur(ctx, encoder, params, &estimate, &counters, &visibility, ts))?;
            visibility
        } else {
            estimate.raw.clone()
        };
        let s = &mask.stats;
        frame.silhouette_stats(&s.silhouette, mask.silhouette_cache_hits, fresh_mask);
        frame.stat("mask_quads", s.mask_quads as i64);
        frame.stat("mask_size", i64::from(mask_size));
        frame.counters(&counters, &COUNTERS);
        frame.intermediate(Intermediate::depth("pvmf_mask_depth", &mask.mask_depth, projection.far()))?;
        frame.intermediate(Intermediate::color("pvmf_edge_distance", &mask.edge_distance, 1))?;
        // The farthest-edge channel (R16Float) is not an intermediate: their
        // readback takes 32-bit texels.
        frame.intermediate(Intermediate::color("pvmf_visibility_raw", &estimate.raw, 1))?;
        frame.intermediate(Intermediate::color("pvmf_blur_mask", &estimate.blur_mask, 1))?;
        frame.intermediate(Intermediate::color("pvmf_filter_width", &estimate.filter_width, 1))?;
        Ok(MethodOutput { visibility })
    }
}

impl PenumbraVolumeMaskFiltering {
    /// Pass 2: builds and renders the penumbra volume mask (5.1).
    fn record_mask(&self, frame: &mut Frame<'_>, params: &PvmfParams, projection: &LightProjection, map: u32) -> Result<PvmfMask> {
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
        // d_e = 0 (the clear value) marks texels without a volume.
        let edge_distance = frame.ctx.light_texture("pvmf::edge_distance", map, projection.layers(), DISTANCE_FORMAT, usage);
        // The CPU work (silhouettes and volumes) is part of the pass's time.
        let (mask_depth, stats, silhouette_cache_hits, vertices) = frame.pass("mask", |ctx, encoder, ts| -> Result<_> {
            let (l, r) = (ctx.light.center, ctx.light.radius);
            let (mut stats, mut cache_hits, mut vertices) = (MaskStats::default(), 0, Vec::new());
            // A point light has no penumbra: no volumes, and nothing is filtered.
            if r > 0.0 {
                let silhouette = ctx.silhouettes.seen_from_light(ctx.prepared, l, params.open_edges, params.repairs.hidden)?;
                cache_hits = silhouette.cache_hits;
                // Beyond the far plane from any moved point (they lie between l and the edges).
                let reach = 4.0 * projection.far() as f64 + 4.0 * r;
                (vertices, stats) = mask_volumes(&silhouette.edges, l, r, params.s_e, params.offsets, reach, params.repairs.distance);
                stats.silhouette.add_scene(&silhouette);
            }
            // The moved points lie between the light and the edges, nearer than
            // the scene's near plane: clip only what is (almost) at the light.
            let mask_projection = projection.with_near(projection.far() * 1e-4);
            let vertices = self.mask_pass.upload(ctx, &vertices)?;
            let depth = self.mask_pass.record_uploaded(ctx, encoder, &mask_projection, &vertices, map, &[&edge_distance], ts);
            let depth = depth.expect("the mask pass (Keep::Nearest) returns its depth map");
            Ok((depth, stats, cache_hits, vertices))
        })??;
        // The same volumes again, without the depth test (its own pass, timed apart).
        let farthest_distance = if params.occluder_distance.farthest() {
            let farthest = frame.ctx.light_texture("pvmf::farthest_distance", map, projection.layers(), FARTHEST_FORMAT, usage);
            frame.pass("mask_farthest", |ctx, encoder, ts| {
                let mask_projection = projection.with_near(projection.far() * 1e-4);
                self.farthest_pass.record_uploaded(ctx, encoder, &mask_projection, &vertices, map, &[&farthest], ts);
            })?;
            Some(farthest)
        } else {
            None
        };
        Ok(PvmfMask { mask_depth, edge_distance, farthest_distance, stats, silhouette_cache_hits })
    }

    /// Passes 4 and 5: the separable, object-aware blur (5.3) of the
    /// estimate, horizontal into a temporary image, then vertical into
    /// `visibility`; `counters` are this frame's.
    #[allow(clippy::too_many_arguments)]
    fn record_blur(
        &self,
        ctx: &crate::frame::FrameContext<'_>,
        encoder: &mut wgpu::CommandEncoder,
        params: &PvmfParams,
        estimate: &PvmfEstimate,
        counters: &PooledBuffer,
        visibility: &PooledTexture,
        timestamps: Option<crate::gpu::PassTimestamps<'_>>,
    ) {
        let temporary = ctx.screen_texture("pvmf::blur_temporary");
        let half_width = (params.n_blur / 2) as i32;
        let steps = [(&estimate.raw, &temporary, [1, 0], true), (&temporary, visibility, [0, 1], false)];
        for (source, destination, step, first) in steps {
            let uniforms = ctx.parameters("pvmf::blur_uniforms", &BlurUniform { step, half_width, count: u32::from(first) });
            let resources = [
                Binding::Texture(source),
                Binding::Texture(&estimate.blur_mask),
                Binding::Buffer(&uniforms),
                Binding::Texture(destination),
                Binding::Buffer(counters),
            ];
            let bind_group = self.blur.bind_group(ctx, &resources);
            let writes = timestamps.and_then(|t| t.compute_part(first, !first));
            self.blur.dispatch(ctx, encoder, "main", &bind_group, writes);
        }
    }
}
