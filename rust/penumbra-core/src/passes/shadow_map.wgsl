// Depth-only shadow map from the light centre over the fitted frustum
// (Williams 1978). Stores linear light-view depth / far, so that biases and
// comparisons are in world units (light_frustum.rs).

struct ShadowUniforms {
    view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    // near, far, unused, unused
    depth: vec4<f32>,
};

@group(0) @binding(0) var<uniform> shadow: ShadowUniforms;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) light_depth: f32,
};

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOut {
    var out: VertexOut;
    let p = vec4<f32>(position, 1.0);
    out.clip = shadow.view_proj * p;
    out.light_depth = -(shadow.view * p).z;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @builtin(frag_depth) f32 {
    // far > 0 by construction of the frustum.
    return clamp(in.light_depth / shadow.depth.y, 0.0, 1.0);
}
