//! Every WGSL shader, as composed for the GPU, parses and validates with naga;
//! every `.wgsl` file under `src/` is in `shaders::FILES` (the table build.rs
//! writes) and part of at least one composed shader (the files of each are
//! derived from its imports); every Rust struct uploaded for a shader, the
//! shared passes' and each registered method's, has the layout naga gives its
//! WGSL twin. No GPU needed.

use std::collections::BTreeSet;

mod common;

#[test]
fn every_shader_validates_with_naga() {
    for (name, source, _) in penumbra_core::shaders::all() {
        let module = naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
        // Ray queries only where the shader enables them (`raytraced`).
        let capabilities = if source.lines().any(|l| l.trim() == "enable wgpu_ray_query;") {
            naga::valid::Capabilities::RAY_QUERY
        } else {
            naga::valid::Capabilities::empty()
        };
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities)
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
    }
}

#[test]
fn every_wgsl_file_is_listed_and_validated() {
    let on_disk = common::files_under_src("wgsl");
    assert!(!on_disk.is_empty());
    let listed: BTreeSet<String> = penumbra_core::shaders::FILES.iter().map(|(p, _)| p.to_string()).collect();
    assert_eq!(on_disk, listed, "build.rs lists exactly the .wgsl files under src/");
    let covered: BTreeSet<String> = penumbra_core::shaders::used_files().iter().map(|f| f.to_string()).collect();
    let missing: Vec<_> = on_disk.difference(&covered).collect();
    assert!(missing.is_empty(), "WGSL files in no composed shader: {missing:?}");
    for (path, _) in penumbra_core::shaders::FILES {
        // Every import names a listed file, without cycles.
        penumbra_core::shaders::files_of(path).unwrap();
    }
}

/// Each field of a Rust struct uploaded for a shader sits where naga lays out
/// the WGSL struct's member of the same name, and the sizes agree.
#[test]
fn rust_structs_match_their_wgsl_layouts() {
    // Every `gpu_type!` under src/, found by build.rs (no list kept by hand).
    let structs: &[fn() -> penumbra_core::shaders::GpuStruct] = include!(concat!(env!("OUT_DIR"), "/gpu_structs.rs"));
    // As many as the sources invoke the macro (outside comments), each once.
    let invocations: usize = common::files_under_src("rs")
        .iter()
        .map(|f| std::fs::read_to_string(common::src().join(f)).unwrap())
        .map(|text| text.lines().filter(|l| !l.trim_start().starts_with("//") && l.contains("gpu_type!")).count())
        .sum();
    assert!(invocations >= 20);
    assert_eq!(structs.len(), invocations, "build.rs found {} of the {invocations} gpu_type! declarations", structs.len());
    let names: BTreeSet<&str> = structs.iter().map(|f| f().rust).collect();
    assert_eq!(names.len(), structs.len(), "a struct listed twice");
    for s in structs.iter().map(|f| f()) {
        let source = penumbra_core::shaders::compose(s.file);
        let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| panic!("{}: {}", s.file, e.emit_to_string(&source)));
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let (handle, ty) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(s.wgsl))
            .unwrap_or_else(|| panic!("{}: no struct {} in {}", s.rust, s.wgsl, s.file));
        let naga::TypeInner::Struct { members, span } = &ty.inner else { panic!("{} is not a struct", s.wgsl) };
        assert_eq!(*span as usize, s.size, "{} is {} bytes, WGSL {} is {span} (alignment {:?})", s.rust, s.size, s.wgsl, layouter[handle].alignment);
        let wgsl: Vec<(String, usize)> = members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize)).collect();
        let rust: Vec<(String, usize)> = s.fields.iter().map(|(n, o)| (n.to_string(), *o)).collect();
        assert_eq!(rust, wgsl, "{} against {} in {}: (field, offset)", s.rust, s.wgsl, s.file);
    }
}

/// Branches and loops in a block, nested ones included.
fn branches(block: &naga::Block) -> usize {
    block
        .iter()
        .map(|statement| match statement {
            naga::Statement::If { accept, reject, .. } => 1 + branches(accept) + branches(reject),
            naga::Statement::Switch { cases, .. } => 1 + cases.iter().map(|c| branches(&c.body)).sum::<usize>(),
            naga::Statement::Loop { body, continuing, .. } => 1 + branches(body) + branches(continuing),
            naga::Statement::Block(inner) => branches(inner),
            _ => 0,
        })
        .sum()
}

/// Lavapipe recompiles a shader on every dispatch, and keeps the old code,
/// when uniform-buffer values decide its branches (`gpu::layout::parameters`):
/// compute passes take their parameters from read-only storage buffers, and a
/// shader that does read a uniform buffer (the raster passes) does not branch.
#[test]
fn no_shader_branches_on_a_uniform_buffer() {
    for (name, source, _) in penumbra_core::shaders::all() {
        let module = naga::front::wgsl::parse_str(&source).unwrap();
        let uniforms: Vec<_> = module
            .global_variables
            .iter()
            .filter(|(_, g)| g.space == naga::AddressSpace::Uniform)
            .map(|(_, g)| g.name.clone().unwrap_or_default())
            .collect();
        if uniforms.is_empty() {
            continue;
        }
        let compute = module.entry_points.iter().any(|e| e.stage == naga::ShaderStage::Compute);
        assert!(!compute, "{name}: a compute shader with uniform buffers {uniforms:?}; bind its parameters with layout::parameters");
        let count = module.functions.iter().map(|(_, f)| branches(&f.body)).sum::<usize>()
            + module.entry_points.iter().map(|e| branches(&e.function.body)).sum::<usize>();
        assert_eq!(count, 0, "{name}: reads uniform buffers {uniforms:?} and has {count} branches or loops");
    }
}
