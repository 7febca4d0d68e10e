#import passes/light_view.wgsl

// PVM pass 2 (Cournia 4.1.3): render the penumbra volumes' quadrilaterals
// from the light into the penumbra volume map: the penumbra volume depth map
// (PVDM, linear light depth / far, first-depth volume) and the penumbra
// volume edge map, in one pass.
//
// Departure from 4.1.3: the paper's two edge maps (PVEMs) hold the end
// points h0 and h1 of the silhouette edge that gave rise to the volume (six
// floats per texel, 16-bit there, 32-bit here). This map holds the edge's
// index + 1 (0 where no volume) and the visibility pass reads h0 and h1 from
// a buffer of the edges: the same information, 4 bytes per texel instead of
// 32. On a software rasteriser the pass's cost is the bytes it clears and
// writes (docs/real_meshes.md).

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) edge: u32,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) light_depth: f32,
    @location(1) @interpolate(flat) edge: u32,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    let p = vec4<f32>(v.position, 1.0);
    out.clip = shadow.view_proj * p;
    out.light_depth = -(shadow.view * p).z;
    out.edge = v.edge;
    return out;
}

struct VolumeMapOut {
    @builtin(frag_depth) depth: f32,
    @location(0) edge: u32,
};

@fragment
fn fs_main(in: VertexOut) -> VolumeMapOut {
    var out: VolumeMapOut;
    // far > 0 by construction of the frustum.
    out.depth = clamp(in.light_depth / shadow.depth.y, 0.0, 1.0);
    out.edge = in.edge + 1u;
    return out;
}
