#import methods/backprojection/contour.wgsl
#import shaders/per_pixel.wgsl

// Method `backprojection`, pass 1 of its v-buffer (section 6): per camera
// pixel, the kernel of Eq. 1 refined through the local minimum of the
// hierarchy (section 3), the pixel's class (lit, umbra or penumbra) from the
// kernel's depth bounds, and for penumbra pixels the hierarchy level (5.1,
// Eq. 2 and 3) and the view-dependent selection (5.2, Eq. 4-6). Lit and
// umbra pixels get their visibility here; the selected penumbra pixels are
// appended to a list that the visibility pass runs over (the paper's pack).

// Which pixels the visibility pass computes: the indirect dispatch's
// workgroup counts (x, y, z), their number, then the pixels (y << 16 | x).
struct PixelList {
    groups: array<atomic<u32>, 3>,
    count: atomic<u32>,
    pixels: array<u32>,
};

// 5.2's discontinuity marks, a bit a pixel (discontinuity.wgsl).
@group(0) @binding(6) var<storage, read> lines: array<u32>;
// -1 where the penumbra pixel is skipped (5.2).
@group(0) @binding(7) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(8) var class_out: texture_storage_2d<r32float, write>;
@group(0) @binding(9) var kernel_out: texture_storage_2d<r32float, write>;
@group(0) @binding(10) var level_out: texture_storage_2d<r32float, write>;
@group(0) @binding(11) var<storage, read_write> list: PixelList;
@group(0) @binding(12) var<storage, read_write> counters: array<atomic<u32>, 21>;
// The object map and each mesh's object (passes/object_map.rs).
@group(0) @binding(13) var object_map: texture_2d_array<u32>;
@group(0) @binding(14) var<storage, read> mesh_objects: array<u32>;
// The widened marks, written where `WRITE_LINES` is set (intermediates).
@group(0) @binding(15) var lines_out: texture_storage_2d<r32float, write>;

// Bit 3 of `bp.flags`: write `lines_out`.
const WRITE_LINES: u32 = 8u;
// 5.2: a pixel within this many pixels of a discontinuity mark, along x and
// y (a square window), is never left to the pull-push: twice the 4x4
// pattern's spacing, as the pull-push's second level reads 4x4 blocks
// bilinearly.
const LINE_RADIUS: i32 = 8;

// Pixel classes (the `backprojection_class` image).
const BACKGROUND: f32 = 0.0;
const LIT: f32 = 1.0;
const UMBRA: f32 = 2.0;
const PENUMBRA: f32 = 3.0;
const SKIPPED: f32 = 4.0;

// Counters, in the order of `COUNTER_NAMES` in mod.rs.
const C_LIT: u32 = 0u;
const C_UMBRA: u32 = 1u;
const C_PENUMBRA: u32 = 2u;
const C_COMPUTED: u32 = 3u;
const C_SKIPPED: u32 = 4u;
const C_DISCONTINUITY: u32 = 5u;
const C_CAPPED: u32 = 8u;
const C_STEEP: u32 = 18u;
const C_LEVELS: u32 = 9u;

// 5.2: a 4x4 ordered-dither pattern (Bayer): the first 4 form a lattice of
// spacing 2, the first 1 one of spacing 4. Eq. 6 with pattern value
// 16 / rank: pixel of rank k (0-15) is computed when
// s_scr < s_min sqrt(16 / k), i.e. k < 16 (s_min / s_scr)^2; rank 0 always.
var<private> dither: array<u32, 16> = array<u32, 16>(0u, 8u, 2u, 10u, 12u, 4u, 14u, 6u, 3u, 11u, 1u, 9u, 15u, 7u, 13u, 5u);

struct Classified {
    kind: f32,
    v: f32,
    // Kernel half width (level-0 texels) and level code (see `level_code`).
    h0: f32,
    level: f32,
    // Smooth occluder depth z_occ (5.1), for Eq. 4.
    z_occ: f32,
};

// What the level-`level` texels meeting [c - h, c + h] (with one texel to
// spare for the contour's reach: at most 3 x 3 at the level where the
// kernel is under two texels wide) hold: x, their minimum depth; y, their
// status, FREE when no sample under them can occlude, OCCLUDED when all
// do, else MIXED (each texel against the receiver's plane over its own
// footprint, as `tile_status` does: bounds of the whole region against the
// plane over the whole region would find a sloped receiver's own surface
// nearer than the plane's far side and never call it lit).
fn kernel_bounds(r: BpReceiver, level: u32, h: f32) -> vec2<f32> {
    let li = level_info(level);
    let s = li.scale;
    let lo = vec2<i32>(floor((r.coords - h - 1.0) / s));
    let hi = vec2<i32>(floor((r.coords + h + 1.0) / s));
    var z_min = 3.0e38;
    var free = true;
    var occluded = true;
    for (var j = lo.y; j <= hi.y; j++) {
        for (var i = lo.x; i <= hi.x; i++) {
            let t = vec2<i32>(i, j);
            let b = map_bounds(r.layer, li, t, true);
            z_min = min(z_min, b.x);
            if (b.x >= r.depth - r.bias) {
                occluded = false;
                continue;
            }
            if (!r.facing) {
                free = false;
                occluded = false;
                continue;
            }
            // The level-0 sample centres under the texel, relative to p'.
            let c0 = vec2<f32>(t) * s + 0.5 - r.coords;
            let a0 = r.inv_grad * c0;
            let a1 = r.inv_grad * (c0 + s - 1.0);
            let inv_lo = r.inv0 + min(a0.x, a1.x) + min(a0.y, a1.y);
            let inv_hi = r.inv0 + max(a0.x, a1.x) + max(a0.y, a1.y);
            if (below_threshold(r, b.x, inv_lo)) {
                free = false;
            }
            if (!below_threshold(r, b.y, inv_hi)) {
                occluded = false;
            }
        }
    }
    var status = MIXED;
    if (free) {
        status = FREE;
    } else if (occluded) {
        status = OCCLUDED;
    }
    return vec2<f32>(z_min, f32(status));
}

// The level where a kernel of half width h, and the texel it reads beyond
// each side, is under two texels wide: floor(log2(w_k)) (section 3) for
// the widened kernel, clamped to the hierarchy.
fn bounds_level(h: f32) -> u32 {
    let w = max(2.0 * h + 2.0, 1.0);
    return min(u32(floor(log2(w))), bp.levels - 1u);
}

// The level the visibility pass works at, as a code: the level plus, in
// [0, 1), the position of Eq. 3's lambda past it (d of the paper's listing);
// 0.5 where no blending applies (a forced level). y: 1 where the kernel cap
// forced a coarser level, 2 where the receiver's slope forced a finer one.
// `finest` is the finest level whose samples still tell the occluders at
// z_occ from the receiver's own surface (see `classify`).
fn level_code(h0: f32, lambda: f32, finest: f32) -> vec2<f32> {
    let top = f32(bp.levels - 1u);
    let width = max(2.0 * h0, 1.0);
    // The finest level whose conservative kernel stays within max_kernel
    // samples: bounds the work whatever Eq. 3 says.
    let need = max(ceil(log2(width / bp.max_kernel)), 0.0);
    var lod = need;
    var forced = select(0.0, 1.0, need > 0.0);
    var blend = false;
    if ((bp.flags & LIGHT_ADAPTIVE) != 0u) {
        lod = max(floor(lambda), 0.0);
        forced = 0.0;
        blend = lambda >= 0.0;
        if (lod < need) {
            lod = need;
            forced = 1.0;
            blend = false;
        }
    }
    if (lod > finest) {
        // Never finer than the level where the kernel spans `descent` caps.
        let floor_level = max(ceil(log2(width / (bp.descent * bp.max_kernel))), 0.0);
        let limited = max(finest, floor_level);
        if (limited < lod) {
            lod = limited;
            forced = 2.0;
            blend = false;
        }
    }
    if (lod >= top) {
        return vec2<f32>(top + 0.5, forced);
    }
    if (blend) {
        return vec2<f32>(lambda, forced);
    }
    return vec2<f32>(lod + 0.5, forced);
}

fn classify(r: BpReceiver) -> Classified {
    var out = Classified(UMBRA, 0.0, 0.0, -1.0, 0.0);
    let ls = shadow.light_space;
    // Global minimum: the top level of every rendered layer (section 3).
    let top = bp.levels - 1u;
    var z_min = ls.depth.y;
    let layers = select(1, 6, is_cube(ls));
    for (var l = 0; l < layers; l++) {
        if (layer_active(ls, l)) {
            z_min = min(z_min, hierarchy[level_offset(top) + u32(l)].x);
        }
    }
    let lit = disk_above_horizon(r) / PI;
    // Nothing nearer the light than the receiver: nothing can hide it.
    if (z_min >= r.depth - r.bias) {
        return Classified(LIT, lit, 0.0, -1.0, 0.0);
    }
    // Eq. 1 from the global minimum, then refined through the local minimum
    // of the level where the kernel is under two texels, until it stops shrinking.
    var h = kernel_half(r, z_min);
    var b = vec2<f32>(z_min, f32(MIXED));
    var level = 0u;
    for (var k = 0; k < 8; k++) {
        level = bounds_level(h);
        b = kernel_bounds(r, level, h);
        if (u32(b.y) != MIXED) {
            break;
        }
        let shrunk = kernel_half(r, b.x);
        if (shrunk >= 0.9 * h) {
            break;
        }
        h = shrunk;
    }
    // Tighter bounds from the level below (at most 5 x 5 texels): the
    // classification takes these, and the kernel shrinks once more.
    if (level > 0u && u32(b.y) == MIXED) {
        level -= 1u;
        b = kernel_bounds(r, level, h);
        h = min(h, kernel_half(r, b.x));
    }
    out.h0 = h;
    // Classification against the kernel's bounds (section 3), with the
    // receiver's plane standing for z_p (see `occludes`).
    if (u32(b.y) == FREE) {
        return Classified(LIT, lit, h, -1.0, 0.0);
    }
    if (u32(b.y) == OCCLUDED) {
        return Classified(UMBRA, 0.0, h, -1.0, 0.0);
    }
    out.kind = PENUMBRA;
    // 5.1: a continuous occluder depth z_occ, bilinear over the occluding
    // texels of that level around p' (a hint only: the kernel stays the
    // conservative one).
    let li = level_info(level);
    let g = r.coords / li.scale - 0.5;
    let g0 = vec2<i32>(floor(g));
    let fr = g - floor(g);
    var sum = 0.0;
    var weight = 0.0;
    for (var q = 0; q < 4; q++) {
        let o = vec2<i32>(q & 1, q >> 1u);
        let t = map_bounds(r.layer, li, g0 + o, false).x;
        let w = select(1.0 - fr.x, fr.x, o.x == 1) * select(1.0 - fr.y, fr.y, o.y == 1);
        if (t < r.depth - r.bias) {
            sum += w * t;
            weight += w;
        }
    }
    var z_occ = b.x;
    if (weight > 1e-6) {
        z_occ = sum / weight;
    }
    z_occ = clamp(z_occ, b.x, r.depth);
    out.z_occ = z_occ;
    // Eq. 3: lambda = log2(w~_k / t_k), w~_k the kernel of z_occ.
    let smooth_width = 2.0 * kernel_half(r, z_occ) / KERNEL_SLACK;
    let lambda = log2(max(smooth_width, 1e-20) / bp.t_k);
    // A coarse sample occludes only below the receiver's plane's nearest
    // point over its footprint (`occludes`), which lies z_p^2 |grad(1/z)| 2^(l-1)
    // nearer the light than at its centre: a receiver steep in the map (a
    // floor seen edge-on from a cube face) would hide occluders standing
    // (z_p - z_occ) above it from every level where that exceeds half the gap.
    let steep = abs(r.inv_grad.x) + abs(r.inv_grad.y);
    var finest = 1e9;
    if (steep > 0.0) {
        finest = floor(log2(max(0.5 * (r.depth - z_occ) / (r.depth * r.depth * steep), 1e-30)));
    }
    let code = level_code(h, lambda, finest);
    out.level = code.x;
    if (code.y == 1.0) {
        atomicAdd(&counters[C_CAPPED], 1u);
    } else if (code.y == 2.0) {
        atomicAdd(&counters[C_STEEP], 1u);
    }
    return out;
}

// 5.2: whether a discontinuity mark lies in the window of LINE_RADIUS about
// px (clipped to the image): at most 2 words a row, as the window's 17
// pixels span at most two 32-pixel words.
fn near_discontinuity(px: vec2<i32>) -> bool {
    let size = vec2<i32>(textureDimensions(gbuffer_normal));
    let words = (size.x + 31) / 32;
    let lo = max(px - LINE_RADIUS, vec2<i32>(0));
    let hi = min(px + LINE_RADIUS, size - 1);
    for (var w = lo.x / 32; w <= hi.x / 32; w++) {
        // The window's bits of word w: from a to b (both in [0, 31]).
        let a = u32(max(lo.x - 32 * w, 0));
        let b = u32(min(hi.x - 32 * w, 31));
        let mask = (0xffffffffu >> (31u - b)) & (0xffffffffu << a);
        for (var y = lo.y; y <= hi.y; y++) {
            if ((lines[y * words + w] & mask) != 0u) {
                return true;
            }
        }
    }
    return false;
}

// 5.2: whether the visibility pass computes this penumbra pixel; if so it
// joins the list, else it is left to the pull-push reconstruction.
fn select_pixel(r: BpReceiver, c_in: Classified, px: vec2<i32>, p: vec3<f32>, n: vec3<f32>) -> Classified {
    var c = c_in;
    var selected = true;
    var on_discontinuity = false;
    if ((bp.flags & SCREEN_ADAPTIVE) != 0u) {
        // Eq. 4: object-space penumbra width from z_occ (w_l = 2 rho).
        let s_obj = 2.0 * r.rho * (r.depth - c.z_occ) / max(c.z_occ, 1e-30);
        // Eq. 5: its smallest screen diameter, eta s_obj / z_pe n.v.
        let view = bp.eye.xyz - p;
        let view_depth = textureLoad(gbuffer_position, px, 0).w;
        let facing_view = abs(dot(n, view)) / max(length(view), 1e-30);
        let s_scr = bp.eye.w * s_obj / max(view_depth, 1e-30) * facing_view;
        // Eq. 6 (see `dither`).
        let rank = f32(dither[(u32(px.y) % 4u) * 4u + u32(px.x) % 4u]);
        let ratio = bp.s_min / max(s_scr, 1e-30);
        selected = rank == 0.0 || rank < 16.0 * ratio * ratio;
        if (!selected && near_discontinuity(px)) {
            selected = true;
            on_discontinuity = true;
        }
    }
    atomicAdd(&counters[C_PENUMBRA], 1u);
    if (!selected) {
        atomicAdd(&counters[C_SKIPPED], 1u);
        c.kind = SKIPPED;
        c.v = -1.0;
        return c;
    }
    atomicAdd(&counters[C_COMPUTED], 1u);
    if (on_discontinuity) {
        atomicAdd(&counters[C_DISCONTINUITY], 1u);
    }
    atomicAdd(&counters[C_LEVELS + min(u32(c.level), 7u)], 1u);
    let index = atomicAdd(&list.count, 1u);
    list.pixels[index] = (u32(px.y) << 16u) | u32(px.x);
    // Workgroups of 64 pixels, at most 65535 along x.
    let group = index / 64u;
    atomicMax(&list.groups[0], min(group + 1u, 65535u));
    atomicMax(&list.groups[1], group / 65535u + 1u);
    atomicMax(&list.groups[2], 1u);
    c.v = 0.0;
    return c;
}

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    load_params();
    let px = pixel.px;
    var c = Classified(BACKGROUND, 0.0, 0.0, -1.0, 0.0);
    if (pixel.geometry) {
        let p = pixel.p;
        let n = pixel.n;
        if (shadow.center.w == 0.0) {
            // A point light: the test of `hard`, bit for bit.
            let v = shadow_test_visibility(shadow, shadow_map, p, n);
            c = Classified(select(UMBRA, LIT, v > 0.5), v, 0.0, -1.0, 0.0);
        } else {
            let r = bp_receiver(p, n);
            let own = mesh_objects[min(u32(pixel.normal_texel.w), arrayLength(&mesh_objects) - 1u)];
            if (r.hd >= 1.0) {
                // The whole light below the horizon.
                c = Classified(UMBRA, 0.0, 0.0, -1.0, 0.0);
            } else if (!r.facing && !horizon_sliver_seen(shadow, object_map, p, own)) {
                // The centre below the horizon and another object than the
                // receiver's own first from it: that object hides the
                // horizon's sliver too (the object map; the kernel's texels
                // behind p's plane are not searched, issue 27).
                c = Classified(UMBRA, 0.0, 0.0, -1.0, 0.0);
            } else {
                c = classify(r);
            }
            if (c.kind == PENUMBRA) {
                c = select_pixel(r, c, px, p, n);
            }
        }
        if (c.kind == LIT) {
            atomicAdd(&counters[C_LIT], 1u);
        } else if (c.kind == UMBRA) {
            atomicAdd(&counters[C_UMBRA], 1u);
        }
    }
    textureStore(visibility_out, px, vec4<f32>(c.v, 0.0, 0.0, 0.0));
    textureStore(class_out, px, vec4<f32>(c.kind, 0.0, 0.0, 0.0));
    textureStore(kernel_out, px, vec4<f32>(c.h0, 0.0, 0.0, 0.0));
    textureStore(level_out, px, vec4<f32>(c.level, 0.0, 0.0, 0.0));
    if ((bp.flags & WRITE_LINES) != 0u) {
        textureStore(lines_out, px, vec4<f32>(select(0.0, 1.0, near_discontinuity(px)), 0.0, 0.0, 0.0));
    }
}
