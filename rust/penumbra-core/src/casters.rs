//! Which triangles can cast a shadow on the scene (issue 30: no work spent on
//! what a scene does not need).
//!
//! A triangle hides part of the light from a point only if the segment from
//! the point to some point of the light crosses the triangle's plane. Where
//! the whole light sphere lies strictly on one side of that plane and every
//! point that could be shaded lies on the same side or on the plane, no such
//! segment crosses it (it can only touch the plane at a receiver lying in
//! it, which is the receiver's own surface), so the triangle hides nothing:
//! a floor under everything, the walls of a room lit from inside. The
//! light's raster passes skip those triangles.
//!
//! The points that could be shaded are every vertex of the scene (a
//! triangle's points are their combinations, so the least signed distance is
//! at a vertex), with one exception: a convex object (a connected surface,
//! [`Topology::components`], however many meshes or pieces it came in) hides
//! no light from its own surface that the receiver's horizon counts. A point
//! on a face receives light from the front of the face's plane (every
//! method's horizon term, with the face's own normal where the mesh has no
//! shading normals); where the front is the body's outside, the segment
//! leaves the body and cannot re-enter it; where the front is its inside
//! (a room's walls) and the light is inside, the segment stays inside. So the
//! faces of such an object are checked against the other objects' vertices
//! only: the top of a floor slab under everything casts nothing either.
//!
//! The checks are exact over the welded vertices, so the set left out is the
//! same however the scene is moved or turned and however its surfaces are
//! split, doubled or given as a soup. Larger objects that are not planar are
//! kept whole (their triangles cut through their own body); a planar one is
//! checked once.

use std::collections::HashMap;

use glam::DVec3;

use crate::scene::{PreparedScene, Scene};
use crate::topology::Topology;

/// Objects of at most this many faces are checked face by face (and for
/// convexity); larger ones only when planar.
const MAX_CHECKED_FACES: usize = 256;

/// The most vertex-plane tests one scene's check spends (a plane against
/// every vertex of the scene is one test per vertex); planes beyond it are
/// kept. 256 planes against 100k vertices is 2.6e7.
const MAX_TESTS: usize = 50_000_000;

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
/// and how many were left out. `scene` is what `prepared` was prepared from,
/// `topology` its connectivity across every mesh.
pub fn caster_indices(scene: &Scene, prepared: &PreparedScene, topology: &Topology, center: DVec3, radius: f64) -> Casters {
    let (lo, hi) = (prepared.bounds_min.as_dvec3(), prepared.bounds_max.as_dvec3());
    let slack = ON_PLANE * (hi - lo).max_element().max(f64::MIN_POSITIVE);
    // Each face's world corners, mesh and object, in the order of position_indices.
    let mut faces = Vec::with_capacity(prepared.triangle_count);
    let mut base = 0usize;
    for (m, mesh) in prepared.meshes.iter().enumerate() {
        for f in &mesh.faces {
            let object = topology.components[topology.weld[base + f[0] as usize] as usize];
            faces.push((f.map(|i| mesh.vertices[i as usize]), m, object));
        }
        base += mesh.vertices.len();
    }
    let mut objects: HashMap<u32, Vec<usize>> = HashMap::new();
    for (i, face) in faces.iter().enumerate() {
        objects.entry(face.2).or_default().push(i);
    }
    let mut order: Vec<_> = objects.into_iter().collect();
    order.sort_unstable_by_key(|(object, _)| *object);
    let mut tests = 0usize;
    // The plane (unit normal n through a) leaves the light strictly on one
    // side and no welded vertex (but those of `skip`, an object) beyond it
    // on that side.
    let mut separates = |n: DVec3, a: DVec3, skip: Option<u32>| {
        let s = n.dot(center - a);
        if s.abs() <= radius + slack || tests + topology.positions.len() > MAX_TESTS {
            return false;
        }
        tests += topology.positions.len();
        let n = n * s.signum();
        topology.positions.iter().zip(&topology.components).all(|(v, c)| Some(*c) == skip || n.dot(*v - a) >= -slack)
    };
    let mut skip = vec![false; faces.len()];
    for (object, members) in &order {
        let vertices: Vec<DVec3> = topology.positions.iter().zip(&topology.components).filter(|(_, c)| *c == object).map(|(v, _)| *v).collect();
        let plane = |i: usize| {
            let [a, b, c] = faces[i].0;
            (b - a).cross(c - a).try_normalize().map(|n| (n, a))
        };
        if members.len() > MAX_CHECKED_FACES {
            // A planar object: one plane for all its faces.
            let largest = members.iter().copied().max_by(|&i, &j| area2(&faces[i].0).total_cmp(&area2(&faces[j].0)));
            if let Some((n, a)) = largest.and_then(plane) {
                if vertices.iter().all(|v| n.dot(*v - a).abs() <= slack) && separates(n, a, None) {
                    members.iter().for_each(|&i| skip[i] = true);
                }
            }
            continue;
        }
        let flat = members.iter().all(|&i| scene.meshes.get(faces[i].1).is_some_and(|m| m.normals.is_none()));
        let own = flat && convex_own_light(members.iter().map(|&i| plane(i)), &vertices, center, slack);
        for &i in members {
            // A zero-area face draws nothing: keep it (its normal is undefined).
            skip[i] = plane(i).is_some_and(|(n, a)| separates(n, a, own.then_some(*object)));
        }
    }
    let (mut indices, mut culled) = (Vec::with_capacity(prepared.position_indices.len()), 0);
    let mut mesh_ranges = Vec::with_capacity(prepared.meshes.len());
    let mut triangles = prepared.position_indices.chunks_exact(3).zip(&skip);
    for mesh in &prepared.meshes {
        let start = indices.len() as u32;
        for (tri, &skip) in triangles.by_ref().take(mesh.faces.len()) {
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

/// Whether a body with these face planes and vertices is convex and lets no
/// light reach its own surface through itself: every face wound outward
/// (its vertices behind every face), or every face inward with the light's
/// centre in front of every face (inside the body).
fn convex_own_light(planes: impl Iterator<Item = Option<(DVec3, DVec3)>> + Clone, vertices: &[DVec3], center: DVec3, slack: f64) -> bool {
    let sides = |(n, a): (DVec3, DVec3)| vertices.iter().fold((0.0f64, 0.0f64), |(l, h), v| (l.min(n.dot(*v - a)), h.max(n.dot(*v - a))));
    let outward = planes.clone().flatten().all(|p| sides(p).1 <= slack);
    let inward = planes.flatten().all(|(n, a)| sides((n, a)).0 >= -slack && n.dot(center - a) > 0.0);
    outward || inward
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
        let topology = crate::silhouettes::SilhouetteCache::default().scene_topology(&p);
        let Casters { indices, mesh_ranges, culled } = caster_indices(
            &scene,
            &p,
            &topology,
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
        // The same faces as unturned: the floor and the block's bottom.
        assert_eq!(culled(vec![f, b], t([0.0, 3.0, 0.0]), 0.5), 2 + 2);
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

    #[test]
    fn a_slab_in_pieces_doubled_or_as_a_soup_is_left_out_as_a_whole_one_is() {
        let slab = cuboid("slab", [-4.0, -0.2, -4.0], [4.0, 0.0, 4.0], false);
        let light = [0.0, 3.0, 0.0];
        assert_eq!(culled(vec![slab.clone(), block()], light, 0.5), 12);
        // Six meshes of two faces each: welded into one object.
        let pieces: Vec<Mesh> = slab.faces.chunks(2).map(|f| mesh("piece", slab.vertices.clone(), f.to_vec())).collect();
        assert_eq!(culled([pieces, vec![block()]].concat(), light, 0.5), 12);
        // A soup: three vertices of its own per face.
        let soup_vertices = slab.faces.iter().flat_map(|f| f.map(|i| slab.vertices[i as usize])).collect();
        let soup = mesh("soup", soup_vertices, (0..12).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect());
        assert_eq!(culled(vec![soup, block()], light, 0.5), 12);
        // Doubled: both copies.
        assert_eq!(culled(vec![slab.clone(), slab, block()], light, 0.5), 24);
    }

    #[test]
    fn a_closed_room_lit_from_outside_keeps_its_ceiling() {
        // Inward faces with the light outside, above: no exemption for the
        // room's own surface, whose vertices count. The ceiling lies between
        // them and the light, and is kept; the walls and the floor have the
        // light and the whole room on one side.
        let room = cuboid("room", [-3.0, 0.0, -3.0], [3.0, 4.0, 3.0], true);
        assert_eq!(culled(vec![room], [0.0, 6.0, 0.0], 0.5), 10);
    }
}
