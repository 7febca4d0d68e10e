//! The geometry of PVMF's penumbra volume mask (Cournia 5.1): per
//! silhouette edge on its own, an overestimated volume of two
//! quadrilaterals from the edge's end points moved towards the light (s_e)
//! and extruded with offsets along the edge and its plane normal. CPU side;
//! the method's mask pass renders what this builds.

use glam::DVec3;

use crate::silhouettes::SilhouetteEdge;

/// Scale of the extrusion offsets e and n in 5.1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Offsets {
    /// Unit vectors, as in the paper.
    Unit,
    /// Scaled by the light's radius.
    Radius,
}

/// One corner of a mask quadrilateral with its edge's distance d_e.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MaskVertex {
    pub position: [f32; 3],
    /// d_e of 5.1, the same on every corner (the mask pass reads it flat).
    pub d_e: f32,
    /// With repair "distance": the distance from the light of the edge's end
    /// this corner comes from, interpolated across the quadrilateral; 0 without.
    pub d_local: f32,
}

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MaskStats {
    /// Silhouette edges, end-on and hidden ones, connectivity.
    pub silhouette: crate::silhouettes::SilhouetteStats,
    /// Quadrilaterals rendered (two per edge: outer and inner).
    pub mask_quads: usize,
}

/// The overestimated volume of one silhouette edge `a -> b` (5.1), as its
/// outer and inner quadrilaterals, extruded `reach` from the moved points.
/// Edges are oriented as `silhouette` leaves them: the hard-shadow normal
/// (b - a) x (a - l) points away from the occluder, which is -n of the paper
/// (n = v x e with e0 = a, e1 = b).
fn edge_volume(e: &SilhouetteEdge, l: DVec3, r: f64, s_e: f64, offsets: Offsets, reach: f64) -> Option<[[DVec3; 4]; 2]> {
    let (d0, d1) = ((e.a - l).length(), (e.b - l).length());
    // No geometry touches the light (scene validation): d0, d1 > r >= 0.
    let d_e = d0.min(d1);
    // Both points move towards the light by the same distance, d_e s_e <= d0, d1.
    let (dir0, dir1) = ((e.a - l) / d0, (e.b - l) / d1);
    let e0 = e.a - dir0 * (d_e * s_e);
    let e1 = e.b - dir1 * (d_e * s_e);
    let along = (e1 - e0).normalize_or_zero();
    // v is the direction of e0 - l, which is also that of the moved point (the
    // move keeps its direction; with s_e = 1 the nearer point lands on l,
    // where its own direction would be undefined).
    let cross = along.cross(dir0);
    // An edge pointing at the light (or of zero length) has no hard-shadow plane.
    if cross.length() <= 1e-9 {
        return None;
    }
    let n = cross.normalize();
    let scale = match offsets {
        Offsets::Unit => 1.0,
        Offsets::Radius => r,
    };
    // The four extrusion vectors of 5.1 (v0-, v1-, v0+, v1+), with n the
    // paper's -n. The text adds +e at e0 and -e at e1, with e pointing from
    // e0 to e1: that would tilt both ends of the volume inwards, against the
    // overestimation the section asks for (and would cross the quads of long
    // edges far from the light). We take the ends outwards: -e at e0, +e at e1.
    // Each sum has a component of exactly +-scale along n, which is
    // orthogonal to the other terms, so its length is at least `scale`.
    let extrude = |p: DVec3, sign_e: f64, sign_n: f64| (p - l + (along * sign_e + n * sign_n) * scale).normalize_or_zero();
    let (v0_out, v1_out) = (extrude(e0, -1.0, 1.0), extrude(e1, 1.0, 1.0));
    let (v0_in, v1_in) = (extrude(e0, -1.0, -1.0), extrude(e1, 1.0, -1.0));
    Some([
        [e0, e0 + v0_out * reach, e1 + v1_out * reach, e1],
        [e1, e1 + v1_in * reach, e0 + v0_in * reach, e0],
    ])
}

/// The mask's quadrilaterals (as triangles) for every silhouette edge, each
/// built independently of its neighbours (5.1).
///
/// With `local_distance` (repair "distance", a departure from 5.1), each
/// corner also carries the distance from the light of the edge's end it is
/// extruded from, and the mask pass interpolates it across the quadrilateral:
/// a texel's distance is that of the part of the edge its volume comes from.
/// The paper's d_e, the nearer end's distance, is that of the top of a long
/// edge that falls away from the light (a box's vertical edge): the filter
/// near its foot is then as wide as under its top, and the shadow of an
/// object standing on the ground shows no contact hardening.
pub fn mask_volumes(edges: &[SilhouetteEdge], l: DVec3, r: f64, s_e: f64, offsets: Offsets, reach: f64, local_distance: bool) -> (Vec<MaskVertex>, MaskStats) {
    let mut stats = MaskStats { silhouette: crate::silhouettes::SilhouetteStats::of(edges.len()), ..Default::default() };
    let mut vertices = Vec::with_capacity(edges.len() * 12);
    for e in edges {
        let Some(quads) = edge_volume(e, l, r, s_e, offsets, reach) else {
            stats.silhouette.light_parallel_edges += 1;
            continue;
        };
        // d_e = min(|e0 - l|, |e1 - l|) of the original points (5.1).
        let (d_a, d_b) = ((e.a - l).length() as f32, (e.b - l).length() as f32);
        let d_e = d_a.min(d_b);
        // Corners 0 and 1 of the outer quad come from a, 2 and 3 from b; the inner quad runs the other way.
        for (quad, ends) in quads.into_iter().zip([[d_a, d_a, d_b, d_b], [d_b, d_b, d_a, d_a]]) {
            for k in [0, 1, 2, 0, 2, 3] {
                let d_local = if local_distance { ends[k] } else { 0.0 };
                vertices.push(MaskVertex { position: quad[k].as_vec3().to_array(), d_e, d_local });
            }
            stats.mask_quads += 1;
        }
    }
    (vertices, stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edge(a: [f64; 3], b: [f64; 3]) -> SilhouetteEdge {
        SilhouetteEdge { a: DVec3::from(a), b: DVec3::from(b), ia: 0, ib: 1, component: 0 }
    }

    /// The far corners of an edge's outer and inner quadrilaterals at `reach`.
    fn far_corners(e: &SilhouetteEdge, l: DVec3, r: f64, s_e: f64, offsets: Offsets) -> [[DVec3; 2]; 2] {
        let [outer, inner] = edge_volume(e, l, r, s_e, offsets, 10.0).unwrap();
        [[outer[1], outer[2]], [inner[2], inner[1]]]
    }

    #[test]
    fn moved_points_keep_their_direction_and_share_the_distance() {
        let l = DVec3::new(0.0, 6.0, 0.0);
        let e = edge([-1.0, 2.0, 1.0], [1.0, 3.0, 1.0]);
        let [outer, _] = edge_volume(&e, l, 0.5, 0.5, Offsets::Unit, 10.0).unwrap();
        let d_e = (e.a - l).length().min((e.b - l).length());
        for (moved, original) in [(outer[0], e.a), (outer[3], e.b)] {
            assert!(((original - moved).length() - 0.5 * d_e).abs() < 1e-12);
            assert!((moved - l).normalize().dot((original - l).normalize()) > 1.0 - 1e-12);
        }
    }

    #[test]
    fn outer_quad_leans_away_from_the_occluder_and_inner_towards_it() {
        // Edge along x at y = 2, z = 1; the occluder lies at z < 1 (normal +z).
        let l = DVec3::new(0.0, 6.0, 0.0);
        let e = edge([1.0, 2.0, 1.0], [-1.0, 2.0, 1.0]);
        let n = (e.b - e.a).cross(e.a - l);
        assert!(n.z > 0.0, "{n}");
        // The hard-shadow plane's z at a point's height: z grows linearly from the light.
        let hard_z = |p: DVec3| (6.0 - p.y) / 4.0;
        for offsets in [Offsets::Unit, Offsets::Radius] {
            let [[o0, o1], [i0, i1]] = far_corners(&e, l, 0.5, 0.5, offsets);
            assert!(o0.z > hard_z(o0) && o1.z > hard_z(o1), "{offsets:?}");
            assert!(i0.z < hard_z(i0) && i1.z < hard_z(i1), "{offsets:?}");
            // The ends spread outwards along the edge.
            assert!(o0.x > 1.0 && o1.x < -1.0);
        }
    }

    #[test]
    fn radius_offsets_cover_the_true_outer_penumbra() {
        // The true outer penumbra boundary through the edge is the plane tangent
        // to the light's sphere; with s_e = 0.5 the radius-scaled volume lies beyond it.
        let l = DVec3::new(0.0, 6.0, 0.0);
        let e = edge([1.0, 2.0, 1.0], [-1.0, 2.0, 1.0]);
        for r in [0.1, 0.5, 1.0, 2.0] {
            let [[o0, _], _] = far_corners(&e, l, r, 0.5, Offsets::Radius);
            // In the y-z plane: the edge line is the point (2, 1); the tangent
            // from it to the circle of radius r around (6, 0), on the outer side.
            let (dy, dz) = (2.0 - 6.0, 1.0_f64);
            let dist = (dy * dy + dz * dz).sqrt();
            let angle = dz.atan2(-dy) + (r / dist).asin();
            let z_at = |y: f64| 1.0 + (2.0 - y) * angle.tan();
            assert!(o0.z >= z_at(o0.y), "r = {r}: {} < {}", o0.z, z_at(o0.y));
        }
    }

    #[test]
    fn degenerate_edges_produce_no_nan() {
        let l = DVec3::new(0.0, 5.0, 0.0);
        let edges = vec![
            // Pointing at the light.
            edge([0.0, 1.0, 0.0], [0.0, 2.0, 0.0]),
            // Zero length.
            edge([1.0, 1.0, 0.0], [1.0, 1.0, 0.0]),
            // Ordinary, with s_e = 1: the nearer point lands on the light.
            edge([1.0, 1.0, 0.0], [2.0, 1.0, 0.0]),
        ];
        for s_e in [1e-6, 0.5, 1.0] {
            for offsets in [Offsets::Unit, Offsets::Radius] {
                let (vertices, stats) = mask_volumes(&edges, l, 0.5, s_e, offsets, 10.0, true);
                assert_eq!(stats.silhouette.light_parallel_edges, 2);
                assert_eq!(stats.mask_quads, 2);
                assert!(vertices.iter().all(|v| v.position.iter().all(|c| c.is_finite()) && v.d_e > 0.0));
            }
        }
    }

    #[test]
    fn local_distances_follow_the_edge_and_the_paper_keeps_the_nearer_end() {
        // A vertical edge from the ground to 2 units up, under a light at 6.
        let l = DVec3::new(0.0, 6.0, 0.0);
        let e = edge([1.0, 0.0, 1.0], [1.0, 2.0, 1.0]);
        let (d_a, d_b) = ((e.a - l).length() as f32, (e.b - l).length() as f32);
        let (paper, _) = mask_volumes(&[e], l, 0.5, 0.02, Offsets::Radius, 10.0, false);
        assert!(paper.iter().all(|v| v.d_e == d_b && v.d_local == 0.0), "the nearer end's distance, flat");
        let (local, _) = mask_volumes(&[e], l, 0.5, 0.02, Offsets::Radius, 10.0, true);
        // Outer quad: corners 0-1 from a, 2-3 from b; inner quad the other way.
        let ends = [d_a, d_a, d_b, d_b, d_b, d_b, d_a, d_a];
        for (quad, corner_ends) in local.chunks(6).zip(ends.chunks(4)) {
            for (v, k) in quad.iter().zip([0, 1, 2, 0, 2, 3]) {
                assert_eq!(v.d_local, corner_ends[k]);
                assert_eq!(v.d_e, d_b);
            }
        }
    }
}
