#import passes/light_depth.wgsl

// The solid layers (passes/solid_layers.rs): each fragment of a solid's
// triangles inserts its linear light depth into its texel's LAYERS slots.
// Slots hold the complement of the depth's bits (a cleared buffer is
// empty; positive floats order as their bits, so the largest complement is
// the nearest depth). Each slot keeps the larger of what it holds and what
// arrives (`atomicMax`) and the other goes on to the next slot: whatever
// the order of the fragments, the slots end with the LAYERS nearest depths
// in order. A depth within SAME_SURFACE of one a slot holds is that
// surface drawn again and stops there.

struct SolidFace {
    layer: u32,
    side: u32,
    unused: vec2<u32>,
};

@group(0) @binding(1) var<storage, read_write> layers: array<atomic<u32>>;
@group(0) @binding(2) var<uniform> face: SolidFace;

const LAYERS: u32 = 4u;
const HEADER: u32 = 4u;
const SAME_SURFACE: f32 = 1e-5;

// Whether `carried` moves on from a slot that held `held` (which now holds
// the larger of the two): not where the slot was empty (it took `carried`)
// nor where the two are one surface; 0 then, which no slot takes.
fn passed_on(held: u32, carried: u32, depth: f32) -> u32 {
    let same = abs(bitcast<f32>(~held) - bitcast<f32>(~carried)) <= SAME_SURFACE * depth;
    return select(min(held, carried), 0u, (held == 0u) | same);
}

// The slots written out, not looped: a raster shader that reads a uniform
// buffer does not branch (tests/shader_validation.rs: lavapipe recompiles
// it per draw). An insertion that stopped carries 0, which atomicMax leaves.
@fragment
fn fs_main(in: VertexOut) {
    // The clip volume keeps 0 <= depth <= far: a positive depth (bits > 0),
    // whose complement is not 0 (empty).
    let depth = max(in.light_depth, 1e-30);
    let x = min(u32(in.clip.x), face.side - 1u);
    let y = min(u32(in.clip.y), face.side - 1u);
    let base = HEADER + ((face.layer * face.side + y) * face.side + x) * LAYERS;
    var carried = ~bitcast<u32>(depth);
    carried = passed_on(atomicMax(&layers[base], carried), carried, depth);
    carried = passed_on(atomicMax(&layers[base + 1u], carried), carried, depth);
    carried = passed_on(atomicMax(&layers[base + 2u], carried), carried, depth);
    atomicMax(&layers[base + 3u], carried);
}
