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
