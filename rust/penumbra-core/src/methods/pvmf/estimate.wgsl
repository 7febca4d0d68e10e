#import shaders/receiver.wgsl
#import passes/pcf_taps.wgsl
#import passes/map_rays.wgsl
#import shaders/per_pixel.wgsl

// PVMF pass 3 (Cournia 5.2): visibility estimation per camera pixel. Pixels
// inside a penumbra volume (the mask is nearer the light than the pixel) or
// failing the shadow-map test take an n_pcf x n_pcf jittered
// percentage-closer filter of width w_pcf over the depth shadow map; all
// others keep the shadow-map test's 0 or 1 and take no taps.

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
@group(0) @binding(3) var mask_depth: texture_depth_2d_array;
@group(0) @binding(4) var edge_distance: texture_2d_array<f32>;
@group(0) @binding(5) var shadow_sampler: sampler_comparison;
// center.w: the light's radius r.
@group(0) @binding(6) var<storage, read> pvmf_params: ShadowTest;

struct PvmfSettings {
    s_p: f32,
    n_pcf: u32,
    seed: u32,
    // bit 0: disk kernel (else the paper's square); bit 1: skip pixels that
    // fail the shadow-map test outside every volume (else filter them, 5.2);
    // bit 2: repair "horizon"; bit 3: estimate "area"; bit 4: blocker_test
    // "behind"; bit 5: occluder_distance "farthest_edge"; bit 6: "darker";
    // bit 7: map_bound "both" (or "solid"); bit 8: map_bound "solid".
    flags: u32,
    // The blur takes only pixels whose w_pcf is at least this many texels.
    blur_min_width: f32,
};
@group(0) @binding(7) var<storage, read> settings_params: PvmfSettings;
// Per-invocation copies of the parameters, read once in `shade` (as in pcss/visibility.wgsl).
var<private> pvmf: ShadowTest;
var<private> settings: PvmfSettings;
@group(0) @binding(8) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(9) var blur_mask_out: texture_storage_2d<r32float, write>;
@group(0) @binding(10) var filter_width_out: texture_storage_2d<r32float, write>;
// masked, filtered, blurred pixels, and those the map bound lowered and
// raised (COUNTERS in mod.rs).
@group(0) @binding(11) var<storage, read_write> counters: array<atomic<u32>, 5>;
// The object map and each mesh's object (passes/object_map.rs), for the horizon repair.
// The largest d_e over far per mask texel (occluder_distance
// "farthest_edge"; methods/pvmf/mask.wgsl's fs_mask_far), else unread.
@group(0) @binding(12) var farthest_distance: texture_2d_array<f32>;
@group(0) @binding(13) var object_map: texture_2d_array<u32>;
@group(0) @binding(14) var<storage, read> mesh_objects: array<u32>;
// map_solids: the solid layers the map rays read (passes/solid_layers.rs).
@group(0) @binding(15) var<storage, read> solid_layers: array<u32>;

// d_o (5.2): the mean of the d_e channel over a 5 x 5 texel region (3 x 3
// taps, 2 texels apart) around the receiver's projection, over texels that
// hold a volume (d_e > 0). The paper does not give the region's size. Where
// no volume is near (an umbra pixel outside every volume), the occluder's
// distance is read from the shadow map instead: the stored depth along the
// receiver's light ray.
// occluder_distance = "farthest_edge" (beyond 5.2, issue 28): 5.2 defines
// d_o over the edges whose volumes enclose the receiver, but the mask's d_e
// is the volume nearest the light's. Where a second caster lies near the
// light (generated scene 37: a boot 0.3 under a light of radius 0.32, over
// a koala), its volumes cover the nearer caster's whole shadow, d_o is the
// boot's, and w_pcf, sized for the boot's penumbra, spreads the koala's
// umbra over the floor (6% of its pixels lit). A tap then takes the edge
// farthest from the light whose volume covers the texel, when that edge is
// nearer the light than the receiver (d_r): a volume starts at its edge, so
// it can hold the receiver only then. Otherwise the tap keeps d_e.
// Returns (d_o from the nearest volumes, d_o from the farthest edges); the
// second is the first without "farthest_edge".
fn occluder_distance(r: Receiver, d_r: f32) -> vec2<f32> {
    let farthest_edge = (settings.flags & 32u) != 0u;
    let ls = pvmf.light_space;
    let centre = vec2<i32>(floor(r.coords));
    var sum = vec2<f32>(0.0);
    var count = 0.0;
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            // The texel's centre, in the receiver's layer (or, beyond a cube
            // face's edge, the neighbour face); a face not rendered holds no volume.
            let m = map_wrap(ls, r.layer, vec2<f32>(centre + 2 * vec2<i32>(i, j)) + 0.5);
            if (layer_active(ls, m.layer)) {
                let dims = textureDimensions(edge_distance);
                let texel = map_texel(dims, map_point_in(ls, m, dims));
                let d = textureLoad(edge_distance, texel, m.layer, 0).x;
                var d_far = d;
                if (farthest_edge) {
                    // The mask and this channel have the same size (mod.rs).
                    let far_e = textureLoad(farthest_distance, texel, m.layer, 0).x * ls.depth.y;
                    if (far_e > 0.0 && far_e < d_r) {
                        d_far = far_e;
                    }
                }
                // far_e > 0 only where some volume, hence d_e > 0.
                if (d > 0.0) {
                    sum += vec2<f32>(d, d_far);
                    count += 1.0;
                }
            }
        }
    }
    if (count > 0.0) {
        return sum / count;
    }
    let depth = map_point_depth(ls, shadow_map, MapPoint(r.layer, vec2<f32>(centre) + 0.5));
    // light_ray has unit depth along the layer's axis, so depth * |ray| is the distance.
    return vec2<f32>(depth * length(light_ray(ls, r.layer, r.coords)));
}

// 5.2's jittered n_pcf x n_pcf percentage-closer filter of width w texels
// per axis about the receiver: the fraction of taps that pass.
fn pcf_estimate(r: Receiver, p: vec3<f32>, px: vec2<u32>, w: vec2<f32>) -> f32 {
    let n_pcf = settings.n_pcf;
    var sum = 0.0;
    for (var i = 0u; i < n_pcf * n_pcf; i++) {
        // An n_pcf x n_pcf grid of cells w_pcf / n_pcf square, one
        // jittered tap per cell (5.2, Fig. 5.3).
        var s = grid_tap(i, n_pcf, jitter2(px, settings.seed, i));
        if ((settings.flags & 1u) != 0u) {
            // The light's projection is a disk: the disk inscribed
            // in the square, with the same strata.
            s = 0.5 * square_to_disk(s);
        }
        // blocker_test "behind" (beyond 5.2): a failing tap counts only
        // where the receiver lies behind its texel's surface.
        sum += pcf_tap_behind(pvmf, shadow_map, shadow_sampler, r, r.coords + s * w, p, (settings.flags & 16u) != 0u);
    }
    return sum / f32(n_pcf * n_pcf);
}

// w_pcf (5.2) in map texels per axis:
//   w_pcf = s_p (d_r - d_o) r / (2 d_o d_r tan(alpha / 2)),
// where 2 d_r tan(alpha / 2) is the frustum's width at the receiver's depth.
// d_e, hence d_o, is a distance from the light; d_r is taken as one too, so
// that (d_r - d_o) / d_o compares like with like, and the frustum's width
// (per axis: the map may be off-centre and non-square) at the receiver's
// light depth z_r converts to the map.
fn filter_width(r: Receiver, p: vec3<f32>, d_o: f32) -> vec2<f32> {
    let d_r = length(p - pvmf.center.xyz);
    // d_o > 0: it is the distance of silhouette edges or map surfaces from
    // the light, which no geometry touches; an occluder at or behind the
    // receiver gives no penumbra.
    let spread = max(d_r - d_o, 0.0) / max(d_o, 1e-30);
    // Wider than the map would only repeat its border.
    return min(unclamped_width(r, p, spread), vec2<f32>(pvmf.light_space.depth.z));
}

// s_p * w_pcf in texels per axis, for spread = (d_r - d_o) / d_o.
fn unclamped_width(r: Receiver, p: vec3<f32>, spread: f32) -> vec2<f32> {
    let window = pvmf.light_space.window;
    let extent = vec2<f32>(window.y - window.x, window.w - window.z) * max(r.depth, 1e-30);
    return settings.s_p * spread * pvmf.center.w / extent * pvmf.light_space.depth.z;
}

// estimate = "area" (beyond 5.2, whose estimate is the fraction of failing
// taps over a kernel sized for one occluder distance, d_o): the part of the
// light the failing taps' occluders hide (passes/pcf_taps.wgsl,
// `area_taps`). An occluder at distance z from the light hides light from
// the receiver (at d_r) within the light's cone through z, of radius
// R(z) = r (d_r - z) / (z texel_r) texels: R(d_o) (w_o / s_p) times
// ((d_r - z) / z) / ((d_r - d_o) / d_o). A texel nearer the light than d_o
// (the top of a thick caster, whose silhouette edges at d_o bound what it
// hides) counts as at d_o, which gives a single caster 5.2's estimate back:
// one at d_o covering the kernel hides all of the light (s_p >= 2: the
// kernel holds its cone; (s_p / 2)^2 below). One nearer the receiver hides
// all of its own smaller cone, and a surface beside the receiver outside
// its cone (a wall meeting the floor) nothing. `spread_o` is
// (d_r - d_o) / d_o, `w` the kernel's width (per axis, texels), `w_o` the
// same unclamped.
fn area_estimate(r: Receiver, p: vec3<f32>, px: vec2<u32>, d_r: f32, spread_o: f32, w: vec2<f32>, w_o: vec2<f32>) -> f32 {
    let ls = pvmf.light_space;
    let half_w = 0.5 * w;
    // The light's radius at d_o, in kernel radii, per axis.
    let light_o = w_o / max(settings.s_p, 1e-30) / max(half_w, vec2<f32>(1e-30));
    let taps = area_taps(settings.n_pcf * settings.n_pcf, min(half_w.x, half_w.y));
    var hidden = 0.0;
    for (var i = 0u; i < settings.n_pcf * settings.n_pcf; i++) {
        let x = area_tap(taps, i, settings.n_pcf, jitter2(px, settings.seed, i));
        let c = r.coords + x * half_w;
        let failed = 1.0 - pcf_tap_behind(pvmf, shadow_map, shadow_sampler, r, c, p, (settings.flags & 16u) != 0u);
        if (failed <= 0.0) {
            continue;
        }
        let m = receiver_read(ls, r, c);
        // The occluder's distance from the light along the tap's ray.
        let z = map_point_depth(ls, shadow_map, MapPoint(m.layer, floor(m.coords) + 0.5)) * length(light_ray(ls, m.layer, m.coords));
        // z > 0 (no surface touches the light), spread_o > 0 (a filtered
        // pixel lies beyond its occluders): the max keeps both divisions finite.
        let cone = light_o * min(max(d_r - z, 0.0) / max(z, 1e-30) / max(spread_o, 1e-30), 1.0);
        hidden += area_share(taps, x, cone, failed);
    }
    return hidden;
}

// The lit fraction of a receiver at p (d_r from the light) filtered for an
// occluder distance d_o, w = filter_width(r, p, d_o): 5.2's count of
// failing taps, or estimate = "area".
fn filtered(r: Receiver, p: vec3<f32>, px: vec2<u32>, d_r: f32, d_o: f32, w: vec2<f32>) -> f32 {
    // A kernel narrower than a texel is the receiver's own test: there the
    // taps' cones shrink to nothing, and 5.2's filter serves.
    if ((settings.flags & 8u) != 0u && min(w.x, w.y) >= 1.0) {
        let spread_o = max(d_r - d_o, 0.0) / max(d_o, 1e-30);
        let w_o = unclamped_width(r, p, spread_o);
        return 1.0 - min(area_estimate(r, p, px, d_r, spread_o, w, w_o), 1.0);
    }
    return pcf_estimate(r, p, px, w);
}

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    pvmf = pvmf_params;
    settings = settings_params;
    let px = pixel.px;
    var v = 0.0;
    var blur = 0.0;
    var width = 0.0;
    if (pixel.geometry) {
        let p = pixel.p;
        let n = pixel.n;
        let cos_theta = light_cosine(pvmf, p, n);
        // Repair "horizon" (beyond the paper, which takes the light's centre
        // for the surface's horizon test): the part of the light below the
        // receiver's tangent plane is hidden (horizon_fraction bounds v).
        let horizon = (settings.flags & 4u) != 0u && pvmf.center.w > 0.0;
        // Centre below the surface's horizon: the surface itself hides it.
        if (cos_theta > 0.0) {
            let q = biased_receiver(pvmf, p, n, cos_theta);
            let lit = q.w <= map_depth(pvmf, shadow_map, q.xyz);
            v = select(0.0, 1.0, lit);
            // A point light (r = 0) has no volumes and no penumbra: the test is all.
            let in_volume = pvmf.center.w > 0.0 && image_depth(pvmf, mask_depth, q.xyz) < q.w;
            if (in_volume) {
                atomicAdd(&counters[0], 1u);
            }
            let filter_umbra = (settings.flags & 2u) == 0u && pvmf.center.w > 0.0;
            if (in_volume || (!lit && filter_umbra)) {
                atomicAdd(&counters[1], 1u);
                let r = pcf_receiver(pvmf, p, n);
                let d_r = length(p - pvmf.center.xyz);
                let distances = occluder_distance(r, d_r);
                // occluder_distance "farthest_edge" filters with the farthest
                // edges' d_o alone; the others start from the nearest volumes'.
                let d_o = select(distances.x, distances.y, (settings.flags & 32u) != 0u);
                let w = filter_width(r, p, d_o);
                width = w.x;
                // occluder_distance "darker" (beyond 5.2, issue 28): where the
                // receiver fails the test and the occluder on its centre ray
                // (z_c, the map's texel) lies farther from the light than the
                // nearest volume's edges (d_o), the mask names another caster,
                // nearer the light, than the one shadowing the receiver
                // (generated scene 37: a boot near the light over a koala,
                // whose umbra the boot's wide filter lit). A second filter
                // sized for z_c, as PCSS would size it for that one blocker,
                // and the lower lit fraction: the wide filter spreads the
                // farther caster's umbra over lit floor, the narrow one misses
                // the nearer caster's wide penumbra, and each keeps an umbra
                // the other loses. docs/methods/pvmf.md measures it.
                v = filtered(r, p, vec2<u32>(pixel.px), d_r, d_o, w);
                if ((settings.flags & 64u) != 0u && !lit) {
                    let ls = pvmf.light_space;
                    // light_ray has unit depth along the layer's axis, so depth * |ray| is the distance.
                    let z_c = map_point_depth(ls, shadow_map, MapPoint(r.layer, floor(r.coords) + 0.5)) * length(light_ray(ls, r.layer, r.coords));
                    if (z_c > distances.x) {
                        v = min(v, filtered(r, p, vec2<u32>(pixel.px), d_r, z_c, filter_width(r, p, z_c)));
                    }
                }
                // map_samples (beyond 5.2, issue 28): at most what the map's
                // rays leave seen (pvm's and the wedges' bound), and with
                // map_bound = "both", where the map sees the centre, at
                // least that (with "solid" also where a solid caster's front
                // hides it). The filter counts the map's texels around the
                // receiver's projection as if one occluder at d_o hid them;
                // the rays follow the light's points through the map, and
                // with map_solids through the closed casters behind it: a
                // filter that reaches lit floor beside a caster lit the
                // umbra at its contact (generated seeds 1, 37, 38). Their
                // search starts at the surface hiding the centre, or at d_o.
                let n_rays = pvmf.mode.z;
                let lower = (settings.flags & 128u) != 0u && (lit || ((settings.flags & 256u) != 0u && solid_in_front(pvmf, q.xyz, map_depth(pvmf, shadow_map, q.xyz))));
                if (n_rays > 0u && (v > map_margin(n_rays) || lower)) {
                    // d_r > 0: no surface touches the light; d_o at the
                    // receiver's ray's light depth per distance.
                    let d_o_depth = d_o * q.w / max(d_r, 1e-30);
                    let d_start = select(map_depth(pvmf, shadow_map, q.xyz), d_o_depth, lit);
                    let bounded = map_bound(pvmf, shadow_map, p, q.w, d_start, n_rays, v, lower, pvmf.mode.w, vec4<f32>(0.0), d_o_depth, false);
                    if (bounded < v) {
                        atomicAdd(&counters[3], 1u);
                    } else if (bounded > v) {
                        atomicAdd(&counters[4], 1u);
                    }
                    v = bounded;
                }
                // 5.3 blurs every filtered pixel; a filter narrower than
                // blur_min_width texels left no jitter noise to hide.
                blur = select(0.0, 1.0, max(w.x, w.y) >= settings.blur_min_width);
            }
            if (horizon) {
                v = min(v, horizon_fraction(pvmf, p, n));
            }
        } else if (horizon) {
            // Only the sliver of the light above the horizon is seen, unless
            // another object than the receiver's own hides the centre.
            let own = mesh_objects[min(u32(pixel.normal_texel.w), arrayLength(&mesh_objects) - 1u)];
            v = select(0.0, horizon_fraction(pvmf, p, n), horizon_sliver_seen(pvmf, object_map, p, own));
        }
    }
    textureStore(visibility_out, px, vec4<f32>(v, 0.0, 0.0, 0.0));
    textureStore(blur_mask_out, px, vec4<f32>(blur, 0.0, 0.0, 0.0));
    textureStore(filter_width_out, px, vec4<f32>(width, 0.0, 0.0, 0.0));
}
