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
