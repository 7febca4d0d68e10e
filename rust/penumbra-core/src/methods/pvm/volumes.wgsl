#import passes/light_view.wgsl

// PVM pass 2 (Cournia 4.1.3): render the penumbra volumes' quadrilaterals
// from the light into the penumbra volume map: the penumbra volume depth map
// (PVDM, linear light depth / far, first-depth volume) and the two penumbra
// volume edge maps (PVEMs, the world-space end points h0 and h1 of the
// silhouette edge that gave rise to the volume), in one pass with multiple
// render targets and float32 edge points.


struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) h0: vec3<f32>,
    @location(2) h1: vec3<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) light_depth: f32,
    @location(1) @interpolate(flat) h0: vec3<f32>,
    @location(2) @interpolate(flat) h1: vec3<f32>,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    let p = vec4<f32>(v.position, 1.0);
    out.clip = shadow.view_proj * p;
    out.light_depth = -(shadow.view * p).z;
    out.h0 = v.h0;
    out.h1 = v.h1;
    return out;
}

struct VolumeMapOut {
    @builtin(frag_depth) depth: f32,
    @location(0) edge0: vec4<f32>,
    @location(1) edge1: vec4<f32>,
};

@fragment
fn fs_main(in: VertexOut) -> VolumeMapOut {
    var out: VolumeMapOut;
    // far > 0 by construction of the frustum.
    out.depth = clamp(in.light_depth / shadow.depth.y, 0.0, 1.0);
    out.edge0 = vec4<f32>(in.h0, 1.0);
    out.edge1 = vec4<f32>(in.h1, 1.0);
    return out;
}
