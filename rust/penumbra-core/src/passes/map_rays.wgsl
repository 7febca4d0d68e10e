#import passes/shadow_test.wgsl

// Rays from a receiver to points of the light, followed through the
// centre's shadow map (beyond the papers, issue 28): pvm's umbra_test "rim"
// and map bound, the wedges' map bound and pvmf's (an option).

// v / |v| without overflow or underflow for any finite v (zero for zero):
// scaled by its largest component first, so that the squares stay near 1.
fn unit(v: vec3<f32>) -> vec3<f32> {
    let big = max(max(abs(v.x), abs(v.y)), abs(v.z));
    if (big == 0.0) {
        return v;
    }
    let w = v / big;
    return w / length(w);
}

// Two unit axes of the light's disk as a receiver p sees it: perpendicular
// to unit(l - p), which is non-zero (no surface touches the light), and to
// each other (the helper axis is at most 0.7 along it).
struct DiskAxes {
    e1: vec3<f32>,
    e2: vec3<f32>,
};

fn disk_axes(t: ShadowTest, p: vec3<f32>) -> DiskAxes {
    let w = unit(t.center.xyz - p);
    let e1 = unit(cross(w, select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(w.x) > 0.7)));
    return DiskAxes(e1, cross(w, e1));
}

// The light depth of the light point `goal` along the axis of p's own
// layer, where the light depth of the ray from p is affine (cube faces:
// nearly so for the ray's points in p's face). `light_view_depth` of a
// light point takes the axis of its own offset from the centre on a cube
// (the largest of its components, at most r): a ray's points then came
// out nearer the light than their depth says, by up to 0.3 of a
// receiver's height under a light of radius 0.8, and a ray 3 texels
// beside a bar's outline read its top (tests/test_pvm.py's straight edge).
fn goal_depth(t: ShadowTest, p: vec3<f32>, goal: vec3<f32>) -> f32 {
    if (!is_cube(t.light_space)) {
        return light_view_depth(t.light_space, goal);
    }
    let layer = light_layer(t.light_space, p);
    return -layer_frame(t.light_space, layer, (t.light_space.view * vec4<f32>(goal, 1.0)).xyz).z;
}

// Whether the shadow map hides the ray from p (at light depth `depth`) to
// the light point `goal`, the search starting at light depth `d_start`
// (a surface thought to lie on the ray): at the light depth d of the last
// surface found, the map's texel under the ray's point holds the first
// surface m on the centre's ray there; the ray is hidden where m lies
// within 2 texels of d (the surface is on it), and seen where m lies
// beyond p or within 2 texels in front of it (p's own surface); else
// d = m, at most 16 times (then taken for seen).
fn ray_hidden(t: ShadowTest, map: texture_depth_2d_array, p: vec3<f32>, depth: f32, d_start: f32, goal: vec3<f32>) -> bool {
    let d_goal = goal_depth(t, p, goal);
    // Surfaces within 2 texels of p's depth are p's own (the ray leaves
    // p's surface there): the far side of the settling tolerance below.
    let near_p = depth - 2.0 * light_texel_size(t.light_space, depth);
    var d = d_start;
    for (var step = 0; step < 16; step++) {
        // Light depth is affine along a ray in a frustum's view (nearly
        // so in a cube face's); a light point lies nearer the light than any
        // surface (no surface touches the light), so depth - d_goal > 0.
        let s = clamp((depth - d) / max(depth - d_goal, 1e-30), 0.0, 1.0);
        let m = map_depth(t, map, p + s * (goal - p));
        if (!(m < near_p)) {
            return false;
        }
        if (abs(m - d) <= 2.0 * light_texel_size(t.light_space, d)) {
            return true;
        }
        // Behind the map's surface (m < d): inside a solid the map cannot see.
        if (solid_stretch(t, p + s * (goal - p), d, d) >= 0.0) {
            return true;
        }
        d = m;
    }
    return false;
}

// map_solids (beyond the papers, issue 28): the solid layers
// (passes/solid_layers.rs) under the point q of a ray, the ray's light
// depths [z0, z1] around it: the middle of the first part of [z0, z1]
// that lies inside a solid caster there (between the 1st and 2nd, or the
// 3rd and 4th, solid surface along the centre's ray through q's texel of
// the layers, each end drawn in by 2 of the layers' texels: a surface
// slanting across a texel is held at its centre's depth, and a thinner
// stretch counts for nothing), or -1 where none does. The importing shader
// binds the layers as `solid_layers` (array<u32>); their side 0 (no solid,
// or map_solids off) answers -1.
fn solid_stretch(t: ShadowTest, q: vec3<f32>, z0: f32, z1: f32) -> f32 {
    let side = solid_layers[0];
    if (side == 0u) {
        return -1.0;
    }
    let m = light_map_point(t.light_space, q);
    if (!layer_active(t.light_space, m.layer)) {
        return -1.0;
    }
    let c = map_texel(vec2<u32>(side), map_point_in(t.light_space, m, vec2<u32>(side)));
    let base = SOLID_HEADER + ((u32(m.layer) * side + u32(c.y)) * side + u32(c.x)) * SOLID_LAYERS;
    // depth.z is the map's side in texels (> 0); side > 0 here.
    let margin = 2.0 * light_texel_size(t.light_space, z1) * (t.light_space.depth.z / f32(side));
    for (var i = 0u; i < SOLID_LAYERS; i += 2u) {
        let exit = solid_layers[base + i + 1u];
        // Fewer surfaces than a stretch needs: none further (0 is empty).
        if (exit == 0u) {
            return -1.0;
        }
        let a = max(z0, bitcast<f32>(~solid_layers[base + i]) + margin);
        let b = min(z1, bitcast<f32>(~exit) - margin);
        if (a <= b) {
            return 0.5 * (a + b);
        }
    }
    return -1.0;
}

// map_bound = "solid" (beyond the papers, issue 28): whether the surface
// the map holds at light depth d on the centre's ray through q is the
// front of a solid caster whose layers hold every surface behind it there:
// the first surface the solid layers hold (within 2 of the layers' texels,
// as `solid_stretch` draws its ends in), with fewer than four surfaces on
// that ray (four fill the layers, and more may lie behind: a hollow
// teapot's walls, generated seed 2). Behind such a front the layers see
// what the map does not, so the map's rays may raise the visibility there
// too; behind an open surface (a scan, an aeroplane with its windows cut
// out) a ray entering through a side the map cannot see would be taken
// for seen. No layers (none solid, or map_solids off): false.
fn solid_in_front(t: ShadowTest, q: vec3<f32>, d: f32) -> bool {
    let side = solid_layers[0];
    if (side == 0u) {
        return false;
    }
    let m = light_map_point(t.light_space, q);
    if (!layer_active(t.light_space, m.layer)) {
        return false;
    }
    let c = map_texel(vec2<u32>(side), map_point_in(t.light_space, m, vec2<u32>(side)));
    let base = SOLID_HEADER + ((u32(m.layer) * side + u32(c.y)) * side + u32(c.x)) * SOLID_LAYERS;
    let exit = solid_layers[base + 1u];
    if (exit == 0u || solid_layers[base + SOLID_LAYERS - 1u] != 0u) {
        return false;
    }
    // depth.z is the map's side in texels (> 0); side > 0 here.
    let margin = 2.0 * light_texel_size(t.light_space, d) * (t.light_space.depth.z / f32(side));
    return abs(bitcast<f32>(~solid_layers[base]) - d) <= margin && d < bitcast<f32>(~exit);
}

// Whether the ray from p (light depth `depth`) to the light point `goal`
// (light depth `d_goal`) passes inside a solid caster between its light
// depths z0 <= z1, as the layers under its point at depth `z` show: where
// they put a solid within [z0, z1] there, the ray's own point at that
// solid's depth must lie inside it too (the ray moves across texels between
// z0 and z1: the first look finds a solid thinner than the step, the second
// keeps a ray that passes beside it).
fn ray_in_solid(t: ShadowTest, p: vec3<f32>, depth: f32, goal: vec3<f32>, d_goal: f32, z: f32, z0: f32, z1: f32) -> bool {
    let inside = solid_stretch(t, ray_point(p, depth, goal, d_goal, z), z0, z1);
    if (inside < 0.0) {
        return false;
    }
    return solid_stretch(t, ray_point(p, depth, goal, d_goal, inside), inside, inside) >= 0.0;
}

// The point of the ray from p (light depth `depth`) to `goal` (`d_goal`)
// at light depth z: light depth is affine along the ray (nearly so in a
// cube face), and depth - d_goal > 0 (no surface touches the light).
fn ray_point(p: vec3<f32>, depth: f32, goal: vec3<f32>, d_goal: f32, z: f32) -> vec3<f32> {
    let s = clamp((depth - z) / max(depth - d_goal, 1e-30), 0.0, 1.0);
    return p + s * (goal - p);
}

// passes/solid_layers.rs' HEADER and LAYERS.
const SOLID_HEADER: u32 = 4u;
const SOLID_LAYERS: u32 = 4u;

// map_march = k (beyond the papers, issue 28): a second look at a ray that
// `ray_hidden` leaves seen. Its search jumps from surface to surface as the
// map shows them from `d_start`, and passes by a surface that lies between
// p and the one it starts at, or that its jumps step over (the rays' seen
// fraction came out high: in the inner penumbra of the generated scenes
// by 0.045 at the median). Here the ray is sampled at k light depths,
// evenly from 2 texels in front of p (p's own surface, as in `ray_hidden`)
// to the map's near plane (or the light point, if nearer p), and it is
// hidden where a sample lies behind the map's surface by at most a step
// and 2 texels: a surface taken as a sheet that thick, which the samples
// cannot step over.
fn ray_marched_hidden(t: ShadowTest, map: texture_depth_2d_array, p: vec3<f32>, depth: f32, goal: vec3<f32>, k: u32) -> bool {
    let d_goal = goal_depth(t, p, goal);
    let z0 = depth - 2.0 * light_texel_size(t.light_space, depth);
    let z1 = max(t.light_space.depth.x, d_goal);
    // No room between p's surface and the near plane: nothing to hide it.
    if (!(z1 < z0) || k == 0u) {
        return false;
    }
    let dz = (z0 - z1) / f32(k);
    for (var i = 0u; i < k; i++) {
        let z = z0 - (f32(i) + 0.5) * dz;
        // Light depth is affine along the ray (as in `ray_hidden`), and
        // depth - d_goal > 0.
        let s = clamp((depth - z) / max(depth - d_goal, 1e-30), 0.0, 1.0);
        let m = map_depth(t, map, p + s * (goal - p));
        if (m <= z && z <= m + dz + 2.0 * light_texel_size(t.light_space, z)) {
            return true;
        }
        if (m <= z && ray_in_solid(t, p, depth, goal, d_goal, z, z - 0.5 * dz, z + 0.5 * dz)) {
            return true;
        }
    }
    return false;
}

// map_samples = n (beyond 4.2, issue 28): the fraction of n points of the
// light's disk as p sees it (an equal-area Vogel spiral in `disk_axes`'
// frame: point i at radius sqrt((i + 1/2) / n), turned by the golden
// angle, each standing for 1/n of the disk) whose rays from p the shadow
// map leaves seen (`ray_hidden`, from light depth `d_start`), bounding the
// visibility k that a method's silhouette edges give p. Those count one
// silhouette's occluder (pvm's half-plane, two edges or loop, the wedges'
// sum); the map sees every surface nearer the light that its texels hold,
// but not what lies behind them. Hidden light is hidden whichever sees it:
// k stands where it lies within `map_margin(n)` and the texel band
// (`texel_band`) of the fraction; beyond, it is wrong by more than the
// points and the texels can be, and it goes to the fraction over one more
// margin (`toward`). With `lower` (map_bound = "both", where the map sees
// the light's centre) the same from below (`away`). With `march` > 0
// (map_march) a ray `ray_hidden` leaves seen is looked at again
// (`ray_marched_hidden`). With `control` (pvm's map_control) the rays are
// compared with k's own model at the same points instead (below). The
// points stop once the rays left cannot take the fraction out of the
// band: the result is then k.
fn map_bound(t: ShadowTest, map: texture_depth_2d_array, p: vec3<f32>, depth: f32, d_start: f32, n: u32, k: f32, lower: bool, march: u32, model: vec4<f32>, model_depth: f32, control: bool) -> f32 {
    let l = t.center.xyz;
    let r = t.center.w;
    let disk = disk_axes(t, p);
    // n >= 1 here (the caller checks).
    let count = f32(n);
    // The map's rays pass within a texel of an occluder's outline over
    // `band` of the light (at the model's depth: pvm's edge, the wedges'
    // holding edge nearest the light); the map cannot tell which side.
    let band = texel_band(t, depth, model_depth, r);
    // The plain bound: k within the spiral's own error (`map_margin`) and
    // the band of the fraction of rays seen (`ray_hidden`, then
    // `ray_marched_hidden`).
    let margin = map_margin(n) + band;
    // With `control`: the fraction of the same points on the lit side of
    // k's own model, the plane `model` (points x with dot(model.xyz, x) >
    // model.w lit). Where the rays and the model disagree the map sees what
    // the model does not, and k moves by those points alone, beyond one
    // point and the band (the spiral's error is the model's too).
    // The control's upper side counts the rays `ray_hidden` leaves seen,
    // without the march: the march takes a surface for a sheet a step
    // thick, and hid rays passing beside a plate's or a wall's edge by up
    // to 2 of 16, which the plain bound's margin covers and one point does
    // not (tests/test_pvm.py's straight edges and resting walls). The
    // march's rays still bound k through the plain bound.
    let control_margin = CONTROL_MARGIN_POINTS / count + band;
    var reference = k;
    if (control) {
        var lit = 0.0;
        for (var i = 0u; i < n; i++) {
            let radius = sqrt((f32(i) + 0.5) / count);
            let a = f32(i) * GOLDEN_ANGLE;
            if (dot(model.xyz, l + r * radius * (cos(a) * disk.e1 + sin(a) * disk.e2)) > model.w) {
                lit += 1.0;
            }
        }
        reference = lit / count;
    }
    // The bounds leave k where, at the end, the rays the search leaves seen
    // are at least lo_search (the control's upper side; none without it),
    // those search and march leave seen at least lo (the plain upper side)
    // and at most hi (the lower side: the control's, else the plain one).
    let lo_search = select(-1.0, count * (reference - control_margin), control);
    let lo = count * (k - margin);
    let hi_plain = select(count * (k + margin), count * (reference + control_margin), control);
    let hi = select(2.0 * count, hi_plain, lower);
    var seen_search = 0.0;
    var seen = 0.0;
    for (var i = 0u; i < n; i++) {
        let radius = sqrt((f32(i) + 0.5) / count);
        let a = f32(i) * GOLDEN_ANGLE;
        let goal = l + r * radius * (cos(a) * disk.e1 + sin(a) * disk.e2);
        if (!ray_hidden(t, map, p, depth, d_start, goal)) {
            seen_search += 1.0;
            if (!ray_marched_hidden(t, map, p, depth, goal, march)) {
                seen += 1.0;
            }
        }
        // Seen at the end: between these and every ray left besides.
        if (seen_search >= lo_search && seen >= lo && seen + count - f32(i + 1u) <= hi) {
            return k;
        }
    }
    // The estimates: the rays' fraction, or with the control k moved by
    // what the rays find beyond the model. Past its band k is wrong and the
    // estimate is the better one: k goes to it over one more band
    // (continuous where it starts to move).
    let f = seen / count;
    var v = toward(k, f, margin);
    var raised = away(k, f, margin);
    if (control) {
        v = min(v, toward(k, k + seen_search / count - reference, control_margin));
        raised = away(k, k + f - reference, control_margin);
    }
    // The lower side acts where the upper one leaves k (it never undoes it).
    if (lower && v >= k) {
        v = raised;
    }
    v = clamp(v, 0.0, 1.0);
    return v;
}

// k where it lies at most `m` above the estimate f; past that, down to f
// over one more m (2 (f + m) - k, continuous at k = f + m), then f.
fn toward(k: f32, f: f32, m: f32) -> f32 {
    return min(k, max(f, 2.0 * (f + m) - k));
}

// The same from below: k where it lies at most `m` under f; past that, up
// to f over one more m.
fn away(k: f32, f: f32, m: f32) -> f32 {
    return max(k, min(f, 2.0 * (f - m) - k));
}

// How far the fraction of n spiral points may lie from k before it moves
// it: the points' own error under one straight edge. A straight line
// through the disk leaves on its lit side a fraction of the points that
// differs from the segment's area by up to 0.443, 0.227, 0.143, 0.081,
// 0.050, 0.036 and 0.022 for n = 4, 8, 16, 32, 64, 128 and 256 (over
// every direction and offset of the line; tests/test_map_rays.py computes
// them), all under 1.2 n^-0.7. Under a lone straight edge, where Eq. 4.1
// and the wedges' coverage are exact, a margin below this moves pixels by
// whatever the points miss: 1/16 at n = 16 (the bound's margin until this
// was measured) lowered a plate's exact k by up to 0.103 at 2836 pixels
// and streaked its penumbra (tests/test_pvm.py's straight edges).
fn map_margin(n: u32) -> f32 {
    // n >= 1 (the callers check): pow of a positive base.
    return 1.2 * pow(f32(n), -0.7);
}

// The fraction of the light's disk whose rays from p (at light depth
// `depth`) cross the occluder's plane at light depth `d` so near an
// outline through it that the map may put them on its other side: the map
// holds each texel's centre, and a point is read at its texel's, at most
// t / sqrt(2) away (t: the texel's width there). The rays' footprint there
// is a disk of radius rho = r (depth - d) / (depth - d_light), and the
// band of that half-width around a straight outline covers at most
// 2 sqrt(2) t / (pi rho) of it (through its middle), whatever the number
// of points. At most 2 (then no bound acts): rho = 0 where the occluder
// lies at p's depth, and a light of radius 0.
fn texel_band(t: ShadowTest, depth: f32, d: f32, r: f32) -> f32 {
    let d_light = light_view_depth(t.light_space, t.center.xyz);
    // depth > d_light: no surface touches the light.
    let rho = r * max(depth - d, 0.0) / max(depth - d_light, 1e-30);
    let band = 2.0 * sqrt(2.0) * light_texel_size(t.light_space, max(d, 0.0)) / (PI * max(rho, 1e-30));
    return min(band, 2.0);
}

// map_control's margin, in points: the map's texel rounding at an
// occluder's outline can put a ray on the other side of it. Under lone
// straight edges (tests/test_pvm.py's) one point moves no pixel.
const CONTROL_MARGIN_POINTS: f32 = 1.0;

// pi (3 - sqrt(5)): the Vogel spiral's turn per point.
const GOLDEN_ANGLE: f32 = 2.3999632;
