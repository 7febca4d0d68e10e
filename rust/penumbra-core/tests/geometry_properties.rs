//! Property and degenerate-case checks of the CPU geometry of the volume
//! methods (issue 8): topology, silhouettes (Cournia 4.1.1), PVM's penumbra
//! volumes (4.1.2) and PVMF's mask volumes (5.1). No GPU needed.
//!
//! proptest is not in the offline registry this project builds from, so the
//! random cases come from a small deterministic generator (xorshift64*): the
//! same cases on every run, a failure names its case index.

use glam::{DMat3, DVec3};
use penumbra_core::methods::pvm::{penumbra_volumes, silhouette, SilhouetteEdge};
use penumbra_core::methods::pvmf::{mask_volumes, Offsets};
use penumbra_core::topology::Topology;

/// xorshift64* (Vigna 2016): deterministic, no dependencies.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    /// Log-uniform in [lo, hi].
    fn log_range(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.unit()).exp()
    }
    fn direction(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            let len = v.length();
            if len > 0.1 && len <= 1.0 {
                return v / len;
            }
        }
    }
    fn rotation(&mut self) -> DMat3 {
        DMat3::from_axis_angle(self.direction(), self.range(0.0, std::f64::consts::TAU))
    }
}

/// A closed mesh: box, octahedron, tetrahedron or a UV sphere (counter-clockwise outward).
fn shape(kind: u64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    match kind % 4 {
        0 => {
            let p = (0..8)
                .map(|i| DVec3::new(if i & 1 == 0 { -1.0 } else { 1.0 }, if i & 2 == 0 { -1.0 } else { 1.0 }, if i & 4 == 0 { -1.0 } else { 1.0 }))
                .collect();
            let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
            (p, quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect())
        }
        1 => {
            let p = vec![DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
            let f = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
            (p, f)
        }
        2 => {
            let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
            (p, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
        }
        _ => uv_sphere(6, 8),
    }
}

fn uv_sphere(rings: u32, segments: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut p = vec![DVec3::Y, -DVec3::Y];
    for i in 1..rings {
        let theta = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let phi = std::f64::consts::TAU * j as f64 / segments as f64;
            p.push(DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
        }
    }
    let at = |i: u32, j: u32| 2 + (i - 1) * segments + (j % segments);
    let mut f = Vec::new();
    for j in 0..segments {
        f.push([0, at(1, j + 1), at(1, j)]);
        f.push([1, at(rings - 1, j), at(rings - 1, j + 1)]);
        for i in 1..rings - 1 {
            f.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            f.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
    }
    (p, f)
}

fn finite(v: &[[f32; 3]]) -> bool {
    v.iter().all(|p| p.iter().all(|c| c.is_finite()))
}

/// One random case: a shape scaled by 1e-3..1e4, rotated and placed, and a
/// light off it (radius 0 to several times the shape, gap down to 1e-6 of the size).
struct Case {
    topology: Topology,
    l: DVec3,
    r: f64,
    scale: f64,
}

fn random_case(rng: &mut Rng) -> Case {
    let (p, f) = shape(rng.next());
    let scale = rng.log_range(1e-3, 1e4);
    let rot = rng.rotation();
    let offset = rng.direction() * scale * rng.range(0.0, 10.0);
    let p: Vec<DVec3> = p.iter().map(|&v| rot * v * scale + offset).collect();
    let r = match rng.next() % 4 {
        0 => 0.0,
        1 => scale * rng.log_range(1e-6, 1e-2),
        _ => scale * rng.range(0.01, 3.0),
    };
    // The shape fits in a ball of radius sqrt(3) scale about `offset`; put the
    // light's surface `gap` beyond that ball (very close when gap is tiny).
    let gap = scale * rng.log_range(1e-6, 10.0);
    let l = offset + rng.direction() * (3f64.sqrt() * scale + r + gap);
    Case { topology: Topology::build(&p, &f), l, r, scale }
}

const CASES: usize = 2000;

#[test]
fn random_scenes_give_finite_oriented_volumes() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for case in 0..CASES {
        let Case { topology, l, r, scale } = random_case(&mut rng);
        topology.require_closed("shape", false).unwrap();
        let edges = silhouette(&topology, l, false);
        assert!(!edges.is_empty(), "case {case}: a closed shape seen from outside has a silhouette");
        let reach = 100.0 * scale;
        let (vertices, stats) = penumbra_volumes(&edges, l, r, reach);
        assert_eq!(stats.volume_quads, 2 * (edges.len() - stats.light_parallel_edges), "case {case}");
        assert_eq!(vertices.len(), 6 * stats.volume_quads, "case {case}");
        for v in &vertices {
            assert!(finite(&[v.position, v.h0, v.h1]), "case {case}: {v:?}");
        }
        // Every extruded corner lies no nearer the light's centre plane than
        // its edge: volumes go away from the light (4.1.2's negation rule).
        for quad in vertices.chunks(6) {
            let (near, far) = (DVec3::from(quad[0].position.map(f64::from)), DVec3::from(quad[1].position.map(f64::from)));
            let away = (near - l).normalize();
            let step = far - near;
            // f32 positions: 1e-5 of the reach is the rounding of the stored corners.
            assert!(
                step.dot(away) >= -1e-5 * reach,
                "case {case}: an extrusion goes towards the light: r/scale {}, |l - edge|/scale {}, step.away/reach {}, edges {}",
                r / scale,
                (near - l).length() / scale,
                step.dot(away) / reach,
                edges.len()
            );
        }
        for s_e in [0.5, 1.0] {
            for offsets in [Offsets::Unit, Offsets::Radius] {
                let (mask, stats) = mask_volumes(&edges, l, r, s_e, offsets, reach);
                assert_eq!(stats.mask_quads, 2 * (edges.len() - stats.light_parallel_edges), "case {case}");
                assert!(mask.iter().all(|m| finite(&[m.position]) && m.d_e.is_finite() && m.d_e > 0.0), "case {case}");
            }
        }
    }
}

#[test]
fn silhouettes_are_invariant_under_scaling_and_translation() {
    let mut rng = Rng(0xD1B5_4A32_D192_ED03);
    for case in 0..CASES / 4 {
        let (p, f) = shape(rng.next());
        let rot = rng.rotation();
        let p: Vec<DVec3> = p.iter().map(|&v| rot * v).collect();
        let l = rng.direction() * rng.range(2.0, 20.0);
        let base: Vec<(u32, u32)> = silhouette(&Topology::build(&p, &f), l, false).iter().map(|e| (e.ia, e.ib)).collect();
        // Powers of two scale exactly, and a translation by a multiple of a
        // power of two not far above the coordinates keeps the facing tests'
        // signs; the welded indices and orientations must not change.
        for k in [-10, -3, 5, 13] {
            let s = 2f64.powi(k);
            let t = DVec3::new(rng.range(-4.0, 4.0), rng.range(-4.0, 4.0), rng.range(-4.0, 4.0)).round() * s;
            let q: Vec<DVec3> = p.iter().map(|&v| v * s + t).collect();
            let moved: Vec<(u32, u32)> = silhouette(&Topology::build(&q, &f), l * s + t, false).iter().map(|e| (e.ia, e.ib)).collect();
            assert_eq!(base, moved, "case {case}: scale 2^{k}");
        }
    }
}

fn edge(a: DVec3, b: DVec3, ia: u32, ib: u32) -> SilhouetteEdge {
    SilhouetteEdge { a, b, ia, ib }
}

fn all_finite_pvm_and_pvmf(edges: &[SilhouetteEdge], l: DVec3, r: f64) {
    let (v, _) = penumbra_volumes(edges, l, r, 50.0);
    assert!(v.iter().all(|v| finite(&[v.position, v.h0, v.h1])), "{v:?}");
    for s_e in [1e-9, 0.5, 1.0] {
        for offsets in [Offsets::Unit, Offsets::Radius] {
            let (m, _) = mask_volumes(edges, l, r, s_e, offsets, 50.0);
            assert!(m.iter().all(|m| finite(&[m.position]) && m.d_e.is_finite()), "{m:?}");
        }
    }
}

#[test]
fn collinear_silhouette_edges_use_the_coincident_plane_rule() {
    // Three collinear edges in a loop-like chain: their planes coincide (n0 = n1).
    let l = DVec3::new(0.0, 5.0, 0.0);
    let edges: Vec<_> = (0..3).map(|i| edge(DVec3::new(i as f64, 1.0, 0.0), DVec3::new(i as f64 + 1.0, 1.0, 0.0), i, i + 1)).collect();
    let (v, stats) = penumbra_volumes(&edges, l, 0.5, 10.0);
    assert_eq!(stats.light_parallel_edges, 0);
    assert!(v.iter().all(|v| finite(&[v.position])));
    // The shared extrusion at vertex 1 is the single plane's ray from d through the vertex.
    let at_vertex_1: Vec<[f32; 3]> = v.chunks(6).filter(|q| q[0].position == [1.0, 1.0, 0.0]).map(|q| q[1].position).collect();
    assert!(!at_vertex_1.is_empty());
    for far in at_vertex_1 {
        assert!(far[1] < 1.0, "extruded away from the light: {far:?}");
    }
    all_finite_pvm_and_pvmf(&edges, l, 0.5);
}

#[test]
fn nearly_collinear_edges_do_not_blow_up() {
    // Bends from 1e-15 to 1e-3 radians: around the 1e-9 threshold of the
    // coincident-plane rule the extrusion must not jump wildly.
    let l = DVec3::new(0.3, 5.0, -0.2);
    let mut previous: Option<DVec3> = None;
    for k in (3..=15).rev() {
        let bend = 10f64.powi(-k);
        let a = DVec3::new(-1.0, 1.0, 0.0);
        let v = DVec3::new(0.0, 1.0, 0.0);
        let b = DVec3::new(1.0, 1.0, bend);
        let edges = vec![edge(a, v, 0, 1), edge(v, b, 1, 2)];
        let (out, _) = penumbra_volumes(&edges, l, 0.5, 10.0);
        assert!(out.iter().all(|q| finite(&[q.position])));
        let far = DVec3::from(out[1].position.map(f64::from)) - a;
        if let Some(p) = previous {
            // The far corner of the first edge's outer quad at `a` moves continuously with the bend.
            assert!((far - p).length() < 1e-2 * 10.0 + 1e-3, "bend 1e-{k}: jumped from {p} to {far}");
        }
        previous = Some(far);
        all_finite_pvm_and_pvmf(&edges, l, 0.5);
    }
}

#[test]
fn edges_parallel_to_the_light_direction_get_no_volume() {
    let l = DVec3::new(0.0, 5.0, 0.0);
    // Pointing straight at the light, and within 1e-12 of it.
    let edges = vec![
        edge(DVec3::new(0.0, 1.0, 0.0), DVec3::new(0.0, 2.0, 0.0), 0, 1),
        edge(DVec3::new(0.0, 2.0, 0.0), DVec3::new(1e-12, 3.0, 0.0), 1, 2),
        edge(DVec3::new(1e-12, 3.0, 0.0), DVec3::new(1.0, 3.0, 0.0), 2, 3),
    ];
    let (v, stats) = penumbra_volumes(&edges, l, 0.5, 10.0);
    assert_eq!(stats.light_parallel_edges, 2);
    assert_eq!(stats.volume_quads, 2);
    assert!(v.iter().all(|v| finite(&[v.position])));
    let (_, mstats) = mask_volumes(&edges, l, 0.5, 0.5, Offsets::Unit, 10.0);
    assert_eq!(mstats.light_parallel_edges, 2);
    all_finite_pvm_and_pvmf(&edges, l, 0.5);
}

#[test]
fn very_acute_corners_stay_finite_and_away_from_the_light() {
    let l = DVec3::new(0.0, 5.0, 0.0);
    for k in 1..=12 {
        let angle = 10f64.powi(-k);
        // A spike: two edges meeting at `v` at `angle` radians.
        let v = DVec3::new(1.0, 1.0, 0.0);
        let a = v - DVec3::new(1.0, 0.0, 0.0);
        let b = v - DVec3::new(angle.cos(), 0.0, angle.sin());
        let edges = vec![edge(a, v, 0, 1), edge(v, b, 1, 2)];
        let (out, _) = penumbra_volumes(&edges, l, 0.5, 10.0);
        for quad in out.chunks(6) {
            let near = DVec3::from(quad[0].position.map(f64::from));
            let far = DVec3::from(quad[1].position.map(f64::from));
            assert!(far.is_finite() && (far - near).dot(near - l) >= -1e-4, "angle 1e-{k}: {near} -> {far}");
        }
        all_finite_pvm_and_pvmf(&edges, l, 0.5);
    }
}

#[test]
fn vertices_with_four_silhouette_edges_are_junctions() {
    // Two cubes touching at one corner (the origin): edge-manifold, but seen
    // from (1, 1, -1) the shared vertex is on both silhouettes: four edges.
    let (p, f) = shape(0);
    let mut q: Vec<DVec3> = p.iter().map(|&v| (v - DVec3::ONE) * 0.5).collect();
    q.extend(p.iter().map(|&v| (v + DVec3::ONE) * 0.5));
    let mut faces = f.clone();
    faces.extend(f.iter().map(|t| t.map(|i| i + 8)));
    let topology = Topology::build(&q, &faces);
    topology.require_closed("bowtie", false).unwrap();
    let l = DVec3::new(6.0, 6.0, -6.0);
    let edges = silhouette(&topology, l, false);
    let (v, stats) = penumbra_volumes(&edges, l, 0.5, 20.0);
    assert!(stats.junction_vertices >= 1, "{stats:?}");
    assert!(v.iter().all(|v| finite(&[v.position])));
    all_finite_pvm_and_pvmf(&edges, l, 0.5);
}

#[test]
fn zero_area_duplicate_and_t_junction_faces_are_classified() {
    let (p, f) = shape(0);
    // A zero-area face (repeated corner) is dropped by the weld and leaves the mesh closed.
    let mut with_sliver = f.clone();
    with_sliver.push([0, 0, 1]);
    Topology::build(&p, &with_sliver).require_closed("sliver", false).unwrap();
    // A collinear (zero-area, distinct corners) face adds a third face to an edge... or not:
    // its edges 0-1, 1-m and m-0 are new unless they coincide with existing ones.
    let mut q = p.clone();
    q.push((p[0] + p[1]) * 0.5);
    let mut collinear = f.clone();
    collinear.push([0, 1, 8]);
    let t = Topology::build(&q, &collinear);
    let err = t.require_closed("collinear", false).unwrap_err().to_string();
    assert!(err.contains("'collinear'"), "{err}");
    // A duplicated face: its edges get two faces of the same winding.
    let mut duplicate = f.clone();
    duplicate.push(f[0]);
    let err = Topology::build(&p, &duplicate).require_closed("dup", true).unwrap_err().to_string();
    assert!(err.contains("not a 2-manifold"), "{err}");
    // A t-junction: split one face's edge with a midpoint its neighbour does not share.
    let mut q = p.clone();
    q.push((p[0] + p[2]) * 0.5);
    let m = 8;
    let mut tj: Vec<[u32; 3]> = f.iter().copied().filter(|t| *t != [0, 2, 3]).collect();
    tj.push([0, m, 3]);
    tj.push([m, 2, 3]);
    let t = Topology::build(&q, &tj);
    let err = t.require_closed("tj", false).unwrap_err().to_string();
    assert!(err.contains("boundary edges"), "{err}");
    // With boundary edges as silhouettes, the volumes are still finite.
    t.require_closed("tj", true).unwrap();
    let l = DVec3::new(0.5, 6.0, 0.3);
    let edges = silhouette(&t, l, true);
    all_finite_pvm_and_pvmf(&edges, l, 0.5);
}

#[test]
fn light_grazing_the_caster_and_tiny_radii_stay_finite() {
    let (p, f) = shape(3);
    let t = Topology::build(&p, &f);
    for (gap, r) in [(1e-9, 0.5), (1e-6, 2.0), (1.0, 1e-30), (1.0, f64::from(f32::MIN_POSITIVE)), (1e-3, 100.0)] {
        let l = DVec3::new(0.0, 1.0 + r + gap, 0.0);
        let edges = silhouette(&t, l, false);
        all_finite_pvm_and_pvmf(&edges, l, r);
    }
}
