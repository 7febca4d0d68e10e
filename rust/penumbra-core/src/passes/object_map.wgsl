#import passes/light_view.wgsl

// The object map (passes/object_map.rs): the first surface's object + 1 per
// texel of the light centre's map, 0 where no surface is.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) object: u32,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) light_depth: f32,
    @location(1) @interpolate(flat) object: u32,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    let p = vec4<f32>(v.position, 1.0);
    out.clip = shadow.view_proj * p;
    out.light_depth = -(shadow.view * p).z;
    out.object = v.object;
    return out;
}

struct ObjectMapOut {
    @builtin(frag_depth) depth: f32,
    @location(0) object: u32,
};

@fragment
fn fs_main(in: VertexOut) -> ObjectMapOut {
    var out: ObjectMapOut;
    // far > 0 by construction of the frustum.
    out.depth = clamp(in.light_depth / shadow.depth.y, 0.0, 1.0);
    // MANY (u32 max) wraps to 0: "cannot tell", read as no surface.
    out.object = in.object + 1u;
    return out;
}
