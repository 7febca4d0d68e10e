#import shaders/receiver.wgsl
#import passes/pcf_taps.wgsl
#import shaders/per_pixel.wgsl

// Method `pcss`: percentage-closer soft shadows (Fernando 2005; surveyed in
// Cournia ch. 3, and the basis of PVMF's filter, 5.2). Per pixel:
//   1. blocker search: the mean light depth d_b of the map texels, in a region
//      around the receiver, that are nearer the light than the receiver's plane
//      (by default the farthest of them inside the receiver's light cone:
//      blocker_depth "cone_farthest");
//      no blocker found: fully lit (the paper's early exit);
//   2. penumbra estimate: w_p = (d_r - d_b) w_light / d_b (parallel planes);
//   3. percentage-closer filtering over a disk of that width (passes/pcf_taps.wgsl).
// Sizes are in map texels. Taps are disk samples (the light is a disk as seen
// from the receiver): a jittered n x n grid through Shirley and Chiu's map, or
// the first n x n points of a fixed Poisson-disk set; both rotated per pixel.

struct PcssSampling {
    // Taps per axis of the blocker search and of the filter.
    blocker_samples: u32,
    filter_samples: u32,
    seed: u32,
    // 1: Poisson-disk taps; 0: jittered grid.
    poisson: u32,
    // blocker_test: 0 "plane" (the paper's), 1 "cone", 2 "behind".
    blocker_test: u32,
    // 1: search "scaled"; 0: "uniform" (the paper's).
    scaled: u32,
    // 1: the horizon repair (parameter `horizon`).
    horizon: u32,
    // 1: estimate "area"; 0: "pcf" (the paper's).
    area: u32,
    // 1: blocker_depth "cone_farthest"; 0: "mean" (the paper's).
    cone_farthest: u32,
};

struct PcssPixel {
    v: f32,
    // Estimated penumbra width w_p in map texels (the filter's diameter), and
    // mean blocker depth d_b (world units); 0 where not computed.
    width: f32,
    blocker: f32,
};

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
@group(0) @binding(3) var cmp_sampler: sampler_comparison;
// center.w: the light's radius.
@group(0) @binding(4) var<storage, read> shadow_params: ShadowTest;
@group(0) @binding(5) var<storage, read> pcss_params: PcssSampling;
// Per-invocation copies of the parameters, read once in `shade`: storage-buffer
// loads are not hoisted out of the tap loops on every driver (lavapipe
// gathers and bounds-checks each one).
var<private> shadow: ShadowTest;
var<private> pcss: PcssSampling;
@group(0) @binding(6) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(7) var width_out: texture_storage_2d<r32float, write>;
@group(0) @binding(8) var blocker_out: texture_storage_2d<r32float, write>;
// [0]: pixels that ran the blocker search; [1]: pixels that ran the filter.
@group(0) @binding(9) var<storage, read_write> counters: array<atomic<u32>, 2>;
// The object map and each mesh's object (passes/object_map.rs), for `horizon`.
@group(0) @binding(10) var object_map: texture_2d_array<u32>;
@group(0) @binding(11) var<storage, read> mesh_objects: array<u32>;

// Mitchell's best-candidate points in the unit disk (scripts/poisson_disk.py):
// every prefix is itself well spread, so the first n x n serve for any n <= 8.
var<private> poisson_disk: array<vec2<f32>, 64> = array<vec2<f32>, 64>(
    vec2<f32>(-0.01525, 0.05641), vec2<f32>(-0.37572, -0.91269), vec2<f32>(0.96134, -0.12786), vec2<f32>(0.35693, 0.90836),
    vec2<f32>(-0.97142, -0.16167), vec2<f32>(-0.58623, 0.70453), vec2<f32>(0.49446, -0.81101), vec2<f32>(0.81751, 0.43372),
    vec2<f32>(0.07565, -0.47412), vec2<f32>(-0.41982, -0.28751), vec2<f32>(-0.07516, 0.58037), vec2<f32>(-0.60757, 0.20637),
    vec2<f32>(0.48518, -0.16165), vec2<f32>(-0.77369, -0.55342), vec2<f32>(0.32297, 0.36064), vec2<f32>(0.07910, -0.98709),
    vec2<f32>(0.78490, -0.51630), vec2<f32>(-0.17581, 0.97523), vec2<f32>(0.66464, 0.73767), vec2<f32>(-0.83367, 0.47486),
    vec2<f32>(-0.24005, -0.59888), vec2<f32>(-0.28885, 0.31969), vec2<f32>(0.67067, 0.10645), vec2<f32>(-0.94463, 0.16044),
    vec2<f32>(0.46048, -0.46468), vec2<f32>(0.98254, 0.17887), vec2<f32>(-0.34566, 0.02928), vec2<f32>(-0.08070, -0.23497),
    vec2<f32>(-0.64842, -0.09897), vec2<f32>(0.20420, 0.65328), vec2<f32>(0.26694, 0.08200), vec2<f32>(0.20576, -0.18768),
    vec2<f32>(0.20094, -0.72497), vec2<f32>(0.05050, 0.32550), vec2<f32>(-0.62489, -0.77861), vec2<f32>(0.08161, 0.90137),
    vec2<f32>(0.56253, 0.49408), vec2<f32>(-0.32178, 0.67348), vec2<f32>(-0.52007, 0.45287), vec2<f32>(-0.50790, -0.53182),
    vec2<f32>(0.73423, -0.23414), vec2<f32>(-0.13409, -0.85232), vec2<f32>(-0.77529, -0.30649), vec2<f32>(-0.39952, 0.90800),
    vec2<f32>(0.43416, 0.68866), vec2<f32>(0.62564, -0.64784), vec2<f32>(0.48597, 0.20788), vec2<f32>(0.30465, -0.92901),
    vec2<f32>(0.93431, -0.33132), vec2<f32>(-0.03575, -0.67033), vec2<f32>(-0.22175, -0.38258), vec2<f32>(-0.11139, 0.78015),
    vec2<f32>(0.26684, -0.38783), vec2<f32>(-0.81787, 0.01321), vec2<f32>(-0.17354, -0.05859), vec2<f32>(-0.42631, -0.70825),
    vec2<f32>(-0.18902, 0.15559), vec2<f32>(0.78863, -0.05173), vec2<f32>(0.38758, -0.64558), vec2<f32>(0.65045, 0.29445),
    vec2<f32>(-0.59920, -0.36141), vec2<f32>(-0.79817, 0.28602), vec2<f32>(0.43949, 0.01575), vec2<f32>(0.62635, -0.38101),
);

// Stream offsets of jitter2's index, so that the two stages and the rotation
// draw independent numbers (at most 32 x 32 taps per stage).
const BLOCKER_STREAM: u32 = 0u;
const FILTER_STREAM: u32 = 1024u;
const ROTATION_STREAM: u32 = 2048u;

// Tap i of n x n on the unit disk, rotated by the unit complex number `rot`.
fn disk_tap(px: vec2<u32>, i: u32, n: u32, stream: u32, rot: vec2<f32>) -> vec2<f32> {
    var s: vec2<f32>;
    if (pcss.poisson == 1u) {
        s = poisson_disk[i];
    } else {
        s = square_to_disk(grid_tap(i, n, jitter2(px, pcss.seed, stream + i)));
    }
    return vec2<f32>(rot.x * s.x - rot.y * s.y, rot.y * s.x + rot.x * s.y);
}

// The blocker test's two depths for the texel under `c` (coordinates in the
// receiver's layer or frame; on a cube, the face the direction falls in is
// read), both along the receiver's axis in world units: x, the surface the
// map stores there; y, the receiver's plane along the ray through that
// texel's centre (the ray the map sampled: along the tap's own ray the plane
// would differ by its slope across the texel, and a plane seen at a grazing
// angle would then find itself a blocker). A texel where nothing was drawn
// (the far plane: beyond every surface) holds no blocker, even where the ray
// passes above the receiver's plane's horizon.
struct Texel {
    // The stored depth along the receiver's axis and the receiver's plane
    // there (z >= plane: no blocker), and the texel read.
    z: f32,
    plane: f32,
    stored: StoredTexel,
};

fn texel_blocker(r: Receiver, c: vec2<f32>) -> Texel {
    let ls = shadow.light_space;
    let s = stored_texel(shadow, shadow_map, r, c);
    if (!s.drawn) {
        return Texel(1.0, 0.0, s);
    }
    // The texel centre in the receiver's coordinates.
    var at = s.centre;
    if (r.layer < 0 || s.layer != r.layer) {
        at = receiver_coords(ls, r, light_ray(ls, s.layer, s.centre));
    }
    // The read layer's depth per unit depth along the receiver's axis is
    // positive: the direction's dominant axis is the read face's.
    let z = s.depth / receiver_depth_scale(ls, r, at, s.layer);
    return Texel(z, plane_depth(shadow, r, at), s);
}

// Whether the point q can hide part of the light's sphere from p: the
// angle at p between q and the light's centre within the sphere's angular
// radius, plus `slack` (an angle) for the texel's extent. Safe divisions:
// |c - p| > radius (p is outside the light) and |q - p| > 0 is checked.
fn in_light_cone(p: vec3<f32>, q: vec3<f32>, slack: f32) -> bool {
    let to_q = q - p;
    let to_c = shadow.center.xyz - p;
    let dq = length(to_q);
    let dc = length(to_c);
    if (dq <= 1e-12 * dc || dc <= shadow.center.w) {
        return true;
    }
    let cos_angle = clamp(dot(to_q, to_c) / (dq * dc), -1.0, 1.0);
    let sin_cone = clamp(shadow.center.w / dc, 0.0, 1.0);
    return acos(cos_angle) <= asin(sin_cone) + slack;
}

fn pcss_visibility(px: vec2<u32>, p: vec3<f32>, n: vec3<f32>, own: u32) -> PcssPixel {
    var out = PcssPixel(0.0, 0.0, 0.0);
    // Centre below the surface's horizon: the surface itself hides it (as
    // `hard`), but for the sliver of the light above it with `horizon`.
    if (light_cosine(shadow, p, n) <= 0.0) {
        if (pcss.horizon == 1u && shadow.center.w > 0.0 && horizon_sliver_seen(shadow, object_map, p, own)) {
            out.v = horizon_fraction(shadow, p, n);
        }
        return out;
    }
    let radius = shadow.center.w;
    // A point light casts hard shadows: the test of `hard` (SPEC 7: skip the search).
    if (radius == 0.0) {
        out.v = shadow_test_visibility(shadow, shadow_map, p, n);
        return out;
    }
    let ls = shadow.light_space;
    // The near plane: a frustum's; on cube faces, the distance to the
    // nearest geometry (LightProjection::nearest), which, unlike the faces'
    // own near plane, does not depend on where they cut. Depths are then
    // along the receiver's frame's axis (pcf_frame_receiver).
    var near = ls.depth.x;
    if (is_cube(ls)) {
        near = bitcast<f32>(ls.faces.y);
    }
    let r = pcf_frame_receiver(shadow, p, n);
    let angle = 2.0 * PI * jitter2(px, pcss.seed, ROTATION_STREAM).x;
    let rot = vec2<f32>(cos(angle), sin(angle));

    // 1. Blocker search (Fernando 2005, step 1). Whatever hides part of the
    // light from the receiver lies in the cone from the receiver to the light's
    // disk, whose radius at depth z is radius (d_r - z) / d_r; its projection is
    // widest at the near plane, where it is radius (d_r - near) / d_r world
    // units: Fernando's w_light (d_r - z_near) / d_r. d_r > 0 (every receiver is
    // in front of the light, frustum fit) and the texel size at near > 0.
    atomicAdd(&counters[0], 1u);
    let search = radius * max(r.depth - near, 0.0) / r.depth / light_texel_size(ls, near);
    let nb = pcss.blocker_samples;
    var blocker_sum = 0.0;
    var blockers = 0u;
    // blocker_depth "cone_farthest": the largest depth of the blockers
    // inside the cone from the receiver to the light; 0 while none is.
    var cone_farthest = 0.0;
    // search "scaled" (a departure from Fernando 2005, step 1, whose taps
    // cover the search disk uniformly) spreads the taps by scale: a point at depth z
    // can hide part of the light only within the cone's projection there,
    // R(z) = radius (d_r - z) / d_r / texel(z) texels, which shrinks from
    // `search` at z = near to 0 at z = d_r. Uniform taps over the near
    // disk, where `near` is the nearest geometry (a cube's, or a light close
    // under a shelf), mostly land far outside R(z) of a blocker close to the
    // receiver and find none; so a tap at distance rho in the unit disk goes
    // to search^rho texels from the receiver (search >= 1; else 1): as many
    // taps per octave of reach, and the receiver's own texel (the centre
    // ray) is read first.
    // The found depths are averaged unweighted: weighting each by the map
    // area its tap stands for (Fernando's area mean), or by the part of the
    // light it hides, measured worse on the room suite with blocker_test
    // "cone" (4.8% and 6.7% of pixels off at worst, against 3.5%).
    let scaled = pcss.scaled == 1u;
    let octaves = log2(max(search, 1.0));
    let first = select(0u, 1u, scaled);
    for (var i = 0u; i < nb * nb + first; i++) {
        var offset = vec2<f32>(0.0);
        if (!scaled) {
            offset = search * disk_tap(px, i, nb, BLOCKER_STREAM, rot);
        } else if (i > 0u) {
            let tap = disk_tap(px, i - 1u, nb, BLOCKER_STREAM, rot);
            let rho = length(tap);
            // The division is safe (max); the reach is at most `search`.
            offset = select(vec2<f32>(0.0), tap * (min(exp2(rho * octaves), search) / max(rho, 1e-6)), rho > 1e-6);
        }
        let b = texel_blocker(r, r.coords + offset);
        var blocker = b.z < b.plane - r.bias;
        // blocker_test "cone" (a departure from Fernando 2005, step 1, which
        // takes every texel nearer than the receiver's plane): a point can
        // hide part of the light from p only inside the cone from p to the
        // light's sphere; a texel's extent (light_texel_size at its depth,
        // seen from p) is the slack. Walls and floors beside a receiver (a
        // room's corners) pass the plane test and fail this one.
        if (blocker && pcss.blocker_test == 1u) {
            let extent = light_texel_size(ls, b.z);
            blocker = in_light_cone(p, b.stored.q, extent / max(length(b.stored.q - p), extent));
        }
        if (blocker && pcss.blocker_test == 2u) {
            blocker = receiver_behind(shadow, shadow_map, b.stored, p);
        }
        if (blocker) {
            blocker_sum += b.z;
            blockers += 1u;
            if (pcss.cone_farthest == 1u && b.z > cone_farthest) {
                let extent = light_texel_size(ls, b.z);
                if (in_light_cone(p, b.stored.q, extent / max(length(b.stored.q - p), extent))) {
                    cone_farthest = b.z;
                }
            }
        }
    }
    // The paper's early exit: no blocker, fully lit.
    if (blockers == 0u) {
        out.v = 1.0;
        return out;
    }
    // blockers >= 1; every stored depth is at least near > 0 (the map covers
    // only geometry beyond the fitted near plane), so d_b > 0. On cube faces
    // a blocker's depth along w may fall below its distance, `near`; the
    // clamp keeps d_b > 0 there.
    var d_b = max(blocker_sum / f32(blockers), near);
    // blocker_depth "cone_farthest" (a departure from Fernando 2005, step
    // 1's mean): the penumbra at the receiver is cast by the occluder's rim
    // as the receiver sees it. Of the blockers found, only those inside the
    // cone from the receiver to the light hide any of it (in_light_cone),
    // and the rim is the farthest of them from the light: the faces between
    // it and the light (a shelf's underside from its edge in to over the
    // light, a blob's top) are nearer, and their mean, with the blockers
    // outside the cone, widens the penumbra. Where none of the taps is in
    // the cone (sparse taps in the outer penumbra), the mean.
    if (cone_farthest > 0.0) {
        d_b = max(cone_farthest, near);
    }
    out.blocker = d_b;

    // 2. Penumbra estimate (Fernando 2005, step 2, parallel planes):
    // w_p = (d_r - d_b) w_light / d_b, here as the radius on the receiver,
    // radius (d_r - d_b) / d_b, then in texels of the map at the receiver's
    // depth (r.texel > 0 as d_r > 0).
    let filter_radius = radius * max(r.depth - d_b, 0.0) / d_b / r.texel;
    out.width = 2.0 * filter_radius;

    // 3. Percentage-closer filtering over that disk (step 3).
    atomicAdd(&counters[1], 1u);
    let nf = pcss.filter_samples;
    // estimate "area" (a departure from step 3, which counts the failing
    // taps as if every occluder lay at d_b): each failing tap hides the part
    // of the light its occluder covers within its own light cone
    // (passes/pcf_taps.wgsl, `area_taps`). The cone at depth z, relative to
    // the filter's (d_b's), is ((d_r - z) / z) / ((d_r - d_b) / d_b); a texel
    // nearer the light than d_b counts as at d_b, so an occluder at d_b
    // covering the disk hides all of the light, as step 3 has it; a wall
    // beside the receiver, outside its cone, hides none. A filter narrower
    // than a texel is the receiver's own test (step 3 below).
    if (pcss.area == 1u && filter_radius >= 0.5) {
        let taps = area_taps(nf * nf, filter_radius);
        // d_b < d_r here (filter_radius > 0), so the spread is positive.
        let spread_b = (r.depth - d_b) / d_b;
        var hidden = 0.0;
        for (var i = 0u; i < nf * nf; i++) {
            let x = area_tap(taps, i, nf, jitter2(px, pcss.seed, FILTER_STREAM + i));
            let c = r.coords + filter_radius * x;
            let failed = 1.0 - pcf_tap(shadow, shadow_map, cmp_sampler, r, c);
            if (failed <= 0.0) {
                continue;
            }
            // A failing tap read a drawn texel: its depth z >= near > 0.
            let z = max(texel_blocker(r, c).z, d_b);
            let cone = min(max(r.depth - z, 0.0) / z / spread_b, 1.0);
            hidden += area_share(taps, x, vec2<f32>(cone), failed);
        }
        out.v = 1.0 - min(hidden, 1.0);
        return out;
    }
    var sum = 0.0;
    for (var i = 0u; i < nf * nf; i++) {
        let c = r.coords + filter_radius * disk_tap(px, i, nf, FILTER_STREAM, rot);
        // blocker_test "behind" holds the filter's failing taps to the
        // search's test: a surface the receiver is in front of (a wall
        // beside it, or every other surface where the receiver's plane
        // passes near the light) hides nothing.
        sum += pcf_tap_behind(shadow, shadow_map, cmp_sampler, r, c, p, pcss.blocker_test == 2u);
    }
    // nf >= 1 (checked on the CPU).
    out.v = sum / f32(nf * nf);
    return out;
}

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    shadow = shadow_params;
    pcss = pcss_params;
    let px = pixel.px;
    var o = PcssPixel(0.0, 0.0, 0.0);
    if (pixel.geometry) {
        let own = mesh_objects[min(u32(pixel.normal_texel.w), arrayLength(&mesh_objects) - 1u)];
        o = pcss_visibility(vec2<u32>(pixel.px), pixel.p, pixel.n, own);
        // `horizon`: no more of the light than lies above the tangent plane.
        if (pcss.horizon == 1u && shadow.center.w > 0.0) {
            o.v = min(o.v, horizon_fraction(shadow, pixel.p, pixel.n));
        }
    }
    textureStore(visibility_out, px, vec4<f32>(o.v, 0.0, 0.0, 0.0));
    textureStore(width_out, px, vec4<f32>(o.width, 0.0, 0.0, 0.0));
    textureStore(blocker_out, px, vec4<f32>(o.blocker, 0.0, 0.0, 0.0));
}
