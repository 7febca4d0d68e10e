#import passes/light_view.wgsl

// A raster from the light of primitives that carry a u32 id: the nearest
// one's linear light depth / far per texel, and its id + 1 (0 where nothing
// was drawn). PVM's penumbra volume map (methods/pvm/mod.rs: the id is the
// volume's silhouette edge) and the object map (passes/object_map.rs:
// the id is the triangle's object) are this pass.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) id: u32,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) light_depth: f32,
    @location(1) @interpolate(flat) id: u32,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    let p = vec4<f32>(v.position, 1.0);
    out.clip = shadow.view_proj * p;
    out.light_depth = -(shadow.view * p).z;
    out.id = v.id;
    return out;
}

struct LightIdOut {
    @builtin(frag_depth) depth: f32,
    @location(0) id: u32,
};

@fragment
fn fs_main(in: VertexOut) -> LightIdOut {
    var out: LightIdOut;
    // far > 0 by construction of the frustum.
    out.depth = clamp(in.light_depth / shadow.depth.y, 0.0, 1.0);
    // u32 max (object_map::MANY) wraps to 0: "none".
    out.id = in.id + 1u;
    return out;
}
