//! WGSL sources. Each pass or method keeps its shader beside its module; shared
//! snippets live in `shaders/` and are prepended here. [`all`] lists every
//! composed shader so that `tests/shader_validation.rs` checks each with naga.

pub const COMMON: &str = include_str!("shaders/common.wgsl");
pub const LIGHT_SPACE: &str = include_str!("shaders/light_space.wgsl");
pub const SHADOW_TEST: &str = include_str!("shaders/shadow_test.wgsl");
pub const PCF: &str = include_str!("shaders/pcf.wgsl");

/// Concatenates snippets into one module source.
pub fn compose(parts: &[&str]) -> String {
    parts.join("\n")
}

pub fn gbuffer() -> String {
    compose(&[include_str!("passes/gbuffer.wgsl")])
}

pub fn shadow_map() -> String {
    compose(&[include_str!("passes/shadow_map.wgsl")])
}

pub fn shading() -> String {
    compose(&[COMMON, include_str!("passes/shading.wgsl")])
}

pub fn hard() -> String {
    compose(&[COMMON, LIGHT_SPACE, SHADOW_TEST, include_str!("methods/hard/visibility.wgsl")])
}

pub fn pcf() -> String {
    compose(&[COMMON, LIGHT_SPACE, SHADOW_TEST, PCF, include_str!("methods/pcf/visibility.wgsl")])
}

pub fn pcss() -> String {
    compose(&[COMMON, LIGHT_SPACE, SHADOW_TEST, PCF, include_str!("methods/pcss/visibility.wgsl")])
}

pub fn reference() -> String {
    compose(&[COMMON, LIGHT_SPACE, SHADOW_TEST, include_str!("methods/reference/visibility.wgsl")])
}

pub fn pvm_volumes() -> String {
    compose(&[include_str!("methods/pvm/volumes.wgsl")])
}

pub fn pvm_edge_maps() -> String {
    compose(&[include_str!("methods/pvm/edge_maps.wgsl")])
}

pub fn pvm() -> String {
    compose(&[COMMON, LIGHT_SPACE, SHADOW_TEST, include_str!("methods/pvm/visibility.wgsl")])
}

pub fn pvmf_mask() -> String {
    compose(&[include_str!("passes/shadow_map.wgsl"), include_str!("methods/pvmf/mask.wgsl")])
}

pub fn pvmf() -> String {
    compose(&[COMMON, LIGHT_SPACE, SHADOW_TEST, PCF, include_str!("methods/pvmf/estimate.wgsl")])
}

pub fn pvmf_blur() -> String {
    compose(&[include_str!("methods/pvmf/blur.wgsl")])
}

/// Every composed shader with the files it is made of (relative to `src/`).
pub fn all() -> Vec<(&'static str, String, &'static [&'static str])> {
    vec![
        ("gbuffer", gbuffer(), &["passes/gbuffer.wgsl"]),
        ("shadow_map", shadow_map(), &["passes/shadow_map.wgsl"]),
        ("shading", shading(), &["shaders/common.wgsl", "passes/shading.wgsl"]),
        (
            "hard",
            hard(),
            &["shaders/common.wgsl", "shaders/light_space.wgsl", "shaders/shadow_test.wgsl", "methods/hard/visibility.wgsl"],
        ),
        (
            "reference",
            reference(),
            &["shaders/common.wgsl", "shaders/light_space.wgsl", "shaders/shadow_test.wgsl", "methods/reference/visibility.wgsl"],
        ),
        (
            "pcf_taps",
            compose(&[COMMON, LIGHT_SPACE, SHADOW_TEST, PCF]),
            &["shaders/common.wgsl", "shaders/light_space.wgsl", "shaders/shadow_test.wgsl", "shaders/pcf.wgsl"],
        ),
        (
            "pcf",
            pcf(),
            &["shaders/common.wgsl", "shaders/light_space.wgsl", "shaders/shadow_test.wgsl", "shaders/pcf.wgsl", "methods/pcf/visibility.wgsl"],
        ),
        (
            "pcss",
            pcss(),
            &["shaders/common.wgsl", "shaders/light_space.wgsl", "shaders/shadow_test.wgsl", "shaders/pcf.wgsl", "methods/pcss/visibility.wgsl"],
        ),
        ("pvm_volumes", pvm_volumes(), &["methods/pvm/volumes.wgsl"]),
        ("pvm_edge_maps", pvm_edge_maps(), &["methods/pvm/edge_maps.wgsl"]),
        (
            "pvm",
            pvm(),
            &["shaders/common.wgsl", "shaders/light_space.wgsl", "shaders/shadow_test.wgsl", "methods/pvm/visibility.wgsl"],
        ),
        ("pvmf_mask", pvmf_mask(), &["passes/shadow_map.wgsl", "methods/pvmf/mask.wgsl"]),
        (
            "pvmf",
            pvmf(),
            &[
                "shaders/common.wgsl",
                "shaders/light_space.wgsl",
                "shaders/shadow_test.wgsl",
                "shaders/pcf.wgsl",
                "methods/pvmf/estimate.wgsl",
            ],
        ),
        ("pvmf_blur", pvmf_blur(), &["methods/pvmf/blur.wgsl"]),
    ]
}

/// Creates a shader module from a composed source.
pub fn module(device: &wgpu::Device, label: &str, source: String) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}
