#import passes/light_depth.wgsl

// Depth-only shadow map from the light centre over the fitted frustum
// (Williams 1978). Stores linear light-view depth / far, so that biases and
// comparisons are in world units (light_frustum.rs).

@fragment
fn fs_main(in: VertexOut) -> @builtin(frag_depth) f32 {
    // far > 0 by construction of the frustum.
    return clamp(in.light_depth / shadow.depth.y, 0.0, 1.0);
}

// The mid-point map (Woo 1992): the average of the first- and second-depth
// maps, written by one full-screen triangle.
@group(0) @binding(0) var first_depth: texture_depth_2d;
@group(0) @binding(1) var second_depth: texture_depth_2d;

@vertex
fn vs_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_midpoint(@builtin(position) frag: vec4<f32>) -> @builtin(frag_depth) f32 {
    let texel = vec2<i32>(frag.xy);
    return 0.5 * (textureLoad(first_depth, texel, 0) + textureLoad(second_depth, texel, 0));
}
