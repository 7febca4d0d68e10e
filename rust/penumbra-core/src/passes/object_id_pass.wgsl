#import passes/object_ids.wgsl
#import shaders/per_pixel.wgsl

// The object id image alone, where radiance (whose pass writes it too) is
// not asked for.
fn shade(pixel: ScreenPixel) {
    store_object_id(pixel);
}
