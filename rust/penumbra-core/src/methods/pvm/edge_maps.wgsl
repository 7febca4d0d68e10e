// The paper's two penumbra volume edge maps (Cournia 4.1.3), rebuilt from
// the edge-index map for the `pvm_edge0` and `pvm_edge1` intermediates: per
// map texel and layer, the end points of the silhouette edge whose volume is
// nearest the light there (w = 1), or zero where no volume is.

struct EdgePoints {
    h0: vec4<f32>,
    h1: vec4<f32>,
    links: vec4<u32>,
};

@group(0) @binding(0) var edge_index: texture_2d_array<u32>;
@group(0) @binding(1) var<storage, read> edges: array<EdgePoints>;
@group(0) @binding(2) var edge0_out: texture_storage_2d_array<rgba32float, write>;
@group(0) @binding(3) var edge1_out: texture_storage_2d_array<rgba32float, write>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(edge_index);
    if (id.x >= size.x || id.y >= size.y || id.z >= textureNumLayers(edge_index)) {
        return;
    }
    let t = vec2<i32>(id.xy);
    let layer = i32(id.z);
    let index = textureLoad(edge_index, t, layer, 0).x;
    var h0 = vec4<f32>(0.0);
    var h1 = vec4<f32>(0.0);
    // 0 marks no volume; indices come from the same build as the buffer.
    if (index > 0u && index <= arrayLength(&edges)) {
        h0 = vec4<f32>(edges[index - 1u].h0.xyz, 1.0);
        h1 = vec4<f32>(edges[index - 1u].h1.xyz, 1.0);
    }
    textureStore(edge0_out, t, layer, h0);
    textureStore(edge1_out, t, layer, h1);
}
