// Shared by every screen-space pass: constants and G-buffer decoding.
// G-buffer layout (passes/gbuffer.wgsl): `position` = world xyz, view depth;
// `normal` = unit shading normal xyz, mesh index (-1 for background).

const PI: f32 = 3.14159265358979;

fn is_background(normal_texel: vec4<f32>) -> bool {
    return normal_texel.w < 0.0;
}
