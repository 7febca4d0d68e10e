#import passes/shadow_test.wgsl

// Rays from a receiver to points of the light, followed through the
// centre's shadow map (beyond the papers, issue 28): pvm's umbra_test "rim"
// and map bound, and wedges' map bound.

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

// Whether the shadow map hides the ray from p (at light depth `depth`) to
// the light point `goal`, the search starting at light depth `d_start`
// (a surface thought to lie on the ray): at the light depth d of the last
// surface found, the map's texel under the ray's point holds the first
// surface m on the centre's ray there; the ray is hidden where m lies
// within 2 texels of d (the surface is on it), and seen where m lies
// beyond p or within 2 texels in front of it (p's own surface); else
// d = m, at most 16 times (then taken for seen).
fn ray_hidden(t: ShadowTest, map: texture_depth_2d_array, p: vec3<f32>, depth: f32, d_start: f32, goal: vec3<f32>) -> bool {
    let d_goal = light_view_depth(t.light_space, goal);
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
        d = m;
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
// k is at most the fraction plus MAP_MARGIN. With `lower` (map_bound =
// "both", where the map sees the light's centre) it is also at least the
// fraction less MAP_MARGIN_LOWER.
// The points stop once the rays left cannot take the fraction out of k's
// band: the result is then k.
fn map_bound(t: ShadowTest, map: texture_depth_2d_array, p: vec3<f32>, depth: f32, d_start: f32, n: u32, k: f32, lower: bool) -> f32 {
    let l = t.center.xyz;
    let r = t.center.w;
    let disk = disk_axes(t, p);
    // n >= 1 here (the caller checks). Seen rays at least `lo`: the upper
    // bound leaves k; at most `hi`: the lower bound does.
    let count = f32(n);
    let lo = count * (k - MAP_MARGIN);
    let hi = select(2.0 * count, count * (k + MAP_MARGIN_LOWER), lower);
    var seen = 0.0;
    for (var i = 0u; i < n; i++) {
        let radius = sqrt((f32(i) + 0.5) / count);
        let a = f32(i) * GOLDEN_ANGLE;
        if (!ray_hidden(t, map, p, depth, d_start, l + r * radius * (cos(a) * disk.e1 + sin(a) * disk.e2))) {
            seen += 1.0;
        }
        // Seen at the end: between these and every ray left besides.
        if (seen >= lo && seen + count - f32(i + 1u) <= hi) {
            return k;
        }
    }
    let f = seen / count;
    if (lower) {
        return clamp(k, f - MAP_MARGIN_LOWER, f + MAP_MARGIN);
    }
    return min(k, f + MAP_MARGIN);
}

// What the map's fraction must fall below k by before it lowers it: the
// points' own error where a boundary crosses their cells and the map's
// texel rounding at the occluder's outline (a ray within half a texel of
// it counted on the wrong side). Under a straight edge, where Eq. 4.1 is
// exact (tests/test_pvm.py's bar), 32 points and 1/32 lowered k by up to
// 0.038; with 1/16, 32 points lower it by at most 0.007 and 16 (the
// default) not at all.
const MAP_MARGIN: f32 = 0.0625;

// What the map's fraction must exceed k by before it raises it (map_bound
// = "both"): more than MAP_MARGIN, as `ray_hidden` misses some occluders
// (its search follows the surfaces the map shows from `d_start`, and a ray
// that passes them by reads as seen), so the fraction errs high. Under a
// straight edge, where Eq. 4.1 and the wedges' coverage are exact
// (long_edge_scene in tests/test_pvm.py, radii 0.02-1.5), 1/16 raised 160
// pixels by up to 0.0175 at radii 0.3 and 0.5; 3/32 raises none.
const MAP_MARGIN_LOWER: f32 = 0.09375;

// pi (3 - sqrt(5)): the Vogel spiral's turn per point.
const GOLDEN_ANGLE: f32 = 2.3999632;
