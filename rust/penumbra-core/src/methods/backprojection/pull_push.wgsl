// Method `backprojection`, 5.2: the pull-push reconstruction (Gortler et
// al. 1996; Grossman and Dally 1998) of the sparse v-buffer. A pyramid of
// (visibility, weight): level 0 is the image, weight 1 where the visibility
// is known (lit, umbra, computed penumbra) and 0 where a penumbra pixel was
// skipped or there is no geometry. Pull: each coarser texel averages its
// children by weight and takes their summed weight, saturated at 1. Push,
// from the coarsest level down: each texel becomes w v + (1 - w) times the
// coarser level's bilinear value. The resolve step keeps every known pixel
// and takes the reconstruction for the skipped ones. Level 0 is not stored:
// level 1 is pulled from the image itself, and the resolve step pushes
// level 1 into the skipped pixels alone (weight 0 there, so the push gives
// the bilinear value), two passes over every pixel fewer (issue 30).

struct PullPushStep {
    // 0: pull level 1 from the image; 1: pull this level from the finer
    // one; 2: push this level from the coarser one; 3: resolve into the
    // image from level 1 (other_width 0: no level 1, a 1 x 1 image).
    mode: u32,
    // This level's size and first texel in `pyramid`, and the other level's.
    width: u32,
    height: u32,
    offset: u32,
    other_width: u32,
    other_height: u32,
    other_offset: u32,
    pad: u32,
};

@group(0) @binding(0) var sparse: texture_2d<f32>;
@group(0) @binding(1) var classes: texture_2d<f32>;
@group(0) @binding(2) var<storage, read> step_params: PullPushStep;
@group(0) @binding(3) var<storage, read_write> pyramid: array<vec2<f32>>;
@group(0) @binding(4) var visibility_out: texture_storage_2d<r32float, write>;

// The class of a skipped penumbra pixel (classify.wgsl).
const SKIPPED: f32 = 4.0;

fn at(s: PullPushStep, other: bool, x: u32, y: u32) -> u32 {
    if (other) {
        return s.other_offset + y * s.other_width + x;
    }
    return s.offset + y * s.width + x;
}

// Level 0's (visibility, weight) at image pixel c.
fn image_texel(c: vec2<u32>) -> vec2<f32> {
    let px = vec2<i32>(c);
    let kind = textureLoad(classes, px, 0).r;
    // Known: lit (1), umbra (2), computed penumbra (3).
    let known = kind > 0.5 && kind < 3.5;
    return select(vec2<f32>(0.0), vec2<f32>(textureLoad(sparse, px, 0).r, 1.0), known);
}

// The coarser (other) level's bilinear value at the centre of texel id of
// this level.
fn coarser_value(s: PullPushStep, id: vec2<u32>) -> f32 {
    let g = (vec2<f32>(id) + 0.5) * 0.5 - 0.5;
    let g0 = floor(g);
    let f = g - g0;
    let limit = vec2<i32>(i32(s.other_width) - 1, i32(s.other_height) - 1);
    var up = 0.0;
    for (var k = 0; k < 4; k++) {
        let o = vec2<i32>(k & 1, k >> 1u);
        let c = clamp(vec2<i32>(g0) + o, vec2<i32>(0), limit);
        let w = select(1.0 - f.x, f.x, o.x == 1) * select(1.0 - f.y, f.y, o.y == 1);
        up += w * pyramid[at(s, true, u32(c.x), u32(c.y))].x;
    }
    return up;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let s = step_params;
    if (id.x >= s.width || id.y >= s.height) {
        return;
    }
    let px = vec2<i32>(id.xy);
    switch s.mode {
        case 0u, 1u: {
            var sum = 0.0;
            var weight = 0.0;
            for (var k = 0u; k < 4u; k++) {
                let c = id.xy * 2u + vec2<u32>(k & 1u, k >> 1u);
                if (c.x < s.other_width && c.y < s.other_height) {
                    var t: vec2<f32>;
                    if (s.mode == 0u) {
                        t = image_texel(c);
                    } else {
                        t = pyramid[at(s, true, c.x, c.y)];
                    }
                    sum += t.x * t.y;
                    weight += t.y;
                }
            }
            // weight > 0 where divided.
            let v = select(0.0, sum / max(weight, 1e-30), weight > 0.0);
            pyramid[at(s, false, id.x, id.y)] = vec2<f32>(v, min(weight, 1.0));
        }
        case 2u: {
            let up = coarser_value(s, id.xy);
            let t = pyramid[at(s, false, id.x, id.y)];
            pyramid[at(s, false, id.x, id.y)] = vec2<f32>(t.y * t.x + (1.0 - t.y) * up, 1.0);
        }
        default: {
            var v = textureLoad(sparse, px, 0).r;
            if (textureLoad(classes, px, 0).r == SKIPPED) {
                // Weight 0: the push gives level 1's bilinear value.
                var up = 0.0;
                if (s.other_width > 0u) {
                    up = coarser_value(s, id.xy);
                }
                v = clamp(up, 0.0, 1.0);
            }
            textureStore(visibility_out, px, vec4<f32>(v, 0.0, 0.0, 0.0));
        }
    }
}
