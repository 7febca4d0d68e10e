enable wgpu_ray_query;
#import shaders/receiver.wgsl
#import shaders/light_samples.wgsl

// Method `raytraced`: visibility by shadow rays through the scene's
// acceleration structure (ray queries). Per pixel, one ray from the surface
// point towards each light sample of `reference`'s sphere sampling, weighted
// as `reference` weights its shadow-map tests (methods/reference/
// visibility.wgsl): the weighted fraction of unblocked rays is the fraction
// of the light's solid angle the point sees, what the ground truth measures.
//
// Entry points: `trace` (every pixel, the full sample set); `classify`,
// `select_pixels` and `refine` (adaptive mode): a few rays first, then the
// full set only where they disagree within a few pixels.

struct RaySettings {
    // The light's centre (xyz) and radius (w).
    light: vec4<f32>,
    // x: the ray origins' offset along the normal, in world units.
    offset: vec4<f32>,
    // x: samples in the full set (at the start of `samples`); y: points in the
    // coarse set (after it: unit-disk points, xy); z: the classification's
    // radius in pixels.
    counts: vec4<u32>,
};

@group(0) @binding(2) var scene_bvh: acceleration_structure;
@group(0) @binding(3) var<storage, read> settings: RaySettings;
@group(0) @binding(4) var<storage, read> samples: array<LightSample>;
// Adaptive mode, per pixel: the first pass's estimate (0 or 1) and 1 where its rays disagree.
@group(0) @binding(5) var<storage, read_write> coarse: array<vec2<f32>>;
// [0]: pixels that took the full sample set; [1]: pixels that took the coarse set.
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(7) var visibility_out: texture_storage_2d<r32float, write>;
// Adaptive mode: the pixels (row-major indices) that take the full sample set.
@group(0) @binding(8) var<storage, read_write> refine_list: array<u32>;

// Whether the segment from `origin` to `end` meets no triangle beyond
// `t_min`. The light is not in the acceleration structure, so the segment
// ends on it.
fn unoccluded(origin: vec3<f32>, end: vec3<f32>, t_min: f32) -> bool {
    let d = end - origin;
    // The origin lies off the light (it is a receiver, offset by far less than
    // its distance to the light), so the length is positive.
    let len = length(d);
    if (len <= t_min) {
        return true;
    }
    var rq: ray_query;
    rayQueryInitialize(&rq, scene_bvh, RayDesc(RAY_FLAG_TERMINATE_ON_FIRST_HIT | RAY_FLAG_FORCE_OPAQUE, 0xFFu, t_min, len, origin, d / len));
    // Opaque triangles only: one proceed commits the first hit, if any.
    while (rayQueryProceed(&rq)) {
    }
    return rayQueryGetCommittedIntersection(&rq).kind == RAY_QUERY_INTERSECTION_NONE;
}

// The visibility of the light from the pixel's surface point through
// samples [first, first + count) of the full set.
fn estimate(pixel: ScreenPixel, first: u32, count: u32) -> f32 {
    // Offset along the normal, so that the surface the point lies on does not
    // hide it (the G-buffer's position is within float rounding of it), and
    // hits closer than the offset ignored, so that neither does a surface
    // meeting it at a corner (a wall's pixel at the floor can lie a rounding
    // error below the floor, which an offset along the wall's normal keeps).
    let eps = settings.offset.x;
    let origin = pixel.p + pixel.n * eps;
    var seen = 0.0;
    var total = 0.0;
    for (var i = first; i < first + count; i++) {
        let s = samples[i];
        let w = sample_weight(s, pixel.p, settings.light.xyz);
        if (w <= 0.0) {
            continue;
        }
        total += w;
        // Samples below the surface's horizon count as hidden, as in the ground truth.
        if (dot(pixel.n, s.position.xyz - pixel.p) > 0.0 && unoccluded(origin, s.position.xyz, eps)) {
            seen += w;
        }
    }
    // No sample faces the pixel (only possible with very few samples): the
    // light is treated as hidden rather than dividing by zero.
    return select(0.0, clamp(seen / total, 0.0, 1.0), total > 0.0);
}

fn pixel_index(px: vec2<i32>) -> u32 {
    return u32(px.y) * textureDimensions(gbuffer_normal).x + u32(px.x);
}

// Plain mode: the full sample set at every pixel.
@compute @workgroup_size(8, 8)
fn trace(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(id);
    if (!pixel.inside) {
        return;
    }
    var v = 0.0;
    if (pixel.geometry) {
        v = estimate(pixel, 0u, settings.counts.x);
        atomicAdd(&counters[0], 1u);
    }
    textureStore(visibility_out, pixel.px, vec4<f32>(v, 0.0, 0.0, 0.0));
}

// An orthonormal pair perpendicular to the unit vector a (Duff et al. 2017,
// "Building an orthonormal basis, revisited": no division by a small number).
fn perpendicular_pair(a: vec3<f32>) -> mat2x3<f32> {
    let sign = select(-1.0, 1.0, a.z >= 0.0);
    let p = -1.0 / (sign + a.z);
    let q = a.x * a.y * p;
    return mat2x3<f32>(vec3<f32>(1.0 + sign * a.x * a.x * p, sign * q, -sign * a.x), vec3<f32>(q, sign + a.y * a.y * p, -a.y));
}

// Adaptive mode, first pass: a few rays from every pixel to points of the
// light's disk facing it (the coarse set's unit-disk points, scaled by the
// radius, around the direction to the centre), so that every pixel spreads
// its first rays over the light as it sees it whatever the sphere sampling's
// weights there (a receiver above a light inside a room sees its far side,
// where few of the full set's samples lie). Stores 1 or 0 (some ray reached
// the light) and whether the rays disagree (some reached it, some not:
// blocked or below the horizon).
@compute @workgroup_size(8, 8)
fn classify(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(id);
    if (!pixel.inside) {
        return;
    }
    var c = vec2<f32>(0.0, 0.0);
    if (pixel.geometry) {
        let to_light = settings.light.xyz - pixel.p;
        // Receivers lie outside the light (scene validation): the length is positive.
        let axis = to_light / max(length(to_light), 1e-30);
        let pair = perpendicular_pair(axis) * settings.light.w;
        let eps = settings.offset.x;
        let origin = pixel.p + pixel.n * eps;
        var lit = 0u;
        var dark = 0u;
        for (var i = settings.counts.x; i < settings.counts.x + settings.counts.y; i++) {
            let q = settings.light.xyz + pair * samples[i].position.xy;
            if (dot(pixel.n, q - pixel.p) > 0.0 && unoccluded(origin, q, eps)) {
                lit += 1u;
            } else {
                dark += 1u;
            }
        }
        c = vec2<f32>(select(0.0, 1.0, lit > 0u), select(0.0, 1.0, lit > 0u && dark > 0u));
        atomicAdd(&counters[1], 1u);
    }
    coarse[pixel_index(pixel.px)] = c;
}

// Adaptive mode, second pass: a pixel whose coarse rays, or those of any
// pixel within `counts.z` pixels, disagree (a penumbra reaches there) joins
// the list of pixels that take the full sample set; elsewhere (all its rays
// and its neighbours' agreed: fully lit or fully hidden) the coarse estimate
// is the visibility.
@compute @workgroup_size(8, 8)
fn select_pixels(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(id);
    if (!pixel.inside) {
        return;
    }
    var v = 0.0;
    if (pixel.geometry) {
        let size = vec2<i32>(textureDimensions(gbuffer_normal));
        let r = i32(settings.counts.z);
        let lo = max(pixel.px - vec2<i32>(r, r), vec2<i32>(0, 0));
        let hi = min(pixel.px + vec2<i32>(r, r), size - vec2<i32>(1, 1));
        var penumbra = false;
        for (var y = lo.y; y <= hi.y && !penumbra; y++) {
            for (var x = lo.x; x <= hi.x; x++) {
                if (coarse[pixel_index(vec2<i32>(x, y))].y > 0.0) {
                    penumbra = true;
                    break;
                }
            }
        }
        if (penumbra) {
            let slot = atomicAdd(&counters[0], 1u);
            refine_list[slot] = pixel_index(pixel.px);
            return;
        }
        v = coarse[pixel_index(pixel.px)].x;
    }
    textureStore(visibility_out, pixel.px, vec4<f32>(v, 0.0, 0.0, 0.0));
}

// Adaptive mode, third pass: the full sample set for the listed pixels.
// Invocation i (counted row by row over the image) takes list entry i, so
// that every lane of a workgroup below the list's end traces rays (no lane
// idles beside a penumbra pixel) and neighbouring entries, listed in the
// order the pixels were visited, trace nearby rays.
@compute @workgroup_size(8, 8)
fn refine(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(gbuffer_normal);
    let i = id.y * size.x + id.x;
    if (id.x >= size.x || id.y >= size.y || i >= atomicLoad(&counters[0])) {
        return;
    }
    let index = refine_list[i];
    let pixel = screen_pixel(vec3<u32>(index % size.x, index / size.x, 0u));
    textureStore(visibility_out, pixel.px, vec4<f32>(estimate(pixel, 0u, settings.counts.x), 0.0, 0.0, 0.0));
}
