//! The scene model of SPEC section 3 and its validation.
//!
//! Everything a user hands in is checked here, before it reaches the GPU: a
//! malformed input is a typed [`Error`] naming the problem, never a panic or a
//! NaN image. [`Scene::prepare`] returns the world-space geometry the passes use.

use glam::{DMat4, DVec3, Mat4, Vec3};

use crate::error::{Error, Result};

/// A triangle mesh. Vertices are in object space; `transform` (affine) takes them
/// to world space. Faces are counter-clockwise when seen from their front side.
#[derive(Debug, Clone)]
pub struct Mesh {
    pub name: String,
    pub vertices: Vec<[f32; 3]>,
    pub faces: Vec<[u32; 3]>,
    /// Optional per-vertex shading normals (object space); face normals otherwise.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Diffuse reflectance, RGB in [0, 1].
    pub albedo: [f32; 3],
    /// Non-negative id written to the object-id image (-1 marks the background).
    pub object_id: i32,
    /// Object-to-world transform, column-major as glam stores it.
    pub transform: Mat4,
}

/// A sphere light (SPEC section 3). `intensity` is the point-light-equivalent
/// intensity I = L * pi * r^2 per RGB channel; storing I rather than the
/// radiance L keeps the radius-0 limit (a point light) well defined.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereLight {
    pub center: [f32; 3],
    pub radius: f32,
    pub intensity: [f32; 3],
}

impl SphereLight {
    /// Radiance L = I / (pi r^2), or `None` for a point light (radius 0).
    pub fn radiance(&self) -> Option<[f32; 3]> {
        (self.radius > 0.0).then(|| {
            let area = std::f32::consts::PI * self.radius * self.radius;
            self.intensity.map(|i| i / area)
        })
    }
}

/// A pinhole camera: `look_at(eye, target, up)` with a vertical field of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    pub up: [f32; 3],
    pub fov_y_degrees: f32,
    pub width: u32,
    pub height: u32,
}

/// Images larger than this many pixels are refused before any allocation.
pub const MAX_PIXELS: u64 = 8192 * 8192;

/// The largest coordinate magnitude a scene may have, in world units: every
/// vertex after its transform, the light's centre plus its radius, and the
/// camera's eye and target. The passes work in float32, which squares
/// distances (lengths, normalisations, the irradiance's 1/d^2): two points
/// within this range are less than 3.5e18 apart, whose square (1.2e37)
/// leaves float32's maximum (3.4e38) a margin of 28 for the products built
/// on it. Beyond about 1.8e19 a single squared coordinate overflows.
/// (`python benchmarks/stability.py --limits`: visibility unchanged with coordinates up
/// to 2e17, pvm's aside.)
pub const MAX_COORDINATE: f64 = 1e18;

/// The smallest extent (largest side of the geometry's bounding box, in world
/// units) a scene may have. Squared distances underflow float32 (smallest
/// normal 1.2e-38) near 1e-19. Measured by `python benchmarks/stability.py --limits` with
/// this bound set to 0: on the fixed box scene of the property tests, every
/// method's visibility (pvm's aside, see docs/stability.md) is unchanged down
/// to an extent of 4e-22 and wrong at 4e-23 (mean difference 0.02-0.04) and
/// 4e-24 (0.15-0.17). The bound leaves a margin of 400.
pub const MIN_EXTENT: f64 = 1e-18;

/// The error of a coordinate beyond [`MAX_COORDINATE`].
fn beyond_range(what: &str) -> String {
    format!(
        "{what} lies beyond the supported range of +-{MAX_COORDINATE:e} world units: \
         the GPU passes work in float32, whose squared distances overflow (float32 max 3.4e38) \
         near 1.8e19; scale the scene down"
    )
}

#[derive(Debug, Clone)]
pub struct Scene {
    pub meshes: Vec<Mesh>,
    pub light: SphereLight,
    /// Ambient term of the shading, `albedo * ambient` (SPEC section 3); 0 by default.
    pub ambient: [f32; 3],
}

/// World-space geometry ready for upload: one entry per triangle corner,
/// and the same triangles indexed for drawing.
#[derive(Debug, Clone)]
pub struct PreparedScene {
    pub corners: Vec<CornerVertex>,
    /// The triangles as the camera's G-buffer draws them: `surface_indices`
    /// (three per triangle, in the order of `corners`) into vertices shared
    /// by the faces of a mesh with vertex normals, and one per corner for a
    /// mesh shaded with face normals.
    pub surface_vertices: Vec<CornerVertex>,
    pub surface_indices: Vec<u32>,
    /// The triangles as the light's raster passes draw them: `position_indices`
    /// (three per triangle, in the same order) into every mesh's world vertices.
    pub positions: Vec<[f32; 3]>,
    pub position_indices: Vec<u32>,
    /// Per mesh: world-space vertices and faces, for the silhouette methods.
    pub meshes: Vec<PreparedMesh>,
    /// Per mesh: albedo and object id, indexed by `CornerVertex::mesh_index`.
    pub materials: Vec<([f32; 3], i32)>,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
    pub triangle_count: usize,
    /// Triangles whose area is zero to working precision; they draw nothing.
    pub degenerate_triangles: usize,
    /// [`Self::mesh_keys`], on first use (the scene is kept while its meshes
    /// are unchanged, so the silhouette caches hash them once, not per render).
    mesh_keys: std::sync::OnceLock<Vec<u64>>,
}

impl PreparedScene {
    /// Per mesh, a hash of its faces and its vertices' bits: what the
    /// silhouette caches know a mesh's geometry by.
    pub fn mesh_keys(&self) -> &[u64] {
        use std::hash::{Hash, Hasher};
        self.mesh_keys.get_or_init(|| {
            self.meshes
                .iter()
                .map(|mesh| {
                    let mut h = std::collections::hash_map::DefaultHasher::new();
                    mesh.faces.hash(&mut h);
                    mesh.vertices.len().hash(&mut h);
                    for v in &mesh.vertices {
                        v.to_array().map(f64::to_bits).hash(&mut h);
                    }
                    h.finish()
                })
                .collect()
        })
    }

    /// A hash of every mesh's geometry, in order ([`Self::mesh_keys`]).
    pub fn geometry_key(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        self.mesh_keys().hash(&mut h);
        h.finish()
    }
}

/// One mesh in world space, as [`Mesh::world_geometry`] checks and builds it.
struct WorldMesh {
    vertices: Vec<DVec3>,
    /// The faces, with their winding reversed where the transform mirrors
    /// (negative determinant), so front faces stay counter-clockwise in world space.
    faces: Vec<[u32; 3]>,
    /// Per face: the unit normal (zero for zero-area faces).
    face_normals: Vec<DVec3>,
    vertex_normals: Option<Vec<DVec3>>,
    degenerate: usize,
}

#[derive(Debug, Clone)]
pub struct PreparedMesh {
    pub name: String,
    pub vertices: Vec<DVec3>,
    pub faces: Vec<[u32; 3]>,
}

/// One triangle corner as the G-buffer and shadow-map passes read it.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CornerVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub mesh_index: u32,
}

fn finite3(v: &[f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite())
}

fn dvec(v: [f32; 3]) -> DVec3 {
    DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
}

impl Mesh {
    /// Checks the mesh on its own and returns its world-space geometry.
    fn world_geometry(&self) -> Result<WorldMesh> {
        let name = self.name.as_str();
        if self.vertices.is_empty() {
            return Err(Error::mesh(name, "has no vertices"));
        }
        if self.faces.is_empty() {
            return Err(Error::mesh(name, "has no faces"));
        }
        if let Some(i) = self.vertices.iter().position(|v| !finite3(v)) {
            return Err(Error::mesh(
                name,
                format!("vertex {i} has a NaN or infinite coordinate: {:?}", self.vertices[i]),
            ));
        }
        let n = self.vertices.len();
        if let Some((f, face)) = self
            .faces
            .iter()
            .enumerate()
            .find(|(_, face)| face.iter().any(|&i| i as usize >= n))
        {
            return Err(Error::mesh(
                name,
                format!("face {f} has index out of range {face:?}: the mesh has {n} vertices"),
            ));
        }
        if !finite3(&self.albedo) || self.albedo.iter().any(|&a| !(0.0..=1.0).contains(&a)) {
            return Err(Error::mesh(
                name,
                format!("albedo must be RGB in [0, 1], got {:?}", self.albedo),
            ));
        }
        if self.object_id < 0 {
            return Err(Error::mesh(
                name,
                format!("object_id must be >= 0 (-1 marks the background), got {}", self.object_id),
            ));
        }
        let m = self.transform.to_cols_array();
        if m.iter().any(|c| !c.is_finite()) {
            return Err(Error::mesh(name, "transform has a NaN or infinite entry"));
        }
        let transform = self.transform.as_dmat4();
        if transform.row(3) != glam::DVec4::new(0.0, 0.0, 0.0, 1.0) {
            return Err(Error::mesh(
                name,
                "transform must be affine (last row 0 0 0 1); projective transforms are not supported",
            ));
        }
        let det = transform.determinant();
        if !det.is_normal() {
            return Err(Error::mesh(name, format!("transform is singular (determinant {det})")));
        }
        let world: Vec<DVec3> = self
            .vertices
            .iter()
            .map(|&v| transform.transform_point3(dvec(v)))
            .collect();
        if let Some(i) = world.iter().position(|v| !v.is_finite() || v.abs().max_element() > MAX_COORDINATE) {
            let what = if self.transform == Mat4::IDENTITY { format!("vertex {i}") } else { format!("vertex {i} after the transform") };
            return Err(Error::mesh(name, beyond_range(&format!("{what} {:?}", world[i].to_array()))));
        }
        // A mirroring transform (negative determinant) turns counter-clockwise
        // faces clockwise in world space: reversing their winding keeps the
        // front side where the transform carries it, the side its inverse
        // transpose maps normals to (as vertex normals already are, below),
        // instead of shading the mesh's back (black) and swapping the front
        // and back faces the second-depth maps and the silhouettes read.
        let faces: Vec<[u32; 3]> = if det < 0.0 {
            self.faces.iter().map(|&[a, b, c]| [a, c, b]).collect()
        } else {
            self.faces.clone()
        };
        let normals = match &self.normals {
            None => None,
            Some(normals) => Some(world_normals(name, normals, n, &transform)?),
        };
        let mut degenerate = 0;
        let face_normals: Vec<DVec3> = faces
            .iter()
            .map(|f| {
                let (a, b, c) = (world[f[0] as usize], world[f[1] as usize], world[f[2] as usize]);
                let cross = (b - a).cross(c - a);
                // A face is degenerate when its area is negligible against its edge lengths
                // (collinear or repeated corners): its normal is undefined, and 0 is safe.
                let scale = (b - a).length_squared().max((c - a).length_squared());
                if cross.length_squared() <= 1e-24 * scale * scale || scale == 0.0 {
                    degenerate += 1;
                    DVec3::ZERO
                } else {
                    cross.normalize()
                }
            })
            .collect();
        if degenerate == faces.len() {
            return Err(Error::mesh(
                name,
                format!("all {degenerate} faces are degenerate (zero area)"),
            ));
        }
        Ok(WorldMesh { vertices: world, faces, face_normals, vertex_normals: normals, degenerate })
    }
}

fn world_normals(name: &str, normals: &[[f32; 3]], n: usize, transform: &DMat4) -> Result<Vec<DVec3>> {
    if normals.len() != n {
        return Err(Error::mesh(
            name,
            format!("has {} normals for {n} vertices", normals.len()),
        ));
    }
    let normal_matrix = transform.inverse().transpose();
    normals
        .iter()
        .enumerate()
        .map(|(i, &nv)| {
            let v = normal_matrix.transform_vector3(dvec(nv));
            let len = v.length();
            if !finite3(&nv) || !len.is_normal() {
                Err(Error::mesh(name, format!("normal {i} is zero, NaN or infinite: {nv:?}")))
            } else {
                Ok(v / len)
            }
        })
        .collect()
}

impl SphereLight {
    pub fn validate(&self) -> Result<()> {
        if !finite3(&self.center) {
            return Err(Error::InvalidLight(format!(
                "center must be finite, got {:?}",
                self.center
            )));
        }
        if !self.radius.is_finite() || self.radius < 0.0 {
            return Err(Error::InvalidLight(format!(
                "radius must be finite and >= 0, got {}",
                self.radius
            )));
        }
        if !finite3(&self.intensity) || self.intensity.iter().any(|&i| i < 0.0) {
            return Err(Error::InvalidLight(format!(
                "intensity must be finite and >= 0, got {:?}",
                self.intensity
            )));
        }
        if dvec(self.center).abs().max_element() + self.radius as f64 > MAX_COORDINATE {
            return Err(Error::InvalidLight(beyond_range(&format!(
                "the sphere of center {:?} and radius {}",
                self.center, self.radius
            ))));
        }
        Ok(())
    }
}

impl Camera {
    pub fn validate(&self) -> Result<()> {
        for (what, v) in [("eye", self.eye), ("target", self.target), ("up", self.up)] {
            if !finite3(&v) {
                return Err(Error::InvalidCamera(format!("{what} must be finite, got {v:?}")));
            }
        }
        for (what, v) in [("eye", self.eye), ("target", self.target)] {
            if dvec(v).abs().max_element() > MAX_COORDINATE {
                return Err(Error::InvalidCamera(beyond_range(&format!("{what} {v:?}"))));
            }
        }
        if self.width == 0 || self.height == 0 {
            return Err(Error::InvalidCamera(format!(
                "image size must be at least 1x1, got {}x{}",
                self.width, self.height
            )));
        }
        if self.width as u64 * self.height as u64 > MAX_PIXELS {
            return Err(Error::InvalidCamera(format!(
                "image of {}x{} exceeds the limit of {MAX_PIXELS} pixels",
                self.width, self.height
            )));
        }
        if !(self.fov_y_degrees > 0.0 && self.fov_y_degrees < 180.0) {
            return Err(Error::InvalidCamera(format!(
                "fov_y must be in (0, 180) degrees, got {}",
                self.fov_y_degrees
            )));
        }
        let forward = dvec(self.target) - dvec(self.eye);
        if forward.length_squared() == 0.0 {
            return Err(Error::InvalidCamera("eye and target coincide".into()));
        }
        let up = dvec(self.up);
        if up.length_squared() == 0.0 {
            return Err(Error::InvalidCamera("up vector is zero".into()));
        }
        let sin = forward.normalize().cross(up.normalize()).length();
        if sin < 1e-6 {
            return Err(Error::InvalidCamera(
                "up vector is parallel to the viewing direction".into(),
            ));
        }
        Ok(())
    }

    /// World-to-view (right-handed, looking down -z).
    pub fn view(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye.into(), self.target.into(), self.up.into())
    }

    /// View-to-clip for wgpu's [0, 1] depth range, with near and far planes fitted
    /// to an axis-aligned box so depth precision is spent on the scene.
    pub fn projection(&self, bounds_min: Vec3, bounds_max: Vec3) -> (Mat4, f32, f32) {
        let view = self.view();
        let mut z_min = f32::INFINITY;
        let mut z_max = 0.0f32;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { bounds_min.x } else { bounds_max.x },
                if i & 2 == 0 { bounds_min.y } else { bounds_max.y },
                if i & 4 == 0 { bounds_min.z } else { bounds_max.z },
            );
            let depth = -view.transform_point3(corner).z;
            z_min = z_min.min(depth);
            z_max = z_max.max(depth);
        }
        // The scene is wholly behind the camera when z_max <= 0: any positive
        // far works. (No absolute floor otherwise: a scene 1e-7 across has
        // depths of 1e-6.)
        let far = if z_max > 0.0 { z_max * 1.01 } else { 1.0 };
        let near = (z_min * 0.99).max(far * 1e-5);
        let aspect = self.width as f32 / self.height as f32;
        (
            // WebGPU shares Direct3D's clip conventions: y up, depth in [0, 1].
            glam::camera::rh::proj::directx::perspective(self.fov_y_degrees.to_radians(), aspect, near, far),
            near,
            far,
        )
    }
}

impl Scene {
    /// Validates the whole scene and builds its world-space geometry.
    pub fn prepare(&self) -> Result<PreparedScene> {
        self.check_light_and_ambient()?;
        let prepared = self.prepare_geometry()?;
        self.check_light(&prepared)?;
        Ok(prepared)
    }

    /// The light's own parameters and the ambient term (the checks of
    /// [`Self::prepare`] that need no geometry).
    pub fn check_light_and_ambient(&self) -> Result<()> {
        self.light.validate()?;
        if !finite3(&self.ambient) || self.ambient.iter().any(|&a| a < 0.0) {
            return Err(Error::InvalidScene(format!(
                "ambient must be finite and >= 0, got {:?}",
                self.ambient
            )));
        }
        Ok(())
    }

    /// That no surface of `prepared` (this scene's geometry) lies within the
    /// light's radius, nor within float32 precision of it.
    pub fn check_light(&self, prepared: &PreparedScene) -> Result<()> {
        let light_center = dvec(self.light.center);
        let light_radius = self.light.radius as f64;
        for mesh in &prepared.meshes {
            for (f, face) in mesh.faces.iter().enumerate() {
                let tri = face.map(|i| mesh.vertices[i as usize]);
                let closest = closest_point_on_triangle(light_center, tri);
                let distance = (closest - light_center).length();
                // A light touching geometry has no defined irradiance there; a point light
                // must lie strictly off every surface. The passes see these points in
                // float32, so "touching" is closer than float32's relative precision of
                // the coordinates involved (at most two steps of the largest): relative
                // to their magnitude, with no absolute floor, so a scene 1e-7 across or
                // 1e7 from the origin is judged as it is at scale 1.
                let magnitude = light_center.abs().max_element().max(closest.abs().max_element()).max(light_radius);
                let tolerance = f32::EPSILON as f64 * magnitude;
                if distance <= light_radius {
                    return Err(Error::InvalidScene(format!(
                        "the light (center {:?}, radius {}) intersects mesh '{}' at face {f}",
                        self.light.center, self.light.radius, mesh.name
                    )));
                }
                if distance <= light_radius + tolerance {
                    return Err(Error::InvalidScene(format!(
                        "the light (center {:?}, radius {}) is within float32 precision ({tolerance:.3e} \
                         world units at coordinates of {magnitude:.3e}) of mesh '{}' at face {f}: \
                         nearer than the coordinates can resolve (move the light away, or the scene \
                         nearer the origin)",
                        self.light.center, self.light.radius, mesh.name
                    )));
                }
            }
        }
        Ok(())
    }

    /// The world-space geometry of [`Self::prepare`], without the light's
    /// checks: what the renderer keeps while the meshes are unchanged
    /// (`geometry_cache.rs`).
    pub fn prepare_geometry(&self) -> Result<PreparedScene> {
        if self.meshes.is_empty() {
            return Err(Error::InvalidScene("has no meshes".into()));
        }
        let mut corners = Vec::new();
        let (mut surface_vertices, mut surface_indices) = (Vec::new(), Vec::new());
        let (mut positions, mut position_indices) = (Vec::new(), Vec::new());
        let mut meshes = Vec::with_capacity(self.meshes.len());
        let mut materials = Vec::with_capacity(self.meshes.len());
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        let mut degenerate_triangles = 0;
        for (mesh_index, mesh) in self.meshes.iter().enumerate() {
            let WorldMesh { vertices: world, faces, face_normals, vertex_normals, degenerate } = mesh.world_geometry()?;
            degenerate_triangles += degenerate;
            for v in &world {
                lo = lo.min(*v);
                hi = hi.max(*v);
            }
            // Indices are u32: the renderer refuses scenes of more corners than that.
            let position_base = positions.len() as u32;
            positions.extend(world.iter().map(|v| v.as_vec3().to_array()));
            let surface_base = surface_vertices.len() as u32;
            if let Some(normals) = &vertex_normals {
                surface_vertices.extend(world.iter().zip(normals).map(|(v, n)| CornerVertex {
                    position: v.as_vec3().into(),
                    normal: n.as_vec3().into(),
                    mesh_index: mesh_index as u32,
                }));
            }
            for (f, face) in faces.iter().enumerate() {
                let tri = face.map(|i| world[i as usize]);
                for (corner, &vi) in face.iter().enumerate() {
                    let normal = match &vertex_normals {
                        Some(normals) => normals[vi as usize],
                        None => face_normals[f],
                    };
                    let vertex = CornerVertex {
                        position: tri[corner].as_vec3().into(),
                        normal: normal.as_vec3().into(),
                        mesh_index: mesh_index as u32,
                    };
                    corners.push(vertex);
                    position_indices.push(position_base + vi);
                    if vertex_normals.is_some() {
                        surface_indices.push(surface_base + vi);
                    } else {
                        surface_indices.push(surface_vertices.len() as u32);
                        surface_vertices.push(vertex);
                    }
                }
            }
            materials.push((mesh.albedo, mesh.object_id));
            meshes.push(PreparedMesh { name: mesh.name.clone(), vertices: world, faces });
        }
        let extent = (hi - lo).max_element();
        if extent < MIN_EXTENT {
            return Err(Error::InvalidScene(format!(
                "the geometry spans only {extent:e} world units, below the supported {MIN_EXTENT:e}: \
                 the GPU passes work in float32, whose squared distances underflow (smallest \
                 normal 1.2e-38) near 1e-19; scale the scene up"
            )));
        }
        Ok(PreparedScene {
            triangle_count: corners.len() / 3,
            corners,
            surface_vertices,
            surface_indices,
            positions,
            position_indices,
            meshes,
            materials,
            bounds_min: lo.as_vec3(),
            bounds_max: hi.as_vec3(),
            degenerate_triangles,
            mesh_keys: Default::default(),
        })
    }
}

/// Closest point to `p` on triangle `t` (Ericson, Real-Time Collision Detection 5.1.5).
/// Works for degenerate triangles too: every division is guarded by its region test.
pub fn closest_point_on_triangle(p: DVec3, t: [DVec3; 3]) -> DVec3 {
    let [a, b, c] = t;
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        // d1 - d3 = |ab|^2 > 0 here because d1 >= 0 >= d3 and not both zero.
        let denom = d1 - d3;
        return if denom > 0.0 { a + ab * (d1 / denom) } else { a };
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let denom = d2 - d6;
        return if denom > 0.0 { a + ac * (d2 / denom) } else { a };
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let denom = (d4 - d3) + (d5 - d6);
        return if denom > 0.0 { b + (c - b) * ((d4 - d3) / denom) } else { b };
    }
    let sum = va + vb + vc;
    if sum <= 0.0 {
        // Degenerate triangle whose regions all failed: fall back to the nearest corner.
        return *[a, b, c]
            .iter()
            .min_by(|x, y| (p - **x).length_squared().total_cmp(&(p - **y).length_squared()))
            .unwrap_or(&a);
    }
    let v = vb / sum;
    let w = vc / sum;
    a + ab * v + ac * w
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A 2 x 2 quad at y = 0 (also the geometry cache's tests').
    pub(crate) fn quad() -> Mesh {
        Mesh {
            name: "quad".into(),
            vertices: vec![[-1.0, 0.0, -1.0], [1.0, 0.0, -1.0], [1.0, 0.0, 1.0], [-1.0, 0.0, 1.0]],
            faces: vec![[0, 2, 1], [0, 3, 2]],
            normals: None,
            albedo: [0.5; 3],
            object_id: 0,
            transform: Mat4::IDENTITY,
        }
    }

    /// `mesh` under a light of radius 0.5, 2 above the origin.
    pub(crate) fn scene(mesh: Mesh) -> Scene {
        Scene {
            meshes: vec![mesh],
            light: SphereLight { center: [0.0, 2.0, 0.0], radius: 0.5, intensity: [1.0; 3] },
            ambient: [0.0; 3],
        }
    }

    #[test]
    fn geometry_keys_follow_the_meshes_content() {
        let base = scene(quad()).prepare().unwrap();
        assert_eq!(base.mesh_keys(), scene(quad()).prepare().unwrap().mesh_keys());
        assert_eq!(base.geometry_key(), scene(quad()).prepare().unwrap().geometry_key());
        let mut moved = quad();
        moved.vertices[0][1] = 1e-6;
        let mut rewound = quad();
        rewound.faces[0].swap(1, 2);
        for (what, mesh) in [("a vertex", moved), ("a face", rewound)] {
            let other = scene(mesh).prepare().unwrap();
            assert_ne!(base.geometry_key(), other.geometry_key(), "{what}");
        }
    }

    #[test]
    fn quad_faces_point_up() {
        let prepared = scene(quad()).prepare().unwrap();
        assert_eq!(prepared.triangle_count, 2);
        for c in &prepared.corners {
            assert_eq!(c.normal, [0.0, 1.0, 0.0]);
        }
    }

    #[test]
    fn bad_meshes_are_named() {
        let mut m = quad();
        m.vertices[2][1] = f32::NAN;
        let err = scene(m).prepare().unwrap_err();
        assert!(matches!(&err, Error::InvalidMesh { mesh, message } if mesh == "quad" && message.contains("vertex 2")), "{err}");
        let mut m = quad();
        m.faces[1][2] = 9;
        assert!(scene(m).prepare().unwrap_err().to_string().contains("out of range"));
        let mut m = quad();
        m.faces = vec![[0, 1, 1]];
        assert!(scene(m).prepare().unwrap_err().to_string().contains("degenerate"));
        let mut m = quad();
        m.transform = Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0));
        assert!(scene(m).prepare().unwrap_err().to_string().contains("singular"));
    }

    #[test]
    fn light_touching_geometry_is_refused() {
        let mut s = scene(quad());
        s.light.center = [0.3, 0.4, 0.2];
        assert!(matches!(s.prepare(), Err(Error::InvalidScene(_))));
        s.light.center = [3.0, 0.0, 0.0];
        s.light.radius = 0.0;
        assert!(s.prepare().is_ok(), "a point light beside the quad's plane is fine");
        s.light.center = [0.5, 0.0, 0.5];
        assert!(matches!(s.prepare(), Err(Error::InvalidScene(_))), "a point light on the quad");
    }

    #[test]
    fn mirrored_meshes_keep_their_front_faces() {
        let mut m = quad();
        m.transform = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let prepared = scene(m).prepare().unwrap();
        for c in &prepared.corners {
            assert_eq!(c.normal, [0.0, 1.0, 0.0], "the mirrored quad still faces up");
        }
        assert_eq!(prepared.meshes[0].faces, vec![[0, 1, 2], [0, 2, 3]], "winding reversed");
        let mut m = quad();
        m.transform = Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
        assert_eq!(scene(m).prepare().unwrap().meshes[0].faces, quad().faces, "no mirror, no change");
    }

    #[test]
    fn light_clearance_is_relative_to_the_coordinates() {
        for (scale, offset) in [(1e-7f32, 0.0f32), (1.0, 1e7), (1e10, 0.0), (1e-7, 1e-6)] {
            let mut m = quad();
            m.transform = Mat4::from_translation(Vec3::splat(offset)) * Mat4::from_scale(Vec3::splat(scale));
            let mut s = scene(m);
            s.light.center = [offset, 2.0 * scale + offset, offset];
            s.light.radius = 0.5 * scale;
            assert!(s.prepare().is_ok(), "scale {scale}, offset {offset}: {:?}", s.prepare().err());
            s.light.center[1] = 0.4 * scale + offset;
            assert!(matches!(s.prepare(), Err(Error::InvalidScene(_))), "scale {scale}, offset {offset}: the light touches the quad");
        }
    }

    #[test]
    fn a_light_within_float32_precision_of_a_surface_is_named_as_such() {
        let mut m = quad();
        m.transform = Mat4::from_translation(Vec3::splat(1e7));
        let mut s = scene(m);
        s.light = SphereLight { center: [1e7, 1e7 + 1.0, 1e7], radius: 0.0, intensity: [1.0; 3] };
        let err = s.prepare().unwrap_err().to_string();
        assert!(err.contains("within float32 precision") && !err.contains("intersects"), "{err}");
    }

    #[test]
    fn scenes_below_the_smallest_extent_are_refused() {
        let mut m = quad();
        m.transform = Mat4::from_scale(Vec3::splat(1e-20));
        let mut s = scene(m);
        s.light.center = [0.0, 2e-20, 0.0];
        s.light.radius = 0.0;
        let err = s.prepare().unwrap_err().to_string();
        assert!(err.contains("spans only") && err.contains("scale the scene up"), "{err}");
    }

    #[test]
    fn coordinates_beyond_the_supported_range_are_named() {
        let mut m = quad();
        m.transform = Mat4::from_scale(Vec3::splat(1e20));
        let err = scene(m).prepare().unwrap_err().to_string();
        assert!(err.contains("vertex 0 after the transform") && err.contains("float32"), "{err}");
        let mut s = scene(quad());
        s.light.center = [0.0, 3e38, 0.0];
        let err = s.prepare().unwrap_err();
        assert!(matches!(&err, Error::InvalidLight(m) if m.contains("supported range")), "{err}");
        let camera = Camera { eye: [0.0, 2e18, 0.0], target: [0.0; 3], up: [1.0, 0.0, 0.0], fov_y_degrees: 45.0, width: 8, height: 8 };
        assert!(matches!(camera.validate(), Err(Error::InvalidCamera(m)) if m.contains("eye")));
    }

    #[test]
    fn closest_point_handles_degenerate_triangles() {
        let p = DVec3::new(0.0, 1.0, 0.0);
        let a = DVec3::new(1.0, 0.0, 0.0);
        let q = closest_point_on_triangle(p, [a, a, a]);
        assert_eq!(q, a);
        let q = closest_point_on_triangle(p, [a, DVec3::new(-1.0, 0.0, 0.0), DVec3::ZERO]);
        assert!(q.is_finite() && (q - DVec3::ZERO).length() < 1e-12, "{q}");
    }
}
