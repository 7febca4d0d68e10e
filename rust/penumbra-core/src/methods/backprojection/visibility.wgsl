#import methods/backprojection/contour.wgsl

// Method `backprojection`, pass 2 of its v-buffer (section 6): the
// visibility of every penumbra pixel the classification selected, one
// invocation per listed pixel (an indirect dispatch: the cost follows the
// penumbra's area, not the image's). Contour edges and radial integration
// (4.1, 4.2) at the level the classification chose, blended with the
// neighbouring level near a level transition (5.1, the paper's listing).

struct PixelList {
    groups: array<u32, 3>,
    count: u32,
    pixels: array<u32>,
};

@group(0) @binding(6) var kernel_in: texture_2d<f32>;
@group(0) @binding(7) var level_in: texture_2d<f32>;
@group(0) @binding(8) var<storage, read> list: PixelList;
@group(0) @binding(9) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(10) var<storage, read_write> counters: array<atomic<u32>, 21>;

const C_EDGES: u32 = 6u;
const C_BLENDED: u32 = 7u;
const C_FALLBACKS: u32 = 17u;
const C_CROSSINGS: u32 = 19u;
const C_BLOCKS: u32 = 20u;
// Levels a kernel crossing a cube face's edge goes down (see `main`), while
// it spans at most CROSSING_BUDGET times the kernel cap at the finer level
// (and `descent` caps): the descent's cost
// (4x the samples a level) stays within 4x the cap's. (Up to 4 caps, it
// cost up to 16x: `backprojection` took 15x `hard`'s time on a wide floor
// under a large light, issue 30.)
const CROSSING_LEVELS: u32 = 2u;
const CROSSING_BUDGET: f32 = 2.0;


@compute @workgroup_size(64)
fn main(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
) {
    load_params();
    let index = (group.y * groups.x + group.x) * 64u + local;
    if (index >= list.count) {
        return;
    }
    let packed = list.pixels[index];
    let px = vec2<i32>(i32(packed & 0xffffu), i32(packed >> 16u));
    let p = textureLoad(gbuffer_position, px, 0).xyz;
    let n = textureLoad(gbuffer_normal, px, 0).xyz;
    let r = with_disk_frame(bp_receiver(p, n));
    let h0 = textureLoad(kernel_in, px, 0).r;
    let code = textureLoad(level_in, px, 0).r;
    let top = bp.levels - 1u;
    var lod = min(u32(max(floor(code), 0.0)), top);
    let d = code - floor(code);
    // Near a contact, a coarse level's samples (each the minimum depth of
    // its footprint) can cover p' where the map does not, or the reverse:
    // its contour then puts the light's centre on the wrong side and the
    // integral is off by the whole disk. Where the centre test of the chosen
    // level disagrees with level 0's, the level goes down until they agree,
    // without blending (its kernel then walked within `descent` caps, below).
    // On a cube, a coarse sample beyond the face reads the neighbour face's
    // texel holding its centre, whose footprint there is turned and
    // stretched against the sample's: a kernel crossing a face edge goes
    // down CROSSING_LEVELS levels the same way, within CROSSING_BUDGET
    // caps. (Reading instead the neighbour's texels that cover the
    // footprint, at the level where 2 x 2 do, was no better: median
    // penumbra RMSE 0.049 over the generated suite against 0.046.)
    let size = shadow.light_space.depth.z;
    let crosses = is_cube(shadow.light_space) && (any(r.coords - h0 < vec2<f32>(0.0)) || any(r.coords + h0 > vec2<f32>(size)));
    let cross_level = select(lod, lod - min(lod, CROSSING_LEVELS), crosses);
    if (crosses) {
        atomicAdd(&counters[C_CROSSINGS], 1u);
    }
    // 5.1, the paper's listing: within beta of a level transition, halfway
    // there a mix of the two levels. (Its second weight, (d / beta) / 2, is
    // read as (1 - (1 - d) / beta) / 2, the weight that joins the first one
    // at the transition.) Not after a fallback, and only with a neighbour
    // level whose centre test agrees with level 0's.
    let beta = bp.beta;
    var other_level = lod;
    var weight = 0.0;
    // The centre tests in order, one call site of `centre_inside` (drivers
    // inline every call: with one per test the pipeline took 36-39 s to
    // compile on NVIDIA's driver and 53-59 s on lavapipe without its shader
    // cache; docs/gpu_timings.md): stage 0 tests level 0; stage 1 goes down
    // from the chosen level while its test disagrees (or its kernel crosses
    // a face edge) within the caps; stage 2 tests the blend's other level.
    var inside0 = false;
    var fell = false;
    var stage = 0u;
    loop {
        var query = 0u;
        if (stage == 1u) {
            if (lod == 0u) {
                stage = 2u;
                continue;
            }
            let finer = 2.0 * h0 / f32(1u << (lod - 1u));
            if (lod > cross_level && finer <= min(CROSSING_BUDGET, bp.descent) * bp.max_kernel) {
                lod -= 1u;
                fell = true;
                continue;
            }
            query = lod;
        } else if (stage == 2u) {
            if ((bp.flags & LIGHT_ADAPTIVE) != 0u && beta > 0.0 && !fell) {
                if (d < beta && lod > 0u) {
                    other_level = lod - 1u;
                    weight = 0.5 * (1.0 - d / beta);
                } else if (1.0 - d < beta && lod < top) {
                    other_level = lod + 1u;
                    weight = 0.5 * (1.0 - (1.0 - d) / beta);
                }
            }
            other_level = select(lod, other_level, !fell);
            if (other_level == lod) {
                break;
            }
            query = other_level;
        }
        let inside = centre_inside(r, query);
        if (stage == 0u) {
            inside0 = inside;
            stage = 1u;
        } else if (stage == 1u) {
            if (inside == inside0) {
                stage = 2u;
            } else {
                lod -= 1u;
                fell = true;
            }
        } else {
            if (inside != inside0) {
                other_level = lod;
            }
            break;
        }
    }
    if (fell) {
        atomicAdd(&counters[C_FALLBACKS], 1u);
    }
    // The chosen level, then the other one where it blends in: one call
    // site of `visibility` too (as `centre_inside` above).
    let count = select(1u, 2u, other_level != lod);
    var v = 0.0;
    var edges = 0u;
    var blocks = 0u;
    // A pixel that fell back walks at most `descent` caps of its kernel at
    // the level it fell to (issue 30): its work stays within that many
    // caps', and the contour around p', which the centre test needed, is
    // whole; occluders farther out in the map than that are left out. (Up
    // to issue 30 the fallback stopped at 4 caps instead, 16 times the
    // cap's samples, and a pixel that needed a finer level kept one whose
    // centre test disagreed with level 0's.)
    let h_walk = select(h0, min(h0, 0.5 * bp.descent * bp.max_kernel * f32(1u << lod)), fell);
    for (var k = 0u; k < count; k++) {
        let vis = visibility(r, select(lod, other_level, k == 1u), h_walk);
        v = select(vis.v, mix(v, vis.v, weight), k == 1u);
        edges += vis.edges;
        blocks += vis.blocks;
    }
    if (count == 2u) {
        atomicAdd(&counters[C_BLENDED], 1u);
    }
    atomicAdd(&counters[C_EDGES], edges);
    atomicAdd(&counters[C_BLOCKS], blocks);
    textureStore(visibility_out, px, vec4<f32>(clamp(v, 0.0, 1.0), 0.0, 0.0, 0.0));
}
