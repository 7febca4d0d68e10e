// Method `hard`: the shadow-map test from the light centre (Williams 1978),
// visibility 0 or 1; the test and its bias schemes are in shaders/shadow_test.wgsl.

@group(0) @binding(0) var gbuffer_position: texture_2d<f32>;
@group(0) @binding(1) var gbuffer_normal: texture_2d<f32>;
@group(0) @binding(2) var shadow_map: texture_depth_2d;
@group(0) @binding(3) var<storage, read> hard: ShadowTest;
@group(0) @binding(4) var visibility_out: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(gbuffer_normal);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let px = vec2<i32>(id.xy);
    let nt = textureLoad(gbuffer_normal, px, 0);
    var v = 0.0;
    if (!is_background(nt)) {
        v = shadow_test_visibility(hard, shadow_map, textureLoad(gbuffer_position, px, 0).xyz, nt.xyz);
    }
    textureStore(visibility_out, px, vec4<f32>(v, 0.0, 0.0, 0.0));
}
