//! Silhouette edges with respect to the light centre (Cournia 4.1.1), shared
//! by the volume methods (`pvm`, `pvmf`), with the caches that make them cheap
//! to repeat: topology per mesh content, silhouettes per (mesh, light centre).

use std::collections::HashMap;
use std::hash::Hash;
use std::sync::{Arc, Mutex};

use glam::DVec3;

use crate::error::Result;
use crate::occluders::Occluders;
use crate::params::ParamSpec;
use crate::scene::PreparedScene;
use crate::topology::{ConnectivityStats, Part, Topology, NO_FACE, WELD_TOLERANCE};

/// The object of a mesh made of several separate surfaces
/// ([`SilhouetteCache::mesh_objects`]; the object map's "cannot tell"): it
/// cannot tell its own body from another surface of the same mesh.
pub const MANY: u32 = u32::MAX;

/// How casters with boundary edges are treated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OpenEdges {
    /// Casters must be closed 2-manifolds (the paper's assumption).
    Error,
    /// Edges that are not two-sided (open and non-manifold meshes) are
    /// silhouette edges where all their faces lie on one side (`silhouette`).
    Silhouette,
}

impl OpenEdges {
    pub const NAMES: [&'static str; 2] = ["silhouette", "error"];

    /// The `open_edges` parameter of the silhouette methods.
    pub fn spec() -> ParamSpec {
        ParamSpec::choice(
            "open_edges",
            "silhouette",
            &Self::NAMES,
            "edges that are not two-sided (open and non-manifold meshes): silhouette edges where all their faces lie on one side of the plane through them and the light, or refuse such meshes",
        )
    }

    pub fn parse(name: &str) -> Self {
        if name == "silhouette" {
            OpenEdges::Silhouette
        } else {
            OpenEdges::Error
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            OpenEdges::Error => "error",
            OpenEdges::Silhouette => "silhouette",
        }
    }
}

/// Where the volume methods depart from Cournia's construction to stay
/// right on real meshes (issue 15; docs/real_meshes.md measures each). The
/// methods take them as cumulative levels of one parameter, `repairs`
/// (`"none"` is the paper's construction as written, `"all"` the default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Repairs {
    /// PVM's extrusion vectors kept in their vertex's light cone
    /// (`pvm::geometry::in_light_cone`).
    pub cone: bool,
    /// Silhouette edges hidden from the light's centre get no volume
    /// (`visible_from_light`).
    pub hidden: bool,
    /// PVM: a volume's visibility must agree with the shadow-map test at
    /// the light's centre (pvm/visibility.wgsl).
    pub centre: bool,
    /// The part of the light below the receiver's tangent plane is hidden
    /// (both methods' visibility shaders).
    pub horizon: bool,
    /// PVMF: the mask's edge distance is that of the edge's point the
    /// volume comes from, not the nearer end's (`pvmf::geometry`).
    pub distance: bool,
}

impl Repairs {
    pub const NONE: Self = Self { cone: false, hidden: false, centre: false, horizon: false, distance: false };
    pub const ALL: Self = Self { cone: true, hidden: true, centre: true, horizon: true, distance: true };

    /// The repairs of cumulative level `name` among `levels`, each level a
    /// `+`-joined list of repair names (`"cone+hidden"`), or `"none"` / `"all"`.
    pub fn parse(name: &str) -> Self {
        match name {
            "none" => Self::NONE,
            "all" => Self::ALL,
            list => {
                let has = |r: &str| list.split('+').any(|x| x == r);
                Self { cone: has("cone"), hidden: has("hidden"), centre: has("centre"), horizon: has("horizon"), distance: has("distance") }
            }
        }
    }
}

/// A silhouette edge `a -> b`, oriented so that the hard-shadow plane normal
/// `(b - a) x (a - l)` points away from the occluder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SilhouetteEdge {
    pub a: DVec3,
    pub b: DVec3,
    /// Welded vertex indices of a and b.
    pub ia: u32,
    pub ib: u32,
    /// The connected surface the edge lies on (`Topology::components`).
    pub component: u32,
}

/// Silhouette edges of one mesh with respect to the light centre `l` (4.1.1):
/// edges between a face facing the light and one facing away, plus, when
/// `open` is set, the edges that are not two-sided (boundary and
/// non-manifold edges) whose faces all lie on one side of the plane through
/// the edge and the light.
///
/// That side test is the facing test's own meaning: for an edge of a closed,
/// consistently wound mesh, one face facing the light and the other away is
/// exactly both faces on one side of that plane (the surface folds there as
/// the light sees it). It needs no winding, so it extends to an edge with
/// one face (the surface ends there: always on the outline, unless the face
/// is seen edge-on), to two faces wound the same way, and to three or more
/// faces (on the outline only when all lie on one side). A departure from
/// the paper, which assumes closed 2-manifolds (`open_edges = "silhouette"`).
pub fn silhouette(topology: &Topology, l: DVec3, open: bool) -> Vec<SilhouetteEdge> {
    let facing: Vec<bool> = (0..topology.faces.len() as u32)
        .map(|f| {
            let centroid = topology.faces[f as usize].iter().map(|&i| topology.positions[i as usize]).sum::<DVec3>() / 3.0;
            topology.face_normal(f).dot(l - centroid) > 0.0
        })
        .collect();
    let mut out = Vec::new();
    for e in &topology.edges {
        let [f0, f1] = e.faces;
        let is_boundary = f0 == NO_FACE || f1 == NO_FACE;
        if is_boundary && !open {
            continue;
        }
        if !is_boundary && facing[f0 as usize] == facing[f1 as usize] {
            continue;
        }
        let faces: Vec<u32> = [f0, f1].into_iter().filter(|&f| f != NO_FACE).collect();
        // Both faces of a silhouette edge lie on the occluder's side of the
        // plane through the edge and the light; take the first that is off it.
        if let Some(edge) = oriented(topology, e.v, &faces, l, false) {
            out.push(edge);
        }
    }
    if open {
        for e in &topology.non_manifold {
            if let Some(edge) = oriented(topology, e.v, &e.faces, l, true) {
                out.push(edge);
            }
        }
    }
    out
}

/// The edge between welded vertices `v`, oriented so that its hard-shadow
/// normal points away from its `faces`. With `strict`, None unless every
/// face off the plane through the edge and `l` lies on one side of it (and
/// one at least is off it); otherwise the first face off the plane decides.
fn oriented(topology: &Topology, v: [u32; 2], faces: &[u32], l: DVec3, strict: bool) -> Option<SilhouetteEdge> {
    let (mut ia, mut ib) = (v[0], v[1]);
    let (mut a, mut b) = (topology.positions[ia as usize], topology.positions[ib as usize]);
    let normal = (b - a).cross(a - l);
    let tolerance = 1e-12 * normal.length() * (b - a).length().max(1e-300);
    let sides = faces.iter().map(|&f| normal.dot(topology.opposite(f, v) - a)).filter(|d| d.abs() > tolerance);
    let side = if strict {
        let (mut positive, mut negative) = (false, false);
        for d in sides {
            positive |= d > 0.0;
            negative |= d < 0.0;
        }
        if positive == negative {
            return None;
        }
        if positive {
            1.0
        } else {
            -1.0
        }
    } else {
        sides.into_iter().next().unwrap_or(0.0)
    };
    if side > 0.0 {
        std::mem::swap(&mut a, &mut b);
        std::mem::swap(&mut ia, &mut ib);
    }
    Some(SilhouetteEdge { a, b, ia, ib, component: topology.components[ia as usize] })
}

/// The silhouette edges that the light's centre sees, and how many are hidden.
///
/// Departure from 4.1.1: the paper extrudes every silhouette edge. On a
/// real mesh most are folds that other parts of the mesh hide from the
/// light (on the teapot of ../shared/meshes, two of three: the lid's and the
/// base's rims under the body, the far side of the handle), and their
/// volumes lie in the umbra of what hides them, where they overwrite the
/// edges that make the visible penumbra (PVM) or mask the umbra (PVMF). An
/// edge is kept when the segment from the light's centre to any of three
/// points on it (at 10%, 50% and 90% of its length), nudged off the edge
/// away from the occluder, is unblocked.
pub fn visible_from_light(edges: &[SilhouetteEdge], occluders: &Occluders, l: DVec3) -> (Vec<SilhouetteEdge>, usize) {
    let mut kept = Vec::with_capacity(edges.len());
    for e in edges {
        let normal = (e.b - e.a).cross(e.a - l);
        let len = normal.length();
        // An edge pointing at the light gets no volume anyway: keep it for the stats.
        let seen = len <= 0.0
            || [0.1, 0.5, 0.9].iter().any(|&t| {
                let x = e.a + (e.b - e.a) * t;
                // Off the hard-shadow plane by a millionth of the distance, away
                // from the occluder, and as much towards the light, so that a
                // surface the edge lies on (a box standing on the ground) does
                // not count as hiding it.
                let q = x + normal * ((x - l).length() * 1e-6 / len) - (x - l) * 1e-6;
                !occluders.blocks(l, q)
            });
        if seen {
            kept.push(*e);
        }
    }
    let hidden = edges.len() - kept.len();
    (kept, hidden)
}

/// Silhouette edges of a scene for the volume methods, with the cache hits
/// and the edges left out as hidden from the light's centre.
#[derive(Debug, Clone, Default)]
pub struct SceneSilhouette {
    pub edges: Vec<SilhouetteEdge>,
    pub cache_hits: usize,
    pub hidden_edges: usize,
    /// What connectivity found across the scene's meshes.
    pub connectivity: ConnectivityStats,
}

/// What every silhouette method reports of the silhouette it builds from
/// (the stats of the same names; `named`).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SilhouetteStats {
    /// Silhouette edges found (hidden ones included).
    pub silhouette_edges: usize,
    /// Edges seen end-on from the light (no hard-shadow plane): nothing built.
    pub light_parallel_edges: usize,
    /// Silhouette edges hidden from the light's centre (nothing built;
    /// counted in `silhouette_edges`).
    pub hidden_edges: usize,
    /// What connectivity found across the scene's meshes (issue 27).
    pub connectivity: ConnectivityStats,
}

impl SilhouetteStats {
    /// The stats of `edges` silhouette edges (the ones a method builds from).
    pub fn of(edges: usize) -> Self {
        Self { silhouette_edges: edges, ..Default::default() }
    }

    /// Adds what `silhouette` left out (its hidden edges) and found (connectivity).
    pub fn add_scene(&mut self, silhouette: &SceneSilhouette) {
        self.hidden_edges = silhouette.hidden_edges;
        self.connectivity = silhouette.connectivity;
        self.silhouette_edges += silhouette.hidden_edges;
    }

    /// Stat names and values, as the methods report them.
    pub fn named(&self) -> Vec<(&'static str, i64)> {
        let mut out = vec![
            ("silhouette_edges", self.silhouette_edges as i64),
            ("light_parallel_edges", self.light_parallel_edges as i64),
            ("hidden_silhouette_edges", self.hidden_edges as i64),
        ];
        out.extend(self.connectivity.named());
        out
    }
}

impl ConnectivityStats {
    /// The render stats that say what connectivity found (issue 27).
    pub fn named(&self) -> [(&'static str, i64); 8] {
        [
            ("corners_welded", self.corners_welded as i64),
            ("pieces_joined", self.pieces_joined as i64),
            ("degenerate_faces_ignored", self.degenerate_faces as i64),
            ("duplicate_faces_ignored", self.duplicate_faces as i64),
            ("faces_rewound", self.faces_rewound as i64),
            ("t_junction_splits", self.t_junction_splits as i64),
            ("open_edges", self.open_edges as i64),
            ("non_manifold_edges", self.non_manifold_edges as i64),
        ]
    }
}

const CACHE_LIMIT: usize = 64;

/// (scene geometry, light centre bits, whether open edges count).
type SilhouetteKey = (u64, [u64; 3], bool);

/// Topology and silhouette caches, owned by the renderer and shared by the
/// methods that need silhouettes.
#[derive(Default)]
pub struct SilhouetteCache {
    /// Topology per scene geometry (built once while the meshes are unchanged, 4.1.1).
    topologies: Mutex<HashMap<u64, Arc<Topology>>>,
    /// Silhouettes per (scene, light centre), recomputed only when either moves.
    silhouettes: Mutex<HashMap<SilhouetteKey, Arc<Vec<SilhouetteEdge>>>>,
    /// Of those, the edges the light's centre sees and how many are hidden
    /// (`visible_from_light`: three occlusion queries an edge), per the same key.
    visible: Mutex<HashMap<SilhouetteKey, Arc<(Vec<SilhouetteEdge>, usize)>>>,
    /// The last scene's occluder hierarchy, by its meshes' keys.
    occluders: Mutex<Option<(Vec<u64>, Arc<Occluders>)>>,
}

impl SilhouetteCache {
    /// Silhouette edges of the scene's surfaces, through the caches, with
    /// whether they were cached and what connectivity found; checks
    /// manifoldness. Connectivity is built across every mesh of the scene
    /// ([`Topology::from_parts`] at [`WELD_TOLERANCE`]), so a surface in
    /// pieces, doubled or as a soup gives the edges of its welded form.
    pub fn edges(&self, scene: &PreparedScene, l: DVec3, open_edges: OpenEdges) -> Result<(Vec<SilhouetteEdge>, usize, ConnectivityStats)> {
        let boundary = open_edges == OpenEdges::Silhouette;
        let key = scene.geometry_key();
        let topology = self.topology(key, scene);
        let names: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
        topology.require_closed(&names, boundary)?;
        let light_key = l.to_array().map(f64::to_bits);
        if let Some(edges) = self.silhouettes.lock().ok().and_then(|c| c.get(&(key, light_key, boundary)).cloned()) {
            return Ok(((*edges).clone(), 1, topology.stats));
        }
        let edges = Arc::new(silhouette(&topology, l, boundary));
        if let Ok(mut c) = self.silhouettes.lock() {
            if c.len() >= CACHE_LIMIT {
                c.clear();
            }
            c.insert((key, light_key, boundary), edges.clone());
        }
        Ok(((*edges).clone(), 0, topology.stats))
    }

    /// The scene's connectivity across every mesh, through the cache.
    pub fn scene_topology(&self, scene: &PreparedScene) -> Arc<Topology> {
        self.topology(scene.geometry_key(), scene)
    }

    /// Each mesh's object for the object map (`passes::object_map`): the
    /// connected surface (`Topology::components`) that all its faces' corners
    /// belong to, or `MANY` when they belong to several.
    /// Faces connectivity ignores (degenerate, duplicate) do not count, so a
    /// sliver's stray corner does not split its mesh; a surface split over
    /// meshes is one object.
    pub fn mesh_objects(&self, scene: &PreparedScene) -> Vec<u32> {
        let topology = self.topology(scene.geometry_key(), scene);
        // None: no face yet; Some(MANY): faces of several components.
        let mut objects: Vec<Option<u32>> = vec![None; scene.meshes.len()];
        for (face, &part) in topology.faces.iter().zip(&topology.face_part) {
            let c = topology.components[face[0] as usize];
            let o = &mut objects[part as usize];
            *o = Some(match *o {
                None => c,
                Some(x) if x == c => c,
                Some(_) => MANY,
            });
        }
        // A mesh none of whose faces survived (a duplicate of another) is
        // the object its welded corners belong to.
        let mut base = 0usize;
        let mut out = Vec::with_capacity(objects.len());
        for (mesh, o) in scene.meshes.iter().zip(objects) {
            let first = mesh.faces.first().map(|f| topology.components[topology.weld[base + f[0] as usize] as usize]);
            out.push(o.or(first).unwrap_or(MANY));
            base += mesh.vertices.len();
        }
        out
    }

    /// Silhouette edges of the scene (`edges`), less those hidden from the
    /// light's centre by any geometry of the scene when `hidden` is set
    /// (`visible_from_light`).
    pub fn seen_from_light(&self, scene: &PreparedScene, l: DVec3, open_edges: OpenEdges, hidden: bool) -> Result<SceneSilhouette> {
        let (edges, cache_hits, connectivity) = self.edges(scene, l, open_edges)?;
        if !hidden {
            return Ok(SceneSilhouette { edges, cache_hits, hidden_edges: 0, connectivity });
        }
        let key = (scene.geometry_key(), l.to_array().map(f64::to_bits), open_edges == OpenEdges::Silhouette);
        if let Some(seen) = self.visible.lock().ok().and_then(|c| c.get(&key).cloned()) {
            return Ok(SceneSilhouette { edges: seen.0.clone(), cache_hits, hidden_edges: seen.1, connectivity });
        }
        let occluders = self.occluders(scene);
        let seen = Arc::new(visible_from_light(&edges, &occluders, l));
        if let Ok(mut c) = self.visible.lock() {
            if c.len() >= CACHE_LIMIT {
                c.clear();
            }
            c.insert(key, seen.clone());
        }
        Ok(SceneSilhouette { edges: seen.0.clone(), cache_hits, hidden_edges: seen.1, connectivity })
    }

    fn occluders(&self, scene: &PreparedScene) -> Arc<Occluders> {
        let keys = scene.mesh_keys().to_vec();
        if let Some((k, occ)) = self.occluders.lock().ok().and_then(|c| c.clone()) {
            if k == keys {
                return occ;
            }
        }
        let occ = Arc::new(Occluders::from_meshes(scene.meshes.iter().map(|m| (m.vertices.as_slice(), m.faces.as_slice()))));
        if let Ok(mut c) = self.occluders.lock() {
            *c = Some((keys, occ.clone()));
        }
        occ
    }

    fn topology(&self, key: u64, scene: &PreparedScene) -> Arc<Topology> {
        if let Some(t) = self.topologies.lock().ok().and_then(|c| c.get(&key).cloned()) {
            return t;
        }
        let parts: Vec<Part<'_>> = scene.meshes.iter().map(|m| Part { vertices: &m.vertices, faces: &m.faces }).collect();
        let t = Arc::new(Topology::from_parts(&parts, WELD_TOLERANCE));
        if let Ok(mut c) = self.topologies.lock() {
            if c.len() >= CACHE_LIMIT {
                c.clear();
            }
            c.insert(key, t.clone());
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An axis-aligned box (outward, counter-clockwise faces) from `lo` to `hi`.
    fn cuboid(lo: DVec3, hi: DVec3) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p = (0..8)
            .map(|i| DVec3::new(if i & 1 == 0 { lo.x } else { hi.x }, if i & 2 == 0 { lo.y } else { hi.y }, if i & 4 == 0 { lo.z } else { hi.z }))
            .collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        (p, quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect())
    }

    fn occluders(parts: &[&(Vec<DVec3>, Vec<[u32; 3]>)]) -> Occluders {
        Occluders::from_meshes(parts.iter().map(|(p, f)| (p.as_slice(), f.as_slice())))
    }

    #[test]
    fn edges_under_a_wider_caster_are_hidden_and_the_casters_own_are_not() {
        let l = DVec3::new(0.3, 6.0, 0.2);
        let top = cuboid(DVec3::new(-1.0, 3.0, -1.0), DVec3::new(1.0, 3.5, 1.0));
        let below = cuboid(DVec3::new(-0.4, 1.0, -0.4), DVec3::new(0.4, 1.8, 0.4));
        let occ = occluders(&[&top, &below]);
        let top_edges = silhouette(&Topology::build(&top.0, &top.1), l, false);
        let below_edges = silhouette(&Topology::build(&below.0, &below.1), l, false);
        let (kept, hidden) = visible_from_light(&top_edges, &occ, l);
        assert_eq!((kept.len(), hidden), (top_edges.len(), 0));
        let (kept, hidden) = visible_from_light(&below_edges, &occ, l);
        assert!(kept.is_empty() && hidden == below_edges.len() && hidden > 0, "{kept:?}");
    }

    #[test]
    fn the_cache_gives_the_edges_seen_from_the_light_as_computed_afresh() {
        use crate::scene::Mesh;
        let mesh = |(p, f): &(Vec<DVec3>, Vec<[u32; 3]>), name: &str| Mesh {
            name: name.into(),
            vertices: p.iter().map(|v| v.as_vec3().to_array()).collect(),
            faces: f.clone(),
            normals: None,
            albedo: [0.5; 3],
            object_id: 0,
            transform: glam::Mat4::IDENTITY,
        };
        let top = cuboid(DVec3::new(-1.0, 3.0, -1.0), DVec3::new(1.0, 3.5, 1.0));
        let below = cuboid(DVec3::new(-0.4, 1.0, -0.4), DVec3::new(0.4, 1.8, 0.4));
        let mut scene = crate::scene::tests::scene(mesh(&top, "top"));
        scene.meshes.push(mesh(&below, "below"));
        let prepared = scene.prepare_geometry().unwrap();
        let cache = SilhouetteCache::default();
        for l in [DVec3::new(0.3, 6.0, 0.2), DVec3::new(4.0, 2.5, 0.0), DVec3::new(0.3, 6.0, 0.2)] {
            let got = cache.seen_from_light(&prepared, l, OpenEdges::Error, true).unwrap();
            let fresh = SilhouetteCache::default().seen_from_light(&prepared, l, OpenEdges::Error, true).unwrap();
            assert_eq!((got.edges.len(), got.hidden_edges), (fresh.edges.len(), fresh.hidden_edges), "{l}");
            assert!(got.edges.iter().zip(&fresh.edges).all(|(a, b)| (a.a, a.b) == (b.a, b.b)), "{l}");
        }
        // From above, the lower box's edges are hidden; from the side, some are seen.
        let above = cache.seen_from_light(&prepared, DVec3::new(0.3, 6.0, 0.2), OpenEdges::Error, true).unwrap();
        let side = cache.seen_from_light(&prepared, DVec3::new(4.0, 2.5, 0.0), OpenEdges::Error, true).unwrap();
        assert!(above.hidden_edges > 0 && side.hidden_edges != above.hidden_edges, "{} {}", above.hidden_edges, side.hidden_edges);
    }

    #[test]
    fn a_box_resting_on_the_ground_keeps_its_contact_edges() {
        // The silhouette's lower edges lie on the ground's top face: the
        // ground does not hide them (the test point is nudged towards the light).
        let l = DVec3::new(2.0, 6.0, 1.0);
        let ground = cuboid(DVec3::new(-5.0, -0.2, -5.0), DVec3::new(5.0, 0.0, 5.0));
        let resting = cuboid(DVec3::new(-0.5, 0.0, -0.5), DVec3::new(0.5, 2.0, 0.5));
        let edges = silhouette(&Topology::build(&resting.0, &resting.1), l, false);
        assert!(edges.iter().any(|e| e.a.y == 0.0 && e.b.y == 0.0), "a contact edge is on the silhouette");
        let (kept, hidden) = visible_from_light(&edges, &occluders(&[&ground, &resting]), l);
        assert_eq!((kept.len(), hidden), (edges.len(), 0));
    }

    #[test]
    fn open_edges_are_silhouettes_oriented_away_from_their_face() {
        // One triangle facing the light: its three boundary edges are its outline.
        let p = vec![DVec3::new(-1.0, 1.0, -1.0), DVec3::new(1.0, 1.0, -1.0), DVec3::new(0.0, 1.0, 1.0)];
        let t = Topology::build(&p, &[[0, 2, 1]]);
        let l = DVec3::new(0.1, 5.0, 0.2);
        assert!(silhouette(&t, l, false).is_empty());
        let edges = silhouette(&t, l, true);
        assert_eq!(edges.len(), 3);
        let centroid = (p[0] + p[1] + p[2]) / 3.0;
        for e in edges {
            assert!((e.b - e.a).cross(e.a - l).dot(centroid - e.a) < 0.0, "{e:?} points towards its face");
        }
    }

    #[test]
    fn a_fin_on_one_side_is_a_silhouette_and_fins_on_both_sides_are_not() {
        // Edge 0-1 along x at the origin, the light above: faces hang off it
        // on the -z side, or on both sides.
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(0.5, -0.2, -1.0), DVec3::new(0.5, 0.3, -1.0), DVec3::new(0.5, 0.0, 1.0), DVec3::new(0.5, 0.05, -1.0)];
        let l = DVec3::new(0.5, 5.0, 0.1);
        // Three distinct fins (a fin given twice, in either winding, would be one face).
        let one_side = Topology::build(&p, &[[0, 1, 2], [0, 1, 3], [1, 0, 5]]);
        assert_eq!(one_side.non_manifold.len(), 1);
        let edges: Vec<_> = silhouette(&one_side, l, true).into_iter().filter(|e| (e.ia.min(e.ib), e.ia.max(e.ib)) == (0, 1)).collect();
        assert_eq!(edges.len(), 1);
        let e = edges[0];
        assert!((e.b - e.a).cross(e.a - l).z > 0.0, "the normal points away from the fins (+z)");
        let both_sides = Topology::build(&p, &[[0, 1, 2], [0, 1, 3], [1, 0, 4]]);
        assert!(silhouette(&both_sides, l, true).iter().all(|e| (e.ia.min(e.ib), e.ia.max(e.ib)) != (0, 1)));
    }
}
