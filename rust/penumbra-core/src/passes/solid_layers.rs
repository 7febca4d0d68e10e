//! The solid layers (beyond the papers, issue 28): for every texel of a
//! light map, the light depths of the first [`LAYERS`] surfaces of *solid*
//! casters that the centre's ray through it crosses. A solid is a closed
//! surface (after welding: `Topology`) that does not hold the light; along
//! a ray from outside every solid, the stretches between the 1st and 2nd
//! and between the 3rd and 4th of their surfaces lie inside one (each
//! surface crossed changes how many solids hold the point by one: an odd
//! count is inside at least one, overlaps and all).
//!
//! The map rays (passes/map_rays.wgsl) read it: the shadow map holds the
//! first surface alone, and a ray from a receiver that passes behind it
//! through a body the map cannot see (a boot under a floating cube, the
//! floor at its contact: generated seeds 1, 37, 38) was taken for seen. The
//! blocking points of those rays lie behind 3 or more surfaces along the
//! centre's ray (`benchmarks/occluder_layers.py`), so a second map layer
//! alone does not reach them; four do.
//!
//! One raster pass over the solids' triangles, whole (the caster cull of
//! `casters.rs` would open them): each fragment inserts its depth into its
//! texel's four slots with atomics (each slot keeps the least it has seen
//! and passes the other on), dropping a depth within [`SAME_SURFACE`] of a
//! kept one: a face drawn twice (overlapping pieces) counts once; a mesh
//! that is a whole copy of another is not drawn ([`solid_meshes`]). Depths are stored as the bits of their complement, so that
//! a cleared buffer (zeros) is empty and the slots keep the largest.
//!
//! Without solids, or when no method reads it, a 16-byte stand-in whose
//! header says so (side 0).

use std::sync::Arc;

use glam::DVec3;

use crate::error::Result;
use crate::frame::{Frame, FrameContext};
use crate::gpu::formats;
use crate::gpu::layout;
use crate::gpu::pool::{Binding, Layout, PooledBuffer, ResourcePool};
use crate::light_frustum::{LightFrustum, LightProjection};
use crate::pass_cache::{CachedPass, PassKey};
use crate::passes::shadow_map::{shadow_uniforms, uniform_buffer, ShadowMapPass};
use crate::topology::{Topology, NO_FACE};

/// The solid layers, as the pass cache keeps them.
pub const SOLID_LAYERS: CachedPass = CachedPass { name: "solid_layers", capacity: 2 };

/// Surfaces kept per texel: two stretches inside solids.
pub const LAYERS: u32 = 4;

/// Header words before the texels: side, layer count, solids drawn, unused.
pub const HEADER: u32 = 4;

/// Two depths closer than this (relative to the depth) are one surface (a
/// doubled one): 1e-5 of the depth is 10 times a float's rounding of a
/// rasterised depth and far below any wall of the shared meshes at their
/// light distances.
pub const SAME_SURFACE: f32 = 1e-5;

crate::gpu_type! {
    pub struct SolidFace => "SolidFace" in "passes/solid_layers.wgsl" {
        pub(crate) layer: u32,
        pub(crate) side: u32,
        pub(crate) unused: [u32; 2],
    }
}

pub struct SolidLayersPass {
    pipeline: wgpu::RenderPipeline,
    layout: Layout,
}

/// The layers over the light's map ([`HEADER`] words, then `LAYERS` words per
/// texel, texels by layer, row and column).
pub struct SolidLayers {
    pub buffer: PooledBuffer,
}

impl SolidLayersPass {
    pub fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let layers = wgpu::BindGroupLayoutEntry {
            binding: 1,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Storage { read_only: false }, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let layout = pool.layout(device, "solid_layers::layout", &[layout::uniform(0), layers, layout::uniform(2)]);
        let module = crate::shaders::module(device, "solid_layers::shader", crate::shader!("solid_layers.wgsl"));
        let positions = [Some(wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &[wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x3, offset: 0, shader_location: 0 }],
        })];
        // Both sides: every surface the centre's ray crosses. The depth
        // attachment is there for the pass to have one: never tested or written.
        let primitive = wgpu::PrimitiveState { cull_mode: None, ..Default::default() };
        let depth = wgpu::DepthStencilState {
            format: formats::DEPTH,
            depth_write_enabled: Some(false),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        };
        let pipeline = layout::render_pipeline(device, "solid_layers::pipeline", &layout, &module, ("vs_main", "fs_main"), &positions, primitive, Some(depth), &[]);
        Self { pipeline, layout }
    }
}

/// The layers when `needed`, else the stand-in (side 0, read as "no solid").
pub fn record_if(frame: &mut Frame<'_>, needed: bool, pass: &SolidLayersPass, projection: &LightProjection, map_size: u32) -> Result<Arc<SolidLayers>> {
    if needed {
        let topology = frame.ctx.silhouettes.scene_topology(frame.ctx.prepared);
        let mut solids = solid_meshes(&topology, frame.ctx.prepared.meshes.len(), frame.ctx.light.center);
        // A solid none of whose triangles casts (casters.rs: a floor slab
        // under everything) holds no ray either: a segment from a receiver
        // to the light that passes inside it crosses its surface, at a
        // triangle that then hides part of the light from that receiver.
        for (solid, range) in solids.iter_mut().zip(frame.ctx.light_geometry_meshes()) {
            *solid &= !range.is_empty();
        }
        frame.stat("solid_meshes", solids.iter().filter(|&&s| s).count() as i64);
        if solids.iter().any(|&s| s) {
            return record(frame, pass, projection, map_size, &solids);
        }
    }
    let buffer = frame.ctx.buffer("solid_layers::none", 16, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
    frame.ctx.queue.write_buffer(&buffer, 0, bytemuck::cast_slice(&[0u32; 4]));
    Ok(Arc::new(SolidLayers { buffer }))
}

/// The layers' side for a shadow map of `map_size`: a quarter of it, at
/// least 256 texels (or the map's own side, if smaller). The rays read the layers only
/// behind the map's first surface, whose outline the map draws at its own
/// size, and a march step's hit is confirmed at the ray's own point; on the
/// generated suite the map's own side (at most 1024) gave the same median
/// (0.0609 against 0.0606 for wedges, 0.0790 for pvm) at twice the pass's
/// time (30-45 ms against 14-20 on the 40k-63k-triangle scenes, 96x96).
///
/// At most the side whose buffer (`layers` map layers of [`LAYERS`] words a
/// texel, after the header) fits `max_bytes`, the adapter's storage-buffer
/// limit: a cube map of 8192-texel faces would want 2048-texel layers, 403
/// MB against lavapipe's 128 MB, and takes 1182 (coarser layers find the
/// same solids, their ends drawn in by more; the map's own texels still
/// draw the outline).
pub fn side(map_size: u32, layers: u32, max_bytes: u64) -> u32 {
    let per_texel = 4 * u64::from(LAYERS) * u64::from(layers.max(1));
    // The largest side whose texels fit beside the header.
    let fit = (max_bytes.saturating_sub(4 * u64::from(HEADER)) / per_texel).isqrt();
    (map_size / 4).max(256).min(map_size).min(fit.min(u64::from(u32::MAX)) as u32).max(1)
}

fn record(frame: &mut Frame<'_>, pass: &SolidLayersPass, projection: &LightProjection, map_size: u32, solids: &[bool]) -> Result<Arc<SolidLayers>> {
    let side = side(map_size, projection.layers(), frame.ctx.max_storage_buffer());
    frame.stat("solid_layers_side", i64::from(side));
    let bytes = 4 * (u64::from(HEADER) + u64::from(LAYERS) * u64::from(side) * u64::from(side) * u64::from(projection.layers()));
    let mut key = PassKey::new(SOLID_LAYERS.name);
    key.bytes(&frame.ctx.geometry).projection(projection).u32(side);
    for &s in solids {
        key.u32(u32::from(s));
    }
    let key = key.finish();
    frame.cached(SOLID_LAYERS.name, key, |frame| {
        frame.pass(SOLID_LAYERS.name, |ctx, encoder, ts| -> Result<Arc<SolidLayers>> {
            let buffer = ctx.buffer("solid_layers::layers", bytes, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
            // The texels cleared (empty) as the pass is recorded; the header,
            // written through the queue before it runs, kept.
            encoder.clear_buffer(&buffer, 4 * u64::from(HEADER), None);
            let drawn = solids.iter().filter(|&&s| s).count() as u32;
            ctx.queue.write_buffer(&buffer, 0, bytemuck::cast_slice(&[side, projection.layers(), drawn, 0]));
            let indices = solid_indices(ctx, solids);
            let index_count = indices.len() as u32;
            let index_buffer = ctx.buffer("solid_layers::indices", (4 * indices.len()).max(16) as u64, wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST);
            ctx.queue.write_buffer(&index_buffer, 0, bytemuck::cast_slice(&indices));
            let positions = ctx.light_geometry().0;
            let depth = ShadowMapPass::create_map(ctx, side, projection.layers());
            let faces: Vec<(u32, &LightFrustum)> = projection.active_layers().collect();
            for (k, (layer, frustum)) in faces.iter().enumerate() {
                let uniforms = uniform_buffer(ctx, "solid_layers::view", &shadow_uniforms(frustum));
                let face = uniform_buffer(ctx, "solid_layers::face", &SolidFace { layer: *layer, side, unused: [0; 2] });
                let group = ctx.pool.bind_group(ctx.device, "solid_layers", &pass.layout, &[Binding::Buffer(&uniforms), Binding::Buffer(&buffer), Binding::Buffer(&face)]);
                let mut rpass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("solid_layers"),
                    color_attachments: &[],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &depth.layer_views[*layer as usize],
                        depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: ts.and_then(|t| t.render_part(k == 0, k + 1 == faces.len())),
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                super::shadow_map::keep_border_empty(&mut rpass, projection, side);
                if index_count > 0 {
                    rpass.set_pipeline(&pass.pipeline);
                    rpass.set_bind_group(0, &group, &[]);
                    rpass.set_vertex_buffer(0, positions.slice(..));
                    rpass.set_index_buffer(index_buffer.slice(..), wgpu::IndexFormat::Uint32);
                    rpass.draw_indexed(0..index_count, 0, 0..1);
                }
            }
            Ok(Arc::new(SolidLayers { buffer }))
        })?
    })
}

/// Every triangle of the solid meshes, as the light's raster passes index
/// the scene's positions.
fn solid_indices(ctx: &FrameContext<'_>, solids: &[bool]) -> Vec<u32> {
    let prepared = ctx.prepared;
    let mut out = Vec::new();
    let mut triangles = prepared.position_indices.chunks_exact(3);
    for (mesh, &solid) in prepared.meshes.iter().zip(solids) {
        for tri in triangles.by_ref().take(mesh.faces.len()) {
            if solid {
                out.extend_from_slice(tri);
            }
        }
    }
    out
}

/// Which of `meshes` meshes are solid: every connected surface its faces
/// belong to is closed (no edge with one face, none with more than two or
/// two wound alike) and does not hold `light` (its winding number there,
/// over its consistently wound faces, is below 1/2 in size). A mesh none of
/// whose faces survived the weld (a whole copy of another) is not drawn:
/// its surface is there once already, and a second copy of every depth
/// would take the layers' four slots two by two. Faces duplicated within
/// drawn meshes (overlapping pieces) are dropped by the shader instead.
pub fn solid_meshes(topology: &Topology, meshes: usize, light: DVec3) -> Vec<bool> {
    let n = topology.positions.len();
    let mut open = vec![false; n];
    for e in &topology.edges {
        if e.faces.contains(&NO_FACE) {
            open[topology.components[e.v[0] as usize] as usize] = true;
        }
    }
    for e in &topology.non_manifold {
        for &f in &e.faces {
            open[topology.components[topology.faces[f as usize][0] as usize] as usize] = true;
        }
    }
    // Winding numbers at the light: the solid angles of each component's faces.
    let mut winding = vec![0.0f64; n];
    for face in &topology.faces {
        let c = topology.components[face[0] as usize] as usize;
        if !open[c] {
            winding[c] += solid_angle(face.map(|v| topology.positions[v as usize] - light));
        }
    }
    let solid = |c: usize| !open[c] && (winding[c] / (4.0 * std::f64::consts::PI)).abs() < 0.5;
    // None: no face yet; Some(s): whether every face so far is on a solid.
    let mut per_mesh: Vec<Option<bool>> = vec![None; meshes];
    for (face, &part) in topology.faces.iter().zip(&topology.face_part) {
        let s = solid(topology.components[face[0] as usize] as usize);
        if let Some(m) = per_mesh.get_mut(part as usize) {
            *m = Some(m.unwrap_or(true) && s);
        }
    }
    per_mesh.into_iter().map(|m| m.unwrap_or(false)).collect()
}

/// The signed solid angle of a triangle with corners `a, b, c` seen from
/// the origin (Van Oosterom and Strackee 1983): 2 atan2 of the triple
/// product over the corners' lengths' combination; atan2 is defined
/// everywhere (0 for a triangle through the origin).
fn solid_angle([a, b, c]: [DVec3; 3]) -> f64 {
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let numerator = a.dot(b.cross(c));
    let denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * numerator.atan2(denominator)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An octahedron (closed, consistent windings) of radius `r` at `c`.
    fn octahedron(c: DVec3, r: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let v = vec![c + DVec3::X * r, c - DVec3::X * r, c + DVec3::Y * r, c - DVec3::Y * r, c + DVec3::Z * r, c - DVec3::Z * r];
        let f = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        (v, f)
    }

    #[test]
    fn the_side_is_a_quarter_of_the_map_within_the_buffer_limit() {
        let big = u64::MAX;
        assert_eq!((side(2048, 1, big), side(512, 1, big), side(128, 1, big), side(16384, 1, big)), (512, 256, 128, 4096));
        // lavapipe's 128 MiB: a cube of 8192-texel faces, a 16384 frustum.
        let limit = 128 << 20;
        for (map, layers, want) in [(8192, 6, 1182), (16384, 1, 2896), (2048, 6, 512)] {
            let s = side(map, layers, limit);
            let bytes = |s: u64| 4 * (u64::from(HEADER) + u64::from(LAYERS) * s * s * u64::from(layers));
            assert!(s == want && bytes(u64::from(s)) <= limit, "{map} {layers}: {s}");
            assert!(s == map / 4 || bytes(u64::from(s) + 1) > limit, "{map} {layers}: {s} is not the largest that fits");
        }
        assert_eq!(side(2048, 1, 0), 1);
    }

    #[test]
    fn a_closed_surface_is_solid_unless_it_holds_the_light_or_is_open() {
        let (v, f) = octahedron(DVec3::ZERO, 1.0);
        let t = Topology::build(&v, &f);
        assert_eq!(solid_meshes(&t, 1, DVec3::new(0.0, 5.0, 0.0)), vec![true]);
        // The light inside (a room lit from within).
        assert_eq!(solid_meshes(&t, 1, DVec3::new(0.1, 0.2, 0.0)), vec![false]);
        // Reversed windings: the same.
        let reversed: Vec<[u32; 3]> = f.iter().map(|&[a, b, c]| [a, c, b]).collect();
        assert_eq!(solid_meshes(&Topology::build(&v, &reversed), 1, DVec3::new(0.0, 5.0, 0.0)), vec![true]);
        // A face missing: open.
        let t = Topology::build(&v, &f[1..]);
        assert_eq!(solid_meshes(&t, 1, DVec3::new(0.0, 5.0, 0.0)), vec![false]);
    }

    #[test]
    fn a_whole_copy_of_a_solid_is_not_drawn_twice() {
        let (v, f) = octahedron(DVec3::ZERO, 1.0);
        let parts = [crate::topology::Part { vertices: &v, faces: &f }, crate::topology::Part { vertices: &v, faces: &f }];
        let t = Topology::from_parts(&parts, crate::topology::WELD_TOLERANCE);
        assert_eq!(solid_meshes(&t, 2, DVec3::new(0.0, 5.0, 0.0)), vec![true, false]);
    }

    #[test]
    fn solid_angles_of_a_closed_surface_sum_to_four_pi_inside_and_zero_outside() {
        let (v, f) = octahedron(DVec3::new(0.3, -0.2, 0.1), 2.0);
        let sum = |p: DVec3| f.iter().map(|t| solid_angle(t.map(|i| v[i as usize] - p))).sum::<f64>();
        assert!((sum(DVec3::ZERO).abs() - 4.0 * std::f64::consts::PI).abs() < 1e-9);
        assert!(sum(DVec3::new(9.0, 1.0, -3.0)).abs() < 1e-9);
    }
}
