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
// writes; with two RGBA32F maps it cost 3-7 times the shadow map on the real
// meshes, with the index about as much as the shadow map.

struct VolumeUniforms {
    view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    // near, far, unused, unused
    depth: vec4<f32>,
};

@group(0) @binding(0) var<uniform> volumes: VolumeUniforms;

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
    out.clip = volumes.view_proj * p;
    out.light_depth = -(volumes.view * p).z;
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
    out.depth = clamp(in.light_depth / volumes.depth.y, 0.0, 1.0);
    out.edge = in.edge + 1u;
    return out;
}
