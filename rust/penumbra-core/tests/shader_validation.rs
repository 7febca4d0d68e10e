//! Every WGSL shader, as composed for the GPU, parses and validates with naga;
//! and every `.wgsl` file under `src/` is part of at least one composed shader.
//! No GPU needed.

use std::collections::BTreeSet;
use std::path::Path;

fn wgsl_files(dir: &Path, out: &mut BTreeSet<String>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            wgsl_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
            out.insert(path.strip_prefix(&src).unwrap().to_string_lossy().replace('\\', "/"));
        }
    }
}

#[test]
fn every_shader_validates_with_naga() {
    for (name, source, _) in penumbra_core::shaders::all() {
        let module = naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::empty())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
    }
}

#[test]
fn every_wgsl_file_is_validated() {
    let mut on_disk = BTreeSet::new();
    wgsl_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), &mut on_disk);
    assert!(!on_disk.is_empty());
    let covered: BTreeSet<String> = penumbra_core::shaders::all()
        .iter()
        .flat_map(|(_, _, files)| files.iter().map(|f| f.to_string()))
        .collect();
    let missing: Vec<_> = on_disk.difference(&covered).collect();
    assert!(missing.is_empty(), "WGSL files in no composed shader: {missing:?}");
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
