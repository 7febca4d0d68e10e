//! Property and degenerate-case checks of the CPU geometry of the volume
//! methods (issue 8): topology, silhouettes (Cournia 4.1.1), PVM's penumbra
//! volumes (4.1.2) and PVMF's mask volumes (5.1). No GPU needed.
//!
//! The random cases come from proptest with a fixed seed: the same cases on
//! every run, and a failure is shrunk to a small case and printed.

use glam::{DMat3, DVec3};
use penumbra_core::methods::pvm::{penumbra_volumes, silhouette, SilhouetteEdge, VolumeGeometry};
use penumbra_core::methods::pvmf::{mask_volumes, Offsets};
use penumbra_core::topology::Topology;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

/// `cases` cases from a fixed seed, with no failure files written.
fn config(cases: u32) -> Config {
    Config { cases, rng_seed: RngSeed::Fixed(0x9E37_79B9_7F4A_7C15), failure_persistence: None, ..Config::default() }
}

/// A unit vector, uniform over directions (rejection from the cube).
fn direction() -> impl Strategy<Value = DVec3> {
    [-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64]
        .prop_map(DVec3::from_array)
        .prop_filter("inside the unit ball, not near its centre", |v| v.length() > 0.1 && v.length() <= 1.0)
        .prop_map(|v| v.normalize())
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
#[derive(Debug, Clone)]
struct CaseParams {
    /// Box, octahedron, tetrahedron or UV sphere (`shape`).
    kind: u64,
    scale: f64,
    axis: DVec3,
    angle: f64,
    /// The shape's centre is `offset * scale` along `offset_direction`.
    offset_direction: DVec3,
    offset: f64,
    /// The light's radius and the gap between its surface and the shape's
    /// bounding ball, in units of `scale`.
    radius: f64,
    gap: f64,
    light_direction: DVec3,
}

fn case_params() -> impl Strategy<Value = CaseParams> {
    let radius = prop_oneof![
        1 => Just(0.0),
        1 => (-6.0..-2.0f64).prop_map(|e| 10f64.powf(e)),
        2 => 0.01..3.0f64,
    ];
    (0..4u64, -3.0..4.0f64, direction(), 0.0..std::f64::consts::TAU, direction(), 0.0..10.0f64, radius, -6.0..1.0f64, direction()).prop_map(
        |(kind, scale, axis, angle, offset_direction, offset, radius, gap, light_direction)| CaseParams {
            kind,
            scale: 10f64.powf(scale),
            axis,
            angle,
            offset_direction,
            offset,
            radius,
            gap: 10f64.powf(gap),
            light_direction,
        },
    )
}

struct Case {
    topology: Topology,
    l: DVec3,
    r: f64,
    scale: f64,
}

fn build(c: &CaseParams) -> Case {
    let (p, f) = shape(c.kind);
    let rot = DMat3::from_axis_angle(c.axis, c.angle);
    let offset = c.offset_direction * c.scale * c.offset;
    let p: Vec<DVec3> = p.iter().map(|&v| rot * v * c.scale + offset).collect();
    let r = c.radius * c.scale;
    // The shape fits in a ball of radius sqrt(3) scale about `offset`; put the
    // light's surface `gap` beyond that ball (very close when gap is tiny).
    let l = offset + c.light_direction * (3f64.sqrt() * c.scale + r + c.gap * c.scale);
    Case { topology: Topology::build(&p, &f), l, r, scale: c.scale }
}

fn check_volumes(params: &CaseParams) -> Result<(), TestCaseError> {
    let Case { topology, l, r, scale } = build(params);
    topology.require_closed(&["shape"], false).unwrap();
    let edges = silhouette(&topology, l, false);
    prop_assert!(!edges.is_empty(), "a closed shape seen from outside has a silhouette");
    let reach = 100.0 * scale;
    for cone in [false, true] {
        let VolumeGeometry { vertices, edges: points, stats } = penumbra_volumes(&edges, l, r, reach, cone);
        prop_assert_eq!(stats.volume_quads, 2 * (edges.len() - stats.silhouette.light_parallel_edges));
        prop_assert_eq!(vertices.len(), 6 * stats.volume_quads);
        prop_assert_eq!(points.len(), stats.volume_quads / 2);
        for v in &vertices {
            prop_assert!(finite(&[v.position]) && (v.edge as usize) < points.len(), "{v:?}");
        }
        for p in &points {
            prop_assert!(p.h0.iter().chain(&p.h1).all(|c| c.is_finite()), "{p:?}");
        }
        // Every extruded corner lies no nearer the light's centre plane than
        // its edge: volumes go away from the light (4.1.2's negation rule).
        for quad in vertices.chunks(6) {
            for (i, j) in [(0, 1), (5, 4)] {
                let (near, far) = (DVec3::from(quad[i].position.map(f64::from)), DVec3::from(quad[j].position.map(f64::from)));
                let away = (near - l).normalize();
                let step = far - near;
                // f32 positions: 1e-5 of the reach is the rounding of the stored corners.
                prop_assert!(
                    step.dot(away) >= -1e-5 * reach,
                    "an extrusion goes towards the light: r/scale {}, |l - edge|/scale {}, step.away/reach {}, edges {}",
                    r / scale,
                    (near - l).length() / scale,
                    step.dot(away) / reach,
                    edges.len()
                );
                if cone && r > 0.0 {
                    // Every extrusion lies in its vertex's light cone (to the f32
                    // rounding of the stored corners, relative to the reach).
                    let half_angle = (r / (near - l).length()).min(1.0).asin();
                    let angle = step.normalize().dot(away).clamp(-1.0, 1.0).acos();
                    prop_assert!(angle <= half_angle + 1e-4, "extrusion {angle} outside the light cone {half_angle}");
                }
            }
        }
    }
    for s_e in [0.5, 1.0] {
        for offsets in [Offsets::Unit, Offsets::Radius] {
            let (mask, stats) = mask_volumes(&edges, l, r, s_e, offsets, reach, true);
            prop_assert_eq!(stats.mask_quads, 2 * (edges.len() - stats.silhouette.light_parallel_edges));
            prop_assert!(mask.iter().all(|m| finite(&[m.position]) && m.d_e.is_finite() && m.d_e > 0.0 && m.d_local >= m.d_e && m.d_local.is_finite()));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(2000))]

    #[test]
    fn random_scenes_give_finite_oriented_volumes(params in case_params()) {
        check_volumes(&params)?;
    }
}

/// The case that found the PVM extrusion turning back towards the light
/// (docs/stability.md, fix 2): a tetrahedron 2372 units across, light radius
/// 1.8 of that, its surface 0.003 of that from the shape's bounding ball.
#[test]
fn large_light_close_to_a_caster_extrudes_away_from_it() {
    let params = CaseParams {
        kind: 2,
        scale: 2.371546580552902e3,
        axis: DVec3::new(0.010379987400876527, -0.8949563409191361, 0.44603296258257497),
        angle: 2.677302161108944,
        offset_direction: DVec3::new(0.7871124721198135, -0.6024118685539994, -0.13249111992399554),
        offset: 9.482015450656998,
        radius: 1.8037486565149892,
        gap: 3.0088013685659856e-3,
        light_direction: DVec3::new(0.022463148125842266, 0.2733885374844814, -0.9616413648280594),
    };
    check_volumes(&params).unwrap();
}

proptest! {
    #![proptest_config(config(500))]

    #[test]
    fn silhouettes_are_invariant_under_scaling_and_translation(
        kind in 0..4u64,
        axis in direction(),
        angle in 0.0..std::f64::consts::TAU,
        light in direction(),
        distance in 2.0..20.0f64,
        shift in [-4i32..=4, -4i32..=4, -4i32..=4],
    ) {
        let (p, f) = shape(kind);
        let rot = DMat3::from_axis_angle(axis, angle);
        let p: Vec<DVec3> = p.iter().map(|&v| rot * v).collect();
        let l = light * distance;
        let base: Vec<(u32, u32)> = silhouette(&Topology::build(&p, &f), l, false).iter().map(|e| (e.ia, e.ib)).collect();
        // Powers of two scale exactly, and a translation by a multiple of a
        // power of two not far above the coordinates keeps the facing tests'
        // signs; the welded indices and orientations must not change.
        for k in [-10, -3, 5, 13] {
            let s = 2f64.powi(k);
            let t = DVec3::new(f64::from(shift[0]), f64::from(shift[1]), f64::from(shift[2])) * s;
            let q: Vec<DVec3> = p.iter().map(|&v| v * s + t).collect();
            let moved: Vec<(u32, u32)> = silhouette(&Topology::build(&q, &f), l * s + t, false).iter().map(|e| (e.ia, e.ib)).collect();
            prop_assert_eq!(&base, &moved, "scale 2^{}", k);
        }
    }
}

fn edge(a: DVec3, b: DVec3, ia: u32, ib: u32) -> SilhouetteEdge {
    SilhouetteEdge { a, b, ia, ib, component: 0 }
}

fn all_finite_pvm_and_pvmf(edges: &[SilhouetteEdge], l: DVec3, r: f64) {
    let v = penumbra_volumes(edges, l, r, 50.0, true);
    assert!(v.vertices.iter().all(|v| finite(&[v.position])), "{v:?}");
    assert!(v.edges.iter().all(|p| p.h0.iter().chain(&p.h1).all(|c| c.is_finite())), "{v:?}");
    for s_e in [1e-9, 0.5, 1.0] {
        for offsets in [Offsets::Unit, Offsets::Radius] {
            let (m, _) = mask_volumes(edges, l, r, s_e, offsets, 50.0, true);
            assert!(m.iter().all(|m| finite(&[m.position]) && m.d_e.is_finite()), "{m:?}");
        }
    }
}

#[test]
fn collinear_silhouette_edges_use_the_coincident_plane_rule() {
    // Three collinear edges in a loop-like chain: their planes coincide (n0 = n1).
    let l = DVec3::new(0.0, 5.0, 0.0);
    let edges: Vec<_> = (0..3).map(|i| edge(DVec3::new(i as f64, 1.0, 0.0), DVec3::new(i as f64 + 1.0, 1.0, 0.0), i, i + 1)).collect();
    let VolumeGeometry { vertices: v, stats, .. } = penumbra_volumes(&edges, l, 0.5, 10.0, true);
    assert_eq!(stats.silhouette.light_parallel_edges, 0);
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
        let out = penumbra_volumes(&edges, l, 0.5, 10.0, true).vertices;
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
    let VolumeGeometry { vertices: v, stats, .. } = penumbra_volumes(&edges, l, 0.5, 10.0, true);
    assert_eq!(stats.silhouette.light_parallel_edges, 2);
    assert_eq!(stats.volume_quads, 2);
    assert!(v.iter().all(|v| finite(&[v.position])));
    let (_, mstats) = mask_volumes(&edges, l, 0.5, 0.5, Offsets::Unit, 10.0, true);
    assert_eq!(mstats.silhouette.light_parallel_edges, 2);
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
        let out = penumbra_volumes(&edges, l, 0.5, 10.0, true).vertices;
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
    topology.require_closed(&["bowtie"], false).unwrap();
    let l = DVec3::new(6.0, 6.0, -6.0);
    let edges = silhouette(&topology, l, false);
    let VolumeGeometry { vertices: v, stats, .. } = penumbra_volumes(&edges, l, 0.5, 20.0, true);
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
    Topology::build(&p, &with_sliver).require_closed(&["sliver"], false).unwrap();
    // A collinear (zero-area, distinct corners) face on an edge is degenerate:
    // it makes no edge of its own, and the box stays closed (issue 27).
    let mut q = p.clone();
    q.push((p[0] + p[1]) * 0.5);
    let mut collinear = f.clone();
    collinear.push([0, 1, 8]);
    let t = Topology::build(&q, &collinear);
    t.require_closed(&["collinear"], false).unwrap();
    assert_eq!((t.stats.degenerate_faces, t.faces.len()), (1, f.len()));
    // A duplicated face, in either winding, is one face.
    let l = DVec3::new(0.5, 6.0, 0.3);
    let key = |edges: Vec<SilhouetteEdge>| {
        let mut k: Vec<(u32, u32)> = edges.iter().map(|e| (e.ia, e.ib)).collect();
        k.sort_unstable();
        k
    };
    for twin in [f[0], [f[0][0], f[0][2], f[0][1]]] {
        let mut duplicate = f.clone();
        duplicate.push(twin);
        let dup = Topology::build(&p, &duplicate);
        dup.require_closed(&["dup"], false).unwrap();
        assert_eq!(dup.stats.duplicate_faces, 1);
        assert_eq!(key(silhouette(&dup, l, false)), key(silhouette(&Topology::build(&p, &f), l, false)));
    }
    // A t-junction: split one face's edge with a midpoint its neighbour does not share.
    let mut q = p.clone();
    q.push((p[0] + p[2]) * 0.5);
    let m = 8;
    let mut tj: Vec<[u32; 3]> = f.iter().copied().filter(|t| *t != [0, 2, 3]).collect();
    tj.push([0, m, 3]);
    tj.push([m, 2, 3]);
    let t = Topology::build(&q, &tj);
    let err = t.require_closed(&["tj"], false).unwrap_err().to_string();
    assert!(err.contains("boundary edges"), "{err}");
    // With boundary edges as silhouettes, the volumes are still finite.
    t.require_closed(&["tj"], true).unwrap();
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

/// The largest angle between an extrusion and its vertex's light-cone
/// axis, in units of the cone's half-angle.
fn widest_extrusion(g: &VolumeGeometry, l: DVec3, r: f64) -> f64 {
    let mut widest: f64 = 0.0;
    for quad in g.vertices.chunks(6) {
        for (i, j) in [(0, 1), (5, 4)] {
            let near = DVec3::from(quad[i].position.map(f64::from));
            let far = DVec3::from(quad[j].position.map(f64::from));
            let angle = (far - near).normalize().dot((near - l).normalize()).clamp(-1.0, 1.0).acos();
            widest = widest.max(angle / (r / (near - l).length()).asin());
        }
    }
    widest
}

/// `uv_sphere` of radius 1 moved to (0, 2, 0), its vertices pushed in or
/// out by up to `bump` of the radius (a fixed pseudo-random pattern): a
/// smooth surface as a scanned or modelled mesh tessellates it.
fn bumpy_sphere(rings: u32, segments: u32, bump: f64) -> Topology {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut jitter = || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        1.0 + bump * ((state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0)
    };
    let centre = DVec3::new(0.0, 2.0, 0.0);
    let (unit, f) = uv_sphere(rings, segments);
    let p: Vec<DVec3> = unit.into_iter().map(|u| centre + u * jitter()).collect();
    Topology::build(&p, &f)
}

#[test]
fn jagged_silhouettes_extrude_inside_the_light_cone() {
    // The silhouette of a bumpy tessellated sphere zigzags, folds back and
    // turns sharp corners as the light sees it; the paper's plane
    // intersections there leave the light's cone by several times its
    // angle (the streaks of issue 15), the repaired ones never do.
    let l = DVec3::new(1.5, 6.0, 1.0);
    let r = 0.5;
    let edges = silhouette(&bumpy_sphere(24, 48, 0.05), l, false);
    assert!(edges.len() > 40);
    let paper = widest_extrusion(&penumbra_volumes(&edges, l, r, 10.0, false), l, r);
    assert!(paper > 3.0, "the paper's extrusions stay near the cone here: {paper}");
    let repaired = widest_extrusion(&penumbra_volumes(&edges, l, r, 10.0, true), l, r);
    assert!(repaired <= 1.0 + 1e-4, "{repaired}");
}
