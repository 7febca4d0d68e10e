#import shaders/receiver.wgsl

// The object id image (SPEC's `object_id` output), shared by the shading
// pass and the object-id pass of passes/shading.rs: each pixel's mesh index
// (the G-buffer normal's w) through `mesh_objects` (per mesh: its object
// id); -1 off geometry and for an index past the table. Read back instead
// of the G-buffer's normals (a quarter of their bytes) where the normals
// themselves are not asked for. Bindings 2 and 3 in both passes.
@group(0) @binding(2) var<storage, read> mesh_objects: array<i32>;
@group(0) @binding(3) var object_ids_out: texture_storage_2d<r32sint, write>;

fn store_object_id(pixel: ScreenPixel) {
    var id = -1;
    if (pixel.geometry) {
        // w holds a mesh index as a float (exact below 2^24); a background
        // pixel's negative w is not read here.
        let mesh = u32(pixel.normal_texel.w);
        if (mesh < arrayLength(&mesh_objects)) {
            id = mesh_objects[mesh];
        }
    }
    textureStore(object_ids_out, pixel.px, vec4<i32>(id, 0, 0, 0));
}
