#import shaders/receiver.wgsl
#import passes/shadow_test.wgsl
#import shaders/accumulation.wgsl

// Method `adaptive`, evaluation (Schwarzler et al. 3.4.1-3.4.3): every
// shadow map's hard shadow test, times its weight (Eq. 3, normalised),
// added to a per-pixel accumulation buffer (`accumulate`, once per map: the
// paper's deferred accumulation-buffer variant), then written as visibility
// (`resolve`, shaders/accumulation.wgsl). With `pcf_2x2` each test is the hardware's 2x2 bilinear
// percentage-closer filter (3.4.3).

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
// The test of one map; center.w = its weight.
@group(0) @binding(3) var<storage, read> sample_test: ShadowTest;
// Bindings 4 and 5: the accumulation (shaders/accumulation.wgsl).
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
    accumulate_sample(id, w, v);
}
