#import shaders/receiver.wgsl
#import passes/shadow_test.wgsl
#import shaders/per_pixel.wgsl

// Method `hard`: the shadow-map test from the light centre (Williams 1978),
// visibility 0 or 1; the test and its bias schemes are in passes/shadow_test.wgsl.

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
@group(0) @binding(3) var<storage, read> hard: ShadowTest;
@group(0) @binding(4) var visibility_out: texture_storage_2d<r32float, write>;

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    var v = 0.0;
    if (pixel.geometry) {
        v = shadow_test_visibility(hard, shadow_map, pixel.p, pixel.n);
    }
    textureStore(visibility_out, pixel.px, vec4<f32>(v, 0.0, 0.0, 0.0));
}
