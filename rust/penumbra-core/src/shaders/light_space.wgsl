// Shared by the shadow-map methods: the light's fitted frustum (light_frustum.rs).
// Shadow maps store linear light-view depth divided by `far`.

struct LightSpace {
    // World to light view (right-handed, looking down -z).
    view: mat4x4<f32>,
    // Frustum window on the unit-depth plane: x0, x1, y0, y1.
    window: vec4<f32>,
    // near, far, map size in texels, unused.
    depth: vec4<f32>,
};

// Distance of `p` along the light's axis; positive in front of the light.
fn light_view_depth(ls: LightSpace, p: vec3<f32>) -> f32 {
    return -(ls.view * vec4<f32>(p, 1.0)).z;
}

// Continuous shadow-map texel coordinates of `p` (row 0 at the window's top),
// matching the rasterisation of the off-centre projection.
fn light_map_coords(ls: LightSpace, p: vec3<f32>) -> vec2<f32> {
    let q = (ls.view * vec4<f32>(p, 1.0)).xyz;
    // Every surface point lies in front of the light (frustum fit), so -q.z > 0;
    // the max keeps the division finite for points pushed behind it by an offset.
    let z = max(-q.z, 1e-30);
    let uv = (q.xy / z - ls.window.xz) / (ls.window.yw - ls.window.xz);
    return vec2<f32>(uv.x, 1.0 - uv.y) * ls.depth.z;
}

// World-space width of one shadow-map texel at light-view depth `z`.
fn light_texel_size(ls: LightSpace, z: f32) -> f32 {
    let extent = max(ls.window.y - ls.window.x, ls.window.w - ls.window.z);
    return extent * z / ls.depth.z;
}
