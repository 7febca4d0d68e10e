#import shaders/receiver.wgsl

// Method `triangle_masks` (Sintorn, Eisemann & Assarsson 2008): per pixel, a
// bitmask over the light samples of `reference`'s sphere sampling; every
// triangle that can hide part of the light from the pixel ORs in the samples
// it hides (their segment from the pixel's point crosses it), and the
// visibility is the weighted share of samples left (methods/triangle_masks/
// mod.rs). Triangles reach a pixel through the list of its screen tile.
//
// Entry points, in the order they run:
// - `tile_bounds`: per 16 x 16-pixel tile, the box of its receivers' points;
// - `group_bounds`: per 8 x 8 tiles, the box of their boxes;
// - `count_bins` / `scan_bins` / `fill_bins`: per triangle, the tiles whose
//   receivers it can shadow (counted, offsets by a prefix sum, listed);
// - `masks`: per pixel, the masks and the visibility.

struct MaskSettings {
    // The light's centre (xyz) and radius (w).
    light: vec4<f32>,
    // x: the ray origins' offset along the normal (world units, raytraced's
    // rule); y: the margin that keeps the binning conservative (world units).
    offset: vec4<f32>,
    // x: light samples; y: triangles; z: the tile lists' capacity (entries);
    // w: 1 binned, 0 every pixel takes every triangle.
    counts: vec4<u32>,
    // x, y: tiles across and down; z, w: groups of tiles across and down.
    tiles: vec4<u32>,
    // x: invocations across the per-triangle dispatch (a row of triangles).
    dispatch: vec4<u32>,
};

struct LightSample {
    // xyz: the point on the light; w: its weight (methods/reference/mod.rs, LightSample).
    position: vec4<f32>,
    // xyz: the sphere's outward unit normal there; w = 1: weight by solid
    // angle, 0: equal weights (a point light).
    normal: vec4<f32>,
};

// A box of receiver points; hi.w = 1 when it holds any (else it is empty).
struct Bounds {
    lo: vec4<f32>,
    hi: vec4<f32>,
};

@group(0) @binding(2) var<storage, read> settings: MaskSettings;
@group(0) @binding(3) var<storage, read> samples: array<LightSample>;
// Three corners (xyz) per triangle.
@group(0) @binding(4) var<storage, read> triangles: array<vec4<f32>>;
// The tiles' boxes, then the groups'.
@group(0) @binding(5) var<storage, read_write> bounds: array<Bounds>;
// [0, tiles): per tile, the count (`count_bins`) and then the fill cursor;
// [tiles + 2 t]: tile t's first entry in `tile_list`, [tiles + 2 t + 1]: its count.
@group(0) @binding(6) var<storage, read_write> bins: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> tile_list: array<u32>;
// Stats (mod.rs, COUNTERS).
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(9) var visibility_out: texture_storage_2d<r32float, write>;

const TILE: u32 = 16u;
const GROUP: u32 = 8u;
// Light samples per pass over a pixel's triangles: 32 words of the mask in
// private memory; more samples take more passes.
const CHUNK_WORDS: u32 = 32u;
const BIG: f32 = 3.0e38;
const FULL: u32 = 0xFFFFFFFFu;

fn saturating_add(a: u32, b: u32) -> u32 {
    return select(a + b, FULL, a > FULL - b);
}

// Adds `value` to the 64-bit counter at counters[i] (low word) and [i + 1].
fn add_wide(i: u32, value: u32) {
    let old = atomicAdd(&counters[i], value);
    if (old > FULL - value) {
        atomicAdd(&counters[i + 1u], 1u);
    }
}

fn tile_count() -> u32 {
    return settings.tiles.x * settings.tiles.y;
}

var<workgroup> wg_lo: array<vec4<f32>, 64>;
var<workgroup> wg_hi: array<vec4<f32>, 64>;

// One workgroup per tile (dispatched over tiles x 8 by tiles y 8
// invocations), each invocation 2 x 2 of its pixels: the box of the
// receivers' points, by a tree reduction.
@compute @workgroup_size(8, 8)
fn tile_bounds(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    var lo = vec4<f32>(BIG, BIG, BIG, 0.0);
    var hi = vec4<f32>(-BIG, -BIG, -BIG, 0.0);
    for (var k = 0u; k < 4u; k++) {
        let px = wg.xy * TILE + lid.xy * 2u + vec2<u32>(k & 1u, k >> 1u);
        let pixel = screen_pixel(vec3<u32>(px, 0u));
        if (pixel.inside && pixel.geometry) {
            lo = vec4<f32>(min(lo.xyz, pixel.p), 0.0);
            hi = vec4<f32>(max(hi.xyz, pixel.p), 1.0);
        }
    }
    wg_lo[li] = lo;
    wg_hi[li] = hi;
    workgroupBarrier();
    for (var s = 32u; s > 0u; s >>= 1u) {
        if (li < s) {
            wg_lo[li] = min(wg_lo[li], wg_lo[li + s]);
            wg_hi[li] = max(wg_hi[li], wg_hi[li + s]);
        }
        workgroupBarrier();
    }
    if (li == 0u && wg.x < settings.tiles.x && wg.y < settings.tiles.y) {
        bounds[wg.y * settings.tiles.x + wg.x] = Bounds(wg_lo[0], wg_hi[0]);
    }
}

// One invocation per group of GROUP x GROUP tiles: the box of their boxes.
@compute @workgroup_size(8, 8)
fn group_bounds(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= settings.tiles.z || id.y >= settings.tiles.w) {
        return;
    }
    var lo = vec4<f32>(BIG, BIG, BIG, 0.0);
    var hi = vec4<f32>(-BIG, -BIG, -BIG, 0.0);
    let first = id.xy * GROUP;
    let last = min(first + GROUP, settings.tiles.xy);
    for (var y = first.y; y < last.y; y++) {
        for (var x = first.x; x < last.x; x++) {
            let b = bounds[y * settings.tiles.x + x];
            if (b.hi.w > 0.0) {
                lo = min(lo, b.lo);
                hi = max(hi, b.hi);
            }
        }
    }
    bounds[tile_count() + id.y * settings.tiles.z + id.x] = Bounds(lo, hi);
}

// Whether triangle (a, b, c) can cross a segment from a receiver of box
// `box` to a point of the light: whether it meets the convex hull of the
// box and the light's sphere, tested conservatively (every test widened by
// the margin, so that rounding never drops a triangle):
// 1. its bounding box against the box around both;
// 2. its plane: some of the box or of the sphere lies on either side;
// 3. its bounding sphere against the hull of the box's bounding sphere and
//    the light's, which lies within max(radii) of the segment between
//    their centres (the hull of two balls is the union of the balls
//    interpolated between them).
fn can_shadow(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, box: Bounds) -> bool {
    let margin = settings.offset.y;
    let l = settings.light.xyz;
    let r = settings.light.w + margin;
    let lo = min(box.lo.xyz, l - vec3<f32>(r)) - vec3<f32>(margin);
    let hi = max(box.hi.xyz, l + vec3<f32>(r)) + vec3<f32>(margin);
    let t_lo = min(a, min(b, c));
    let t_hi = max(a, max(b, c));
    if (any(t_lo > hi) || any(t_hi < lo)) {
        return false;
    }
    let n = cross(b - a, c - a);
    let n_len = length(n);
    let center = 0.5 * (box.lo.xyz + box.hi.xyz);
    let half = 0.5 * (box.hi.xyz - box.lo.xyz) + vec3<f32>(margin);
    // A zero-area triangle hides nothing (`occlude` needs a strict crossing of its plane).
    if (n_len == 0.0) {
        return false;
    }
    let box_mid = dot(n, center - a);
    let box_reach = dot(abs(n), half);
    let light_mid = dot(n, l - a);
    let light_reach = r * n_len;
    let above = box_mid - box_reach > 0.0 && light_mid - light_reach > 0.0;
    let below = box_mid + box_reach < 0.0 && light_mid + light_reach < 0.0;
    if (above || below) {
        return false;
    }
    let m = (a + b + c) / 3.0;
    let t_radius = sqrt(max(dot(a - m, a - m), max(dot(b - m, b - m), dot(c - m, c - m))));
    let axis = l - center;
    let axis_len2 = dot(axis, axis);
    // The closest point of the axis segment to m (a point for a zero-length axis).
    let t = select(0.0, clamp(dot(m - center, axis) / axis_len2, 0.0, 1.0), axis_len2 > 0.0);
    let d = m - (center + axis * t);
    let reach = max(length(half), r) + t_radius + margin;
    return dot(d, d) <= reach * reach;
}

fn corner(i: u32, k: u32) -> vec3<f32> {
    return triangles[3u * i + k].xyz;
}

// Per triangle (mode 0: count, 1: fill): the tiles it can shadow, through
// the groups (a group's box holds its tiles', so a group the triangle cannot
// shadow has no tile it can).
fn bin_triangle(i: u32, fill: bool) {
    let a = corner(i, 0u);
    let b = corner(i, 1u);
    let c = corner(i, 2u);
    let tiles = tile_count();
    for (var gy = 0u; gy < settings.tiles.w; gy++) {
        for (var gx = 0u; gx < settings.tiles.z; gx++) {
            let g = bounds[tiles + gy * settings.tiles.z + gx];
            if (g.hi.w == 0.0 || !can_shadow(a, b, c, g)) {
                continue;
            }
            let last = min(vec2<u32>(gx + 1u, gy + 1u) * GROUP, settings.tiles.xy);
            for (var y = gy * GROUP; y < last.y; y++) {
                for (var x = gx * GROUP; x < last.x; x++) {
                    let t = y * settings.tiles.x + x;
                    let box = bounds[t];
                    if (box.hi.w == 0.0 || !can_shadow(a, b, c, box)) {
                        continue;
                    }
                    let slot = atomicAdd(&bins[t], 1u);
                    if (fill) {
                        let start = atomicLoad(&bins[tiles + 2u * t]);
                        let count = atomicLoad(&bins[tiles + 2u * t + 1u]);
                        // An overflowed tile lists nothing: its pixels take every triangle.
                        if (saturating_add(start, count) <= settings.counts.z) {
                            tile_list[start + slot] = i;
                        }
                    }
                }
            }
        }
    }
}

fn triangle_index(id: vec3<u32>) -> u32 {
    return id.y * settings.dispatch.x + id.x;
}

@compute @workgroup_size(8, 8)
fn count_bins(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = triangle_index(id);
    if (id.x < settings.dispatch.x && i < settings.counts.y) {
        bin_triangle(i, false);
    }
}

@compute @workgroup_size(8, 8)
fn fill_bins(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = triangle_index(id);
    if (id.x < settings.dispatch.x && i < settings.counts.y) {
        bin_triangle(i, true);
    }
}

var<workgroup> wg_sums: array<u32, 64>;

// One workgroup: the tiles' first entries, an exclusive prefix sum of their
// counts (64 contiguous runs, then the runs' sums); the counts become fill
// cursors (zeroed). Sums saturate: a tile whose list would end past the
// capacity (or past 2^32) is overflowed and takes every triangle.
@compute @workgroup_size(8, 8)
fn scan_bins(@builtin(local_invocation_index) li: u32) {
    let tiles = tile_count();
    let run = (tiles + 63u) / 64u;
    let first = min(li * run, tiles);
    let last = min(first + run, tiles);
    var sum = 0u;
    for (var t = first; t < last; t++) {
        sum = saturating_add(sum, atomicLoad(&bins[t]));
    }
    wg_sums[li] = sum;
    workgroupBarrier();
    if (li == 0u) {
        var total = 0u;
        for (var k = 0u; k < 64u; k++) {
            let s = wg_sums[k];
            wg_sums[k] = total;
            total = saturating_add(total, s);
        }
        atomicStore(&counters[0], total);
    }
    workgroupBarrier();
    var start = wg_sums[li];
    for (var t = first; t < last; t++) {
        let count = atomicLoad(&bins[t]);
        atomicStore(&bins[tiles + 2u * t], start);
        atomicStore(&bins[tiles + 2u * t + 1u], count);
        atomicStore(&bins[t], 0u);
        if (saturating_add(start, count) > settings.counts.z) {
            atomicAdd(&counters[1], 1u);
        }
        if (count == 0u && bounds[t].hi.w > 0.0) {
            atomicAdd(&counters[7], 1u);
        }
        start = saturating_add(start, count);
    }
}

// The weight of sample s for a receiver at p: raytraced's sample_weight
// (methods/raytraced/visibility.wgsl), the same as reference's.
fn sample_weight(s: LightSample, p: vec3<f32>) -> f32 {
    if (s.normal.w == 0.0) {
        return s.position.w;
    }
    let to_p = p - s.position.xyz;
    // Receivers lie outside the light (scene validation), so |p - s| > 0;
    // the floor only keeps a degenerate input finite.
    let l = max(length(to_p), 1e-30);
    let cos_s = dot(s.normal.xyz, to_p) / l;
    let ratio = length(p - settings.light.xyz) / l;
    return s.position.w * max(cos_s, 0.0) * ratio * ratio;
}

// A word's bits past the chunk's end (`used` samples in it, 1 to 32) count as set.
fn unused_bits(used: u32) -> u32 {
    return select(~((1u << used) - 1u), 0u, used >= 32u);
}

struct PixelWork {
    // Triangles tested, those that needed a test per sample, and whether
    // every chunk's mask filled before its list ended.
    pairs: u32,
    per_sample: u32,
    ended_early: bool,
};

var<private> mask: array<u32, CHUNK_WORDS>;

// ORs into `mask` (the chunk of `words` words from sample `base`) the
// samples whose segment from `o` crosses triangle (a, b, c): s beyond the
// triangle's plane from o (strictly) and inside the three planes through o
// and its edges (the projection of the sample from o falls in the triangle,
// the paper's three edge half-planes, section 3, evaluated per sample
// rather than through its lookup textures). Returns 0 when the light's
// sphere is wholly outside (no sample tested), 2 when wholly inside (every
// bit set), 1 when each sample was tested. Hits closer than the offset eps
// to o are ignored, as raytraced's ray queries' t_min does.
fn occlude(o: vec3<f32>, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, base: u32, words: u32, eps: f32) -> u32 {
    let l = settings.light.xyz;
    let r = settings.light.w;
    let n = cross(b - a, c - a);
    let n_len = length(n);
    let d_o = dot(n, o - a);
    // o in the plane (or a zero-area triangle): no segment crosses it strictly.
    if (d_o == 0.0 || n_len == 0.0) {
        return 0u;
    }
    let side = sign(d_o);
    // The sphere's reach from any plane through o or of the triangle is
    // widened by `slack`, so that rounding in these tests only ever sends a
    // pair to the per-sample test: float32 rounding of the samples and of
    // the dot products is within a few 1e-7 of |l - o| + r.
    let slack = 1e-4 * (r + length(l - o));
    // The light's centre from the triangle's plane, towards o positive.
    let light_plane = side * dot(n, l - a) / n_len;
    if (light_plane > r + slack) {
        return 0u;
    }
    let beyond_all = light_plane < -(r + slack);
    // Edge planes through o, oriented so that the triangle's inside is
    // positive: det(a - o, b - o, c - o) = -d_o (the triple product).
    let e0 = cross(a - o, b - o) * -side;
    let e1 = cross(b - o, c - o) * -side;
    let e2 = cross(c - o, a - o) * -side;
    var inside_all = beyond_all;
    var test = vec3<bool>(true, true, true);
    var es = array<vec3<f32>, 3>(e0, e1, e2);
    for (var k = 0u; k < 3u; k++) {
        let len = length(es[k]);
        // An edge through o (zero-length normal): o sees the triangle edge-on.
        if (len == 0.0) {
            return 0u;
        }
        let dist = dot(es[k], l - o) / len;
        if (dist < -(r + slack)) {
            return 0u;
        }
        let whole = dist > r + slack;
        inside_all = inside_all && whole;
        test[k] = !whole;
    }
    // Hits within eps of o can only come from a plane that close to it.
    let near = abs(d_o) < eps * n_len;
    if (inside_all && !near) {
        for (var w = 0u; w < words; w++) {
            mask[w] = FULL;
        }
        return 2u;
    }
    for (var w = 0u; w < words; w++) {
        var bits = mask[w];
        if (bits == FULL) {
            continue;
        }
        for (var k = 0u; k < 32u; k++) {
            let bit = 1u << k;
            if ((bits & bit) != 0u) {
                continue;
            }
            let s = samples[base + 32u * w + k].position.xyz;
            let x = s - o;
            var hidden = (!test.x || dot(e0, x) >= 0.0) && (!test.y || dot(e1, x) >= 0.0) && (!test.z || dot(e2, x) >= 0.0);
            if (hidden && !beyond_all) {
                hidden = side * dot(n, s - a) < 0.0;
            }
            if (hidden && near) {
                // The hit's distance from o along the segment: |x| d_o / (d_o - d_s) >= eps.
                let d_s = dot(n, s - a);
                hidden = abs(d_o) * length(x) >= eps * abs(d_o - d_s);
            }
            if (hidden) {
                bits |= bit;
            }
        }
        mask[w] = bits;
    }
    return 1u;
}

fn chunk_full(words: u32) -> bool {
    for (var w = 0u; w < words; w++) {
        if (mask[w] != FULL) {
            return false;
        }
    }
    return true;
}

// The visibility of the light from a pixel: per chunk of samples, the mask
// (samples below the horizon, or of no weight, set from the start), every
// listed triangle's hidden samples ORed in until the mask is full, then
// the weighted sum of the samples left over the weighted sum of all.
fn pixel_visibility(pixel: ScreenPixel, first: u32, count: u32, listed: bool, work: ptr<function, PixelWork>) -> f32 {
    let eps = settings.offset.x;
    let o = pixel.p + pixel.n * eps;
    let n_samples = settings.counts.x;
    var seen = 0.0;
    var total = 0.0;
    (*work).ended_early = true;
    for (var base = 0u; base < n_samples; base += 32u * CHUNK_WORDS) {
        let used = min(n_samples - base, 32u * CHUNK_WORDS);
        let words = (used + 31u) / 32u;
        for (var w = 0u; w < words; w++) {
            let in_word = min(used - 32u * w, 32u);
            var bits = unused_bits(in_word);
            for (var k = 0u; k < in_word; k++) {
                let s = samples[base + 32u * w + k];
                // Samples below the surface's horizon count as hidden (raytraced's rule).
                if (sample_weight(s, pixel.p) <= 0.0 || !(dot(pixel.n, s.position.xyz - pixel.p) > 0.0)) {
                    bits |= 1u << k;
                }
            }
            mask[w] = bits;
        }
        var k = 0u;
        var full = chunk_full(words);
        for (; k < count && !full; k++) {
            var i = first + k;
            if (listed) {
                i = tile_list[first + k];
            }
            let kind = occlude(o, corner(i, 0u), corner(i, 1u), corner(i, 2u), base, words, eps);
            if (kind != 0u) {
                if (kind == 1u) {
                    (*work).per_sample += 1u;
                }
                full = chunk_full(words);
            }
        }
        (*work).pairs += k;
        (*work).ended_early = (*work).ended_early && full && k < count;
        for (var w = 0u; w < words; w++) {
            let in_word = min(used - 32u * w, 32u);
            for (var b = 0u; b < in_word; b++) {
                let s = samples[base + 32u * w + b];
                let weight = sample_weight(s, pixel.p);
                if (weight > 0.0) {
                    total += weight;
                    if ((mask[w] & (1u << b)) == 0u) {
                        seen += weight;
                    }
                }
            }
        }
    }
    // No sample faces the pixel (only possible with very few samples): the
    // light is treated as hidden rather than dividing by zero (raytraced's rule).
    return select(0.0, clamp(seen / total, 0.0, 1.0), total > 0.0);
}

var<workgroup> wg_pairs: atomic<u32>;
var<workgroup> wg_per_sample: atomic<u32>;
var<workgroup> wg_early: atomic<u32>;

@compute @workgroup_size(8, 8)
fn masks(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let pixel = screen_pixel(id);
    if (pixel.inside) {
        var v = 0.0;
        if (pixel.geometry) {
            let tiles = tile_count();
            let tile = vec2<u32>(pixel.px) / TILE;
            let t = tile.y * settings.tiles.x + tile.x;
            var first = 0u;
            var count = settings.counts.y;
            var listed = false;
            if (settings.counts.w == 1u) {
                let start = atomicLoad(&bins[tiles + 2u * t]);
                let n = atomicLoad(&bins[tiles + 2u * t + 1u]);
                // An overflowed tile's list was not written: every triangle instead.
                if (saturating_add(start, n) <= settings.counts.z) {
                    first = start;
                    count = n;
                    listed = true;
                }
            }
            var work = PixelWork(0u, 0u, false);
            v = pixel_visibility(pixel, first, count, listed, &work);
            atomicAdd(&wg_pairs, work.pairs);
            atomicAdd(&wg_per_sample, work.per_sample);
            if (work.ended_early) {
                atomicAdd(&wg_early, 1u);
            }
        }
        textureStore(visibility_out, pixel.px, vec4<f32>(v, 0.0, 0.0, 0.0));
    }
    workgroupBarrier();
    if (li == 0u) {
        add_wide(2u, atomicLoad(&wg_pairs));
        add_wide(4u, atomicLoad(&wg_per_sample));
        atomicAdd(&counters[6], atomicLoad(&wg_early));
    }
}
