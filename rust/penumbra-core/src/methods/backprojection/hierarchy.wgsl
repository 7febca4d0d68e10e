// Method `backprojection`, section 3 of Guennebaud, Barthe and Paulin 2007:
// the hierarchical shadow map (HSM). Level l >= 1 of each layer holds, per
// texel, the minimum and maximum light depth (world units along the layer's
// axis) of the 2^l x 2^l map texels it covers; level 0 is the shadow map
// itself. Built from level l - 1, one dispatch per level, like a mipmap. A
// layer that was not rendered (a cube face that sees nothing) holds the far
// plane: no occluder.

struct HierarchyLevel {
    // The level built (>= 1) and its side in texels; the side of the level
    // below (level 0: the map).
    level: u32,
    size: u32,
    below_size: u32,
    // First texel of this level and of the level below in `hierarchy`
    // (layers one after the other, rows of `size` texels).
    offset: u32,
    below_offset: u32,
    layers: u32,
    // Bit i: layer i was rendered.
    active_layers: u32,
    // The far plane: the map stores depth / far.
    far: f32,
};

@group(0) @binding(0) var shadow_map: texture_depth_2d_array;
@group(0) @binding(1) var<storage, read> level_params: HierarchyLevel;
// x: minimum depth, y: maximum depth.
@group(0) @binding(2) var<storage, read_write> hierarchy: array<vec2<f32>>;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let lv = level_params;
    if (id.x >= lv.size || id.y >= lv.size || id.z >= lv.layers) {
        return;
    }
    let layer = id.z;
    var lo = lv.far;
    var hi = lv.far;
    if ((lv.active_layers & (1u << layer)) != 0u) {
        lo = 3.0e38;
        hi = -3.0e38;
        for (var k = 0u; k < 4u; k++) {
            let c = id.xy * 2u + vec2<u32>(k & 1u, k >> 1u);
            // An odd side leaves the last texel of a level with fewer children.
            if (c.x < lv.below_size && c.y < lv.below_size) {
                var b: vec2<f32>;
                if (lv.level == 1u) {
                    let z = textureLoad(shadow_map, vec2<i32>(c), i32(layer), 0) * lv.far;
                    b = vec2<f32>(z, z);
                } else {
                    b = hierarchy[lv.below_offset + (layer * lv.below_size + c.y) * lv.below_size + c.x];
                }
                lo = min(lo, b.x);
                hi = max(hi, b.y);
            }
        }
    }
    hierarchy[lv.offset + (layer * lv.size + id.y) * lv.size + id.x] = vec2<f32>(lo, hi);
}
