//! Method `wedges`: penumbra wedges (Akenine-Möller & Assarsson 2002), by
//! default with the per-pixel coverage of their 2003 successor (Assarsson &
//! Akenine-Möller, "A geometry-based soft shadow volume algorithm using
//! graphics hardware"): the wedge only bounds where an edge matters, and
//! inside it the edge, projected from the pixel onto the light, gives the
//! covered part of the light's disk exactly (`intensity`; the 2002
//! interpolation of 4.2 is `intensity="interpolation"`). Where silhouettes
//! overlap as the light sees them, `overlap="gate"` drops the terms of an
//! edge with another surface right behind it (docs/methods/wedges.md).
//!
//! Pass 1 is the shadow map of `hard`, the hard shadow from the light
//! centre. Pass 2 builds, on the CPU, a penumbra wedge per silhouette edge
//! of the light centre (4.1: front and back planes through the edge and the
//! points c -+ r n, side planes shared by consecutive edges, extra wedges at
//! acute vertices) and bins them by the screen tiles their part inside the
//! scene's box covers. Pass 3 first marks, per 8 x 8 pixels, the binned
//! wedges whose support (`support_planes`) holds none of their points
//! (`tile_cull.wgsl`, beyond the papers, `tile_cull`), then, a compute pass
//! over the G-buffer, adds for
//! every wedge holding the pixel's point the interpolated intensity of 4.2
//! (Eq. 1-3) minus the hard step of that wedge's shadow-volume quad to the
//! hard shadow, and clamps the sum to [0, 1].
//!
//! Why the shadow map rather than the paper's shadow-volume count along the
//! camera ray: the two agree where the silhouette loops close and the
//! camera is lit (the wedges' entry and exit terms telescope to the count),
//! and the map stays right where they do not: junction vertices, edges
//! hidden from the light and open casters leave loops open, which a count
//! turns into unbounded streaks; with the map an error stays inside the
//! wedges. Radius 0 is then exactly `hard`. docs/methods/wedges.md measures it.
//!
//! The silhouettes, their caches and the open/non-manifold caster decision
//! are `pvm`'s (`crate::silhouettes`); the `repairs` levels reuse its
//! `Repairs` ("cone" for the shared side lines, "hidden", "horizon").

use crate::passes::map_rays::MapBound;
use std::sync::Arc;

/// `map_samples`' default for the wedges: 32 points. The wedges' sum is
/// further from the truth than pvm's edge (no one plane to control the
/// rays with), so the rays' own error counts for more: with 32 the
/// generated median is 0.0732 -> 0.0625 at 2.57 against 2.20 times `hard`,
/// and the slow suite's 0.0695 -> 0.0591, lower on 46 of its 60 scenes,
/// higher on 3 (docs/methods/wedges.md).
const MAP_SAMPLES_DEFAULT: i64 = 32;

/// `subsample`'s default: 0.1 light radii. On the bench's 28 scenes at
/// 256x256 it took `wedges`' worst time from 20.9 to 9.9 times `hard`'s
/// (generated:1, a light as wide as its mesh), the whole render 0.97 times
/// as long at the median scene (0.45-1.64: a few ms more where little is
/// interpolated), with the median penumbra RMSE 0.0559 -> 0.0544 (lower on
/// 8 scenes, higher on none by more than 0.001: stray pixels no longer
/// reproduced); on the generated suite at 96x96 the median stays 0.0625
/// (lower on 3, higher on none), on the slow suite 0.0591 -> 0.0584 (lower
/// on 14, higher on none). At 0.05: 11.7 times at worst
/// (docs/methods/wedges.md).
const SUBSAMPLE_DEFAULT: f64 = 0.1;

use bytemuck::Zeroable;
use glam::DMat4;

use crate::error::Result;
use crate::frame::{Frame, Intermediate};
use crate::gpu::layout;
use crate::gpu::pool::{Binding, PooledBuffer};
use crate::method::{Method, MethodOutput};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::pass_cache::{CachedPass, PassKey};
use crate::passes::centre_map::{self, CENTRE_MAP};
use crate::passes::object_map::{self, OBJECT_MAP};
use crate::passes::solid_layers::{self, SolidLayersPass, SOLID_LAYERS};
use crate::passes::screen::ScreenPass;
use crate::passes::shadow_test::ShadowMapSettings;
use crate::passes::volumes::VolumePass;
use crate::silhouettes::{OpenEdges, Repairs};

pub mod geometry;
pub use geometry::{bin_wedges, coverage_bounds, coverage_term, penumbra_wedges, support_planes, wedge_bounds, wedge_intensity, Bins, WedgeBoundsGpu, WedgeGpu, WedgeStats, Wedges, TILE};

/// The values of `repairs`, cumulative in the order docs/methods/wedges.md
/// measures them; "all" adds the horizon to the last.
pub const REPAIR_LEVELS: [&str; 5] = ["all", "none", "hidden", "cone+hidden", "cone+horizon"];

/// The wedges and their screen bins (pass 2), as the pass cache keeps them.
pub const PENUMBRA_WEDGES: CachedPass = CachedPass { name: "penumbra_wedges", capacity: 1 };

#[derive(Debug, Clone, PartialEq)]
pub struct WedgesParams {
    pub shadow: ShadowMapSettings,
    /// Extra wedges per 120 degrees of turn at acute silhouette vertices (4.1, Figure 7).
    pub acute_wedges: u32,
    /// Parker et al.'s 3s^2 - 2s^3 attenuation (4.2, last paragraph).
    pub falloff: bool,
    pub open_edges: OpenEdges,
    pub repairs: Repairs,
    /// Where the hard shadow map is read for a pixel inside wedges (`HardTerm`).
    pub hard_term: HardTerm,
    /// How a wedge's light intensity is computed (`Intensity`).
    pub intensity: Intensity,
    /// Whether a wedge adds nothing where the map just outside its edge's
    /// hard shadow is shadowed by something else (`"gate"`), or its term all
    /// the same (`"sum"`, both papers').
    pub overlap_gate: bool,
    /// Whether separate objects' terms multiply as independent occluders
    /// (`"independent"`) or all add (`"sum"`, both papers').
    pub independent_occluders: bool,
    /// Whether the tile cull (`tile_cull.wgsl`) skips wedges whose support
    /// holds no point of an 8 x 8 block of pixels.
    pub tile_cull: bool,
    /// The map bound (beyond the papers: `map_samples`, `map_bound`,
    /// `map_march`; passes/map_rays.rs).
    pub map: MapBound,
    /// The largest shift, in light radii, of a projected edge between a
    /// pixel and the coarse pixels it may be interpolated from (beyond the
    /// papers; 0: every pixel computed). Coverage only.
    pub subsample: f64,
}

/// How the light intensity s inside a wedge is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Intensity {
    /// The 2002 paper's interpolation between the front and back planes
    /// along the side rays, then between the side planes (4.2, Eq. 1-3).
    Interpolation,
    /// The edge projected from the pixel onto the light, and the part of the
    /// light's disk it uncovers (or covers) measured exactly (Assarsson &
    /// Akenine-Möller 2003's per-pixel coverage). The wedges then only bound
    /// where an edge matters (`geometry::coverage_bounds`).
    Coverage,
}

impl Intensity {
    pub const NAMES: [&'static str; 2] = ["interpolation", "coverage"];
}

/// Where the shadow map is read for a pixel inside wedges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HardTerm {
    /// At the pixel (moved a few texels off a quad plane it nearly lies
    /// on, to h's side); each wedge adds s - h.
    AtPoint,
    /// On the lit side of every holding wedge's quad; each wedge adds s - 1.
    /// The map then counts only the other casters' shadows, which the
    /// wedges' intensities join by the paper's sum (its shadow-volume count).
    LitSide,
}

impl HardTerm {
    pub const NAMES: [&'static str; 2] = ["at_point", "lit_side"];
}

crate::gpu_type! {
    /// The tile cull's settings (`CullSettings` in tile_cull.wgsl).
    #[derive(Debug)]
    pub struct CullSettingsUniform => "CullSettings" in "methods/wedges/tile_cull.wgsl" {
        /// Tiles per row, and the planes' slack in world units (f32 bits).
        pub tiles: [u32; 4],
    }
}

crate::gpu_type! {
    /// The visibility pass's settings (`WedgeSettings` in visibility.wgsl).
    #[derive(Debug)]
    pub struct WedgeSettingsUniform => "WedgeSettings" in "methods/wedges/visibility.wgsl" {
        pub tiles: [u32; 4],
        /// subsample's shift bound, and the coarse grid's width.
        pub subsample: [f32; 4],
    }
}

/// Names of the visibility pass's counters, in order: pixels inside some
/// wedge, pixels the map bound lowered and raised, pixels `subsample`
/// interpolated, and binned (tile, wedge) entries the tile cull kept (of
/// `binned_wedge_tiles`).
pub const COUNTER_NAMES: &[&str] = &["pixels_in_wedge", "map_bounded_pixels", "map_raised_pixels", "interpolated_pixels", "wedge_tiles_kept"];

/// Pass 2's output.
pub struct WedgeBuffers {
    pub wedges: PooledBuffer,
    pub offsets: PooledBuffer,
    pub indices: PooledBuffer,
    /// Each wedge's `support_planes` (`WedgeBoundsGpu`), for the tile cull.
    pub bounds: PooledBuffer,
    /// Entries of `indices`.
    pub binned: u32,
    pub tiles_x: u32,
    pub tiles_y: u32,
    /// The support planes' slack in world units: 1e-3 of the scene's
    /// diagonal plus its largest coordinate, far above their f32 rounding.
    pub slack: f32,
    pub count: u32,
    pub stats: WedgeStats,
    pub silhouette_cache_hits: usize,
}

pub struct PenumbraWedges {
    cull: ScreenPass,
    visibility: ScreenPass,
    object_pass: VolumePass,
    solid_pass: SolidLayersPass,
}

impl MethodParams for WedgesParams {
    fn specs() -> Vec<ParamSpec> {
        ShadowMapSettings::specs_and([
            ParamSpec::int(
                "acute_wedges",
                0,
                0,
                64,
                "extra wedges at acute silhouette vertices (4.1, Figure 7), per 120 degrees of turn (0: one wedge per edge, the base algorithm)",
            ),
            ParamSpec::choice(
                "hard_term",
                "at_point",
                &HardTerm::NAMES,
                "where the hard shadow map is read inside wedges: at the pixel (each wedge adds s - h), or on the lit side of every holding wedge's quad (each adds s - 1: overlapping casters summed as the paper's count)",
            ),
            ParamSpec::choice(
                "intensity",
                "coverage",
                &Intensity::NAMES,
                "light intensity inside a wedge: the 2002 paper's interpolation between its planes (4.2, Eq. 1-3), or the fraction of the light's disk the edge projected from the pixel covers, computed exactly (Assarsson & Akenine-Möller 2003; falloff and acute_wedges then do nothing)",
            ),
            ParamSpec::choice(
                "overlap",
                "gate",
                &["sum", "gate"],
                "silhouettes that overlap as the light sees them (folds, several casters): every wedge's term summed, as both papers, or a wedge's term dropped where the map, read at the pixel moved just outside the hard shadow its edge casts, is in shadow too (another surface right behind the edge covers what it would uncover or hide)",
            ),
            ParamSpec::choice(
                "occluders",
                "sum",
                &["sum", "independent"],
                "separate objects (connected surfaces, however many meshes they come in) whose penumbrae overlap: every wedge's term summed with the hard shadow, as both papers, or each object's terms summed alone, its visible fraction taken, and the objects' fractions multiplied as independent occluders (worse at the median of the generated scenes, better in their worst case: docs/methods/wedges.md)",
            ),
            ParamSpec::bool(
                "tile_cull",
                true,
                "skip, per 8 x 8 pixels, the binned wedges whose support holds none of their points (beyond the papers: the same image to within float rounding, the visibility pass in 0.42-0.76 of its time on generated scenes at 256x256: docs/methods/wedges.md); false: every binned wedge is evaluated at every pixel of its tile",
            ),
            ParamSpec::bool("falloff", false, "Parker et al.'s 3s^2 - 2s^3 attenuation of the interpolated intensity (4.2)"),
            ParamSpec::float(
                "subsample",
                SUBSAMPLE_DEFAULT,
                0.0,
                1.0,
                "beyond the papers, with intensity \"coverage\": the pixels with x and y multiples of 4 are computed first; then each other pixel of the 2-pixel grid, and then each remaining pixel, takes the mean of its 2 or 4 neighbours on the grid above where they lie on its surface, its map reads their hard shadow, their values agree, and no edge that can meet the light's disk near them moves, projected from the pixel, by more than this many light radii between them (the visibility is then smooth there), and is computed otherwise; 0: every pixel computed; with intensity \"interpolation\" every pixel is computed (docs/methods/wedges.md)",
            ),
        ]
        .into_iter()
        .chain(MapBound::specs(
            MAP_SAMPLES_DEFAULT,
            "inside wedges, points of the light's disk whose rays from the pixel are followed through the shadow map (as pvm's): the visibility is at most the fraction seen plus 1.2 n^-0.7 (0.106 at 32, 0.17 at 16: the points' own error under a straight edge) and the texel band at the holding edge nearest the light; 0: the wedges' sum alone (both papers)",
        ))
        .chain([
            OpenEdges::spec(),
            ParamSpec::choice(
                "repairs",
                "all",
                &REPAIR_LEVELS,
                "departures from the paper for real meshes, cumulative: none, hidden (no wedge for silhouette edges hidden from the light centre), cone+hidden (shared side lines kept in their vertex's light cone), all (+ the light below the receiver's horizon hidden); cone+horizon is all but hidden",
            ),
        ]))
    }

    fn parse(p: &ParamSet) -> Result<WedgesParams> {
        let level = p.choice("repairs");
        let repairs = match level {
            "all" => Repairs { cone: true, hidden: true, horizon: true, centre: false, distance: false },
            other => Repairs::parse(other),
        };
        Ok(WedgesParams {
            shadow: ShadowMapSettings::from_params(p),
            acute_wedges: p.int("acute_wedges") as u32,
            falloff: p.bool("falloff"),
            open_edges: OpenEdges::parse(p.choice("open_edges")),
            repairs,
            hard_term: if p.choice("hard_term") == "lit_side" { HardTerm::LitSide } else { HardTerm::AtPoint },
            intensity: if p.choice("intensity") == "coverage" { Intensity::Coverage } else { Intensity::Interpolation },
            overlap_gate: p.choice("overlap") == "gate",
            independent_occluders: p.choice("occluders") == "independent",
            tile_cull: p.bool("tile_cull"),
            map: MapBound::parse(p),
            subsample: p.float("subsample"),
        })
    }
}

impl Method for PenumbraWedges {
    const NAME: &'static str = "wedges";
    const PAPER: &'static str = "penumbra wedges (Akenine-Möller & Assarsson 2002, 4.1-4.2; per-pixel coverage of Assarsson & Akenine-Möller 2003)";
    type Params = WedgesParams;

    fn cached_passes() -> &'static [CachedPass] {
        &[CENTRE_MAP, PENUMBRA_WEDGES, OBJECT_MAP, SOLID_LAYERS]
    }

    fn new(device: &wgpu::Device, pool: &crate::gpu::pool::ResourcePool) -> Self {
        // Reads the map, the test block, the wedges, their tile bins and the
        // settings; writes visibility, the hard term, the intensity and the counter.
        // Then the tile cull's marks (tile_cull.wgsl), after the object map's.
        let mut bindings = object_map::with_bindings(&[
            layout::depth_array, layout::parameters, layout::storage_buffer, layout::storage_buffer, layout::storage_buffer, layout::parameters,
            layout::visibility_storage, layout::visibility_storage, layout::visibility_storage, layout::storage_buffer_rw,
        ]);
        bindings.push(layout::storage_buffer);
        // And subsample's coarse results and list of pixels to evaluate.
        bindings.push(layout::storage_buffer_rw);
        bindings.push(layout::storage_buffer_rw);
        // The solid layers (map_solids).
        bindings.push(layout::storage_buffer);
        let visibility = ScreenPass::new(device, pool, "wedges::visibility_pass", crate::shader!("visibility.wgsl"), &bindings, &["main", "coarse_main", "middle_main", "middle_fallback_main", "fallback_main"]);
        // Reads the bins, the support planes and the settings; writes the marks.
        let cull_bindings = [layout::storage_buffer, layout::storage_buffer, layout::storage_buffer, layout::parameters, layout::storage_buffer_rw, layout::storage_buffer_rw];
        let cull = ScreenPass::new(device, pool, "wedges::tile_cull", crate::shader!("tile_cull.wgsl"), &cull_bindings, &["main"]);
        Self { cull, visibility, object_pass: object_map::pass(device, pool), solid_pass: SolidLayersPass::new(device, pool) }
    }

    fn record(&self, frame: &mut Frame<'_>, params: &WedgesParams) -> Result<MethodOutput> {
        let (map, projection) = centre_map::centre_map(frame, &params.shadow)?;
        let light = frame.ctx.light;
        let mut key = PassKey::new(PENUMBRA_WEDGES.name);
        key.key(&frame.ctx.gbuffer_key)
            .f64s(&light.center.to_array())
            .f64s(&[light.radius])
            .u32(params.acute_wedges)
            .bytes(params.open_edges.name().as_bytes())
            .bytes(&[u8::from(params.repairs.cone), u8::from(params.repairs.hidden), u8::from(params.intensity == Intensity::Coverage)]);
        let mut fresh = false;
        let wedges = frame.cached(PENUMBRA_WEDGES.name, key.finish(), |frame| {
            fresh = true;
            Self::record_wedges(frame, params).map(Arc::new)
        })?;
        let objects = object_map::record_if(frame, params.repairs.horizon && light.radius > 0.0, &self.object_pass, &projection, params.shadow.map_size)?;
        let solids = solid_layers::record_if(frame, params.map.solids && params.map.samples > 0 && light.radius > 0.0, &self.solid_pass, &projection, params.shadow.map_size)?;
        let visibility = frame.ctx.screen_texture("wedges::visibility");
        let hard = frame.ctx.screen_texture("wedges::hard");
        let intensity = frame.ctx.screen_texture("wedges::intensity");
        // subsample: the records of the pixels with even x and y (two vec4
        // each) and the list of pixels to evaluate, checked against the
        // adapter's storage-buffer limit before any is made.
        let subsampled = params.intensity == Intensity::Coverage && params.subsample > 0.0;
        let (width, height) = (u64::from(frame.ctx.size.0), u64::from(frame.ctx.size.1));
        let coarse_len = if subsampled { 32 * width.div_ceil(2) * height.div_ceil(2) } else { 32 };
        let list_len = if subsampled { 16 + 4 * width * height } else { 32 };
        frame.ctx.check_buffer("wedges", "subsample's records of the even pixels", coarse_len, "the image size, or set subsample=0")?;
        frame.ctx.check_buffer("wedges", "subsample's list of pixels to evaluate", list_len, "the image size, or set subsample=0")?;
        let counter = frame.pass("visibility", |ctx, encoder, ts| {
            let counter = ctx.counters("wedges::pixels_in_wedge", 4, encoder);
            let kept = ctx.counters("wedges::tiles_kept", 1, encoder);
            let coverage = params.intensity == Intensity::Coverage;
            let flags = u32::from(params.falloff && !coverage)
                | (u32::from(params.repairs.horizon) << 1)
                | (u32::from(params.hard_term == HardTerm::LitSide) << 2)
                | (u32::from(coverage) << 3)
                | (u32::from(params.overlap_gate) << 4)
                | (u32::from(params.independent_occluders) << 5)
                | (u32::from(params.map.both) << 6)
                | (u32::from(params.map.solid) << 7);
            let mut shadow_test = params.shadow.uniform(&projection, light.center_f32, light.radius_f32, 0);
            [shadow_test.mode[2], shadow_test.mode[3]] = params.map.mode();
            let test = ctx.parameters("wedges::shadow_test", &shadow_test);
            // subsample: the records of the pixels with even x and y, two vec4 each.
            let subsample = if subsampled { params.subsample as f32 } else { 0.0 };
            let (coarse_w, coarse_h) = (ctx.size.0.div_ceil(2), ctx.size.1.div_ceil(2));
            let settings = ctx.parameters(
                "wedges::settings",
                &WedgeSettingsUniform { tiles: [TILE, wedges.tiles_x, flags, wedges.count], subsample: [subsample, coarse_w as f32, 0.0, 0.0] },
            );
            let coarse = ctx.buffer("wedges::coarse", coarse_len, wgpu::BufferUsages::STORAGE);
            let list = ctx.buffer("wedges::pixel_list", list_len, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST);
            // The dispatch's counts, copied out of the list (a buffer bound read-write may not also be a dispatch's argument).
            let args = ctx.buffer("wedges::fallback_groups", 16, wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST);

            // The tile cull: which binned wedges hold no pixel of their tile.
            let keep = ctx.buffer("wedges::tile_keep", 16 * u64::from(wedges.binned.max(1)), wgpu::BufferUsages::STORAGE);
            let cull = ctx.parameters("wedges::cull_settings", &CullSettingsUniform { tiles: [wedges.tiles_x, wedges.slack.to_bits(), u32::from(params.tile_cull), 0] });
            let cull_group = self.cull.bind_group(
                ctx,
                &[Binding::Buffer(&wedges.offsets), Binding::Buffer(&wedges.indices), Binding::Buffer(&wedges.bounds), Binding::Buffer(&cull), Binding::Buffer(&keep), Binding::Buffer(&kept)],
            );
            let ts = ts.map(|t| (t.compute_part(true, false), t.compute_part(false, true)));
            self.cull.dispatch_workgroups(encoder, "main", &cull_group, (2 * wedges.tiles_x, 2 * wedges.tiles_y, 1), ts.as_ref().and_then(|t| t.0.clone()));
            let resources = [
                Binding::Texture(&map),
                Binding::Buffer(&test),
                Binding::Buffer(&wedges.wedges),
                Binding::Buffer(&wedges.offsets),
                Binding::Buffer(&wedges.indices),
                Binding::Buffer(&settings),
                Binding::Texture(&visibility),
                Binding::Texture(&hard),
                Binding::Texture(&intensity),
                Binding::Buffer(&counter),
            ];
            let mut resources = objects.after(&resources);
            resources.push(Binding::Buffer(&keep));
            resources.push(Binding::Buffer(&coarse));
            resources.push(Binding::Buffer(&list));
            resources.push(Binding::Buffer(&solids.buffer));
            let group = self.visibility.bind_group(ctx, &resources);
            if subsample > 0.0 {
                // The cascade (visibility.wgsl): the top grid (x, y multiples of 4) evaluated, the middle's
                // other pixels interpolated or listed and evaluated, then the image's.
                self.visibility.dispatch_workgroups(encoder, "coarse_main", &group, (ctx.size.0.div_ceil(32), ctx.size.1.div_ceil(32), 1), None);
                encoder.clear_buffer(&list, 0, Some(16));
                self.visibility.dispatch_workgroups(encoder, "middle_main", &group, (coarse_w.div_ceil(8), coarse_h.div_ceil(8), 1), None);
                encoder.copy_buffer_to_buffer(&list, 0, &args, 0, 16);
                self.visibility.dispatch_indirect(encoder, "middle_fallback_main", &group, &args, 0, None);
                encoder.clear_buffer(&list, 0, Some(16));
                self.visibility.dispatch(ctx, encoder, "main", &group, None);
                encoder.copy_buffer_to_buffer(&list, 0, &args, 0, 16);
                self.visibility.dispatch_indirect(encoder, "fallback_main", &group, &args, 0, ts.and_then(|t| t.1));
            } else {
                self.visibility.dispatch(ctx, encoder, "main", &group, ts.and_then(|t| t.1));
            }
            (counter, kept)
        })?;
        let s = &wedges.stats;
        frame.silhouette_stats(&s.silhouette, wedges.silhouette_cache_hits, fresh);
        frame.stat("wedges", s.wedges as i64);
        frame.stat("extra_wedges", s.extra_wedges as i64);
        frame.stat("culled_wedges", s.culled_wedges as i64);
        frame.stat("silhouette_junction_vertices", s.junction_vertices as i64);
        frame.stat("side_line_fallbacks", s.side_fallbacks as i64);
        frame.stat("binned_wedge_tiles", s.binned as i64);
        frame.counters(&counter.0, &COUNTER_NAMES[..4]);
        frame.counters(&counter.1, &COUNTER_NAMES[4..]);
        frame.intermediate(Intermediate::color("wedges_hard", &hard, 1))?;
        frame.intermediate(Intermediate::color("wedges_intensity", &intensity, 1))?;
        Ok(MethodOutput { visibility })
    }
}

impl PenumbraWedges {
    /// Pass 2: the wedges of every silhouette edge (4.1) and their screen bins.
    fn record_wedges(frame: &mut Frame<'_>, params: &WedgesParams) -> Result<WedgeBuffers> {
        frame.pass("penumbra_wedges", |ctx, _encoder, _ts| -> Result<WedgeBuffers> {
            let (l, r) = (ctx.light.center, ctx.light.radius);
            let mut built = Wedges::default();
            let mut cache_hits = 0;
            // A point light has no penumbra: no wedges, the hard shadow alone.
            if r > 0.0 {
                let silhouette = ctx.silhouettes.seen_from_light(ctx.prepared, l, params.open_edges, params.repairs.hidden)?;
                cache_hits = silhouette.cache_hits;
                // Coverage measures a corner exactly: extra wedges there would add nothing.
                let acute = if params.intensity == Intensity::Coverage { 0 } else { params.acute_wedges };
                built = penumbra_wedges(&silhouette.edges, l, r, acute, params.repairs.cone);
                built.stats.silhouette.add_scene(&silhouette);
            }
            let camera = ctx.camera;
            let (projection, _, _) = camera.projection(ctx.prepared.bounds_min, ctx.prepared.bounds_max);
            let view_proj = DMat4::from_cols_array(&(projection * camera.view()).to_cols_array().map(f64::from));
            let coverage = (params.intensity == Intensity::Coverage).then_some((l, r));
            let bins = bin_wedges(&built.wedges, view_proj, ctx.size, ctx.prepared.bounds_min.as_dvec3(), ctx.prepared.bounds_max.as_dvec3(), coverage);
            built.stats.culled_wedges = bins.culled;
            built.stats.binned = bins.indices.len();
            // A storage binding may not be empty: one zeroed entry stands for none.
            let upload = |label: &str, bytes: &[u8]| {
                let buffer = ctx.buffer(label, bytes.len().max(16) as u64, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
                ctx.queue.write_buffer(&buffer, 0, bytes);
                buffer
            };
            let wedge_list = if built.wedges.is_empty() { vec![WedgeGpu::zeroed()] } else { built.wedges.clone() };
            let bounds = wedge_bounds(&wedge_list, coverage);
            let (lo, hi) = (ctx.prepared.bounds_min, ctx.prepared.bounds_max);
            let slack = 1e-3 * ((hi - lo).length() + lo.abs().max(hi.abs()).max_element());
            let indices = if bins.indices.is_empty() { vec![0u32; 4] } else { bins.indices.clone() };
            Ok(WedgeBuffers {
                wedges: upload("wedges::wedges", bytemuck::cast_slice(&wedge_list)),
                offsets: upload("wedges::tile_offsets", bytemuck::cast_slice(&bins.offsets)),
                indices: upload("wedges::tile_wedges", bytemuck::cast_slice(&indices)),
                bounds: upload("wedges::bounds", bytemuck::cast_slice(&bounds)),
                binned: bins.indices.len() as u32,
                tiles_x: bins.tiles_x,
                tiles_y: bins.tiles_y,
                slack,
                count: built.wedges.len() as u32,
                stats: built.stats,
                silhouette_cache_hits: cache_hits,
            })
        })?
    }
}
