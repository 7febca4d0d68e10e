#import shaders/receiver.wgsl
#import passes/pcf_taps.wgsl

// Method `backprojection` (Guennebaud, Barthe and Paulin 2007), shared by
// its classification and visibility passes: the receiver and the light disk
// it sees, reads of the hierarchical shadow map (section 3), the kernel of
// Eq. 1, the contour edges of 4.1 and the radial area integration of 4.2.
//
// Conventions. Map coordinates are texels of level 0 in the receiver's layer
// (cube faces: coordinates beyond the face read the neighbour face through
// `map_wrap`). A sample of level l is the level-l texel, at its centre, with
// its minimum depth (5.1). The light is the disk the receiver sees: the
// section of the sphere's tangent cone from the receiver through the light's
// centre, perpendicular to the cone's axis, of radius rho = r d / sqrt(d^2 -
// r^2); a point of it is given in units of rho, in a 2D frame whose axes are
// the map's axes as seen from the receiver (so orientations in the map and
// on the disk agree).

struct Backprojection {
    // 4.1: contour offset in [-1, 1].
    t: f32,
    // 5.1: kernel threshold of Eq. 2 and 3, and the blending width beta.
    t_k: f32,
    beta: f32,
    // 5.2: s_min of Eq. 6, pixels.
    s_min: f32,
    // Camera eye xyz; w: eta of Eq. 5, pixels per world unit at unit view depth.
    eye: vec4<f32>,
    // Bit 0: light-space multi-resolution (5.1); bit 1: screen-space (5.2);
    // bit 2: coarse contours' crossings refined on level 0; bit 3: write the
    // widened discontinuity marks (classify.wgsl, intermediates only).
    flags: u32,
    // Levels of the hierarchy, level 0 (the map) included.
    levels: u32,
    // Largest kernel side, in samples of the level it is taken at.
    max_kernel: f32,
    // `descent`: how many times the kernel cap a kernel may span where a
    // pixel goes finer than the cap allows: a steep receiver's level
    // (classify.wgsl) no finer than that, and the kernel a centre-test
    // fallback walks (visibility.wgsl) cut to that.
    descent: f32,
    // Per level l: its first texel in `hierarchy`, and its side in texels.
    level_offset: array<vec4<u32>, 4>,
    level_size: array<vec4<u32>, 4>,
};

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
// Levels 1 and up of the hierarchy: x minimum, y maximum depth.
@group(0) @binding(3) var<storage, read> hierarchy: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read> shadow_params: ShadowTest;
@group(0) @binding(5) var<storage, read> bp_params: Backprojection;
// Per-invocation copies of the parameters (see methods/pcss/visibility.wgsl).
var<private> shadow: ShadowTest;
var<private> bp: Backprojection;

const LIGHT_ADAPTIVE: u32 = 1u;
const SCREEN_ADAPTIVE: u32 = 2u;
const REFINED_CONTOUR: u32 = 4u;
// Bisection steps of a refined crossing (see `side_crossing`).
const REFINE_STEPS: u32 = 3u;
// Eq. 1 gives the kernel to first order in the angle between the light's
// rays; this covers the second-order rest on the widest cube-face kernels.
const KERNEL_SLACK: f32 = 1.05;
// A sample stands for its level's whole texel: kernels are read this many
// samples wider. (Edges lie inside their block's cell, and every cell
// meeting the kernel is read.)
const KERNEL_MARGIN: f32 = 0.5;
// Homogeneous weight below which a backprojected point is clipped: the part
// of an edge no nearer the light than the receiver is (see `edge_term`).
const MIN_W: f32 = 1e-5;

fn load_params() {
    shadow = shadow_params;
    bp = bp_params;
}

struct BpReceiver {
    // The surface point and its normal: the backprojection's centre, the horizon.
    p: vec3<f32>,
    n: vec3<f32>,
    // The layer of p, its map coordinates p' and light depth z_p there, and
    // the depth bias (world units, passes/pcf_taps.wgsl).
    layer: i32,
    coords: vec2<f32>,
    depth: f32,
    bias: f32,
    // 1 / depth, along the ray through map coordinates c, of the plane
    // through the biased lookup point (pcf_receiver's origin) with normal n:
    // inv0 + dot(inv_grad, c - coords).
    inv0: f32,
    inv_grad: vec2<f32>,
    // The light's centre on the normal's side of that plane; otherwise the
    // centre has set below the receiver's horizon.
    facing: bool,
    // The light disk: distance d to the centre, the unit axis towards it,
    // the radius rho, and (`with_disk_frame`) dot products of the light rays through p' and its
    // neighbours one texel along x and y with (e1, e2, axis): a ray through
    // c is ray0 + ray_x (c - p').x + ray_y (c - p').y (light_ray is affine in c).
    d: f32,
    axis: vec3<f32>,
    rho: f32,
    proj0: vec3<f32>,
    proj_x: vec3<f32>,
    proj_y: vec3<f32>,
    // The horizon on the unit disk: the visible side is dot(hm, u) >= hd
    // (hm from `with_disk_frame`); `cut` when it crosses the disk.
    hm: vec2<f32>,
    hd: f32,
    cut: bool,
    // 1 / cos of the angle between p's light ray and the layer's axis, and
    // the world size of a texel at unit depth.
    sec: f32,
    texel1: f32,
    // The light ray through p' (unit depth along the layer's axis) and its
    // change per texel along x and y.
    ray0: vec3<f32>,
    ray_x: vec3<f32>,
    ray_y: vec3<f32>,
    // The part along the axis of those rays, over d: a point at depth z on
    // the ray through p' + dc lies 1 + z (toward . (1, dc)) of the way from
    // the light's plane to the receiver (the w of `disk_point`).
    toward: vec3<f32>,
};

fn bp_receiver(p: vec3<f32>, n: vec3<f32>) -> BpReceiver {
    var r: BpReceiver;
    let ls = shadow.light_space;
    let l = shadow.center.xyz;
    let radius = shadow.center.w;
    // The contour and the centre test work around the map point of p itself,
    // the centre of the backprojection: the centre test must say whether the
    // ray from p to the light's centre meets the contour the edges are
    // integrated from (at the biased point's coordinates, one texel off, it
    // contradicts them along every hard-shadow boundary). The bias only moves
    // the plane occluders are tested against.
    let pr = pcf_receiver(shadow, p, n);
    let m = light_map_point(ls, p);
    r.p = p;
    r.n = n;
    r.layer = m.layer;
    r.coords = m.coords;
    r.depth = light_view_depth(ls, p);
    r.bias = pr.bias;
    let ray0 = light_ray(ls, r.layer, r.coords);
    let ray_x = light_ray(ls, r.layer, r.coords + vec2<f32>(1.0, 0.0)) - ray0;
    let ray_y = light_ray(ls, r.layer, r.coords + vec2<f32>(0.0, 1.0)) - ray0;
    // The plane n . (X - o) = 0 meets the ray X = l + z ray(c) at
    // z = k / (n . ray(c)), k = n . (o - l): so 1 / z is affine in c.
    // k < 0 when the centre lies on the normal's side. |k| is kept away
    // from 0 (a plane through the light's centre: every ray runs in it).
    let k = dot(n, pr.origin - l);
    r.facing = k < 0.0;
    let kk = select(max(k, 1e-30), min(k, -1e-30), r.facing);
    r.inv0 = clamp(dot(n, ray0) / kk, -1e30, 1e30);
    r.inv_grad = clamp(vec2<f32>(dot(n, ray_x), dot(n, ray_y)) / kk, vec2<f32>(-1e30), vec2<f32>(1e30));

    let to_light = l - p;
    // Surfaces lie outside the light (scene validation): d > radius >= 0.
    r.d = max(length(to_light), 1e-30);
    r.axis = to_light / r.d;
    r.rho = radius * r.d / sqrt(max(r.d * r.d - radius * radius, 1e-12 * r.d * r.d));
    // Horizon: X = l + rho u (u on the disk's plane, in units of rho) is above
    // the surface's plane when n . (l - p) + rho n . u >= 0; n's part across
    // the axis has length sin(theta), so the line lies at hd (in units of
    // rho) from the centre along that part, away from the visible side.
    let cos_theta = dot(n, r.axis);
    let across = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    r.hd = -2.0;
    if (across > 1e-7 && r.rho > 0.0) {
        r.hd = clamp(-r.d * cos_theta / (r.rho * across), -2.0, 2.0);
    } else if (cos_theta < 0.0) {
        r.hd = 2.0;
    }
    // A zero normal (a degenerate face): no light, as the shadow test gives it.
    if (dot(n, n) < 0.25) {
        r.hd = 2.0;
    }
    r.cut = r.hd > -1.0;
    r.sec = length(ray0);
    r.texel1 = light_texel_size(ls, 1.0);
    r.ray0 = ray0;
    r.toward = vec3<f32>(dot(ray0, r.axis), dot(ray_x, r.axis), dot(ray_y, r.axis)) / r.d;
    r.ray_x = ray_x;
    r.ray_y = ray_y;
    return r;
}

// The disk's 2D frame, for the visibility pass: axes e1, e2 the images of
// the map's x and y axes as seen from the receiver (e1 along the part of
// ray_x across the axis, e2 the part of ray_y across both; ray_x and ray_y
// lie in the layer's image plane, which no light ray lies in, so neither is
// parallel to the axis), the rays' coordinates in it, and the horizon's
// direction there.
fn with_disk_frame(r_in: BpReceiver) -> BpReceiver {
    var r = r_in;
    let e1 = normalize(r.ray_x - dot(r.ray_x, r.axis) * r.axis);
    let y_across = r.ray_y - dot(r.ray_y, r.axis) * r.axis;
    let e2 = normalize(y_across - dot(y_across, e1) * e1);
    r.proj0 = vec3<f32>(dot(r.ray0, e1), dot(r.ray0, e2), dot(r.ray0, r.axis));
    r.proj_x = vec3<f32>(dot(r.ray_x, e1), dot(r.ray_x, e2), dot(r.ray_x, r.axis));
    r.proj_y = vec3<f32>(dot(r.ray_y, e1), dot(r.ray_y, e2), dot(r.ray_y, r.axis));
    let tilt = vec2<f32>(dot(r.n, e1), dot(r.n, e2));
    let len = length(tilt);
    r.hm = select(vec2<f32>(1.0, 0.0), tilt / max(len, 1e-30), len > 1e-7);
    return r;
}

// Whether a sample of depth z (along the receiver layer's axis) on the ray
// through map coordinates c, standing for a footprint `half` texels either
// side of c, can hide part of the light from the receiver: it is nearer the
// light than the receiver and lies on the light's side of the receiver's
// plane (through the biased lookup point; at coarse levels over the whole
// footprint, so that the receiver's own surface, whose minimum depth a
// coarse sample keeps, never counts). The plane replaces the paper's z < z_p
// (section 3), which makes every receiver sloped towards the light shadow
// itself.
fn occludes(r: BpReceiver, c: vec2<f32>, half: f32, z: f32) -> bool {
    let dc = c - r.coords;
    // Only what lies between the receiver and the light along the axis
    // towards the light's centre can hide it (the layer's axis, which z is
    // measured along, turns up to 55 degrees from it on cube faces): beyond,
    // the line from the receiver leads away from the light, and a contour
    // through such samples would not close once backprojected.
    if (1.0 + z * (r.toward.x + r.toward.y * dc.x + r.toward.z * dc.y) <= 2.0 * MIN_W) {
        return false;
    }
    let spread = (abs(r.inv_grad.x) + abs(r.inv_grad.y)) * half;
    let inv = r.inv0 + dot(r.inv_grad, dc);
    if (r.facing) {
        // Above the plane: z < 1 / inv, or any z where the ray never meets it.
        return below_threshold(r, z, inv + spread);
    }
    // The centre below the plane: above it means beyond where the ray crosses it.
    let lo = inv - spread;
    return z < r.depth - r.bias && lo > 0.0 && z * lo > 1.0 + r.bias * lo;
}

fn level_offset(level: u32) -> u32 {
    return bp.level_offset[level / 4u][level % 4u];
}

fn level_size(level: u32) -> u32 {
    return bp.level_size[level / 4u][level % 4u];
}

// What reads of one level need, looked up once per loop rather than per
// texel (indexing the parameter arrays per texel is slow on lavapipe).
struct LevelInfo {
    level: u32,
    // Side in texels (level 0: the map's), first texel in `hierarchy`, and
    // the texel's width in level-0 texels.
    size: i32,
    offset: u32,
    scale: f32,
};

fn level_info(level: u32) -> LevelInfo {
    return LevelInfo(level, i32(level_size(level)), level_offset(level), f32(1u << level));
}

// Minimum and maximum depth, along the receiver layer's axis, of texel t
// of level `li` of the receiver's layer (level 0: the map's texel). On a
// cube, a texel beyond the face stands for the direction of its centre,
// (t + 0.5) 2^l in level-0 coordinates: the neighbour face's texel holding
// it is read (one level coarser when `widen`, for bounds: the texel grids
// of two faces do not line up); a frustum's map holds nothing beyond its
// edges (it covers the casters and their penumbrae).
fn map_bounds(layer: i32, li: LevelInfo, t: vec2<i32>, widen: bool) -> vec2<f32> {
    let ls = shadow.light_space;
    let far = ls.depth.y;
    if (all(t >= vec2<i32>(0)) && all(t < vec2<i32>(li.size))) {
        // The receiver's own layer was rendered (the receiver is in it).
        if (li.level == 0u) {
            return vec2<f32>(textureLoad(shadow_map, t, layer, 0) * far);
        }
        return hierarchy[li.offset + u32((layer * li.size + t.y) * li.size + t.x)];
    }
    if (!is_cube(ls)) {
        return vec2<f32>(far);
    }
    let c = (vec2<f32>(t) + 0.5) * li.scale;
    let m = map_wrap(ls, layer, c);
    if (!layer_active(ls, m.layer)) {
        return vec2<f32>(far);
    }
    var ri = li;
    if (widen) {
        ri = level_info(min(li.level + 1u, bp.levels - 1u));
    }
    let q = clamp(vec2<i32>(floor(m.coords / ri.scale)), vec2<i32>(0), vec2<i32>(ri.size - 1));
    var b: vec2<f32>;
    if (ri.level == 0u) {
        b = vec2<f32>(textureLoad(shadow_map, q, m.layer, 0) * far);
    } else {
        b = hierarchy[ri.offset + u32((m.layer * ri.size + q.y) * ri.size + q.x)];
    }
    // Positive: the direction's dominant axis is the read face's.
    return b / layer_depth_scale(ls, layer, c, m.layer);
}

// Half the kernel width of Eq. 1, in level-0 texels, for occluders no
// nearer the light than z: w_l z_n r / w_n (1/z - 1/z_p) with the disk's
// radius rho for w_l / 2 and the texel at unit depth for w_n / (z_n r),
// widened by 1 / cos of the ray's angle from the layer's axis (a cone's
// section grows by that factor in the map away from the axis).
fn kernel_half(r: BpReceiver, z: f32) -> f32 {
    let zz = max(z, shadow.light_space.depth.x);
    // r.texel1 > 0 (the window has a positive extent).
    return KERNEL_SLACK * r.rho * r.sec * max(1.0 / zz - 1.0 / r.depth, 0.0) / r.texel1;
}

// ---- 4.2: radial area integration over the unit disk.

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// The part of the triangle (O, a, b) inside the unit disk less the disk's
// sector between the directions of a and b (both signed by the turn from a to
// b): zero unless the segment crosses the disk, where it is the closed form
// of the sector cut by the segment's line, (cross - angle) / 2 over the
// chord. Written from the line's distance h to the centre and positions tau
// along it, so that far endpoints (clipped edges reach 1e5) lose nothing.
fn chord_term(a: vec2<f32>, b: vec2<f32>) -> f32 {
    let d = b - a;
    let len = length(d);
    if (len < 1e-12) {
        return 0.0;
    }
    let u = d / len;
    let h = cross2(a, u);
    if (abs(h) >= 1.0) {
        return 0.0;
    }
    let q = sqrt(1.0 - h * h);
    let t1 = max(dot(a, u), -q);
    let t2 = min(dot(b, u), q);
    if (t2 <= t1) {
        return 0.0;
    }
    // The chord's ends are h (u.y, -u.x) + tau u for tau = t1, t2.
    let twice_triangle = (t2 - t1) * h;
    return 0.5 * (twice_triangle - atan2(twice_triangle, h * h + t1 * t2));
}

// Signed area of the triangle (O, a, b) inside the unit disk.
fn triangle_in_disk(a: vec2<f32>, b: vec2<f32>) -> f32 {
    // A vertex at the centre: no area (and atan2(0, 0) is not defined).
    if (dot(a, a) < 1e-24 || dot(b, b) < 1e-24) {
        return 0.0;
    }
    return 0.5 * atan2(cross2(a, b), dot(a, b)) + chord_term(a, b);
}

// Signed area, inside the unit disk and on the visible side of the horizon
// (dot(r.hm, u) >= r.hd), of the polygon of `count` (<= 4) corners.
fn polygon_above_horizon(r: BpReceiver, corners: array<vec2<f32>, 4>, count: u32) -> f32 {
    // Sutherland-Hodgman against one half-plane: at most count + 1 corners.
    var clipped: array<vec2<f32>, 5>;
    var n = 0u;
    for (var i = 0u; i < count; i++) {
        let a = corners[i];
        let b = corners[(i + 1u) % count];
        let sa = dot(r.hm, a) - r.hd;
        let sb = dot(r.hm, b) - r.hd;
        if (sa >= 0.0) {
            clipped[n] = a;
            n++;
        }
        if ((sa >= 0.0) != (sb >= 0.0)) {
            // sa != sb here.
            clipped[n] = a + (b - a) * (sa / (sa - sb));
            n++;
        }
    }
    var area = 0.0;
    for (var i = 0u; i < n; i++) {
        area += triangle_in_disk(clipped[i], clipped[(i + 1u) % n]);
    }
    return area;
}

// Area of the unit disk on the visible side of the horizon.
fn disk_above_horizon(r: BpReceiver) -> f32 {
    let c = clamp(r.hd, -1.0, 1.0);
    return acos(c) - c * sqrt(max(1.0 - c * c, 0.0));
}

// Homogeneous disk coordinates of the point at depth z on the light ray
// through map coordinates c: (x, y) / w is where the line from the receiver
// through the point meets the light's plane, in units of rho; w is the
// point's distance towards the light along the axis, over d.
fn disk_point(r: BpReceiver, c: vec2<f32>, z: f32) -> vec3<f32> {
    let dc = c - r.coords;
    let ray = r.proj0 + r.proj_x * dc.x + r.proj_y * dc.y;
    // The receiver lies on the axis at distance d from the light's centre.
    return vec3<f32>(z * ray.x / r.rho, z * ray.y / r.rho, 1.0 + z * ray.z / r.d);
}

// One contour edge from (ca, za) to (cb, zb), occluder on its left in map
// coordinates: its term of the occluded area (4.2). Backprojected from the
// receiver onto the light's plane, clipped to the points nearer the light
// than the receiver (beyond, the line from the receiver misses the light).
// Without the horizon: area(triangle(O, A, B) in disk) - sector(A, B) (the
// chord term). With it, K = disk above the horizon: area(triangle in K) -
// area(cone(O, A, B) in K). Summed over a closed contour, the sectors add
// up to the winding number of the contour around the centre times the
// area, which the centre test supplies (see `visibility`).
fn edge_term(r: BpReceiver, ca: vec2<f32>, za: f32, cb: vec2<f32>, zb: f32) -> f32 {
    var ha = disk_point(r, ca, za);
    var hb = disk_point(r, cb, zb);
    if (ha.z < MIN_W && hb.z < MIN_W) {
        return 0.0;
    }
    // Clip in homogeneous coordinates (the segment stays a segment).
    if (ha.z < MIN_W) {
        ha = hb + (ha - hb) * ((hb.z - MIN_W) / (hb.z - ha.z));
    } else if (hb.z < MIN_W) {
        hb = ha + (hb - ha) * ((ha.z - MIN_W) / (ha.z - hb.z));
    }
    let a = ha.xy / ha.z;
    let b = hb.xy / hb.z;
    if (!r.cut) {
        return chord_term(a, b);
    }
    var tri: array<vec2<f32>, 4>;
    tri[0] = vec2<f32>(0.0);
    tri[1] = a;
    tri[2] = b;
    let inside = polygon_above_horizon(r, tri, 3u);
    // The cone between the directions of a and b, as the polygon O, 2a^,
    // 2m^, 2b^ (m^ halfway): its outer sides stay beyond the unit disk for any
    // turn below pi.
    let la = length(a);
    let lb = length(b);
    if (la < 1e-12 || lb < 1e-12) {
        return inside;
    }
    let ua = a / la;
    let turn = atan2(cross2(a, b), dot(a, b));
    let half = 0.5 * turn;
    let um = vec2<f32>(ua.x * cos(half) - ua.y * sin(half), ua.x * sin(half) + ua.y * cos(half));
    var cone: array<vec2<f32>, 4>;
    cone[0] = vec2<f32>(0.0);
    cone[1] = 2.0 * ua;
    cone[2] = 2.0 * um;
    cone[3] = 2.0 * b / lb;
    return inside - polygon_above_horizon(r, cone, 4u);
}

// ---- 4.1: contour edges of one 2x2 block of samples.

// A block's samples in counter-clockwise order: 0 at (i, j), 1 at (i + 1,
// j), 2 at (i + 1, j + 1), 3 at (i, j + 1) of the level's sample grid.
struct Block {
    // Map coordinates (level 0) of the four samples' centres.
    c: array<vec2<f32>, 4>,
    z: array<f32, 4>,
    // Bit k: sample k occludes.
    mask: u32,
    // A level above 0 (its samples' depths are their footprints' minima), and the level.
    coarse: bool,
    level: u32,
};

// What a block adds: the area terms of its edges, their number, and whether
// the point `probe` lies on the occluders' side of one of them.
struct BlockResult {
    area: f32,
    edges: u32,
    inside: bool,
};

// The point on the side from occluder sample a towards background sample
// b where the contour crosses it: a fraction (1 - t) / 2 of the way (t = 1:
// at a's centre; 0: the samples' common border; -1: at b's centre).
fn crossing(blk: Block, a: u32, b: u32, f: f32) -> vec2<f32> {
    return blk.c[a] + f * (blk.c[b] - blk.c[a]);
}

// Depth of level 0 at map point p (its texel; beyond a cube face, the
// neighbour face's), along the receiver layer's axis.
fn depth0(r: BpReceiver, p: vec2<f32>) -> f32 {
    return map_bounds(r.layer, level_info(0u), vec2<i32>(floor(p)), false).x;
}

// Where the contour crosses the side from occluder sample a towards
// background sample b, and the depth there. 5.1 (`coarse_contour`
// "centres"): the crossing of `crossing` (t = 1 on coarse levels: a's
// centre) at a's footprint's minimum depth. That places a contour up to
// half a coarse texel from the map's, the same way along a whole edge that
// runs along the texel grid (an axis-aligned shelf above a cube's light),
// and a surface steep in the map nearer the light than it is at the contour.
// "refined" (beyond the paper): the crossing found on level 0 by bisection
// along the line through a's and b's centres, to 1/32 of a's texel, at the
// depth of the last occluding texel. Where a's centre does not occlude on
// level 0 (the footprint's occluder lies off it), 5.1's.
fn side_crossing(r: BpReceiver, blk: Block, a: u32, b: u32, f: f32) -> vec3<f32> {
    let paper = vec3<f32>(crossing(blk, a, b, f), blk.z[a]);
    if (!blk.coarse || (bp.flags & REFINED_CONTOUR) == 0u) {
        return paper;
    }
    let ca = blk.c[a];
    let cb = blk.c[b];
    // Fractions of the way from a's centre to b's: the map's contour crosses
    // the line after a's centre (0) where that occludes on level 0, and
    // before the samples' common border (1/2: b's footprint is free). The
    // crossing stays in the block's cell: the centre test of 4.2 reads the
    // cell around p' alone. (An occluder beyond a's centre from b would
    // move it out, into the cell of blocks that hold no edge.)
    var lo = 0.0;
    var hi = 0.5;
    var z = depth0(r, ca);
    if (!occludes(r, ca, 0.0, z)) {
        return paper;
    }
    // REFINE_STEPS halvings leave the crossing within 1/2^(steps+2) of a's
    // texel (or half a texel of level 0, below level REFINE_STEPS).
    for (var k = 0u; k < min(blk.level, REFINE_STEPS); k++) {
        let mid = 0.5 * (lo + hi);
        let p = mix(ca, cb, mid);
        let zm = depth0(r, p);
        if (occludes(r, p, 0.0, zm)) {
            lo = mid;
            z = zm;
        } else {
            hi = mid;
        }
    }
    return vec3<f32>(mix(ca, cb, 0.5 * (lo + hi)), max(z, blk.z[a]));
}

fn add_edge(r: BpReceiver, res: ptr<function, BlockResult>, blk: Block, f: f32, a0: u32, b0: u32, a1: u32, b1: u32, probe: vec2<f32>, test: bool) {
    // The edge runs from the crossing of side (a0, b0) to that of (a1, b1);
    // its ends take the depths of their occluder samples, a0 and a1.
    let pa = side_crossing(r, blk, a0, b0, f);
    let pb = side_crossing(r, blk, a1, b1, f);
    let ca = pa.xy;
    let cb = pb.xy;
    let e = cb - ca;
    if (dot(e, e) < 1e-12) {
        // t = 1 shrinks a lone occluder to its centre: no edge.
        return;
    }
    (*res).edges += 1u;
    (*res).area += edge_term(r, ca, pa.z, cb, pb.z);
    if (test && cross2(e, probe - ca) > 0.0) {
        (*res).inside = true;
    }
}

// The marching-squares rules of 4.1 (Figure 4), oriented so that the
// occluders lie on each edge's left: one occluder k, an edge from side (k,
// k+1) to side (k, k-1); three, around the background sample k, from side
// (k-1, k) to (k+1, k); two neighbours k, k+1, from side (k+1, k+2) to (k,
// k-1); two opposite, the one-occluder edge of each (the central symmetry of
// the paper's table). `probe` is tested (the centre test of 4.2) when `test`.
fn block_edges(r: BpReceiver, blk: Block, t: f32, probe: vec2<f32>, test: bool) -> BlockResult {
    var res = BlockResult(0.0, 0u, false);
    let m = blk.mask;
    if (m == 0u || m == 15u) {
        res.inside = m == 15u;
        return res;
    }
    let f = 0.5 * (1.0 - t);
    let count = countOneBits(m);
    if (count == 1u) {
        let k = firstTrailingBit(m);
        add_edge(r, &res, blk, f, k, (k + 1u) % 4u, k, (k + 3u) % 4u, probe, test);
    } else if (count == 3u) {
        let k = firstTrailingBit(~m & 15u);
        add_edge(r, &res, blk, f, (k + 3u) % 4u, k, (k + 1u) % 4u, k, probe, test);
        // t = -1 grows the occluders onto the lone background sample's
        // centre: no edge, and the whole block (but that point) is inside.
        if (test && res.edges == 0u) {
            res.inside = true;
        }
    } else if (m == 5u || m == 10u) {
        let k = firstTrailingBit(m);
        add_edge(r, &res, blk, f, k, (k + 1u) % 4u, k, (k + 3u) % 4u, probe, test);
        let k2 = k + 2u;
        add_edge(r, &res, blk, f, k2, (k2 + 1u) % 4u, k2, (k2 + 3u) % 4u, probe, test);
    } else {
        // Two neighbours: k is the one whose successor also occludes.
        var k = 0u;
        if (m == 6u) {
            k = 1u;
        } else if (m == 12u) {
            k = 2u;
        } else if (m == 9u) {
            k = 3u;
        }
        add_edge(r, &res, blk, f, (k + 1u) % 4u, (k + 2u) % 4u, k, (k + 3u) % 4u, probe, test);
    }
    return res;
}

struct Sample {
    c: vec2<f32>,
    z: f32,
    occ: bool,
};

fn read_sample(r: BpReceiver, li: LevelInfo, ij: vec2<i32>) -> Sample {
    var s: Sample;
    s.c = (vec2<f32>(ij) + 0.5) * li.scale;
    s.z = map_bounds(r.layer, li, ij, false).x;
    // Level 0: the sample's own ray; coarser: its whole footprint (5.1).
    s.occ = occludes(r, s.c, select(0.0, 0.5 * li.scale, li.level > 0u), s.z);
    return s;
}

// A tile of 4 x 4 samples of a level (from sample 4 (a, b)), which texel
// (a, b) of the level two above bounds: none of its samples occludes, all
// do, or either.
const FREE: u32 = 0u;
const OCCLUDED: u32 = 1u;
const MIXED: u32 = 2u;

// Whether depth z lies below the depth under which a sample occludes, for
// the plane's 1 / depth `inv` on its ray (see `occludes`): below
// min(1 / inv, z_p) - bias (z_p - bias where the ray never meets the
// plane). The threshold does not increase with inv.
fn below_threshold(r: BpReceiver, z: f32, inv: f32) -> bool {
    let zb = z + r.bias;
    return zb < r.depth && (inv <= 0.0 || zb * inv < 1.0);
}

// A tile's status and the minimum depth of its samples (0 where unknown).
struct Tile {
    status: u32,
    z_min: f32,
};

// `li` is the samples' level, `tiles` the level two above (its texels are the tiles).
fn tile_status(r: BpReceiver, li: LevelInfo, tiles: LevelInfo, ab: vec2<i32>) -> Tile {
    if (li.level + 2u >= bp.levels) {
        return Tile(MIXED, 0.0);
    }
    // A tile reaching past the level's edge (an odd side, or beyond a cube
    // face, whose samples wrap one by one) is not bounded by one texel.
    // (A frustum's tile wholly beyond the map holds nothing: FREE below.)
    let n = vec2<i32>(li.size);
    let first = ab * 4;
    let last = first + 3;
    let outside = any(first < vec2<i32>(0)) || any(last >= n);
    if (outside && !(any(last < vec2<i32>(0)) || any(first >= n))) {
        return Tile(MIXED, 0.0);
    }
    // Wholly beyond a cube face: bounded through the neighbour face.
    let wrapped = outside && is_cube(shadow.light_space);
    var b: vec2<f32>;
    if (wrapped) {
        let w = beyond_face_bounds(r, li, ab);
        if (w.x == 0.0) {
            return Tile(MIXED, 0.0);
        }
        b = w.yz;
    } else {
        b = map_bounds(r.layer, tiles, ab, false);
    }
    if (b.x >= r.depth - r.bias) {
        return Tile(FREE, b.x);
    }
    if (!r.facing) {
        return Tile(MIXED, b.x);
    }
    // The plane's 1 / depth over the tile's sample centres (affine: its
    // extremes at the corners), widened by the samples' footprints as
    // `occludes` does.
    let s = li.scale;
    let c0 = (vec2<f32>(ab * 4) + 0.5) * s - r.coords;
    let a0 = r.inv_grad * c0;
    let a1 = r.inv_grad * (c0 + 3.0 * s);
    let spread = select(0.0, (abs(r.inv_grad.x) + abs(r.inv_grad.y)) * 0.5 * s, li.level > 0u);
    let inv_lo = r.inv0 + min(a0.x, a1.x) + min(a0.y, a1.y) + spread;
    let inv_hi = r.inv0 + max(a0.x, a1.x) + max(a0.y, a1.y) + spread;
    if (!below_threshold(r, b.x, inv_lo)) {
        return Tile(FREE, b.x);
    }
    // (Beyond a face, `occludes`' test along the axis towards the light
    // may drop samples that pass the threshold: never OCCLUDED there.)
    if (below_threshold(r, b.y, inv_hi) && !wrapped) {
        return Tile(OCCLUDED, b.x);
    }
    return Tile(MIXED, b.x);
}

// Bounds (y: minimum, z: maximum depth along the receiver layer's axis) of
// what `read_sample` reads for the 4 x 4 samples of level `li` from sample
// 4 ab, a tile wholly beyond the receiver's cube face; x: 1 where they hold,
// 0 where they cannot be had (the samples map to several faces or to an
// inactive one, or no level of the hierarchy holds them in 2 x 2 texels).
// Each sample reads the neighbour face's texel holding its centre's
// direction (`map_bounds`). The corner samples' directions map into one
// face: the rectangle's directions form a convex cone, and so does a face's,
// so every sample's does, and the central projection between the two
// planes maps the rectangle to the convex hull of its corners' images. The
// level-l texels under that hull lie within up to 2 x 2 texels of a level
// L >= l, whose minimum and maximum bound theirs (each level bounds the
// map's texels under its own). A depth read on the neighbour face is
// divided by `layer_depth_scale`, the ray's component along the read face's
// axis per unit along the receiver's (1 / an affine function of c on the
// receiver's plane, positive over the cone: its extremes at the corners).
fn beyond_face_bounds(r: BpReceiver, li: LevelInfo, ab: vec2<i32>) -> vec3<f32> {
    let ls = shadow.light_space;
    var layer = -1;
    var q_lo = vec2<f32>(3e38);
    var q_hi = vec2<f32>(-3e38);
    var scale_lo = 3e38;
    var scale_hi = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let corner = vec2<f32>(f32(k & 1u), f32(k >> 1u)) * 3.0;
        let c = (vec2<f32>(ab * 4) + corner + 0.5) * li.scale;
        let m = map_wrap(ls, r.layer, c);
        if ((k > 0u && m.layer != layer) || m.layer == r.layer || !layer_active(ls, m.layer)) {
            return vec3<f32>(0.0);
        }
        layer = m.layer;
        q_lo = min(q_lo, m.coords);
        q_hi = max(q_hi, m.coords);
        let scale = layer_depth_scale(ls, r.layer, c, m.layer);
        if (!(scale > 0.0)) {
            return vec3<f32>(0.0);
        }
        scale_lo = min(scale_lo, scale);
        scale_hi = max(scale_hi, scale);
    }
    // The texels of level l the samples read (clamped to the map, as the
    // reads are), the hull widened by 0.05 level-0 texels and the depth
    // scales by 1e-5 of theirs, far beyond float32 rounding of an inner
    // sample's image and scale (about 1e-4 texels on a 1024-texel face).
    q_lo -= vec2<f32>(0.05);
    q_hi += vec2<f32>(0.05);
    scale_lo *= 1.0 - 1e-5;
    scale_hi *= 1.0 + 1e-5;
    let size = li.size;
    let t_lo = clamp(vec2<i32>(floor(q_lo / li.scale)), vec2<i32>(0), vec2<i32>(size - 1));
    let t_hi = clamp(vec2<i32>(floor(q_hi / li.scale)), vec2<i32>(0), vec2<i32>(size - 1));
    for (var level = max(li.level, 1u); level < bp.levels; level++) {
        let shift = level - li.level;
        let a = t_lo >> vec2<u32>(shift);
        let z = t_hi >> vec2<u32>(shift);
        if (any(z - a > vec2<i32>(1))) {
            continue;
        }
        let ri = level_info(level);
        var b = vec2<f32>(3e38, 0.0);
        for (var y = a.y; y <= z.y; y++) {
            for (var x = a.x; x <= z.x; x++) {
                let h = hierarchy[ri.offset + u32((layer * ri.size + y) * ri.size + x)];
                b = vec2<f32>(min(b.x, h.x), max(b.y, h.y));
            }
        }
        return vec3<f32>(1.0, b.x / scale_hi, b.y / scale_lo);
    }
    return vec3<f32>(0.0);
}

struct Visibility {
    v: f32,
    edges: u32,
    // Blocks of 2 x 2 samples walked (the work `descent` bounds).
    blocks: u32,
};

// The centre test of 4.2 alone at `level`: whether the block of samples
// around p' puts p' inside the contour.
fn centre_inside(r: BpReceiver, level: u32) -> bool {
    let li = level_info(level);
    let t = select(1.0, bp.t, level == 0u);
    let centre = vec2<i32>(floor(r.coords / li.scale - 0.5));
    let s0 = read_sample(r, li, centre);
    let s1 = read_sample(r, li, centre + vec2<i32>(1, 0));
    let s2 = read_sample(r, li, centre + vec2<i32>(1, 1));
    let s3 = read_sample(r, li, centre + vec2<i32>(0, 1));
    var blk: Block;
    blk.coarse = level > 0u;
    blk.level = level;
    blk.mask = u32(s0.occ) | (u32(s1.occ) << 1u) | (u32(s2.occ) << 2u) | (u32(s3.occ) << 3u);
    if (blk.mask == 0u || blk.mask == 15u) {
        return blk.mask == 15u;
    }
    blk.c = array<vec2<f32>, 4>(s0.c, s1.c, s2.c, s3.c);
    blk.z = array<f32, 4>(s0.z, s1.z, s2.z, s3.z);
    return block_edges(r, blk, t, r.coords, true).inside;
}

// The visibility of the light from the receiver at hierarchy level `level`
// (4.1, 4.2, 5.1): contour edges of the level's samples over the kernel of
// half width `h0` level-0 texels, backprojected and integrated from the
// disk's centre. The integration starts from the whole disk (above the
// horizon) when the centre is outside the contour and from nothing when it
// is inside: the centre test applies the same rules to the block around p'.
// Tiles of 4 x 4 blocks whose samples the hierarchy shows all occluding or
// all free hold no edge and are skipped.
fn visibility(r: BpReceiver, level: u32, h0: f32) -> Visibility {
    let li = level_info(level);
    let tiles = level_info(min(level + 2u, bp.levels - 1u));
    let s = li.scale;
    // 5.1: coarse levels shrink the contour onto the occluders' centres (t = 1).
    var t = 1.0;
    if (level == 0u) {
        t = bp.t;
    }
    let pl = r.coords / s;
    let hl = h0 / s + KERNEL_MARGIN;
    // Block (i, j) spans the cell between the centres of samples i and i + 1,
    // [i + 0.5, i + 1.5]: the blocks whose cells meet [p - h, p + h].
    let lo = vec2<i32>(floor(pl - hl - 0.5));
    let hi = vec2<i32>(floor(pl + hl - 0.5));
    let centre = vec2<i32>(floor(pl - 0.5));
    // Tiles holding the blocks' first samples (>> 2 is a floor division).
    let tlo = lo >> vec2<u32>(2u);
    let thi = hi >> vec2<u32>(2u);
    var area = 0.0;
    var edges = 0u;
    var blocks = 0u;
    var inside = false;
    for (var tb = tlo.y; tb <= thi.y; tb++) {
        // A block's samples lie in its tile and the next ones along x and y.
        var top_left = tile_status(r, li, tiles, vec2<i32>(tlo.x, tb));
        var bottom_left = tile_status(r, li, tiles, vec2<i32>(tlo.x, tb + 1));
        for (var ta = tlo.x; ta <= thi.x; ta++) {
            let top_right = tile_status(r, li, tiles, vec2<i32>(ta + 1, tb));
            let bottom_right = tile_status(r, li, tiles, vec2<i32>(ta + 1, tb + 1));
            let b0 = max(vec2<i32>(ta, tb) * 4, lo);
            let b1 = min(vec2<i32>(ta, tb) * 4 + 3, hi);
            let has_centre = all(centre >= b0) && all(centre <= b1);
            let st = top_left.status;
            let same = st != MIXED && st == top_right.status && st == bottom_left.status && st == bottom_right.status;
            // The tile's blocks span the cells of [4 (a, b) + 0.5, 4 (a, b) + 4.5]
            // samples; their edges' ends hold depths of these four tiles'
            // samples, so nowhere nearer than their minimum: beyond that
            // depth's own kernel (Eq. 1) from p', they project off the disk.
            let z4 = min(min(top_left.z_min, top_right.z_min), min(bottom_left.z_min, bottom_right.z_min));
            let cell_lo = (vec2<f32>(vec2<i32>(ta, tb) * 4) + 0.5) * s;
            let away = max(max(cell_lo - r.coords, r.coords - (cell_lo + 4.0 * s)), vec2<f32>(0.0));
            let off_disk = max(away.x, away.y) > kernel_half(r, z4) + s;
            if (same || (off_disk && !has_centre)) {
                if (same && has_centre) {
                    inside = st == OCCLUDED;
                }
            } else {
                blocks += u32((b1.x - b0.x + 1) * (b1.y - b0.y + 1));
                for (var j = b0.y; j <= b1.y; j++) {
                    var s0 = read_sample(r, li, vec2<i32>(b0.x, j));
                    var s3 = read_sample(r, li, vec2<i32>(b0.x, j + 1));
                    for (var i = b0.x; i <= b1.x; i++) {
                        let s1 = read_sample(r, li, vec2<i32>(i + 1, j));
                        let s2 = read_sample(r, li, vec2<i32>(i + 1, j + 1));
                        var blk: Block;
                        blk.coarse = level > 0u;
                        blk.level = level;
                        blk.mask = u32(s0.occ) | (u32(s1.occ) << 1u) | (u32(s2.occ) << 2u) | (u32(s3.occ) << 3u);
                        let test = i == centre.x && j == centre.y;
                        if (blk.mask != 0u && (blk.mask != 15u || test)) {
                            blk.c = array<vec2<f32>, 4>(s0.c, s1.c, s2.c, s3.c);
                            blk.z = array<f32, 4>(s0.z, s1.z, s2.z, s3.z);
                            let res = block_edges(r, blk, t, r.coords, test);
                            area += res.area;
                            edges += res.edges;
                            if (test) {
                                inside = res.inside;
                            }
                        }
                        s0 = s1;
                        s3 = s2;
                    }
                }
            }
            top_left = top_right;
            bottom_left = bottom_right;
        }
    }
    let w = select(0.0, 1.0, inside);
    var v: f32;
    if (r.cut) {
        v = (disk_above_horizon(r) * (1.0 - w) - area) / PI;
    } else {
        v = 1.0 - w - area / PI;
    }
    return Visibility(clamp(v, 0.0, 1.0), edges, blocks);
}
