//! Which triangles can cast a shadow on the scene (issue 30: no work spent on
//! what a scene does not need).
//!
//! A triangle hides part of the light from a point only if the segment from
//! the point to some point of the light crosses the triangle's plane. Where
//! the whole light sphere lies strictly on one side of that plane and every
//! point of the scene on the same side or on the plane, no such segment
//! crosses it (it can only touch the plane at a receiver lying in it, which
//! is the receiver's own surface), so the triangle hides nothing from any
//! point of the scene: a floor under everything, the walls of a room lit from
//! inside. The light's raster passes skip those triangles. Their depth never
//! decides a shadow test: a receiver on them is as near the light as they are.
//!
//! The scene's side is checked against its bounding box's corners (a
//! superset of the scene), and, for a planar mesh whose plane the box's
//! corners leave undecided (a floor under a turned scene), against every
//! vertex of the scene: so a floor is skipped however the scene is turned.
//! A convex mesh (a floor slab, a box) hides no light from its own surface,
//! so its faces are checked against the other meshes' box only: the top of a
//! slab under everything casts nothing either.

use glam::DVec3;

use crate::scene::{PreparedScene, Scene};

/// The planar meshes whose plane is checked against every vertex of the
/// scene (each check is one pass over the vertices); beyond these, meshes
/// are checked per triangle against the bounding box only.
const MAX_EXACT_PLANES: usize = 64;

/// The slack, relative to the scene's extent, within which a point counts as
/// lying on a plane: far below any shadow map's bias, which already lets a
/// receiver that near a surface see past it.
const ON_PLANE: f64 = 1e-6;

/// The triangles that can cast a shadow, as [`caster_indices`] finds them.
pub struct Casters {
    /// `prepared.position_indices` without those that cannot, in mesh order.
    pub indices: Vec<u32>,
    /// Per mesh: its triangles' range in `indices`, three per triangle.
    pub mesh_ranges: Vec<std::ops::Range<u32>>,
    /// How many triangles were left out.
    pub culled: usize,
}

/// `prepared.position_indices` without the triangles that can hide no part of
/// the light (centre `center`, radius `radius`) from any point of the scene,
/// and how many were left out. `scene` is what `prepared` was prepared from.
pub fn caster_indices(
    scene: &Scene,
    prepared: &PreparedScene,
    center: DVec3,
    radius: f64,
) -> Casters {
    let (lo, hi) = (
        prepared.bounds_min.as_dvec3(),
        prepared.bounds_max.as_dvec3(),
    );
    let slack = ON_PLANE * (hi - lo).max_element().max(f64::MIN_POSITIVE);
    // The plane (unit normal n through a) leaves the light strictly on one
    // side and `lowest(n, a)`, the least signed distance on that side of the
    // points it could shade, above -slack: none lies beyond it.
    let separates = |n: DVec3, a: DVec3, lowest: &dyn Fn(DVec3, DVec3) -> f64| {
        let s = n.dot(center - a);
        if s.abs() <= radius + slack {
            return false;
        }
        lowest(n * s.signum(), a) >= -slack
    };
    // Over a box: the corner least along n (+infinity for an empty box).
    let box_lowest = |(lo, hi): (DVec3, DVec3)| {
        move |n: DVec3, a: DVec3| {
            if lo.x > hi.x {
                f64::INFINITY
            } else {
                n.dot((lo + hi) * 0.5 - a) - n.abs().dot((hi - lo) * 0.5)
            }
        }
    };
    let every_vertex_lowest = |n: DVec3, a: DVec3| {
        prepared
            .meshes
            .iter()
            .flat_map(|m| m.vertices.iter())
            .fold(f64::INFINITY, |low, v| low.min(n.dot(*v - a)))
    };
    let bounds: Vec<(DVec3, DVec3)> = prepared
        .meshes
        .iter()
        .map(|m| bounds_of(&m.vertices))
        .collect();
    let whole = (lo, hi);
    let mut exact_planes = 0;
    let (mut indices, mut culled) = (Vec::with_capacity(prepared.position_indices.len()), 0);
    let mut triangles = prepared.position_indices.chunks_exact(3);
    let mut mesh_ranges = Vec::with_capacity(prepared.meshes.len());
    for (m, mesh) in prepared.meshes.iter().enumerate() {
        let start = indices.len() as u32;
        let plane = plane_of(&mesh.vertices, &mesh.faces, slack);
        let mesh_separates = plane
            .filter(|_| exact_planes < MAX_EXACT_PLANES)
            .map(|(n, a)| {
                exact_planes += 1;
                separates(n, a, &every_vertex_lowest)
            });
        // A convex mesh hides no light from its own surface: a point on a
        // face receives light only from beyond the face's plane (the horizon
        // term of every method, with the face's own normal where the mesh has
        // no shading normals), where no part of the body lies. Its faces are
        // checked against the rest.
        let flat = scene
            .meshes
            .get(m)
            .is_some_and(|mesh| mesh.normals.is_none());
        let shaded = if flat && is_convex(&mesh.vertices, &mesh.faces, slack) {
            bounds
                .iter()
                .enumerate()
                .filter(|(k, _)| *k != m)
                .fold(empty_box(), |b, (_, o)| union(b, *o))
        } else {
            whole
        };
        let lowest = box_lowest(shaded);
        for face in &mesh.faces {
            let tri = triangles.next().expect("one index triple per face");
            let skip = mesh_separates.unwrap_or_else(|| {
                let [a, b, c] = face.map(|i| mesh.vertices[i as usize]);
                // A zero-area face draws nothing: keep it (its normal is undefined).
                let n = (b - a).cross(c - a).try_normalize();
                n.is_some_and(|n| separates(n, a, &lowest))
            });
            if skip {
                culled += 1;
            } else {
                indices.extend_from_slice(tri);
            }
        }
        mesh_ranges.push(start..indices.len() as u32);
    }
    Casters { indices, mesh_ranges, culled }
}

/// Meshes of at most this many faces are checked for convexity (each face's
/// plane against every vertex); larger ones count as not convex.
const MAX_CONVEX_FACES: usize = 256;

/// Whether every vertex lies on one side of (or within `slack` of) each
/// face's plane, whichever way the faces wind: a convex body or a planar piece.
fn is_convex(vertices: &[DVec3], faces: &[[u32; 3]], slack: f64) -> bool {
    faces.len() <= MAX_CONVEX_FACES
        && faces.iter().all(|f| {
            let [a, b, c] = f.map(|i| vertices[i as usize]);
            let Some(n) = (b - a).cross(c - a).try_normalize() else {
                return true;
            };
            let (low, high) = vertices.iter().fold((0.0f64, 0.0f64), |(l, h), v| {
                let s = n.dot(*v - a);
                (l.min(s), h.max(s))
            });
            low >= -slack || high <= slack
        })
}

fn bounds_of(vertices: &[DVec3]) -> (DVec3, DVec3) {
    vertices
        .iter()
        .fold(empty_box(), |(lo, hi), v| (lo.min(*v), hi.max(*v)))
}

fn empty_box() -> (DVec3, DVec3) {
    (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY))
}

fn union(a: (DVec3, DVec3), b: (DVec3, DVec3)) -> (DVec3, DVec3) {
    (a.0.min(b.0), a.1.max(b.1))
}

/// The plane (unit normal, a point) that every vertex of a mesh lies within
/// `slack` of, if there is one: the plane of its largest face.
fn plane_of(vertices: &[DVec3], faces: &[[u32; 3]], slack: f64) -> Option<(DVec3, DVec3)> {
    let largest = faces
        .iter()
        .map(|f| f.map(|i| vertices[i as usize]))
        .max_by(|p, q| area2(p).total_cmp(&area2(q)))?;
    let n = (largest[1] - largest[0])
        .cross(largest[2] - largest[0])
        .try_normalize()?;
    let a = largest[0];
    vertices
        .iter()
        .all(|v| n.dot(*v - a).abs() <= slack)
        .then_some((n, a))
}

fn area2(t: &[DVec3; 3]) -> f64 {
    (t[1] - t[0]).cross(t[2] - t[0]).length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Mesh, SphereLight};
    use glam::Mat4;

    fn mesh(name: &str, vertices: Vec<[f32; 3]>, faces: Vec<[u32; 3]>) -> Mesh {
        Mesh {
            name: name.into(),
            vertices,
            faces,
            normals: None,
            albedo: [0.5; 3],
            object_id: 0,
            transform: Mat4::IDENTITY,
        }
    }

    fn floor() -> Mesh {
        mesh(
            "floor",
            vec![
                [-4.0, 0.0, -4.0],
                [-4.0, 0.0, 4.0],
                [4.0, 0.0, 4.0],
                [4.0, 0.0, -4.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    /// A box from `lo` to `hi`, faces out (`inward`: faces in, a room).
    fn cuboid(name: &str, lo: [f32; 3], hi: [f32; 3], inward: bool) -> Mesh {
        let v = (0..8)
            .map(|i| {
                [
                    [lo[0], hi[0]][i & 1],
                    [lo[1], hi[1]][(i >> 1) & 1],
                    [lo[2], hi[2]][(i >> 2) & 1],
                ]
            })
            .collect();
        let mut f = vec![
            [0, 1, 5],
            [0, 5, 4],
            [2, 6, 7],
            [2, 7, 3],
            [0, 4, 6],
            [0, 6, 2],
            [1, 3, 7],
            [1, 7, 5],
            [0, 2, 3],
            [0, 3, 1],
            [4, 5, 7],
            [4, 7, 6],
        ];
        if inward {
            f.iter_mut().for_each(|t: &mut [u32; 3]| t.swap(1, 2));
        }
        mesh(name, v, f)
    }

    fn block() -> Mesh {
        cuboid("block", [-0.5, 0.0, -0.5], [0.5, 1.0, 0.5], false)
    }

    fn culled(meshes: Vec<Mesh>, center: [f32; 3], radius: f32) -> usize {
        let light = SphereLight {
            center,
            radius,
            intensity: [1.0; 3],
        };
        let scene = Scene {
            meshes,
            light,
            ambient: [0.0; 3],
        };
        let p = scene.prepare().unwrap();
        let Casters { indices, mesh_ranges, culled } = caster_indices(
            &scene,
            &p,
            DVec3::from(center.map(f64::from)),
            radius as f64,
        );
        assert_eq!(indices.len() + 3 * culled, p.position_indices.len());
        // The ranges tile the list in mesh order.
        assert_eq!(mesh_ranges.len(), p.meshes.len());
        assert!(mesh_ranges.windows(2).all(|w| w[0].end == w[1].start));
        assert_eq!((mesh_ranges[0].start, mesh_ranges.last().unwrap().end), (0, indices.len() as u32));
        culled
    }

    #[test]
    fn a_floor_or_slab_under_everything_casts_nothing() {
        // The block's bottom lies in the floor's plane, with the whole scene
        // on the light's side: it hides nothing either. Its top and sides
        // shade the floor.
        assert_eq!(culled(vec![floor(), block()], [0.0, 3.0, 0.0], 0.5), 2 + 2);
        // A slab under the block is convex: its top hides nothing from the
        // block, nor from the slab's own sides. All its faces are left out;
        // the block's bottom is kept (the slab's box reaches below its plane).
        let slab = cuboid("slab", [-4.0, -0.2, -4.0], [4.0, 0.0, 4.0], false);
        assert_eq!(
            culled(vec![slab.clone(), block()], [0.0, 3.0, 0.0], 0.5),
            12
        );
        // With shading normals the slab is not taken as convex (its shading
        // horizon is not its faces'): its top shades its sides, and is kept.
        let mut smooth = slab;
        smooth.normals = Some(smooth.vertices.iter().map(|_| [0.0, 1.0, 0.0]).collect());
        assert_eq!(culled(vec![smooth, block()], [0.0, 3.0, 0.0], 0.5), 10);
    }

    #[test]
    fn a_floor_with_geometry_below_it_is_kept() {
        let below = cuboid("below", [-0.5, -2.0, -0.5], [0.5, -1.0, 0.5], false);
        // The lower box's bottom and top are the only faces left out: its
        // top is under the floor, which it hides nothing from.
        assert_eq!(culled(vec![floor(), below], [0.0, 3.0, 0.0], 0.5), 2 + 2);
    }

    #[test]
    fn a_plane_through_the_light_sphere_is_kept() {
        // A wall whose plane passes within the light's radius of its centre;
        // the floor is still skipped.
        let wall = mesh(
            "wall",
            vec![
                [2.0, 0.0, -4.0],
                [2.0, 2.0, -4.0],
                [2.0, 2.0, 4.0],
                [2.0, 0.0, 4.0],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        assert_eq!(culled(vec![floor(), wall], [1.8, 3.0, 0.0], 0.5), 2);
    }

    #[test]
    fn a_floor_is_skipped_however_the_scene_is_turned() {
        let turn = glam::DQuat::from_euler(glam::EulerRot::XYZ, 0.5, 0.3, 0.2);
        let t = |p: [f32; 3]| {
            turn.mul_vec3(DVec3::from(p.map(f64::from)))
                .as_vec3()
                .to_array()
        };
        let (mut f, mut b) = (floor(), block());
        f.vertices = f.vertices.iter().map(|&p| t(p)).collect();
        b.vertices = b.vertices.iter().map(|&p| t(p)).collect();
        // The box's corners leave both undecided: the floor's plane is checked
        // against every vertex, the block's faces against the floor's box.
        assert_eq!(culled(vec![f, b], t([0.0, 3.0, 0.0]), 0.5), 2);
    }

    #[test]
    fn the_walls_of_a_room_lit_from_inside_cast_nothing() {
        let room = cuboid("room", [-3.0, 0.0, -3.0], [3.0, 4.0, 3.0], true);
        // Every wall against the other meshes' box (the room is convex
        // whichever way it winds), and the block's bottom.
        assert_eq!(culled(vec![room, block()], [1.0, 3.0, 0.5], 0.3), 12 + 2);
    }

    #[test]
    fn a_degenerate_face_is_kept() {
        let mut b = block();
        // Corner 0, the block's centre and corner 7 are collinear.
        b.vertices.push([0.0, 0.5, 0.0]);
        b.faces.push([0, 8, 7]);
        assert_eq!(culled(vec![floor(), b], [0.0, 3.0, 0.0], 0.5), 2 + 2);
    }
}
