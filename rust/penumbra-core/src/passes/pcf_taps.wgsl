#import shaders/common.wgsl
#import passes/shadow_test.wgsl

// Shared by the filtering methods (`pcf`, `pcss`, `pvmf`): shadow-map taps
// away from the receiver's own texel (percentage-closer filtering, Reeves et
// al. 1987; Cournia ch. 3 and 5.2).
//
// Each tap compares the map against the depth of the receiver's tangent plane
// along that tap's light ray ("receiver-plane depth"), not against the
// receiver's own depth, so that a wide kernel over a receiver sloped towards
// the light does not shadow itself. Taps go through a comparison sampler:
// with linear filtering that is the hardware's 2x2 bilinear PCF.

struct Receiver {
    // A point on the receiver's plane (the biased lookup point) and its unit normal.
    origin: vec3<f32>,
    normal: vec3<f32>,
    // Light depth of `origin` along the receiver's axis, the layer and its
    // map coordinates there in texels: taps step away from them in this
    // layer. Layer -1 (`pcf_frame_receiver` on cube faces): the receiver's
    // own frame, whose axis is the light's direction to `origin`.
    depth: f32,
    layer: i32,
    coords: vec2<f32>,
    // Depth bias subtracted from every tap, world units.
    bias: f32,
    // World size of one map texel at `depth`.
    texel: f32,
    // Layer -1: columns t, b, w, a rotation: w the unit direction from the
    // light to `origin`, t and b across it (see `pcf_frame_receiver`).
    frame: mat3x3<f32>,
};

// The receiver at p (normal n, light cosine cos_theta > 0) for the bias mode
// of `t`: mode 0 (`slope`) offsets the plane along n by `normal_offset`
// texels and subtracts `constant_bias` texels (the plane itself replaces the
// slope term); the other modes compare the plane unbiased.
fn pcf_receiver(t: ShadowTest, p: vec3<f32>, n: vec3<f32>) -> Receiver {
    var r: Receiver;
    r.normal = n;
    r.texel = light_texel_size(t.light_space, light_view_depth(t.light_space, p));
    r.origin = p;
    r.bias = 0.0;
    if (t.mode.x == 0u) {
        r.origin = p + n * (t.bias.x * r.texel);
        r.bias = t.bias.y * r.texel;
    }
    r.depth = light_view_depth(t.light_space, r.origin);
    let m = light_map_point(t.light_space, r.origin);
    r.layer = m.layer;
    r.coords = m.coords;
    return r;
}

// On cube faces, the receiver at p as `pcf_receiver` builds it, but in its
// own frame (layer -1) instead of its face's: taps are laid out on the plane
// across the light's direction w to the receiver, in units of the texel at a
// face's centre (2 / map size at unit depth), and each is read from the face
// its own direction falls in, in that face's texel coordinates. The kernel is
// then the same whichever way the cube's faces cut the scene (issue 31): a
// face's own axes turn with the scene, and its texels shrink towards its
// edges. Depths are along w. The frame's t is the normal's direction across
// w, a direction the scene carries along when it turns; where the normal
// faces the light (within 0.06 degrees) any t across w does (Duff et al.
// 2017's basis). A frustum's receiver is `pcf_receiver`'s.
fn pcf_frame_receiver(t: ShadowTest, p: vec3<f32>, n: vec3<f32>) -> Receiver {
    let ls = t.light_space;
    if (!is_cube(ls)) {
        return pcf_receiver(t, p, n);
    }
    var r: Receiver;
    r.normal = n;
    // Cube faces: `view` is the translation to the light point. Every surface
    // point lies off the light (scene validation): the lengths are positive.
    r.texel = light_texel_size(ls, length((ls.view * vec4<f32>(p, 1.0)).xyz));
    r.origin = p;
    r.bias = 0.0;
    if (t.mode.x == 0u) {
        r.origin = p + n * (t.bias.x * r.texel);
        r.bias = t.bias.y * r.texel;
    }
    let v = (ls.view * vec4<f32>(r.origin, 1.0)).xyz;
    r.depth = max(length(v), 1e-30);
    let w = v / r.depth;
    r.layer = -1;
    r.coords = vec2<f32>(0.0);
    let across = n - dot(n, w) * w;
    let len = length(across);
    var tx: vec3<f32>;
    if (len > 1e-3) {
        tx = across / len;
    } else {
        // Duff et al. 2017, "Building an orthonormal basis, revisited": unit
        // for unit w (1 + |w.z| >= 1 keeps the division finite).
        let sign = select(-1.0, 1.0, w.z >= 0.0);
        let a = -1.0 / (sign + w.z);
        tx = vec3<f32>(1.0 + sign * w.x * w.x * a, sign * w.x * w.y * a, -sign * w.x);
    }
    r.frame = mat3x3<f32>(tx, cross(w, tx), w);
    return r;
}

// World direction of the light ray through coordinates `c` of the
// receiver's layer (its own frame for layer -1), scaled so that its depth
// along the receiver's axis is 1.
fn receiver_ray(ls: LightSpace, r: Receiver, c: vec2<f32>) -> vec3<f32> {
    if (r.layer >= 0) {
        return light_ray(ls, r.layer, c);
    }
    // One unit of c is a face-centre texel: 2 / map size at unit depth.
    return r.frame * vec3<f32>(c * (2.0 / ls.depth.z), 1.0);
}

// Coordinates in the receiver's layer of the light-space direction `d`
// (within 90 degrees of the receiver's axis).
fn receiver_coords(ls: LightSpace, r: Receiver, d: vec3<f32>) -> vec2<f32> {
    if (r.layer >= 0) {
        return view_coords(ls, layer_frame(ls, r.layer, d));
    }
    // The frame is a rotation: its inverse is its transpose. q.z > 0 for d
    // within 90 degrees of w; the max keeps the division finite otherwise.
    let q = transpose(r.frame) * d;
    return q.xy / max(q.z, 1e-30) / (2.0 / ls.depth.z);
}

// The map point a tap at coordinates `c` of the receiver's layer reads: on
// a cube, the face its direction falls in (`map_wrap`).
fn receiver_read(ls: LightSpace, r: Receiver, c: vec2<f32>) -> MapPoint {
    if (r.layer >= 0) {
        return map_wrap(ls, r.layer, c);
    }
    let d = receiver_ray(ls, r, c);
    let face = cube_face_of(d);
    return MapPoint(face, view_coords(ls, cube_face_frame(face) * d));
}

// Depth along `read`'s axis of the point at depth 1 along the receiver's
// axis on the ray through `c` (1 within one layer): positive where `read` is
// the face the ray falls in.
fn receiver_depth_scale(ls: LightSpace, r: Receiver, c: vec2<f32>, read: i32) -> f32 {
    if (r.layer >= 0) {
        return layer_depth_scale(ls, r.layer, c, read);
    }
    return -(cube_face_frame(read) * receiver_ray(ls, r, c)).z;
}

// Light depth (along the receiver's axis) at which the ray through
// coordinates `c` of the receiver's layer meets the receiver's plane,
// clamped to within `t.bias.w` (the largest slope the bias schemes use)
// times the lateral distance from the receiver.
fn plane_depth(t: ShadowTest, r: Receiver, c: vec2<f32>) -> f32 {
    let lateral = length(c - r.coords) * r.texel;
    let limit = t.bias.w * lateral;
    let d = receiver_ray(t.light_space, r, c);
    // The light is on the normal's side of the plane (cos_theta > 0), so the
    // ray meets the plane ahead of it exactly where dot(n, d) < 0; elsewhere
    // (beyond the plane's horizon as seen from the light) the plane is taken
    // as far as the clamp allows.
    let denom = dot(r.normal, d);
    if (denom >= -1e-12) {
        return r.depth + limit;
    }
    let depth = dot(r.normal, r.origin - t.center.xyz) / denom;
    return clamp(depth, r.depth - limit, r.depth + limit);
}

// One tap: the fraction of the (bilinearly weighted) texels around `c`
// (coordinates in the receiver's layer or frame; on a cube, the face the
// tap's direction falls in is read) that do not hide the receiver's plane. A cube
// face that was not rendered holds no occluder.
fn pcf_tap(t: ShadowTest, map: texture_depth_2d_array, cmp: sampler_comparison, r: Receiver, c: vec2<f32>) -> f32 {
    let ls = t.light_space;
    let m = receiver_read(ls, r, c);
    if (!layer_active(ls, m.layer)) {
        return 1.0;
    }
    // The plane's depth along the axis of the layer read (the same ray). Where
    // the plane lies beyond the far plane (or the ray passes above its
    // horizon), only drawn surfaces hide it: a texel where nothing was drawn
    // (cleared to the far plane, 1) passes.
    let depth = plane_depth(t, r, c) * receiver_depth_scale(ls, r, c, m.layer);
    let reference = min((depth - r.bias) / ls.depth.y, 1.0);
    return textureSampleCompareLevel(map, cmp, m.coords / ls.depth.z, m.layer, reference);
}

// The map texel a tap at coordinates `c` of the receiver's layer reads: its
// layer, its centre there, and the point the map stores (`drawn` false
// where nothing was: the far plane, or a cube face not rendered).
struct StoredTexel {
    layer: i32,
    centre: vec2<f32>,
    // Stored depth along the layer's axis, world units.
    depth: f32,
    q: vec3<f32>,
    drawn: bool,
};

fn stored_texel(t: ShadowTest, map: texture_depth_2d_array, r: Receiver, c: vec2<f32>) -> StoredTexel {
    let ls = t.light_space;
    let m = receiver_read(ls, r, c);
    let centre = vec2<f32>(map_texel(textureDimensions(map), m)) + 0.5;
    let stored = map_point_depth(ls, map, MapPoint(m.layer, centre));
    // The stored point: along the read layer's ray, whose depth along that
    // layer's axis is 1 per unit.
    let q = t.center.xyz + light_ray(ls, m.layer, centre) * stored;
    return StoredTexel(m.layer, centre, stored, q, stored < ls.depth.y);
}

// The stored point of the texel `d` texels from `s`'s in its layer, less
// s's point, where that texel is in the map and drawn; else zero.
fn stored_step(t: ShadowTest, map: texture_depth_2d_array, s: StoredTexel, d: vec2<f32>) -> vec3<f32> {
    let ls = t.light_space;
    let c = s.centre + d;
    if (any(c < vec2<f32>(0.0)) || any(c >= vec2<f32>(textureDimensions(map)))) {
        return vec3<f32>(0.0);
    }
    let stored = map_point_depth(ls, map, MapPoint(s.layer, c));
    if (stored >= ls.depth.y) {
        return vec3<f32>(0.0);
    }
    return t.center.xyz + light_ray(ls, s.layer, c) * stored - s.q;
}

// Of the steps to a texel's two neighbours along one axis, the one to the
// nearer stored point (the same surface, where the other crosses a depth
// edge); zero where neither is drawn.
fn surface_step(t: ShadowTest, map: texture_depth_2d_array, s: StoredTexel, axis: vec2<f32>) -> vec3<f32> {
    let ahead = stored_step(t, map, s, axis);
    let back = stored_step(t, map, s, -axis);
    let la = dot(ahead, ahead);
    let lb = dot(back, back);
    if (la == 0.0 || (lb > 0.0 && lb < la)) {
        return -back;
    }
    return ahead;
}

// The "behind" test of a map texel (a departure from the receiver-plane
// test of Fernando 2005 and Cournia 5.2, option `blocker_test="behind"`):
// whether the receiver p lies behind the surface the map stores at `s` (its
// tangent plane through the neighbouring texels' points, facing the light's
// centre) by more than a texel's extent there. A ray from p to a point of
// the light that an occluder hides leaves the occluder through a surface
// that p is behind; a wall or floor beside p, nearer the light than p's
// plane (a room's concave corners, or every other surface where p's plane
// passes near the light), has p in front of it and hides nothing. Unlike a
// cone test, an occluder's texels outside the cone from p to the light
// still count, so a search still finds the blockers of the outer penumbra.
// Where no tangent plane is found (an isolated texel, or parallel steps)
// the texel is taken as behind: the plane test alone decides. The one
// division is by the normal's length, checked nonzero.
fn receiver_behind(t: ShadowTest, map: texture_depth_2d_array, s: StoredTexel, p: vec3<f32>) -> bool {
    let n = cross(surface_step(t, map, s, vec2<f32>(1.0, 0.0)), surface_step(t, map, s, vec2<f32>(0.0, 1.0)));
    let length_n = length(n);
    let facing = dot(n, t.center.xyz - s.q);
    if (length_n == 0.0 || facing == 0.0) {
        return true;
    }
    let behind = -dot(n, p - s.q) * sign(facing) / length_n;
    return behind > light_texel_size(t.light_space, s.depth);
}

// `pcf_tap`, with a failing tap whose texel's surface the receiver p is not
// behind (`receiver_behind`) counted lit, when `behind` is set.
fn pcf_tap_behind(t: ShadowTest, map: texture_depth_2d_array, cmp: sampler_comparison, r: Receiver, c: vec2<f32>, p: vec3<f32>, behind: bool) -> f32 {
    let lit = pcf_tap(t, map, cmp, r, c);
    if (lit < 1.0 && behind && !receiver_behind(t, map, stored_texel(t, map, r, c), p)) {
        return 1.0;
    }
    return lit;
}

// PCG hash (O'Neill; the "pcg" of Jarzynski and Olano 2020).
fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Two uniform numbers in [0, 1) fixed by pixel, seed and tap index.
fn jitter2(px: vec2<u32>, seed: u32, index: u32) -> vec2<f32> {
    let h = pcg_hash(px.x ^ pcg_hash(px.y ^ pcg_hash(seed ^ pcg_hash(index))));
    let h2 = pcg_hash(h);
    return vec2<f32>(f32(h >> 8u), f32(h2 >> 8u)) / 16777216.0;
}

// Tap `index` of an n x n grid over [-0.5, 0.5]^2, placed at `jitter` in its cell.
fn grid_tap(index: u32, n: u32, jitter: vec2<f32>) -> vec2<f32> {
    let cell = vec2<f32>(f32(index % n), f32(index / n));
    return (cell + jitter) / f32(n) - 0.5;
}

// Shirley and Chiu's concentric map from [-0.5, 0.5]^2 to the unit disk: keeps
// a stratified grid stratified.
fn square_to_disk(s: vec2<f32>) -> vec2<f32> {
    let a = 2.0 * s;
    if (a.x == 0.0 && a.y == 0.0) {
        return vec2<f32>(0.0);
    }
    // The larger of |a.x|, |a.y| is non-zero here, so each division is safe.
    if (abs(a.x) > abs(a.y)) {
        let phi = (PI / 4.0) * (a.y / a.x);
        return a.x * vec2<f32>(cos(phi), sin(phi));
    }
    let phi = (PI / 2.0) - (PI / 4.0) * (a.x / a.y);
    return a.y * vec2<f32>(cos(phi), sin(phi));
}

// Light-area taps (`pvmf`'s and `pcss`'s estimate = "area", beyond their
// papers' fraction of failing taps): the part of the light that the
// occluders under a disk kernel hide from the receiver. An occluder at
// distance z from the light hides light only within the light's cone
// through z, whose radius R(z) (texels at the receiver) shrinks as z nears
// the receiver, and a point x of it hides dx / (pi R(z)^2) of the light's
// disk, so
//   hidden = integral over the kernel of fail(x) [|x| <= R(z(x))] / (pi R(z(x))^2) dx.
// The taps estimate it from two sets combined by the balance heuristic
// (Veach), in units of the kernel's radius: three in four uniform over the
// disk, one in four log-radial (radius t0^(1 - u) for u uniform: as many
// taps per octave, down to half a texel), so that an occluder near the
// receiver, whose cone is small, is still hit by several taps. (On the 40
// generated scenes with pvmf: a half share measured 0.0754 median penumbra
// RMSE, a quarter 0.0688, an eighth 0.0734.)
struct AreaTaps {
    // The log-radial set's inner radius (kernel radii) and -ln of it.
    t0: f32,
    octaves: f32,
    // Taps of each set; n_log is 0 for a kernel narrower than a texel or a single tap.
    n_uniform: f32,
    n_log: f32,
};

// The two sets for `count` taps over a kernel of `radius_texels` (its
// smaller radius, in texels).
fn area_taps(count: u32, radius_texels: f32) -> AreaTaps {
    let t0 = clamp(0.5 / max(radius_texels, 1e-30), 1e-6, 1.0);
    let two_sets = t0 < 0.5 && count > 1u;
    let n_log = select(0.0, f32(count / 4u), two_sets);
    return AreaTaps(t0, -log(t0), f32(count) - n_log, n_log);
}

// Tap i (of n x n) in kernel radii: jittered in its stratum of the unit
// disk (Shirley and Chiu), then, for every fourth tap when there are two
// sets, carried to radius t0^(1 - rho^2) (rho^2 is uniform for a uniform
// disk point) along the same direction.
fn area_tap(taps: AreaTaps, i: u32, n: u32, jitter: vec2<f32>) -> vec2<f32> {
    let u = square_to_disk(grid_tap(i, n, jitter));
    if (taps.n_log == 0.0 || (i & 3u) != 3u || i / 4u >= u32(taps.n_log)) {
        return u;
    }
    let rho2 = dot(u, u);
    let t = exp(-taps.octaves * (1.0 - rho2));
    // rho2 > 0 but at the disk's centre, whose direction is any.
    return select(vec2<f32>(t, 0.0), u * (t / sqrt(rho2)), rho2 > 1e-12);
}

// The share of the light a tap at x (kernel radii) hides: `failed` (the
// part of its footprint that fails the test) over the light's disk at the
// occluder's depth, pi cone.x cone.y (kernel radii, per axis), and over the
// two sets' density there; 0 outside that cone.
fn area_share(taps: AreaTaps, x: vec2<f32>, cone: vec2<f32>, failed: f32) -> f32 {
    let q = x / max(cone, vec2<f32>(1e-30));
    if (failed <= 0.0 || dot(q, q) > 1.0) {
        return 0.0;
    }
    // Densities per unit kernel area: uniform 1 / pi; log-radial
    // 1 / (2 pi t^2 octaves) from t0 to 1.
    let t2 = dot(x, x);
    var density = taps.n_uniform / PI;
    if (taps.n_log > 0.0 && t2 >= taps.t0 * taps.t0) {
        density += taps.n_log / (2.0 * PI * max(t2, 1e-30) * taps.octaves);
    }
    return failed / (PI * max(cone.x * cone.y, 1e-30)) / density;
}
