//! Helpers shared by the integration tests that read the crate's sources.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The crate's `src/`.
pub fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every file under `src/` whose name ends in `.{extension}`, as its path under `src/` with `/`.
pub fn files_under_src(extension: &str) -> BTreeSet<String> {
    fn walk(dir: &Path, extension: &str, out: &mut BTreeSet<String>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, extension, out);
            } else if path.extension().is_some_and(|e| e == extension) {
                out.insert(path.strip_prefix(src()).unwrap().to_string_lossy().replace('\\', "/"));
            }
        }
    }
    let mut out = BTreeSet::new();
    walk(&src(), extension, &mut out);
    out
}
