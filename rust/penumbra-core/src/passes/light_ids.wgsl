#import passes/light_view.wgsl

// A raster from the light of primitives that carry a u32 id: the nearest
// one's linear light depth / far per texel, and its id + 1 (0 where nothing
// was drawn). PVM's penumbra volume map (methods/pvm/mod.rs: the id is the
// volume's silhouette edge) and the object map (passes/object_map.rs:
// the id is the triangle's object + 1, drawn as the instance index: see
// vs_instance) are this pass.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) id: u32,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) light_depth: f32,
    @location(1) @interpolate(flat) id: u32,
};

fn light_vertex(position: vec3<f32>, id: u32) -> VertexOut {
    var out: VertexOut;
    let p = vec4<f32>(position, 1.0);
    out.clip = shadow.view_proj * p;
    out.light_depth = -(shadow.view * p).z;
    out.id = id;
    return out;
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    return light_vertex(v.position, v.id);
}

// The light geometry's positions, the id the draw's instance index (the
// object map: each mesh drawn as instance object + 1, so the fragment's
// id + 1 below is undone here).
@vertex
fn vs_instance(@location(0) position: vec3<f32>, @builtin(instance_index) instance: u32) -> VertexOut {
    return light_vertex(position, instance - 1u);
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
