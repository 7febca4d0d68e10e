//! Resident-set growth of whole renders through `Renderer::render`, the
//! Rust counterpart of `tests/test_long_runs.py` (docs/stability.md,
//! "Resident set"): a plane and a box, 32x32, `METHOD` rendered `N` times after
//! 20 warm-up renders with the light radius cycling; prints the growth and the
//! wall time per render.
//!
//! No pass cache: every pass runs in every render.
//!
//! `cargo run --release --example render_rss -- METHOD N [KEY=VALUE ...]`

use std::collections::BTreeMap;

use glam::Mat4;
use penumbra_core::{Camera, MethodConfig, Mesh, ParamValue, RenderOptions, Renderer, Scene, SphereLight};

fn rss_mib() -> f64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap();
    let pages: f64 = statm.split_whitespace().nth(1).unwrap().parse().unwrap();
    pages * 4096.0 / (1024.0 * 1024.0)
}

fn mesh(name: &str, vertices: Vec<[f32; 3]>, faces: Vec<[u32; 3]>, object_id: i32) -> Mesh {
    Mesh { name: name.into(), vertices, faces, normals: None, albedo: [0.8; 3], object_id, transform: Mat4::IDENTITY }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let method = args.get(1).cloned().unwrap_or_else(|| "hard".into());
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(60);
    let plane = mesh("plane", vec![[-4.0, 0.0, -4.0], [4.0, 0.0, -4.0], [4.0, 0.0, 4.0], [-4.0, 0.0, 4.0]], vec![[0, 2, 1], [0, 3, 2]], 0);
    let (c, h) = ([0.0f32, 1.0, 0.0], 0.5f32);
    let vertices = (0..8)
        .map(|i| {
            [
                c[0] + if i & 1 == 0 { -h } else { h },
                c[1] + if i & 2 == 0 { -h } else { h },
                c[2] + if i & 4 == 0 { -h } else { h },
            ]
        })
        .collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let faces = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    let cube = mesh("cube", vertices, faces, 1);
    let camera = Camera { eye: [0.0, 6.0, 6.0], target: [0.0; 3], up: [0.0, 1.0, 0.0], fov_y_degrees: 45.0, width: 32, height: 32 };
    // The plane is an open receiver: the silhouette methods treat its border as silhouette edges.
    let mut params = BTreeMap::new();
    if method.starts_with("pvm") {
        params.insert("open_edges".to_owned(), ParamValue::Str("silhouette".into()));
    }
    for pair in args.iter().skip(3) {
        let (key, value) = pair.split_once('=').expect("parameters as key=value");
        let value = match (value.parse::<i64>(), value.parse::<f64>()) {
            (Ok(i), _) => ParamValue::Int(i),
            (_, Ok(f)) => ParamValue::Float(f),
            _ => ParamValue::Str(value.into()),
        };
        params.insert(key.to_owned(), value);
    }
    let config = MethodConfig::parse(&method, &params).expect("method");
    let renderer = Renderer::with_pass_cache(false, false).expect("renderer");
    let one = |i: usize| {
        let scene = Scene {
            meshes: vec![plane.clone(), cube.clone()],
            light: SphereLight { center: [0.0, 5.0, 0.0], radius: 0.2 + 0.001 * (i % 97) as f32, intensity: [10.0; 3] },
            ambient: [0.0; 3],
        };
        renderer.render(&scene, &camera, &config, &RenderOptions::default()).expect("render");
    };
    for i in 0..20 {
        one(i);
    }
    let start = rss_mib();
    let clock = std::time::Instant::now();
    for i in 20..20 + n {
        one(i);
    }
    let seconds = clock.elapsed().as_secs_f64() / n as f64;
    let end = rss_mib();
    println!(
        "{method}: {start:.1} -> {end:.1} MiB over {n} renders, {:.4} MiB and {:.1} ms per render",
        (end - start) / n as f64,
        seconds * 1e3
    );
}
