//! The geometry of penumbra wedges (Akenine-Möller & Assarsson 2002, 4.1),
//! on the CPU: per silhouette edge a front, a back and two side planes, side
//! planes shared by consecutive edges of a silhouette loop, the side ray
//! directions of the interpolation (4.2), the extra wedges at acute
//! vertices (4.1, Figure 7), and a screen-space binning of the wedges so
//! that the visibility pass tests each pixel against the wedges whose
//! screen footprint covers its tile.

use std::collections::HashMap;

use glam::{DMat4, DVec3, DVec4};

use crate::silhouettes::SilhouetteEdge;

crate::gpu_type! {
    /// One wedge as the visibility shader reads it (methods/wedges/visibility.wgsl,
    /// struct `Wedge`). Planes are unit normals; a plane through the edge's
    /// start `a` (front, back, hard, left) is evaluated as `dot(n, p - a)`, the
    /// right side plane through the end `b` as `dot(n, p - b)`.
    #[derive(Debug, PartialEq)]
    pub struct WedgeGpu => "Wedge" in "methods/wedges/visibility.wgsl" {
        /// Edge start (xyz).
        pub a: [f32; 4],
        /// Edge end (xyz); equal to `a` for an extra wedge at a vertex.
        pub b: [f32; 4],
        /// Unit direction of the edge (xyz), the ray direction of Eq. 3; w: the
        /// connected surface it lies on (`SilhouetteEdge::component`).
        pub dir: [f32; 4],
        /// Front plane (through `f = c - r n`): the wedge is where it is <= 0.
        pub front: [f32; 4],
        /// Back plane (through `b = c + r n`): the wedge is where it is >= 0.
        pub back: [f32; 4],
        /// The shadow-volume quad's plane (normal n, away from the occluder).
        pub hard: [f32; 4],
        /// Side planes, normals pointing into the wedge.
        pub left: [f32; 4],
        pub right: [f32; 4],
        /// Unit ray directions in the left and right side planes (4.1, last paragraph).
        pub u_left: [f32; 4],
        pub u_right: [f32; 4],
    }
}

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct WedgeStats {
    /// Silhouette edges, end-on and hidden ones, connectivity.
    pub silhouette: crate::silhouettes::SilhouetteStats,
    /// Wedges built (silhouette edges with a wedge plus extra wedges).
    pub wedges: usize,
    /// Extra wedges at acute vertices (`acute_wedges`).
    pub extra_wedges: usize,
    /// Wedges whose part inside the scene's box is off screen or empty.
    pub culled_wedges: usize,
    /// Silhouette vertices without exactly one incoming and one outgoing
    /// edge: their wedges end in a side plane of their own.
    pub junction_vertices: usize,
    /// Shared side lines (front-front or back-back plane intersections)
    /// replaced because they were degenerate or outside the vertex's light cone.
    pub side_fallbacks: usize,
    /// (wedge, tile) pairs in the binning.
    pub binned: usize,
}

/// An edge of the wedge list: a silhouette edge or a zero-length extra edge.
#[derive(Debug, Clone, Copy)]
struct WedgeEdge {
    a: DVec3,
    b: DVec3,
    dir: DVec3,
    /// Hard-shadow (SV quad) plane normal, away from the occluder.
    n: DVec3,
    /// Front and back plane normals (4.1).
    front: DVec3,
    back: DVec3,
    f: DVec3,
    bp: DVec3,
}

/// The planes of an edge through `a` with unit direction `dir` (4.1):
/// `f = c - r n` and `b = c + r n`, n the SV quad's normal. None when the
/// edge points at the light (no SV quad).
fn edge_planes(a: DVec3, b: DVec3, dir: DVec3, l: DVec3, r: f64) -> Option<WedgeEdge> {
    let to = a - l;
    let cross = dir.cross(to);
    // |dir| = 1: the sine of the angle between the edge and the light ray.
    if cross.length() <= 1e-9 * to.length() {
        return None;
    }
    let n = cross.normalize();
    let f = l - n * r;
    let bp = l + n * r;
    // The edge is off f and bp (they lie on the light's sphere and no
    // surface touches the light): these crosses are non-zero.
    let front = dir.cross(a - f).normalize_or_zero();
    let back = dir.cross(a - bp).normalize_or_zero();
    Some(WedgeEdge { a, b, dir, n, front, back, f, bp })
}

/// The line two planes through a common point share, pointing away from the light.
fn shared_line(n0: DVec3, n1: DVec3, v: DVec3, l: DVec3) -> Option<DVec3> {
    let line = n0.cross(n1);
    if line.length() <= 1e-9 {
        return None;
    }
    let d = line.normalize();
    Some(if d.dot(v - l) < 0.0 { -d } else { d })
}

/// Whether `d` (unit) leaves the light through `v`: within the cone about
/// `v - l` of half-angle asin(r / |v - l|) (and a hair more).
fn in_light_cone(d: DVec3, v: DVec3, l: DVec3, r: f64) -> bool {
    let axis = v - l;
    let dist = axis.length();
    let sin = (r / dist).min(1.0);
    let cos = (1.0 - sin * sin).max(0.0).sqrt();
    d.dot(axis) / dist >= cos - 1e-6
}

/// A side plane through `v` (unit normal, not yet oriented) and its ray direction.
struct SidePlane {
    normal: DVec3,
    u: DVec3,
}

/// The side plane of an edge end that no neighbour shares: through the
/// vertex and the edge's own front and back points, so it holds the light's
/// centre (Figure 6's single wedge).
fn own_side(e: &WedgeEdge, v: DVec3, l: DVec3) -> SidePlane {
    let d_f = (v - e.f).normalize_or_zero();
    let d_b = (v - e.bp).normalize_or_zero();
    let mut normal = d_f.cross(d_b);
    if normal.length() <= 1e-12 {
        normal = e.n.cross(v - l);
    }
    let normal = normal.normalize_or_zero();
    SidePlane { normal, u: project_unit(e.n, normal, e.n) }
}

/// `x` without its component along unit `normal`, made unit; `fallback` if that vanishes.
fn project_unit(x: DVec3, normal: DVec3, fallback: DVec3) -> DVec3 {
    let p = x - normal * x.dot(normal);
    if p.length() <= 1e-12 {
        fallback
    } else {
        p.normalize()
    }
}

/// The side plane shared by `e0` (ending at `v`) and `e1` (starting at `v`)
/// (4.1, Figure 5): through the line the two front planes share and the line
/// the two back planes share; its ray direction is the mean of the two SV
/// quad normals projected into it. With `cone`, a shared line that is
/// degenerate or leaves the vertex's light cone is replaced by the ray from
/// the mean displaced light point through `v` (shared all the same, so the
/// intensity stays continuous); the bool says whether that happened.
fn shared_side(e0: &WedgeEdge, e1: &WedgeEdge, v: DVec3, l: DVec3, r: f64, cone: bool) -> Option<(SidePlane, bool)> {
    let mean_n = e0.n + e1.n;
    if mean_n.length() <= 1e-9 {
        return None;
    }
    let mean_n = mean_n.normalize();
    let mut fallback = false;
    let mut line = |n0: DVec3, n1: DVec3, displaced: DVec3| {
        match shared_line(n0, n1, v, l) {
            Some(d) if !cone || in_light_cone(d, v, l, r) => d,
            _ => {
                fallback = true;
                (v - displaced).normalize_or_zero()
            }
        }
    };
    let d_f = line(e0.front, e1.front, l - mean_n * r);
    let d_b = line(e0.back, e1.back, l + mean_n * r);
    let mut normal = d_f.cross(d_b);
    if normal.length() <= 1e-12 {
        normal = mean_n.cross(v - l);
        if normal.length() <= 1e-12 {
            return None;
        }
    }
    let normal = normal.normalize();
    Some((SidePlane { normal, u: project_unit(mean_n, normal, mean_n) }, fallback))
}

/// Rotates unit `x` about unit `axis` by `angle` radians (Rodrigues).
fn rotate(x: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    x * c + axis.cross(x) * s + axis * axis.dot(x) * (1.0 - c)
}

/// The extra edges at the vertex `v` between `e0` and `e1` (4.1, Figure 7):
/// when the silhouette turns by more than 90 degrees towards the occluder
/// as the light sees it (an acute corner), `ceil(per_120 * turn / 120 deg)`
/// zero-length edges whose directions turn from `e0`'s to `e1`'s in equal
/// steps about the light ray through `v`.
fn acute_extra(e0: &WedgeEdge, e1: &WedgeEdge, v: DVec3, l: DVec3, r: f64, per_120: u32) -> Vec<WedgeEdge> {
    if per_120 == 0 {
        return Vec::new();
    }
    let axis = (v - l).normalize_or_zero();
    let d0 = project_unit(e0.dir, axis, DVec3::ZERO);
    let d1 = project_unit(e1.dir, axis, DVec3::ZERO);
    if d0 == DVec3::ZERO || d1 == DVec3::ZERO {
        return Vec::new();
    }
    // Convex corner: the silhouette turns towards the occluder (against n).
    if d1.dot(e0.n) >= 0.0 {
        return Vec::new();
    }
    let turn = d0.dot(d1).clamp(-1.0, 1.0).acos();
    if turn <= std::f64::consts::FRAC_PI_2 {
        return Vec::new();
    }
    // The turn's sense about the axis.
    let sense = if d0.cross(d1).dot(axis) >= 0.0 { 1.0 } else { -1.0 };
    let k = (f64::from(per_120) * turn / (2.0 * std::f64::consts::FRAC_PI_3)).ceil() as u32;
    (1..=k)
        .filter_map(|i| {
            let dir = rotate(d0, axis, sense * turn * f64::from(i) / f64::from(k + 1));
            edge_planes(v, v, dir, l, r)
        })
        .collect()
}

/// The wedges of a scene, for the visibility pass.
#[derive(Debug, Clone, Default)]
pub struct Wedges {
    pub wedges: Vec<WedgeGpu>,
    pub stats: WedgeStats,
}

fn plane4(n: DVec3) -> [f32; 4] {
    [n.x as f32, n.y as f32, n.z as f32, 0.0]
}

fn point4(p: DVec3) -> [f32; 4] {
    [p.x as f32, p.y as f32, p.z as f32, 1.0]
}

/// Builds the penumbra wedges of `edges` (oriented as [`SilhouetteEdge`]
/// says) for a sphere light of centre `l` and radius `r > 0` (4.1).
/// `acute_wedges` extra wedges per 120 degrees of turn at acute vertices;
/// `cone` replaces shared side lines outside the vertex's light cone.
pub fn penumbra_wedges(edges: &[SilhouetteEdge], l: DVec3, r: f64, acute_wedges: u32, cone: bool) -> Wedges {
    let mut stats = WedgeStats { silhouette: crate::silhouettes::SilhouetteStats::of(edges.len()), ..Default::default() };
    // Edges with an SV quad, by silhouette edge.
    let mut built: Vec<(usize, WedgeEdge)> = Vec::with_capacity(edges.len());
    // Grouped by connected surface (stable), so that every tile's list holds
    // each object's wedges together (`occluders = "independent"`).
    let mut order: Vec<usize> = (0..edges.len()).collect();
    order.sort_by_key(|&i| edges[i].component);
    for i in order {
        let e = &edges[i];
        let along = e.b - e.a;
        let len = along.length();
        match (len > 0.0).then(|| edge_planes(e.a, e.b, along / len, l, r)).flatten() {
            Some(w) => built.push((i, w)),
            None => stats.silhouette.light_parallel_edges += 1,
        }
    }
    // Loops: an edge ending at v continues into the edge starting at v when
    // v has exactly one of each.
    let mut incoming: HashMap<u32, Vec<usize>> = HashMap::new();
    let mut outgoing: HashMap<u32, Vec<usize>> = HashMap::new();
    for (k, (i, _)) in built.iter().enumerate() {
        outgoing.entry(edges[*i].ia).or_default().push(k);
        incoming.entry(edges[*i].ib).or_default().push(k);
    }
    let mut next: Vec<Option<usize>> = vec![None; built.len()];
    let mut vertices: Vec<u32> = incoming.keys().chain(outgoing.keys()).copied().collect();
    vertices.sort_unstable();
    vertices.dedup();
    for v in vertices {
        match (incoming.get(&v).map(Vec::as_slice), outgoing.get(&v).map(Vec::as_slice)) {
            (Some([k0]), Some([k1])) if k0 != k1 => next[*k0] = Some(*k1),
            _ => stats.junction_vertices += 1,
        }
    }
    // The wedge list: silhouette edges in order, each followed by the
    // extra edges at its end vertex; left/right side planes per entry.
    let mut list: Vec<WedgeEdge> = Vec::with_capacity(built.len());
    let mut left: Vec<Option<SidePlane>> = Vec::new();
    let mut right: Vec<Option<SidePlane>> = Vec::new();
    // For each built edge, its index in `list`, and its chain of extras.
    let mut position = vec![0usize; built.len()];
    let mut chains: Vec<Vec<usize>> = vec![Vec::new(); built.len()];
    let mut component: Vec<u32> = Vec::with_capacity(built.len());
    for (k, (i, e)) in built.iter().enumerate() {
        position[k] = list.len();
        list.push(*e);
        component.push(edges[*i].component);
        left.push(None);
        right.push(None);
        if let Some(k1) = next[k] {
            let extra = acute_extra(e, &built[k1].1, e.b, l, r, acute_wedges);
            stats.extra_wedges += extra.len();
            for x in extra {
                chains[k].push(list.len());
                list.push(x);
                component.push(edges[*i].component);
                left.push(None);
                right.push(None);
            }
        }
    }
    // Shared side planes between consecutive entries of each chain
    // (edge, extras..., next edge).
    for k in 0..built.len() {
        let Some(k1) = next[k] else { continue };
        let mut seq = vec![position[k]];
        seq.extend(&chains[k]);
        seq.push(position[k1]);
        let v = built[k].1.b;
        for pair in seq.windows(2) {
            let (i0, i1) = (pair[0], pair[1]);
            let (e0, e1) = (list[i0], list[i1]);
            let Some((side, fallback)) = shared_side(&e0, &e1, v, l, r, cone) else { continue };
            stats.side_fallbacks += usize::from(fallback);
            // Oriented along the silhouette's direction of travel at v: the
            // plane is e0's right end and e1's left end.
            let travel = e0.dir + e1.dir;
            let sign = if side.normal.dot(travel) >= 0.0 { 1.0 } else { -1.0 };
            let n = side.normal * sign;
            right[i0] = Some(SidePlane { normal: -n, u: side.u });
            left[i1] = Some(SidePlane { normal: n, u: side.u });
        }
    }
    let mut wedges = Vec::with_capacity(list.len());
    for (i, e) in list.iter().enumerate() {
        let lp = left[i].take().unwrap_or_else(|| {
            let s = own_side(e, e.a, l);
            let sign = if s.normal.dot(e.dir) >= 0.0 { 1.0 } else { -1.0 };
            SidePlane { normal: s.normal * sign, u: s.u }
        });
        let rp = right[i].take().unwrap_or_else(|| {
            let s = own_side(e, e.b, l);
            let sign = if s.normal.dot(e.dir) <= 0.0 { 1.0 } else { -1.0 };
            SidePlane { normal: s.normal * sign, u: s.u }
        });
        wedges.push(WedgeGpu {
            a: point4(e.a),
            b: point4(e.b),
            // w: the edge's connected surface, exact in f32 below 2^24
            // vertices (beyond, neighbouring ids may round together: those
            // objects then add as one, the AAM sum).
            dir: [e.dir.x as f32, e.dir.y as f32, e.dir.z as f32, component[i] as f32],
            front: plane4(e.front),
            back: plane4(e.back),
            hard: plane4(e.n),
            left: plane4(lp.normal),
            right: plane4(rp.normal),
            u_left: plane4(lp.u),
            u_right: plane4(rp.u),
        });
    }
    stats.wedges = wedges.len();
    Wedges { wedges, stats }
}

/// The light intensity of Eq. 1-3 at `p` for wedge `w`, in f64 (the
/// shader's twin, for tests): None when `p` is outside the wedge.
pub fn wedge_intensity(w: &WedgeGpu, p: DVec3) -> Option<f64> {
    let v = |x: [f32; 4]| DVec3::new(f64::from(x[0]), f64::from(x[1]), f64::from(x[2]));
    let (a, b) = (v(w.a), v(w.b));
    let (front, back, left, right) = (v(w.front), v(w.back), v(w.left), v(w.right));
    let f = front.dot(p - a);
    let bk = back.dot(p - a);
    let lt = left.dot(p - a);
    let rt = right.dot(p - b);
    if f > 0.0 || bk < 0.0 || lt < 0.0 || rt < 0.0 {
        return None;
    }
    // Eq. 2: along a side ray u, |t_f| = -F / (N_f.u), |t_b| = B / (N_b.u).
    let side = |u: DVec3| {
        let tf = -f / front.dot(u).max(1e-6);
        let tb = bk / back.dot(u).max(1e-6);
        if tf + tb <= 0.0 {
            0.5
        } else {
            tb / (tf + tb)
        }
    };
    let (s_l, s_r) = (side(v(w.u_left)), side(v(w.u_right)));
    // Eq. 3: distances along the edge direction to the side planes.
    let dir = v(w.dir);
    let t_l = lt / left.dot(dir).max(1e-6);
    let t_r = rt / (-right.dot(dir)).max(1e-6);
    Some(if t_l + t_r <= 0.0 { 0.5 * (s_l + s_r) } else { (t_r * s_l + t_l * s_r) / (t_l + t_r) })
}

/// The half-spaces `n.x <= d` that hold every point whose view of the
/// sphere light (centre `l`, radius `r`) the edge `a..b` of `w` crosses: the
/// region where the per-pixel coverage term of `coverage_term` can be
/// non-zero (the segment's penumbra volume, `{q + t (q - x)}` for q on the
/// edge, x in the sphere, t >= 0). Two planes through the edge's line
/// tangent to the sphere, and at each end a plane through the vertex,
/// tangent to the sphere, with the sphere on one side and the edge on the
/// other (left out where no such plane contains the quad normal: an edge
/// pointing back towards the light). Conservative, unlike 4.1's planes
/// through c -+ r n, which cut the sphere.
pub fn coverage_bounds(w: &WedgeGpu, l: DVec3, r: f64) -> Vec<(DVec3, f64)> {
    let v = |x: [f32; 4]| DVec3::new(f64::from(x[0]), f64::from(x[1]), f64::from(x[2]));
    let (a, b, dir) = (v(w.a), v(w.b), v(w.dir));
    let mut out = Vec::with_capacity(4);
    if (b - a).length() <= 0.0 {
        return out;
    }
    // Across the edge's line: the cone of directions about -u of half-angle
    // asin(r / d), u towards the light in the plane perpendicular to dir.
    let to_light = l - a;
    let across = to_light - dir * to_light.dot(dir);
    let d = across.length();
    if d > r {
        let u = across / d;
        let w2 = dir.cross(u);
        let sin = r / d;
        let cos = (1.0 - sin * sin).max(0.0).sqrt();
        for side in [1.0, -1.0] {
            // Inward normal m of a boundary line: m.(p - a) >= 0 inside.
            let m = -u * sin + w2 * (cos * side);
            out.push((-m, -m.dot(a)));
        }
    }
    // At each end: m = alpha t + beta s, t from the light to the vertex, s
    // perpendicular to it towards the other end, m.(l - v) = -r.
    for (vertex, along) in [(a, dir), (b, -dir)] {
        let to = vertex - l;
        let dist = to.length();
        if dist <= r {
            continue;
        }
        let t = to / dist;
        let s_raw = along - t * along.dot(t);
        if s_raw.length() <= 1e-12 {
            continue;
        }
        let s = s_raw.normalize();
        let alpha = r / dist;
        let m = t * alpha + s * (1.0 - alpha * alpha).max(0.0).sqrt();
        if m.dot(along) >= 0.0 {
            out.push((-m, -m.dot(vertex)));
        }
    }
    out
}

/// The signed area of the part of the unit disk inside the triangle (0, p, q)
/// (positive when p to q turns anticlockwise about 0).
fn disk_triangle(p: glam::DVec2, q: glam::DVec2) -> f64 {
    let sector = |x: glam::DVec2, y: glam::DVec2| 0.5 * x.perp_dot(y).atan2(x.dot(y));
    let e = q - p;
    let (qa, qb, qc) = (e.length_squared(), 2.0 * p.dot(e), p.length_squared() - 1.0);
    let disc = qb * qb - 4.0 * qa * qc;
    if qa <= 0.0 || disc <= 0.0 {
        return sector(p, q);
    }
    let root = disc.sqrt();
    let (t0, t1) = (((-qb - root) / (2.0 * qa)).max(0.0), ((-qb + root) / (2.0 * qa)).min(1.0));
    if t0 >= t1 {
        return sector(p, q);
    }
    let (x0, x1) = (p + e * t0, p + e * t1);
    sector(p, x0) + 0.5 * x0.perp_dot(x1) + sector(x1, q)
}

/// The per-pixel coverage term of wedge `w` at `p` for the sphere light (c,
/// r), in f64 (the shader's twin, `coverage_term` in visibility.wgsl; for
/// tests): the edge is projected from p onto the plane through c facing p,
/// and the part of the light's disk inside the angular sector of the
/// projected edge that lies beyond it (away from c) is the fraction the
/// edge moves from the hard shadow's value: visible when p is behind the
/// quad (h = 0), hidden when in front (h = 1). Returns that fraction, s - h,
/// with s the light intensity; 0 where the projected edge misses the disk.
/// The terms of a closed loop sum with the hard shadow to the exact covered
/// fraction of the disk (the fan decomposition of the projected polygon
/// about c).
pub fn coverage_term(w: &WedgeGpu, p: DVec3, c: DVec3, r: f64) -> f64 {
    let v = |x: [f32; 4]| DVec3::new(f64::from(x[0]), f64::from(x[1]), f64::from(x[2]));
    let (a, b) = (v(w.a), v(w.b));
    let axis = c - p;
    let dist = axis.length();
    if dist <= r * 1.0001 {
        return 0.0;
    }
    let z = axis / dist;
    // Clip the edge to the slab in front of p (depth along z >= eps) and
    // up to the light's plane (depth <= dist): the part beyond the light
    // hides nothing from p (the shader's `coverage_term`).
    let eps = 1e-4 * dist;
    let (da, db) = ((a - p).dot(z), (b - p).dot(z));
    if (da < eps && db < eps) || (da > dist && db > dist) {
        return 0.0;
    }
    let cut = |x: DVec3, dx: f64, y: DVec3, dy: f64| if dx >= eps { x } else { x + (y - x) * ((eps - dx) / (dy - dx)) };
    let (a, b) = (cut(a, da, b, db), cut(b, db, a, da));
    let (da, db) = (da.max(eps), db.max(eps));
    let far = |x: DVec3, dx: f64, y: DVec3, dy: f64| if dx <= dist { x } else { x + (y - x) * ((dx - dist) / (dx - dy)) };
    let (a, b) = (far(a, da, b, db), far(b, db, a, da));
    // The disk seen from p, in the plane through c: radius of the tangent cone there.
    let radius = r * dist / (dist * dist - r * r).sqrt();
    let (e1, e2) = z.any_orthonormal_pair();
    let project = |x: DVec3| {
        let q = (x - p) * (dist / (x - p).dot(z)) - axis;
        glam::DVec2::new(q.dot(e1), q.dot(e2)) / radius
    };
    let (pa, pb) = (project(a), project(b));
    let sector = 0.5 * pa.perp_dot(pb).atan2(pa.dot(pb));
    let beyond = (sector - disk_triangle(pa, pb)).abs() / std::f64::consts::PI;
    let lit = v(w.hard).dot(p - v(w.a)) > 0.0;
    if lit {
        -beyond
    } else {
        beyond
    }
}

/// Screen-space bins of the wedges: tiles of `TILE` pixels, each with the
/// wedges whose part inside the scene's box projects onto it (CSR form).
pub const TILE: u32 = 16;

#[derive(Debug, Clone, Default)]
pub struct Bins {
    pub tiles_x: u32,
    pub tiles_y: u32,
    /// `offsets[t]..offsets[t + 1]` index `indices` for tile t.
    pub offsets: Vec<u32>,
    pub indices: Vec<u32>,
    pub culled: usize,
}

/// The vertices of the convex polyhedron `{x: n.x <= d}` of `planes`
/// (at most a few dozen planes), by enumerating plane triples.
fn polyhedron_vertices(planes: &[(DVec3, f64)]) -> Vec<DVec3> {
    let scale = planes.iter().map(|(_, d)| d.abs()).fold(1e-30, f64::max);
    let mut out = Vec::new();
    for i in 0..planes.len() {
        for j in i + 1..planes.len() {
            for k in j + 1..planes.len() {
                let (a, b, c) = (planes[i], planes[j], planes[k]);
                let det = a.0.dot(b.0.cross(c.0));
                if det.abs() <= 1e-12 {
                    continue;
                }
                let x = (b.0.cross(c.0) * a.1 + c.0.cross(a.0) * b.1 + a.0.cross(b.0) * c.1) / det;
                if !x.is_finite() {
                    continue;
                }
                if planes.iter().all(|(n, d)| n.dot(x) <= d + 1e-9 * scale) {
                    out.push(x);
                }
            }
        }
    }
    out
}

/// The planes, as n.x <= d, holding every point where wedge `w`'s term can
/// be non-zero: front <= 0, back >= 0, left >= 0, right >= 0 (the 2002
/// interpolation's wedge); with `coverage` (the light's centre and radius),
/// the region where the coverage term can be (`coverage_bounds`) instead.
pub fn support_planes(w: &WedgeGpu, coverage: Option<(DVec3, f64)>) -> Vec<(DVec3, f64)> {
    let v = |x: [f32; 4]| DVec3::new(f64::from(x[0]), f64::from(x[1]), f64::from(x[2]));
    let (a, b) = (v(w.a), v(w.b));
    match coverage {
        Some((l, r)) => coverage_bounds(w, l, r),
        None => vec![
            (v(w.front), v(w.front).dot(a)),
            (-v(w.back), -v(w.back).dot(a)),
            (-v(w.left), -v(w.left).dot(a)),
            (-v(w.right), -v(w.right).dot(b)),
        ],
    }
}

crate::gpu_type! {
    /// A wedge's [`support_planes`] as `methods/wedges/tile_cull.wgsl` reads
    /// them: (n, d) per plane, unused ones (0, 0, 0, 1).
    #[derive(Debug, PartialEq)]
    pub struct WedgeBoundsGpu => "WedgeBounds" in "methods/wedges/tile_cull.wgsl" {
        pub planes: [[f32; 4]; 4],
    }
}

/// Every wedge's [`support_planes`] for the tile cull.
pub fn wedge_bounds(wedges: &[WedgeGpu], coverage: Option<(DVec3, f64)>) -> Vec<WedgeBoundsGpu> {
    wedges
        .iter()
        .map(|w| {
            let mut planes = [[0.0, 0.0, 0.0, 1.0]; 4];
            for (slot, (n, d)) in planes.iter_mut().zip(support_planes(w, coverage)) {
                *slot = [n.x as f32, n.y as f32, n.z as f32, d as f32];
            }
            WedgeBoundsGpu { planes }
        })
        .collect()
}

/// Bins `wedges` into tiles of a `size` image seen through `view_proj`
/// (world to clip, wgpu conventions: depth in [0, 1]), clipping each wedge
/// to the box `lo..hi` (every receiver lies in it) and to the camera's near
/// plane, so that every corner left projects in front of the camera.
pub fn bin_wedges(wedges: &[WedgeGpu], view_proj: DMat4, size: (u32, u32), lo: DVec3, hi: DVec3, coverage: Option<(DVec3, f64)>) -> Bins {
    let tiles_x = size.0.div_ceil(TILE);
    let tiles_y = size.1.div_ceil(TILE);
    let pad = (hi - lo).length() * 1e-3 + 1e-6;
    let (lo, hi) = (lo - DVec3::splat(pad), hi + DVec3::splat(pad));
    let v = |x: [f32; 4]| DVec3::new(f64::from(x[0]), f64::from(x[1]), f64::from(x[2]));
    // z_clip >= 0 (the near plane), as n.x <= d, normalised.
    let row = view_proj.row(2);
    let near_n = -row.truncate();
    let near = (near_n / near_n.length().max(1e-300), row.w / near_n.length().max(1e-300));
    let mut ranges: Vec<Option<(u32, u32, u32, u32)>> = Vec::with_capacity(wedges.len());
    let mut culled = 0;
    for w in wedges {
        let (a, b) = (v(w.a), v(w.b));
        // A zero-length edge covers nothing.
        if coverage.is_some() && a == b {
            culled += 1;
            ranges.push(None);
            continue;
        }
        let mut planes = support_planes(w, coverage);
        planes.push(near);
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            planes.push((axis, axis.dot(hi)));
            planes.push((-axis, -axis.dot(lo)));
        }
        let corners = polyhedron_vertices(&planes);
        let (mut x0, mut y0, mut x1, mut y1) = (f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        for c in &corners {
            let clip: DVec4 = view_proj * c.extend(1.0);
            // In front of the near plane, so w >= near > 0 (up to rounding).
            let w = clip.w.max(1e-300);
            // NDC to pixels: x right, y up in NDC; image row 0 at the top.
            let px = (clip.x / w * 0.5 + 0.5) * f64::from(size.0);
            let py = (0.5 - clip.y / w * 0.5) * f64::from(size.1);
            x0 = x0.min(px);
            y0 = y0.min(py);
            x1 = x1.max(px);
            y1 = y1.max(py);
        }
        // A pixel of margin for rounding; empty or off screen means culled.
        let (x0, y0, x1, y1) = (x0 - 1.0, y0 - 1.0, x1 + 1.0, y1 + 1.0);
        let unbounded = corners.is_empty() || !(x0.is_finite() && y0.is_finite() && x1.is_finite() && y1.is_finite());
        let off_screen = x1 < 0.0 || y1 < 0.0 || x0 > f64::from(size.0) || y0 > f64::from(size.1);
        let range = if unbounded || off_screen {
            None
        } else {
            let t = |p: f64, n: u32| ((p.max(0.0) / f64::from(TILE)) as u32).min(n - 1);
            Some((t(x0, tiles_x), t(y0, tiles_y), t(x1, tiles_x), t(y1, tiles_y)))
        };
        culled += usize::from(range.is_none());
        ranges.push(range);
    }
    let n_tiles = (tiles_x * tiles_y) as usize;
    let mut counts = vec![0u32; n_tiles + 1];
    for (tx0, ty0, tx1, ty1) in ranges.iter().flatten() {
        for ty in *ty0..=*ty1 {
            for tx in *tx0..=*tx1 {
                counts[(ty * tiles_x + tx) as usize + 1] += 1;
            }
        }
    }
    for t in 0..n_tiles {
        counts[t + 1] += counts[t];
    }
    let offsets = counts;
    let mut fill = offsets.clone();
    let mut indices = vec![0u32; offsets[n_tiles] as usize];
    for (i, range) in ranges.iter().enumerate() {
        let Some((tx0, ty0, tx1, ty1)) = *range else { continue };
        for ty in ty0..=ty1 {
            for tx in tx0..=tx1 {
                let t = (ty * tiles_x + tx) as usize;
                indices[fill[t] as usize] = i as u32;
                fill[t] += 1;
            }
        }
    }
    Bins { tiles_x, tiles_y, offsets, indices, culled }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tile_cull_works_on_quarters_of_the_bins_tiles() {
        // tile_cull.wgsl's workgroups are quarters of a bin's tile, and the
        // visibility pass finds a pixel's quarter from the tile size.
        assert_eq!(TILE, 16);
        let cull = include_str!("tile_cull.wgsl");
        assert!(cull.contains("@workgroup_size(8, 8)") && cull.contains("i = i + 64u"));
    }

    #[test]
    fn support_planes_hold_the_wedge_in_both_intensities() {
        // An edge under a light: the point of the floor (y = 0) on the line
        // from the light's centre through the edge's middle lies on the hard
        // shadow's boundary, inside the penumbra, so inside both sets of
        // planes; points 10 away from it across the edge, either way, lie outside.
        let l = DVec3::new(0.0, 4.0, 0.0);
        let edges = polygon(&[(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)], 1.0, l);
        let built = penumbra_wedges(&edges, l, 0.5, 0, true);
        let w = &built.wedges[0];
        let v = |x: [f32; 4]| DVec3::new(f64::from(x[0]), f64::from(x[1]), f64::from(x[2]));
        let m = (v(w.a) + v(w.b)) * 0.5;
        let on_floor = l + (m - l) * (l.y / (l.y - m.y));
        let across = (v(w.b) - v(w.a)).cross(DVec3::Y).normalize() * 10.0;
        let inside = |p: DVec3, planes: &[(DVec3, f64)]| planes.iter().all(|(n, d)| n.dot(p) <= *d + 1e-9);
        for coverage in [None, Some((l, 0.5))] {
            let planes = support_planes(w, coverage);
            assert!(!planes.is_empty() && planes.len() <= 4, "{coverage:?}");
            assert!(inside(on_floor, &planes), "{coverage:?}");
            assert!(!inside(on_floor + across, &planes) && !inside(on_floor - across, &planes), "{coverage:?}");
            let gpu = &wedge_bounds(std::slice::from_ref(w), coverage)[0];
            assert_eq!(gpu.planes[planes.len()..].iter().filter(|p| **p != [0.0, 0.0, 0.0, 1.0]).count(), 0);
        }
    }

    fn edge(a: DVec3, b: DVec3, ia: u32, ib: u32) -> SilhouetteEdge {
        SilhouetteEdge { a, b, ia, ib, component: 0 }
    }

    /// The outline of a convex polygon at height y, seen from above, oriented
    /// as the silhouette code does: normals (b - a) x (a - l) away from the polygon.
    fn polygon(points: &[(f64, f64)], y: f64, l: DVec3) -> Vec<SilhouetteEdge> {
        let n = points.len();
        let mut out: Vec<SilhouetteEdge> = (0..n)
            .map(|i| {
                let (p, q) = (points[i], points[(i + 1) % n]);
                edge(DVec3::new(p.0, y, p.1), DVec3::new(q.0, y, q.1), i as u32, ((i + 1) % n) as u32)
            })
            .collect();
        let centroid = out.iter().map(|e| e.a).sum::<DVec3>() / n as f64;
        if (out[0].b - out[0].a).cross(out[0].a - l).dot(centroid - out[0].a) > 0.0 {
            out = out.iter().map(|e| edge(e.b, e.a, e.ib, e.ia)).collect();
        }
        out
    }

    #[test]
    fn adjacent_wedges_share_their_side_plane_and_the_intensity_is_continuous_across_it() {
        let l = DVec3::new(0.2, 5.0, 0.1);
        let edges = polygon(&[(-1.0, -1.0), (1.0, -1.2), (1.3, 0.9), (-0.8, 1.1)], 2.0, l);
        // The paper's construction: continuous (4.2). With repair "cone"
        // the corners' shared lines leave the front and back planes, and
        // the two wedges' side intensities part a little (measured 0.007).
        for (cone, tolerance) in [(false, 1e-4), (true, 0.02)] {
            continuity(&edges, l, cone, tolerance);
        }
    }

    fn continuity(edges: &[SilhouetteEdge], l: DVec3, cone: bool, tolerance: f64) {
        let w = penumbra_wedges(edges, l, 0.6, 0, cone);
        assert_eq!(w.wedges.len(), 4);
        assert_eq!(w.stats.junction_vertices, 0);
        let v = |x: [f32; 4]| DVec3::new(f64::from(x[0]), f64::from(x[1]), f64::from(x[2]));
        for (i, a) in w.wedges.iter().enumerate() {
            // The wedge that starts where this one ends.
            let b = w.wedges.iter().find(|b| b.a == a.b).unwrap_or_else(|| panic!("wedge {i} has a successor"));
            assert!((v(a.right) + v(b.left)).length() < 1e-6, "one plane, opposite inward normals");
            // Points on the shared plane inside both wedges get one intensity.
            let vertex = v(a.b);
            let (u, n) = (v(a.u_right), v(b.left));
            let down = (vertex - l).normalize();
            let mut checked = 0;
            for t in [0.5, 1.0, 2.0] {
                for s in [-0.3, -0.1, 0.0, 0.1, 0.3] {
                    let mut p = vertex + down * t + u * (s * t);
                    p -= n * n.dot(p - vertex);
                    // A hair to each side of the plane, inside each wedge.
                    if let (Some(x), Some(y)) = (wedge_intensity(a, p - n * 1e-7), wedge_intensity(b, p + n * 1e-7)) {
                        assert!((x - y).abs() < tolerance, "{x} {y} at {p}");
                        checked += 1;
                    }
                }
            }
            assert!(checked >= 3, "{checked}");
        }
    }

    #[test]
    fn the_intensity_runs_from_one_on_the_front_plane_to_zero_on_the_back_plane() {
        let l = DVec3::new(0.0, 6.0, 0.0);
        let edges = polygon(&[(-4.0, -1.5), (4.0, -1.5), (4.0, 1.5), (-4.0, 1.5)], 2.0, l);
        let w = penumbra_wedges(&edges, l, 0.8, 0, true);
        // The +z edge's wedge, over its middle on the ground (y = 0).
        let wedge = w.wedges.iter().find(|w| w.a[2] == 1.5 && w.b[2] == 1.5).expect("the +z edge");
        let mut last = f64::INFINITY;
        let mut values = Vec::new();
        for i in 0..=200 {
            let p = DVec3::new(0.0, 0.0, 1.0 + 4.0 * f64::from(i) / 200.0);
            if let Some(s) = wedge_intensity(wedge, p) {
                assert!((0.0..=1.0).contains(&s));
                // Away from the caster, more of the light: s grows with z.
                assert!(last == f64::INFINITY || s >= last - 1e-9, "{last} {s}");
                last = s;
                values.push(s);
            }
        }
        assert!(values.len() > 20 && values[0] < 0.03 && *values.last().unwrap() > 0.97, "{values:?}");
        // Near half way on the hard-shadow plane (z = 1.5 * 6 / 4 = 2.25 on
        // the ground): not exactly, as the side rays are perpendicular to
        // the light ray through the edge's end, not to the one through p
        // (measured 0.550 here, 8 units from the ends).
        let mid = wedge_intensity(wedge, DVec3::new(0.0, 0.0, 2.25)).unwrap();
        assert!((mid - 0.5).abs() < 0.06, "{mid}");
    }

    #[test]
    fn acute_vertices_get_extra_wedges_and_right_angles_none() {
        let l = DVec3::new(0.0, 6.0, 0.0);
        // A thin triangle: two tips of about 20 degrees, one of 140.
        let spike = polygon(&[(-2.0, 0.0), (2.0, -0.35), (2.0, 0.35)], 2.0, l);
        let none = penumbra_wedges(&spike, l, 0.5, 0, true);
        let some = penumbra_wedges(&spike, l, 0.5, 6, true);
        assert_eq!(none.stats.extra_wedges, 0);
        // ceil(6 * turn / 120 deg) at each of the two acute tips: turns near 160 and 100 degrees.
        assert!(some.stats.extra_wedges >= 2 * 6, "{:?}", some.stats);
        assert_eq!(some.wedges.len(), 3 + some.stats.extra_wedges);
        let square = polygon(&[(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)], 2.0, l);
        assert_eq!(penumbra_wedges(&square, l, 0.5, 6, true).stats.extra_wedges, 0);
    }

    #[test]
    fn degenerate_edges_make_finite_wedges() {
        let l = DVec3::new(0.0, 6.0, 0.0);
        let edges = vec![
            // Collinear run.
            edge(DVec3::new(-1.0, 2.0, 1.0), DVec3::new(0.0, 2.0, 1.0), 0, 1),
            edge(DVec3::new(0.0, 2.0, 1.0), DVec3::new(1.0, 2.0, 1.0), 1, 2),
            // Pointing at the light.
            edge(DVec3::new(0.0, 1.0, 0.0), DVec3::new(0.0, 2.0, 0.0), 3, 4),
            // Turning straight back.
            edge(DVec3::new(1.0, 2.0, 1.0), DVec3::new(0.0, 2.0, 1.0), 2, 5),
        ];
        for r in [1e-9, 0.5, 3.0] {
            let w = penumbra_wedges(&edges, l, r, 8, true);
            assert_eq!(w.stats.silhouette.light_parallel_edges, 1);
            for x in &w.wedges {
                let all = [x.a, x.b, x.dir, x.front, x.back, x.hard, x.left, x.right, x.u_left, x.u_right];
                assert!(all.iter().flatten().all(|c| c.is_finite()), "{x:?}");
                for p in [DVec3::new(0.0, 0.0, 1.5), DVec3::new(0.5, 0.0, 1.2), DVec3::new(-0.7, 1.0, 1.1)] {
                    if let Some(s) = wedge_intensity(x, p) {
                        assert!((0.0..=1.0).contains(&s), "{s}");
                    }
                }
            }
        }
    }

    /// Whether (x, z) lies inside the polygon (even-odd rule).
    fn inside(points: &[(f64, f64)], x: f64, z: f64) -> bool {
        let mut odd = false;
        for i in 0..points.len() {
            let (p, q) = (points[i], points[(i + 1) % points.len()]);
            if (p.1 > z) != (q.1 > z) && x < p.0 + (z - p.1) * (q.0 - p.0) / (q.1 - p.1) {
                odd = !odd;
            }
        }
        odd
    }

    /// The fraction of the light's disk (in the plane through `l` facing
    /// `p`, radius that of the tangent cone there, as the coverage term
    /// measures it) that the flat polygon at height `y` hides from `p`,
    /// counted on a fine grid.
    fn covered_fraction(points: &[(f64, f64)], y: f64, l: DVec3, r: f64, p: DVec3) -> f64 {
        let axis = l - p;
        let dist = axis.length();
        let radius = r * dist / (dist * dist - r * r).sqrt();
        let (e1, e2) = (axis / dist).any_orthonormal_pair();
        let n = 400;
        let (mut hit, mut all) = (0usize, 0usize);
        for i in 0..n {
            for j in 0..n {
                let (u, v) = ((f64::from(i) + 0.5) / f64::from(n) * 2.0 - 1.0, (f64::from(j) + 0.5) / f64::from(n) * 2.0 - 1.0);
                if u * u + v * v > 1.0 {
                    continue;
                }
                all += 1;
                let x = l + (e1 * u + e2 * v) * radius;
                let t = (y - p.y) / (x.y - p.y);
                let q = p + (x - p) * t;
                hit += usize::from((0.0..=1.0).contains(&t) && inside(points, q.x, q.z));
            }
        }
        hit as f64 / all as f64
    }

    #[test]
    fn coverage_terms_of_a_closed_loop_and_the_hard_shadow_give_the_covered_fraction() {
        // A square and an L (concave), under a light smaller and one larger
        // than they are; ground points in the umbra, the penumbra, outside.
        let l = DVec3::new(0.2, 5.0, 0.1);
        let square = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
        let ell = [(-1.0, -1.0), (1.0, -1.0), (1.0, -0.2), (-0.2, -0.2), (-0.2, 1.0), (-1.0, 1.0)];
        let mut checked = 0;
        for points in [&square[..], &ell[..]] {
            let edges = polygon(points, 2.0, l);
            for r in [0.6, 2.5] {
                let w = penumbra_wedges(&edges, l, r, 0, false);
                for x in [-2.0, -1.4, -0.9, -0.3, 0.0, 0.4, 1.1, 1.6, 2.4] {
                    for z in [-1.8, -0.6, 0.1, 0.9, 1.7] {
                        let p = DVec3::new(x, 0.0, z);
                        // The hard shadow: the light centre seen through the polygon.
                        let t = (2.0 - p.y) / (l.y - p.y);
                        let q = p + (l - p) * t;
                        let hard = if inside(points, q.x, q.z) { 0.0 } else { 1.0 };
                        let v = hard + w.wedges.iter().map(|x| coverage_term(x, p, l, r)).sum::<f64>();
                        let truth = 1.0 - covered_fraction(points, 2.0, l, r, p);
                        // The grid counts to about 1e-3 (400 x 400 over the disk).
                        assert!((v - truth).abs() < 4e-3, "r {r} at {p}: {v} against {truth}");
                        checked += usize::from(truth > 0.02 && truth < 0.98);
                    }
                }
            }
        }
        assert!(checked > 40, "{checked} penumbra points");
    }

    #[test]
    fn an_edge_beyond_the_light_hides_nothing() {
        // A square 2 above the light, seen from the ground below the light:
        // the light lies between the points and every edge. Projected from
        // them onto the light's plane the loop would surround the disk's
        // centre (before the clip it gave each point about half the light
        // per edge crossing the disk).
        let l = DVec3::new(0.2, 5.0, 0.1);
        let square = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)];
        let w = penumbra_wedges(&polygon(&square, 7.0, l), l, 0.6, 0, false);
        for p in [DVec3::new(0.3, 0.0, 0.2), DVec3::new(2.0, 0.0, -1.0), DVec3::new(0.2, 4.0, 0.1)] {
            for x in &w.wedges {
                assert_eq!(coverage_term(x, p, l, 0.6), 0.0, "{p}");
            }
        }
        // Below the light the same square's terms still count (the closed
        // loop's sum is the test above).
        let below = penumbra_wedges(&polygon(&square, 3.0, l), l, 0.6, 0, false);
        assert!(below.wedges.iter().any(|x| coverage_term(x, DVec3::new(0.3, 0.0, 0.2), l, 0.6) != 0.0));
    }

    #[test]
    fn coverage_bounds_hold_every_point_the_edge_can_shadow() {
        let l = DVec3::new(0.3, 5.0, -0.2);
        let edges = polygon(&[(-1.0, -1.0), (1.0, -1.2), (1.3, 0.9), (-0.8, 1.1)], 2.0, l);
        // Plus an edge pointing away from the light and one pointing back at it.
        let mut all = edges.clone();
        all.push(edge(DVec3::new(2.0, 2.0, 0.0), DVec3::new(2.2, 1.0, 0.1), 10, 11));
        all.push(edge(DVec3::new(-2.0, 1.0, 0.0), DVec3::new(-2.1, 2.5, 0.2), 12, 13));
        for r in [0.2, 1.0, 2.0] {
            let w = penumbra_wedges(&all, l, r, 0, false);
            let mut state = 12345u64;
            let mut uniform = || {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64
            };
            for x in &w.wedges {
                let bounds = coverage_bounds(x, l, r);
                let v = |c: [f32; 4]| DVec3::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2]));
                let (a, b) = (v(x.a), v(x.b));
                for _ in 0..2000 {
                    // q on the edge, s on the sphere, p beyond q seen from s.
                    let q = a + (b - a) * uniform();
                    let d = DVec3::new(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5).normalize_or_zero();
                    let s = l + d * (r * uniform().cbrt());
                    let p = q + (q - s) * (4.0 * uniform());
                    for (n, dd) in &bounds {
                        assert!(n.dot(p) <= dd + 1e-9 * (1.0 + dd.abs()), "{p} outside {n} {dd}");
                    }
                }
                // And where the term is not zero, the point is inside.
                for _ in 0..500 {
                    let p = DVec3::new(uniform() * 8.0 - 4.0, uniform() * 2.0 - 0.5, uniform() * 8.0 - 4.0);
                    if coverage_term(x, p, l, r) != 0.0 {
                        assert!(bounds.iter().all(|(n, dd)| n.dot(p) <= dd + 1e-9), "{p}");
                    }
                }
            }
        }
    }

    #[test]
    fn bins_cover_the_wedges_footprint_and_cull_what_leaves_the_box() {
        let l = DVec3::new(0.0, 6.0, 0.0);
        let edges = polygon(&[(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)], 2.0, l);
        let w = penumbra_wedges(&edges, l, 0.5, 0, true);
        let camera = crate::scene::Camera { eye: [0.0, 8.0, 0.01], target: [0.0; 3], up: [0.0, 1.0, 0.0], fov_y_degrees: 60.0, width: 64, height: 64 };
        let (p, _, _) = camera.projection(glam::Vec3::new(-5.0, -0.1, -5.0), glam::Vec3::new(5.0, 2.5, 5.0));
        let view_proj = DMat4::from_cols_array(&(p * camera.view()).to_cols_array().map(f64::from));
        let bins = bin_wedges(&w.wedges, view_proj, (64, 64), DVec3::new(-5.0, -0.1, -5.0), DVec3::new(5.0, 2.5, 5.0), None);
        assert_eq!((bins.tiles_x, bins.tiles_y, bins.culled), (4, 4, 0));
        assert_eq!(bins.offsets.len(), 17);
        assert_eq!(*bins.offsets.last().unwrap() as usize, bins.indices.len());
        // Every wedge is binned somewhere; none in every tile (they are narrow).
        for i in 0..4u32 {
            let n = bins.indices.iter().filter(|&&x| x == i).count();
            assert!(n > 0 && n < 16, "{i}: {n}");
        }
        // A camera inside the box: the wedges are clipped at its near plane,
        // not binned everywhere.
        let inside = crate::scene::Camera { eye: [0.0, 1.0, 4.0], target: [0.0; 3], up: [0.0, 1.0, 0.0], fov_y_degrees: 60.0, width: 64, height: 64 };
        let (p, _, _) = inside.projection(glam::Vec3::new(-5.0, -0.1, -5.0), glam::Vec3::new(5.0, 2.5, 5.0));
        let near_view = DMat4::from_cols_array(&(p * inside.view()).to_cols_array().map(f64::from));
        let close = bin_wedges(&w.wedges, near_view, (64, 64), DVec3::new(-5.0, -0.1, -5.0), DVec3::new(5.0, 2.5, 5.0), None);
        assert!(close.indices.len() < 4 * 16 && !close.indices.is_empty(), "{}", close.indices.len());
        // A box that ends above the wedges culls them all.
        let culled = bin_wedges(&w.wedges, view_proj, (64, 64), DVec3::new(-5.0, 3.0, -5.0), DVec3::new(5.0, 4.0, 5.0), None);
        assert_eq!(culled.culled, 4);
    }
}
