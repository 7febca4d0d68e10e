#import shaders/receiver.wgsl
#import passes/pcf_taps.wgsl
#import shaders/per_pixel.wgsl

// Method `pcf`: percentage-closer filtering with a fixed kernel (Reeves et
// al. 1987; Cournia 3.4): the mean of the shadow-map tests over a square of
// `kernel` texels around the receiver, from an n x n jittered grid of taps
// (passes/pcf_taps.wgsl).

struct PcfKernel {
    // Kernel width in map texels.
    kernel: f32,
    // Taps per axis.
    samples: u32,
    seed: u32,
    // 1 when the comparison sampler is the nearest-texel one.
    nearest: u32,
};

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
@group(0) @binding(3) var cmp_sampler: sampler_comparison;
@group(0) @binding(4) var<storage, read> shadow_params: ShadowTest;
@group(0) @binding(5) var<storage, read> pcf_params: PcfKernel;
// Per-invocation copies of the parameters, read once in `shade` (as in pcss/visibility.wgsl).
var<private> shadow: ShadowTest;
var<private> pcf: PcfKernel;
@group(0) @binding(6) var visibility_out: texture_storage_2d<r32float, write>;

fn pcf_visibility(px: vec2<u32>, p: vec3<f32>, n: vec3<f32>) -> f32 {
    // Centre below the surface's horizon: the surface itself hides it (as `hard`).
    if (light_cosine(shadow, p, n) <= 0.0) {
        return 0.0;
    }
    // A zero-width nearest kernel reads one texel: Williams' test, with the
    // bias of `hard` (the receiver plane only stands in for the slope term
    // where taps leave the receiver's texel).
    if (pcf.kernel == 0.0 && pcf.nearest == 1u) {
        return shadow_test_visibility(shadow, shadow_map, p, n);
    }
    // On cube faces the kernel lies across the light's direction (pcf_frame_receiver).
    let r = pcf_frame_receiver(shadow, p, n);
    let count = pcf.samples * pcf.samples;
    var sum = 0.0;
    for (var i = 0u; i < count; i++) {
        let offset = grid_tap(i, pcf.samples, jitter2(px, pcf.seed, i)) * pcf.kernel;
        sum += pcf_tap(shadow, shadow_map, cmp_sampler, r, r.coords + offset);
    }
    // count >= 1 (samples >= 1 is checked on the CPU).
    return sum / f32(count);
}

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    shadow = shadow_params;
    pcf = pcf_params;
    var v = 0.0;
    if (pixel.geometry) {
        v = pcf_visibility(vec2<u32>(pixel.px), pixel.p, pixel.n);
    }
    textureStore(visibility_out, pixel.px, vec4<f32>(v, 0.0, 0.0, 0.0));
}
