//! The geometry of PVM's penumbra volumes (Cournia 4.1.2): per silhouette
//! edge, the outer and inner penumbra planes through the edge and the two
//! displaced light positions, and the extrusion vectors shared by
//! consecutive edges of a silhouette loop. CPU side; the method's passes
//! render what this builds.

use std::collections::HashMap;

use glam::DVec3;

use crate::silhouettes::SilhouetteEdge;


/// One corner of a volume quadrilateral with the index (into
/// [`VolumeGeometry::edges`]) of the silhouette edge it comes from.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VolumeVertex {
    pub position: [f32; 3],
    pub edge: u32,
}

crate::gpu_type! {
    /// The end points h0 and h1 of a silhouette edge with a volume (h0.w:
    /// its surface; h1.w unused), as the visibility pass reads them (4.1.3's
    /// edge maps, by index), and its neighbours along its silhouette loop
    /// (`links`: x the index + 1 of the edge ending at h0, y of the edge
    /// starting at h1, 0 where h0 or h1 is a junction; for `edges = "chain"`).
    #[derive(Debug, PartialEq)]
    pub struct EdgePoints => "EdgePoints" in "methods/pvm/visibility.wgsl" {
        pub h0: [f32; 4],
        pub h1: [f32; 4],
        pub links: [u32; 4],
    }
}

/// Everything pass 2 renders: the quadrilaterals' corners and the edges they index.
#[derive(Debug, Clone, Default)]
pub struct VolumeGeometry {
    pub vertices: Vec<VolumeVertex>,
    pub edges: Vec<EdgePoints>,
    pub stats: VolumeStats,
}

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct VolumeStats {
    /// Silhouette edges, end-on and hidden ones, connectivity.
    pub silhouette: crate::silhouettes::SilhouetteStats,
    /// Quadrilaterals rendered (two per edge: outer and inner).
    pub volume_quads: usize,
    /// Silhouette vertices without exactly one incoming and one outgoing edge.
    pub junction_vertices: usize,
    /// Quadrilateral corners whose neighbouring planes meet outside the
    /// vertex's light cone (`in_light_cone`): kept as the paper has them
    /// without repair "cone", each edge's own plane with it.
    pub extrusions_outside_cone: usize,
}

/// The planes of one silhouette edge (4.1.2).
struct EdgePlanes {
    /// Hard-shadow plane normal n.
    n: DVec3,
    /// Outer and inner penumbra plane normals n- and n+.
    outer: DVec3,
    inner: DVec3,
    /// Displaced light positions d- and d+.
    d_outer: DVec3,
    d_inner: DVec3,
}

fn edge_planes(e: &SilhouetteEdge, l: DVec3, r: f64) -> Option<EdgePlanes> {
    let along = e.b - e.a;
    let cross = along.cross(e.a - l);
    // An edge pointing at the light has no hard-shadow plane.
    if cross.length() <= 1e-9 * along.length() * (e.a - l).length() {
        return None;
    }
    let n = cross.normalize();
    let d_outer = l - n * r;
    let d_inner = l + n * r;
    // The edge is off the displaced positions (they lie on the light's sphere,
    // and no surface touches the light), so these crosses are non-zero.
    let outer = along.cross(e.a - d_outer).normalize_or_zero();
    let inner = along.cross(e.a - d_inner).normalize_or_zero();
    Some(EdgePlanes { n, outer, inner, d_outer, d_inner })
}

/// The sine of the angle between two neighbouring edges' planes below
/// which they count as one plane (the coincident-plane rule). Their
/// intersection line's direction is then set by rounding, not geometry: the
/// two halves of a cube's edge (`cube.obj` splits each face 3 x 3), whose
/// planes the f32 vertices and a soup's rounded corners turn against each
/// other by far more than the 1e-9 this was, met along lines anywhere in the
/// plane (along the edges themselves, for a soup), which the cone test kept
/// or not by chance: the soup of generated seed 38's cube moved 0.5% of
/// `pvm`'s ground pixels against the welded cube (tests/test_pvm.py; the
/// test below). Taking a plane's own ray instead turns a corner by at most
/// about the planes' angle, 1e-4 radians, a fifth of a 2048-texel map's
/// texel across a 60-degree frustum.
const COINCIDENT_PLANES: f64 = 1e-4;

/// Extrusion vector at vertex `v` shared by the planes with normals `n_in`
/// (incoming edge) and `n_out` (outgoing edge), both through `v` (4.1.2),
/// for a light of centre `l` and radius `r`; and whether the planes'
/// intersection left the vertex's light cone.
fn extrusion(v: DVec3, n_in: DVec3, n_out: DVec3, d: DVec3, l: DVec3, r: f64, cone: bool) -> (DVec3, bool) {
    let line = n_out.cross(n_in);
    // Coincident (or nearly) planes: the paper's rule, away from the displaced light.
    let mut dir = if line.length() < COINCIDENT_PLANES { (v - d).normalize_or_zero() } else { line.normalize() };
    // Cournia negates v^ when v1 lies in the negative half-space of (v0, v2, l);
    // that picks, of the two directions of the intersection line, the one that
    // continues the rays from the displaced light position d through v. We
    // test for that directly, which holds for either loop orientation (and,
    // unlike a test against the light centre, for lights large against their
    // distance).
    if dir.dot(v - d) < 0.0 {
        dir = -dir;
    }
    let inside = in_light_cone(v, dir, d, l, r);
    let outside = inside != dir;
    if cone {
        return (inside, outside);
    }
    // The paper's construction alone (`repairs = "none"`), with the one
    // guard it always had: every ray of the true penumbra through v leaves
    // the light, so it lies in the cone of half-angle asin(r / |v - l|)
    // about v - l. For a light large against its distance, the two planes
    // can meet in a line that turns back past the plane through v
    // perpendicular to v - l (found by the property tests: r = 1.8,
    // |v - l| = 2.7 gave a line 94 degrees off v - l), and the volume then
    // sweeps over space in front of the silhouette. There the vertex takes
    // its own plane's ray from d instead, which always leaves the light: n is
    // orthogonal to v - l, so (v - d).(v - l) = |v - l|^2 > 0.
    if dir.dot(v - l) <= 0.0 {
        return ((v - d).normalize_or_zero(), outside);
    }
    (dir, outside)
}

/// `dir` if it lies in the cone of the rays that leave the light and pass
/// through `v` (the cone about `v - l` of half-angle asin(r / |v - l|)),
/// else the ray from the edge's own displaced light position `d` through `v`.
///
/// Departure from 4.1.2 (repair "cone"): every ray of the true penumbra
/// through `v` comes from a point of the light, so it lies in that cone. The
/// intersection of two neighbouring planes does not when the planes are
/// nearly parallel (a jagged silhouette whose consecutive edges are nearly
/// collinear seen from the light but not in depth: the line then turns
/// towards the silhouette's own direction), nearly opposite (a silhouette
/// that folds back), or meet at a sharp corner (the miter runs off beyond
/// the cone). On spot and the teapot of ../shared/meshes 21-74% of the
/// quad corners lie outside it (`extrusions_outside_light_cone`,
/// docs/real_meshes.md), some far off, and their quads swept across the
/// floor as streaks. No vector in both planes
/// lies in the cone then; each edge keeps its own plane at `v` (the paper's
/// coincident-plane rule), which leaves a sliver between the two quads
/// where the shadow-map test decides. (Clamping the miter onto the cone
/// instead tilts the whole planar quad of a long edge off its plane and
/// narrows its penumbra along all of it: tests/test_pvm.py's disk-cut test
/// across a bar's edge failed with it.)
fn in_light_cone(v: DVec3, dir: DVec3, d: DVec3, l: DVec3, r: f64) -> DVec3 {
    let to_v = v - l;
    // No geometry touches the light (scene validation): |v - l| > r >= 0.
    let sin_c = (r / to_v.length()).min(1.0);
    let cos_c = (1.0 - sin_c * sin_c).max(0.0).sqrt();
    if dir.dot(to_v.normalize()) >= cos_c {
        return dir;
    }
    (v - d).normalize_or_zero()
}

/// Builds the outer and inner quadrilaterals of every silhouette edge,
/// extruded by `reach` (beyond the light's far plane). With `cone`, every
/// extrusion vector lies in its vertex's light cone (`in_light_cone`);
/// without, it is the paper's plane intersection alone.
pub fn penumbra_volumes(edges: &[SilhouetteEdge], l: DVec3, r: f64, reach: f64, cone: bool) -> VolumeGeometry {
    let mut stats = VolumeStats { silhouette: crate::silhouettes::SilhouetteStats::of(edges.len()), ..Default::default() };
    let planes: Vec<Option<EdgePlanes>> = edges.iter().map(|e| edge_planes(e, l, r)).collect();
    // Loop connectivity: the incoming and outgoing edges of each vertex.
    let mut incoming: HashMap<u32, Vec<usize>> = HashMap::new();
    let mut outgoing: HashMap<u32, Vec<usize>> = HashMap::new();
    for (i, e) in edges.iter().enumerate() {
        if planes[i].is_some() {
            outgoing.entry(e.ia).or_default().push(i);
            incoming.entry(e.ib).or_default().push(i);
        }
    }
    let paired = |v: u32| -> Option<(usize, usize)> {
        match (incoming.get(&v).map(Vec::as_slice), outgoing.get(&v).map(Vec::as_slice)) {
            (Some([i]), Some([o])) => Some((*i, *o)),
            _ => None,
        }
    };
    let mut junctions: Vec<u32> = incoming.keys().chain(outgoing.keys()).copied().filter(|&v| paired(v).is_none()).collect();
    junctions.sort_unstable();
    junctions.dedup();
    stats.junction_vertices = junctions.len();

    // Each edge's index among those with a volume (the buffer's order).
    let mut index = vec![u32::MAX; edges.len()];
    let mut next = 0u32;
    for (i, slot) in index.iter_mut().enumerate() {
        if planes[i].is_some() {
            *slot = next;
            next += 1;
        }
    }
    // The index + 1 of vertex v's incoming (or outgoing) edge where v pairs two.
    let link = |v: u32, incoming: bool| -> u32 { paired(v).map_or(0, |(i, o)| index[if incoming { i } else { o }] + 1) };
    let mut vertices = Vec::with_capacity(edges.len() * 12);
    let mut points = Vec::with_capacity(edges.len());
    let outside = std::cell::Cell::new(0usize);
    let f = |p: DVec3| p.as_vec3().to_array();
    for (i, e) in edges.iter().enumerate() {
        let Some(own) = &planes[i] else {
            stats.silhouette.light_parallel_edges += 1;
            continue;
        };
        // Extrusion vectors at a (shared with the incoming edge) and b (with the outgoing one).
        let at = |v: DVec3, vi: u32, start: bool| -> (DVec3, DVec3) {
            let neighbour = paired(vi).map(|(inc, out)| if start { inc } else { out });
            match neighbour.and_then(|j| planes[j].as_ref()) {
                Some(other) => {
                    let (n_in, n_out) = if start { (other, own) } else { (own, other) };
                    let (o, outer_outside) = extrusion(v, n_in.outer, n_out.outer, own.d_outer, l, r, cone);
                    let (i, inner_outside) = extrusion(v, n_in.inner, n_out.inner, own.d_inner, l, r, cone);
                    outside.set(outside.get() + usize::from(outer_outside) + usize::from(inner_outside));
                    (o, i)
                }
                // Unpaired: this edge's own plane alone (coincident-plane rule).
                None => ((v - own.d_outer).normalize_or_zero(), (v - own.d_inner).normalize_or_zero()),
            }
        };
        let (a_out, a_in) = at(e.a, e.ia, true);
        let (b_out, b_in) = at(e.b, e.ib, false);
        debug_assert!(own.n.is_finite());
        let edge = points.len() as u32;
        let [ax, ay, az] = f(e.a);
        let [bx, by, bz] = f(e.b);
        // h0.w: the edge's surface (exact in f32 below 2^24 components).
        points.push(EdgePoints { h0: [ax, ay, az, e.component as f32], h1: [bx, by, bz, 1.0], links: [link(e.ia, true), link(e.ib, false), 0, 0] });
        for (va, vb) in [(a_out, b_out), (a_in, b_in)] {
            let quad = [e.a, e.a + va * reach, e.b + vb * reach, e.b];
            for k in [0, 1, 2, 0, 2, 3] {
                vertices.push(VolumeVertex { position: f(quad[k]), edge });
            }
            stats.volume_quads += 1;
        }
    }
    stats.extrusions_outside_cone = outside.get();
    VolumeGeometry { vertices, edges: points, stats }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::silhouettes::silhouette;

    /// A unit cube centred at (0, 2, 0), outward faces.
    fn cube() -> Topology {
        let mut p = Vec::new();
        for i in 0..8 {
            p.push(DVec3::new(
                if i & 1 == 0 { -0.5 } else { 0.5 },
                2.0 + if i & 2 == 0 { -0.5 } else { 0.5 },
                if i & 4 == 0 { -0.5 } else { 0.5 },
            ));
        }
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let faces: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        Topology::build(&p, &faces)
    }

    use crate::topology::Topology;

    #[test]
    fn cube_under_a_light_has_one_square_loop() {
        let l = DVec3::new(0.0, 6.0, 0.0);
        let edges = silhouette(&cube(), l, false);
        // Seen from straight above, the silhouette is the top face's rim... of the
        // whole cube: the four vertical-face/top-face edges.
        assert_eq!(edges.len(), 4);
        for e in &edges {
            let n = (e.b - e.a).cross(e.a - l);
            // Normal points away from the cube's centre (the occluder).
            assert!(n.dot(e.a - DVec3::new(0.0, 2.0, 0.0)) > 0.0, "{e:?}");
        }
        let VolumeGeometry { vertices, stats, .. } = penumbra_volumes(&edges, l, 0.5, 100.0, true);
        assert_eq!(stats.junction_vertices, 0);
        assert_eq!(stats.volume_quads, 8);
        assert_eq!(vertices.len(), 8 * 6);
        assert!(vertices.iter().all(|v| v.position.iter().all(|c| c.is_finite())));
        // Extruded corners go away from the light (downwards here).
        assert!(vertices.iter().all(|v| v.position[1] <= 2.5 + 1e-6));
    }

    #[test]
    fn links_follow_the_loop_and_stop_at_junctions() {
        // The cube's square loop: each edge's next starts where it ends, and
        // its previous edge's next is itself.
        let l = DVec3::new(0.0, 6.0, 0.0);
        let points = penumbra_volumes(&silhouette(&cube(), l, false), l, 0.5, 10.0, true).edges;
        assert_eq!(points.len(), 4);
        for (i, e) in points.iter().enumerate() {
            let [prev, next, ..] = e.links;
            assert!(prev > 0 && next > 0, "{e:?}");
            let (p, n) = (&points[prev as usize - 1], &points[next as usize - 1]);
            assert_eq!(n.h0[..3], e.h1[..3]);
            assert_eq!(p.h1[..3], e.h0[..3]);
            assert_eq!(n.links[0] as usize, i + 1);
            assert_eq!(p.links[1] as usize, i + 1);
        }
        // An open chain with an edge pointing at the light (no volume) in
        // the middle: links skip no edge, so the ends and both sides of the
        // light-parallel edge have none; indices count the edges with volumes.
        let chain = vec![
            SilhouetteEdge { a: DVec3::new(-1.0, 1.0, 0.0), b: DVec3::new(0.0, 1.0, 0.0), ia: 0, ib: 1, component: 0 },
            SilhouetteEdge { a: DVec3::new(0.0, 1.0, 0.0), b: DVec3::new(1.0, 1.0, 0.0), ia: 1, ib: 2, component: 0 },
            SilhouetteEdge { a: DVec3::new(1.0, 1.0, 0.0), b: DVec3::new(1.0, 2.0, 0.0), ia: 2, ib: 3, component: 0 },
            SilhouetteEdge { a: DVec3::new(1.0, 2.0, 0.0), b: DVec3::new(2.0, 2.0, 0.0), ia: 3, ib: 4, component: 0 },
        ];
        let l = DVec3::new(1.0, 5.0, 0.0);
        let links: Vec<[u32; 2]> = penumbra_volumes(&chain, l, 0.5, 10.0, true).edges.iter().map(|e| [e.links[0], e.links[1]]).collect();
        assert_eq!(links, vec![[0, 2], [1, 0], [0, 0]]);
    }

    #[test]
    fn outer_volume_leans_outwards_and_inner_inwards() {
        let l = DVec3::new(0.0, 6.0, 0.0);
        let edges = silhouette(&cube(), l, false);
        let vertices = penumbra_volumes(&edges, l, 0.5, 10.0, true).vertices;
        // Far corners: outer quads spread beyond the hard shadow's, inner ones inside it.
        let hard_spread = |y: f32| 0.5 * (6.0 - y) / (6.0 - 2.5);
        let (outer, inner) = vertices.split_at(6);
        let far_outer = outer.iter().map(|v| v.position).min_by(|a, b| a[1].total_cmp(&b[1])).unwrap();
        let far_inner = vertices[6..12].iter().map(|v| v.position).min_by(|a, b| a[1].total_cmp(&b[1])).unwrap();
        let spread = |p: [f32; 3]| p[0].abs().max(p[2].abs());
        assert!(spread(far_outer) > hard_spread(far_outer[1]), "{far_outer:?}");
        assert!(spread(far_inner) < hard_spread(far_inner[1]), "{far_inner:?}");
        let _ = inner;
    }

    #[test]
    fn degenerate_edges_produce_no_nan() {
        // An edge pointing at the light and collinear silhouette edges.
        let l = DVec3::new(0.0, 5.0, 0.0);
        let edges = vec![
            SilhouetteEdge { a: DVec3::new(0.0, 1.0, 0.0), b: DVec3::new(0.0, 2.0, 0.0), ia: 0, ib: 1, component: 0 },
            SilhouetteEdge { a: DVec3::new(1.0, 1.0, 0.0), b: DVec3::new(2.0, 1.0, 0.0), ia: 2, ib: 3, component: 0 },
            SilhouetteEdge { a: DVec3::new(2.0, 1.0, 0.0), b: DVec3::new(3.0, 1.0, 0.0), ia: 3, ib: 4, component: 0 },
        ];
        let VolumeGeometry { vertices, edges: points, stats } = penumbra_volumes(&edges, l, 0.5, 10.0, true);
        assert_eq!(stats.silhouette.light_parallel_edges, 1);
        assert!(vertices.iter().all(|v| v.position.iter().all(|c| c.is_finite()) && (v.edge as usize) < points.len()));
        assert!(points.iter().all(|p| p.h0.iter().chain(&p.h1).all(|c| c.is_finite())));
        // Radius 0: all planes coincide with the hard-shadow plane; still finite.
        let vertices = penumbra_volumes(&edges, l, 0.0, 10.0, true).vertices;
        assert!(vertices.iter().all(|v| v.position.iter().all(|c| c.is_finite())));
    }

    #[test]
    fn collinear_edges_rounded_apart_take_the_coincident_plane_rule() {
        // Two halves of one straight edge, their far ends off its line by
        // 1e-6 of its length (a soup's rounding), under a large light
        // beyond the edge's near end, whose cone at the shared vertex holds
        // directions near the edge's. Each half's extrusion there must be
        // its own plane's ray from d, as for exactly collinear halves, not
        // the planes' intersection, which rounding sets.
        let l = DVec3::new(-2.0, 0.5, 0.0);
        let (r, v) = (1.0, DVec3::new(0.5, 0.0, 0.0));
        let first = SilhouetteEdge { a: DVec3::new(0.0, 0.0, 1e-6), b: v, ia: 0, ib: 1, component: 0 };
        let second = SilhouetteEdge { a: v, b: DVec3::new(1.0, 1e-6, 0.0), ia: 1, ib: 2, component: 0 };
        let (p0, p1) = (edge_planes(&first, l, r).unwrap(), edge_planes(&second, l, r).unwrap());
        let line = p1.outer.cross(p0.outer);
        assert!(line.length() > 1e-9 && line.length() < COINCIDENT_PLANES, "{}", line.length());
        // The line, oriented as `extrusion` orients it, is no ray from d
        // through v (it runs about 30 degrees off it) and lies in the cone.
        let own = (v - p1.d_outer).normalize();
        let u = if line.dot(own) < 0.0 { -line.normalize() } else { line.normalize() };
        assert!(u.dot(own) < 0.99 && in_light_cone(v, u, p1.d_outer, l, r) == u, "{u} {own}");
        let (dir, _) = extrusion(v, p0.outer, p1.outer, p1.d_outer, l, r, true);
        assert!((dir - own).length() < 1e-9, "{dir} against {own}");
    }

    #[test]
    fn a_long_edge_keeps_its_own_planes_at_square_corners() {
        // The cube's silhouette under the light: square corners, whose miters
        // leave the light's cone (by sqrt 2). Each edge then keeps its own
        // outer and inner planes: every corner of its quads lies in them.
        let l = DVec3::new(0.0, 6.0, 0.0);
        let edges = silhouette(&cube(), l, false);
        let g = penumbra_volumes(&edges, l, 0.5, 10.0, true);
        assert_eq!(g.stats.junction_vertices, 0);
        let mut quads = g.vertices.chunks(6);
        for e in edges.iter().filter_map(|e| edge_planes(e, l, 0.5).map(|p| (e, p))) {
            let (edge, planes) = e;
            for normal in [planes.outer, planes.inner] {
                let quad = quads.next().unwrap();
                for corner in quad {
                    let p = DVec3::from(corner.position.map(f64::from));
                    assert!(normal.dot(p - edge.a).abs() < 1e-5, "{p} off its edge's plane");
                }
            }
        }
    }
}
