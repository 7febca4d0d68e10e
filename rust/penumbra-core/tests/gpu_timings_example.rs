//! Keeps `examples/gpu_timings.rs` (docs/gpu_timings.md) compiling and
//! working: its scenes and readers without a GPU, and one small run of every
//! registered method on whatever adapter there is (skipped without one).

#[allow(dead_code)]
#[path = "../examples/gpu_timings.rs"]
mod gpu_timings;

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;
use gpu_timings::{builtin_scene, icosphere, mesh_scene, parse_args, read_obj, read_ply, run, Status, BUILTIN_SCENES};
use penumbra_core::REGISTRY;

fn args(line: &str) -> Vec<String> {
    line.split_whitespace().map(str::to_owned).collect()
}

/// Twice the signed volume of a closed mesh over 3 (positive when its faces
/// are counter-clockwise seen from outside), and whether every edge is used
/// once in each direction.
fn volume_and_closed(vertices: &[DVec3], faces: &[[u32; 3]]) -> (f64, bool) {
    let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
    let mut volume = 0.0;
    for &[a, b, c] in faces {
        volume += vertices[a as usize].dot(vertices[b as usize].cross(vertices[c as usize])) / 6.0;
        for (p, q) in [(a, b), (b, c), (c, a)] {
            *edges.entry((p, q)).or_default() += 1;
        }
    }
    let closed = edges.iter().all(|(&(p, q), &n)| n == 1 && edges.get(&(q, p)) == Some(&1));
    (volume, closed)
}

#[test]
fn options_default_to_every_registered_method_at_1080p() {
    let o = parse_args(&[]).unwrap();
    assert_eq!(o.methods, REGISTRY.iter().map(|r| r.name).collect::<Vec<_>>());
    assert_eq!((o.width, o.height), (1920, 1080));
    assert_eq!(o.scenes[..4], BUILTIN_SCENES.map(str::to_owned));
    let o = parse_args(&args("--size 64x36 --methods hard,pcss --scenes cube.obj --repeats 2 --out a.json --out b.csv")).unwrap();
    assert_eq!((o.width, o.height, o.repeats, o.out.len()), (64, 36, 2, 2));
    let o = parse_args(&args("--set pcss.kernel=disk --set pcss.filter_samples=8 --set hard.map_size=512")).unwrap();
    assert_eq!(o.params["pcss"].len(), 2);
    assert_eq!(o.params["hard"]["map_size"], penumbra_core::ParamValue::Int(512));
    let e = parse_args(&args("--methods hard,magic")).unwrap_err();
    assert!(e.contains("unknown method \"magic\"") && e.contains("triangle_masks"), "{e}");
    for bad in ["--size 64", "--size 0x8", "--scenes nowhere", "--timing sometimes", "--repeats", "--set magic.a=1", "--set hard"] {
        assert!(parse_args(&args(bad)).is_err(), "{bad} was accepted");
    }
}

#[test]
fn icospheres_are_closed_outward_and_on_the_sphere() {
    for n in [0, 1, 4] {
        let (vertices, faces) = icosphere(n);
        assert_eq!(faces.len(), 20 * 4usize.pow(n));
        assert!(vertices.iter().all(|v| (v.length() - 1.0).abs() < 1e-12));
        let (volume, closed) = volume_and_closed(&vertices, &faces);
        // The volume approaches the unit ball's 4.19 from below.
        assert!(closed && volume > 2.5 && volume < 4.19, "subdivisions {n}: volume {volume}, closed {closed}");
    }
}

#[test]
fn built_in_scenes_have_the_python_triangle_counts() {
    // python/penumbra/scenes.py: a 12-triangle slab, icospheres of 20480 and 5120 faces, 12-triangle boxes.
    let counts: Vec<usize> = BUILTIN_SCENES.iter().map(|s| builtin_scene(s).unwrap().meshes.iter().map(|m| m.faces.len()).sum()).collect();
    assert_eq!(counts, [20492, 24, 5144, 24]);
    for name in BUILTIN_SCENES {
        let scene = builtin_scene(name).unwrap();
        for m in &scene.meshes {
            let vertices: Vec<DVec3> = m.vertices.iter().map(|v| DVec3::from_array(v.map(f64::from))).collect();
            let (volume, closed) = volume_and_closed(&vertices, &m.faces);
            assert!(closed && volume > 0.0, "{name}: {} volume {volume}, closed {closed}", m.name);
        }
    }
    assert!(builtin_scene("nowhere").is_none());
}

#[test]
fn mesh_readers_take_relative_indices_polygons_and_ascii_ply() {
    let (v, f) = read_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1 4/1\nf -4 -2 -1\n").unwrap();
    assert_eq!((v.len(), f), (4, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]));
    assert!(read_obj("v 0 0 0\nf 1 2 3\n").unwrap_err().contains("out of range"));
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
               property float confidence\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
               0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n4 0 1 2 3\n";
    assert_eq!(read_ply(ply).unwrap().1, vec![[0, 1, 2], [0, 2, 3]]);
    assert!(read_ply(&ply.replace("ascii", "binary_little_endian")).unwrap_err().contains("ASCII"));
    assert!(read_ply(&ply.replace("4 0 1 2 3\n", "")).unwrap_err().contains("ends before"));
}

#[test]
fn shared_meshes_are_placed_as_from_mesh_default_places_them() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes/spot.obj");
    if !path.exists() {
        eprintln!("skipping: {} is absent", path.display());
        return;
    }
    let scene = mesh_scene(&path).unwrap();
    let spot = &scene.meshes[1];
    let (lo, hi) = spot.vertices.iter().fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), v| {
        (std::array::from_fn(|i| lo[i].min(v[i])), std::array::from_fn(|i| hi[i].max(v[i])))
    });
    let extent = (0..3).map(|i| hi[i] - lo[i]).fold(0.0, f32::max);
    assert!((extent - 2.5).abs() < 1e-4 && (lo[1] - 1e-3).abs() < 1e-5, "extent {extent}, lowest {}", lo[1]);
    assert!((lo[0] + hi[0]).abs() < 1e-4 && (lo[2] + hi[2]).abs() < 1e-4, "centred on the y axis: {lo:?} {hi:?}");
}

#[test]
fn a_small_run_times_every_registered_method() {
    let dir = std::env::temp_dir().join(format!("gpu_timings_test_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (json, csv) = (dir.join("t.json"), dir.join("t.csv"));
    // The sampling methods' costs grow with their light samples, not with
    // the image: fewer samples keep this test short (reference's 256 took
    // 10-20 s of the run on lavapipe, adaptive's depth 4 about 2 s).
    let cheap = "--set reference.n_samples=4 --set adaptive.max_depth=1";
    let line = format!("--size 48x27 --repeats 1 --scenes resting_box {cheap} --out {} --out {}", json.display(), csv.display());
    let o = parse_args(&args(&line)).unwrap();
    let mut log = Vec::new();
    let report = match run(&o, &mut log) {
        Ok(r) => r,
        Err(e) if e.contains("no GPU adapter") => {
            eprintln!("skipping GPU test: {e}");
            return;
        }
        Err(e) => panic!("{e}"),
    };
    let log = String::from_utf8(log).unwrap();
    eprintln!("{log}");
    assert!(log.starts_with("adapter: "), "{log}");
    // The closing tables: a title, a header and a line per method, twice.
    let tail: Vec<&str> = log.lines().rev().take(2 * (2 + REGISTRY.len())).collect();
    assert!(tail.iter().any(|l| l.starts_with("wall ms")) && tail.iter().any(|l| l.starts_with("method ") && l.contains("resting_box")), "{log}");
    assert!(tail.iter().filter(|l| l.starts_with("triangle_masks ")).count() == 2, "{log}");
    assert_eq!(report.rows.len(), REGISTRY.len());
    for (row, r) in report.rows.iter().zip(REGISTRY) {
        assert_eq!(row.method, r.name);
        match &row.status {
            Status::Ok => {
                assert!(row.wall_ms.len() == 1 && row.wall_ms[0] > 0.0 && row.first_ms > 0.0, "{row:?}");
                let names: Vec<&str> = row.passes.iter().map(|(n, _)| n.as_str()).collect();
                assert!(names.first() == Some(&"gbuffer") && names.ends_with(&["shading", "readback"]), "{}: {names:?}", r.name);
                assert!(row.passes.iter().all(|(_, ms)| ms.is_finite() && *ms >= 0.0), "{row:?}");
            }
            // Only a method that needs a feature the adapter may lack (ray queries).
            Status::Unsupported(why) => assert!(r.name == "raytraced" && why.contains("ray queries"), "{}: {why}", r.name),
            other => panic!("{}: {other:?}", r.name),
        }
    }
    let json = std::fs::read_to_string(&json).unwrap();
    assert!(REGISTRY.iter().all(|r| json.contains(&format!("\"method\": \"{}\"", r.name))), "{json}");
    assert!(json.contains("\"timing_source\": ") && json.trim_end().ends_with('}'));
    assert!(json.contains("\"settings\": {\"adaptive.max_depth\": \"1\", \"reference.n_samples\": \"4\"}"), "{json}");
    let csv = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(csv.lines().count(), 1 + REGISTRY.len());
    assert!(csv.starts_with("adapter,backend,timing_source,width,height,scene,method,status"));
    std::fs::remove_dir_all(&dir).ok();
}
