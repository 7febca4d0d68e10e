// Method `reference` (Herf 3.4 and 4.2; Schwarzler Eq. 1-2): visibility is
// the average of hard shadows from n points on the light. `accumulate` adds
// one sample's shadow-map test, weighted 1/n (in `sample_test.center.w`), to
// a per-pixel accumulation buffer; `resolve` writes the sum as visibility.

@group(0) @binding(0) var gbuffer_position: texture_2d<f32>;
@group(0) @binding(1) var gbuffer_normal: texture_2d<f32>;
@group(0) @binding(2) var shadow_map: texture_depth_2d;
// The shadow test from one light sample; center.xyz = the sample, center.w = its weight.
@group(0) @binding(3) var<uniform> sample_test: ShadowTest;
@group(0) @binding(4) var<storage, read_write> accumulated: array<f32>;
@group(0) @binding(5) var visibility_out: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(gbuffer_normal);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let px = vec2<i32>(id.xy);
    let nt = textureLoad(gbuffer_normal, px, 0);
    if (is_background(nt)) {
        return;
    }
    let p = textureLoad(gbuffer_position, px, 0).xyz;
    // Samples below the surface's horizon count as hidden (shadow_test_visibility).
    let v = shadow_test_visibility(sample_test, shadow_map, p, nt.xyz);
    accumulated[id.y * size.x + id.x] += sample_test.center.w * v;
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(gbuffer_normal);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let v = clamp(accumulated[id.y * size.x + id.x], 0.0, 1.0);
    textureStore(visibility_out, vec2<i32>(id.xy), vec4<f32>(v, 0.0, 0.0, 0.0));
}
