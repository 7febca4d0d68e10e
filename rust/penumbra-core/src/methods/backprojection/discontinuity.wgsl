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
// instead of two passes of a separable maximum over every pixel (issue 30,
// docs/methods/backprojection.md).

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

fn mark(px: vec2<i32>) {
    let p = vec2<u32>(px);
    let words = (textureDimensions(gbuffer_normal).x + 31u) / 32u;
    atomicOr(&lines[p.y * words + p.x / 32u], 1u << (p.x % 32u));
}

// A pixel is marked where another mesh or the background, or a normal
// turned by more than NORMAL_ANGLE, lies among its 8 neighbours: a relation
// between two pixels that holds both ways, so each pair is tested once, by
// the pixel before the other in reading order (its 4 neighbours after it),
// which marks whichever of the two has geometry (4 reads of the normals a
// pixel, not 9). A pixel whose own normal is degenerate is marked too, as
// the test against itself did.
fn shade(pixel: ScreenPixel) {
    let px = pixel.px;
    let size = vec2<i32>(textureDimensions(gbuffer_normal));
    var own = false;
    if (pixel.geometry) {
        own = dot(pixel.n, pixel.n) < NORMAL_COS;
        let centre = inverse_depth(px);
        let dx = inverse_depth(px - vec2<i32>(1, 0)) - 2.0 * centre + inverse_depth(px + vec2<i32>(1, 0));
        let dy = inverse_depth(px - vec2<i32>(0, 1)) - 2.0 * centre + inverse_depth(px + vec2<i32>(0, 1));
        own = own || max(abs(dx), abs(dy)) > DEPTH_CURVATURE * centre;
    }
    for (var k = 0; k < 4; k++) {
        let q = px + select(vec2<i32>(k - 2, 1), vec2<i32>(1, 0), k == 0);
        if (any(q < vec2<i32>(0)) || any(q >= size)) {
            continue;
        }
        let t = textureLoad(gbuffer_normal, q, 0);
        if (t.w != pixel.normal_texel.w || dot(t.xyz, pixel.n) < NORMAL_COS) {
            own = own || pixel.geometry;
            if (!is_background(t)) {
                mark(q);
            }
        }
    }
    if (own) {
        mark(px);
    }
}
