//! WGSL sources and their composition.
//!
//! Every `.wgsl` file of the crate is listed once in [`FILES`] (embedded with
//! `include_str!`). A file states what it uses of others with `#import`
//! lines at its top, naming the file by its path under `src/`:
//!
//! ```text
//! #import shaders/receiver.wgsl
//! #import passes/shadow_test.wgsl
//! ```
//!
//! [`compose`] resolves them: each imported file once, before the files that
//! import it (depth first), then the file itself with its `#import` lines
//! blanked (so line numbers within it stay as written). WGSL has no modules,
//! so composition is textual, as the shader compiler sees it; names are
//! global and a file may use only what it imports, directly or through its
//! imports. Bevy's `naga_oil` (0.23 supports the naga 30 of wgpu 30) composes
//! at the level of naga's IR instead: it mangles every imported name in the
//! module the driver sees (and in every naga and driver message) and needs
//! qualified names or item lists at each use; file-level imports are all
//! these shaders need, and this keeps the WGSL the GPU compiles the WGSL
//! that is written.
//!
//! A file with an entry point (`@compute`, `@vertex`, `@fragment`) is a
//! shader a pipeline is built from; `tests/shader_validation.rs` composes
//! and validates each one with naga, checks that every file on disk is
//! listed and used, and checks every Rust uniform and storage struct
//! against naga's layout of its WGSL twin ([`gpu_structs`]).

use std::collections::BTreeSet;

/// Every WGSL file of the crate: its path under `src/` and its text.
pub const FILES: &[(&str, &str)] = &[
    ("shaders/common.wgsl", include_str!("shaders/common.wgsl")),
    ("shaders/light_space.wgsl", include_str!("shaders/light_space.wgsl")),
    ("shaders/receiver.wgsl", include_str!("shaders/receiver.wgsl")),
    ("shaders/light_samples.wgsl", include_str!("shaders/light_samples.wgsl")),
    ("passes/light_view.wgsl", include_str!("passes/light_view.wgsl")),
    ("passes/shadow_test.wgsl", include_str!("passes/shadow_test.wgsl")),
    ("passes/pcf_taps.wgsl", include_str!("passes/pcf_taps.wgsl")),
    ("passes/gbuffer.wgsl", include_str!("passes/gbuffer.wgsl")),
    ("passes/shadow_map.wgsl", include_str!("passes/shadow_map.wgsl")),
    ("passes/shading.wgsl", include_str!("passes/shading.wgsl")),
    ("passes/light_ids.wgsl", include_str!("passes/light_ids.wgsl")),
    ("methods/hard/visibility.wgsl", include_str!("methods/hard/visibility.wgsl")),
    ("methods/pcf/visibility.wgsl", include_str!("methods/pcf/visibility.wgsl")),
    ("methods/pcss/visibility.wgsl", include_str!("methods/pcss/visibility.wgsl")),
    ("methods/reference/visibility.wgsl", include_str!("methods/reference/visibility.wgsl")),
    ("methods/adaptive/compare.wgsl", include_str!("methods/adaptive/compare.wgsl")),
    ("methods/adaptive/evaluate.wgsl", include_str!("methods/adaptive/evaluate.wgsl")),
    ("methods/raytraced/visibility.wgsl", include_str!("methods/raytraced/visibility.wgsl")),
    ("methods/pvm/visibility.wgsl", include_str!("methods/pvm/visibility.wgsl")),
    ("methods/pvm/edge_maps.wgsl", include_str!("methods/pvm/edge_maps.wgsl")),
    ("methods/pvmf/mask.wgsl", include_str!("methods/pvmf/mask.wgsl")),
    ("methods/pvmf/estimate.wgsl", include_str!("methods/pvmf/estimate.wgsl")),
    ("methods/pvmf/blur.wgsl", include_str!("methods/pvmf/blur.wgsl")),
    ("methods/backprojection/hierarchy.wgsl", include_str!("methods/backprojection/hierarchy.wgsl")),
    ("methods/backprojection/contour.wgsl", include_str!("methods/backprojection/contour.wgsl")),
    ("methods/backprojection/discontinuity.wgsl", include_str!("methods/backprojection/discontinuity.wgsl")),
    ("methods/backprojection/classify.wgsl", include_str!("methods/backprojection/classify.wgsl")),
    ("methods/backprojection/visibility.wgsl", include_str!("methods/backprojection/visibility.wgsl")),
    ("methods/backprojection/pull_push.wgsl", include_str!("methods/backprojection/pull_push.wgsl")),
    ("methods/wedges/visibility.wgsl", include_str!("methods/wedges/visibility.wgsl")),
    ("methods/triangle_masks/masks.wgsl", include_str!("methods/triangle_masks/masks.wgsl")),
];

const IMPORT: &str = "#import ";

fn text(path: &str) -> Result<&'static str, String> {
    FILES.iter().find(|(p, _)| *p == path).map(|(_, t)| *t).ok_or_else(|| format!("no WGSL file '{path}' in shaders::FILES"))
}

/// The files `path` imports directly, in order.
pub fn imports(path: &str) -> Result<Vec<&'static str>, String> {
    text(path)?
        .lines()
        .filter_map(|line| line.trim().strip_prefix(IMPORT))
        .map(|name| {
            let name = name.trim();
            FILES.iter().map(|(p, _)| *p).find(|p| *p == name).ok_or_else(|| format!("{path}: imports unknown file '{name}'"))
        })
        .collect()
}

/// `path` and everything it imports, dependencies first, each once.
pub fn files_of(path: &str) -> Result<Vec<&'static str>, String> {
    fn visit(path: &'static str, stack: &mut Vec<&'static str>, out: &mut Vec<&'static str>) -> Result<(), String> {
        if out.contains(&path) {
            return Ok(());
        }
        if stack.contains(&path) {
            return Err(format!("import cycle: {} -> {path}", stack.join(" -> ")));
        }
        stack.push(path);
        for dependency in imports(path)? {
            visit(dependency, stack, out)?;
        }
        stack.pop();
        out.push(path);
        Ok(())
    }
    let path = FILES.iter().map(|(p, _)| *p).find(|p| *p == path).ok_or_else(|| format!("no WGSL file '{path}' in shaders::FILES"))?;
    let mut out = Vec::new();
    visit(path, &mut Vec::new(), &mut out)?;
    Ok(out)
}

const ENABLE: &str = "enable ";

/// The composed source of `path`: its imports resolved. WGSL wants its
/// `enable` directives (`enable wgpu_ray_query;`) before any declaration:
/// those of every file come first, each once, and are blanked where written.
pub fn try_compose(path: &str) -> Result<String, String> {
    let files = files_of(path)?;
    let mut out = String::new();
    for file in &files {
        for line in text(file)?.lines().filter(|l| l.trim().starts_with(ENABLE)) {
            if !out.lines().any(|l| l == line.trim()) {
                out.push_str(line.trim());
                out.push('\n');
            }
        }
    }
    for file in files {
        out.push_str(&format!("// ---- {file}\n"));
        for line in text(file)?.lines() {
            let trimmed = line.trim();
            if !trimmed.starts_with(IMPORT) && !trimmed.starts_with(ENABLE) {
                out.push_str(line);
            }
            out.push('\n');
        }
    }
    Ok(out)
}

/// [`try_compose`] for a path the crate itself names (a missing file or an
/// import cycle is a bug caught by `tests/shader_validation.rs`).
pub fn compose(path: &str) -> String {
    try_compose(path).unwrap_or_else(|e| panic!("{e}"))
}

/// Whether a file holds an entry point: a shader a pipeline is built from.
pub fn is_entry(path: &str) -> bool {
    text(path).is_ok_and(|t| ["@compute", "@vertex", "@fragment"].iter().any(|e| t.contains(e)))
}

/// Every shader a pipeline is built from, composed, with the files it is made of.
pub fn all() -> Vec<(&'static str, String, Vec<&'static str>)> {
    FILES
        .iter()
        .filter(|(p, _)| is_entry(p))
        .map(|(p, _)| (*p, compose(p), files_of(p).unwrap_or_default()))
        .collect()
}

/// Every file that some shader uses.
pub fn used_files() -> BTreeSet<&'static str> {
    all().into_iter().flat_map(|(_, _, files)| files).collect()
}

/// Creates a shader module from a composed source.
pub fn module(device: &wgpu::Device, label: &str, source: String) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}

/// A Rust struct uploaded to a uniform or storage buffer and its WGSL twin:
/// the names, the file that declares the WGSL struct, and the Rust layout
/// (size, and each field's name and offset).
#[derive(Debug, Clone)]
pub struct GpuStruct {
    pub rust: &'static str,
    pub wgsl: &'static str,
    pub file: &'static str,
    pub size: usize,
    pub fields: Vec<(&'static str, usize)>,
}

macro_rules! gpu_struct {
    ($rust:ty => $wgsl:literal in $file:literal { $($field:ident),* $(,)? }) => {
        GpuStruct {
            rust: stringify!($rust),
            wgsl: $wgsl,
            file: $file,
            size: std::mem::size_of::<$rust>(),
            fields: vec![$((stringify!($field), std::mem::offset_of!($rust, $field))),*],
        }
    };
}

/// Every Rust struct a pass uploads for a shader, with its WGSL twin.
pub fn gpu_structs() -> Vec<GpuStruct> {
    use crate::methods::{adaptive, backprojection, pcf, pcss, pvm, pvmf, raytraced, reference, triangle_masks, wedges};
    use crate::passes::{gbuffer, shading, shadow_map, shadow_test};
    vec![
        gpu_struct!(shadow_map::LightSpaceUniform => "LightSpace" in "shaders/light_space.wgsl" { view, window, depth, faces }),
        gpu_struct!(shadow_map::ShadowUniforms => "ShadowUniforms" in "passes/light_view.wgsl" { view_proj, view, depth }),
        gpu_struct!(shadow_test::ShadowTestUniform => "ShadowTest" in "passes/shadow_test.wgsl" { light_space, center, bias, mode }),
        gpu_struct!(gbuffer::CameraUniforms => "CameraUniforms" in "passes/gbuffer.wgsl" { view_proj, view }),
        gpu_struct!(shading::ShadingUniforms => "ShadingUniforms" in "passes/shading.wgsl" { light, intensity, ambient, eye }),
        gpu_struct!(pcf::PcfUniform => "PcfKernel" in "methods/pcf/visibility.wgsl" { kernel, samples, seed, nearest }),
        gpu_struct!(pcss::PcssUniform => "PcssSampling" in "methods/pcss/visibility.wgsl" { blocker_samples, filter_samples, seed, poisson, cone, horizon }),
        gpu_struct!(reference::SampleWeightUniform => "SampleWeight" in "methods/reference/visibility.wgsl" { normal, light_center }),
        gpu_struct!(adaptive::CellCompareUniform => "CellCompare" in "methods/adaptive/compare.wgsl" { tests, cell }),
        gpu_struct!(pvm::EdgePoints => "EdgePoints" in "methods/pvm/visibility.wgsl" { h0, h1 }),
        gpu_struct!(raytraced::RaySettingsUniform => "RaySettings" in "methods/raytraced/visibility.wgsl" { light, offset, counts }),
        gpu_struct!(raytraced::SampleUniform => "LightSample" in "shaders/light_samples.wgsl" { position, normal }),
        gpu_struct!(triangle_masks::MaskSettingsUniform => "MaskSettings" in "methods/triangle_masks/masks.wgsl" { light, offset, counts, tiles, dispatch }),
        gpu_struct!(pvmf::SettingsUniform => "PvmfSettings" in "methods/pvmf/estimate.wgsl" { s_p, n_pcf, seed, flags, blur_min_width }),
        gpu_struct!(pvmf::BlurUniform => "BlurSettings" in "methods/pvmf/blur.wgsl" { step, half_width, count }),
        gpu_struct!(backprojection::BackprojectionUniform => "Backprojection" in "methods/backprojection/contour.wgsl" {
            t, t_k, beta, s_min, eye, flags, levels, max_kernel, pad, level_offset, level_size
        }),
        gpu_struct!(backprojection::HierarchyLevelUniform => "HierarchyLevel" in "methods/backprojection/hierarchy.wgsl" {
            level, size, below_size, offset, below_offset, layers, active_layers, far
        }),
        gpu_struct!(backprojection::DiscontinuityUniform => "DiscontinuityStep" in "methods/backprojection/discontinuity.wgsl" { mode, radius, pad0, pad1 }),
        gpu_struct!(backprojection::PullPushUniform => "PullPushStep" in "methods/backprojection/pull_push.wgsl" {
            mode, width, height, offset, other_width, other_height, other_offset, pad
        }),
        gpu_struct!(wedges::WedgeGpu => "Wedge" in "methods/wedges/visibility.wgsl" { a, b, dir, front, back, hard, left, right, u_left, u_right }),
        gpu_struct!(wedges::WedgeSettingsUniform => "WedgeSettings" in "methods/wedges/visibility.wgsl" { tiles }),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn imports_resolve_once_in_dependency_order() {
        let files = files_of("methods/pcss/visibility.wgsl").unwrap();
        assert_eq!(files.last(), Some(&"methods/pcss/visibility.wgsl"));
        let position = |f: &str| files.iter().position(|x| *x == f).unwrap();
        assert!(position("shaders/light_space.wgsl") < position("passes/shadow_test.wgsl"));
        assert!(position("passes/shadow_test.wgsl") < position("passes/pcf_taps.wgsl"));
        let unique: BTreeSet<_> = files.iter().collect();
        assert_eq!(unique.len(), files.len());
        let source = compose("methods/pcss/visibility.wgsl");
        assert!(!source.lines().any(|l| l.trim().starts_with(IMPORT)));
        assert!(try_compose("methods/nope.wgsl").unwrap_err().contains("no WGSL file"));
    }
}
