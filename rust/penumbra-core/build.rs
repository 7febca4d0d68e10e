//! Writes `$OUT_DIR/wgsl_files.rs`: every `.wgsl` file under `src/`, found on
//! disk, as `(path under src/, include_str!(...))` for `shaders::FILES`. No
//! list of shaders is kept by hand, and `shaders.rs` names no method: a
//! module's WGSL is its own, beside it, and the build finds it.
//!
//! Writes `$OUT_DIR/gpu_structs.rs` too: the `gpu_struct` function of every
//! struct declared with `gpu_type!` under `src/`, as an array expression that
//! `tests/shader_validation.rs` includes to check each against naga's layout
//! of its WGSL twin.

use std::path::{Path, PathBuf};

fn files_with(dir: &Path, extension: &str, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).expect("src/ is readable").map(|e| e.expect("a directory entry").path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            files_with(&path, extension, out);
        } else if path.extension().is_some_and(|e| e == extension) {
            out.push(path);
        }
    }
}

fn main() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    // A directory: cargo reruns this when anything below it changes.
    println!("cargo:rerun-if-changed=src");
    let mut files = Vec::new();
    files_with(&src, "wgsl", &mut files);
    let mut table = String::from("/// Every WGSL file under `src/` (written by build.rs): its path under `src/` and its text.\npub const FILES: &[(&str, &str)] = &[\n");
    for path in &files {
        let relative = path.strip_prefix(&src).expect("under src/").to_string_lossy().replace('\\', "/");
        table.push_str(&format!("    ({relative:?}, include_str!({:?})),\n", path.to_string_lossy()));
    }
    table.push_str("];\n");
    write_if_changed("wgsl_files.rs", &table);

    let mut sources = Vec::new();
    files_with(&src, "rs", &mut sources);
    let mut structs = String::from("&[\n");
    for path in &sources {
        let relative = path.strip_prefix(&src).expect("under src/").with_extension("");
        let mut module: Vec<String> = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
        if matches!(module.last().map(String::as_str), Some("mod" | "lib")) {
            module.pop();
        }
        let text = std::fs::read_to_string(path).expect("a source file is readable");
        for name in gpu_type_names(&text) {
            let path = std::iter::once("penumbra_core".to_string()).chain(module.iter().cloned()).chain([name]).collect::<Vec<_>>().join("::");
            structs.push_str(&format!("    {path}::gpu_struct,\n"));
        }
    }
    structs.push_str("]\n");
    write_if_changed("gpu_structs.rs", &structs);
}

/// The struct names of the `gpu_type!` invocations in one file: after a line
/// (not a comment) that opens `gpu_type! {`, the first `struct NAME =>`.
fn gpu_type_names(text: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut open = false;
    for line in text.lines().map(str::trim) {
        if line.starts_with("//") {
            continue;
        }
        if line.contains("gpu_type! {") {
            open = true;
        } else if open {
            if let Some(rest) = line.split("struct ").nth(1).filter(|r| r.contains("=>")) {
                names.push(rest.split_whitespace().next().expect("a struct name").to_string());
                open = false;
            }
        }
    }
    names
}

/// Rewritten only when it changes, so an edit elsewhere rebuilds nothing more.
fn write_if_changed(name: &str, text: &str) {
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join(name);
    if std::fs::read_to_string(&out).ok().as_deref() != Some(text) {
        std::fs::write(&out, text).expect("OUT_DIR is writable");
    }
}
