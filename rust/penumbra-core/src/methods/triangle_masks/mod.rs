//! Method `triangle_masks`: exact visibility at a fixed set of light samples
//! from per-triangle sample masks (Sintorn, Eisemann & Assarsson, "Sample
//! Based Visibility for Soft Shadows using Alias-free Shadow Maps", EGSR
//! 2008), with no shadow map and no ray query: it runs on every adapter.
//!
//! Per pixel, a bitmask over the light samples (section 3): every triangle
//! that can hide part of the light from the pixel's point ORs in the samples
//! it hides, those whose segment from the point crosses it, and the
//! visibility is the share of samples left. The samples are `reference`'s
//! and `raytraced`'s ([`scene_sphere_samples`]: the same `n_samples`, `seed`,
//! strata and cap), weighted per receiver as they weight them (solid-angle
//! weights: the share is the weighted sum of the samples left over that of
//! all, `1 - popcount / n` only for equal weights); receivers follow
//! `raytraced`'s rules (origins offset along the normal by `ray_offset` times
//! the scene's size, hits closer than the offset ignored, samples below the
//! horizon hidden). The three then agree up to floating point.
//!
//! Departures from the paper, each as the issue allows:
//! - **The hidden samples of a triangle come from an exact test per
//!   sample** (the sample inside the three planes through the point and the
//!   triangle's edges, and beyond the triangle's plane) rather than from the
//!   paper's lookup textures of the edges' half-plane masks: the paper's
//!   light is planar, where an edge's half-plane is two numbers; on the
//!   sphere a sample's projection from the point moves with the point. A
//!   pair first tests the light's sphere against the four planes: wholly
//!   outside one (no sample tested) or wholly inside all (every bit set).
//! - **How triangles reach a pixel** (`traversal`): the paper rasterises
//!   each triangle's shadow volume from the light's bounding box into the
//!   receivers' alias-free shadow map, so a triangle reaches every pixel its
//!   volume covers, and a fine mesh gives each pixel thousands. The default,
//!   `"bvh"`, turns the order round: per pixel, a walk of a bounding volume
//!   hierarchy over the triangles (`Occluders`: binned surface-area splits)
//!   with the samples of one word still open whose segments from the point
//!   can meet a node's box, as a ray tracer walks 32 rays at once, so the
//!   cost follows the segments (tens of triangles per pixel) and not the
//!   triangles. `"tiles"` keeps the paper's per-triangle order: triangles
//!   binned to 16 x 16-pixel screen tiles on the GPU by a conservative test
//!   against the hull of the tile's receiver box and the light's sphere
//!   (masks.wgsl, `can_shadow`), through groups of 8 x 8 tiles: counted,
//!   offset by a prefix sum, then listed; a tile whose list would pass the
//!   adapter's storage-buffer limit takes every triangle
//!   (`tiles_overflowed`), never fewer. `"all"` is every triangle at every
//!   pixel. The three give the same image bit for bit.
//! - With tiles, the `masks` pass culls its tile's list again per 8 x 8-pixel workgroup
//!   against the receiver boxes of its 4 x 4-pixel quarters, and each pair
//!   first tests the triangle's bounding ball against the pixel's cone
//!   around the light; the samples are ordered into words of nearby samples
//!   ([`sample_words`]) so that whole words are kept or set at once.
//! - Pixels stop at a full mask (early out), workgroups when all of their
//!   pixels have; tiles no triangle can shadow test none.

use glam::{DVec3, Vec3};

use crate::error::Result;
use crate::frame::Frame;
use crate::gpu::layout;
use crate::gpu::pool::{Binding, ResourcePool};
use crate::light_sampling::{scene_sphere_samples, LightSample, SampleUniform, DEFAULT_RAY_OFFSET};
use crate::method::{Method, MethodOutput};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::passes::screen::ScreenPass;

/// Pixels per tile side and tiles per group side (masks.wgsl's TILE, GROUP).
pub const TILE: u32 = 16;
pub const GROUP: u32 = 8;
/// Invocations across a row of the per-triangle dispatch (256 workgroups of 8).
const TRIANGLE_ROW: u32 = 2048;

#[derive(Debug, Clone, PartialEq)]
pub struct TriangleMaskParams {
    pub n_samples: u32,
    pub seed: u64,
    /// Relative to the scene's size, as `raytraced`'s.
    pub ray_offset: f64,
    /// How triangles reach a pixel.
    pub traversal: Traversal,
}

/// How triangles reach a pixel's mask; the image is the same bit for bit
/// (a mask is an OR, and each way leaves out only triangles that set no bit).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Traversal {
    /// Per pixel and word of 32 samples, a walk of a bounding volume
    /// hierarchy over the triangles with the word's samples still open.
    Bvh,
    /// The triangles binned to screen tiles (the paper's per-triangle order).
    Tiles,
    /// Every triangle at every pixel: the unculled cost.
    All,
}

crate::gpu_type! {
    pub struct BvhNodeUniform => "BvhNode" in "methods/triangle_masks/masks.wgsl" {
        pub(crate) lo: [f32; 3],
        pub(crate) start: u32,
        pub(crate) hi: [f32; 3],
        pub(crate) count: u32,
    }
}

/// masks.wgsl's STACK: the deepest hierarchy its walk holds.
const STACK: usize = 48;

crate::gpu_type! {
    pub struct MaskSettingsUniform => "MaskSettings" in "methods/triangle_masks/masks.wgsl" {
        pub(crate) light: [f32; 4],
        pub(crate) offset: [f32; 4],
        pub(crate) counts: [u32; 4],
        pub(crate) tiles: [u32; 4],
        pub(crate) dispatch: [u32; 4],
    }
}

/// Counters of masks.wgsl: [0] tile-list entries (triangles binned, summed
/// over tiles), [1] tiles overflowed, [2..4] triangle-pixel pairs tested
/// (64 bits), [4..6] pairs tested sample by sample (64 bits), [6] pixels
/// whose masks filled before their lists ended, [7] tiles with receivers
/// and no triangle that can shadow them, [8..10] pairs whose triangle's
/// bounding ball meets the pixel's cone around the light (64 bits),
/// [10..12] nodes of the hierarchy entered (64 bits).
const COUNTERS: usize = 12;

/// The samples in the order of their mask bits, then one ball per word of
/// 32 (`LightSample` position: centre xyz, radius w) around its samples. The
/// order (bits are the method's own; the set is reference's) puts nearby
/// samples in one word, by splitting the set along its longest extent into
/// halves of whole words, recursively: a triangle edge then cuts few words'
/// balls, and the others are kept or set whole.
pub fn sample_words(samples: &[LightSample]) -> Vec<SampleUniform> {
    fn split(order: &mut [usize], samples: &[LightSample]) {
        if order.len() <= 32 {
            return;
        }
        let (lo, hi) = order.iter().fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), &i| {
            (lo.min(samples[i].position), hi.max(samples[i].position))
        });
        let extent = hi - lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z { 0 } else if extent.y >= extent.z { 1 } else { 2 };
        order.sort_by(|&i, &j| samples[i].position[axis].total_cmp(&samples[j].position[axis]));
        // The first half holds whole words.
        let middle = 32 * order.len().div_ceil(64);
        let (left, right) = order.split_at_mut(middle);
        split(left, samples);
        split(right, samples);
    }
    let mut order: Vec<usize> = (0..samples.len()).collect();
    split(&mut order, samples);
    let mut out: Vec<SampleUniform> = order.iter().map(|&i| SampleUniform::from(&samples[i])).collect();
    let balls = sample_words_in_order(&out);
    out.extend(balls);
    out
}

/// One ball per word of 32 samples in the order given, around its samples.
fn sample_words_in_order(samples: &[SampleUniform]) -> Vec<SampleUniform> {
    samples
        .chunks(32)
        .map(|word| {
            let points: Vec<DVec3> = word.iter().map(|s| DVec3::new(s.position[0] as f64, s.position[1] as f64, s.position[2] as f64)).collect();
            // Chunks are never empty: the division is by 1 to 32.
            let center = points.iter().copied().sum::<DVec3>() / points.len() as f64;
            let reach = points.iter().map(|p| (*p - center).length()).fold(0.0, f64::max);
            // Widened past the rounding of the centre to float32.
            let radius = reach * (1.0 + 1e-6) + 1e-6 * center.abs().max_element();
            let c = center.as_vec3();
            SampleUniform { position: [c.x, c.y, c.z, radius as f32], normal: [0.0; 4] }
        })
        .collect()
}

/// Per triangle (corners three by three): its bounding ball around the
/// centroid (xyz, radius w, widened past float32 rounding of the centre),
/// then its corners.
pub fn triangle_records(corners: &[Vec3]) -> Vec<[f32; 4]> {
    corners
        .chunks_exact(3)
        .flat_map(|t| {
            let p = [t[0].as_dvec3(), t[1].as_dvec3(), t[2].as_dvec3()];
            let m = (p[0] + p[1] + p[2]) / 3.0;
            let reach = p.iter().map(|q| (*q - m).length()).fold(0.0, f64::max);
            let radius = (reach * (1.0 + 1e-6) + 1e-6 * m.abs().max_element()) as f32;
            let c = m.as_vec3();
            [[c.x, c.y, c.z, radius], [t[0].x, t[0].y, t[0].z, 0.0], [t[1].x, t[1].y, t[1].z, 0.0], [t[2].x, t[2].y, t[2].z, 0.0]]
        })
        .collect()
}

pub struct TriangleMasks {
    pass: ScreenPass,
}

impl MethodParams for TriangleMaskParams {
    fn specs() -> Vec<ParamSpec> {
        vec![
            ParamSpec::int("n_samples", 256, 1, 4096, "light samples of reference's sphere sampling, one mask bit each (rounded up to full stratified grids)"),
            ParamSpec::seed(i64::MAX, "fixes the samples' jitter"),
            ParamSpec::float(
                "ray_offset",
                DEFAULT_RAY_OFFSET,
                0.0,
                0.01,
                "segment origins' offset along the normal, relative to the scene's size (raytraced's ray_offset)",
            ),
            ParamSpec::choice(
                "traversal",
                "bvh",
                &["bvh", "tiles", "all"],
                "how triangles reach a pixel: a bounding volume hierarchy walked with the samples still open (bvh), lists of 16x16-pixel tiles (tiles), every triangle (all); the same image",
            ),
        ]
    }

    fn parse(p: &ParamSet) -> Result<TriangleMaskParams> {
        Ok(TriangleMaskParams {
            n_samples: p.int("n_samples") as u32,
            seed: p.int("seed") as u64,
            ray_offset: p.float("ray_offset"),
            traversal: match p.choice("traversal") {
                "tiles" => Traversal::Tiles,
                "all" => Traversal::All,
                _ => Traversal::Bvh,
            },
        })
    }
}

impl Method for TriangleMasks {
    const NAME: &'static str = "triangle_masks";
    const PAPER: &'static str = "per-triangle light-sample masks (Sintorn, Eisemann & Assarsson 2008, section 3), \
        exact at reference's sphere samples, without ray queries";
    type Params = TriangleMaskParams;

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        // Reads the settings, the samples and the triangles; writes bounds,
        // bins, the tile list, the counters and visibility; reads the hierarchy.
        let bindings = [
            layout::parameters, layout::storage_buffer, layout::storage_buffer,
            layout::storage_buffer_rw, layout::storage_buffer_rw, layout::storage_buffer_rw, layout::storage_buffer_rw, layout::visibility_storage,
            layout::storage_buffer,
        ];
        let entry_points = ["tile_bounds", "group_bounds", "count_bins", "scan_bins", "fill_bins", "masks", "masks_bvh"];
        Self { pass: ScreenPass::new(device, pool, "triangle_masks::pass", crate::shader!("masks.wgsl"), &bindings, &entry_points) }
    }

    /// Pass `masks_bvh` (traversal "bvh"); passes `tile_bounds`,
    /// `count_bins` (count and prefix sum), `fill_bins` and `masks`
    /// ("tiles"); `masks` alone ("all").
    fn record(&self, frame: &mut Frame<'_>, params: &TriangleMaskParams) -> Result<MethodOutput> {
        let ctx = &frame.ctx;
        let scene = ctx.prepared;
        let (center, radius) = (ctx.light.center, ctx.light.radius);
        let samples = scene_sphere_samples(center, radius, scene, ctx.camera, params.n_samples, params.seed);
        let uploaded = sample_words(&samples);
        // In the hierarchy's order for "bvh" (its leaves' triangles contiguous).
        let hierarchy = (params.traversal == Traversal::Bvh).then(|| ctx.corner_hierarchy());
        let corners = match &hierarchy {
            Some(h) => {
                let ordered: Vec<Vec3> = h.triangles().iter().flat_map(|t| t.map(|p| p.as_vec3())).collect();
                triangle_records(&ordered)
            }
            None => triangle_records(ctx.corner_positions()),
        };
        let triangles = corners.len() / 4;
        let triangle_bytes = std::mem::size_of_val(corners.as_slice()) as u64;
        ctx.check_buffer(Self::NAME, &format!("the scene's {triangles} triangles"), triangle_bytes, "the triangle count (decimate the meshes)")?;
        let (w, h) = ctx.size;
        let tiles = (w.div_ceil(TILE), h.div_ceil(TILE));
        let groups = (tiles.0.div_ceil(GROUP), tiles.1.div_ceil(GROUP));
        let tile_count = tiles.0 as u64 * tiles.1 as u64;
        ctx.check_buffer(Self::NAME, &format!("the bins of {tile_count} tiles"), 12 * tile_count, "the image size")?;
        // Entries the tile lists may hold (the largest list buffer this
        // adapter binds); beyond it a tile takes every triangle.
        let capacity = (ctx.max_storage_buffer() / 4).min(u32::MAX as u64) as u32;
        // raytraced's offset: the G-buffer's float32 positions are within
        // rounding of the surface at the scale of the scene's coordinates.
        let extent = (scene.bounds_max - scene.bounds_min).max_element() as f64;
        let coordinate = scene.bounds_min.abs().max(scene.bounds_max.abs()).max_element() as f64;
        let size = coordinate.max(extent);
        let offset = params.ray_offset * size;
        // The binning's margin: the origins lie within the offset of the
        // tile's points, and 1e-5 of the scene's size is far beyond float32
        // rounding of the boxes and planes (a few 1e-7).
        let margin = 2.0 * offset + 1e-5 * size;
        let row = if triangles as u32 > TRIANGLE_ROW { TRIANGLE_ROW } else { (triangles as u32).max(1) };
        let c = ctx.light.center_f32;
        let settings = ctx.parameters(
            "triangle_masks::settings",
            &MaskSettingsUniform {
                light: [c[0], c[1], c[2], ctx.light.radius_f32],
                offset: [offset as f32, margin as f32, 0.0, 0.0],
                counts: [samples.len() as u32, triangles as u32, capacity, u32::from(params.traversal == Traversal::Tiles)],
                tiles: [tiles.0, tiles.1, groups.0, groups.1],
                dispatch: [row, 0, 0, 0],
            },
        );
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let sample_buffer = ctx.buffer("triangle_masks::samples", std::mem::size_of_val(uploaded.as_slice()) as u64, storage);
        ctx.queue.write_buffer(&sample_buffer, 0, bytemuck::cast_slice(&uploaded));
        // A storage binding may not be empty: one zeroed triangle stands for none.
        let triangle_buffer = ctx.buffer("triangle_masks::triangles", triangle_bytes.max(64), storage);
        if !corners.is_empty() {
            ctx.queue.write_buffer(&triangle_buffer, 0, bytemuck::cast_slice(&corners));
        }
        let node_records: Vec<BvhNodeUniform> = hierarchy
            .as_ref()
            .map(|h| {
                h.nodes()
                    .map(|(lo, hi, start, count)| BvhNodeUniform { lo: lo.as_vec3().into(), start, hi: hi.as_vec3().into(), count })
                    .collect()
            })
            .unwrap_or_default();
        if let Some(h) = &hierarchy {
            // Occluders bounds the depth at 24 + log2(triangles / 4) + 2: past
            // the stack only beyond 2^24 triangles (800 MB of records).
            if h.depth() >= STACK {
                return Err(crate::error::Error::InvalidScene(format!(
                    "triangle_masks: the triangle hierarchy is {} levels deep, past the walk's {STACK}",
                    h.depth()
                )));
            }
        }
        let node_bytes = std::mem::size_of_val(node_records.as_slice()) as u64;
        ctx.check_buffer(Self::NAME, &format!("the hierarchy of the scene's {triangles} triangles"), node_bytes, "the triangle count (decimate the meshes)")?;
        let node_buffer = ctx.buffer("triangle_masks::nodes", node_bytes.max(32), storage);
        if !node_records.is_empty() {
            ctx.queue.write_buffer(&node_buffer, 0, bytemuck::cast_slice(&node_records));
        }
        let bounds = ctx.buffer("triangle_masks::bounds", 32 * (tile_count + groups.0 as u64 * groups.1 as u64), storage);
        let bins = ctx.buffer("triangle_masks::bins", 12 * tile_count, storage);
        let visibility = ctx.screen_texture("triangle_masks::visibility");
        let counters = frame.untimed(|ctx, encoder| {
            encoder.clear_buffer(&bins, 0, None);
            ctx.counters("triangle_masks::counters", COUNTERS, encoder)
        });
        let pass = &self.pass;
        let bind = |ctx: &crate::frame::FrameContext<'_>, list: &crate::gpu::pool::PooledBuffer| {
            pass.bind_group(
                ctx,
                &[
                    Binding::Buffer(&settings),
                    Binding::Buffer(&sample_buffer),
                    Binding::Buffer(&triangle_buffer),
                    Binding::Buffer(&bounds),
                    Binding::Buffer(&bins),
                    Binding::Buffer(list),
                    Binding::Buffer(&counters),
                    Binding::Texture(&visibility),
                    Binding::Buffer(&node_buffer),
                ],
            )
        };
        let triangle_grid = (row, (triangles as u32).div_ceil(row).max(1));
        let list = if params.traversal == Traversal::Tiles {
            let placeholder = frame.ctx.buffer("triangle_masks::no_list", 4, wgpu::BufferUsages::STORAGE);
            let counting = bind(&frame.ctx, &placeholder);
            frame.pass("tile_bounds", |ctx, encoder, ts| {
                pass.dispatch_size(encoder, "tile_bounds", &counting, (tiles.0 * 8, tiles.1 * 8), ts.and_then(|t| t.compute_part(true, false)));
                pass.dispatch_size(encoder, "group_bounds", &counting, groups, ts.and_then(|t| t.compute_part(false, true)));
                let _ = ctx;
            })?;
            frame.pass("count_bins", |_, encoder, ts| {
                pass.dispatch_size(encoder, "count_bins", &counting, triangle_grid, ts.and_then(|t| t.compute_part(true, false)));
                pass.dispatch_size(encoder, "scan_bins", &counting, (8, 8), ts.and_then(|t| t.compute_part(false, true)));
            })?;
            // The lists' total decides the list buffer's size.
            let head: Vec<u32> = bytemuck::pod_collect_to_vec(&frame.read_now(&counters, 4)?);
            let entries = head.first().copied().unwrap_or(0).min(capacity).max(1);
            let list = frame.ctx.buffer("triangle_masks::tile_list", 4 * entries as u64, wgpu::BufferUsages::STORAGE);
            let filling = bind(&frame.ctx, &list);
            frame.pass("fill_bins", |_, encoder, ts| {
                pass.dispatch_size(encoder, "fill_bins", &filling, triangle_grid, ts.map(|t| t.compute()));
            })?;
            list
        } else {
            frame.ctx.buffer("triangle_masks::no_list", 4, wgpu::BufferUsages::STORAGE)
        };
        let shading = bind(&frame.ctx, &list);
        let entry = if params.traversal == Traversal::Bvh { "masks_bvh" } else { "masks" };
        frame.pass("masks", |ctx, encoder, ts| pass.dispatch(ctx, encoder, entry, &shading, ts.map(|t| t.compute())))?;
        let counts: Vec<u32> = bytemuck::pod_collect_to_vec(&frame.read_now(&counters, 4 * COUNTERS as u32)?);
        let count = |i: usize| counts.get(i).copied().unwrap_or(0) as i64;
        let wide = |i: usize| count(i) | (count(i + 1) << 32);
        frame.stat("light_samples", samples.len() as i64);
        frame.stat("triangles", triangles as i64);
        frame.stat("tiles", tile_count as i64);
        frame.stat(
            "triangles_binned",
            match params.traversal {
                Traversal::Tiles => count(0),
                Traversal::All => triangles as i64 * tile_count as i64,
                Traversal::Bvh => 0,
            },
        );
        frame.stat("nodes_entered", wide(10));
        frame.stat("tiles_overflowed", count(1));
        frame.stat("tiles_unshadowed", count(7));
        frame.stat("triangle_pixel_pairs", wide(2));
        frame.stat("pairs_tested_per_sample", wide(4));
        frame.stat("pairs_past_cone", wide(8));
        frame.stat("pixels_ended_early", count(6));
        Ok(MethodOutput { visibility })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light_sampling::sphere_samples;

    #[test]
    fn sample_words_reorder_the_samples_and_their_balls_hold_them() {
        for n in [1, 16, 261, 1032, 4129] {
            let samples = sphere_samples(DVec3::new(1.0, 5.0, 0.0), 0.5, DVec3::NEG_Y, -0.3, n, 7);
            let words = samples.len().div_ceil(32);
            let out = sample_words(&samples);
            assert_eq!(out.len(), samples.len() + words, "{n}");
            // The same samples (positions and weights), in another order.
            let key = |s: &SampleUniform| s.position.map(f32::to_bits);
            let mut given: Vec<_> = samples.iter().map(SampleUniform::from).map(|s| key(&s)).collect();
            let mut got: Vec<_> = out[..samples.len()].iter().map(key).collect();
            given.sort_unstable();
            got.sort_unstable();
            assert_eq!(given, got, "{n}");
            for (w, ball) in out[samples.len()..].iter().enumerate() {
                let c = Vec3::from_slice(&ball.position[..3]);
                for s in out[32 * w..(32 * w + 32).min(samples.len())].iter() {
                    assert!((Vec3::from_slice(&s.position[..3]) - c).length() <= ball.position[3], "{n}: word {w}");
                }
            }
            if n >= 261 {
                // Coherent: the words' balls are smaller than those of the
                // samples' own order (rows of the strata, across the light).
                let mean = |balls: &[SampleUniform]| balls.iter().map(|b| b.position[3]).sum::<f32>() / words as f32;
                let unordered: Vec<SampleUniform> = samples.iter().map(SampleUniform::from).collect();
                let rows = sample_words_in_order(&unordered);
                let (ordered, plain) = (mean(&out[samples.len()..]), mean(&rows));
                assert!(ordered < 0.8 * plain, "{n}: {ordered} vs {plain}");
            }
        }
    }

    #[test]
    fn triangle_records_hold_the_corners_in_their_balls() {
        let corners = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 1e6)];
        let r = triangle_records(&corners);
        assert_eq!(r.len(), 4);
        let c = Vec3::from_slice(&r[0][..3]);
        for (k, p) in corners.iter().enumerate() {
            assert_eq!(Vec3::from_slice(&r[k + 1][..3]), *p);
            assert!((*p - c).length() <= r[0][3]);
        }
    }
}
