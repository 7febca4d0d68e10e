#import passes/light_view.wgsl

// PVMF pass 2 (Cournia 5.1): render every silhouette edge's overestimated
// penumbra volume quadrilaterals from the light into the penumbra volume
// mask: its depth channel (linear light depth / far, the volume nearest the
// light) and, in a float channel, d_e, the distance from the light to the edge
// that gave rise to the volume.

struct MaskVertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) light_depth: f32,
    @location(1) @interpolate(flat) d_e: f32,
    // Repair "distance": the distance of the edge's point this part of the
    // volume comes from (its ends' distances, interpolated); 0 without it.
    @location(2) d_local: f32,
};

@vertex
fn vs_mask(@location(0) position: vec3<f32>, @location(1) d_e: f32, @location(2) d_local: f32) -> MaskVertexOut {
    var out: MaskVertexOut;
    let p = vec4<f32>(position, 1.0);
    out.clip = shadow.view_proj * p;
    out.light_depth = -(shadow.view * p).z;
    out.d_e = d_e;
    out.d_local = d_local;
    return out;
}

struct MaskOut {
    @builtin(frag_depth) depth: f32,
    @location(0) d_e: f32,
};

@fragment
fn fs_mask(in: MaskVertexOut) -> MaskOut {
    var out: MaskOut;
    // far > 0 by construction of the frustum.
    out.depth = clamp(in.light_depth / shadow.depth.y, 0.0, 1.0);
    out.d_e = select(in.d_e, in.d_local, in.d_local > 0.0);
    return out;
}

// occluder_distance = "farthest_edge" (beyond 5.2): the same volumes drawn
// again without the depth test into a channel that keeps, per texel, the
// largest d_e (blend max), over the light's far distance so that a 16-bit
// float holds it at 2^-11 relative precision. 0 (the clear value) marks
// texels without a volume.
@fragment
fn fs_mask_far(in: MaskVertexOut) -> @location(0) f32 {
    // far > 0 by construction of the frustum; d_e > 0 (no edge touches the light).
    return select(in.d_e, in.d_local, in.d_local > 0.0) / shadow.depth.y;
}
