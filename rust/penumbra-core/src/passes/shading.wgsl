#import shaders/receiver.wgsl
#import passes/object_ids.wgsl
#import shaders/per_pixel.wgsl

// Shading of SPEC section 3, shared by every method:
//   radiance = albedo / pi * E(p) * v(p) + albedo * ambient
// with E the unoccluded irradiance of the sphere light and v the method's visibility.

struct ShadingUniforms {
    // Light centre xyz, radius.
    light: vec4<f32>,
    // Point-equivalent intensity I = L * pi * r^2 (rgb).
    intensity: vec4<f32>,
    ambient: vec4<f32>,
    eye: vec4<f32>,
};

@group(0) @binding(4) var visibility: texture_2d<f32>;
// Per mesh: albedo rgb, unused.
@group(0) @binding(5) var<storage, read> materials: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> shading: ShadingUniforms;
@group(0) @binding(7) var radiance_out: texture_storage_2d<rgba32float, write>;

// Irradiance from a uniform sphere of intensity I and radius r at distance d,
// divided by I / d^2, as a function of cos(theta) between the normal and the
// centre direction and sin^2(sigma) = (r / d)^2. Fully above the horizon it is
// exactly cos(theta) (Cournia Eq. 2.1 with a sphere); across the horizon it is
// the closed form of the clipped spherical cap (Snyder 1996).
fn sphere_irradiance_factor(cos_theta: f32, sin2_sigma: f32) -> f32 {
    if (cos_theta * cos_theta > sin2_sigma) {
        return max(cos_theta, 0.0);
    }
    // Tiny lights: the horizon band |cos| <= sin(sigma) is negligible, and the
    // closed form below would cancel catastrophically; use the point limit.
    if (sin2_sigma < 1e-7) {
        return max(cos_theta, 0.0);
    }
    // Scene validation keeps surfaces outside the light (d > r), so s < 1;
    // the clamp guards the last ulp. Then x > 0 and sin(theta) >= sqrt(1 - s) > 0.
    let s = min(sin2_sigma, 1.0 - 1e-6);
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 1e-12));
    let x = sqrt(1.0 / s - 1.0);
    let y = clamp(-x * cos_theta / sin_theta, -1.0, 1.0);
    let w = sin_theta * sqrt(max(1.0 - y * y, 0.0));
    let f = (cos_theta * acos(y) - x * w) * s + atan(w / x);
    return max(f, 0.0) / (PI * s);
}

fn sphere_light_irradiance(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let to_light = shading.light.xyz - p;
    let d2 = dot(to_light, to_light);
    // d > r >= 0 by scene validation; the max only guards a zero normal's pixel.
    let d = sqrt(max(d2, 1e-30));
    let cos_theta = dot(n, to_light) / d;
    let r = shading.light.w;
    let factor = sphere_irradiance_factor(cos_theta, (r * r) / max(d2, 1e-30));
    return shading.intensity.rgb * factor / max(d2, 1e-30);
}

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    let px = pixel.px;
    var radiance = vec3<f32>(0.0);
    if (pixel.geometry) {
        let p = pixel.p;
        let n = pixel.n;
        let albedo = materials[u32(pixel.normal_texel.w)].rgb;
        // One-sided surfaces (as Mitsuba's diffuse BSDF): a face seen from its
        // back gets no direct light.
        var irradiance = vec3<f32>(0.0);
        if (dot(n, shading.eye.xyz - p) > 0.0) {
            irradiance = sphere_light_irradiance(p, n);
        }
        let v = textureLoad(visibility, px, 0).r;
        radiance = albedo / PI * irradiance * v + albedo * shading.ambient.rgb;
    }
    textureStore(radiance_out, px, vec4<f32>(radiance, 1.0));
    store_object_id(pixel);
}
