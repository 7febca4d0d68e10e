//! Method `adaptive`: adaptive light-source sampling (Schwarzler, Luksch,
//! Scherzer and Wimmer 2013, sections 3.2-3.4): hard shadows from points of
//! the light, averaged (Eq. 2), the points chosen by a quadtree over the
//! light's domain that is refined only where the camera would see banding.
//!
//! - Domain: the paper's lights are squares; here the unit square is mapped
//!   by Shirley and Chiu's concentric map onto the disk through the sphere's
//!   centre facing the scene (`reference`'s `sampling = "disk"`, Herf 4.2).
//!   Its four corners are four distinct points of the disk's rim whatever
//!   the scene. (The visible cap of the sphere was the other candidate, but
//!   when the scene surrounds the light the cap is the whole sphere and the
//!   square's whole boundary, corners included, maps to one point.)
//! - 3.3.1, 3.3.4: maps at the square's corners, then each cell that fails
//!   the test is split in four and maps are rendered at the new corners
//!   (points shared between cells are rendered once), down to `max_depth`.
//! - 3.3.2, 3.3.3: for each cell, its four maps' hard shadows reprojected
//!   into the comparison target (the camera's image scaled by
//!   `comparison_scale`) and summed per texel (0-4); penumbra texels (1-3)
//!   whose 1-ring holds no other value fail; an atomic counter plays the
//!   occlusion query, read back once per level; a cell splits when more than
//!   `tolerance` texels fail.
//! - 3.4.1: weights by Eq. 3, `1 / (2^d + 1)^2` with d the deepest leaf
//!   cell the point is a corner of, normalised to sum to 1.
//! - 3.4.2: the deferred accumulation-buffer variant (one accumulation
//!   dispatch per map), not the single pass over a texture array.
//! - 3.4.3: `pcf_2x2`, the hardware's 2x2 bilinear comparison filter.
//!
//! A point light (radius 0) is `hard`'s centre map, alone.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use crate::error::{Error, Result};
use crate::frame::{Frame, FrameContext, Intermediate};
use crate::gpu::formats;
use crate::gpu::layout;
use crate::gpu::PassTimestamps;
use crate::gpu::pool::{Binding, PooledTexture, ResourcePool};
use crate::light_frustum::{light_sample_error, LightProjection, ProjectionMode};
use crate::light_sampling::{camera_basis, disk_point, scene_axis};
use crate::method::{Method, MethodOutput};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::passes::centre_map;
use crate::passes::samplers::{ComparisonSamplers, Filter};
use crate::passes::screen::ScreenPass;
use crate::passes::shadow_map::ShadowMapPass;
use crate::passes::shadow_test::{ShadowMapSettings, ShadowTestUniform};

/// Deepest quadtree level `max_depth` may ask for.
pub const MAX_DEPTH: u32 = 6;

/// The most memory the maps of a full grid may take (they are all kept until
/// the evaluation): `max_depth` and `map_size` beyond it are refused.
const MAP_BUDGET_BYTES: u64 = 2 << 30;

/// Bytes of one face of a light point's map (32-bit depth).
fn face_bytes(map_size: u32) -> u64 {
    (map_size as u64).pow(2) * 4
}

/// The refusal of a render whose maps would take `bytes`: `maps` maps of
/// `faces` (in words), `when` ("may keep": the full grid), `cube_faces`
/// whether cube maps' six faces are among those counted.
fn over_budget(params: &AdaptiveParams, maps: u64, faces: &str, bytes: u64, when: &str, cube_faces: bool) -> Error {
    let mut fixes = Vec::new();
    if params.max_depth > 0 {
        let lower = params.max_depth - 1;
        fixes.push(format!("lower max_depth (max_depth {lower} keeps at most {} maps)", ((1u64 << lower) + 1).pow(2)));
    }
    fixes.push("a smaller map_size".to_owned());
    if cube_faces {
        fixes.push("projection='frustum' (one face per map where a cube map has six)".to_owned());
    }
    Error::InvalidParameter(format!(
        "adaptive: max_depth {} with map_size {} and projection '{}' {when} {maps} maps of {faces} ({:.2} MiB a face), \
         {:.2} GiB, more than the {} GiB allowed; try {}",
        params.max_depth,
        params.shadow.map_size,
        params.shadow.projection.name(),
        face_bytes(params.shadow.map_size) as f64 / (1u64 << 20) as f64,
        bytes as f64 / (1u64 << 30) as f64,
        MAP_BUDGET_BYTES >> 30,
        fixes.join(", "),
    ))
}

const LEVEL_PASSES: [&str; MAX_DEPTH as usize + 1] = ["level0", "level1", "level2", "level3", "level4", "level5", "level6"];
const SUMS: [&str; MAX_DEPTH as usize] =
    ["adaptive_sums_level0", "adaptive_sums_level1", "adaptive_sums_level2", "adaptive_sums_level3", "adaptive_sums_level4", "adaptive_sums_level5"];
const MASKS: [&str; MAX_DEPTH as usize] = [
    "adaptive_failing_level0",
    "adaptive_failing_level1",
    "adaptive_failing_level2",
    "adaptive_failing_level3",
    "adaptive_failing_level4",
    "adaptive_failing_level5",
];

#[derive(Debug, Clone, PartialEq)]
pub struct AdaptiveParams {
    pub shadow: ShadowMapSettings,
    pub max_depth: u32,
    pub tolerance: u64,
    pub comparison_scale: f64,
    pub pcf_2x2: bool,
    pub weights: Weights,
}

/// A cell of the quadtree over the unit square, on the integer grid of the
/// deepest level: lower corner (x, y), side `2^(max_depth - level)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Cell {
    pub x: u32,
    pub y: u32,
    pub level: u32,
}

/// The quadtree of 3.3.4: its leaf cells and the light points at their
/// corners, each once, in the order they were made.
#[derive(Debug, Clone)]
pub struct Quadtree {
    max_depth: u32,
    points: Vec<(u32, u32)>,
    index: HashMap<(u32, u32), usize>,
    leaves: Vec<Cell>,
}

impl Quadtree {
    /// The root cell and its four corners.
    pub fn new(max_depth: u32) -> Self {
        let mut tree = Self { max_depth, points: Vec::new(), index: HashMap::new(), leaves: vec![Cell { x: 0, y: 0, level: 0 }] };
        for c in tree.corners(Cell { x: 0, y: 0, level: 0 }) {
            tree.add_point(c);
        }
        tree
    }

    pub fn root() -> Cell {
        Cell { x: 0, y: 0, level: 0 }
    }

    fn side(&self, cell: Cell) -> u32 {
        1 << (self.max_depth - cell.level)
    }

    /// Lower left, lower right, upper left, upper right.
    pub fn corners(&self, cell: Cell) -> [(u32, u32); 4] {
        let s = self.side(cell);
        [(cell.x, cell.y), (cell.x + s, cell.y), (cell.x, cell.y + s), (cell.x + s, cell.y + s)]
    }

    fn add_point(&mut self, p: (u32, u32)) {
        if !self.index.contains_key(&p) {
            self.index.insert(p, self.points.len());
            self.points.push(p);
        }
    }

    /// Splits leaf `cell` (above the deepest level) into its four children,
    /// adding the points at their corners that are new.
    pub fn split(&mut self, cell: Cell) -> [Cell; 4] {
        assert!(cell.level < self.max_depth, "a cell at the deepest level cannot split");
        self.leaves.retain(|c| *c != cell);
        let h = self.side(cell) / 2;
        let level = cell.level + 1;
        let children = [
            Cell { x: cell.x, y: cell.y, level },
            Cell { x: cell.x + h, y: cell.y, level },
            Cell { x: cell.x, y: cell.y + h, level },
            Cell { x: cell.x + h, y: cell.y + h, level },
        ];
        for child in children {
            for c in self.corners(child) {
                self.add_point(c);
            }
        }
        self.leaves.extend(children);
        children
    }

    pub fn points(&self) -> &[(u32, u32)] {
        &self.points
    }

    pub fn index_of(&self, p: (u32, u32)) -> usize {
        self.index[&p]
    }

    pub fn leaves(&self) -> &[Cell] {
        &self.leaves
    }

    /// Point `p` in the unit square.
    pub fn unit(&self, p: (u32, u32)) -> DVec2 {
        let n = (1u32 << self.max_depth) as f64;
        DVec2::new(p.0 as f64 / n, p.1 as f64 / n)
    }

    /// Eq. 3: `1 / (2^d + 1)^2` per point, d the deepest leaf it is a
    /// corner of (every point is a corner of a leaf: the children of a
    /// split keep their parent's corners), normalised to sum to 1 (3.4.1).
    pub fn weights(&self) -> Vec<f64> {
        let mut depth = vec![0u32; self.points.len()];
        for leaf in &self.leaves {
            for c in self.corners(*leaf) {
                let i = self.index[&c];
                depth[i] = depth[i].max(leaf.level);
            }
        }
        let raw: Vec<f64> = depth.iter().map(|&d| 1.0 / ((1u64 << d) as f64 + 1.0).powi(2)).collect();
        normalised(raw)
    }

    /// Beyond the paper: each leaf cell's area shared among its four
    /// corners (the trapezoid rule over the square, which the concentric
    /// map carries to the disk's area), normalised to sum to 1.
    pub fn area_weights(&self) -> Vec<f64> {
        let mut raw = vec![0.0; self.points.len()];
        for leaf in &self.leaves {
            let area = 0.25f64.powi(leaf.level as i32);
            for c in self.corners(*leaf) {
                raw[self.index[&c]] += area / 4.0;
            }
        }
        normalised(raw)
    }
}

/// `raw` over its sum: every list here holds at least the four root
/// corners, each with a positive weight, so the sum is positive.
fn normalised(raw: Vec<f64>) -> Vec<f64> {
    let total: f64 = raw.iter().sum();
    raw.into_iter().map(|w| w / total).collect()
}

/// How the maps are weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Weights {
    /// Eq. 3, normalised (3.4.1).
    Eq3,
    /// Each leaf cell's area shared among its corners.
    Area,
}

impl Weights {
    pub const NAMES: [&'static str; 2] = ["eq3", "area"];
}

crate::gpu_type! {
    pub struct CellCompareUniform => "CellCompare" in "methods/adaptive/compare.wgsl" {
        pub(crate) tests: [ShadowTestUniform; 4],
        pub(crate) cell: [u32; 4],
    }
}

/// One rendered light point.
struct LightMap {
    texture: PooledTexture,
    test: ShadowTestUniform,
    projection: LightProjection,
}

/// Hands out the begin and end timestamps of a named pass made of `total` wgpu passes.
struct Parts<'t> {
    ts: Option<PassTimestamps<'t>>,
    next: usize,
    total: usize,
}

impl<'t> Parts<'t> {
    fn next(&mut self) -> (bool, bool) {
        let k = self.next;
        self.next += 1;
        (k == 0, k + 1 == self.total)
    }

    fn compute(&mut self) -> Option<wgpu::ComputePassTimestampWrites<'t>> {
        let (first, last) = self.next();
        self.ts.and_then(|t| t.compute_part(first, last))
    }
}

pub struct AdaptiveShadows {
    compare: ScreenPass,
    evaluate: ScreenPass,
}

impl AdaptiveShadows {
    /// The fitted projection of each light point of `positions` (the maps
    /// `first + 1`.. of at most `total`, for the error's wording).
    fn fit_maps(ctx: &FrameContext<'_>, params: &AdaptiveParams, positions: &[DVec3], first: usize, total: usize) -> Result<Vec<LightProjection>> {
        let positions: Vec<glam::Vec3> = positions.iter().map(|p| p.as_vec3()).collect();
        ctx.fit_projections(&positions, 0.0, params.shadow.projection)
            .into_iter()
            .zip(&positions)
            .enumerate()
            .map(|(i, (fitted, &position))| fitted.map_err(|e| light_sample_error(e, "adaptive", first + i + 1, total, position)))
            .collect()
    }

    /// The accumulation of every map's test with its weight, and the resolve.
    fn evaluate(&self, ctx: &FrameContext<'_>, encoder: &mut wgpu::CommandEncoder, ts: Option<PassTimestamps<'_>>, maps: &[(&PooledTexture, ShadowTestUniform)], visibility: &PooledTexture) {
        let (w, h) = ctx.size;
        let accumulated =
            ctx.buffer("adaptive::accumulated", (w as u64 * h as u64 * 8).max(8), wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
        encoder.clear_buffer(&accumulated, 0, None);
        let size = std::mem::size_of::<ShadowTestUniform>();
        let align = ctx.device.limits().min_storage_buffer_offset_alignment as usize;
        let stride = size.div_ceil(align) * align;
        let mut bytes = vec![0u8; stride * maps.len()];
        for (i, (_, test)) in maps.iter().enumerate() {
            bytes[i * stride..][..size].copy_from_slice(bytemuck::bytes_of(test));
        }
        let tests = ctx.buffer("adaptive::map_tests", bytes.len() as u64, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
        ctx.queue.write_buffer(&tests, 0, &bytes);
        let mut parts = Parts { ts, next: 0, total: maps.len() + 1 };
        let mut last_group = None;
        for (i, (map, _)) in maps.iter().enumerate() {
            let samplers = ComparisonSamplers::shared(ctx.device, ctx.pool);
            let group = self.evaluate.bind_group(
                ctx,
                &[
                    Binding::Texture(map),
                    Binding::BufferRange(&tests, (i * stride) as u64, size as u64),
                    Binding::Buffer(&accumulated),
                    Binding::Texture(visibility),
                    samplers.binding(Filter::Bilinear),
                ],
            );
            let writes = parts.compute();
            self.evaluate.dispatch(ctx, encoder, "accumulate", &group, writes);
            last_group = Some(group);
        }
        if let Some(group) = last_group {
            let writes = parts.compute();
            self.evaluate.dispatch(ctx, encoder, "resolve", &group, writes);
        }
    }
}

impl MethodParams for AdaptiveParams {
    fn specs() -> Vec<ParamSpec> {
        let mut specs: Vec<ParamSpec> = ShadowMapSettings::specs()
            .into_iter()
            .map(|s| {
                if s.name == "map_size" {
                    ParamSpec::map_size(
                        "map_size",
                        512,
                        16,
                        16384,
                        "shadow-map resolution in texels per side, per light point (the paper's 512); 'auto' as for hard",
                    )
                } else {
                    s
                }
            })
            .collect();
        specs.extend([
            ParamSpec::int(
                "max_depth",
                4,
                0,
                MAX_DEPTH as i64,
                "deepest quadtree level over the light (3.3.4): at most (2^max_depth + 1)^2 maps, the paper's 4 gives 289",
            ),
            ParamSpec::int(
                "tolerance",
                0,
                0,
                i64::from(u32::MAX),
                "failing comparison texels a cell may hold and not split (3.3.3; the paper's occlusion-query threshold, 0)",
            ),
            ParamSpec::float_above(
                "comparison_scale",
                1.0,
                0.0,
                1.0,
                "comparison target's size as a fraction of the camera's image (3.3.2): smaller, fewer maps",
            ),
            ParamSpec::bool("pcf_2x2", false, "sample every map through the hardware's 2x2 bilinear comparison filter (3.4.3)"),
            ParamSpec::choice(
                "weights",
                "eq3",
                &Weights::NAMES,
                "map weights: the paper's Eq. 3 by subdivision depth, or (beyond the paper) each leaf cell's area shared among its corners",
            ),
        ]);
        specs
    }

    fn parse(p: &ParamSet) -> Result<AdaptiveParams> {
        let params = AdaptiveParams {
            shadow: ShadowMapSettings::from_params(p),
            max_depth: p.int("max_depth") as u32,
            tolerance: p.int("tolerance") as u64,
            comparison_scale: p.float("comparison_scale"),
            pcf_2x2: p.bool("pcf_2x2"),
            weights: if p.choice("weights") == "area" { Weights::Area } else { Weights::Eq3 },
        };
        // map_size 'auto' (0 here) is checked once the renderer resolves it
        // and parses the parameters again. The full grid, each map with its
        // faces: six for a cube, one for a frustum, and for 'auto' one here
        // (its least), the maps' real faces counted as they are fitted (`record`).
        let side = (1u64 << params.max_depth) + 1;
        let faces = if params.shadow.projection == ProjectionMode::Cube { 6 } else { 1 };
        let bytes = side * side * faces * face_bytes(params.shadow.map_size);
        if bytes > MAP_BUDGET_BYTES {
            let faces = if faces == 6 { "6 cube faces" } else { "one face" };
            return Err(over_budget(&params, side * side, faces, bytes, "may keep", faces == "6 cube faces"));
        }
        Ok(params)
    }
}

impl Method for AdaptiveShadows {
    const NAME: &'static str = "adaptive";
    const PAPER: &'static str = "adaptive light-source sampling (Schwarzler et al. 2013, 3.2-3.4)";
    type Params = AdaptiveParams;

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        // Reads four corners' maps and the cell's block; writes sums, failing
        // pixels, the level images and an image.
        let bindings = [
            layout::depth_array, layout::depth_array, layout::depth_array, layout::depth_array, layout::parameters,
            layout::storage_buffer_rw, layout::storage_buffer_rw, layout::storage_buffer_rw, layout::visibility_storage,
        ];
        let compare = ScreenPass::new(device, pool, "adaptive::compare", crate::shader!("compare.wgsl"), &bindings, &["compare", "ring", "image"]);
        let bindings = [layout::depth_array, layout::parameters, layout::storage_buffer_rw, layout::visibility_storage, layout::comparison_sampler];
        let evaluate = ScreenPass::new(device, pool, "adaptive::evaluate", crate::shader!("evaluate.wgsl"), &bindings, &["accumulate", "resolve"]);
        Self { compare, evaluate }
    }

    fn record(&self, frame: &mut Frame<'_>, params: &AdaptiveParams) -> Result<MethodOutput> {
        params.shadow.check_limits(frame.ctx.max_texture_side())?;
        let visibility = frame.ctx.screen_texture("adaptive::visibility");
        let flags = u32::from(params.pcf_2x2);
        if frame.ctx.light.radius == 0.0 {
            // A point light: one map, `hard`'s.
            let (map, projection) = centre_map::centre_map(frame, &params.shadow)?;
            let mut test = params.shadow.uniform(&projection, frame.ctx.light.center_f32, 0.0, flags);
            test.set_center_w(1.0);
            frame.pass("evaluate", |ctx, encoder, ts| self.evaluate(ctx, encoder, ts, &[(&map, test)], &visibility))?;
            frame.stat("light_samples", 1);
            frame.stat("maps_level0", 1);
            frame.stat("cells_subdivided", 0);
            frame.stat("max_depth_reached", 0);
            return Ok(MethodOutput { visibility });
        }
        let (center, radius) = (frame.ctx.light.center, frame.ctx.light.radius);
        let axis = scene_axis(center, frame.ctx.prepared, frame.ctx.camera);
        // The square's corners lie where the camera's frame puts them, so that
        // they turn with the scene (issue 31; any frame serves the paper).
        let basis = camera_basis(axis, frame.ctx.camera);
        let (w, h) = frame.ctx.size;
        let target = (((w as f64 * params.comparison_scale).round() as u32).max(1), ((h as f64 * params.comparison_scale).round() as u32).max(1));
        let texels = target.0 as usize * target.1 as usize;
        let max_points = ((1usize << params.max_depth) + 1).pow(2);
        let depth = params.shadow.bias.map_depth();
        let mut tree = Quadtree::new(params.max_depth);
        let mut maps: Vec<LightMap> = Vec::new();
        let mut to_test: Vec<Cell> = if params.max_depth > 0 { vec![Quadtree::root()] } else { Vec::new() };
        let mut subdivided = 0i64;
        for level in 0..=params.max_depth {
            let new_points: Vec<DVec3> = tree.points()[maps.len()..].iter().map(|&p| disk_point(center, radius, basis, tree.unit(p))).collect();
            if new_points.is_empty() && to_test.is_empty() {
                break;
            }
            let projections = Self::fit_maps(&frame.ctx, params, &new_points, maps.len(), max_points)?;
            // The maps held so far and this level's, with their real faces
            // (projection 'auto' makes a cube map where the frustum cannot
            // cover the geometry), before this level allocates any.
            let faces: u64 = maps.iter().map(|m| m.projection.layers() as u64).chain(projections.iter().map(|p| p.layers() as u64)).sum();
            let held = faces * face_bytes(params.shadow.map_size);
            if held > MAP_BUDGET_BYTES {
                let count = (maps.len() + projections.len()) as u64;
                let words = format!("{faces} faces in all");
                return Err(over_budget(params, count, &words, held, &format!("would hold at level {level}"), faces > count));
            }
            let want_images = frame.wants_intermediates() && !to_test.is_empty();
            // Corner maps of each tested cell, by index into maps (old and new).
            let cell_maps: Vec<[usize; 4]> = to_test.iter().map(|c| tree.corners(*c).map(|p| tree.index_of(p))).collect();
            let first_new = maps.len();
            let (new_maps, failing, images) = frame.pass(LEVEL_PASSES[level as usize], |ctx, encoder, ts| {
                let units = new_points.len() + 2 * to_test.len() + if want_images { 2 } else { 0 };
                let mut parts = Parts { ts, next: 0, total: units };
                let mut new_maps = Vec::with_capacity(new_points.len());
                for (position, projection) in new_points.iter().zip(projections) {
                    let texture = ShadowMapPass::create_map(ctx, params.shadow.map_size, projection.layers());
                    let (first, last) = parts.next();
                    ShadowMapPass::shared(ctx.device, ctx.pool).record(ctx, encoder, &texture, &projection, depth, ts, (first, last));
                    let p = position.as_vec3();
                    let test = params.shadow.uniform(&projection, p.to_array(), 0.0, flags);
                    new_maps.push(LightMap { texture, test, projection });
                }
                if to_test.is_empty() {
                    return (new_maps, None, Vec::new());
                }
                let map_of = |i: usize| -> &LightMap { if i < first_new { &maps[i] } else { &new_maps[i - first_new] } };
                let size = std::mem::size_of::<CellCompareUniform>();
                let align = ctx.device.limits().min_storage_buffer_offset_alignment as usize;
                let stride = size.div_ceil(align) * align;
                let mut bytes = vec![0u8; stride * (to_test.len() + 2)];
                for (k, corners) in cell_maps.iter().enumerate() {
                    let uniform = CellCompareUniform {
                        tests: corners.map(|i| map_of(i).test),
                        cell: [k as u32, target.0, target.1, u32::from(want_images)],
                    };
                    bytes[k * stride..][..size].copy_from_slice(bytemuck::bytes_of(&uniform));
                }
                // The two image dispatches: which image, the target's size.
                for which in 0..2u32 {
                    let uniform = CellCompareUniform { tests: [map_of(0).test; 4], cell: [which, target.0, target.1, 0] };
                    bytes[(to_test.len() + which as usize) * stride..][..size].copy_from_slice(bytemuck::bytes_of(&uniform));
                }
                let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
                let cells = ctx.buffer("adaptive::cells", bytes.len() as u64, usage);
                ctx.queue.write_buffer(&cells, 0, &bytes);
                let sums = ctx.buffer("adaptive::sums", 4 * texels as u64, usage);
                let failing = ctx.counters("adaptive::failing", to_test.len(), encoder);
                let level_images = ctx.counters("adaptive::level_images", if want_images { 2 * texels } else { 1 }, encoder);
                let image_usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
                let images: Vec<PooledTexture> = (0..if want_images { 2 } else { 1 })
                    .map(|_| ctx.texture("adaptive::comparison_image", target, formats::VISIBILITY, image_usage))
                    .collect();
                let group = |slot: usize, corners: [usize; 4], image: &PooledTexture| {
                    let [a, b, c, d] = corners.map(|i| &map_of(i).texture);
                    self.compare.bind_group(
                        ctx,
                        &[
                            Binding::Texture(a),
                            Binding::Texture(b),
                            Binding::Texture(c),
                            Binding::Texture(d),
                            Binding::BufferRange(&cells, (slot * stride) as u64, size as u64),
                            Binding::Buffer(&sums),
                            Binding::Buffer(&failing),
                            Binding::Buffer(&level_images),
                            Binding::Texture(image),
                        ],
                    )
                };
                for (k, corners) in cell_maps.iter().enumerate() {
                    let bind = group(k, *corners, &images[0]);
                    let writes = parts.compute();
                    self.compare.dispatch_size(encoder, "compare", &bind, target, writes);
                    let writes = parts.compute();
                    self.compare.dispatch_size(encoder, "ring", &bind, target, writes);
                }
                if want_images {
                    for (which, image) in images.iter().enumerate() {
                        let bind = group(to_test.len() + which, cell_maps[0], image);
                        let writes = parts.compute();
                        self.compare.dispatch_size(encoder, "image", &bind, target, writes);
                    }
                }
                (new_maps, Some(failing), if want_images { images } else { Vec::new() })
            })?;
            frame.stat(&format!("maps_level{level}"), new_maps.len() as i64);
            maps.extend(new_maps);
            if let [sums, mask] = images.as_slice() {
                frame.intermediate(Intermediate::color(SUMS[level as usize], &sums.resource.texture, 1))?;
                frame.intermediate(Intermediate::color(MASKS[level as usize], &mask.resource.texture, 1))?;
            }
            let Some(failing) = failing else {
                break;
            };
            let counts: Vec<u32> = bytemuck::pod_collect_to_vec(&frame.read_now(&failing, 4 * to_test.len() as u32)?);
            frame.stat(&format!("cells_tested_level{level}"), to_test.len() as i64);
            frame.stat(&format!("failing_texels_level{level}"), counts.iter().map(|&c| c as i64).sum());
            let mut next = Vec::new();
            for (cell, &count) in to_test.iter().zip(&counts) {
                if count as u64 > params.tolerance {
                    let children = tree.split(*cell);
                    subdivided += 1;
                    if cell.level + 1 < params.max_depth {
                        next.extend(children);
                    }
                }
            }
            to_test = next;
        }
        let weights = match params.weights {
            Weights::Eq3 => tree.weights(),
            Weights::Area => tree.area_weights(),
        };
        let evaluated: Vec<(&PooledTexture, ShadowTestUniform)> = maps
            .iter()
            .zip(&weights)
            .map(|(m, &w)| {
                let mut test = m.test;
                test.set_center_w(w as f32);
                (&m.texture, test)
            })
            .collect();
        frame.pass("evaluate", |ctx, encoder, ts| self.evaluate(ctx, encoder, ts, &evaluated, &visibility))?;
        frame.stat("light_samples", maps.len() as i64);
        frame.stat("shadow_maps_rendered", maps.len() as i64);
        frame.stat("shadow_map_faces", maps.iter().map(|m| m.projection.active_faces() as i64).sum());
        frame.stat("cube_maps", maps.iter().filter(|m| m.projection.is_cube()).count() as i64);
        frame.stat("map_size", params.shadow.map_size as i64);
        frame.stat("cells_subdivided", subdivided);
        frame.stat("max_depth_reached", i64::from(tree.leaves().iter().any(|c| c.level == params.max_depth)));
        frame.stat("comparison_width", target.0 as i64);
        frame.stat("comparison_height", target.1 as i64);
        Ok(MethodOutput { visibility })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quadtree with every cell split down to `depth`.
    fn full_tree(depth: u32) -> Quadtree {
        let mut tree = Quadtree::new(depth);
        let mut cells = vec![Quadtree::root()];
        for _ in 0..depth {
            cells = cells.into_iter().flat_map(|c| tree.split(c)).collect();
        }
        tree
    }

    /// The tree's points on the unit square, bit for bit.
    fn unit_bits(tree: &Quadtree) -> Vec<(u64, u64)> {
        tree.points().iter().map(|&p| tree.unit(p)).map(|u| (u.x.to_bits(), u.y.to_bits())).collect()
    }

    #[test]
    fn a_full_quadtree_is_the_regular_grid_with_equal_weights() {
        for depth in 0..=4u32 {
            let tree = full_tree(depth);
            let side = (1usize << depth) + 1;
            assert_eq!(tree.points().len(), side * side, "depth {depth}");
            let w = tree.weights();
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(w.iter().all(|x| (x - 1.0 / (side * side) as f64).abs() < 1e-15), "Eq. 3 at one depth: equal weights");
            let mut units = unit_bits(&tree);
            units.sort_unstable();
            units.dedup();
            assert_eq!(units.len(), side * side, "each point once");
        }
    }

    #[test]
    fn mixed_depths_weigh_by_equation_3_and_sum_to_one() {
        let mut tree = Quadtree::new(3);
        let children = tree.split(Quadtree::root());
        assert_eq!(tree.points().len(), 9);
        let grandchildren = tree.split(children[0]);
        assert_eq!(tree.points().len(), 9 + 5, "corners shared with the parent are not new");
        tree.split(grandchildren[3]);
        assert_eq!(tree.points().len(), 14 + 5);
        let w = tree.weights();
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // Raw weights: the far root corner only touches a level-1 leaf (1/9),
        // the centre of the deepest split only level-3 leaves (1/81).
        let far = tree.index_of((8, 8));
        let deep = tree.index_of((3, 3));
        assert!((w[far] / w[deep] - 81.0 / 9.0).abs() < 1e-9, "{} {}", w[far], w[deep]);
        assert_eq!(tree.leaves().len(), 4 + 3 + 3);
        let a = tree.area_weights();
        assert!((a.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // The far root corner: a quarter of its level-1 leaf (1/4 of the square).
        assert!((a[far] - 1.0 / 16.0).abs() < 1e-12, "{}", a[far]);
    }

    #[test]
    fn the_full_grid_is_references_regular_grid() {
        use crate::light_sampling::{jittered_grid, Strata};
        for depth in 0..=4u32 {
            let mut ours = unit_bits(&full_tree(depth));
            let side = (1u32 << depth) + 1;
            let mut grid: Vec<(u64, u64)> = jittered_grid(side * side, Strata::Centred).iter().map(|u| (u.x.to_bits(), u.y.to_bits())).collect();
            ours.sort_unstable();
            grid.sort_unstable();
            assert_eq!(ours, grid, "depth {depth}: bit for bit");
        }
    }

    #[test]
    #[should_panic(expected = "deepest level")]
    fn the_deepest_cells_do_not_split() {
        let mut tree = Quadtree::new(1);
        let c = tree.split(Quadtree::root());
        tree.split(c[0]);
    }
}
