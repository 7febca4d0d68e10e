//! Writes `$OUT_DIR/wgsl_files.rs`: every `.wgsl` file under `src/`, found on
//! disk, as `(path under src/, include_str!(...))` for `shaders::FILES`. No
//! list of shaders is kept by hand, and `shaders.rs` names no method: a
//! module's WGSL is its own, beside it, and the build finds it.

use std::path::{Path, PathBuf};

fn wgsl_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir).expect("src/ is readable").map(|e| e.expect("a directory entry").path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            wgsl_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            out.push(path);
        }
    }
}

fn main() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    // A directory: cargo reruns this when anything below it changes.
    println!("cargo:rerun-if-changed=src");
    let mut files = Vec::new();
    wgsl_files(&src, &mut files);
    let mut table = String::from("/// Every WGSL file under `src/` (written by build.rs): its path under `src/` and its text.\npub const FILES: &[(&str, &str)] = &[\n");
    for path in &files {
        let relative = path.strip_prefix(&src).expect("under src/").to_string_lossy().replace('\\', "/");
        table.push_str(&format!("    ({relative:?}, include_str!({:?})),\n", path.to_string_lossy()));
    }
    table.push_str("];\n");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("wgsl_files.rs");
    // Rewritten only when it changes, so an edit elsewhere rebuilds nothing more.
    if std::fs::read_to_string(&out).ok().as_deref() != Some(table.as_str()) {
        std::fs::write(&out, table).expect("OUT_DIR is writable");
    }
}
