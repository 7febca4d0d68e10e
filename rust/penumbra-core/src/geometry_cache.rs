//! What a render derives from a scene's geometry, kept by the renderer from
//! one render to the next while the geometry is unchanged (issue 30: no
//! per-render preparation or upload of unchanged geometry).
//!
//! A render of a 70k-triangle mesh spent most of its fixed cost before any
//! pass ran: world-space corners and normals ([`Scene::prepare_geometry`]),
//! their upload, the casters (`casters.rs`) and the points a light map is
//! fitted around. The renderer keeps these for the last geometry rendered:
//!
//! - [`SceneGeometry`]: the prepared geometry, its hash for the pass cache,
//!   its vertex and index buffers and its corner positions. It is recognised
//!   by the meshes it was prepared from, compared bit for bit (names,
//!   vertices, faces, normals, materials, transforms): a mesh changed in
//!   place, moved or recoloured prepares afresh.
//! - [`LightGeometry`], per light (centre and radius, bit for bit) of that
//!   geometry, the most recent [`LIGHTS_KEPT`]: the casters, their index
//!   buffers and points. The light's check against the geometry (no surface
//!   within its radius) is remembered with it.
//!
//! Results are bit-identical to preparing afresh: nothing is kept that any
//! input the comparison leaves out could change. `stats["reused_geometry"]`
//! is 1 where a render found its geometry kept.

use std::ops::Range;
use std::sync::{Arc, Mutex, OnceLock};

use glam::Vec3;

use crate::casters::Casters;
use crate::error::Result;
use crate::gpu::pool::PooledBuffer;
use crate::occluders::Occluders;
use crate::scene::{Mesh, PreparedScene, Scene, SphereLight};

/// Lights whose casters one geometry keeps (a sweep over the light's
/// radius or position reuses them when it comes back to one).
pub const LIGHTS_KEPT: usize = 8;

/// A scene's triangles on the GPU, indexed (see [`PreparedScene`]).
pub struct GeometryBuffers {
    pub surface_vertices: PooledBuffer,
    pub surface_indices: PooledBuffer,
    pub positions: PooledBuffer,
}

/// A scene's prepared geometry and what is derived from it alone.
pub struct SceneGeometry {
    /// The meshes it was prepared from, to recognise them.
    meshes: Vec<Mesh>,
    pub prepared: PreparedScene,
    /// `pass_cache::geometry_hash` of `prepared`, on first use.
    pub(crate) hash: OnceLock<u64>,
    /// Its vertex and index buffers, uploaded on first use.
    pub(crate) buffers: OnceLock<Arc<GeometryBuffers>>,
    /// The triangle corners' positions, three per triangle.
    pub(crate) corner_positions: OnceLock<Vec<Vec3>>,
    /// A bounding volume hierarchy over those triangles, on first use.
    pub(crate) corner_hierarchy: OnceLock<Arc<Occluders>>,
    /// Per light, most recent last.
    lights: Mutex<Vec<Arc<LightGeometry>>>,
}

/// What one light of a geometry derives from it.
pub struct LightGeometry {
    key: [u32; 4],
    /// The triangles that can cast a shadow and their index buffer.
    pub(crate) casters: OnceLock<(PooledBuffer, Casters)>,
    /// The casters' corners, each vertex once.
    pub(crate) caster_points: OnceLock<Vec<Vec3>>,
    /// The casters per cube face, one index buffer with a range per face.
    pub(crate) face_casters: OnceLock<(PooledBuffer, Vec<Range<u32>>)>,
}

fn light_key(light: &SphereLight) -> [u32; 4] {
    [light.center[0].to_bits(), light.center[1].to_bits(), light.center[2].to_bits(), light.radius.to_bits()]
}

fn bits(values: &[f32]) -> impl Iterator<Item = u32> + '_ {
    values.iter().map(|v| v.to_bits())
}

/// Whether two meshes are the same bit for bit (floats by their bits, so
/// that -0 and 0 differ and a NaN equals itself).
fn same_mesh(a: &Mesh, b: &Mesh) -> bool {
    a.name == b.name
        && a.object_id == b.object_id
        && a.faces == b.faces
        && bits(&a.albedo).eq(bits(&b.albedo))
        && bits(&a.transform.to_cols_array()).eq(bits(&b.transform.to_cols_array()))
        && a.vertices.len() == b.vertices.len()
        && bits(a.vertices.as_flattened()).eq(bits(b.vertices.as_flattened()))
        && match (&a.normals, &b.normals) {
            (None, None) => true,
            (Some(x), Some(y)) => x.len() == y.len() && bits(x.as_flattened()).eq(bits(y.as_flattened())),
            _ => false,
        }
}

impl SceneGeometry {
    fn new(scene: &Scene) -> Result<Self> {
        Ok(Self {
            meshes: scene.meshes.clone(),
            prepared: scene.prepare_geometry()?,
            hash: OnceLock::new(),
            buffers: OnceLock::new(),
            corner_positions: OnceLock::new(),
            corner_hierarchy: OnceLock::new(),
            lights: Mutex::default(),
        })
    }

    fn matches(&self, scene: &Scene) -> bool {
        self.meshes.len() == scene.meshes.len() && self.meshes.iter().zip(&scene.meshes).all(|(a, b)| same_mesh(a, b))
    }

    /// What `light` derives from this geometry: kept, or new once `light`
    /// has passed its check against the geometry ([`Scene::check_light`]).
    fn light(&self, scene: &Scene) -> Result<Arc<LightGeometry>> {
        let key = light_key(&scene.light);
        let mut lights = self.lights.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(i) = lights.iter().position(|l| l.key == key) {
            let light = lights.remove(i);
            lights.push(light.clone());
            return Ok(light);
        }
        scene.check_light(&self.prepared)?;
        let light = Arc::new(LightGeometry { key, casters: OnceLock::new(), caster_points: OnceLock::new(), face_casters: OnceLock::new() });
        if lights.len() >= LIGHTS_KEPT {
            lights.remove(0);
        }
        lights.push(light.clone());
        Ok(light)
    }
}

/// The renderer's store: the last geometry rendered.
#[derive(Default)]
pub struct GeometryCache {
    last: Mutex<Option<Arc<SceneGeometry>>>,
}

/// A render's geometry and light, and whether the geometry was kept.
pub struct Prepared {
    pub geometry: Arc<SceneGeometry>,
    pub light: Arc<LightGeometry>,
    pub reused: bool,
}

impl GeometryCache {
    /// `scene`'s prepared geometry and light (checked as
    /// [`Scene::prepare`] checks them), kept from the last render when its
    /// meshes are the same.
    pub fn prepare(&self, scene: &Scene) -> Result<Prepared> {
        scene.check_light_and_ambient()?;
        let kept = self.last.lock().unwrap_or_else(|e| e.into_inner()).clone().filter(|g| g.matches(scene));
        let reused = kept.is_some();
        let geometry = match kept {
            Some(g) => g,
            None => {
                // The old geometry's buffers go back to the pool before the new one's are made.
                *self.last.lock().unwrap_or_else(|e| e.into_inner()) = None;
                let g = Arc::new(SceneGeometry::new(scene)?);
                *self.last.lock().unwrap_or_else(|e| e.into_inner()) = Some(g.clone());
                g
            }
        };
        let light = geometry.light(scene)?;
        Ok(Prepared { geometry, light, reused })
    }

    /// Forgets the kept geometry (its GPU buffers return to the pool once no
    /// render holds them).
    pub fn clear(&self) {
        *self.last.lock().unwrap_or_else(|e| e.into_inner()) = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat4;

    fn scene() -> Scene {
        crate::scene::tests::scene(crate::scene::tests::quad())
    }

    #[test]
    fn the_same_meshes_are_kept_and_any_change_prepares_afresh() {
        let cache = GeometryCache::default();
        let base = scene();
        let first = cache.prepare(&base).unwrap();
        assert!(!first.reused);
        assert!(cache.prepare(&base.clone()).unwrap().reused);
        type Change = (&'static str, Box<dyn Fn(&mut Scene)>);
        let changes: Vec<Change> = vec![
            ("vertex", Box::new(|s| s.meshes[0].vertices[1][1] = 1e-3)),
            ("negative zero", Box::new(|s| s.meshes[0].vertices[0][1] = -0.0)),
            ("face", Box::new(|s| s.meshes[0].faces[0] = [0, 1, 2])),
            ("normals", Box::new(|s| s.meshes[0].normals = Some(vec![[0.0, 1.0, 0.0]; 4]))),
            ("albedo", Box::new(|s| s.meshes[0].albedo[2] = 0.25)),
            ("object id", Box::new(|s| s.meshes[0].object_id = 3)),
            ("transform", Box::new(|s| s.meshes[0].transform = Mat4::from_translation(glam::Vec3::X))),
            ("name", Box::new(|s| s.meshes[0].name = "floor".into())),
            ("a second mesh", Box::new(|s| s.meshes.push(s.meshes[0].clone()))),
        ];
        for (what, change) in changes {
            let mut changed = base.clone();
            change(&mut changed);
            assert!(!cache.prepare(&changed).unwrap().reused, "{what}");
            assert!(!cache.prepare(&base).unwrap().reused, "{what}: back to the base");
        }
    }

    #[test]
    fn lights_are_kept_per_geometry_and_checked_once_each() {
        let cache = GeometryCache::default();
        let mut s = scene();
        let a = cache.prepare(&s).unwrap().light;
        s.light.radius = 0.25;
        let b = cache.prepare(&s).unwrap();
        assert!(b.reused && !Arc::ptr_eq(&a, &b.light));
        s.light.radius = 0.5;
        assert!(Arc::ptr_eq(&a, &cache.prepare(&s).unwrap().light));
        // A light touching the geometry is refused whether or not the geometry was kept.
        s.light.center = [0.0, 0.25, 0.0];
        let err = cache.prepare(&s).err().expect("the light touches the quad").to_string();
        assert!(err.contains("intersects mesh 'quad'"), "{err}");
        assert!(cache.prepare(&s).is_err());
        // The oldest lights go beyond LIGHTS_KEPT.
        s.light.center = [0.0, 2.0, 0.0];
        for i in 0..LIGHTS_KEPT {
            s.light.radius = 0.01 * (i + 1) as f32;
            cache.prepare(&s).unwrap();
        }
        s.light.radius = 0.5;
        assert!(!Arc::ptr_eq(&a, &cache.prepare(&s).unwrap().light));
    }

    #[test]
    fn bad_geometry_is_refused_and_not_kept() {
        let cache = GeometryCache::default();
        let mut s = scene();
        s.meshes[0].vertices[0][0] = f32::NAN;
        assert!(cache.prepare(&s).is_err());
        assert!(cache.prepare(&s).is_err());
        assert!(!cache.prepare(&scene()).unwrap().reused);
    }
}
