#import shaders/receiver.wgsl
#import shaders/per_pixel.wgsl

// PVMF passes 4 and 5 (Cournia 5.3, 5.5): one direction of the separable
// blur of the visibility buffer,
//   v = 1/b_s sum_{i = -n_blur/2}^{n_blur/2} S(u + i) B(u, u + i),
// where B keeps only texels of the same object as texel u and b_s counts
// them. Only texels in the blur mask are blurred; the others are copied and
// take no taps.

@group(0) @binding(2) var source: texture_2d<f32>;
@group(0) @binding(3) var blur_mask: texture_2d<f32>;

struct BlurSettings {
    // One texel along the blur's direction.
    step: vec2<i32>,
    // n_blur / 2 (rounded down).
    half_width: i32,
    // 1 on the pass that counts blurred pixels.
    count: u32,
};
@group(0) @binding(4) var<storage, read> blur_params: BlurSettings;
// Per-invocation copies of the parameters, read once in `shade` (as in pcss/visibility.wgsl).
var<private> blur: BlurSettings;
@group(0) @binding(5) var destination: texture_storage_2d<r32float, write>;
// COUNTERS in mod.rs; the blur adds to blurred_pixels alone.
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>, 5>;

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    blur = blur_params;
    let size = vec2<i32>(textureDimensions(gbuffer_normal));
    let u = pixel.px;
    var v = textureLoad(source, u, 0).x;
    if (textureLoad(blur_mask, u, 0).x > 0.0) {
        // ID(u): the mesh index in the G-buffer (-1 for background, which is never masked).
        let id_u = pixel.normal_texel.w;
        var sum = 0.0;
        var b_s = 0.0;
        for (var i = -blur.half_width; i <= blur.half_width; i++) {
            let t = u + i * blur.step;
            if (all(t >= vec2<i32>(0)) && all(t < size) && textureLoad(gbuffer_normal, t, 0).w == id_u) {
                sum += textureLoad(source, t, 0).x;
                b_s += 1.0;
            }
        }
        // b_s >= 1: texel u itself always counts.
        v = sum / max(b_s, 1.0);
        if (blur.count != 0u) {
            atomicAdd(&counters[2], 1u);
        }
    }
    textureStore(destination, u, vec4<f32>(v, 0.0, 0.0, 0.0));
}
