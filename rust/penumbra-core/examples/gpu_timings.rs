//! Per-pass GPU timings of every registered method (`penumbra_core::REGISTRY`)
//! on the built-in scenes and the shared meshes, for one run on a GPU machine
//! (docs/gpu_timings.md, issue 30 "A release example").
//!
//! The scenes are `python/penumbra/scenes.py`'s, rebuilt here with the same
//! geometry, camera and light: `sphere_on_plane`, `cube_on_plane`,
//! `overlapping_casters`, `resting_box`, and each mesh file placed as
//! `scenes.from_mesh(path, setup="default")` places it (scaled to a 2.5-unit
//! box resting on the 10 x 10 ground slab, the built-in light of radius 0.5 and
//! camera). Every method renders with its default parameters, no pass cache
//! (every pass runs in every render, as `penumbra bench` measures), reading
//! back what the bench reads (radiance, visibility, object id).
//!
//! Per scene and method it prints the warm wall time of `Renderer::render`
//! (median of `--repeats` renders after `--warmup` ones, upload and readback
//! included) and the median time of each pass: GPU timestamps where the adapter
//! has them (`--timing auto` uses CPU clocks on a software adapter such as
//! lavapipe, whose timestamps are unreliable, as the bench does), the
//! `readback` pass being the host's part. A method the adapter cannot run
//! (`raytraced` without ray queries) is reported as `unsupported` with the
//! reason; any other error as `error`, and the run goes on.
//!
//! ```sh
//! cargo run --release --example gpu_timings -p penumbra-core -- \
//!     [--scenes a,b] [--methods a,b] [--size 1920x1080] [--repeats 5] [--warmup 1] \
//!     [--meshes ../shared/meshes] [--out FILE.json] [--out FILE.csv] \
//!     [--timing auto|gpu|cpu] [--max-seconds 20] [--budget-seconds 0] \
//!     [--set METHOD.KEY=VALUE]... [--adapter-only]
//! ```
//!
//! `--set reference.n_samples=64` renders a method with a parameter other
//! than its default (repeatable; the JSON's `settings` lists them).
//!
//! `--adapter-only` prints the adapter line and exits: 0 for a hardware
//! adapter, 3 for a software one (lavapipe), 1 when there is none.
//!
//! `--out` may be given more than once: a `.csv` name gets one row per scene
//! and method (a column per pass), any other name JSON. Each file is rewritten
//! after every scene and method, so a run stopped early leaves what it measured.

use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{DVec3, Mat4, Vec3};
use penumbra_core::{
    adapter_summary, AdapterSummary, Camera, Error, MethodConfig, Mesh, Outputs, ParamValue, RenderOptions, Renderer, Scene,
    SphereLight, REGISTRY,
};

/// The built-in scenes of `python/penumbra/scenes.py`, the default first.
pub const BUILTIN_SCENES: [&str; 4] = ["sphere_on_plane", "cube_on_plane", "overlapping_casters", "resting_box"];

/// The mesh files of `../shared/meshes` timed by default: the closed meshes
/// of `scenes.CLOSED_MESHES` and the (open) Stanford bunny.
pub const MESH_FILES: [&str; 4] = ["cube.obj", "spot.obj", "teapot-mcguire-closed.obj", "bun_zipper.ply"];

/// What the bench reads back (`penumbra.bench.runner.OUTPUTS`).
const OUTPUTS: [&str; 3] = ["radiance", "visibility", "object_id"];

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Timing {
    /// GPU timestamps on hardware, CPU clocks on a software adapter.
    Auto,
    /// GPU timestamps wherever the adapter has them.
    Gpu,
    /// CPU clocks around each pass.
    Cpu,
}

#[derive(Debug, Clone)]
pub struct Options {
    pub scenes: Vec<String>,
    pub methods: Vec<String>,
    pub width: u32,
    pub height: u32,
    pub warmup: usize,
    pub repeats: usize,
    pub meshes: PathBuf,
    pub out: Vec<PathBuf>,
    pub timing: Timing,
    /// Timed repeats stop once they would pass this many seconds per scene and method.
    pub max_seconds: f64,
    /// No new scene and method starts after this many seconds of the run (0: no limit).
    pub budget_seconds: f64,
    /// Print the adapter the renderer would pick and stop.
    pub adapter_only: bool,
    /// Parameters other than the defaults, per method (`--set METHOD.KEY=VALUE`).
    pub params: BTreeMap<String, BTreeMap<String, ParamValue>>,
}

const USAGE: &str = "usage: gpu_timings [--scenes a,b] [--methods a,b] [--size WxH] [--repeats N] [--warmup N] \
[--meshes DIR] [--out FILE.json|FILE.csv]... [--timing auto|gpu|cpu] [--max-seconds S] [--budget-seconds S] [--set METHOD.KEY=VALUE]... [--adapter-only]";

fn list(value: &str) -> Vec<String> {
    value.split(',').map(str::trim).filter(|s| !s.is_empty()).map(str::to_owned).collect()
}

fn number<T: std::str::FromStr>(flag: &str, value: &str) -> Result<T, String> {
    value.parse().map_err(|_| format!("{flag}: cannot read {value:?} as a number"))
}

/// Reads the command line (without the program name).
pub fn parse_args(args: &[String]) -> Result<Options, String> {
    let mut o = Options {
        scenes: Vec::new(),
        methods: REGISTRY.iter().map(|r| r.name.to_owned()).collect(),
        width: 1920,
        height: 1080,
        warmup: 1,
        repeats: 5,
        meshes: PathBuf::from("../shared/meshes"),
        out: Vec::new(),
        timing: Timing::Auto,
        max_seconds: 20.0,
        budget_seconds: 0.0,
        adapter_only: false,
        params: BTreeMap::new(),
    };
    let mut scenes = None;
    let mut it = args.iter();
    while let Some(flag) = it.next() {
        if flag == "-h" || flag == "--help" {
            return Err(USAGE.to_owned());
        }
        if flag == "--adapter-only" {
            o.adapter_only = true;
            continue;
        }
        let value = it.next().ok_or_else(|| format!("{flag} needs a value\n{USAGE}"))?;
        match flag.as_str() {
            "--scenes" => scenes = Some(list(value)),
            "--methods" => o.methods = list(value),
            "--size" => {
                let (w, h) = value.split_once(['x', 'X']).ok_or_else(|| format!("--size: expected WxH, got {value:?}"))?;
                (o.width, o.height) = (number("--size", w)?, number("--size", h)?);
                if o.width == 0 || o.height == 0 {
                    return Err(format!("--size: {value:?} has a zero side"));
                }
            }
            "--repeats" => o.repeats = number::<usize>(flag, value)?.max(1),
            // The first render is always a warm-up (it builds the method's pipelines).
            "--warmup" => o.warmup = number::<usize>(flag, value)?.max(1),
            "--meshes" => o.meshes = PathBuf::from(value),
            "--out" => o.out.push(PathBuf::from(value)),
            "--timing" => {
                o.timing = match value.as_str() {
                    "auto" => Timing::Auto,
                    "gpu" => Timing::Gpu,
                    "cpu" => Timing::Cpu,
                    _ => return Err(format!("--timing: expected auto, gpu or cpu, got {value:?}")),
                }
            }
            "--max-seconds" => o.max_seconds = number(flag, value)?,
            "--budget-seconds" => o.budget_seconds = number(flag, value)?,
            "--set" => {
                let parsed = value.split_once('.').and_then(|(m, kv)| kv.split_once('=').map(|(k, v)| (m, k, v)));
                let (method, key, v) = parsed.ok_or_else(|| format!("--set: expected METHOD.KEY=VALUE, got {value:?}"))?;
                o.params.entry(method.to_owned()).or_default().insert(key.to_owned(), param_value(v));
            }
            _ => return Err(format!("unknown option {flag:?}\n{USAGE}")),
        }
    }
    let known: Vec<&str> = REGISTRY.iter().map(|r| r.name).collect();
    if let Some(bad) = o.methods.iter().chain(o.params.keys()).find(|m| !known.contains(&m.as_str())) {
        return Err(format!("--methods: unknown method {bad:?}; registered: {}", known.join(", ")));
    }
    o.scenes = scenes.unwrap_or_else(|| BUILTIN_SCENES.iter().chain(MESH_FILES.iter()).map(|s| (*s).to_owned()).collect());
    if let Some(bad) = o.scenes.iter().find(|s| !BUILTIN_SCENES.contains(&s.as_str()) && !is_mesh_file(s)) {
        return Err(format!(
            "--scenes: {bad:?} is neither a built-in scene ({}) nor a .obj or .ply file name",
            BUILTIN_SCENES.join(", ")
        ));
    }
    Ok(o)
}

/// A parameter value as written: an integer, a float, true or false, else a string.
fn param_value(text: &str) -> ParamValue {
    match (text.parse::<i64>(), text.parse::<f64>(), text) {
        (Ok(i), _, _) => ParamValue::Int(i),
        (_, Ok(f), _) => ParamValue::Float(f),
        (_, _, "true" | "True") => ParamValue::Bool(true),
        (_, _, "false" | "False") => ParamValue::Bool(false),
        _ => ParamValue::Str(text.into()),
    }
}

fn is_mesh_file(name: &str) -> bool {
    let lower = name.to_lowercase();
    lower.ends_with(".obj") || lower.ends_with(".ply")
}

// ---------------------------------------------------------------------------
// Scenes (python/penumbra/scenes.py)

fn mesh(name: &str, vertices: Vec<DVec3>, faces: Vec<[u32; 3]>, albedo: f32, object_id: i32) -> Mesh {
    let vertices = vertices.iter().map(|v| v.as_vec3().to_array()).collect();
    Mesh { name: name.into(), vertices, faces, normals: None, albedo: [albedo; 3], object_id, transform: Mat4::IDENTITY }
}

/// trimesh's `creation.icosphere(subdivisions, radius=1)`: the icosahedron of
/// `creation.icosahedron`, each face split in four at its edge midpoints
/// `subdivisions` times, the vertices pushed back onto the unit sphere after
/// each split (20 * 4^n faces, counter-clockwise seen from outside).
pub fn icosphere(subdivisions: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let corners = [
        [-1.0, t, 0.0], [1.0, t, 0.0], [-1.0, -t, 0.0], [1.0, -t, 0.0],
        [0.0, -1.0, t], [0.0, 1.0, t], [0.0, -1.0, -t], [0.0, 1.0, -t],
        [t, 0.0, -1.0], [t, 0.0, 1.0], [-t, 0.0, -1.0], [-t, 0.0, 1.0],
    ];
    // Every corner has length sqrt(1 + t^2) > 1: normalising is safe.
    let mut vertices: Vec<DVec3> = corners.iter().map(|c| DVec3::from_array(*c).normalize()).collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
        [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<DVec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                // Two distinct unit vectors that are not antipodal (neighbours
                // on the sphere): their midpoint is far from the origin.
                vertices.push(((vertices[a as usize] + vertices[b as usize]) * 0.5).normalize());
                vertices.len() as u32 - 1
            })
        };
        let mut split = Vec::with_capacity(faces.len() * 4);
        for [a, b, c] in faces {
            let (ab, bc, ca) = (midpoint(a, b, &mut vertices), midpoint(b, c, &mut vertices), midpoint(c, a, &mut vertices));
            split.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        faces = split;
    }
    (vertices, faces)
}

/// `scenes.sphere`: an icosphere at `center`; `smooth` gives it the radial normals.
fn sphere(center: DVec3, radius: f64, subdivisions: u32, smooth: bool, object_id: i32, name: &str) -> Mesh {
    let (unit, faces) = icosphere(subdivisions);
    let mut m = mesh(name, unit.iter().map(|v| center + *v * radius).collect(), faces, 0.7, object_id);
    if smooth {
        m.normals = Some(unit.iter().map(|v| v.as_vec3().to_array()).collect());
    }
    m
}

/// An axis-aligned box of full `extents` centred on the origin, faces counter-clockwise seen from outside.
fn box_geometry(extents: DVec3) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let h = extents * 0.5;
    let vertices = (0..8)
        .map(|i| DVec3::new(if i & 1 == 0 { -h.x } else { h.x }, if i & 2 == 0 { -h.y } else { h.y }, if i & 4 == 0 { -h.z } else { h.z }))
        .collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let faces = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    (vertices, faces)
}

/// `scenes.box`: a box of `extents` turned by `yaw_degrees` about y, then moved to `center`.
fn box_mesh(center: [f32; 3], extents: [f64; 3], yaw_degrees: f32, object_id: i32, name: &str) -> Mesh {
    let (vertices, faces) = box_geometry(DVec3::from_array(extents));
    let mut m = mesh(name, vertices, faces, 0.7, object_id);
    m.transform = Mat4::from_translation(Vec3::from_array(center)) * Mat4::from_rotation_y(yaw_degrees.to_radians());
    m
}

/// `scenes.ground_slab()`: a closed 10 x 0.2 x 10 box whose top face is y = 0.
fn ground_slab() -> Mesh {
    let (vertices, faces) = box_geometry(DVec3::new(10.0, 0.2, 10.0));
    mesh("ground", vertices.iter().map(|v| *v - DVec3::new(0.0, 0.1, 0.0)).collect(), faces, 0.8, 0)
}

/// `scenes._camera()` at the asked size.
fn camera(width: u32, height: u32) -> Camera {
    Camera { eye: [0.0, 5.0, 9.0], target: [0.0, 0.8, 0.0], up: [0.0, 1.0, 0.0], fov_y_degrees: 40.0, width, height }
}

/// `scenes._light(radius)` in a scene of `meshes`.
fn lit(meshes: Vec<Mesh>, radius: f32) -> Scene {
    Scene { meshes, light: SphereLight { center: [1.5, 6.0, 1.0], radius, intensity: [80.0; 3] }, ambient: [0.0; 3] }
}

/// The built-in scene `name`, as `scenes.get(name)` builds it.
pub fn builtin_scene(name: &str) -> Option<Scene> {
    let origin = DVec3::ZERO;
    Some(match name {
        "sphere_on_plane" => lit(vec![ground_slab(), sphere(origin.with_y(1.6), 1.0, 5, true, 1, "sphere")], 0.5),
        "cube_on_plane" => lit(vec![ground_slab(), box_mesh([0.0, 1.6, 0.0], [1.5; 3], 30.0, 1, "box")], 0.5),
        "overlapping_casters" => lit(
            vec![
                ground_slab(),
                sphere(DVec3::new(0.6, 3.2, 0.4), 0.6, 4, false, 1, "high_sphere"),
                box_mesh([-0.4, 1.2, -0.2], [1.4, 0.4, 1.4], 15.0, 2, "low_box"),
            ],
            0.5,
        ),
        "resting_box" => lit(vec![ground_slab(), box_mesh([0.0, 1.0, 0.0], [0.8, 2.0, 0.8], 20.0, 1, "box")], 0.8),
        _ => return None,
    })
}

/// Positions and triangles of an OBJ file: `v` lines and `f` lines (1-based
/// or negative indices, `v/vt/vn` corners read by position), polygons
/// fan-triangulated as `scenes._obj_with_relative_indices` does.
pub fn read_obj(text: &str) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), String> {
    let (mut vertices, mut faces) = (Vec::new(), Vec::new());
    for (number, line) in text.lines().enumerate() {
        let mut fields = line.split_whitespace();
        match fields.next() {
            Some("v") => {
                let xyz: Vec<f64> = fields.take(3).map(str::parse).collect::<Result<_, _>>().map_err(|e| format!("line {}: {e}", number + 1))?;
                if xyz.len() != 3 {
                    return Err(format!("line {}: a vertex needs three coordinates", number + 1));
                }
                vertices.push(DVec3::new(xyz[0], xyz[1], xyz[2]));
            }
            Some("f") => {
                let mut corners = Vec::new();
                for field in fields {
                    let i: i64 = field.split('/').next().unwrap_or("").parse().map_err(|e| format!("line {}: {field:?}: {e}", number + 1))?;
                    let i = if i > 0 { i - 1 } else { vertices.len() as i64 + i };
                    if !(0..vertices.len() as i64).contains(&i) {
                        return Err(format!("line {}: vertex index {field} out of range", number + 1));
                    }
                    corners.push(i as u32);
                }
                faces.extend((1..corners.len().saturating_sub(1)).map(|k| [corners[0], corners[k], corners[k + 1]]));
            }
            _ => {}
        }
    }
    Ok((vertices, faces))
}

/// Positions and triangles of an ASCII PLY file (the first three vertex
/// properties are x, y, z; faces are index lists, fan-triangulated).
pub fn read_ply(text: &str) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), String> {
    let mut lines = text.lines();
    let (mut n_vertices, mut n_faces) = (0usize, 0usize);
    let mut ascii = false;
    for line in lines.by_ref() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        match fields.as_slice() {
            ["format", "ascii", ..] => ascii = true,
            ["element", "vertex", n] => n_vertices = n.parse().map_err(|e| format!("vertex count: {e}"))?,
            ["element", "face", n] => n_faces = n.parse().map_err(|e| format!("face count: {e}"))?,
            ["end_header"] => break,
            _ => {}
        }
    }
    if !ascii {
        return Err("only ASCII PLY files are read here".into());
    }
    let mut vertices = Vec::with_capacity(n_vertices);
    for line in lines.by_ref().take(n_vertices) {
        let xyz: Vec<f64> = line.split_whitespace().take(3).map(str::parse).collect::<Result<_, _>>().map_err(|e| format!("vertex: {e}"))?;
        if xyz.len() != 3 {
            return Err(format!("vertex {} has fewer than three coordinates", vertices.len()));
        }
        vertices.push(DVec3::new(xyz[0], xyz[1], xyz[2]));
    }
    let mut faces = Vec::with_capacity(n_faces);
    for line in lines.take(n_faces) {
        let ids: Vec<u32> = line.split_whitespace().skip(1).map(str::parse).collect::<Result<_, _>>().map_err(|e| format!("face: {e}"))?;
        if let Some(&bad) = ids.iter().find(|&&i| i as usize >= vertices.len()) {
            return Err(format!("face index {bad} out of range"));
        }
        faces.extend((1..ids.len().saturating_sub(1)).map(|k| [ids[0], ids[k], ids[k + 1]]));
    }
    if vertices.len() != n_vertices || faces.len() < n_faces {
        return Err(format!("the file ends before its {n_vertices} vertices and {n_faces} faces"));
    }
    Ok((vertices, faces))
}

/// The scene of `scenes.from_mesh(path, setup="default")`: the mesh scaled to
/// a 2.5-unit bounding box (of the vertices its faces use), centred on the y
/// axis, resting 1e-3 above the ground slab, under the built-in light of radius 0.5.
pub fn mesh_scene(path: &Path) -> Result<Scene, String> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let (vertices, faces) = if name.to_lowercase().ends_with(".ply") { read_ply(&text)? } else { read_obj(&text)? };
    let used: Vec<DVec3> = faces.iter().flatten().map(|&i| vertices[i as usize]).collect();
    let (lo, hi) = used.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), v| (lo.min(*v), hi.max(*v)));
    let extent = (hi - lo).max_element();
    if faces.is_empty() || !(extent.is_finite() && extent > 0.0) {
        return Err(format!("{}: no triangles, or a degenerate or non-finite bounding box", path.display()));
    }
    // extent > 0 checked above.
    let scale = 2.5 / extent;
    let centre = (lo + hi) * 0.5;
    let lift = -(lo.y - centre.y) * scale + 1e-3;
    let placed = vertices.iter().map(|v| (*v - centre) * scale + DVec3::new(0.0, lift, 0.0)).collect();
    Ok(lit(vec![ground_slab(), mesh(&name, placed, faces, 0.7, 1)], 0.5))
}

// ---------------------------------------------------------------------------
// Measurement

#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    Ok,
    /// The adapter lacks a feature the method needs.
    Unsupported(String),
    /// The scene could not be built, or the render failed.
    Error(String),
    /// Not started: the run's `--budget-seconds` were spent.
    NotRun(String),
}

impl Status {
    pub fn name(&self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Unsupported(_) => "unsupported",
            Status::Error(_) => "error",
            Status::NotRun(_) => "not_run",
        }
    }
    pub fn reason(&self) -> &str {
        match self {
            Status::Ok => "",
            Status::Unsupported(r) | Status::Error(r) | Status::NotRun(r) => r,
        }
    }
}

/// One scene and method.
#[derive(Debug, Clone)]
pub struct Row {
    pub scene: String,
    pub method: String,
    pub status: Status,
    pub triangles: i64,
    /// The first render's wall time (the method's pipelines are built in the first render of a run).
    pub first_ms: f64,
    /// Every timed render's wall time.
    pub wall_ms: Vec<f64>,
    /// Median per pass over the timed renders, in the order they ran.
    pub passes: Vec<(String, f64)>,
    pub stats: BTreeMap<String, i64>,
}

impl Row {
    fn new(scene: &str, method: &str, status: Status) -> Self {
        Row {
            scene: scene.into(),
            method: method.into(),
            status,
            triangles: 0,
            first_ms: f64::NAN,
            wall_ms: Vec::new(),
            passes: Vec::new(),
            stats: BTreeMap::new(),
        }
    }

    pub fn wall_median_ms(&self) -> f64 {
        median(&self.wall_ms)
    }

    /// The sum of the timed passes but the host's `readback` (GPU time with timestamps).
    pub fn pass_sum_ms(&self) -> f64 {
        self.passes.iter().filter(|(n, _)| n != "readback").map(|(_, ms)| ms).sum()
    }
}

fn median(values: &[f64]) -> f64 {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

pub struct Report {
    pub adapter: AdapterSummary,
    pub timing_source: &'static str,
    pub options: Options,
    pub rows: Vec<Row>,
    pub seconds: f64,
}

fn ms(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.3}")
    } else {
        "null".into()
    }
}

fn json_string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if (c as u32) < 0x20 => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

impl Report {
    pub fn to_json(&self) -> String {
        let a = &self.adapter;
        let mut s = String::from("{\n");
        s += &format!(
            "  \"adapter\": {{\"name\": {}, \"backend\": {}, \"device_type\": {}, \"driver\": {}, \"driver_info\": {}, \
             \"timestamp_queries\": {}, \"ray_queries\": {}, \"is_software\": {}}},\n",
            json_string(&a.name),
            json_string(&a.backend),
            json_string(&a.device_type),
            json_string(&a.driver),
            json_string(&a.driver_info),
            a.timestamp_queries,
            a.ray_queries,
            a.is_software
        );
        let o = &self.options;
        let settings: Vec<String> = o
            .params
            .iter()
            .flat_map(|(m, kv)| kv.iter().map(move |(k, v)| format!("{}: {}", json_string(&format!("{m}.{k}")), json_string(&v.to_string()))))
            .collect();
        s += &format!("  \"settings\": {{{}}},\n", settings.join(", "));
        s += &format!(
            "  \"timing_source\": {},\n  \"width\": {},\n  \"height\": {},\n  \"warmup\": {},\n  \"repeats\": {},\n  \"seconds\": {:.1},\n  \"rows\": [",
            json_string(self.timing_source),
            o.width,
            o.height,
            o.warmup,
            o.repeats,
            self.seconds
        );
        for (i, r) in self.rows.iter().enumerate() {
            let passes: Vec<String> = r.passes.iter().map(|(n, v)| format!("{}: {}", json_string(n), ms(*v))).collect();
            let walls: Vec<String> = r.wall_ms.iter().map(|v| ms(*v)).collect();
            let stats: Vec<String> = r.stats.iter().map(|(n, v)| format!("{}: {v}", json_string(n))).collect();
            s += if i == 0 { "\n" } else { ",\n" };
            s += &format!(
                "    {{\"scene\": {}, \"method\": {}, \"status\": {}, \"reason\": {}, \"triangles\": {}, \"first_ms\": {}, \
                 \"wall_ms\": {}, \"wall_ms_all\": [{}], \"pass_sum_ms\": {}, \"passes_ms\": {{{}}}, \"stats\": {{{}}}}}",
                json_string(&r.scene),
                json_string(&r.method),
                json_string(r.status.name()),
                json_string(r.status.reason()),
                r.triangles,
                ms(r.first_ms),
                ms(r.wall_median_ms()),
                walls.join(", "),
                if r.passes.is_empty() { "null".into() } else { ms(r.pass_sum_ms()) },
                passes.join(", "),
                stats.join(", ")
            );
        }
        s += "\n  ]\n}\n";
        s
    }

    /// One row per scene and method; a column `ms_<pass>` per pass any row has.
    pub fn to_csv(&self) -> String {
        let mut pass_names: Vec<&str> = Vec::new();
        for (name, _) in self.rows.iter().flat_map(|r| &r.passes) {
            if !pass_names.contains(&name.as_str()) {
                pass_names.push(name);
            }
        }
        let quote = |s: &str| format!("\"{}\"", s.replace('"', "\"\""));
        let mut header = vec!["adapter", "backend", "timing_source", "width", "height", "scene", "method", "status", "reason", "triangles", "repeats", "first_ms", "wall_ms", "pass_sum_ms"]
            .into_iter()
            .map(str::to_owned)
            .collect::<Vec<_>>();
        header.extend(pass_names.iter().map(|n| format!("ms_{n}")));
        let mut out = header.join(",") + "\n";
        let blank = |x: f64| if x.is_finite() { format!("{x:.3}") } else { String::new() };
        for r in &self.rows {
            let mut cells = vec![
                quote(&self.adapter.name),
                self.adapter.backend.clone(),
                self.timing_source.into(),
                self.options.width.to_string(),
                self.options.height.to_string(),
                quote(&r.scene),
                r.method.clone(),
                r.status.name().into(),
                quote(r.status.reason()),
                r.triangles.to_string(),
                r.wall_ms.len().to_string(),
                blank(r.first_ms),
                blank(r.wall_median_ms()),
                if r.passes.is_empty() { String::new() } else { blank(r.pass_sum_ms()) },
            ];
            cells.extend(pass_names.iter().map(|n| r.passes.iter().find(|(p, _)| p == n).map_or(String::new(), |(_, v)| blank(*v))));
            out += &(cells.join(",") + "\n");
        }
        out
    }

    fn write_files(&self) -> Result<(), String> {
        for path in &self.options.out {
            let csv = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
            let text = if csv { self.to_csv() } else { self.to_json() };
            // Written beside and renamed: a run stopped mid-write leaves the last whole file.
            let partial = path.with_extension("partial");
            std::fs::write(&partial, text)
                .and_then(|()| std::fs::rename(&partial, path))
                .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        }
        Ok(())
    }
}

/// The human-readable line of a row.
pub fn describe(r: &Row) -> String {
    let head = format!("{:<28} {:<15}", r.scene, r.method);
    match &r.status {
        Status::Ok => {
            let passes: Vec<String> = r.passes.iter().map(|(n, v)| format!("{n} {v:.2}")).collect();
            format!(
                "{head} wall {:>9.2} ms (n={}, first {:.0} ms)  passes {:>8.2} ms  [{}]",
                r.wall_median_ms(),
                r.wall_ms.len(),
                r.first_ms,
                r.pass_sum_ms(),
                passes.join(", ")
            )
        }
        other => format!("{head} {}: {}", other.name(), other.reason()),
    }
}

/// Tables of the warm wall time and the passes' sum, methods by scenes, in
/// ms (`unsup`, `error`, `-` for rows without times; scene names without
/// their extension, cut to 15 characters): the end of a run's output, short
/// enough for the tail of a log.
pub fn summary(rows: &[Row]) -> String {
    let mut scenes: Vec<&str> = Vec::new();
    let mut methods: Vec<&str> = Vec::new();
    for r in rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    let short = |s: &str| s.split('.').next().unwrap_or(s).chars().take(15).collect::<String>();
    let mut out = String::new();
    for (title, value) in [("wall ms, median", Row::wall_median_ms as fn(&Row) -> f64), ("passes ms, without readback", Row::pass_sum_ms)] {
        out += &format!("{title}\n{:<15}{}\n", "method", scenes.iter().map(|s| format!(" {:>15}", short(s))).collect::<String>());
        for m in &methods {
            out += &format!("{m:<15}");
            for s in &scenes {
                let cell = match rows.iter().find(|r| r.method == *m && r.scene == *s) {
                    Some(r) if r.status == Status::Ok => format!("{:.1}", value(r)),
                    Some(r) if matches!(r.status, Status::Unsupported(_)) => "unsup".into(),
                    Some(r) if matches!(r.status, Status::Error(_)) => "error".into(),
                    _ => "-".into(),
                };
                out += &format!(" {cell:>15}");
            }
            out += "\n";
        }
    }
    out
}

/// The adapter, as the first line of a run prints it.
pub fn adapter_line(a: &AdapterSummary) -> String {
    format!(
        "adapter: {} | backend {} | {} | driver {} {} | timestamps {} | ray queries {}",
        a.name, a.backend, a.device_type, a.driver, a.driver_info, a.timestamp_queries, a.ray_queries
    )
}

fn status_of(e: &Error) -> Status {
    match e {
        Error::MissingFeature(why) => Status::Unsupported(why.clone()),
        other => Status::Error(other.to_string()),
    }
}

/// Times one method on one scene.
fn measure(renderer: &Renderer, scene: &Scene, camera: &Camera, name: &str, scene_name: &str, o: &Options) -> Row {
    let mut row = Row::new(scene_name, name, Status::Ok);
    let config = match MethodConfig::parse(name, o.params.get(name).unwrap_or(&BTreeMap::new())) {
        Ok(c) => c,
        Err(e) => return Row { status: status_of(&e), ..row },
    };
    let options = RenderOptions { intermediates: false, outputs: Outputs::parse(OUTPUTS).expect("known outputs") };
    let render = || {
        let clock = Instant::now();
        renderer.render(scene, camera, &config, &options).map(|r| (r, clock.elapsed().as_secs_f64() * 1e3))
    };
    let mut warm_ms = f64::NAN;
    for i in 0..o.warmup {
        match render() {
            Ok((result, wall)) => {
                if i == 0 {
                    row.first_ms = wall;
                    row.triangles = result.stats.get("triangles").copied().unwrap_or(0);
                }
                warm_ms = wall;
            }
            Err(e) => return Row { status: status_of(&e), ..row },
        }
    }
    // As many repeats as fit in --max-seconds at the last warm-up's pace, at least one.
    let fit = (o.max_seconds * 1e3 / warm_ms.max(1e-3)).floor().max(1.0) as usize;
    let mut per_pass: Vec<(String, Vec<f64>)> = Vec::new();
    for _ in 0..o.repeats.min(fit) {
        match render() {
            Ok((result, wall)) => {
                row.wall_ms.push(wall);
                for (pass, t) in result.timings.passes {
                    match per_pass.iter_mut().find(|(n, _)| *n == pass) {
                        Some((_, v)) => v.push(t),
                        None => per_pass.push((pass, vec![t])),
                    }
                }
                row.stats = result.stats;
            }
            Err(e) => return Row { status: status_of(&e), ..row },
        }
    }
    row.passes = per_pass.into_iter().map(|(n, v)| (n, median(&v))).collect();
    row
}

/// Runs every scene and method of `o`, printing each line to `log` and
/// rewriting the `--out` files after each.
pub fn run(o: &Options, log: &mut dyn Write) -> Result<Report, String> {
    let start = Instant::now();
    let adapter = adapter_summary().map_err(|e| e.to_string())?;
    let use_timestamps = match o.timing {
        Timing::Auto => !adapter.is_software,
        Timing::Gpu => true,
        Timing::Cpu => false,
    };
    let renderer = Renderer::with_pass_cache(use_timestamps, false).map_err(|e| e.to_string())?;
    let adapter = renderer.adapter().clone();
    let timing_source = if renderer.uses_timestamps() { "gpu_timestamps" } else { "cpu_clock" };
    let _ = writeln!(log, "{}", adapter_line(&adapter));
    let _ = writeln!(
        log,
        "size {}x{}, warm-up {}, repeats {} (at most {} s each), timing {timing_source}, no pass cache; times in ms",
        o.width, o.height, o.warmup, o.repeats, o.max_seconds
    );
    for (method, kv) in &o.params {
        let set: Vec<String> = kv.iter().map(|(k, v)| format!("{k}={v}")).collect();
        let _ = writeln!(log, "{method}: {}", set.join(" "));
    }
    let mut report = Report { adapter, timing_source, options: o.clone(), rows: Vec::new(), seconds: 0.0 };
    let camera = camera(o.width, o.height);
    for scene_name in &o.scenes {
        let scene = match builtin_scene(scene_name) {
            Some(s) => Ok(s),
            None => mesh_scene(&o.meshes.join(scene_name)),
        };
        for method in &o.methods {
            let spent = start.elapsed().as_secs_f64();
            let row = match &scene {
                _ if o.budget_seconds > 0.0 && spent > o.budget_seconds => {
                    Row::new(scene_name, method, Status::NotRun(format!("the run's budget of {} s was spent", o.budget_seconds)))
                }
                Err(why) => Row::new(scene_name, method, Status::Error(why.clone())),
                Ok(scene) => measure(&renderer, scene, &camera, method, scene_name, o),
            };
            let _ = writeln!(log, "{}", describe(&row));
            report.rows.push(row);
            report.seconds = start.elapsed().as_secs_f64();
            report.write_files()?;
        }
    }
    let _ = write!(log, "{}", summary(&report.rows));
    Ok(report)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let options = match parse_args(&args) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    if options.adapter_only {
        match adapter_summary() {
            Ok(a) => {
                println!("{}", adapter_line(&a));
                std::process::exit(if a.is_software { 3 } else { 0 });
            }
            Err(e) => {
                eprintln!("gpu_timings: {e}");
                std::process::exit(1);
            }
        }
    }
    match run(&options, &mut std::io::stdout()) {
        Ok(report) => {
            let failed = report.rows.iter().filter(|r| matches!(r.status, Status::Error(_))).count();
            println!("{} scene-method pairs in {:.1} s, {failed} with errors", report.rows.len(), report.seconds);
        }
        Err(e) => {
            eprintln!("gpu_timings: {e}");
            std::process::exit(1);
        }
    }
}
