#import shaders/common.wgsl
#import shaders/light_space.wgsl

// The shadow-map test from the light centre with its bias schemes (Cournia
// ch. 3), shared by every shadow-map method (passes/shadow_test.rs):
//   mode 0 `slope`: receiver-side normal offset plus slope-scaled depth bias,
//                   both in texels of the map at the receiver's depth;
//   mode 1 `second_depth`: map of back faces (front faces culled; Wang and
//                   Molnar 1994), compared without bias;
//   mode 2 `none`: raw comparison (shows acne; for study);
//   mode 3 `midpoint`: map half-way between first and second depth (Woo
//                   1992), compared without bias.

struct ShadowTest {
    light_space: LightSpace,
    // Light centre xyz, light radius.
    center: vec4<f32>,
    // normal offset, constant bias, slope bias, max slope (tan theta), all in texels.
    bias: vec4<f32>,
    // x: mode; y: method flags (method-specific).
    mode: vec4<u32>,
};

// Cosine between the normal and the direction to the light centre.
fn light_cosine(t: ShadowTest, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let to_light = t.center.xyz - p;
    // The light centre lies off every surface (scene validation): length > 0.
    return dot(n, to_light) / max(length(to_light), 1e-30);
}

// The point whose map texel is read (xyz) and the biased depth compared
// with the map (w), for a receiver at p with normal n and light cosine cos_theta > 0.
fn biased_receiver(t: ShadowTest, p: vec3<f32>, n: vec3<f32>, cos_theta: f32) -> vec4<f32> {
    if (t.mode.x != 0u) {
        return vec4<f32>(p, light_view_depth(t.light_space, p));
    }
    let texel = light_texel_size(t.light_space, light_view_depth(t.light_space, p));
    let q = p + n * (t.bias.x * texel);
    // cos_theta > 0, so the tangent is finite; it is clamped at grazing angles.
    let tan_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0)) / cos_theta;
    let bias = texel * (t.bias.y + t.bias.z * min(tan_theta, t.bias.w));
    return vec4<f32>(q, light_view_depth(t.light_space, q) - bias);
}

// World-unit depth, along its layer's axis, stored in a linear-depth map at
// the texel under `m`; the far plane in a layer that was not rendered (a
// cube face that sees no geometry holds nothing).
fn map_point_depth(ls: LightSpace, map: texture_depth_2d_array, m: MapPoint) -> f32 {
    if (!layer_active(ls, m.layer)) {
        return ls.depth.y;
    }
    return textureLoad(map, map_texel(textureDimensions(map), m), m.layer, 0) * ls.depth.y;
}

// Map point `m` in a light-space image of `dims` texels that is read only
// at the receivers' projections (pvm's volume map, pvmf's mask): the map's
// coordinates scaled. Such an image is the map's size, or smaller where a
// texel per pixel serves (`FrameContext::receiver_image_size`).
fn map_point_in(ls: LightSpace, m: MapPoint, dims: vec2<u32>) -> MapPoint {
    return MapPoint(m.layer, m.coords * (f32(dims.x) / ls.depth.z));
}

// World-unit depth stored in such a linear-depth image at the texel over `q`.
fn image_depth(t: ShadowTest, image: texture_depth_2d_array, q: vec3<f32>) -> f32 {
    return map_point_depth(t.light_space, image, map_point_in(t.light_space, light_map_point(t.light_space, q), textureDimensions(image)));
}

// World-unit depth stored in a linear-depth map at the texel over `q`.
fn map_depth(t: ShadowTest, map: texture_depth_2d_array, q: vec3<f32>) -> f32 {
    return map_point_depth(t.light_space, map, light_map_point(t.light_space, q));
}

// Hard visibility of the light centre: 0 or 1.
fn shadow_test_visibility(t: ShadowTest, map: texture_depth_2d_array, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let cos_theta = light_cosine(t, p, n);
    // Centre below the surface's horizon: the surface itself hides it.
    if (cos_theta <= 0.0) {
        return 0.0;
    }
    let r = biased_receiver(t, p, n, cos_theta);
    return select(0.0, 1.0, r.w <= map_depth(t, map, r.xyz));
}

// Hard visibility of the light centre through the comparison sampler `cmp`:
// with linear filtering, the hardware's 2x2 bilinear percentage-closer
// filter around the receiver's texel (Schwarzler et al. 3.4.3), with the
// receiver biased as in `shadow_test_visibility`.
fn shadow_test_visibility_filtered(t: ShadowTest, map: texture_depth_2d_array, cmp: sampler_comparison, p: vec3<f32>, n: vec3<f32>) -> f32 {
    let cos_theta = light_cosine(t, p, n);
    if (cos_theta <= 0.0) {
        return 0.0;
    }
    let r = biased_receiver(t, p, n, cos_theta);
    let ls = t.light_space;
    let m = light_map_point(ls, r.xyz);
    // A cube face that was not rendered holds no occluder.
    if (!layer_active(ls, m.layer)) {
        return 1.0;
    }
    // Maps store depth / far; beyond the far plane only drawn texels hide.
    let reference = min(r.w / ls.depth.y, 1.0);
    return textureSampleCompareLevel(map, cmp, m.coords / ls.depth.z, m.layer, reference);
}

// Cournia Eq. 4.1 and 4.2: the fraction of a disk of radius r > 0 whose
// centre lies at signed distance s from a line, on the far side of the line
// from the centre when s > 0 (and on the centre's side when s < 0).
// Continuous in s, 1/2 at 0.
fn disk_fraction(s: f32, r: f32) -> f32 {
    let c = clamp(s / r, -1.0, 1.0);
    // a = acos(s/r) r^2 / 2 - s sqrt(r^2 - s^2) / 2; k = 2a / (pi r^2), in units of r.
    let a = 0.5 * acos(c) - 0.5 * c * sqrt(max(1.0 - c * c, 0.0));
    return clamp(2.0 * a / PI, 0.0, 1.0);
}

// The fraction of a sphere light of radius r = t.center.w > 0 above the
// tangent plane of a receiver at p with normal n: Eq. 4.1 with that plane
// as the cutting plane (the light's part below it is hidden by the
// receiver's own surface, as the ground truth counts it).
fn horizon_fraction(t: ShadowTest, p: vec3<f32>, n: vec3<f32>) -> f32 {
    return disk_fraction(-dot(n, t.center.xyz - p), t.center.w);
}

// Whether a receiver at p whose light centre lies below its tangent plane
// may see the horizon's sliver of the light (`horizon_fraction`): yes when
// the first surface from the centre towards p is its own object (its body
// near the terminator), no when it is another object, which then lies
// between the light and p on both sides of p's plane (issue 27: a floor
// between a light below it and a box above). `objects` is the object map
// (passes/object_map.rs: object + 1, 0 for none or "cannot tell") and `own`
// the receiver's mesh's object (u32 max: a mesh of several surfaces, which
// cannot tell its own body from the others). The centre's ray to such a p
// grazes p's own silhouette as the light sees it (the terminator), so p's
// texel may have rasterised the surface beyond it: the sliver is taken as
// hidden only when p's texel and its 8 neighbours all hold another object.
// The clamp keeps every read inside the map; coordinates outside a
// frustum's window (a receiver no caster can shade: light_frustum.rs) read
// its empty rim, and the sliver is seen.
fn horizon_sliver_seen(t: ShadowTest, objects: texture_2d_array<u32>, p: vec3<f32>, own: u32) -> bool {
    if (own == 0xffffffffu) {
        return true;
    }
    let m = light_map_point(t.light_space, p);
    if (!layer_active(t.light_space, m.layer)) {
        return true;
    }
    // The object map is smaller than the shadow map (`object_map::side`);
    // map coordinates are in the shadow map's texels (light_space.wgsl).
    let size = vec2<i32>(textureDimensions(objects));
    let centre = vec2<i32>(floor(m.coords * (f32(size.x) / t.light_space.depth.z)));
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let texel = clamp(centre + vec2<i32>(dx, dy), vec2<i32>(0), size - 1);
            let first = textureLoad(objects, texel, m.layer, 0).x;
            if (first == 0u || first == own + 1u) {
                return true;
            }
        }
    }
    return false;
}
