#import passes/light_view.wgsl

// The vertex stage of the light's depth rasters (the shadow map, the solid
// layers): clip position and linear light-view depth.

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
