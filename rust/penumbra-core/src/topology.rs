//! Mesh connectivity for the silhouette methods (Cournia 4.1.1): for each
//! edge, the faces it belongs to, in a winged-edge spirit.
//!
//! Vertices at identical positions are welded first, so meshes split for
//! normals or texture seams still connect. Faces whose welded corners repeat
//! are dropped (they have no area and no edges of their own).

use std::collections::HashMap;

use glam::DVec3;

use crate::error::{Error, Result};

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
/// way (inconsistent winding): every face on it, in no order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NonManifoldEdge {
    pub v: [u32; 2],
    pub faces: Vec<u32>,
}

/// Connectivity of one mesh.
#[derive(Debug, Clone)]
pub struct Topology {
    /// Welded vertex index of each input vertex.
    pub weld: Vec<u32>,
    /// Position of each welded vertex (world space).
    pub positions: Vec<DVec3>,
    /// Faces in welded indices, degenerate ones removed.
    pub faces: Vec<[u32; 3]>,
    pub edges: Vec<Edge>,
    /// Edges that are not two-sided (not in `edges`).
    pub non_manifold: Vec<NonManifoldEdge>,
    /// Edges with one face.
    pub boundary_edges: usize,
    /// Edges with more than two faces, or two faces of the same winding.
    pub non_manifold_edges: usize,
}

impl Topology {
    pub fn build(positions: &[DVec3], faces: &[[u32; 3]]) -> Self {
        let mut index: HashMap<[u64; 3], u32> = HashMap::with_capacity(positions.len());
        let mut welded = Vec::new();
        let weld: Vec<u32> = positions
            .iter()
            .map(|p| {
                // +0.0 and -0.0 are the same point.
                let key = [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
                *index.entry(key).or_insert_with(|| {
                    welded.push(*p);
                    (welded.len() - 1) as u32
                })
            })
            .collect();
        let faces: Vec<[u32; 3]> = faces
            .iter()
            .map(|f| f.map(|i| weld[i as usize]))
            .filter(|f| f[0] != f[1] && f[1] != f[2] && f[2] != f[0])
            .collect();
        // Directed half-edges per undirected edge: (forward faces, backward faces).
        let mut sides: HashMap<(u32, u32), (Vec<u32>, Vec<u32>)> = HashMap::with_capacity(faces.len() * 3 / 2);
        for (fi, f) in faces.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                let entry = sides.entry((a.min(b), a.max(b))).or_default();
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
        Self { weld, positions: welded, faces, edges, non_manifold, boundary_edges, non_manifold_edges }
    }

    /// Refuses meshes that are not closed 2-manifolds (what PVM assumes,
    /// Cournia 4.1.1), naming the mesh and the edge counts. With
    /// `allow_open`, every mesh is accepted: edges with one face or with
    /// other than two consistently wound faces get the silhouette test of
    /// `silhouettes::silhouette` (all their faces on one side).
    pub fn require_closed(&self, mesh: &str, allow_open: bool) -> Result<()> {
        if allow_open {
            return Ok(());
        }
        if self.non_manifold_edges > 0 {
            return Err(Error::mesh(
                mesh,
                format!(
                    "is not a 2-manifold: {} edges have more than two faces or two faces of the same \
                     winding; pass open_edges='silhouette' to take such edges as silhouette edges where \
                     all their faces lie on one side",
                    self.non_manifold_edges
                ),
            ));
        }
        if self.boundary_edges > 0 {
            return Err(Error::mesh(
                mesh,
                format!(
                    "is not closed: {} boundary edges (edges with one face); close the mesh, or pass \
                     open_edges='silhouette' to treat boundary edges as silhouette edges",
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
        t.require_closed("tet", false).unwrap();
    }

    #[test]
    fn split_vertices_are_welded() {
        let (mut p, mut f) = tetrahedron();
        p.push(DVec3::Z); // a duplicate of vertex 3
        f[3] = [1, 2, 4];
        let t = Topology::build(&p, &f);
        assert_eq!(t.positions.len(), 4);
        t.require_closed("tet", false).unwrap();
    }

    #[test]
    fn open_and_non_manifold_meshes_are_named() {
        let (p, f) = tetrahedron();
        let open = Topology::build(&p, &f[..3]);
        assert_eq!(open.boundary_edges, 3);
        let err = open.require_closed("lid", false).unwrap_err().to_string();
        assert!(err.contains("'lid'") && err.contains("3 boundary edges"), "{err}");
        open.require_closed("lid", true).unwrap();
        let err = open.require_closed("lid", false).unwrap_err().to_string();
        assert!(err.contains("open_edges='silhouette'"), "{err}");
        let mut fins = f.clone();
        fins.push([0, 1, 2]); // a third face on edges 0-1, 1-2, 0-2
        let finned = Topology::build(&p, &fins);
        let err = finned.require_closed("fin", false).unwrap_err().to_string();
        assert!(err.contains("not a 2-manifold") && err.contains("open_edges='silhouette'"), "{err}");
        finned.require_closed("fin", true).unwrap();
        // The three edges keep all their faces: two of the tetrahedron's and the fin.
        assert_eq!(finned.non_manifold.len(), 3);
        assert!(finned.non_manifold.iter().all(|e| e.faces.len() == 3));
        assert_eq!(finned.edges.len(), 3);
    }
}
