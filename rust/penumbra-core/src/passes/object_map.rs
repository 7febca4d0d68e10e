//! The object map: for every texel of the light centre's map, which object
//! (connected surface) is the first surface seen from the light (0: none).
//! The silhouette methods' `horizon` repair reads it (issue 27): a receiver
//! whose light centre lies below its tangent plane sees the sliver of the
//! light above that plane only where the surface hiding the centre from it
//! is its own object (the receiver's body, near its terminator); where
//! another object is first (a floor between a light below it and a box
//! above), that object hides the sliver too.
//!
//! The map draws the triangles the shadow map draws (`casters.rs`): a
//! triangle that hides no part of the light from any point hides no sliver
//! either, and where it was first the texel now holds what lies beyond it,
//! nothing of the scene ("none": the sliver is seen).
//!
//! Objects come from the silhouette layer's connectivity
//! ([`SilhouetteCache::mesh_objects`](crate::silhouettes::SilhouetteCache::mesh_objects)):
//! a mesh that is one connected surface, or a piece of one spread over
//! several meshes, is that surface's object; a mesh of several separate
//! surfaces (a room's walls and furniture in one file) is [`MANY`], and its
//! receivers keep the sliver whatever hides their centre.

use std::sync::Arc;

use crate::error::Result;
use crate::frame::{Frame, FrameContext};
use crate::gpu::layout;
use crate::gpu::pool::{Binding, PooledBuffer, PooledTexture, ResourcePool};
use crate::light_frustum::LightProjection;
use crate::pass_cache::{CachedPass, PassKey};
use crate::passes::screen::LayoutEntry;
use crate::passes::volumes::{Keep, VolumePass};

/// The object map and the per-mesh object table, as the pass cache keeps them.
pub const OBJECT_MAP: CachedPass = CachedPass { name: "object_map", capacity: 2 };

pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;

pub use crate::silhouettes::MANY;

/// The raster pass (one per method that reads the map): the light
/// geometry's positions, each mesh drawn as instance object + 1.
pub fn pass(device: &wgpu::Device, pool: &ResourcePool) -> VolumePass {
    VolumePass::new::<[f32; 3]>(
        Keep::Nearest,
        device,
        pool,
        "object_map",
        crate::shader!("light_ids.wgsl"),
        ("vs_instance", "fs_main"),
        &wgpu::vertex_attr_array![0 => Float32x3],
        &[FORMAT],
    )
}

/// The map over `projection` at `map_size`, and the table of each mesh's
/// object (`objects[mesh_index]`, [`MANY`] for a mesh of several surfaces),
/// for the G-buffer's mesh index of a receiver.
pub struct ObjectMap {
    pub map: PooledTexture,
    pub objects: PooledBuffer,
}

/// `entries` followed by the two layout entries a screen pass reads the map
/// through (`horizon_sliver_seen` of passes/shadow_test.wgsl), last among its
/// bindings: the map (`texture_2d_array<u32>`) and the per-mesh table
/// (storage, read). [`ObjectMap::after`] binds them.
pub fn with_bindings(entries: &[LayoutEntry]) -> Vec<LayoutEntry> {
    let map: LayoutEntry = |binding| layout::array_texture(binding, wgpu::TextureSampleType::Uint);
    [entries, &[map, layout::parameters]].concat()
}

impl ObjectMap {
    /// `resources` followed by the map and its table, for a layout made by [`with_bindings`].
    pub fn after<'a>(&'a self, resources: &'a [Binding<'a>]) -> Vec<Binding<'a>> {
        resources.iter().map(Binding::reborrow).chain([Binding::Texture(&self.map), Binding::Buffer(&self.objects)]).collect()
    }
}

/// The map when `needed` (the `horizon` repair), or a 1-texel stand-in that
/// the shaders do not read.
pub fn record_if(frame: &mut Frame<'_>, needed: bool, pass: &VolumePass, projection: &LightProjection, map_size: u32) -> Result<Arc<ObjectMap>> {
    if needed {
        return record(frame, pass, projection, map_size);
    }
    let ctx = &frame.ctx;
    let map = ctx.light_texture("object_map::none", 1, 1, FORMAT, wgpu::TextureUsages::TEXTURE_BINDING);
    Ok(Arc::new(ObjectMap { map, objects: table(ctx, &[MANY]) }))
}

/// The object map's side for a shadow map of `map_size`: a quarter of it
/// (at least 64 texels). The test asks only whether p's neighbourhood holds
/// its own object anywhere, a question of which object covers a region and
/// not of where an edge falls within a texel, and the map costs as much as
/// the shadow map at full size (the silhouette methods' time went up by 30-50%).
pub fn side(map_size: u32) -> u32 {
    (map_size / 4).max(64).min(map_size)
}

fn record(frame: &mut Frame<'_>, pass: &VolumePass, projection: &LightProjection, map_size: u32) -> Result<Arc<ObjectMap>> {
    let map_size = side(map_size);
    let key = PassKey::new(OBJECT_MAP.name).bytes(&frame.ctx.geometry).u32(frame.ctx.non_casters() as u32).projection(projection).u32(map_size).finish();
    frame.cached(OBJECT_MAP.name, key, |frame| {
        frame.pass(OBJECT_MAP.name, |ctx, encoder, ts| -> Result<Arc<ObjectMap>> {
            let objects = ctx.silhouettes.mesh_objects(ctx.prepared);
            // The instance is object + 1 (the map's id); MANY wraps to 0,
            // "none", as the shader's id + 1 would.
            let ids: Vec<Option<u32>> = objects.iter().map(|&o| Some(o.wrapping_add(1))).collect();
            let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
            let map = ctx.light_texture("object_map::map", map_size, projection.layers(), FORMAT, usage);
            pass.record_meshes(ctx, encoder, projection, &ids, map_size, &[&map], ts);
            Ok(Arc::new(ObjectMap { map, objects: table(ctx, &objects) }))
        })?
    })
}

fn table(ctx: &FrameContext<'_>, objects: &[u32]) -> PooledBuffer {
    let bytes: &[u8] = bytemuck::cast_slice(objects);
    let buffer = ctx.buffer("object_map::objects", bytes.len().max(16) as u64, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
    ctx.queue.write_buffer(&buffer, 0, bytes);
    buffer
}
