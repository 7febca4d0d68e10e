#import shaders/receiver.wgsl
#import passes/shadow_test.wgsl
#import passes/map_rays.wgsl
#import shaders/per_pixel.wgsl

// PVM pass 3 (Cournia 4.2, listing 4.2): light visibility per camera pixel.
// Inside a penumbra volume (the PVDM is nearer the light than the pixel),
// visibility is the fraction of a disk of the light's radius, centred on the
// light and perpendicular to the cutting plane through the stored silhouette
// edge and the pixel, that lies on the unoccluded side (Eq. 4.1, 4.2), with
// the optional 3k^2 - 2k^3 falloff; outside, the shadow-map test decides.

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
@group(0) @binding(3) var volume_depth: texture_depth_2d_array;
// The penumbra volume edge map (4.1.3), by index into `edges` (`EDGE_INDEX_FORMAT` in pvm/mod.rs).
@group(0) @binding(4) var edge_index: texture_2d_array<u32>;
// h0.w: the edge's surface; links: x the index + 1 of the loop's edge
// ending at h0, y of the one starting at h1 (0: a junction or an open end).
struct EdgePoints {
    h0: vec4<f32>,
    h1: vec4<f32>,
    links: vec4<u32>,
};
@group(0) @binding(5) var<storage, read> edges: array<EdgePoints>;
// mode.y bit 0: falloff; bit 1: repair "centre"; bit 2: repair "horizon";
// bit 3: edges = "two" (the far edge map below is read); bit 4: lookup = "3x3";
// bit 5: umbra_test = "rim"; bit 6: edges = "chain"; bit 7: map_bound =
// "both" (or "solid"); bit 8: map_control; bit 9: map_bound = "solid". mode.z: map_samples; mode.w: map_march.
@group(0) @binding(6) var<storage, read> pvm: ShadowTest;
@group(0) @binding(7) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(8) var membership_out: texture_storage_2d<r32float, write>;
// pixels_in_volume, chain_walks, chain_pixels, map_bounded_pixels (stats, pvm/mod.rs).
@group(0) @binding(9) var<storage, read_write> counters: array<atomic<u32>, 5>;
// With edges = "two": the index + 1 of the volume farthest from the light.
@group(0) @binding(10) var far_edge_index: texture_2d_array<u32>;
// The object map and each mesh's object (passes/object_map.rs), for the horizon repair.
@group(0) @binding(11) var object_map: texture_2d_array<u32>;
@group(0) @binding(12) var<storage, read> mesh_objects: array<u32>;
// map_solids: the solid layers the map rays read (passes/solid_layers.rs).
@group(0) @binding(13) var<storage, read> solid_layers: array<u32>;

// The cutting plane of an edge through a receiver (4.2): its unit normal n,
// pointing away from the occluder, and the signed distance s of the light's
// centre from it towards the occluder (Eq. 4.1's s); n = 0 where p lies on
// the edge's line.
struct Cut {
    n: vec3<f32>,
    s: f32,
};

fn cutting_plane(p: vec3<f32>, h0: vec3<f32>, h1: vec3<f32>) -> Cut {
    let r = pvm.center.w;
    let l = pvm.center.xyz;
    // Cutting plane through h0, h1 and p (4.2). Silhouette edges are oriented
    // so that (h1 - h0) x (h0 - l), the hard-shadow plane's normal, points
    // away from the occluder; so does this normal, which turns continuously
    // with p through the hard-shadow plane.
    // Both factors are made unit first: the cross product of raw differences
    // squares the scene's scale, and its length the square again, which
    // overflows f32 beyond coordinates of about 1e9 (issue 22: visibility
    // 1/2 everywhere in the volumes of a scene scaled by 1e10).
    let m = cross(unit(h1 - h0), unit(p - h0));
    let len = length(m);
    // p on the edge's line: the plane is undefined (s = 0: half the light, the limit).
    if (len <= 1e-7) {
        return Cut(vec3<f32>(0.0), 0.0);
    }
    let n = m / len;
    // Signed distance of the light centre from the plane, measured towards the
    // occluder: the visible part of the disk is the part beyond the plane from
    // an occluded centre, so Eq. 4.1 applies with this s.
    return Cut(n, -(dot(n, l) - dot(n, h0)));
}

// k of Eq. 4.2 for the silhouette edge h0-h1 and the receiver p
// (disk_fraction, Eq. 4.1, is in passes/shadow_test.wgsl).
fn volume_visibility(p: vec3<f32>, h0: vec3<f32>, h1: vec3<f32>) -> f32 {
    return disk_fraction(cutting_plane(p, h0, h1).s, pvm.center.w);
}

// The counter-clockwise angle from unit vector u to unit vector v, in [0, 2 pi).
fn ccw_angle(u: vec2<f32>, v: vec2<f32>) -> f32 {
    let a = atan2(u.x * v.y - u.y * v.x, dot(u, v));
    return select(a, a + 2.0 * PI, a < 0.0);
}

// The fraction of the unit disk in both half-planes {a1.x >= c1} and
// {a2.x >= c2} (a1, a2 unit). Where the two lines cross inside the disk
// at X, the region is the triangle X P1 P2 and the circular segment beyond
// P1 P2, Pi the end of line i's chord on the other half-plane's side;
// otherwise the chords split the disk into three parts and the region is
// one of them, the smaller segment, or empty.
fn half_planes_fraction(a1: vec2<f32>, c1: f32, a2: vec2<f32>, c2: f32) -> f32 {
    // Each half-plane's own fraction: Eq. 4.1 in units of the radius.
    let k1 = disk_fraction(c1, 1.0);
    let k2 = disk_fraction(c2, 1.0);
    // A half-plane holding the whole disk (or none of it) leaves the other's fraction (or none).
    if (c1 <= -1.0 || c2 >= 1.0) {
        return select(k2, 0.0, c2 >= 1.0 || c1 >= 1.0);
    }
    if (c2 <= -1.0 || c1 >= 1.0) {
        return select(k1, 0.0, c1 >= 1.0);
    }
    let det = a1.x * a2.y - a1.y * a2.x;
    // |det| >= 1e-6: X within 1e6 of the centre, so |X| is finite; nearer
    // parallel the lines cross (if at all) far outside the disk.
    if (abs(det) >= 1e-6) {
        let x = vec2<f32>(c1 * a2.y - c2 * a1.y, a1.x * c2 - a2.x * c1) / det;
        if (dot(x, x) < 1.0) {
            // Along line 1 towards half-plane 2, and along line 2 towards half-plane 1.
            var d1 = vec2<f32>(-a1.y, a1.x);
            d1 = select(d1, -d1, dot(a2, d1) < 0.0);
            var d2 = vec2<f32>(-a2.y, a2.x);
            d2 = select(d2, -d2, dot(a1, d2) < 0.0);
            // |x| < 1: each root is real and positive.
            let b1 = dot(x, d1);
            let b2 = dot(x, d2);
            let q = 1.0 - dot(x, x);
            let p1 = x + d1 * (-b1 + sqrt(b1 * b1 + q));
            let p2 = x + d2 * (-b2 + sqrt(b2 * b2 + q));
            let twice = (p1.x - x.x) * (p2.y - x.y) - (p1.y - x.y) * (p2.x - x.x);
            // The arc bounding the region runs from P1 to P2 the way X, P1, P2 turn.
            let u1 = p1 / max(length(p1), 1e-20);
            let u2 = p2 / max(length(p2), 1e-20);
            let phi = select(ccw_angle(u2, u1), ccw_angle(u1, u2), twice >= 0.0);
            return clamp((abs(twice) + phi - sin(phi)) / (2.0 * PI), 0.0, min(k1, k2));
        }
    }
    // The chords do not cross in the disk: each lies wholly on one side of
    // the other's line (its midpoint c a says which).
    let one_in_two = dot(a2, c1 * a1) >= c2;
    let two_in_one = dot(a1, c2 * a2) >= c1;
    if (one_in_two && two_in_one) {
        return max(k1 + k2 - 1.0, 0.0);
    }
    if (one_in_two) {
        return k1;
    }
    if (two_in_one) {
        return k2;
    }
    return 0.0;
}

// Beyond 4.2 (edges = "two", issue 28): the light that two silhouette
// edges A and B leave a receiver p in both their penumbrae. Each edge's
// cutting plane cuts the light's disk (seen from p) into a lit side of
// Eq. 4.1's fraction k and an occluded side; one edge alone takes the
// occluder for a half-plane, too dark where it is thinner than the light
// and too light where a second caster also hides part of it.
// Where A and B lie on one surface (h0.w: its component, pvm/geometry.rs),
// each on the other's occluder side, with no occluder nearer than p just
// past either (the shadow map), the occluder lies between them (a shadow
// thinner than the light, a convex corner) and hides what both hide: p
// sees the union of the lit sides. Otherwise A alone decides, as 4.2.
// (Edges of two surfaces, p seeing the intersection of the lit sides, was
// measured too: better on the 40 scenes of the generated suite, much worse
// on two of its slow suite's 60: an aeroplane's separate wing and body
// surfaces, each thin, taken for two half-planes.)
fn two_edge_visibility(p: vec3<f32>, depth: f32, a: EdgePoints, b: EdgePoints) -> f32 {
    let r = pvm.center.w;
    let l = pvm.center.xyz;
    let ca = cutting_plane(p, a.h0.xyz, a.h1.xyz);
    let cb = cutting_plane(p, b.h0.xyz, b.h1.xyz);
    let ka = disk_fraction(ca.s, r);
    let between = a.h0.w == b.h0.w && on_occluder_side(a, b, l) && on_occluder_side(b, a, l) && !covered(a, depth) && !covered(b, depth);
    if (!between) {
        return ka;
    }
    // The light's disk as p sees it, its lines the cutting planes' traces,
    // the lit sides towards each n.
    let disk = disk_axes(pvm, p);
    let pa = vec2<f32>(dot(ca.n, disk.e1), dot(ca.n, disk.e2));
    let pb = vec2<f32>(dot(cb.n, disk.e1), dot(cb.n, disk.e2));
    // A cutting plane nearly parallel to w has no trace on the disk to speak
    // of (n = 0 too where p lies on an edge's line): A alone decides.
    if (dot(pa, pa) < 1e-6 || dot(pb, pb) < 1e-6) {
        return ka;
    }
    // Offsets in units of r, as Eq. 4.1's (the traces' normals are within
    // s/|l - p| of unit length).
    let both = half_planes_fraction(normalize(pa), ca.s / r, normalize(pb), cb.s / r);
    return clamp(ka + disk_fraction(cb.s, r) - both, 0.0, 1.0);
}

// edges = "chain" (beyond 4.2, issue 28): how many edges the walk takes
// each way along a silhouette loop from the pixel's edge.
const CHAIN_STEPS: i32 = 64;

// The light's disk as a receiver p sees it: a point v (in front of p,
// (v - p).w >= zmin) is seen on it where the ray from p through v meets
// the plane through the light's centre perpendicular to w, at
// (v - p) dist / z; in units of the radius about the centre.
struct DiskView {
    p: vec3<f32>,
    w: vec3<f32>,
    e1: vec3<f32>,
    e2: vec3<f32>,
    // |l - p| / r and |l - p| / 1e4: points nearer p's plane are clipped.
    scale: f32,
    zmin: f32,
};

// The segment a-b seen on the disk, clipped to z >= zmin (ok: some of it
// is in front of p; cut_a, cut: its end a or b was clipped, so the loop
// does not go on from there on the disk).
struct SeenSegment {
    ok: bool,
    cut_a: bool,
    cut: bool,
    a: vec2<f32>,
    b: vec2<f32>,
};

fn seen_segment(view: DiskView, a: vec3<f32>, b: vec3<f32>) -> SeenSegment {
    var va = a - view.p;
    var vb = b - view.p;
    let za = dot(va, view.w);
    let zb = dot(vb, view.w);
    if (za < view.zmin && zb < view.zmin) {
        return SeenSegment(false, true, true, vec2<f32>(0.0), vec2<f32>(0.0));
    }
    // One end behind the clip plane: za != zb, so the division is finite.
    if (za < view.zmin) {
        va = va + (vb - va) * ((view.zmin - za) / (zb - za));
    }
    if (zb < view.zmin) {
        vb = vb + (va - vb) * ((view.zmin - zb) / (za - zb));
    }
    // z >= zmin > 0 after clipping.
    let fa = view.scale / max(dot(va, view.w), view.zmin);
    let fb = view.scale / max(dot(vb, view.w), view.zmin);
    return SeenSegment(true, za < view.zmin, zb < view.zmin, vec2<f32>(dot(va, view.e1), dot(va, view.e2)) * fa, vec2<f32>(dot(vb, view.e1), dot(vb, view.e2)) * fb);
}

fn cross2(u: vec2<f32>, v: vec2<f32>) -> f32 {
    return u.x * v.y - u.y * v.x;
}

// The signed angle from u to v (0 where either is zero).
fn turn(u: vec2<f32>, v: vec2<f32>) -> f32 {
    let c = cross2(u, v);
    let d = dot(u, v);
    return select(atan2(c, d), 0.0, c == 0.0 && d == 0.0);
}

// The signed area of the unit disk within the triangle (0, a, b): the
// segment's part inside the disk (between its crossings of the circle at
// distance sqrt(1 - h^2) either side of its point nearest the centre) adds
// its triangle, the parts outside their sectors. Summed over a closed
// path, the area of the disk the path encloses (counter-clockwise positive).
fn disk_in_triangle(a: vec2<f32>, b: vec2<f32>) -> f32 {
    let d = b - a;
    let len = length(d);
    if (!(len > 0.0)) {
        return 0.0;
    }
    let u = d / len;
    // h: the line's distance from the centre; along: a's foot along u.
    let h = cross2(a, u);
    let along = -dot(a, u);
    var t1 = len;
    var t2 = len;
    if (abs(h) < 1.0) {
        let half = sqrt(1.0 - h * h);
        t1 = clamp(along - half, 0.0, len);
        t2 = clamp(along + half, 0.0, len);
    }
    let p1 = a + u * t1;
    let p2 = a + u * t2;
    return 0.5 * (turn(a, p1) + cross2(p1, p2) + turn(p2, b));
}

// Whether the ray from q along unit d (or q itself) reaches the unit disk.
fn ray_meets_disk(q: vec2<f32>, d: vec2<f32>) -> bool {
    return dot(q, q) <= 1.0 || (dot(q, d) < 0.0 && abs(cross2(q, d)) < 1.0);
}

fn unit2(v: vec2<f32>) -> vec2<f32> {
    let len = length(v);
    return select(vec2<f32>(0.0), v / len, len > 0.0);
}

// One way of `chain_visibility`'s walk along a silhouette loop: where it
// ended on the disk and the direction it went on in, the sums of
// `disk_in_triangle` and `turn` along it (in the walk's direction), the
// last edge taken, and whether it came round to the edge it was to stop at.
struct Walk {
    end: vec2<f32>,
    dir: vec2<f32>,
    area: f32,
    swept: f32,
    last: u32,
    closed: bool,
};

// Walks from the point `start` (going on in `dir`) along the loop, edge
// link `link` (index + 1) first, through `links.y` (forward: each edge from
// h0 to h1) or `links.x` (backward: from h1 to h0), while the path can still
// reach the disk, at most CHAIN_STEPS edges; closed on reaching edge `stop`.
// `open`: the start was clipped behind p, so the loop does not go on there.
fn walk_loop(view: DiskView, link: u32, forward: bool, stop: u32, start: vec2<f32>, dir: vec2<f32>, open: bool) -> Walk {
    var w = Walk(start, dir, 0.0, 0.0, stop, false);
    if (open) {
        return w;
    }
    let count = arrayLength(&edges);
    var j = link;
    for (var step = 0; step < CHAIN_STEPS && j != 0u; step++) {
        if (j - 1u == stop) {
            w.closed = true;
            break;
        }
        if (!ray_meets_disk(w.end, w.dir)) {
            break;
        }
        let f = edges[min(j - 1u, count - 1u)];
        let seen = seen_segment(view, select(f.h1.xyz, f.h0.xyz, forward), select(f.h0.xyz, f.h1.xyz, forward));
        if (!seen.ok) {
            break;
        }
        w.area += disk_in_triangle(w.end, seen.b);
        w.swept += turn(w.end, seen.b);
        let d = unit2(seen.b - w.end);
        w.dir = select(w.dir, d, dot(d, d) > 0.0);
        w.end = seen.b;
        w.last = j - 1u;
        if (seen.cut) {
            break;
        }
        j = select(f.links.x, f.links.y, forward);
    }
    return w;
}

// edges = "chain" (beyond 4.2, issue 28): the light that silhouette edge e
// (at `index`) and its silhouette loop leave receiver p. 4.2 takes e for a
// half-plane: where the occluder's outline turns within the light's disk
// as p sees it (a box's corner, an L's inner corner, a leg), that
// half-plane hides too much or too little. Here the loop is seen on the
// disk from p and walked from e both ways (`links`) while the path can
// still reach the disk, at most CHAIN_STEPS edges each way; its open ends
// go on as rays along their last edges. The occluded part is the disk on
// the occluder's side of that path: the sum of `disk_in_triangle` over its
// segments, closed at infinity counter-clockwise (Green's theorem on the
// fan from the centre); a loop walked all round is closed. One edge alone
// gives Eq. 4.1's half-plane (on the disk facing p rather than the cutting
// plane). The rest of the scene is left out, as 4.2 leaves it.
// It returns -1 where the walk cannot decide, and the k of 4.2 (or of
// edges = "two") stays: where the walk stops while the loop could still
// reach the disk (a junction, an edge behind p, the step bound), or its
// path disagrees with the shadow map at the light's centre (`centre_lit`):
// another part of the scene decides there, not this loop.
fn chain_visibility(p: vec3<f32>, index: u32, centre_lit: bool) -> f32 {
    let r = pvm.center.w;
    let l = pvm.center.xyz;
    let e = edges[index];
    let cut = cutting_plane(p, e.h0.xyz, e.h1.xyz);
    if (!(r > 0.0) || dot(cut.n, cut.n) == 0.0) {
        return -1.0;
    }
    let axes = disk_axes(pvm, p);
    let w = unit(l - p);
    // No surface touches the light: dist > r > 0.
    let dist = dot(l - p, w);
    let view = DiskView(p, w, axes.e1, axes.e2, dist / r, dist * 1e-4);
    let first = seen_segment(view, e.h0.xyz, e.h1.xyz);
    let dir = unit2(first.b - first.a);
    if (!first.ok || dot(dir, dir) == 0.0) {
        return -1.0;
    }
    // The lit side of e's trace on the disk: its cutting plane's normal.
    let lit = vec2<f32>(dot(cut.n, axes.e1), dot(cut.n, axes.e2));
    if (dot(lit, lit) < 1e-12) {
        return -1.0;
    }
    let lit_left = cross2(dir, lit) > 0.0;
    var area = disk_in_triangle(first.a, first.b);
    // The angle the path sweeps about the disk's centre: with its closure,
    // 2 pi times its winding number there.
    var swept = turn(first.a, first.b);
    // Forward from h1, then backward from h0 until the walk meets the forward one.
    let ahead = walk_loop(view, e.links.y, true, index, first.b, dir, first.cut);
    var back = Walk(first.a, -dir, 0.0, 0.0, index, ahead.closed);
    if (!ahead.closed) {
        back = walk_loop(view, e.links.x, false, ahead.last, first.a, -dir, first.cut_a);
    }
    let closed = back.closed;
    let tail = ahead.end;
    let tail_dir = ahead.dir;
    let head = back.end;
    let head_dir = back.dir;
    // Walked backwards, the path runs the other way: its terms change sign.
    area += ahead.area - back.area;
    swept += ahead.swept - back.swept;
    // A walk that ends where the loop could still reach the disk leaves
    // the occluder's outline unknown there.
    if (!closed && (ray_meets_disk(tail, tail_dir) || ray_meets_disk(head, head_dir))) {
        return -1.0;
    }
    if (!closed) {
        // The open ends go on along their last edges, out of the disk
        // (beyond |q| + 2 a ray stays 2 from the centre), and the path
        // closes at infinity counter-clockwise from its end to its start.
        let far_tail = tail + tail_dir * (length(tail) + 2.0);
        let far_head = head + head_dir * (length(head) + 2.0);
        area += disk_in_triangle(tail, far_tail) + disk_in_triangle(far_head, head);
        let around = ccw_angle(unit2(far_tail), unit2(far_head));
        area += 0.5 * around;
        swept += turn(tail, far_tail) + turn(far_head, head) + around;
    }
    // |area| and |swept| are a few pi for any path of finite points; the
    // guard keeps an overflow (coordinates beyond about 1e18 radii) out.
    if (!(abs(area) < 1e6 && abs(swept) < 1e6)) {
        return -1.0;
    }
    // The path's left side, in units of the disk's area; a loop walked all
    // round turning clockwise has the disk outside it on its left.
    let left = clamp(select(area, area + PI, closed && area < 0.0) / PI, 0.0, 1.0);
    // The centre lies on the path's left where the closed path winds once
    // round it (a clockwise loop: where it does not wind round it).
    let winding = i32(round(swept / (2.0 * PI)));
    let centre_left = winding == 1 || (closed && area < 0.0 && winding == 0);
    if ((centre_left == lit_left) != centre_lit) {
        return -1.0;
    }
    return select(1.0 - left, left, lit_left);
}

// How far past an edge `covered` looks, in radii of the light's disk as the
// receiver sees it at the edge's depth: half of it.
const PAST_EDGE: f32 = 0.5;

// Whether the shadow map says an occluder nearer the light than the
// receiver (at light depth `depth`) lies just past edge e's midpoint on its
// lit side: PAST_EDGE of the light's disk seen from the receiver, at least
// 3 texels, away from the edge.
fn covered(e: EdgePoints, depth: f32) -> bool {
    let mid = 0.5 * (e.h0.xyz + e.h1.xyz);
    let out = hard_normal(e);
    let d_e = light_view_depth(pvm.light_space, mid);
    let seen = pvm.center.w * max(depth - d_e, 0.0) / max(depth, 1e-30);
    let q = mid + out * max(3.0 * light_texel_size(pvm.light_space, d_e), PAST_EDGE * seen);
    return map_depth(pvm, shadow_map, q) < depth;
}

// The unit normal of edge e's hard-shadow plane (through the edge and the
// light's centre), away from its occluder: the orientation of silhouette.rs.
// Edges pointing at the light have no volume, so the cross is non-zero.
fn hard_normal(e: EdgePoints) -> vec3<f32> {
    return unit(cross(unit(e.h1.xyz - e.h0.xyz), unit(e.h0.xyz - pvm.center.xyz)));
}

// Whether the midpoint of edge b lies on the occluder's side of edge a's hard-shadow plane.
fn on_occluder_side(a: EdgePoints, b: EdgePoints, l: vec3<f32>) -> bool {
    return dot(hard_normal(a), 0.5 * (b.h0.xyz + b.h1.xyz) - a.h0.xyz) < 0.0;
}

// How far (in k) a volume's visibility may disagree with the shadow-map test
// at the light's centre before the volume is taken for another edge's: the
// test and the volume map are rasterised separately, so within a texel or
// two of the hard-shadow boundary they disagree by design.
const CENTRE_TOLERANCE: f32 = 0.1;

// Whether edge e's k for receiver p (light depth `depth`) agrees with the
// shadow map's test at the light's centre (repair "centre"): within
// CENTRE_TOLERANCE, or p within the band where the map's raster and its
// normal offset move the hard-shadow boundary: 2 texels and the offset at
// p's depth from e's hard-shadow plane. Under a penumbra a few texels wide
// k crosses from 0 to 1 within that band, and a tolerance in k alone
// rejects the right edge (a bar under a light of radius 0.05 on a 256
// map: every penumbra pixel given the hard test).
fn agrees_with_centre(k: f32, centre_lit: bool, p: vec3<f32>, e: EdgePoints, depth: f32) -> bool {
    if (select(k <= 0.5 + CENTRE_TOLERANCE, k >= 0.5 - CENTRE_TOLERANCE, centre_lit)) {
        return true;
    }
    let band = (2.0 + max(pvm.bias.x, 0.0)) * light_texel_size(pvm.light_space, depth);
    return abs(dot(hard_normal(e), p - e.h0.xyz)) <= band;
}

// What the volume map holds at one texel for receiver p (light depth
// `depth`): whether a volume there is nearer the light than p (listing 4.2),
// whether that edge's penumbra holds p (0 < k < 1) with k agreeing with the
// shadow map's test at the light's centre where repair "centre" asks it,
// whether k agrees so, the edge's index, Eq. 4.1's k for p and the volume's depth.
struct VolumeHit {
    inside: bool,
    holds: bool,
    agrees: bool,
    index: u32,
    k: f32,
    depth: f32,
};

fn volume_at(p: vec3<f32>, depth: f32, t: vec2<i32>, layer: i32, centre_lit: bool) -> VolumeHit {
    var d = pvm.light_space.depth.y;
    if (layer_active(pvm.light_space, layer)) {
        d = textureLoad(volume_depth, t, layer, 0) * pvm.light_space.depth.y;
    }
    if (!(d < depth)) {
        return VolumeHit(false, false, false, 0u, 0.0, d);
    }
    // The depth map and the index map are written together: a texel
    // behind a volume holds an index (clamped all the same).
    let index = min(max(textureLoad(edge_index, t, layer, 0).x, 1u) - 1u, arrayLength(&edges) - 1u);
    let edge = edges[index];
    let k = volume_visibility(p, edge.h0.xyz, edge.h1.xyz);
    let agrees = agrees_with_centre(k, centre_lit, p, edge, depth);
    let holds = k > 0.0 && k < 1.0 && ((pvm.mode.y & 2u) == 0u || agrees);
    return VolumeHit(true, holds, agrees, index, k, d);
}

// umbra_test = "rim" (beyond 4.2): whether the light's rim is hidden from
// p (at light depth `depth`) as its centre is (by a surface at light depth
// d_s, the shadow map's at p's texel): the rays from p to 8 points of the
// rim, followed against the map from d_s (`ray_hidden`). 4.2 takes the
// nearest volume's edge for a half-plane and leaves p the light on its lit
// side; where another part hides that side too (a teapot's knob over its
// body: the body's umbra lit to 1/2), p is in the umbra.
fn rim_hidden(p: vec3<f32>, depth: f32, d_s: f32) -> bool {
    let l = pvm.center.xyz;
    let r = pvm.center.w;
    // The map resolves the rim only where the light, seen from p, spans
    // more than 2 of its texels at d_s (the settling tolerance of
    // `ray_hidden`): a penumbra narrower than that lies within the texels
    // of the centre's occluder, whose rim rays then read as hidden (a bar
    // under a light of radius 0.05 on a 128 map). There the test keeps
    // Eq. 4.1's k.
    if (r * (depth - d_s) < 2.0 * light_texel_size(pvm.light_space, d_s) * depth) {
        return false;
    }
    let disk = disk_axes(pvm, p);
    for (var i = 0; i < 8; i++) {
        let a = f32(i) * (PI / 4.0);
        if (!ray_hidden(pvm, shadow_map, p, depth, d_s, l + r * (cos(a) * disk.e1 + sin(a) * disk.e2))) {
            return false;
        }
    }
    return true;
}

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    let px = pixel.px;
    var v = 0.0;
    var inside = 0.0;
    if (pixel.geometry) {
        let p = pixel.p;
        let n = pixel.n;
        let cos_theta = light_cosine(pvm, p, n);
        let r = pvm.center.w;
        let horizon = (pvm.mode.y & 4u) != 0u && r > 0.0;
        // Repair "horizon" (beyond the paper, which takes the light's centre
        // for the surface's horizon test): the fraction of the light above
        // the receiver's tangent plane, by Eq. 4.1 with that plane as the
        // cutting plane. It bounds the visibility; a receiver whose centre
        // lies below its horizon sees that fraction of the light, unless the
        // object map says another object than its own hides the centre
        // (`horizon_sliver_seen`).
        var k_h = 1.0;
        if (horizon) {
            k_h = horizon_fraction(pvm, p, n);
        }
        // Centre below the surface's horizon: the surface itself hides it
        // (and only the horizon's sliver of the light can be seen).
        if (cos_theta > 0.0) {
            let q = biased_receiver(pvm, p, n, cos_theta);
            let centre_depth = map_depth(pvm, shadow_map, q.xyz);
            let centre_lit = q.w <= centre_depth;
            v = select(0.0, 1.0, centre_lit);
            // Listing 4.2: in a volume when the PVDM is nearer the light than the pixel.
            let dims = textureDimensions(edge_index);
            let m = map_point_in(pvm.light_space, light_map_point(pvm.light_space, q.xyz), dims);
            var t = map_texel(dims, m);
            var hit = volume_at(p, q.w, t, m.layer, centre_lit);
            // lookup = "3x3" (beyond 4.2): where p's own texel holds no
            // volume whose edge's penumbra holds p, the volume map (a
            // rasterisation at texel centres) may have missed one narrower
            // than a texel; the neighbour texels' volumes nearest the light
            // whose penumbra holds p decide instead.
            if ((pvm.mode.y & 16u) != 0u && !hit.holds) {
                var best = VolumeHit(false, false, false, 0u, 0.0, q.w);
                for (var dy = -1; dy <= 1; dy++) {
                    for (var dx = -1; dx <= 1; dx++) {
                        let n = clamp(t + vec2<i32>(dx, dy), vec2<i32>(0), vec2<i32>(dims) - 1);
                        let h = volume_at(p, q.w, n, m.layer, centre_lit);
                        if (h.holds && h.depth < best.depth) {
                            best = h;
                            t = n;
                        }
                    }
                }
                if (best.holds) {
                    hit = best;
                }
            }
            if (hit.inside) {
                let index = hit.index;
                let edge = edges[index];
                var k = hit.k;
                // map_control: k is still the nearest edge's half-plane
                // fraction (Eq. 4.1), the model the rays are compared with.
                var half_plane = (pvm.mode.y & 256u) != 0u;
                let agrees = hit.agrees;
                if ((pvm.mode.y & 8u) != 0u && ((pvm.mode.y & 2u) == 0u || agrees) && k > 0.0 && k < 1.0) {
                    // edges = "two": the volume farthest from the light at this
                    // texel, where its edge is another, lies between the light
                    // and p (the farthest volume may start beyond p: its edge
                    // then hides nothing from p, whatever its cut says), and p
                    // is in its penumbra too.
                    let far = textureLoad(far_edge_index, t, m.layer, 0).x;
                    if (far > 0u && min(far - 1u, arrayLength(&edges) - 1u) != index) {
                        let other = edges[min(far - 1u, arrayLength(&edges) - 1u)];
                        let kb = volume_visibility(p, other.h0.xyz, other.h1.xyz);
                        let nearer = max(light_view_depth(pvm.light_space, other.h0.xyz), light_view_depth(pvm.light_space, other.h1.xyz)) < q.w;
                        if (nearer && kb > 0.0 && kb < 1.0) {
                            k = two_edge_visibility(p, q.w, edge, other);
                            half_plane = half_plane && k == hit.k;
                        }
                    }
                }
                // edges = "chain": the edge's loop decides, not its half-plane,
                // where the map sees the light's centre. Where it hides it, a
                // loop that leaves p much of the light is often wrong: other
                // parts of the mesh hide it too (a boot's sole under its leg,
                // generated seed 38: 1.3% of its pixels lit in the umbra), and
                // the two edges or 4.2's half-plane decide there.
                if ((pvm.mode.y & 64u) != 0u && ((pvm.mode.y & 2u) == 0u || agrees) && hit.k > 0.0 && hit.k < 1.0 && centre_lit) {
                    atomicAdd(&counters[1], 1u);
                    let chain = chain_visibility(p, index, centre_lit);
                    if (chain >= 0.0) {
                        k = chain;
                        half_plane = false;
                        atomicAdd(&counters[2], 1u);
                    }
                }
                // umbra_test = "rim" (beyond 4.2): the centre and the rim hidden, p is in the umbra.
                if ((pvm.mode.y & 32u) != 0u && !centre_lit && k > 0.0 && rim_hidden(p, q.w, centre_depth)) {
                    k = 0.0;
                }
                if ((pvm.mode.y & 2u) == 0u || agrees) {
                    if ((pvm.mode.y & 1u) != 0u) {
                        // Parker et al.'s sinusoidal falloff, as the Bernstein interpolant (4.2).
                        k = k * k * (3.0 - 2.0 * k);
                        half_plane = false;
                    }
                    // map_samples (beyond 4.2): at most what the map's rays
                    // leave seen, and with map_bound = "both", where the map
                    // sees the centre, at least that. Their search starts at
                    // the surface hiding the centre, or where the centre is
                    // seen at the edge.
                    let lower = (pvm.mode.y & 128u) != 0u && (centre_lit || ((pvm.mode.y & 512u) != 0u && solid_in_front(pvm, q.xyz, centre_depth)));
                    if (pvm.mode.z > 0u && (k > map_margin(pvm.mode.z) || lower)) {
                        let edge_depth = light_view_depth(pvm.light_space, 0.5 * (edge.h0.xyz + edge.h1.xyz));
                        var d_start = centre_depth;
                        if (centre_lit) {
                            d_start = edge_depth;
                        }
                        // Points x on the lit side of the edge's cutting plane:
                        // dot(n, x) > dot(n, h0) (n = 0 where p lies on the
                        // edge's line: no model).
                        let cut = cutting_plane(p, edge.h0.xyz, edge.h1.xyz);
                        let model = vec4<f32>(cut.n, dot(cut.n, edge.h0.xyz));
                        let bounded = map_bound(pvm, shadow_map, p, q.w, d_start, pvm.mode.z, k, lower, pvm.mode.w, model, edge_depth, half_plane && dot(cut.n, cut.n) > 0.5);
                        if (bounded < k) {
                            atomicAdd(&counters[3], 1u);
                        } else if (bounded > k) {
                            atomicAdd(&counters[4], 1u);
                        }
                        k = bounded;
                    }
                    v = k;
                }
                inside = 1.0;
                atomicAdd(&counters[0], 1u);
            }
            if (horizon) {
                v = min(v, k_h);
            }
        } else if (horizon) {
            let own = mesh_objects[min(u32(pixel.normal_texel.w), arrayLength(&mesh_objects) - 1u)];
            v = select(0.0, k_h, horizon_sliver_seen(pvm, object_map, p, own));
        }
    }
    textureStore(visibility_out, px, vec4<f32>(v, 0.0, 0.0, 0.0));
    textureStore(membership_out, px, vec4<f32>(inside, 0.0, 0.0, 0.0));
}
