#import shaders/common.wgsl

// The per-pixel opening of every screen pass (passes/screen.rs): the
// G-buffer's images, bound at 0 and 1 by every screen pass, and the pixel an
// invocation works on.

@group(0) @binding(0) var gbuffer_position: texture_2d<f32>;
@group(0) @binding(1) var gbuffer_normal: texture_2d<f32>;

struct ScreenPixel {
    // Texel coordinates in the image.
    px: vec2<i32>,
    // Inside the image: the invocation has a pixel to write.
    inside: bool,
    // On geometry (not background); p and n are only meaningful then.
    geometry: bool,
    // World position and unit shading normal.
    p: vec3<f32>,
    n: vec3<f32>,
    // The G-buffer's normal texel: xyz the normal, w the mesh index (-1 background).
    normal_texel: vec4<f32>,
};

// The pixel of invocation `id` of a per-pixel dispatch (8x8 workgroups over
// the image, so the last ones reach past its edges).
fn screen_pixel(id: vec3<u32>) -> ScreenPixel {
    var pixel: ScreenPixel;
    let size = textureDimensions(gbuffer_normal);
    pixel.px = vec2<i32>(id.xy);
    pixel.inside = id.x < size.x && id.y < size.y;
    if (!pixel.inside) {
        return pixel;
    }
    pixel.normal_texel = textureLoad(gbuffer_normal, pixel.px, 0);
    pixel.geometry = !is_background(pixel.normal_texel);
    if (pixel.geometry) {
        pixel.p = textureLoad(gbuffer_position, pixel.px, 0).xyz;
        pixel.n = pixel.normal_texel.xyz;
    }
    return pixel;
}
