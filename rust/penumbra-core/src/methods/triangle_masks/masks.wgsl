#import shaders/receiver.wgsl
#import shaders/light_samples.wgsl

// Method `triangle_masks` (Sintorn, Eisemann & Assarsson 2008): per pixel, a
// bitmask over the light samples of `reference`'s sphere sampling; every
// triangle that can hide part of the light from the pixel ORs in the samples
// it hides (their segment from the pixel's point crosses it), and the
// visibility is the weighted share of samples left (methods/triangle_masks/
// mod.rs). Triangles reach a pixel through a bounding volume hierarchy
// (`traversal="bvh"`) or through the list of its screen tile ("tiles").
//
// Entry points, in the order they run:
// - `masks_bvh`: per pixel, a walk of the hierarchy, the masks and the
//   visibility (alone: "bvh");
// - `tile_bounds`: per 16 x 16-pixel tile, the box of its receivers' points;
// - `group_bounds`: per 8 x 8 tiles, the box of their boxes;
// - `count_bins` / `scan_bins` / `fill_bins`: per triangle, the tiles whose
//   receivers it can shadow (counted, offsets by a prefix sum, listed);
// - `masks`: per pixel, the masks and the visibility ("tiles", and "all"
//   alone: every triangle at every pixel).

struct MaskSettings {
    // The light's centre (xyz) and radius (w).
    light: vec4<f32>,
    // x: the ray origins' offset along the normal (world units, raytraced's
    // rule); y: the margin that keeps the binning conservative (world units).
    offset: vec4<f32>,
    // x: light samples; y: triangles; z: the tile lists' capacity (entries);
    // w: 1 binned, 0 every pixel takes every triangle (`masks`).
    counts: vec4<u32>,
    // x, y: tiles across and down; z, w: groups of tiles across and down.
    tiles: vec4<u32>,
    // x: invocations across the per-triangle dispatch (a row of triangles).
    dispatch: vec4<u32>,
};

// A box of receiver points; hi.w = 1 when it holds any (else it is empty).
struct Bounds {
    lo: vec4<f32>,
    hi: vec4<f32>,
};

@group(0) @binding(2) var<storage, read> settings: MaskSettings;
// The light samples, in words of 32 (mod.rs orders them so that a word's
// lie close together), then per word the ball around its samples (position:
// centre xyz, radius w).
@group(0) @binding(3) var<storage, read> samples: array<LightSample>;
// Per triangle: its bounding ball (centre xyz, radius w), then its three corners (xyz).
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

// A node of the hierarchy over the triangles (occluders.rs, depth first):
// its box; a leaf lists triangles [start, start + count) of `triangles`
// (count > 0), an inner node's left child follows it and `start` is its
// right child (count 0).
struct BvhNode {
    lo: vec3<f32>,
    start: u32,
    hi: vec3<f32>,
    count: u32,
};
@group(0) @binding(10) var<storage, read> nodes: array<BvhNode>;

const TILE: u32 = 16u;
const GROUP: u32 = 8u;
// Light samples per pass over a pixel's triangles: 40 words of the mask in
// private memory (1280 samples: n_samples = 1024 gives 1032, one pass);
// more samples take more passes.
const CHUNK_WORDS: u32 = 40u;
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
// 3. its bounding ball against the hull of the box's bounding ball B(q, rq)
//    and the light's B(l, r): the union of the balls B(P(t), R(t))
//    interpolated between them (P, R linear in t). A point whose closest
//    axis point is P(t) (t clamped to [0, 1]) lies within
//    R(t) / sqrt(1 - s^2) of it, s = |r - rq| / |l - q| (maximise
//    R(t')^2 - (t - t')^2 |l - q|^2 with R(t') <= R(t) + s |t - t'| |l - q|),
//    and always within max(rq, r).
fn can_shadow(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, ball: vec4<f32>, box: Bounds) -> bool {
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
    // The normal from the edges scaled to at most 1 (so that neither the
    // cross product nor its length overflows float32 at any scene scale).
    let e1 = b - a;
    let e2 = c - a;
    let longest = max(max(abs(e1.x), max(abs(e1.y), abs(e1.z))), max(abs(e2.x), max(abs(e2.y), abs(e2.z))));
    // A zero-area triangle hides nothing (`occlude` needs a strict crossing of its plane).
    if (longest == 0.0) {
        return false;
    }
    let n = cross(e1 / longest, e2 / longest);
    let n_len = length(n);
    if (n_len == 0.0) {
        return false;
    }
    let center = 0.5 * (box.lo.xyz + box.hi.xyz);
    let half = 0.5 * (box.hi.xyz - box.lo.xyz) + vec3<f32>(margin);
    let box_mid = dot(n, center - a);
    let box_reach = dot(abs(n), half);
    let light_mid = dot(n, l - a);
    let light_reach = r * n_len;
    let above = box_mid - box_reach > 0.0 && light_mid - light_reach > 0.0;
    let below = box_mid + box_reach < 0.0 && light_mid + light_reach < 0.0;
    if (above || below) {
        return false;
    }
    let rq = length(half);
    let axis = l - center;
    let axis_len = length(axis);
    // The closest point of the axis segment to the ball's centre (t = 0 for a zero-length axis).
    let t = select(0.0, clamp(dot(ball.xyz - center, axis) / (axis_len * axis_len), 0.0, 1.0), axis_len > 0.0);
    let d = ball.xyz - (center + axis * t);
    let s = select(1.0, abs(r - rq) / axis_len, axis_len > 0.0);
    var hull = max(rq, r);
    if (s < 0.99) {
        hull = min(hull, mix(rq, r, t) / sqrt(1.0 - s * s));
    }
    let reach = hull + ball.w + margin;
    return dot(d, d) <= reach * reach;
}

fn corner(i: u32, k: u32) -> vec3<f32> {
    return triangles[4u * i + 1u + k].xyz;
}

// Per triangle (mode 0: count, 1: fill): the tiles it can shadow, through
// the groups (a group's box holds its tiles', so a group the triangle cannot
// shadow has no tile it can).
fn bin_triangle(i: u32, fill: bool) {
    let a = corner(i, 0u);
    let b = corner(i, 1u);
    let c = corner(i, 2u);
    let ball = triangles[4u * i];
    let tiles = tile_count();
    for (var gy = 0u; gy < settings.tiles.w; gy++) {
        for (var gx = 0u; gx < settings.tiles.z; gx++) {
            let g = bounds[tiles + gy * settings.tiles.z + gx];
            if (g.hi.w == 0.0 || !can_shadow(a, b, c, ball, g)) {
                continue;
            }
            let last = min(vec2<u32>(gx + 1u, gy + 1u) * GROUP, settings.tiles.xy);
            for (var y = gy * GROUP; y < last.y; y++) {
                for (var x = gx * GROUP; x < last.x; x++) {
                    let t = y * settings.tiles.x + x;
                    let box = bounds[t];
                    if (box.hi.w == 0.0 || !can_shadow(a, b, c, ball, box)) {
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

// A word's bits past the chunk's end (`used` samples in it, 1 to 32) count as set.
fn unused_bits(used: u32) -> u32 {
    return select(~((1u << used) - 1u), 0u, used >= 32u);
}

struct PixelWork {
    // Triangles tested, those that needed a test per sample, and whether
    // every chunk's mask filled before its list ended.
    pairs: u32,
    per_sample: u32,
    past_cone: u32,
    ended_early: bool,
};

// The pixel's segment origin and the cone from it around the light's
// sphere: unit axis, distance to the centre, the half-angle's sine and
// cosine; and the slack that widens every whole-sphere or whole-word test so
// that rounding only ever sends a pair or a word to the test per sample
// (float32 rounding of the samples, balls and dot products is within a few
// 1e-7 of |l - o| + r; the slack is 1e-4 of it).
struct Cone {
    o: vec3<f32>,
    axis: vec3<f32>,
    distance: f32,
    sin_a: f32,
    cos_a: f32,
    slack: f32,
    eps: f32,
};

fn pixel_cone(o: vec3<f32>, eps: f32) -> Cone {
    let u = settings.light.xyz - o;
    // Receivers lie outside the light (scene validation): the distance is
    // positive and above the radius; the floor keeps a degenerate input finite.
    let distance = max(length(u), 1e-30);
    let sin_a = min(settings.light.w / distance, 1.0);
    return Cone(o, u / distance, distance, sin_a, sqrt(max(1.0 - sin_a * sin_a, 0.0)), 1e-4 * (settings.light.w + distance), eps);
}

var<private> mask: array<u32, CHUNK_WORDS>;
// Words of the chunk's mask not yet full.
var<private> open_words: u32;

fn has_bit(items: vec2<u32>, w: u32) -> bool {
    return ((select(items.x, items.y, w >= 32u) >> (w & 31u)) & 1u) != 0u;
}

fn fill_word(w: u32) {
    if (mask[w] != FULL) {
        open_words -= 1u;
        mask[w] = FULL;
    }
}

// The normal of the plane through o and the edge from corner p to corner q
// (world wp, wq; relative to o in units of |l - o| p, q): cross(p, q), as
// cross(p, (wq - wp) k) from the corner nearer in lexicographic order. The
// edge's direction then comes from the corners' own difference, not from
// that of two rounded offsets from o, which cancels on a short edge far
// from o (its plane's normal off by up to 1e-7 |p| / |q - p|); and the two
// triangles sharing an edge compute it from the same corner, so their
// planes are still exact negatives (no sample leaks between them).
fn edge_plane(wp: vec3<f32>, wq: vec3<f32>, p: vec3<f32>, q: vec3<f32>, k: f32) -> vec3<f32> {
    let p_first = wp.x < wq.x || (wp.x == wq.x && (wp.y < wq.y || (wp.y == wq.y && wp.z <= wq.z)));
    if (p_first) {
        return cross(p, (wq - wp) * k);
    }
    return -cross(q, (wp - wq) * k);
}

// ORs into `mask` (the chunk of `words` words from word `first_word`) the
// samples whose segment from the cone's origin o crosses triangle `i`: s
// beyond the triangle's plane from o (strictly) and inside the three planes
// through o and its edges, where its projection from o falls in the
// triangle: the paper's three edge half-planes (section 3), evaluated per
// sample rather than through its lookup textures. Culled in order: the
// triangle's bounding ball against the cone from o around the light; the
// light's sphere against the four planes (wholly outside one: no sample;
// wholly inside all: every bit); then per word, its samples' ball the same
// way, and the samples of the words a plane cuts one by one. Hits closer
// than eps to o are ignored, as raytraced's ray queries' t_min does.
// Only the words of `chosen_words` (bit w of x, then y, for word w of the
// chunk) and their samples of `chosen_bits` are tested: the hierarchy's walk
// leaves out those whose segments miss the triangle's box (their test would
// set nothing; a whole light hidden still sets every word).
// Returns 0 (culled by the cone), 1 (culled by a plane of the light),
// 2 (tested per word or sample) or 3 (every bit set).
fn occlude(cone: Cone, i: u32, first_word: u32, words: u32, chosen_words: vec2<u32>, chosen_bits: u32) -> u32 {
    let o = cone.o;
    // The ball (m, rho) meets the cone only if its centre is within rho of
    // it: perp cos(a) - along sin(a) is at most m's distance to the cone
    // (to its apex behind o), and the segments end within r beyond l.
    let ball = triangles[4u * i];
    let v = ball.xyz - o;
    let along = dot(v, cone.axis);
    // |v x axis|, not sqrt(|v|^2 - along^2): that difference cancels near
    // the axis, and its square root turns 1e-7 of rounding into 3e-4.
    let perp = length(cross(v, cone.axis));
    let rho = ball.w + cone.slack;
    if (perp * cone.cos_a - along * cone.sin_a > rho || along < -rho || along > cone.distance + settings.light.w + rho) {
        return 0u;
    }
    // From here on, coordinates are relative to o in units of |l - o|: every
    // value is then of the order of 1, so no cross product or length
    // overflows or underflows float32 at any scene scale (1e10 squared
    // twice is past its range). o is the origin; the light's centre is the
    // cone's axis.
    let k = 1.0 / cone.distance;
    let wa = triangles[4u * i + 1u].xyz;
    let wb = triangles[4u * i + 2u].xyz;
    let wc = triangles[4u * i + 3u].xyz;
    let a = (wa - o) * k;
    let b = (wb - o) * k;
    let c = (wc - o) * k;
    let l = cone.axis;
    let r = settings.light.w * k;
    let slack = cone.slack * k;
    let eps = cone.eps * k;
    let n = cross(b - a, c - a);
    let n_len = length(n);
    let d_o = -dot(n, a);
    // o in the plane (or a zero-area triangle): no segment crosses it strictly.
    if (d_o == 0.0 || n_len == 0.0) {
        return 1u;
    }
    let side = sign(d_o);
    // The unit normal towards o.
    let h = n * (side / n_len);
    let light_plane = dot(h, l - a);
    if (light_plane > r + slack) {
        return 1u;
    }
    // Edge planes through o, oriented so that the triangle's inside is
    // positive (det(a - o, b - o, c - o) = -d_o, the triple product), unit.
    var e = array<vec3<f32>, 3>(edge_plane(wa, wb, a, b, k) * -side, edge_plane(wb, wc, b, c, k) * -side, edge_plane(wc, wa, c, a, k) * -side);
    var inside_all = light_plane < -(r + slack);
    for (var q = 0u; q < 3u; q++) {
        let len = length(e[q]);
        // An edge through o (zero-length normal): o sees the triangle edge-on.
        if (len == 0.0) {
            return 1u;
        }
        e[q] = e[q] / len;
        let dist = dot(e[q], l);
        if (dist < -(r + slack)) {
            return 1u;
        }
        inside_all = inside_all && dist > r + slack;
    }
    // Hits within eps of o can only come from a plane that close to it.
    let near = abs(d_o) < eps * n_len;
    if (inside_all && !near) {
        for (var w = 0u; w < words; w++) {
            fill_word(w);
        }
        return 3u;
    }
    let e0 = e[0];
    let e1 = e[1];
    let e2 = e[2];
    let n_samples = settings.counts.x;
    for (var w = 0u; w < words; w++) {
        var bits = mask[w];
        if (bits == FULL || !has_bit(chosen_words, w)) {
            continue;
        }
        let word = samples[n_samples + first_word + w].position;
        let center = (word.xyz - o) * k;
        let reach = word.w * k + slack;
        let de = vec3<f32>(dot(e0, center), dot(e1, center), dot(e2, center));
        let dp = dot(h, center - a);
        if (any(de < vec3<f32>(-reach)) || dp > reach) {
            continue;
        }
        // The planes that cut the word's ball; the rest hold it whole.
        let cut = de <= vec3<f32>(reach);
        let cut_plane = dp >= -reach;
        if (!any(cut) && !cut_plane && !near) {
            fill_word(w);
            continue;
        }
        let untested = bits | ~chosen_bits;
        for (var j = 0u; j < 32u; j++) {
            let bit = 1u << j;
            if ((untested & bit) != 0u) {
                continue;
            }
            let x = (samples[32u * (first_word + w) + j].position.xyz - o) * k;
            var hidden = (!cut.x || dot(e0, x) >= 0.0) && (!cut.y || dot(e1, x) >= 0.0) && (!cut.z || dot(e2, x) >= 0.0);
            let d_s = dot(h, x - a);
            if (hidden && cut_plane) {
                hidden = d_s < 0.0;
            }
            if (hidden && near) {
                // The hit's distance from o along the segment, |x| d_o / (d_o - d_s)
                // with d_o = dot(h, o - a) > 0 > d_s, at least eps.
                let h_o = -dot(h, a);
                hidden = length(x) * h_o >= eps * (h_o - d_s);
            }
            if (hidden) {
                bits |= bit;
            }
        }
        if (bits == FULL) {
            open_words -= 1u;
        }
        mask[w] = bits;
    }
    return 2u;
}

// Chunk setup: the pixel's mask of the chunk of `words` words from word
// `first_word`, samples below the horizon or of no weight set from the
// start (raytraced's rule); `open_words` counts the words not full.
fn start_chunk(pixel: ScreenPixel, first_word: u32, words: u32) {
    let n_samples = settings.counts.x;
    open_words = 0u;
    for (var w = 0u; w < words; w++) {
        let base = 32u * (first_word + w);
        let in_word = min(n_samples - base, 32u);
        var bits = unused_bits(in_word);
        for (var k = 0u; k < in_word; k++) {
            let s = samples[base + k];
            // No weight (the sphere's far side: sample_weight's cos_s <= 0,
            // without its lengths), or below the horizon (raytraced's rule).
            let facing = s.normal.w == 0.0 || dot(s.normal.xyz, pixel.p - s.position.xyz) > 0.0;
            if (!facing || !(dot(pixel.n, s.position.xyz - pixel.p) > 0.0)) {
                bits |= 1u << k;
            }
        }
        mask[w] = bits;
        if (bits != FULL) {
            open_words += 1u;
        }
    }
}

// Chunk end: the weights of the chunk's samples left (x) and of all (y).
fn end_chunk(pixel: ScreenPixel, first_word: u32, words: u32) -> vec2<f32> {
    let n_samples = settings.counts.x;
    var sums = vec2<f32>(0.0, 0.0);
    for (var w = 0u; w < words; w++) {
        let base = 32u * (first_word + w);
        let in_word = min(n_samples - base, 32u);
        for (var b = 0u; b < in_word; b++) {
            let weight = sample_weight(samples[base + b], pixel.p, settings.light.xyz);
            if (weight > 0.0) {
                sums += vec2<f32>(select(0.0, weight, (mask[w] & (1u << b)) == 0u), weight);
            }
        }
    }
    return sums;
}

var<workgroup> wg_pairs: atomic<u32>;
var<workgroup> wg_per_sample: atomic<u32>;
var<workgroup> wg_early: atomic<u32>;
var<workgroup> wg_past_cone: atomic<u32>;
// Nodes of the hierarchy entered (`masks_bvh`; none in `masks`).
var<workgroup> wg_entered: atomic<u32>;
// The tile's list: first entry, length, whether listed (1) or every triangle (0).
var<workgroup> wg_list: vec3<u32>;
// Pixels of the workgroup whose chunk's mask is not yet full.
var<workgroup> wg_open: atomic<u32>;
// A batch of the list: the triangles and, per triangle, the bits of the
// 4 x 4-pixel quarters whose receivers it can shadow.
var<workgroup> wg_batch: array<u32, 64>;
var<workgroup> wg_quarters: array<u32, 64>;
var<workgroup> wg_quarter_box: array<Bounds, 4>;

// One workgroup per 8 x 8 pixels (a quarter of a tile). The tile's list is
// culled again, 64 triangles at a time, against the receiver boxes of the
// workgroup's four 4 x 4-pixel quarters (`can_shadow`, one invocation per
// triangle); every pixel then tests the triangles its quarter keeps, until
// its mask is full. Per chunk of samples: the mask, the batches, the sums.
@compute @workgroup_size(8, 8)
fn masks(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let pixel = screen_pixel(id);
    let receiver = pixel.inside && pixel.geometry;
    let quarter = lid.x / 4u + 2u * (lid.y / 4u);
    // The quarters' receiver boxes: each pixel's point, then 4 serial reductions.
    wg_lo[li] = select(vec4<f32>(BIG, BIG, BIG, 0.0), vec4<f32>(pixel.p, 0.0), receiver);
    wg_hi[li] = select(vec4<f32>(-BIG, -BIG, -BIG, 0.0), vec4<f32>(pixel.p, 1.0), receiver);
    if (li == 0u) {
        let tiles = tile_count();
        let tile = id.xy / TILE;
        let t = tile.y * settings.tiles.x + tile.x;
        var list = vec3<u32>(0u, settings.counts.y, 0u);
        if (settings.counts.w == 1u && t < tiles) {
            let start = atomicLoad(&bins[tiles + 2u * t]);
            let n = atomicLoad(&bins[tiles + 2u * t + 1u]);
            // An overflowed tile's list was not written: every triangle instead.
            if (saturating_add(start, n) <= settings.counts.z) {
                list = vec3<u32>(start, n, 1u);
            }
        }
        wg_list = list;
    }
    workgroupBarrier();
    if (li < 4u) {
        var lo = vec4<f32>(BIG, BIG, BIG, 0.0);
        var hi = vec4<f32>(-BIG, -BIG, -BIG, 0.0);
        let corner_px = vec2<u32>(li % 2u, li / 2u) * 4u;
        for (var k = 0u; k < 16u; k++) {
            let j = (corner_px.y + k / 4u) * 8u + corner_px.x + k % 4u;
            lo = min(lo, wg_lo[j]);
            hi = max(hi, wg_hi[j]);
        }
        wg_quarter_box[li] = Bounds(lo, hi);
    }
    let list = workgroupUniformLoad(&wg_list);
    let eps = settings.offset.x;
    let cone = pixel_cone(pixel.p + pixel.n * eps, eps);
    let n_words = (settings.counts.x + 31u) / 32u;
    var work = PixelWork(0u, 0u, 0u, true);
    var sums = vec2<f32>(0.0, 0.0);
    for (var first_word = 0u; first_word < n_words; first_word += CHUNK_WORDS) {
        let words = min(n_words - first_word, CHUNK_WORDS);
        open_words = 0u;
        if (receiver) {
            start_chunk(pixel, first_word, words);
        }
        var tested = 0u;
        for (var batch = 0u; batch < list.y; batch += 64u) {
            // Every pixel's mask full: the rest of the list hides nothing new.
            atomicStore(&wg_open, 0u);
            workgroupBarrier();
            if (open_words > 0u) {
                atomicAdd(&wg_open, 1u);
            }
            let j = batch + li;
            var bits = 0u;
            var i = 0u;
            if (j < list.y) {
                i = list.x + j;
                if (list.z == 1u) {
                    i = tile_list[list.x + j];
                }
                let a = corner(i, 0u);
                let b = corner(i, 1u);
                let c = corner(i, 2u);
                let ball = triangles[4u * i];
                for (var q = 0u; q < 4u; q++) {
                    let box = wg_quarter_box[q];
                    if (box.hi.w > 0.0 && can_shadow(a, b, c, ball, box)) {
                        bits |= 1u << q;
                    }
                }
            }
            wg_batch[li] = i;
            wg_quarters[li] = bits;
            if (workgroupUniformLoad(&wg_open) == 0u) {
                break;
            }
            let in_batch = min(list.y - batch, 64u);
            for (var e = 0u; e < in_batch && open_words > 0u; e++) {
                if ((wg_quarters[e] & (1u << quarter)) == 0u) {
                    continue;
                }
                tested += 1u;
                let kind = occlude(cone, wg_batch[e], first_word, words, vec2<u32>(FULL, FULL), FULL);
                work.past_cone += u32(kind != 0u);
                work.per_sample += u32(kind == 2u);
            }
            workgroupBarrier();
        }
        work.pairs += tested;
        // Ended early: the mask filled with triangles of its quarter's list left.
        work.ended_early = work.ended_early && open_words == 0u;
        if (receiver) {
            sums += end_chunk(pixel, first_word, words);
        }
    }
    if (receiver) {
        store_pixel(pixel, sums, work, list.y > 0u);
    } else if (pixel.inside) {
        textureStore(visibility_out, pixel.px, vec4<f32>(0.0, 0.0, 0.0, 0.0));
    }
    workgroupBarrier();
    if (li == 0u) {
        add_counters();
    }
}

// A receiver's visibility from its sums, and its work into the workgroup's
// counters (`ended_early` counts only where some triangle was there to test).
fn store_pixel(pixel: ScreenPixel, sums: vec2<f32>, work: PixelWork, any_triangle: bool) {
    // No sample faces the pixel (only possible with very few samples): the
    // light is treated as hidden rather than dividing by zero (raytraced's rule).
    let v = select(0.0, clamp(sums.x / sums.y, 0.0, 1.0), sums.y > 0.0);
    textureStore(visibility_out, pixel.px, vec4<f32>(v, 0.0, 0.0, 0.0));
    atomicAdd(&wg_pairs, work.pairs);
    atomicAdd(&wg_per_sample, work.per_sample);
    atomicAdd(&wg_past_cone, work.past_cone);
    if (work.ended_early && any_triangle) {
        atomicAdd(&wg_early, 1u);
    }
}

// The workgroup's counters into the totals (one invocation, after a barrier).
fn add_counters() {
    add_wide(2u, atomicLoad(&wg_pairs));
    add_wide(4u, atomicLoad(&wg_per_sample));
    atomicAdd(&counters[6], atomicLoad(&wg_early));
    add_wide(8u, atomicLoad(&wg_past_cone));
    add_wide(10u, atomicLoad(&wg_entered));
}

// The walk of the hierarchy (`masks_bvh`), one word of samples at a time:
// a node is entered only with the word's samples still open whose segments
// from the pixel's point can meet its box, and its children test only
// those, so the work per pixel follows the segments still open, as a ray
// tracer's does (32 at once), while the leaves' triangles set bits as in
// `masks` (`occlude`). The mask is the same bit for bit: a sample is left
// out only where its segment misses the box widened by the slack, so its
// test could set nothing.

// The deepest hierarchy mod.rs uploads (it refuses deeper ones; occluders.rs
// bounds the depth at 24 + log2(triangles / 4) + 2).
const STACK: u32 = 48u;

// Per sample j of the word walked: 1 / (s_j - o) per axis, in units of
// |l - o| (components under 1e-20 taken as 1e-20: the box is widened by the
// slack, so a segment that moves less than that along an axis is inside the
// slab exactly where its origin is, at every t).
var<private> segment_inv: array<vec3<f32>, 32>;

// The walked word's ball seen from o: per axis 1 / (c - rho) and
// 1 / (c + rho) (c its centre, rho its radius, in units of |l - o|).
var<private> ball_inv_minus: vec3<f32>;
var<private> ball_inv_plus: vec3<f32>;

fn start_walk(cone: Cone, word: u32) {
    let k = 1.0 / cone.distance;
    let ball = samples[settings.counts.x + word].position;
    let c = (ball.xyz - cone.o) * k;
    let minus = c - vec3<f32>(ball.w * k);
    let plus = c + vec3<f32>(ball.w * k);
    ball_inv_minus = 1.0 / select(minus, vec3<f32>(1e-20), abs(minus) < vec3<f32>(1e-20));
    ball_inv_plus = 1.0 / select(plus, vec3<f32>(1e-20), abs(plus) < vec3<f32>(1e-20));
    let base = 32u * word;
    let in_word = min(settings.counts.x - base, 32u);
    for (var j = 0u; j < in_word; j++) {
        let x = (samples[base + j].position.xyz - cone.o) * k;
        let tiny = abs(x) < vec3<f32>(1e-20);
        segment_inv[j] = 1.0 / select(x, vec3<f32>(1e-20), tiny);
    }
}

// Of the samples `items` of the word walked, those whose segments from o
// can meet node n's box: the slab test over t in [0, 1], against the box
// widened by the slack, relative to o in units of |l - o| (occlude's frame).
fn node_items(cone: Cone, n: u32, items: u32) -> u32 {
    let node = nodes[n];
    let k = 1.0 / cone.distance;
    let m = vec3<f32>(cone.slack * k);
    let lo = (node.lo - cone.o) * k - m;
    let hi = (node.hi - cone.o) * k + m;
    // First the whole word: a segment from o to a point within rho of c
    // meets the box only if, per axis, t (c - rho) <= hi and
    // t (c + rho) >= lo for some t in [0, 1].
    let qa = hi * ball_inv_minus;
    let qb = lo * ball_inv_plus;
    let big = vec3<f32>(3e38);
    let lower = max(select(-big, qa, ball_inv_minus < vec3<f32>(0.0)), select(-big, qb, ball_inv_plus > vec3<f32>(0.0)));
    let upper = min(select(big, qa, ball_inv_minus > vec3<f32>(0.0)), select(big, qb, ball_inv_plus < vec3<f32>(0.0)));
    if (max(max(max(lower.x, lower.y), lower.z), 0.0) > min(min(min(upper.x, upper.y), upper.z), 1.0)) {
        return 0u;
    }
    var hit = 0u;
    var rest = items;
    while (rest != 0u) {
        let j = firstTrailingBit(rest);
        rest &= rest - 1u;
        let a = lo * segment_inv[j];
        let b = hi * segment_inv[j];
        let near = max(max(max(min(a.x, b.x), min(a.y, b.y)), min(a.z, b.z)), 0.0);
        let far = min(min(min(max(a.x, b.x), max(a.y, b.y)), max(a.z, b.z)), 1.0);
        if (near <= far) {
            hit |= 1u << j;
        }
    }
    return hit;
}

// Walks the hierarchy for word w of the chunk of `words` words from
// `first_word`; adds its work to `work` (pairs, past the cone, per sample)
// and returns the nodes entered.
fn walk(cone: Cone, first_word: u32, words: u32, w: u32, work: ptr<function, PixelWork>) -> u32 {
    start_walk(cone, first_word + w);
    var stack: array<vec2<u32>, STACK>;
    var top = 0u;
    var entered = 0u;
    let root = node_items(cone, 0u, ~mask[w]);
    if (root != 0u) {
        stack[0] = vec2<u32>(0u, root);
        top = 1u;
    }
    let chosen_words = select(vec2<u32>(0u, 1u << (w - 32u)), vec2<u32>(1u << w, 0u), w < 32u);
    while (top > 0u) {
        top -= 1u;
        let entry = stack[top];
        // Samples set since the node was pushed need no more.
        let items = entry.y & ~mask[w];
        if (items == 0u) {
            continue;
        }
        entered += 1u;
        let node = nodes[entry.x];
        if (node.count > 0u) {
            for (var i = node.start; i < node.start + node.count && mask[w] != FULL; i++) {
                let kind = occlude(cone, i, first_word, words, chosen_words, items);
                (*work).pairs += 1u;
                (*work).past_cone += u32(kind != 0u);
                (*work).per_sample += u32(kind == 2u);
            }
            continue;
        }
        let right = node_items(cone, node.start, items);
        let left = node_items(cone, entry.x + 1u, items);
        // The child whose box's centre is nearer o is walked first: of the
        // orders tried while building this (left first, nearer first,
        // farther first) it entered the fewest nodes on generated scenes.
        let dl = nodes[entry.x + 1u].lo + nodes[entry.x + 1u].hi - 2.0 * cone.o;
        let dr = nodes[node.start].lo + nodes[node.start].hi - 2.0 * cone.o;
        let left_first = dot(dl, dl) <= dot(dr, dr);
        let later = select(vec2<u32>(entry.x + 1u, left), vec2<u32>(node.start, right), left_first);
        let sooner = select(vec2<u32>(node.start, right), vec2<u32>(entry.x + 1u, left), left_first);
        if (later.y != 0u && top < STACK) {
            stack[top] = later;
            top += 1u;
        }
        if (sooner.y != 0u && top < STACK) {
            stack[top] = sooner;
            top += 1u;
        }
    }
    return entered;
}

// One invocation per pixel: per chunk of samples, the mask, a walk per word, the sums.
@compute @workgroup_size(8, 8)
fn masks_bvh(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let pixel = screen_pixel(id);
    let receiver = pixel.inside && pixel.geometry;
    var work = PixelWork(0u, 0u, 0u, true);
    var entered = 0u;
    if (receiver) {
        let eps = settings.offset.x;
        let cone = pixel_cone(pixel.p + pixel.n * eps, eps);
        let n_words = (settings.counts.x + 31u) / 32u;
        var sums = vec2<f32>(0.0, 0.0);
        for (var first_word = 0u; first_word < n_words; first_word += CHUNK_WORDS) {
            let words = min(n_words - first_word, CHUNK_WORDS);
            start_chunk(pixel, first_word, words);
            for (var w = 0u; w < words && settings.counts.y > 0u; w++) {
                if (mask[w] != FULL) {
                    entered += walk(cone, first_word, words, w, &work);
                }
            }
            work.ended_early = work.ended_early && open_words == 0u;
            sums += end_chunk(pixel, first_word, words);
        }
        store_pixel(pixel, sums, work, settings.counts.y > 0u);
        atomicAdd(&wg_entered, entered);
    } else if (pixel.inside) {
        textureStore(visibility_out, pixel.px, vec4<f32>(0.0, 0.0, 0.0, 0.0));
    }
    workgroupBarrier();
    if (li == 0u) {
        add_counters();
    }
}
