//! Mesh connectivity for the silhouette methods (Cournia 4.1.1): for each
//! edge, the faces it belongs to, in a winged-edge spirit, built from
//! positions across every mesh of a scene (SPEC section 3: a surface handed
//! over as a triangle soup, in pieces, doubled, with reversed windings or
//! with slivers casts the shadow of its welded form; issue 27).
//!
//! In order ([`Topology::from_parts`]):
//! 1. **Weld.** Corners closer than a tolerance are one vertex: the
//!    tolerance of a mesh is [`WELD_TOLERANCE`] times its bounding box's
//!    diagonal, and two corners of different meshes weld within the smaller
//!    of their meshes' tolerances. Clusters are closed transitively (union-find).
//! 2. **Degenerate faces.** A face whose welded corners repeat, or whose
//!    smallest altitude is within its mesh's tolerance (zero-area faces,
//!    needles whose short edge welded, caps whose third corner lies on the
//!    opposite edge), has no area and makes no edge of its own. Where a cap
//!    was glued into the surface along the chain `a - c - b` (a T-junction),
//!    the faces on `a - b` are split at `c` so the chain stays connected.
//! 3. **Duplicates.** Faces with the same three welded corners, in either
//!    winding, are one face (a doubled part casts once).
//! 4. **Windings.** Faces are re-wound so that two faces sharing an edge
//!    traverse it in opposite directions wherever the surface allows
//!    (orientable components); every triangle casts (SPEC 3), so windings
//!    decide nothing about the shadow.

use std::collections::HashMap;

use glam::DVec3;

use crate::error::{Error, Result};

/// The weld tolerance, relative to each mesh's bounding-box diagonal.
///
/// Measured over the 17 meshes of `../shared/meshes` and its corpus
/// (`tests/test_invariance.py::test_weld_tolerance_is_below_every_real_feature`
/// prints them): the shortest edge is 1.2e-4 of its
/// mesh's diagonal (Sponza; 7e-4 and above elsewhere) and the smallest
/// altitude of a face with area is 5.6e-5 (the full bunny), so 1e-5 welds no
/// two corners of a real mesh that its file keeps apart. A soup whose
/// corners were moved by up to 1e-6 of the mesh's size (rounding in an
/// exporter) has copies at most 3.5e-6 of the diagonal apart: the tolerance
/// welds them with a margin of about three.
pub const WELD_TOLERANCE: f64 = 1e-5;

/// No face on this side of the edge.
pub const NO_FACE: u32 = u32::MAX;

/// An undirected edge between welded vertices `v[0] < v[1]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    pub v: [u32; 2],
    /// The face that traverses the edge `v[0] -> v[1]`, and the one that
    /// traverses it `v[1] -> v[0]` (counter-clockwise winding), or [`NO_FACE`].
    pub faces: [u32; 2],
}

/// An edge with more than two faces, or two faces that traverse it the same
/// way (a non-orientable surface): every face on it, in no order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NonManifoldEdge {
    pub v: [u32; 2],
    pub faces: Vec<u32>,
}

/// What connectivity found, for the render's stats.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ConnectivityStats {
    /// Input corners welded into another corner.
    pub corners_welded: usize,
    /// Meshes joined to another mesh by a shared edge (a surface in pieces).
    pub pieces_joined: usize,
    /// Faces with no area (repeated welded corners, or an altitude within the tolerance).
    pub degenerate_faces: usize,
    /// Faces on the same three welded corners as an earlier face.
    pub duplicate_faces: usize,
    /// Faces re-wound to agree with their neighbours.
    pub faces_rewound: usize,
    /// Faces split where a cap left a T-junction.
    pub t_junction_splits: usize,
    /// Edges with one face.
    pub open_edges: usize,
    /// Edges with more than two faces, or two that cannot be wound apart.
    pub non_manifold_edges: usize,
}

/// The geometry of one mesh for [`Topology::from_parts`].
#[derive(Debug, Clone, Copy)]
pub struct Part<'a> {
    pub vertices: &'a [DVec3],
    pub faces: &'a [[u32; 3]],
}

/// Connectivity of a scene's meshes (or of one mesh).
#[derive(Debug, Clone)]
pub struct Topology {
    /// Welded vertex index of each input vertex, the parts' vertices in order.
    pub weld: Vec<u32>,
    /// Position of each welded vertex (world space).
    pub positions: Vec<DVec3>,
    /// Faces in welded indices: degenerate and duplicate ones removed,
    /// windings made consistent.
    pub faces: Vec<[u32; 3]>,
    /// The part (mesh) each face comes from.
    pub face_part: Vec<u32>,
    pub edges: Vec<Edge>,
    /// Edges that are not two-sided (not in `edges`).
    pub non_manifold: Vec<NonManifoldEdge>,
    /// Edges with one face.
    pub boundary_edges: usize,
    /// Edges with more than two faces, or two faces of the same winding.
    pub non_manifold_edges: usize,
    /// The connected surface each welded vertex belongs to (faces sharing a
    /// vertex are connected), named by its smallest vertex: one object as
    /// the light sees it, however many meshes or pieces it came in.
    pub components: Vec<u32>,
    pub stats: ConnectivityStats,
}

/// Union-find over welded corners; the smallest index represents its set.
struct Clusters(Vec<u32>);

impl Clusters {
    fn find(&mut self, mut i: u32) -> u32 {
        while self.0[i as usize] != i {
            let parent = self.0[self.0[i as usize] as usize];
            self.0[i as usize] = parent;
            i = parent;
        }
        i
    }

    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        self.0[hi as usize] = lo;
    }
}

/// Cluster representative of every corner: corners within
/// `min(tolerance[i], tolerance[j])` of each other are one vertex.
///
/// Each corner goes into a hash grid at its own tolerance's level (cells of
/// the power of two at or above it); a corner looks for partners in the 27
/// cells around it at every level at or below its own, which holds every
/// corner whose tolerance (the smaller of the pair's) reaches it, so a
/// floor's coarse tolerance never makes a fine mesh's corners share cells.
fn weld_clusters(points: &[DVec3], tolerance: &[f64]) -> Clusters {
    let mut clusters = Clusters((0..points.len() as u32).collect());
    // Exact duplicates first (tolerance 0 welds only these; +0.0 and -0.0 are one point).
    let mut exact: HashMap<[u64; 3], u32> = HashMap::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        let key = [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
        let first = *exact.entry(key).or_insert(i as u32);
        if first != i as u32 {
            clusters.union(first, i as u32);
        }
    }
    let level = |t: f64| if t > 0.0 && t.is_finite() { Some(t.log2().ceil() as i32) } else { None };
    let mut grids: HashMap<i32, HashMap<[i64; 3], Vec<u32>>> = HashMap::new();
    for (i, p) in points.iter().enumerate() {
        if let Some(l) = level(tolerance[i]) {
            let cell = (2f64).powi(l);
            let key = (*p / cell).floor().to_array().map(|c| c as i64);
            grids.entry(l).or_default().entry(key).or_default().push(i as u32);
        }
    }
    let mut levels: Vec<i32> = grids.keys().copied().collect();
    levels.sort_unstable();
    for (i, p) in points.iter().enumerate() {
        let Some(own) = level(tolerance[i]) else { continue };
        for &l in levels.iter().take_while(|&&l| l <= own) {
            let cell = (2f64).powi(l);
            let c = (*p / cell).floor().to_array().map(|c| c as i64);
            let grid = &grids[&l];
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(near) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else { continue };
                        for &j in near {
                            if j as usize != i && points[j as usize].distance(*p) <= tolerance[i].min(tolerance[j as usize]) {
                                clusters.union(i as u32, j);
                            }
                        }
                    }
                }
            }
        }
    }
    clusters
}

/// Twice the area of triangle `abc` over its longest edge: its smallest altitude.
fn smallest_altitude(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let longest = (b - a).length().max((c - b).length()).max((a - c).length());
    // A triangle whose corners coincide has no altitude at all.
    if longest <= 0.0 {
        return 0.0;
    }
    (b - a).cross(c - a).length() / longest
}

fn undirected(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

impl Topology {
    /// Connectivity of one mesh, welding only corners at identical positions.
    pub fn build(positions: &[DVec3], faces: &[[u32; 3]]) -> Self {
        Self::from_parts(&[Part { vertices: positions, faces }], 0.0)
    }

    /// Connectivity across every part (a scene's meshes), welding corners
    /// within `relative_tolerance` times their part's bounding-box diagonal
    /// ([`WELD_TOLERANCE`] for the silhouette methods; 0 welds identical
    /// positions only). Face indices must be in range (`Scene::prepare` checks them).
    pub fn from_parts(parts: &[Part<'_>], relative_tolerance: f64) -> Self {
        let mut stats = ConnectivityStats::default();
        let mut points = Vec::new();
        let mut tolerance = Vec::new();
        let mut part_tolerance = Vec::with_capacity(parts.len());
        for part in parts {
            let (lo, hi) = part.vertices.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
            let diagonal = if part.vertices.is_empty() { 0.0 } else { (hi - lo).length() };
            let t = relative_tolerance * diagonal;
            part_tolerance.push(t);
            points.extend_from_slice(part.vertices);
            tolerance.extend(std::iter::repeat_n(t, part.vertices.len()));
        }
        let mut clusters = weld_clusters(&points, &tolerance);
        // Welded indices in order of first appearance; a cluster sits at its first corner.
        let mut index_of_root: HashMap<u32, u32> = HashMap::new();
        let mut positions = Vec::new();
        let weld: Vec<u32> = (0..points.len() as u32)
            .map(|i| {
                let root = clusters.find(i);
                *index_of_root.entry(root).or_insert_with(|| {
                    positions.push(points[root as usize]);
                    (positions.len() - 1) as u32
                })
            })
            .collect();
        stats.corners_welded = points.len() - positions.len();

        // Faces in welded indices; degenerate ones out, caps kept aside.
        let mut faces = Vec::new();
        let mut face_part = Vec::new();
        let mut caps = Vec::new();
        let mut offset = 0u32;
        for (p, part) in parts.iter().enumerate() {
            for f in part.faces {
                let w = f.map(|i| weld[(offset + i) as usize]);
                if w[0] == w[1] || w[1] == w[2] || w[2] == w[0] {
                    stats.degenerate_faces += 1;
                    continue;
                }
                let [a, b, c] = w.map(|i| positions[i as usize]);
                if smallest_altitude(a, b, c) <= part_tolerance[p] {
                    stats.degenerate_faces += 1;
                    caps.push(w);
                    continue;
                }
                faces.push(w);
                face_part.push(p as u32);
            }
            offset += part.vertices.len() as u32;
        }
        split_t_junctions(&positions, &mut faces, &mut face_part, &caps, &mut stats);

        // Duplicates: the same corners in either winding.
        let mut seen: HashMap<[u32; 3], ()> = HashMap::with_capacity(faces.len());
        let mut kept = 0;
        for i in 0..faces.len() {
            let mut key = faces[i];
            key.sort_unstable();
            if seen.insert(key, ()).is_some() {
                stats.duplicate_faces += 1;
                continue;
            }
            faces[kept] = faces[i];
            face_part[kept] = face_part[i];
            kept += 1;
        }
        faces.truncate(kept);
        face_part.truncate(kept);

        stats.faces_rewound = orient(&mut faces);
        stats.pieces_joined = pieces_joined(&faces, &face_part, parts.len());

        // Directed half-edges per undirected edge: (forward faces, backward faces).
        let mut sides: HashMap<(u32, u32), (Vec<u32>, Vec<u32>)> = HashMap::with_capacity(faces.len() * 3 / 2);
        for (fi, f) in faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                let entry = sides.entry(undirected(a, b)).or_default();
                if a < b {
                    entry.0.push(fi as u32);
                } else {
                    entry.1.push(fi as u32);
                }
            }
        }
        let mut edges = Vec::with_capacity(sides.len());
        let mut non_manifold = Vec::new();
        let mut boundary_edges = 0;
        let mut keys: Vec<_> = sides.into_iter().collect();
        keys.sort_unstable_by_key(|(k, _)| *k);
        for ((a, b), (forward, backward)) in keys {
            match (forward.len(), backward.len()) {
                (1, 1) => edges.push(Edge { v: [a, b], faces: [forward[0], backward[0]] }),
                (1, 0) => {
                    boundary_edges += 1;
                    edges.push(Edge { v: [a, b], faces: [forward[0], NO_FACE] });
                }
                (0, 1) => {
                    boundary_edges += 1;
                    edges.push(Edge { v: [a, b], faces: [NO_FACE, backward[0]] });
                }
                _ => non_manifold.push(NonManifoldEdge { v: [a, b], faces: forward.into_iter().chain(backward).collect() }),
            }
        }
        let non_manifold_edges = non_manifold.len();
        stats.open_edges = boundary_edges;
        stats.non_manifold_edges = non_manifold_edges;
        let mut connected = Clusters((0..positions.len() as u32).collect());
        for f in &faces {
            connected.union(f[0], f[1]);
            connected.union(f[0], f[2]);
        }
        let components = (0..positions.len() as u32).map(|v| connected.find(v)).collect();
        Self { weld, positions, faces, face_part, edges, non_manifold, boundary_edges, non_manifold_edges, components, stats }
    }

    /// Refuses surfaces that are not closed 2-manifolds (what PVM assumes,
    /// Cournia 4.1.1), naming a mesh with such an edge (`names`: the
    /// parts' names) and the edge counts. With `allow_open`, every surface
    /// is accepted: edges with one face or with other than two faces wound
    /// apart get the silhouette test of `silhouettes::silhouette` (all their
    /// faces on one side).
    pub fn require_closed(&self, names: &[&str], allow_open: bool) -> Result<()> {
        if allow_open {
            return Ok(());
        }
        let name_of = |face: u32| names.get(self.face_part[face as usize] as usize).copied().unwrap_or("mesh");
        if let Some(e) = self.non_manifold.first() {
            return Err(Error::mesh(
                name_of(e.faces[0]),
                format!(
                    "is not a 2-manifold: {} edges (welded across the scene's meshes) have more than two \
                     faces or two faces that cannot be wound apart; pass open_edges='silhouette' to take \
                     such edges as silhouette edges where all their faces lie on one side",
                    self.non_manifold_edges
                ),
            ));
        }
        if let Some(e) = self.edges.iter().find(|e| e.faces.contains(&NO_FACE)) {
            let face = if e.faces[0] == NO_FACE { e.faces[1] } else { e.faces[0] };
            return Err(Error::mesh(
                name_of(face),
                format!(
                    "is not closed: {} boundary edges (edges with one face, welded across the scene's \
                     meshes); close the mesh, or pass open_edges='silhouette' to treat boundary edges as \
                     silhouette edges",
                    self.boundary_edges
                ),
            ));
        }
        Ok(())
    }

    /// Unit face normal (zero for a zero-area face).
    pub fn face_normal(&self, f: u32) -> DVec3 {
        let [a, b, c] = self.faces[f as usize].map(|i| self.positions[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// The corner of face `f` that is not on edge `e`.
    pub fn opposite_vertex(&self, f: u32, e: &Edge) -> DVec3 {
        self.opposite(f, e.v)
    }

    /// The corner of face `f` that is not on the edge between welded vertices `v`.
    pub fn opposite(&self, f: u32, v: [u32; 2]) -> DVec3 {
        let face = self.faces[f as usize];
        let i = face.iter().copied().find(|i| *i != v[0] && *i != v[1]).unwrap_or(face[0]);
        self.positions[i as usize]
    }
}

/// Where a cap `[a, b, c]` (corner `c` on the edge `a - b`, its longest)
/// was glued into the surface along `a - c` and `c - b` while other faces
/// hold `a - b`, those faces are split at `c` (a T-junction zipped), so that
/// removing the cap leaves no open edges. A loose sliver only goes.
fn split_t_junctions(positions: &[DVec3], faces: &mut Vec<[u32; 3]>, face_part: &mut Vec<u32>, caps: &[[u32; 3]], stats: &mut ConnectivityStats) {
    if caps.is_empty() {
        return;
    }
    let mut on_edge: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (fi, f) in faces.iter().enumerate() {
        for k in 0..3 {
            on_edge.entry(undirected(f[k], f[(k + 1) % 3])).or_default().push(fi as u32);
        }
    }
    for cap in caps {
        // The longest edge is the one the third corner lies on.
        let len = |k: usize| positions[cap[k] as usize].distance(positions[cap[(k + 1) % 3] as usize]);
        let k = (0..3).max_by(|&i, &j| len(i).total_cmp(&len(j))).unwrap_or(0);
        let (a, b, c) = (cap[k], cap[(k + 1) % 3], cap[(k + 2) % 3]);
        let glued = |x: u32, y: u32| on_edge.get(&undirected(x, y)).is_some_and(|f| !f.is_empty());
        if !(glued(a, c) && glued(c, b)) {
            continue;
        }
        let Some(split) = on_edge.remove(&undirected(a, b)) else { continue };
        for fi in split {
            let f = faces[fi as usize];
            // Rotate so that the face reads (x, y, d) with {x, y} = {a, b}.
            let r = (0..3).find(|&r| undirected(f[r], f[(r + 1) % 3]) == undirected(a, b)).unwrap_or(0);
            let (x, y, d) = (f[r], f[(r + 1) % 3], f[(r + 2) % 3]);
            let (first, second) = ([x, c, d], [c, y, d]);
            faces[fi as usize] = first;
            faces.push(second);
            face_part.push(face_part[fi as usize]);
            let new = faces.len() as u32 - 1;
            for (edge, face) in [(undirected(x, c), fi), (undirected(c, d), fi), (undirected(c, y), new), (undirected(y, d), new), (undirected(c, d), new)] {
                on_edge.entry(edge).or_default().push(face);
            }
            if let Some(list) = on_edge.get_mut(&undirected(y, d)) {
                list.retain(|&g| g != fi);
            }
            stats.t_junction_splits += 1;
        }
    }
}

/// Re-winds faces so that neighbours across an edge with two faces
/// traverse it in opposite directions, component by component (breadth
/// first from its first face, then the smaller set flipped); returns how
/// many faces were re-wound. Edges of a non-orientable surface stay as they are.
fn orient(faces: &mut [[u32; 3]]) -> usize {
    let mut on_edge: HashMap<(u32, u32), Vec<u32>> = HashMap::with_capacity(faces.len() * 3 / 2);
    for (fi, f) in faces.iter().enumerate() {
        for k in 0..3 {
            on_edge.entry(undirected(f[k], f[(k + 1) % 3])).or_default().push(fi as u32);
        }
    }
    let forward = |f: &[u32; 3], a: u32, b: u32| (0..3).any(|k| f[k] == a && f[(k + 1) % 3] == b);
    let mut flip: Vec<Option<bool>> = vec![None; faces.len()];
    let mut rewound = 0;
    for start in 0..faces.len() {
        if flip[start].is_some() {
            continue;
        }
        flip[start] = Some(false);
        let mut component = vec![start as u32];
        let mut next = 0;
        while next < component.len() {
            let fi = component[next];
            next += 1;
            let f = faces[fi as usize];
            let flipped = flip[fi as usize] == Some(true);
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                let Some(neighbours) = on_edge.get(&undirected(a, b)) else { continue };
                if neighbours.len() != 2 {
                    continue;
                }
                let g = if neighbours[0] == fi { neighbours[1] } else { neighbours[0] };
                if flip[g as usize].is_some() {
                    continue;
                }
                // As wound after this face's flip, the neighbour must run b -> a.
                let (a, b) = if flipped { (b, a) } else { (a, b) };
                flip[g as usize] = Some(forward(&faces[g as usize], a, b));
                component.push(g);
            }
        }
        let flipped = component.iter().filter(|&&g| flip[g as usize] == Some(true)).count();
        let invert = flipped * 2 > component.len();
        for &g in &component {
            if (flip[g as usize] == Some(true)) != invert {
                let f = &mut faces[g as usize];
                f.swap(1, 2);
                rewound += 1;
            }
        }
    }
    rewound
}

/// How many parts joined another through a shared edge: parts less the
/// groups of parts that edges connect (parts with no faces left count as their own group).
fn pieces_joined(faces: &[[u32; 3]], face_part: &[u32], parts: usize) -> usize {
    let mut groups = Clusters((0..parts as u32).collect());
    let mut first_on_edge: HashMap<(u32, u32), u32> = HashMap::with_capacity(faces.len() * 3 / 2);
    for (fi, f) in faces.iter().enumerate() {
        for k in 0..3 {
            let part = face_part[fi];
            let other = *first_on_edge.entry(undirected(f[k], f[(k + 1) % 3])).or_insert(part);
            if other != part {
                groups.union(other, part);
            }
        }
    }
    (0..parts as u32).filter(|&p| groups.find(p) != p).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        (p, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    }

    #[test]
    fn closed_tetrahedron_has_six_two_sided_edges() {
        let (p, f) = tetrahedron();
        let t = Topology::build(&p, &f);
        assert_eq!(t.edges.len(), 6);
        assert!(t.edges.iter().all(|e| e.faces[0] != NO_FACE && e.faces[1] != NO_FACE));
        t.require_closed(&["tet"], false).unwrap();
    }

    #[test]
    fn split_vertices_are_welded() {
        let (mut p, mut f) = tetrahedron();
        p.push(DVec3::Z); // a duplicate of vertex 3
        f[3] = [1, 2, 4];
        let t = Topology::build(&p, &f);
        assert_eq!(t.positions.len(), 4);
        t.require_closed(&["tet"], false).unwrap();
    }

    #[test]
    fn open_and_non_manifold_meshes_are_named() {
        let (p, f) = tetrahedron();
        let open = Topology::build(&p, &f[..3]);
        assert_eq!(open.boundary_edges, 3);
        let err = open.require_closed(&["lid"], false).unwrap_err().to_string();
        assert!(err.contains("'lid'") && err.contains("3 boundary edges"), "{err}");
        open.require_closed(&["lid"], true).unwrap();
        let err = open.require_closed(&["lid"], false).unwrap_err().to_string();
        assert!(err.contains("open_edges='silhouette'"), "{err}");
        let mut fins = f.clone();
        let mut q = p.clone();
        q.push(DVec3::new(0.4, 0.3, -0.6));
        fins.push([0, 1, 4]); // a third face on edge 0-1
        let finned = Topology::build(&q, &fins);
        let err = finned.require_closed(&["fin"], false).unwrap_err().to_string();
        assert!(err.contains("not a 2-manifold") && err.contains("open_edges='silhouette'"), "{err}");
        finned.require_closed(&["fin"], true).unwrap();
        // The edge keeps all its faces: two of the tetrahedron's and the fin.
        assert_eq!(finned.non_manifold.len(), 1);
        assert_eq!(finned.non_manifold[0].faces.len(), 3);
        // The other five edges of the tetrahedron and the fin's two open edges.
        assert_eq!((finned.edges.len(), finned.boundary_edges), (7, 2));
    }
    /// An octahedron (closed, outward windings) of radius `r` at `c`.
    fn octahedron(c: DVec3, r: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p = [DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z].map(|d| c + d * r).to_vec();
        let f = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        (p, f)
    }

    fn sorted_edges(t: &Topology) -> Vec<([i64; 3], [i64; 3])> {
        // Edges by their ends' positions (rounded to 1e-4), so two topologies compare by geometry.
        let round = |p: DVec3| (p * 1e4).round().to_array().map(|c| c as i64);
        let mut e: Vec<_> = t
            .edges
            .iter()
            .map(|e| {
                let (a, b) = (round(t.positions[e.v[0] as usize]), round(t.positions[e.v[1] as usize]));
                (a.min(b), a.max(b))
            })
            .collect();
        e.sort_unstable();
        e
    }

    #[test]
    fn a_jittered_soup_split_doubled_and_rewound_welds_to_the_closed_mesh() {
        let (p, f) = octahedron(DVec3::new(3.0, 1.0, -2.0), 0.7);
        let welded = Topology::build(&p, &f);
        // Soup: every face its own corners, each moved by up to 1e-6 of the size.
        let mut soup = Vec::new();
        let mut k = 0u32;
        for face in &f {
            for &i in face {
                k = k.wrapping_mul(747796405).wrapping_add(2891336453);
                let jitter = DVec3::new((k % 7) as f64 - 3.0, (k % 5) as f64 - 2.0, (k % 3) as f64 - 1.0).normalize() * 1.4e-6 * 0.5;
                soup.push(p[i as usize] + jitter);
            }
        }
        let soup_faces: Vec<[u32; 3]> = (0..f.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let t = Topology::from_parts(&[Part { vertices: &soup, faces: &soup_faces }], WELD_TOLERANCE);
        t.require_closed(&["soup"], false).unwrap();
        assert_eq!((t.positions.len(), t.stats.corners_welded), (6, 24 - 6));
        assert_eq!(sorted_edges(&t), sorted_edges(&welded));
        // Without the tolerance the soup is 8 loose triangles.
        assert_eq!(Topology::from_parts(&[Part { vertices: &soup, faces: &soup_faces }], 0.0).boundary_edges, 24);
        // Split in two meshes, one of them re-wound, and a third mesh doubling a face.
        let (upper, lower) = f.split_at(4);
        let lower_rewound: Vec<[u32; 3]> = lower.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let doubled = [f[0]];
        let parts = [Part { vertices: &p, faces: upper }, Part { vertices: &p, faces: &lower_rewound }, Part { vertices: &p, faces: &doubled }];
        let t = Topology::from_parts(&parts, WELD_TOLERANCE);
        t.require_closed(&["upper", "lower", "copy"], false).unwrap();
        assert_eq!(sorted_edges(&t), sorted_edges(&welded));
        assert_eq!((t.stats.pieces_joined, t.stats.duplicate_faces, t.stats.faces_rewound), (1, 1, 4));
        // Wound apart: every edge's two faces traverse it in opposite directions.
        assert!(t.edges.iter().all(|e| e.faces[0] != NO_FACE && e.faces[1] != NO_FACE));
    }

    #[test]
    fn corners_of_separate_meshes_weld_within_the_smaller_tolerance() {
        // A floor 1000 wide (tolerance 1.4e-2) and a mesh of size 1.4 (tolerance
        // 1.4e-5) 1e-3 above it: the mesh's corners stay its own.
        let floor = vec![DVec3::new(-500.0, 0.0, -500.0), DVec3::new(500.0, 0.0, -500.0), DVec3::new(0.0, 0.0, 500.0)];
        let (p, f) = octahedron(DVec3::new(-500.0 + 0.7, 0.7 + 1e-3, -500.0), 0.7);
        let parts = [Part { vertices: &floor, faces: &[[0, 2, 1]] }, Part { vertices: &p, faces: &f }];
        let t = Topology::from_parts(&parts, WELD_TOLERANCE);
        assert_eq!((t.positions.len(), t.stats.corners_welded, t.stats.pieces_joined), (9, 0, 0));
        // Two objects: the floor's corners one, the octahedron's another.
        let floor_object = t.components[t.weld[0] as usize];
        assert!(t.weld[..3].iter().all(|&v| t.components[v as usize] == floor_object));
        let mesh_object = t.components[t.weld[3] as usize];
        assert!(mesh_object != floor_object && t.weld[3..].iter().all(|&v| t.components[v as usize] == mesh_object));
    }

    #[test]
    fn a_surface_in_pieces_is_one_component_and_separate_surfaces_are_not() {
        let (p, f) = octahedron(DVec3::ZERO, 1.0);
        let (q, g) = octahedron(DVec3::new(5.0, 0.0, 0.0), 1.0);
        let (upper, lower) = f.split_at(4);
        let parts = [Part { vertices: &p, faces: upper }, Part { vertices: &q, faces: &g }, Part { vertices: &p, faces: lower }];
        let t = Topology::from_parts(&parts, WELD_TOLERANCE);
        let component = |part_vertex: usize| t.components[t.weld[part_vertex] as usize];
        // The two halves (parts 0 and 2) weld into one surface; part 1 is its own.
        assert!((0..6).all(|v| component(v) == component(12 + v)));
        assert!((6..12).all(|v| component(v) == component(6) && component(v) != component(0)));
    }

    #[test]
    fn a_cap_glued_into_the_surface_is_zipped_and_a_loose_sliver_goes() {
        let (mut p, f) = octahedron(DVec3::ZERO, 1.0);
        // The edge 0-2 (+x to +y) gets a midpoint m; the faces on one side use it
        // (a T-junction), and a cap [0, m, 2] closes the crack, as exporters leave it.
        let m = p.len() as u32;
        p.push((p[0] + p[2]) * 0.5);
        let mut faces: Vec<[u32; 3]> = f.iter().copied().filter(|t| *t != [0, 2, 4]).collect();
        faces.extend([[0, m, 4], [m, 2, 4], [0, 2, m]]);
        let t = Topology::build(&p, &faces);
        assert_eq!((t.stats.degenerate_faces, t.stats.t_junction_splits), (1, 1));
        t.require_closed(&["zipped"], false).unwrap();
        // A loose zero-area sliver (new corners on a line) is dropped and splits nothing.
        let mut q = p.clone();
        let n = q.len() as u32;
        q.extend([DVec3::new(5.0, 0.0, 0.0), DVec3::new(6.0, 0.0, 0.0), DVec3::new(7.0, 0.0, 0.0)]);
        let mut loose = f.clone();
        loose.push([n, n + 2, n + 1]);
        let t = Topology::build(&q, &loose);
        assert_eq!((t.stats.degenerate_faces, t.stats.t_junction_splits, t.faces.len()), (1, 0, 8));
        t.require_closed(&["loose"], false).unwrap();
    }
}
