// Shared by the shadow-map methods: the light's shadow-map projection
// (light_frustum.rs), one fitted frustum or the six faces of a cube around
// the light point. Maps are 2D array textures of 1 or 6 layers storing
// linear depth along the layer's axis divided by `far`.
//
// A map point is a layer and continuous texel coordinates in it. Filters
// that step away from a receiver's texel work in the receiver's layer;
// `map_wrap` takes coordinates that leave a cube face to the face their
// direction falls in, so kernels straddling a seam read the neighbour face.

struct LightSpace {
    // Frustum: world to light view (right-handed, looking down -z).
    // Cube: the translation by -origin; each face then rotates (cube_face_frame).
    view: mat4x4<f32>,
    // Window on the unit-depth plane: x0, x1, y0, y1 ((-1, 1, -1, 1) on cube faces).
    window: vec4<f32>,
    // near, far, map size in texels, layers (1: a frustum; 6: cube faces).
    depth: vec4<f32>,
    // x: the layers rendered (bit i: layer i); y, z, w unused.
    faces: vec4<u32>,
};

struct MapPoint {
    layer: i32,
    // Texel coordinates, row 0 at the window's top.
    coords: vec2<f32>,
};

fn is_cube(ls: LightSpace) -> bool {
    return ls.depth.w > 1.5;
}

// Rows right, up, -axis of cube face f (+x, -x, +y, -y, +z, -z), as glam's
// look_to_rh builds the view of light_frustum.rs's cube_face(f).
fn cube_face_frame(f: i32) -> mat3x3<f32> {
    var axis = vec3<f32>(0.0, 0.0, -1.0);
    var up = vec3<f32>(0.0, 1.0, 0.0);
    switch f {
        case 0: { axis = vec3<f32>(1.0, 0.0, 0.0); }
        case 1: { axis = vec3<f32>(-1.0, 0.0, 0.0); }
        case 2: { axis = vec3<f32>(0.0, 1.0, 0.0); up = vec3<f32>(0.0, 0.0, 1.0); }
        case 3: { axis = vec3<f32>(0.0, -1.0, 0.0); up = vec3<f32>(0.0, 0.0, -1.0); }
        case 4: { axis = vec3<f32>(0.0, 0.0, 1.0); }
        default: {}
    }
    // Unit, orthogonal axis and up: the crosses are exact unit vectors.
    let right = cross(axis, up);
    let true_up = cross(right, axis);
    // WGSL matrices are built from columns: transpose the rows.
    return transpose(mat3x3<f32>(right, true_up, -axis));
}

// The cube face a direction falls in: its dominant axis (ties: x, then y, then z).
fn cube_face_of(d: vec3<f32>) -> i32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(1, 0, d.x > 0.0);
    }
    if (a.y >= a.z) {
        return select(3, 2, d.y > 0.0);
    }
    return select(5, 4, d.z > 0.0);
}

// Whether a layer was rendered (cube faces that see no geometry are not).
fn layer_active(ls: LightSpace, layer: i32) -> bool {
    return (ls.faces.x & (1u << u32(layer))) != 0u;
}

// The layer whose map holds `p`.
fn light_layer(ls: LightSpace, p: vec3<f32>) -> i32 {
    if (!is_cube(ls)) {
        return 0;
    }
    return cube_face_of((ls.view * vec4<f32>(p, 1.0)).xyz);
}

// Light-view coordinates of a light-space offset `q` (view applied) in `layer`'s frame.
fn layer_frame(ls: LightSpace, layer: i32, q: vec3<f32>) -> vec3<f32> {
    if (!is_cube(ls)) {
        return q;
    }
    return cube_face_frame(layer) * q;
}

// Distance of `p` along the axis of its own layer; positive in front of the light.
fn light_view_depth(ls: LightSpace, p: vec3<f32>) -> f32 {
    if (!is_cube(ls)) {
        return -(ls.view * vec4<f32>(p, 1.0)).z;
    }
    let q = abs((ls.view * vec4<f32>(p, 1.0)).xyz);
    return max(q.x, max(q.y, q.z));
}

// Texel coordinates of light-view coordinates `q`, matching the
// rasterisation of the off-centre projection.
fn view_coords(ls: LightSpace, q: vec3<f32>) -> vec2<f32> {
    // Every surface point lies in front of the light (frustum fit, or its
    // own cube face), so -q.z > 0; the max keeps the division finite for
    // points pushed behind it by an offset.
    let z = max(-q.z, 1e-30);
    let uv = (q.xy / z - ls.window.xz) / (ls.window.yw - ls.window.xz);
    return vec2<f32>(uv.x, 1.0 - uv.y) * ls.depth.z;
}

// The map point of `p`: its layer and its coordinates there. A frustum is
// fitted around what may shadow something (light_frustum.rs), so points
// outside its window are lit, and reads there clamp to the map's empty
// border ring; a point at or behind the light's plane is sent far outside
// (no kernel offset brings it back in), not through the division.
fn light_map_point(ls: LightSpace, p: vec3<f32>) -> MapPoint {
    let layer = light_layer(ls, p);
    let q = layer_frame(ls, layer, (ls.view * vec4<f32>(p, 1.0)).xyz);
    if (!is_cube(ls) && !(-q.z > 0.0)) {
        return MapPoint(layer, vec2<f32>(-1e9));
    }
    return MapPoint(layer, view_coords(ls, q));
}

// Continuous shadow-map texel coordinates of `p` in its own layer.
fn light_map_coords(ls: LightSpace, p: vec3<f32>) -> vec2<f32> {
    return light_map_point(ls, p).coords;
}

// World-space width of one shadow-map texel at light-view depth `z`.
fn light_texel_size(ls: LightSpace, z: f32) -> f32 {
    let extent = max(ls.window.y - ls.window.x, ls.window.w - ls.window.z);
    return extent * z / ls.depth.z;
}

// World direction of the light ray through texel coordinates `c` of
// `layer`, scaled so that its depth along the layer's axis is 1.
fn light_ray(ls: LightSpace, layer: i32, c: vec2<f32>) -> vec3<f32> {
    let uv = c / ls.depth.z;
    let x = ls.window.x + uv.x * (ls.window.y - ls.window.x);
    let y = ls.window.z + (1.0 - uv.y) * (ls.window.w - ls.window.z);
    if (is_cube(ls)) {
        // The face frame is a rotation: its inverse is its transpose.
        return transpose(cube_face_frame(layer)) * vec3<f32>(x, y, -1.0);
    }
    // The view matrix is a rigid transform: its 3x3 part is a rotation, whose
    // inverse is its transpose.
    let rot = mat3x3<f32>(ls.view[0].xyz, ls.view[1].xyz, ls.view[2].xyz);
    return transpose(rot) * vec3<f32>(x, y, -1.0);
}

// Depth along `read`'s axis of the point at depth 1 along `layer`'s axis on
// the ray through `c` of `layer` (1 within one layer).
fn layer_depth_scale(ls: LightSpace, layer: i32, c: vec2<f32>, read: i32) -> f32 {
    if (!is_cube(ls) || layer == read) {
        return 1.0;
    }
    return -(cube_face_frame(read) * light_ray(ls, layer, c)).z;
}

// Coordinates `c` of `layer`, possibly beyond its edges, as the map point
// of the same direction: on a cube, the face that direction falls in; a
// frustum's single map keeps them (reads clamp to its border).
fn map_wrap(ls: LightSpace, layer: i32, c: vec2<f32>) -> MapPoint {
    if (!is_cube(ls)) {
        return MapPoint(layer, c);
    }
    let d = light_ray(ls, layer, c);
    let face = cube_face_of(d);
    if (face == layer) {
        return MapPoint(layer, c);
    }
    return MapPoint(face, view_coords(ls, cube_face_frame(face) * d));
}

// The texel under map point `m`, clamped to the map.
fn map_texel(map_size: vec2<u32>, m: MapPoint) -> vec2<i32> {
    return clamp(vec2<i32>(floor(m.coords)), vec2<i32>(0), vec2<i32>(map_size) - 1);
}
