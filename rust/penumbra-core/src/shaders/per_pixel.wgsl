#import shaders/receiver.wgsl

// The entry point of a screen pass that works pixel by pixel (passes/screen.rs
// runs `main`): each invocation whose pixel lies inside the image runs the
// importing file's `fn shade(pixel: ScreenPixel)`; those of the last
// workgroups that reach past the image's edges do nothing.

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(id);
    if (pixel.inside) {
        shade(pixel);
    }
}
