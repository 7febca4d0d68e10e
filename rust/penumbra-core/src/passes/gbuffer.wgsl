// Camera G-buffer (SPEC section 3): world position and view depth, shading
// normal and mesh index. Albedo and object id are looked up by mesh index.

struct CameraUniforms {
    view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
};

@group(0) @binding(0) var<uniform> camera: CameraUniforms;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) mesh_index: u32,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) mesh_index: u32,
    @location(3) view_depth: f32,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    let p = vec4<f32>(v.position, 1.0);
    out.clip = camera.view_proj * p;
    out.world = v.position;
    out.normal = v.normal;
    out.mesh_index = v.mesh_index;
    out.view_depth = -(camera.view * p).z;
    return out;
}

struct GBufferOut {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
};

@fragment
fn fs_main(in: VertexOut) -> GBufferOut {
    // Interpolated vertex normals are renormalised; zero normals (degenerate
    // faces) stay zero rather than dividing by zero.
    let len = length(in.normal);
    let n = select(vec3<f32>(0.0), in.normal / max(len, 1e-30), len > 1e-20);
    var out: GBufferOut;
    out.position = vec4<f32>(in.world, in.view_depth);
    out.normal = vec4<f32>(n, f32(in.mesh_index));
    return out;
}
