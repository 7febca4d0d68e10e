#import shaders/receiver.wgsl
#import passes/shadow_test.wgsl
#import passes/map_rays.wgsl
#import shaders/per_pixel.wgsl

// Method `wedges` (Akenine-Möller & Assarsson 2002): light intensity per
// camera pixel. The hard shadow from the light centre (the shadow map of
// `hard`) stands for the shadow-volume count; every penumbra wedge that
// holds the pixel's point p then adds s(p) - h(p) to the light-intensity
// sum, where s is the interpolated intensity of 4.2 (Eq. 1-3) and h the
// hard shadow that wedge's shadow-volume quad gives p (1 on its lit side,
// 0 behind it). That is the paper's per-wedge term s(p_i) - s(p_f) with the
// quad's own step subtracted: the entry and exit terms of wedges the camera
// ray crosses sum to the shadow-volume count, which the map already holds.
// The sum is clamped to [0, 1] (4, after the pseudocode).

struct Wedge {
    a: vec4<f32>,
    b: vec4<f32>,
    dir: vec4<f32>,
    front: vec4<f32>,
    back: vec4<f32>,
    hard: vec4<f32>,
    left: vec4<f32>,
    right: vec4<f32>,
    u_left: vec4<f32>,
    u_right: vec4<f32>,
};

struct WedgeSettings {
    // x: tile size in pixels; y: tiles per row; z: flags (bit 0: falloff,
    // bit 1: repair "horizon", bit 2: hard_term "lit_side", bit 3: intensity
    // "coverage", bit 4: overlap "gate", bit 5: occluders "independent",
    // bit 6: map_bound "both"); w: wedge count. wedge_test.mode.z: map_samples;
    // wedge_test.mode.w: map_march.
    tiles: vec4<u32>,
};

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
@group(0) @binding(3) var<storage, read> wedge_test: ShadowTest;
@group(0) @binding(4) var<storage, read> wedges: array<Wedge>;
@group(0) @binding(5) var<storage, read> tile_offsets: array<u32>;
@group(0) @binding(6) var<storage, read> tile_wedges: array<u32>;
@group(0) @binding(7) var<storage, read> settings: WedgeSettings;
@group(0) @binding(8) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(9) var hard_out: texture_storage_2d<r32float, write>;
@group(0) @binding(10) var intensity_out: texture_storage_2d<r32float, write>;
// pixels_in_wedge, map_bounded_pixels, map_raised_pixels (COUNTER_NAMES in mod.rs).
@group(0) @binding(11) var<storage, read_write> counters: array<atomic<u32>, 3>;
// The object map and each mesh's object (passes/object_map.rs), for the horizon repair.
@group(0) @binding(12) var object_map: texture_2d_array<u32>;
@group(0) @binding(13) var<storage, read> mesh_objects: array<u32>;
// Per entry of tile_wedges and quarter of its tile: 0 where the tile cull
// (tile_cull.wgsl) found the wedge holds no pixel of that quarter (its term
// is zero at every one).
@group(0) @binding(14) var<storage, read> tile_keep: array<u32>;

// Eq. 1-2 along the side ray u: p's distances to the front plane (F <= 0
// inside) and the back plane (B >= 0 inside), as fractions of the chord.
// The ray meets the front plane ahead (N_f.u > 0) and the back plane behind
// (N_b.u > 0) for any light smaller than its distance; the floors keep the
// quotient finite otherwise, and a point on the edge's line takes 1/2.
fn side_intensity(f: f32, b: f32, w: Wedge, u: vec3<f32>) -> f32 {
    let tf = -f / max(dot(w.front.xyz, u), 1e-6);
    let tb = b / max(dot(w.back.xyz, u), 1e-6);
    let sum = tf + tb;
    if (sum <= 0.0) {
        return 0.5;
    }
    return clamp(tb / sum, 0.0, 1.0);
}

// The contribution s(p) - h(p) of wedge w at p, or none (x = 0 flag in y).
fn wedge_term(w: Wedge, p: vec3<f32>) -> vec2<f32> {
    let pa = p - w.a.xyz;
    let f = dot(w.front.xyz, pa);
    if (f > 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let b = dot(w.back.xyz, pa);
    if (b < 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let tl_plane = dot(w.left.xyz, pa);
    if (tl_plane < 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let tr_plane = dot(w.right.xyz, p - w.b.xyz);
    if (tr_plane < 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    // Eq. 2 in each side plane, then Eq. 3 along the edge's direction.
    let s_l = side_intensity(f, b, w, w.u_left.xyz);
    let s_r = side_intensity(f, b, w, w.u_right.xyz);
    let t_l = tl_plane / max(dot(w.left.xyz, w.dir.xyz), 1e-6);
    let t_r = tr_plane / max(-dot(w.right.xyz, w.dir.xyz), 1e-6);
    var s = 0.5 * (s_l + s_r);
    if (t_l + t_r > 0.0) {
        s = (t_r * s_l + t_l * s_r) / (t_l + t_r);
    }
    if ((settings.tiles.z & 1u) != 0u) {
        // Parker et al.'s sinusoidal attenuation, s' = 3s^2 - 2s^3 (4.2).
        s = s * s * (3.0 - 2.0 * s);
    }
    // h: the quad's step, or 1 where the map is read on every quad's lit side.
    let h = select(0.0, 1.0, dot(w.hard.xyz, pa) > 0.0 || (settings.tiles.z & 4u) != 0u);
    return vec2<f32>(s - h, 1.0);
}

// The area of the part of the unit disk beyond the segment p-q, inside the
// sector between the directions of p and q: the sector between the ends
// x0, x1 of the segment's part inside the disk less the triangle (0, x0,
// x1). Equal to |sector(p, q) - (the disk's part of the triangle (0, p,
// q))|, whose sector angles along the segment add up (the segment misses 0
// or the area is 0), with one atan2 instead of three. 0 where the segment
// misses the disk.
fn beyond_segment(p: vec2<f32>, q: vec2<f32>) -> f32 {
    let e = q - p;
    let qa = dot(e, e);
    let qb = 2.0 * dot(p, e);
    let qc = dot(p, p) - 1.0;
    let disc = qb * qb - 4.0 * qa * qc;
    // qa > 0 here (the caller drops degenerate projections), so the roots are finite.
    if (qa <= 0.0 || disc <= 0.0) {
        return 0.0;
    }
    let root = sqrt(disc);
    let t0 = max((-qb - root) / (2.0 * qa), 0.0);
    let t1 = min((-qb + root) / (2.0 * qa), 1.0);
    if (t0 >= t1) {
        return 0.0;
    }
    let x0 = p + e * t0;
    let x1 = p + e * t1;
    return abs(sector_area(x0, x1) - 0.5 * cross2(x0, x1));
}

fn cross2(x: vec2<f32>, y: vec2<f32>) -> f32 {
    return x.x * y.y - x.y * y.x;
}

// The signed area of the unit disk's sector from direction x to direction y
// (atan2 is defined for the zero vector too: the sector is then empty).
fn sector_area(x: vec2<f32>, y: vec2<f32>) -> f32 {
    return 0.5 * atan2(cross2(x, y), dot(x, y));
}

// The light's disk as pixel p sees it, the same for every wedge at p.
struct Disk {
    // The unit direction from p to the light's centre, and its distance.
    z: vec3<f32>,
    dist: f32,
    // Axes of the plane through the centre facing p, and the tangent
    // cone's radius there (0 when p is inside or on the light: nothing to
    // project).
    e1: vec3<f32>,
    radius: f32,
    e2: vec3<f32>,
    // c - p.
    axis: vec3<f32>,
};

fn light_disk(p: vec3<f32>, c: vec3<f32>, r: f32) -> Disk {
    let axis = c - p;
    let dist = length(axis);
    if (dist <= r * 1.0001) {
        return Disk(vec3<f32>(0.0, 0.0, 1.0), dist, vec3<f32>(1.0, 0.0, 0.0), 0.0, vec3<f32>(0.0, 1.0, 0.0), axis);
    }
    let z = axis / dist;
    // dist > r * 1.0001: the root is positive.
    let radius = r * dist / sqrt(dist * dist - r * r);
    let e1 = normalize(select(vec3<f32>(0.0, -z.z, z.y), vec3<f32>(-z.y, z.x, 0.0), abs(z.z) < 0.9));
    return Disk(z, dist, e1, radius, cross(z, e1), axis);
}

// Per-pixel coverage (Assarsson & Akenine-Möller 2003, the visibility of a
// point from the silhouette edges projected onto the light; geometry.rs's
// `coverage_term` is the f64 twin): wedge `index`'s edge, clipped to the part in
// front of p, is projected from p onto the plane through the light's centre
// c facing p, where the light is a disk (the tangent cone's radius there).
// The part of the disk inside the projected edge's angular sector about c
// and beyond the edge is the fraction this edge changes from the hard
// shadow's value: light seen past it when p is behind the quad (h = 0),
// hidden by it when in front (h = 1). Returns s - h and whether the
// projected edge meets the disk (y = 1). Summed over a closed loop with the
// hard shadow, the terms give the disk's covered fraction exactly (the fan
// of the projected polygon about c); there is no interpolation.
fn coverage_term(index: u32, p: vec3<f32>, disk: Disk) -> vec2<f32> {
    // p inside (or on) the light: nothing to project.
    if (disk.radius <= 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let z = disk.z;
    let dist = disk.dist;
    let axis = disk.axis;
    let eps = 1e-4 * dist;
    var a = wedges[index].a.xyz;
    var b = wedges[index].b.xyz;
    var da = dot(a - p, z);
    var db = dot(b - p, z);
    // Only the part of the edge between p and the light's plane (the
    // disk's, at depth dist) can hide the light from p: an edge (or its
    // part) beyond it, a silhouette with the light between it and p, hides
    // nothing (beyond the 2003 paper's projection, which has every edge in
    // front of the light; here a receiver beyond the light, as a room's
    // wall behind a light beside a block, took half the light off).
    if ((da < eps && db < eps) || (da > dist && db > dist)) {
        return vec2<f32>(0.0, 0.0);
    }
    // Clip to depth >= eps in front of p (db - da != 0 when exactly one end is behind).
    if (da < eps) {
        a = a + (b - a) * ((eps - da) / (db - da));
        da = eps;
    }
    if (db < eps) {
        b = b + (a - b) * ((eps - db) / (da - db));
        db = eps;
    }
    // And to depth <= dist (db - da != 0 when exactly one end is beyond).
    if (da > dist) {
        a = a + (b - a) * ((da - dist) / (da - db));
    }
    if (db > dist) {
        b = b + (a - b) * ((db - dist) / (db - da));
    }
    let radius = disk.radius;
    let e1 = disk.e1;
    let e2 = disk.e2;
    // Depths >= eps > 0 after the clip.
    let qa = (a - p) * (dist / dot(a - p, z)) - axis;
    let qb = (b - p) * (dist / dot(b - p, z)) - axis;
    let pa = vec2<f32>(dot(qa, e1), dot(qa, e2)) / radius;
    let pb = vec2<f32>(dot(qb, e1), dot(qb, e2)) / radius;
    let e = pb - pa;
    if (dot(e, e) <= 1e-12) {
        return vec2<f32>(0.0, 0.0);
    }
    // Whether the projected edge meets the disk: its distance to the centre below 1.
    let t = clamp(-dot(pa, e) / dot(e, e), 0.0, 1.0);
    let closest = pa + e * t;
    if (dot(closest, closest) >= 1.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let beyond = beyond_segment(pa, pb) / 3.14159265;
    let hard_plane = wedges[index].hard.xyz;
    let lit = dot(hard_plane, p - wedges[index].a.xyz) > 0.0;
    let s = select(beyond, 1.0 - beyond, lit);
    // With hard_term "lit_side" every holding wedge adds s - 1.
    let h = select(0.0, 1.0, lit || (settings.tiles.z & 4u) != 0u);
    return vec2<f32>(s - h, 1.0);
}

// Texels (besides the normal offset) a pixel near a wedge's quad plane is
// moved off it for the shadow-map read (see main).
const CONSISTENCY_TEXELS: f32 = 2.0;

// occluders "independent" (beyond both papers, whose wedges all add): the
// terms of one object (a connected surface; a tile lists each object's
// wedges together, `Wedge.dir.w`) sum to its own change to the hard term,
// s > 0 where the centre lies in its hard shadow (the part of the light it
// leaves visible) and s <= 0 where it does not (minus the part it covers).
// Objects combine as independent occluders: visibility is the product of
// the parts each leaves visible. One object alone gives the sum's result.
struct Objects {
    // Product of 1 + s over objects with s <= 0 (the parts they leave).
    leave: f32,
    // Product of min(s, 1) over objects with s > 0, and whether any has.
    uncover: f32,
    any_uncover: bool,
};

fn fold_object(o: Objects, s: f32) -> Objects {
    var out = o;
    if (s > 0.0) {
        out.uncover = out.uncover * min(s, 1.0);
        out.any_uncover = true;
    } else {
        out.leave = out.leave * max(1.0 + s, 0.0);
    }
    return out;
}

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    let px = pixel.px;
    var v = 0.0;
    var hard = 0.0;
    var intensity = 0.0;
    if (pixel.geometry) {
        let p = pixel.p;
        let n = pixel.n;
        let r = wedge_test.center.w;
        let cos_theta = light_cosine(wedge_test, p, n);
        let horizon = (settings.tiles.z & 2u) != 0u && r > 0.0;
        var k_h = 1.0;
        if (horizon) {
            k_h = horizon_fraction(wedge_test, p, n);
        }
        if (cos_theta > 0.0) {
            // The shadow map and a wedge's quad plane draw the same hard
            // boundary only to within a texel or two (rasterisation and
            // bias). Where p lies that close to the quad plane of a wedge
            // holding it, the map is read at p moved, in its tangent plane,
            // to CONSISTENCY_TEXELS off that plane on the side h(p) gives,
            // so that the map's count and the wedge's step agree (otherwise
            // a lone pixel gets 1 + s or s - 1).
            let texel = light_texel_size(wedge_test.light_space, light_view_depth(wedge_test.light_space, p));
            let margin = (CONSISTENCY_TEXELS + wedge_test.bias.x) * texel;
            var push = vec3<f32>(0.0);
            var terms = 0.0;
            let tile = vec2<u32>(px) / settings.tiles.x;
            let t = tile.y * settings.tiles.y + tile.x;
            let quarter_of = (vec2<u32>(px) / (settings.tiles.x / 2u)) % 2u;
            let quarter = quarter_of.y * 2u + quarter_of.x;
            let start = tile_offsets[t];
            let end = tile_offsets[t + 1u];
            var inside = false;
            let disk = light_disk(p, wedge_test.center.xyz, r);
            let independent = (settings.tiles.z & 32u) != 0u;
            var objects = Objects(1.0, 1.0, false);
            var object = -1.0;
            var object_terms = 0.0;
            var edge_depth = 3.4e38;
            for (var i = start; i < end; i = i + 1u) {
                if (tile_keep[4u * i + quarter] == 0u) {
                    continue;
                }
                // Each term reads only the wedge's fields it uses: a whole
                // Wedge is 160 bytes, and llvmpipe loads all of it for
                // every wedge and pixel (generated:1 at 256x256, 26M pairs:
                // the pass took 1.02 s so, 0.81 s so).
                let index = tile_wedges[i];
                var term: vec2<f32>;
                if ((settings.tiles.z & 8u) != 0u) {
                    term = coverage_term(index, p, disk);
                } else {
                    term = wedge_term(wedges[index], p);
                }
                if (term.y > 0.0 && (settings.tiles.z & 16u) != 0u) {
                    // overlap "gate": the map read at p moved, in its
                    // tangent plane, to just off the lit side of this
                    // wedge's quad (margin off its plane: just outside the
                    // hard shadow this edge casts). If that point is in
                    // shadow, another surface lies right behind the edge as
                    // the light sees it (an inner fold, a second caster),
                    // and it covers what this edge would uncover (p behind
                    // the quad) or already covers what it would hide (p in
                    // front): the wedge adds nothing. A quad nearly
                    // parallel to the receiver keeps its term.
                    let quad = wedges[index].hard.xyz;
                    let d_gate = dot(quad, p - wedges[index].a.xyz);
                    let along_gate = quad - n * dot(quad, n);
                    let rate_gate = dot(along_gate, quad);
                    if (rate_gate > 0.05) {
                        let probe = p + along_gate * ((margin - d_gate) / rate_gate);
                        let qg = biased_receiver(wedge_test, probe, n, cos_theta);
                        if (qg.w > map_depth(wedge_test, shadow_map, qg.xyz)) {
                            term = vec2<f32>(0.0, 0.0);
                        }
                    }
                }
                if (term.y > 0.0) {
                    let edge_object = wedges[index].dir.w;
                    let quad = wedges[index].hard.xyz;
                    terms = terms + term.x;
                    if (edge_object != object) {
                        if (object >= 0.0) {
                            objects = fold_object(objects, object_terms);
                        }
                        object = edge_object;
                        object_terms = 0.0;
                    }
                    object_terms = object_terms + term.x;
                    inside = true;
                    // The holding edge nearest the light: where the map
                    // sees the centre, the map bound's rays start there.
                    edge_depth = min(edge_depth, light_view_depth(wedge_test.light_space, 0.5 * (wedges[index].a.xyz + wedges[index].b.xyz)));
                    let d = dot(quad, p - wedges[index].a.xyz);
                    // The side the map is read on: h(p)'s, or always the lit one.
                    let lit = d > 0.0 || (settings.tiles.z & 4u) != 0u;
                    if (abs(d) < margin || (lit && d < margin)) {
                        let along = quad - n * dot(quad, n);
                        // How fast moving along `along` leaves the plane;
                        // a quad plane nearly parallel to the receiver is
                        // left alone (the move would be long).
                        let rate = dot(along, quad);
                        if (rate > 0.05) {
                            push = push + along * ((select(-margin, margin, lit) - d) / rate);
                        }
                    }
                }
            }
            // p + push lies in p's tangent plane: its biased depth is the receiver's there.
            let q = biased_receiver(wedge_test, p + push, n, cos_theta);
            hard = select(0.0, 1.0, q.w <= map_depth(wedge_test, shadow_map, q.xyz));
            intensity = hard + terms;
            if (inside) {
                atomicAdd(&counters[0], 1u);
            }
            v = clamp(intensity, 0.0, 1.0);
            if (independent && inside) {
                objects = fold_object(objects, object_terms);
                // Centre lit: the objects' left parts; hidden: the parts
                // that the hiding objects uncover, less what the others
                // cover (none uncovering: an umbra no wedge reaches).
                if (hard > 0.0) {
                    v = objects.leave;
                } else {
                    v = select(0.0, objects.uncover * objects.leave, objects.any_uncover);
                }
                intensity = v;
            }
            // map_samples (beyond both papers, issue 28): at most what the
            // map's rays leave seen, and with map_bound = "both", where the
            // map sees the centre, at least that (pvm's bound). Their search
            // starts at the surface hiding the centre, or at the holding
            // edge nearest the light.
            let lower = (settings.tiles.z & 64u) != 0u && hard > 0.0;
            if (inside && wedge_test.mode.z > 0u && (v > map_margin(wedge_test.mode.z) || lower)) {
                var d_start = map_depth(wedge_test, shadow_map, q.xyz);
                if (hard > 0.0) {
                    d_start = edge_depth;
                }
                // The wedges' sum has no one plane to compare the rays with: k itself.
                let bounded = map_bound(wedge_test, shadow_map, p, q.w, d_start, wedge_test.mode.z, v, lower, wedge_test.mode.w, vec4<f32>(0.0), edge_depth, false);
                if (bounded < v) {
                    atomicAdd(&counters[1], 1u);
                } else if (bounded > v) {
                    atomicAdd(&counters[2], 1u);
                }
                v = bounded;
            }
            if (horizon) {
                v = min(v, k_h);
            }
        } else if (horizon) {
            // Only the sliver above the horizon, unless another object hides the centre.
            let own = mesh_objects[min(u32(pixel.normal_texel.w), arrayLength(&mesh_objects) - 1u)];
            v = select(0.0, k_h, horizon_sliver_seen(wedge_test, object_map, p, own));
        }
    }
    textureStore(visibility_out, px, vec4<f32>(v, 0.0, 0.0, 0.0));
    textureStore(hard_out, px, vec4<f32>(hard, 0.0, 0.0, 0.0));
    textureStore(intensity_out, px, vec4<f32>(intensity, 0.0, 0.0, 0.0));
}
