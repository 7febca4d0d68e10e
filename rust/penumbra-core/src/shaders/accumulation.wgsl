#import shaders/receiver.wgsl

// A per-pixel accumulation of weighted visibility samples, and its resolve:
// a method adds each sample's test and weight to `accumulated` (one dispatch
// per sample or map, the accumulation-buffer form of Herf 3.4 and Schwarzler
// et al. 3.4.1), then `resolve` writes their weighted mean as visibility.
// Its bindings are 4 and 5 of the importing pass (`reference`, `adaptive`).

// Per pixel: (sum of weight * visibility, sum of weights).
@group(0) @binding(4) var<storage, read_write> accumulated: array<vec2<f32>>;
@group(0) @binding(5) var visibility_out: texture_storage_2d<r32float, write>;

// Adds visibility v with weight w to the sum of invocation id's pixel.
fn accumulate_sample(id: vec3<u32>, w: f32, v: f32) {
    let size = textureDimensions(gbuffer_normal);
    accumulated[id.y * size.x + id.x] += vec2<f32>(w * v, w);
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(gbuffer_normal);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let a = accumulated[id.y * size.x + id.x];
    // No weight (a background pixel, or, with very few samples, no sample
    // facing the pixel): visibility 0, the light treated as hidden, rather
    // than a division by zero.
    let v = select(0.0, clamp(a.x / a.y, 0.0, 1.0), a.y > 0.0);
    textureStore(visibility_out, vec2<i32>(id.xy), vec4<f32>(v, 0.0, 0.0, 0.0));
}
