// Light samples of `reference`'s sphere sampling as the methods that test
// them one by one upload them (`raytraced`, `triangle_masks`; Rust twin:
// light_sampling.rs, SampleUniform), and their weight per receiver.

struct LightSample {
    // xyz: the point on the light; w: its weight (methods/reference/mod.rs, LightSample).
    position: vec4<f32>,
    // xyz: the sphere's outward unit normal there; w = 1: weight by solid
    // angle, 0: equal weights (a point light).
    normal: vec4<f32>,
};

// The weight of sample s for a receiver at p (light centre c): with
// solid-angle weights, cos(theta_s) / |p - s|^2 over the sampling density
// (the sample's patch of the sphere seen from p), scaled by |p - c|^2 to stay
// near 1 at any scene scale; zero on the far side of the sphere, where the
// ray from p would enter the light elsewhere first. The same as
// `reference`'s sample_weight_at (methods/reference/visibility.wgsl).
fn sample_weight(s: LightSample, p: vec3<f32>, c: vec3<f32>) -> f32 {
    if (s.normal.w == 0.0) {
        return s.position.w;
    }
    let to_p = p - s.position.xyz;
    // Receivers lie outside the light (scene validation), so |p - s| > 0;
    // the floor only keeps a degenerate input finite.
    let l = max(length(to_p), 1e-30);
    let cos_s = dot(s.normal.xyz, to_p) / l;
    let ratio = length(p - c) / l;
    return s.position.w * max(cos_s, 0.0) * ratio * ratio;
}
