#import shaders/receiver.wgsl
#import passes/shadow_test.wgsl

// Method `adaptive`, the subdivision test of Schwarzler et al. 3.3.2-3.3.3
// for one cell of the light's quadtree: `compare` reprojects the hard
// shadows of the cell's four corner maps into camera space (the comparison
// target, the camera's image or a `comparison_scale` fraction of it) and
// stores their sum per texel, 0-4 (5: background); `ring` counts the
// penumbra texels (1-3) whose 1-ring holds no other value (the occlusion
// query of the paper, an atomic counter here); `image` turns a level's
// summed sums or failing mask into an intermediate image.

@group(0) @binding(2) var map0: texture_depth_2d_array;
@group(0) @binding(3) var map1: texture_depth_2d_array;
@group(0) @binding(4) var map2: texture_depth_2d_array;
@group(0) @binding(5) var map3: texture_depth_2d_array;

struct CellCompare {
    // The shadow tests of the cell's four corner maps.
    tests: array<ShadowTest, 4>,
    // x: the cell's counter; y, z: the comparison target's size; w: 1 to add
    // to the level's images (intermediates), 0 not to. In `image`: x = 0 the
    // sums, 1 the failing mask.
    cell: vec4<u32>,
};
@group(0) @binding(6) var<storage, read> cell: CellCompare;
// Per comparison texel: the sum of the four shadow values (0-4), 5 off geometry.
@group(0) @binding(7) var<storage, read_write> sums: array<u32>;
// Per cell tested at this level: its failing texels.
@group(0) @binding(8) var<storage, read_write> failing: array<atomic<u32>>;
// Per comparison texel, for the intermediates: the level's sums added over
// its cells, then (from texel count on) its cells failing there.
@group(0) @binding(9) var<storage, read_write> level_images: array<atomic<u32>>;
@group(0) @binding(10) var image_out: texture_storage_2d<r32float, write>;

// The G-buffer pixel under comparison texel t (nearest, the target scaled
// to the camera's image).
fn comparison_pixel(t: vec2<u32>, target_size: vec2<u32>) -> vec2<i32> {
    let size = textureDimensions(gbuffer_normal);
    let px = (vec2<f32>(t) + 0.5) * vec2<f32>(size) / vec2<f32>(target_size);
    return min(vec2<i32>(px), vec2<i32>(size) - 1);
}

@compute @workgroup_size(8, 8)
fn compare(@builtin(global_invocation_id) id: vec3<u32>) {
    let target_size = cell.cell.yz;
    if (id.x >= target_size.x || id.y >= target_size.y) {
        return;
    }
    let px = comparison_pixel(id.xy, target_size);
    let normal_texel = textureLoad(gbuffer_normal, px, 0);
    var s = 5u;
    if (!is_background(normal_texel)) {
        let p = textureLoad(gbuffer_position, px, 0).xyz;
        let n = normal_texel.xyz;
        // tau_i of Eq. 1: 1 in the shadow of corner i.
        let lit = shadow_test_visibility(cell.tests[0], map0, p, n) + shadow_test_visibility(cell.tests[1], map1, p, n)
            + shadow_test_visibility(cell.tests[2], map2, p, n) + shadow_test_visibility(cell.tests[3], map3, p, n);
        s = 4u - u32(lit + 0.5);
    }
    sums[id.y * target_size.x + id.x] = s;
}

@compute @workgroup_size(8, 8)
fn ring(@builtin(global_invocation_id) id: vec3<u32>) {
    let target_size = cell.cell.yz;
    if (id.x >= target_size.x || id.y >= target_size.y) {
        return;
    }
    let i = id.y * target_size.x + id.x;
    let s = sums[i];
    var fails = false;
    if (s >= 1u && s <= 3u) {
        // A penumbra texel passes when a texel of its 1-ring (on geometry)
        // holds another value: the hard-shadow borders are close enough.
        fails = true;
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let q = vec2<i32>(id.xy) + vec2<i32>(dx, dy);
                if ((dx == 0 && dy == 0) || any(q < vec2<i32>(0)) || any(q >= vec2<i32>(target_size))) {
                    continue;
                }
                let t = sums[u32(q.y) * target_size.x + u32(q.x)];
                if (t != 5u && t != s) {
                    fails = false;
                }
            }
        }
    }
    if (fails) {
        atomicAdd(&failing[cell.cell.x], 1u);
    }
    if (cell.cell.w != 0u) {
        if (s <= 4u) {
            atomicAdd(&level_images[i], s);
        }
        if (fails) {
            atomicAdd(&level_images[target_size.x * target_size.y + i], 1u);
        }
    }
}

@compute @workgroup_size(8, 8)
fn image(@builtin(global_invocation_id) id: vec3<u32>) {
    let target_size = cell.cell.yz;
    if (id.x >= target_size.x || id.y >= target_size.y) {
        return;
    }
    let offset = cell.cell.x * target_size.x * target_size.y;
    let v = atomicLoad(&level_images[offset + id.y * target_size.x + id.x]);
    textureStore(image_out, vec2<i32>(id.xy), vec4<f32>(f32(v), 0.0, 0.0, 0.0));
}
