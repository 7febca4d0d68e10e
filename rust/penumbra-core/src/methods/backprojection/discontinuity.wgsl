#import shaders/receiver.wgsl
#import shaders/per_pixel.wgsl

// Method `backprojection`, 5.2: the screen-space discontinuity buffer. It
// marks pixels at a discontinuity of the receivers: another mesh or the
// background among the 8 neighbours, a normal turning by more than
// NORMAL_ANGLE, or a jump in depth. The paper uses a thresholded Sobel
// filter on depth and normals; the depth test here is on the second
// difference of 1 / depth, which is zero across any plane (1 / view depth is
// affine in screen coordinates over a plane), so that planes seen at grazing
// angles, whose depth gradient is steep, are not discontinuities. The marks
// are bits, 32 pixels of a row to a word (`lines`, cleared before the
// pass): the classification widens them only where it asks, at the
// penumbra pixels the dither skips (`near_discontinuity` in classify.wgsl),
// instead of two passes of a separable maximum over every pixel (issue 30:
// those were 60% of the classification's time at 1920x1080).

@group(0) @binding(2) var<storage, read_write> lines: array<atomic<u32>>;

// cos 30 degrees.
const NORMAL_COS: f32 = 0.866;
// Relative second difference of 1 / depth that marks a depth discontinuity.
const DEPTH_CURVATURE: f32 = 0.01;

fn texel(px: vec2<i32>) -> vec2<i32> {
    return clamp(px, vec2<i32>(0), vec2<i32>(textureDimensions(gbuffer_normal)) - 1);
}

fn inverse_depth(px: vec2<i32>) -> f32 {
    return 1.0 / max(textureLoad(gbuffer_position, texel(px), 0).w, 1e-30);
}

fn detect(pixel: ScreenPixel) -> bool {
    let px = pixel.px;
    for (var k = 0; k < 9; k++) {
        let o = vec2<i32>(k % 3 - 1, k / 3 - 1);
        let q = textureLoad(gbuffer_normal, texel(px + o), 0);
        if (q.w != pixel.normal_texel.w) {
            return true;
        }
        if (dot(q.xyz, pixel.n) < NORMAL_COS) {
            return true;
        }
    }
    let centre = inverse_depth(px);
    let dx = inverse_depth(px - vec2<i32>(1, 0)) - 2.0 * centre + inverse_depth(px + vec2<i32>(1, 0));
    let dy = inverse_depth(px - vec2<i32>(0, 1)) - 2.0 * centre + inverse_depth(px + vec2<i32>(0, 1));
    return max(abs(dx), abs(dy)) > DEPTH_CURVATURE * centre;
}

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    if (pixel.geometry && detect(pixel)) {
        let px = vec2<u32>(pixel.px);
        let words = (textureDimensions(gbuffer_normal).x + 31u) / 32u;
        atomicOr(&lines[px.y * words + px.x / 32u], 1u << (px.x % 32u));
    }
}
