#import shaders/receiver.wgsl
#import shaders/per_pixel.wgsl

// Method `backprojection`, 5.2: the screen-space discontinuity buffer. Step
// 0 marks pixels at a discontinuity of the receivers: another mesh or the
// background among the 8 neighbours, a normal turning by more than
// NORMAL_ANGLE, or a jump in depth. The paper uses a thresholded Sobel
// filter on depth and normals; the depth test here is on the second
// difference of 1 / depth, which is zero across any plane (1 / view depth is
// affine in screen coordinates over a plane), so that planes seen at grazing
// angles, whose depth gradient is steep, are not discontinuities. Steps 1
// and 2 widen the lines by `radius` pixels along x, then y (a separable
// maximum), beyond the pixel spacing of the sparse selection, so that the
// pull-push reconstruction never fills a pixel from across a discontinuity.

struct DiscontinuityStep {
    // 0: detect; 1: widen along x; 2: along y.
    mode: u32,
    radius: i32,
    pad0: u32,
    pad1: u32,
};

@group(0) @binding(2) var source: texture_2d<f32>;
@group(0) @binding(3) var<storage, read> step: DiscontinuityStep;
@group(0) @binding(4) var lines_out: texture_storage_2d<r32float, write>;

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
    let px = pixel.px;
    var line = 0.0;
    let s = step;
    if (s.mode == 0u) {
        if (pixel.geometry && detect(pixel)) {
            line = 1.0;
        }
    } else {
        let dir = select(vec2<i32>(0, 1), vec2<i32>(1, 0), s.mode == 1u);
        for (var k = -s.radius; k <= s.radius; k++) {
            line = max(line, textureLoad(source, texel(px + k * dir), 0).r);
        }
    }
    textureStore(lines_out, px, vec4<f32>(line, 0.0, 0.0, 0.0));
}
