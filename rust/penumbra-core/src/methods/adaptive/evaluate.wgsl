#import shaders/receiver.wgsl
#import passes/shadow_test.wgsl

// Method `adaptive`, evaluation (Schwarzler et al. 3.4.1-3.4.3): every
// shadow map's hard shadow test, times its weight (Eq. 3, normalised),
// added to a per-pixel accumulation buffer (`accumulate`, once per map: the
// paper's deferred accumulation-buffer variant), then written as visibility
// (`resolve`). With `pcf_2x2` each test is the hardware's 2x2 bilinear
// percentage-closer filter (3.4.3).

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
// The test of one map; center.w = its weight.
@group(0) @binding(3) var<storage, read> sample_test: ShadowTest;
// Per pixel: (sum of weight * visibility, sum of weights).
@group(0) @binding(4) var<storage, read_write> accumulated: array<vec2<f32>>;
@group(0) @binding(5) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(6) var comparison: sampler_comparison;

@compute @workgroup_size(8, 8)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(id);
    if (!pixel.inside || !pixel.geometry) {
        return;
    }
    let w = sample_test.center.w;
    var v = 0.0;
    // mode.y = 1: `pcf_2x2`.
    if (sample_test.mode.y == 1u) {
        v = shadow_test_visibility_filtered(sample_test, shadow_map, comparison, pixel.p, pixel.n);
    } else {
        v = shadow_test_visibility(sample_test, shadow_map, pixel.p, pixel.n);
    }
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
    // Background pixels got no weight: visibility 0 there, never a division by zero.
    let v = select(0.0, clamp(a.x / a.y, 0.0, 1.0), a.y > 0.0);
    textureStore(visibility_out, vec2<i32>(id.xy), vec4<f32>(v, 0.0, 0.0, 0.0));
}
