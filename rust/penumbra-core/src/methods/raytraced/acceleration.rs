//! The acceleration structures `raytraced` traces its rays through:
//!
//! - a bottom-level structure (BLAS) per mesh, over its vertices and faces in
//!   the mesh's own coordinates, built once and kept while the mesh's content
//!   is unchanged (keyed by a hash of its vertices and faces, as the
//!   silhouette methods key topology): moving a mesh (its transform) or the
//!   light builds no BLAS;
//! - a top-level structure (TLAS) per scene: one instance per mesh, placing
//!   its BLAS with the mesh's object-to-world transform. Kept for the last few
//!   scenes (keyed by their BLASes and transforms).
//!
//! They are built in a submission of their own, waited for inside an error
//! scope, before any render reads them: a structure enters the cache only
//! once it is built, so a concurrent render never binds one still in flight
//! and a failed build leaves nothing behind.
//!
//! Memory: on Vulkan (the only backend with ray queries), each structure's
//! size is read from the device allocator's report (the allocation named by
//! the structure's label); where the allocator gives no report, it is
//! estimated at [`ESTIMATED_BYTES_PER_TRIANGLE`]. The cache holds at most
//! [`ACCELERATION_BUDGET`] bytes: beyond it the least recently used BLASes
//! not in the current scene go (with the TLASes that use them).

use std::collections::hash_map::DefaultHasher;
use std::hash::{Hash, Hasher};
use std::sync::Mutex;

use crate::error::{Error, Result};
use crate::frame::FrameContext;
use crate::scene::Mesh;

/// Bytes of acceleration structures the cache keeps at most (besides those of
/// the scene being rendered, which it always holds).
pub const ACCELERATION_BUDGET: u64 = 512 << 20;

/// TLASes kept (the scenes rendered last).
const TLAS_ENTRIES: usize = 4;

/// The size assumed for a BLAS per triangle where the allocator reports none
/// (lavapipe's report: 104 bytes per triangle, the stats `acceleration_bytes`
/// over `triangles` of `penumbra render --method raytraced --param n_samples=1`;
/// docs/methods/raytraced.md).
pub const ESTIMATED_BYTES_PER_TRIANGLE: u64 = 128;

/// A mesh's content key: its object-space vertices (exact bits) and faces.
pub fn mesh_key(mesh: &Mesh) -> u64 {
    let mut h = DefaultHasher::new();
    mesh.faces.hash(&mut h);
    mesh.vertices.len().hash(&mut h);
    for v in &mesh.vertices {
        v.map(f32::to_bits).hash(&mut h);
    }
    h.finish()
}

/// A mesh's object-to-world transform as the 3x4 row-major matrix a TLAS
/// instance takes (the last row of an affine transform, 0 0 0 1, is implied;
/// scene validation checks it).
pub fn instance_transform(mesh: &Mesh) -> [f32; 12] {
    let m = mesh.transform;
    let (r0, r1, r2) = (m.row(0), m.row(1), m.row(2));
    [r0.x, r0.y, r0.z, r0.w, r1.x, r1.y, r1.z, r1.w, r2.x, r2.y, r2.z, r2.w]
}

/// A cached BLAS (`B`: `wgpu::Blas`; the tests use a stand-in).
struct BlasEntry<B> {
    key: u64,
    blas: B,
    bytes: u64,
    last_used: u64,
}

struct TlasEntry<T> {
    key: Vec<u8>,
    blas_keys: Vec<u64>,
    tlas: T,
    /// Names the TLAS in the resource pool's bind-group cache.
    id: u64,
    bytes: u64,
    last_used: u64,
}

struct Entries<B = wgpu::Blas, T = wgpu::Tlas> {
    blas: Vec<BlasEntry<B>>,
    tlas: Vec<TlasEntry<T>>,
    clock: u64,
}

impl<B, T> Default for Entries<B, T> {
    fn default() -> Self {
        Self { blas: Vec::new(), tlas: Vec::new(), clock: 0 }
    }
}

impl<B, T> Entries<B, T> {
    fn bytes(&self) -> u64 {
        self.blas.iter().map(|b| b.bytes).sum::<u64>() + self.tlas.iter().map(|t| t.bytes).sum::<u64>()
    }

    /// Drops the least recently used BLASes beyond the budget (never those of
    /// `keep`), and the TLASes that use them.
    fn evict(&mut self, keep: &[u64], budget: u64) {
        while self.bytes() > budget {
            let victim = self
                .blas
                .iter()
                .enumerate()
                .filter(|(_, b)| !keep.contains(&b.key))
                .min_by_key(|(_, b)| b.last_used)
                .map(|(i, _)| i);
            let Some(i) = victim else { break };
            let gone = self.blas.swap_remove(i).key;
            self.tlas.retain(|t| !t.blas_keys.contains(&gone));
        }
    }
}

/// What [`AccelerationCache::prepare`] hands a render.
pub struct SceneAcceleration {
    pub tlas: wgpu::Tlas,
    pub tlas_id: u64,
    /// BLASes built for this render, and reused from earlier ones.
    pub blas_built: usize,
    pub blas_reused: usize,
    pub tlas_built: bool,
    /// Bytes of acceleration structures the cache holds after this render.
    pub cache_bytes: u64,
    /// Bytes of this scene's structures (its BLASes and TLAS).
    pub scene_bytes: u64,
    pub triangles: u64,
}

/// BLASes per mesh content and TLASes per scene, bounded by [`ACCELERATION_BUDGET`].
pub struct AccelerationCache {
    entries: Mutex<Entries>,
    budget: u64,
}

impl Default for AccelerationCache {
    fn default() -> Self {
        Self { entries: Mutex::new(Entries::default()), budget: ACCELERATION_BUDGET }
    }
}

/// The bytes the allocator reports for the allocation named `label`, or the
/// estimate for `triangles` where it reports nothing.
fn allocated_bytes(device: &wgpu::Device, label: &str, triangles: u64) -> u64 {
    let reported = device
        .generate_allocator_report()
        .map(|r| r.allocations.iter().filter(|a| a.name == label).map(|a| a.size).sum::<u64>())
        .unwrap_or(0);
    if reported > 0 {
        reported
    } else {
        triangles.max(1) * ESTIMATED_BYTES_PER_TRIANGLE
    }
}

impl AccelerationCache {
    /// The TLAS of the frame's scene, building (in a submission of its own,
    /// waited for) every BLAS and the TLAS the cache lacks.
    pub fn prepare(&self, ctx: &FrameContext<'_>) -> Result<SceneAcceleration> {
        let meshes = &ctx.scene.meshes;
        let limits = ctx.device.limits();
        if meshes.len() as u64 > limits.max_tlas_instance_count as u64 {
            return Err(Error::InvalidScene(format!(
                "{} meshes exceed this adapter's {} instances per acceleration structure",
                meshes.len(),
                limits.max_tlas_instance_count
            )));
        }
        for mesh in meshes {
            if mesh.faces.len() as u64 > limits.max_blas_primitive_count as u64 || mesh.vertices.len() as u64 > u32::MAX as u64 {
                return Err(Error::InvalidScene(format!(
                    "mesh '{}': {} triangles exceed this adapter's {} per acceleration structure",
                    mesh.name,
                    mesh.faces.len(),
                    limits.max_blas_primitive_count
                )));
            }
        }
        let keys: Vec<u64> = meshes.iter().map(mesh_key).collect();
        let transforms: Vec<[f32; 12]> = meshes.iter().map(instance_transform).collect();
        let mut tlas_key = Vec::with_capacity(keys.len() * 56);
        for (k, t) in keys.iter().zip(&transforms) {
            tlas_key.extend_from_slice(&k.to_le_bytes());
            tlas_key.extend(t.iter().flat_map(|x| x.to_bits().to_le_bytes()));
        }
        let mut entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        entries.clock += 1;
        let now = entries.clock;
        let device = ctx.device;

        // The BLASes missing, built from the meshes' own vertices and faces.
        let mut fresh: Vec<(u64, wgpu::Blas, wgpu::BlasTriangleGeometrySizeDescriptor, wgpu::Buffer, wgpu::Buffer, String, u64)> = Vec::new();
        let mut reused = 0;
        for (mesh, &key) in meshes.iter().zip(&keys) {
            if let Some(b) = entries.blas.iter_mut().find(|b| b.key == key) {
                b.last_used = now;
                reused += 1;
                continue;
            }
            if fresh.iter().any(|f| f.0 == key) {
                continue; // the same content twice in one scene: one BLAS
            }
            let size = wgpu::BlasTriangleGeometrySizeDescriptor {
                vertex_format: wgpu::VertexFormat::Float32x3,
                vertex_count: mesh.vertices.len() as u32,
                index_format: Some(wgpu::IndexFormat::Uint32),
                index_count: Some(mesh.faces.len() as u32 * 3),
                flags: wgpu::AccelerationStructureGeometryFlags::OPAQUE,
            };
            let label = format!("raytraced::blas {key:016x}");
            let blas = device.create_blas(
                &wgpu::CreateBlasDescriptor {
                    label: Some(&label),
                    flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                    update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                },
                wgpu::BlasGeometrySizeDescriptors::Triangles { descriptors: vec![size.clone()] },
            );
            let input = |what: &str, bytes: &[u8]| {
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&format!("raytraced::blas_{what}")),
                    size: bytes.len() as u64,
                    usage: wgpu::BufferUsages::BLAS_INPUT | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                ctx.queue.write_buffer(&buffer, 0, bytes);
                buffer
            };
            let vertices = input("vertices", bytemuck::cast_slice(&mesh.vertices));
            let indices = input("indices", bytemuck::cast_slice(&spatial_order(&mesh.vertices, &mesh.faces)));
            fresh.push((key, blas, size, vertices, indices, label, mesh.faces.len() as u64));
        }

        let cached_tlas = entries.tlas.iter().position(|t| t.key == tlas_key);
        let mut new_tlas = None;
        if cached_tlas.is_none() || !fresh.is_empty() {
            let label = format!("raytraced::tlas {}", ctx.pool.new_id());
            let mut tlas = device.create_tlas(&wgpu::CreateTlasDescriptor {
                label: Some(&label),
                max_instances: meshes.len() as u32,
                flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                update_mode: wgpu::AccelerationStructureUpdateMode::Build,
            });
            for (i, (key, transform)) in keys.iter().zip(&transforms).enumerate() {
                let blas = match entries.blas.iter().find(|b| b.key == *key) {
                    Some(b) => &b.blas,
                    None => &fresh.iter().find(|f| f.0 == *key).expect("made above").1,
                };
                tlas[i] = Some(wgpu::TlasInstance::new(blas, *transform, 0, 0xff));
            }
            new_tlas = Some((tlas, label));
        }

        let tlas_built = new_tlas.is_some();
        if tlas_built {
            let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
            let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("raytraced::acceleration") });
            let builds: Vec<wgpu::BlasBuildEntry<'_>> = fresh
                .iter()
                .map(|(_, blas, size, vertices, indices, _, _)| wgpu::BlasBuildEntry {
                    blas,
                    geometry: wgpu::BlasGeometries::TriangleGeometries(vec![wgpu::BlasTriangleGeometry {
                        size,
                        vertex_buffer: vertices,
                        first_vertex: 0,
                        vertex_stride: 12,
                        index_buffer: Some(indices),
                        first_index: Some(0),
                        transform_buffer: None,
                        transform_buffer_offset: None,
                    }]),
                })
                .collect();
            let tlas = &new_tlas.as_ref().expect("built above").0;
            encoder.build_acceleration_structures(builds.iter(), std::iter::once(tlas));
            ctx.queue.submit([encoder.finish()]);
            let waited = device.poll(wgpu::PollType::wait_indefinitely());
            let validation_error = pollster::block_on(validation.pop());
            let oom_error = pollster::block_on(oom.pop());
            if let Some(e) = oom_error {
                return Err(Error::OutOfMemory(format!("out of GPU memory building acceleration structures: {e}")));
            }
            if let Some(e) = validation_error {
                return Err(Error::Gpu(format!("building acceleration structures: {e}")));
            }
            waited.map_err(|e| Error::Gpu(format!("waiting for the acceleration-structure build failed: {e}")))?;
        }

        let blas_built = fresh.len();
        for (key, blas, _, _, _, label, triangles) in fresh {
            let bytes = allocated_bytes(device, &label, triangles);
            entries.blas.push(BlasEntry { key, blas, bytes, last_used: now });
        }
        let index = match (new_tlas, cached_tlas) {
            (Some((tlas, label)), _) => {
                // A TLAS's own memory is small (one record per instance) and
                // has no per-triangle estimate: 64 bytes per instance at least.
                let bytes = allocated_bytes(device, &label, 0).max(64 * meshes.len() as u64);
                entries.tlas.retain(|t| t.key != tlas_key);
                let id = ctx.pool.new_id();
                entries.tlas.push(TlasEntry { key: tlas_key.clone(), blas_keys: keys.clone(), tlas, id, bytes, last_used: now });
                if entries.tlas.len() > TLAS_ENTRIES {
                    if let Some(oldest) = entries.tlas.iter().enumerate().min_by_key(|(_, t)| t.last_used).map(|(i, _)| i) {
                        entries.tlas.swap_remove(oldest);
                    }
                }
                entries.tlas.iter().position(|t| t.key == tlas_key).expect("just inserted, and the newest")
            }
            (None, Some(i)) => {
                entries.tlas[i].last_used = now;
                i
            }
            (None, None) => unreachable!("a TLAS is built whenever none is cached"),
        };
        let budget = self.budget;
        let (tlas, tlas_id, tlas_bytes) = {
            let t = &entries.tlas[index];
            (t.tlas.clone(), t.id, t.bytes)
        };
        entries.evict(&keys, budget);
        let scene_bytes = tlas_bytes
            + entries.blas.iter().filter(|b| keys.contains(&b.key)).map(|b| b.bytes).sum::<u64>();
        Ok(SceneAcceleration {
            tlas,
            tlas_id,
            blas_built,
            blas_reused: reused,
            tlas_built,
            cache_bytes: entries.bytes(),
            scene_bytes,
            triangles: meshes.iter().map(|m| m.faces.len() as u64).sum(),
        })
    }

    /// Bytes and counts the cache holds: (bytes, BLASes, TLASes).
    pub fn held(&self) -> (u64, usize, usize) {
        let entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        (entries.bytes(), entries.blas.len(), entries.tlas.len())
    }
}

/// The faces in Morton order of their centroids (10 bits per axis over the
/// mesh's bounding box). Lavapipe's BLAS builder keeps the order it is given
/// (measured on spot.obj, 5856 triangles, 128x128, 16 rays per pixel: 267 ms
/// for the faces as the file has them, 4845 ms for the same faces shuffled,
/// 335 ms shuffled then sorted into a grid), so a soup or an exporter's
/// arbitrary face order made `raytraced` 11-18x slower; sorted, every order
/// traces alike. Visibility does not depend on the order (no shader reads a
/// primitive index).
pub fn spatial_order(vertices: &[[f32; 3]], faces: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let centroid = |f: &[u32; 3]| {
        let mut c = [0.0f64; 3];
        for &i in f {
            for (k, x) in vertices[i as usize].iter().enumerate() {
                c[k] += f64::from(*x) / 3.0;
            }
        }
        c
    };
    let centroids: Vec<[f64; 3]> = faces.iter().map(centroid).collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for c in &centroids {
        for k in 0..3 {
            lo[k] = lo[k].min(c[k]);
            hi[k] = hi[k].max(c[k]);
        }
    }
    // Spreads the low 10 bits of x to every third bit.
    let spread = |x: u32| {
        let mut x = x & 0x3ff;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    };
    let code = |c: &[f64; 3]| {
        let mut m = 0u32;
        for k in 0..3 {
            // A flat box (extent 0 on an axis) puts every centroid in cell 0 there.
            let extent = hi[k] - lo[k];
            let cell = if extent > 0.0 { ((c[k] - lo[k]) / extent * 1023.0).round() as u32 } else { 0 };
            m |= spread(cell) << k;
        }
        m
    };
    let mut order: Vec<(u32, u32)> = centroids.iter().enumerate().map(|(i, c)| (code(c), i as u32)).collect();
    order.sort_unstable();
    order.into_iter().map(|(_, i)| faces[i as usize]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat4;

    fn mesh(vertices: Vec<[f32; 3]>, transform: Mat4) -> Mesh {
        Mesh {
            name: "m".into(),
            vertices,
            faces: vec![[0, 1, 2]],
            normals: None,
            albedo: [0.5; 3],
            object_id: 0,
            transform,
        }
    }

    #[test]
    fn mesh_keys_follow_content_not_placement() {
        let a = mesh(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], Mat4::IDENTITY);
        let moved = mesh(a.vertices.clone(), Mat4::from_translation(glam::Vec3::new(1.0, 2.0, 3.0)));
        let mut other = a.clone();
        other.vertices[2][1] = 1.0 + f32::EPSILON;
        assert_eq!(mesh_key(&a), mesh_key(&moved));
        assert_ne!(mesh_key(&a), mesh_key(&other));
        let mut flipped = a.clone();
        flipped.faces = vec![[0, 2, 1]];
        assert_ne!(mesh_key(&a), mesh_key(&flipped));
    }

    #[test]
    fn the_cache_stays_within_its_budget_keeping_the_current_scene() {
        let mut e: Entries<(), ()> = Entries::default();
        for key in 0..5u64 {
            e.blas.push(BlasEntry { key, blas: (), bytes: 100, last_used: key });
        }
        e.tlas.push(TlasEntry { key: vec![0], blas_keys: vec![0, 4], tlas: (), id: 0, bytes: 10, last_used: 0 });
        e.tlas.push(TlasEntry { key: vec![1], blas_keys: vec![3, 4], tlas: (), id: 1, bytes: 10, last_used: 4 });
        assert_eq!(e.bytes(), 520);
        // 300 bytes: the least recently used BLASes go (0, then 1), never the
        // current scene's (0 is kept while it is in use), and with them the
        // TLASes that use them.
        e.evict(&[0, 4], 300);
        let keys: Vec<u64> = e.blas.iter().map(|b| b.key).collect();
        assert!(e.bytes() <= 300, "{}", e.bytes());
        assert!(keys.contains(&0) && keys.contains(&4) && !keys.contains(&1) && !keys.contains(&2), "{keys:?}");
        assert_eq!(e.tlas.len(), 1, "the TLAS over BLAS 3 went with it");
        // A budget below the current scene's own size keeps the scene.
        e.evict(&[0, 4], 0);
        assert_eq!(e.blas.iter().map(|b| b.key).collect::<Vec<_>>().len(), 2);
    }

    #[test]
    fn instance_transforms_are_row_major_3x4() {
        let t = Mat4::from_translation(glam::Vec3::new(1.0, 2.0, 3.0)) * Mat4::from_scale(glam::Vec3::new(2.0, 3.0, 4.0));
        let m = mesh(vec![[0.0; 3]; 3], t);
        assert_eq!(instance_transform(&m), [2.0, 0.0, 0.0, 1.0, 0.0, 3.0, 0.0, 2.0, 0.0, 0.0, 4.0, 3.0]);
    }

    #[test]
    fn spatial_order_keeps_every_face_and_sorts_by_position() {
        // A row of 16 triangles along x, given in reverse: sorted, they run left to right.
        let vertices: Vec<[f32; 3]> = (0..16).flat_map(|i| [[i as f32, 0.0, 0.0], [i as f32 + 0.5, 1.0, 0.0], [i as f32, 1.0, 0.5]]).collect();
        let faces: Vec<[u32; 3]> = (0..16u32).rev().map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let sorted = spatial_order(&vertices, &faces);
        assert_eq!(sorted, (0..16u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect::<Vec<_>>());
        // A flat or single-face mesh stays whole.
        assert_eq!(spatial_order(&vertices, &faces[..1]), faces[..1].to_vec());
    }
}
