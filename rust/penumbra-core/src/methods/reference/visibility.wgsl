#import shaders/receiver.wgsl
#import passes/shadow_test.wgsl
#import shaders/accumulation.wgsl

// Method `reference` (Herf 3.4 and 4.2; Schwarzler Eq. 1-2): visibility is
// the weighted average of hard shadows from n points on the light.
// `accumulate` adds one sample's shadow-map test and its weight to a
// per-pixel accumulation buffer; `resolve` writes their ratio as visibility
// (shaders/accumulation.wgsl).

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
// The shadow test from one light sample; center.xyz = the sample, center.w =
// its weight: 1/n (equal weights), or the inverse of its sampling density.
@group(0) @binding(3) var<storage, read> sample_test: ShadowTest;
// Bindings 4 and 5: the accumulation (shaders/accumulation.wgsl).

struct SampleWeight {
    // The sphere's outward unit normal at the sample; w = 1: weight by solid angle, 0: equal weights.
    normal: vec4<f32>,
    // The light's centre (xyz).
    light_center: vec4<f32>,
};
@group(0) @binding(6) var<storage, read> sample_weight: SampleWeight;

// The weight of the sample for a receiver at p. With `sphere` sampling it is
// the solid angle of the sample's patch seen from p (Herf 4.1's form factor
// without the equal-weight assumption), cos(theta_s) / |p - s|^2 over the
// sampling density (sphere_samples in reference.rs), scaled by |p - c|^2 to
// stay near 1 at any scene scale: zero on the far side of the sphere, where
// the ray from p would enter the light elsewhere first.
fn sample_weight_at(p: vec3<f32>) -> f32 {
    if (sample_weight.normal.w == 0.0) {
        return sample_test.center.w;
    }
    let to_p = p - sample_test.center.xyz;
    // Receivers lie outside the light (scene validation), so |p - s| > 0;
    // the floor only keeps a degenerate input finite.
    let l = max(length(to_p), 1e-30);
    let cos_s = dot(sample_weight.normal.xyz, to_p) / l;
    let ratio = length(p - sample_weight.light_center.xyz) / l;
    return sample_test.center.w * max(cos_s, 0.0) * ratio * ratio;
}

@compute @workgroup_size(8, 8)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(id);
    if (!pixel.inside || !pixel.geometry) {
        return;
    }
    let w = sample_weight_at(pixel.p);
    if (w <= 0.0) {
        return;
    }
    // Samples below the surface's horizon count as hidden (shadow_test_visibility).
    let v = shadow_test_visibility(sample_test, shadow_map, pixel.p, pixel.n);
    accumulate_sample(id, w, v);
}
