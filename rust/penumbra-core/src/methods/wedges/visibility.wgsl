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
    // bit 6: map_bound "both" or "solid", bit 7: "solid"); w: wedge count. wedge_test.mode.z: map_samples;
    // wedge_test.mode.w: map_march.
    tiles: vec4<u32>,
    // subsample (beyond both papers, issue 30): x: the largest shift, in
    // light radii, of any projected edge between a pixel and the coarse
    // pixels it is interpolated from (0: every pixel computed); y: the
    // coarse grid's width (f32).
    subsample: vec4<f32>,
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
// pixels_in_wedge, map_bounded_pixels, map_raised_pixels, interpolated_pixels (COUNTER_NAMES in mod.rs).
@group(0) @binding(11) var<storage, read_write> counters: array<atomic<u32>, 4>;
// The object map and each mesh's object (passes/object_map.rs), for the horizon repair.
@group(0) @binding(12) var object_map: texture_2d_array<u32>;
@group(0) @binding(13) var<storage, read> mesh_objects: array<u32>;
// Per entry of tile_wedges and quarter of its tile: 0 where the tile cull
// (tile_cull.wgsl) found the wedge holds no pixel of that quarter (its term
// is zero at every one).
@group(0) @binding(14) var<storage, read> tile_keep: array<u32>;
// subsample > 0: the results of the pixels with even x and y, two entries
// each: `Evaluated`'s v, hard, intensity, kappa, then its reach, inside and
// whether it may be interpolated from (see `interpolated`).
@group(0) @binding(15) var<storage, read_write> coarse: array<vec4<f32>>;

// subsample > 0: the pixels that `interpolated` refused, which
// middle_fallback_main or fallback_main evaluates (an indirect dispatch, so
// that its workgroups hold only such pixels): the dispatch's workgroup
// counts (x, y, z), their number, then the pixels (y << 16 | x).
struct PixelList {
    groups: array<atomic<u32>, 3>,
    count: atomic<u32>,
    pixels: array<u32>,
};
@group(0) @binding(16) var<storage, read_write> list: PixelList;
// map_solids: the solid layers the map rays read (passes/solid_layers.rs).
@group(0) @binding(17) var<storage, read> solid_layers: array<u32>;

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
//
// subsample (reach > 0): *kappa is raised to this edge's sensitivity, the
// shift of its projection in disk radii per world unit p moves ((dist -
// d) / (d radius) at its nearest end's depth d: the projection from p of a
// point at depth d moves by (dist / d - 1) times p's move, relative to the
// disk), where the edge can meet the disk within `reach` of p; to
// infinity where an end lies within reach of p's depth 0 or of the light's
// plane (a contact, whose projection is unbounded).
fn coverage_term(index: u32, p: vec3<f32>, disk: Disk, reach: f32, kappa: ptr<function, f32>) -> vec2<f32> {
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
        // p's move changes depths, and dist, by at most its length.
        if (reach > 0.0 && select(min(da, db) < dist + 2.0 * reach, max(da, db) > -reach, da < eps && db < eps)) {
            *kappa = 3.4e38;
        }
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
    // Whether the projected edge meets the disk: its distance to the centre
    // below 1 (a degenerate projection, a point, has no term).
    let t = clamp(-dot(pa, e) / max(dot(e, e), 1e-30), 0.0, 1.0);
    let closest = pa + e * t;
    if (reach > 0.0) {
        // da, db >= eps > 0 after the clip; radius > 0 (checked above).
        let d_near = min(da, db);
        let k = (dist - d_near) / (d_near * radius);
        if (length(closest) < 1.0 + k * reach) {
            *kappa = max(*kappa, k);
        }
    }
    if (dot(e, e) <= 1e-12 || dot(closest, closest) >= 1.0) {
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

// One pixel's result. kappa, reach and usable serve subsample: the
// largest sensitivity of an edge that can meet the disk within `reach`
// (world units) of p (see coverage_term), and whether the pixel may be
// interpolated from (its centre above the horizon).
struct Evaluated {
    v: f32,
    hard: f32,
    intensity: f32,
    kappa: f32,
    reach: f32,
    inside: bool,
    usable: bool,
};

// The visibility of one pixel: the wedges' sum (and its bounds). reach > 0
// also measures the pixel's kappa for subsample.
fn evaluate(pixel: ScreenPixel, reach: f32) -> Evaluated {
    let px = pixel.px;
    var v = 0.0;
    var hard = 0.0;
    var intensity = 0.0;
    var kappa = 0.0;
    var usable = false;
    var inside = false;
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
                    term = coverage_term(index, p, disk, reach, &kappa);
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
            // map sees the centre, at least that (pvm's bound; with "solid"
            // also where a solid caster's front hides it). Their search
            // starts at the surface hiding the centre, or at the holding
            // edge nearest the light.
            let lower = (settings.tiles.z & 64u) != 0u && (hard > 0.0 || ((settings.tiles.z & 128u) != 0u && solid_in_front(wedge_test, q.xyz, map_depth(wedge_test, shadow_map, q.xyz))));
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
            usable = true;
        } else if (horizon) {
            // Only the sliver above the horizon, unless another object hides the centre.
            let own = mesh_objects[min(u32(pixel.normal_texel.w), arrayLength(&mesh_objects) - 1u)];
            v = select(0.0, k_h, horizon_sliver_seen(wedge_test, object_map, p, own));
        }
    }
    return Evaluated(v, hard, intensity, kappa, reach, inside, usable);
}

fn store(px: vec2<i32>, v: f32, hard: f32, intensity: f32) {
    textureStore(visibility_out, px, vec4<f32>(v, 0.0, 0.0, 0.0));
    textureStore(hard_out, px, vec4<f32>(hard, 0.0, 0.0, 0.0));
    textureStore(intensity_out, px, vec4<f32>(intensity, 0.0, 0.0, 0.0));
}

// subsample (beyond both papers, issue 30: cost that follows the
// penumbra), a cascade over three grids: the pixels with x and y multiples
// of 4 (the top), of 2 (the middle) and all. coarse_main evaluates the top;
// middle_main gives each other pixel of the middle the mean of its top
// neighbours 2 pixels away (`interpolated`) or lists it, and
// middle_fallback_main evaluates the listed; main then does the same for
// the remaining pixels from the middle's, and fallback_main evaluates the
// pixels it lists. The middle's results (`coarse`) carry kappa and reach
// down: an interpolated pixel takes its neighbours' largest kappa and the
// least of their reaches less its distance to them.

// Index of the `coarse` record of a pixel with even x and y.
fn record(q: vec2<i32>) -> u32 {
    return 2u * (u32(q.y / 2) * u32(settings.subsample.y) + u32(q.x / 2));
}

fn store_record(q: vec2<i32>, v: f32, hard: f32, intensity: f32, kappa: f32, reach: f32, inside: bool) {
    let i = record(q);
    coarse[i] = vec4<f32>(v, hard, intensity, kappa);
    coarse[i + 1u] = vec4<f32>(reach, select(0.0, 1.0, inside), 1.0, 0.0);
}

// A pixel's evaluation for the grids below it: reach is the distance to the
// farthest of its four diagonal neighbours `spread` pixels away (the pixels
// it may serve lie within it on a flat receiver; `interpolated` checks).
fn evaluate_record(pixel: ScreenPixel, spread: i32) {
    let size = vec2<i32>(textureDimensions(gbuffer_normal));
    var reach = 0.0;
    if (pixel.geometry) {
        for (var k = 0; k < 4; k = k + 1) {
            let q = clamp(pixel.px + spread * vec2<i32>(2 * (k % 2) - 1, 2 * (k / 2) - 1), vec2<i32>(0), size - 1);
            if (!is_background(textureLoad(gbuffer_normal, q, 0))) {
                reach = max(reach, distance(textureLoad(gbuffer_position, q, 0).xyz, pixel.p));
            }
        }
    }
    // A pixel alone (no geometry around it) still gets a reach > 0, so that kappa is measured.
    let e = evaluate(pixel, max(reach, 1e-30));
    let i = record(pixel.px);
    coarse[i] = vec4<f32>(e.v, e.hard, e.intensity, e.kappa);
    coarse[i + 1u] = vec4<f32>(e.reach, select(0.0, 1.0, e.inside), select(0.0, 1.0, e.usable), 0.0);
}

@compute @workgroup_size(8, 8)
fn coarse_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(vec3<u32>(4u * id.xy, 0u));
    if (pixel.inside) {
        evaluate_record(pixel, 4);
    }
}

struct Interpolated {
    ok: bool,
    v: f32,
    hard: f32,
    intensity: f32,
    inside: bool,
    kappa: f32,
    reach: f32,
};

// Whether a pixel of the grid of spacing `stride` (1 or 2), not on the one
// above it, may take the mean of its two (one coordinate an odd multiple of
// stride) or four (both) neighbours on that grid, stride pixels away, and
// that mean. It may where every neighbour lies on the pixel's own object
// and plane (same object, normals within 8 degrees, off its plane by at
// most 2% of their distance), has the centre above its horizon, holds the
// pixel within its reach and has kappa times its distance to the pixel at
// most subsample.x (every edge that can meet the disk near either moves by
// at most that many light radii between them, so that the visibility,
// Lipschitz in the edges' shift, is smooth there), the neighbours' values
// differ by no more than that allows, and the map gives the pixel the
// neighbours' hard term. Every edge with a term at the pixel is
// in the tile list of its left or upper neighbour, in its 8 x 8 quarter
// (quarters start at multiples of 8), whose kappa then counts it.
fn interpolated(pixel: ScreenPixel, stride: i32) -> Interpolated {
    var out = Interpolated(false, 0.0, 0.0, 0.0, false, 0.0, 3.4e38);
    let px = pixel.px;
    let size = vec2<i32>(textureDimensions(gbuffer_normal));
    let odd = (px / stride) % 2;
    if (!pixel.geometry || px.x + stride * odd.x >= size.x || px.y + stride * odd.y >= size.y) {
        return out;
    }
    let cos_theta = light_cosine(wedge_test, pixel.p, pixel.n);
    if (cos_theta <= 0.0) {
        return out;
    }
    var sum = vec2<f32>(0.0);
    var count = 0.0;
    var hard = -1.0;
    var lowest = 1.0;
    var highest = 0.0;
    for (var k = 0; k < 4; k = k + 1) {
        let step = vec2<i32>(k % 2, k / 2);
        // Skip the second of a pair along an even axis (two neighbours, not four).
        if (any(step > odd)) {
            continue;
        }
        let q = px + stride * (2 * step - odd);
        let texel = textureLoad(gbuffer_normal, q, 0);
        if (is_background(texel) || texel.w != pixel.normal_texel.w || dot(texel.xyz, pixel.n) < 0.99) {
            return out;
        }
        let offset = textureLoad(gbuffer_position, q, 0).xyz - pixel.p;
        let d = length(offset);
        if (abs(dot(offset, pixel.n)) > 0.02 * d) {
            return out;
        }
        let i = record(q);
        let a = coarse[i];
        let b = coarse[i + 1u];
        if (b.z == 0.0 || d > b.x || a.w * d > settings.subsample.x || (hard >= 0.0 && a.y != hard)) {
            return out;
        }
        hard = a.y;
        out.inside = out.inside || b.y > 0.0;
        out.kappa = max(out.kappa, a.w);
        out.reach = min(out.reach, b.x - d);
        sum = sum + a.xz;
        count = count + 1.0;
        lowest = min(lowest, a.x);
        highest = max(highest, a.x);
    }
    // Neighbours further apart than a shift of 2 subsample.x allows (4 / pi
    // of the disk per radius the silhouette moves as a whole): one of them
    // is off (a stray pixel of the gate or the map's rays), and its mean
    // would spread it.
    if (highest - lowest > 2.0 * (4.0 / 3.14159265) * settings.subsample.x) {
        return out;
    }
    let r = biased_receiver(wedge_test, pixel.p, pixel.n, cos_theta);
    let own = select(0.0, 1.0, r.w <= map_depth(wedge_test, shadow_map, r.xyz));
    if (own != hard) {
        return out;
    }
    out.ok = true;
    out.v = sum.x / count;
    out.hard = hard;
    out.intensity = sum.y / count;
    if (out.inside) {
        atomicAdd(&counters[0], 1u);
    }
    atomicAdd(&counters[3], 1u);
    return out;
}

// Whether the pixel's screen tile binned no wedge: its evaluation is the
// map's hard term alone, cheaper than `interpolated`'s checks.
fn bin_empty(px: vec2<i32>) -> bool {
    let tile = vec2<u32>(px) / settings.tiles.x;
    let t = tile.y * settings.tiles.y + tile.x;
    return tile_offsets[t] == tile_offsets[t + 1u];
}

fn list_pixel(px: vec2<i32>) {
    let index = atomicAdd(&list.count, 1u);
    list.pixels[index] = (u32(px.y) << 16u) | u32(px.x);
    // Workgroups of 64 pixels, at most 65535 along x.
    let group = index / 64u;
    atomicMax(&list.groups[0], min(group + 1u, 65535u));
    atomicMax(&list.groups[1], group / 65535u + 1u);
    atomicMax(&list.groups[2], 1u);
}

// The listed pixel of a fallback dispatch's invocation, if any.
fn listed_pixel(group: vec3<u32>, groups: vec3<u32>, local: u32) -> ScreenPixel {
    let index = (group.y * groups.x + group.x) * 64u + local;
    if (index >= atomicLoad(&list.count)) {
        var none: ScreenPixel;
        none.inside = false;
        return none;
    }
    let packed = list.pixels[index];
    return screen_pixel(vec3<u32>(packed & 0xffffu, packed >> 16u, 0u));
}

@compute @workgroup_size(8, 8)
fn middle_main(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(vec3<u32>(2u * id.xy, 0u));
    if (!pixel.inside || all(pixel.px % 4 == vec2<i32>(0))) {
        return;
    }
    if (bin_empty(pixel.px)) {
        evaluate_record(pixel, 2);
        return;
    }
    let m = interpolated(pixel, 2);
    if (m.ok) {
        store_record(pixel.px, m.v, m.hard, m.intensity, m.kappa, m.reach, m.inside);
    } else {
        list_pixel(pixel.px);
    }
}

@compute @workgroup_size(64)
fn middle_fallback_main(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let pixel = listed_pixel(group, groups, local);
    if (pixel.inside) {
        evaluate_record(pixel, 2);
    }
}

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
// With subsample, the middle grid's pixels take their records, and the
// others their neighbours' mean (`interpolated`) or a place in the list,
// but for those of tiles without wedges, evaluated at once.
fn shade(pixel: ScreenPixel) {
    let px = pixel.px;
    if (settings.subsample.x > 0.0) {
        if (all(px % 2 == vec2<i32>(0))) {
            let a = coarse[record(px)];
            store(px, a.x, a.y, a.z);
            return;
        }
        if (!bin_empty(px)) {
            let m = interpolated(pixel, 1);
            if (m.ok) {
                store(px, m.v, m.hard, m.intensity);
            } else {
                list_pixel(px);
            }
            return;
        }
    }
    let e = evaluate(pixel, 0.0);
    store(px, e.v, e.hard, e.intensity);
}

// subsample: the listed pixels, evaluated.
@compute @workgroup_size(64)
fn fallback_main(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let pixel = listed_pixel(group, groups, local);
    if (pixel.inside) {
        let e = evaluate(pixel, 0.0);
        store(pixel.px, e.v, e.hard, e.intensity);
    }
}
