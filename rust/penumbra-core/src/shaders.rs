//! WGSL sources and their composition.
//!
//! Every `.wgsl` file under `src/` is in [`FILES`], embedded by the table
//! `build.rs` writes: no list is kept by hand, and nothing here names a
//! method. A module builds its pipelines from the WGSL beside it with
//! [`crate::shader!`] (`shader!("visibility.wgsl")`), as `re_renderer`'s
//! `include_shader_module!` does, and from shared files with [`compose`]. A
//! file states what it uses of others with `#import`
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
//! A file that no file imports, with an entry point (`@compute`, `@vertex`,
//! `@fragment`) of its own or of a file it imports, is a shader a pipeline
//! is built from ([`is_entry`]);
//! `tests/shader_validation.rs` composes and validates each one with naga,
//! checks that every file is used, and checks every Rust uniform and storage
//! struct against naga's layout of its WGSL twin ([`GpuStruct`]: a module
//! declares its own with [`gpu_type!`], and build.rs finds every
//! declaration, as it finds the WGSL files).

use std::collections::BTreeSet;

include!(concat!(env!("OUT_DIR"), "/wgsl_files.rs"));

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

/// The path under `src/` of WGSL file `name` beside the Rust source file
/// `file` (as `file!()` gives it: from the workspace or the crate root).
pub fn beside(file: &str, name: &str) -> String {
    let file = file.replace('\\', "/");
    let under_src = match file.rfind("/src/") {
        Some(i) => &file[i + 5..],
        None => file.strip_prefix("src/").unwrap_or(&file),
    };
    match under_src.rfind('/') {
        Some(i) => format!("{}/{name}", &under_src[..i]),
        None => name.to_owned(),
    }
}

/// The composed source of the WGSL file `name` beside the calling module's
/// Rust file: `shader!("visibility.wgsl")` in `methods/pcss/mod.rs` composes
/// `methods/pcss/visibility.wgsl`.
#[macro_export]
macro_rules! shader {
    ($name:literal) => {
        $crate::shaders::compose(&$crate::shaders::beside(file!(), $name))
    };
}

/// Whether a file is a shader a pipeline is built from: no file imports it,
/// and it or a file it imports holds an entry point. An imported file's
/// entry points are its importers' (`shaders/per_pixel.wgsl`'s `main` runs
/// the importing pass's `shade`), composed and validated within each of them.
pub fn is_entry(path: &str) -> bool {
    let imported = FILES.iter().any(|(p, _)| imports(p).is_ok_and(|i| i.contains(&path)));
    let has_entry = |file: &&str| text(file).is_ok_and(|t| ["@compute", "@vertex", "@fragment"].iter().any(|e| t.contains(e)));
    !imported && files_of(path).is_ok_and(|files| files.iter().any(has_entry))
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

/// A [`GpuStruct`] of a Rust type and the WGSL struct it mirrors:
/// `gpu_struct!(Rust => "Wgsl" in "path/under/src.wgsl" { field, ... })`.
#[macro_export]
macro_rules! gpu_struct {
    ($rust:ty => $wgsl:literal in $file:literal { $($field:ident),* $(,)? }) => {
        $crate::shaders::GpuStruct {
            rust: stringify!($rust),
            wgsl: $wgsl,
            file: $file,
            size: std::mem::size_of::<$rust>(),
            fields: vec![$((stringify!($field), std::mem::offset_of!($rust, $field))),*],
        }
    };
}

/// Declares a Rust struct uploaded for a shader (`#[repr(C)]`, `Pod`) with
/// the WGSL struct it mirrors, its fields written once:
/// `Type::gpu_struct()` is its [`GpuStruct`] for the layout test.
///
/// ```text
/// gpu_type! {
///     /// docs
///     pub struct PcfUniform => "PcfKernel" in "methods/pcf/visibility.wgsl" {
///         pub(crate) kernel: f32,
///     }
/// }
/// ```
#[macro_export]
macro_rules! gpu_type {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident => $wgsl:literal in $file:literal {
            $( $(#[$field_meta:meta])* $field_vis:vis $field:ident : $ty:ty ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
        $vis struct $name {
            $( $(#[$field_meta])* $field_vis $field: $ty ),*
        }

        impl $name {
            /// This struct's layout with its WGSL twin's name and file
            /// (`tests/shader_validation.rs` checks them against naga's).
            pub fn gpu_struct() -> $crate::shaders::GpuStruct {
                $crate::gpu_struct!($name => $wgsl in $file { $($field),* })
            }
        }
    };
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

    #[test]
    fn a_module_names_the_wgsl_beside_it() {
        assert_eq!(beside("rust/penumbra-core/src/methods/pcss/mod.rs", "visibility.wgsl"), "methods/pcss/visibility.wgsl");
        assert_eq!(beside("src/passes/gbuffer.rs", "gbuffer.wgsl"), "passes/gbuffer.wgsl");
        assert_eq!(beside("C:\\x\\src\\passes\\shading.rs", "shading.wgsl"), "passes/shading.wgsl");
        assert_eq!(beside("src/lib.rs", "a.wgsl"), "a.wgsl");
    }
}
