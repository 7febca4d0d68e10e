// Method `hard`: the shadow-map test from the light centre (Williams 1978),
// visibility 0 or 1. Bias schemes (Cournia ch. 3):
//   mode 0 `slope`: receiver-side normal offset plus slope-scaled depth bias,
//                   both in texels of the map at the receiver's depth;
//   mode 1 `second_depth`: map of back faces (front faces culled; Wang and
//                   Molnar 1994), compared without bias;
//   mode 2 `none`: raw comparison (shows acne; for study).

struct HardUniforms {
    light_space: LightSpace,
    // Light centre xyz, unused.
    center: vec4<f32>,
    // normal offset, constant bias, slope bias, max slope (tan theta), all in texels.
    bias: vec4<f32>,
    // x: mode.
    mode: vec4<u32>,
};

@group(0) @binding(0) var gbuffer_position: texture_2d<f32>;
@group(0) @binding(1) var gbuffer_normal: texture_2d<f32>;
@group(0) @binding(2) var shadow_map: texture_depth_2d;
@group(0) @binding(3) var<uniform> hard: HardUniforms;
@group(0) @binding(4) var visibility_out: texture_storage_2d<r32float, write>;

fn stored_depth(p: vec3<f32>) -> f32 {
    let size = vec2<i32>(textureDimensions(shadow_map));
    let t = clamp(vec2<i32>(floor(light_map_coords(hard.light_space, p))), vec2<i32>(0), size - 1);
    return textureLoad(shadow_map, t, 0) * hard.light_space.depth.y;
}

fn hard_visibility(p: vec3<f32>, n: vec3<f32>) -> f32 {
    let to_light = hard.center.xyz - p;
    // The light centre lies off every surface (scene validation): length > 0.
    let cos_theta = dot(n, to_light) / max(length(to_light), 1e-30);
    // Centre below the surface's horizon: the surface itself hides it.
    if (cos_theta <= 0.0) {
        return 0.0;
    }
    if (hard.mode.x == 1u || hard.mode.x == 2u) {
        let z = light_view_depth(hard.light_space, p);
        return select(0.0, 1.0, z <= stored_depth(p));
    }
    let texel = light_texel_size(hard.light_space, light_view_depth(hard.light_space, p));
    let q = p + n * (hard.bias.x * texel);
    // cos_theta > 0 here, so the tangent is finite; it is clamped at grazing angles.
    let tan_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0)) / cos_theta;
    let bias = texel * (hard.bias.y + hard.bias.z * min(tan_theta, hard.bias.w));
    let z = light_view_depth(hard.light_space, q);
    return select(0.0, 1.0, z - bias <= stored_depth(q));
}

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
        v = hard_visibility(textureLoad(gbuffer_position, px, 0).xyz, nt.xyz);
    }
    textureStore(visibility_out, px, vec4<f32>(v, 0.0, 0.0, 0.0));
}
