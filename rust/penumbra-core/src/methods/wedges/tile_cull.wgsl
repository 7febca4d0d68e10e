#import shaders/receiver.wgsl

// Method `wedges`, before the visibility pass (beyond the papers, which
// rasterise each wedge; issue 30: cost that follows the penumbra): one
// workgroup per quarter of a screen tile of the bins (geometry.rs `TILE` =
// 16 pixels; a quarter is 8 x 8, the workgroup's size) takes the box of its
// pixels' world positions from the G-buffer, and marks each wedge of its
// tile's bin whose support (the planes of
// `wedges::geometry::coverage_bounds`, or the wedge's own four for the 2002
// interpolation) leaves the whole box outside: no pixel of the tile gets a
// term from it, so the visibility pass skips it without reading it. The
// marks keep the bins' order: the pass's sums are those it made before.

struct WedgeBounds {
    // Up to four planes n.x <= w holding every point where the wedge's
    // term is non-zero; unused ones are (0, 0, 0, 1).
    planes: array<vec4<f32>, 4>,
};

struct CullSettings {
    // x: tiles per row; y: the planes' slack in world units (as f32 bits),
    // far above the rounding of evaluating them in f32; z: 1 to cull, 0 to
    // keep every wedge of a tile with geometry (`tile_cull=False`).
    tiles: vec4<u32>,
};

@group(0) @binding(2) var<storage, read> tile_offsets: array<u32>;
@group(0) @binding(3) var<storage, read> tile_wedges: array<u32>;
@group(0) @binding(4) var<storage, read> bounds: array<WedgeBounds>;
@group(0) @binding(5) var<storage, read> cull: CullSettings;
// Per entry i of tile_wedges and quarter q (0-3, row-major) of its tile: keep[4 i + q].
@group(0) @binding(6) var<storage, read_write> keep: array<u32>;
// The entries kept, over every tile (stats["wedge_tiles_kept"]).
@group(0) @binding(7) var<storage, read_write> kept_total: atomic<u32>;

// The tile's box, as order-preserving integers of the floats.
var<workgroup> box_lo: array<atomic<u32>, 3>;
var<workgroup> box_hi: array<atomic<u32>, 3>;
var<workgroup> geometry_pixels: atomic<u32>;
var<workgroup> kept: atomic<u32>;

// Order-preserving map of finite floats to u32 (negative floats reversed).
fn ordered(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn unordered(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) tile: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    if (local < 3u) {
        atomicStore(&box_lo[local], 0xffffffffu);
        atomicStore(&box_hi[local], 0u);
    }
    if (local == 0u) {
        atomicStore(&geometry_pixels, 0u);
        atomicStore(&kept, 0u);
    }
    workgroupBarrier();
    let pixel = screen_pixel(id);
    if (pixel.inside && pixel.geometry) {
        for (var k = 0u; k < 3u; k = k + 1u) {
            atomicMin(&box_lo[k], ordered(pixel.p[k]));
            atomicMax(&box_hi[k], ordered(pixel.p[k]));
        }
        atomicAdd(&geometry_pixels, 1u);
    }
    workgroupBarrier();
    let t = (tile.y / 2u) * cull.tiles.x + tile.x / 2u;
    let quarter = (tile.y % 2u) * 2u + tile.x % 2u;
    let start = tile_offsets[t];
    let end = tile_offsets[t + 1u];
    let any = atomicLoad(&geometry_pixels) > 0u;
    let lo = vec3<f32>(unordered(atomicLoad(&box_lo[0])), unordered(atomicLoad(&box_lo[1])), unordered(atomicLoad(&box_lo[2])));
    let hi = vec3<f32>(unordered(atomicLoad(&box_hi[0])), unordered(atomicLoad(&box_hi[1])), unordered(atomicLoad(&box_hi[2])));
    let centre = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo);
    let slack = bitcast<f32>(cull.tiles.y);
    for (var i = start + local; i < end; i = i + 64u) {
        var held = 1u;
        if (!any) {
            held = 0u;
        } else if (cull.tiles.z != 0u) {
            let b = bounds[tile_wedges[i]];
            for (var j = 0u; j < 4u; j = j + 1u) {
                let plane = b.planes[j];
                // The box's least n.x, against the plane's offset.
                if (dot(plane.xyz, centre) - dot(abs(plane.xyz), half) > plane.w + slack) {
                    held = 0u;
                }
            }
        }
        keep[4u * i + quarter] = held;
        atomicAdd(&kept, held);
    }
    workgroupBarrier();
    if (local == 0u) {
        atomicAdd(&kept_total, atomicLoad(&kept));
    }
}
