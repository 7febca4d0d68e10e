// The light's view for raster passes that draw from it (shadow maps,
// penumbra volumes, PVMF's mask), bound at 0: `ShadowUniforms` in
// passes/shadow_map.rs. Depths are linear light-view depths; `far` > 0 by
// construction of the frustum (light_frustum.rs).

struct ShadowUniforms {
    view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    // near, far, unused, unused
    depth: vec4<f32>,
};

@group(0) @binding(0) var<uniform> shadow: ShadowUniforms;
