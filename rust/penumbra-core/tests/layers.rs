//! The core's modules keep SPEC section 2's one direction of use, from the
//! top down: `lib`/`renderer` → `methods/` (the registry and one folder per
//! method) → `method.rs` (the trait) → `passes/` → the frame → the scene's
//! geometry, light sampling and caches → `gpu/`, shaders, params, errors.
//! A module may use its own layer or those below it, never one above; no
//! two modules use each other (directly or round a circle); nothing below
//! `methods/` names a method, and no method's folder uses another's. Read
//! from the sources' `crate::` paths (comments left out).

use std::collections::{BTreeMap, BTreeSet};

mod common;
use common::src;

/// Layers from the top (0) down: a path prefix under `src/` and its rank.
const LAYERS: &[(&str, u32)] = &[
    ("lib.rs", 0),
    ("renderer.rs", 1),
    ("methods/", 2),
    ("method.rs", 3),
    ("passes/", 4),
    ("frame.rs", 5),
    ("pass_cache.rs", 6),
    ("geometry_cache.rs", 6),
    ("map_size.rs", 6),
    ("casters.rs", 6),
    ("silhouettes.rs", 6),
    ("light_sampling.rs", 6),
    ("light_frustum.rs", 7),
    ("scene.rs", 7),
    ("topology.rs", 7),
    ("image_io.rs", 7),
    ("occluders.rs", 8),
    ("gpu/", 8),
    ("shaders.rs", 9),
    ("params.rs", 9),
    ("error.rs", 10),
];

fn rank(file: &str) -> u32 {
    LAYERS.iter().find(|(prefix, _)| file.starts_with(prefix)).unwrap_or_else(|| panic!("{file}: in no layer of tests/layers.rs")).1
}

/// The file a `crate::a::b::c` path names: the longest prefix that is a module file.
fn file_of(path: &[&str], files: &BTreeSet<String>) -> Option<String> {
    (1..=path.len()).rev().find_map(|n| {
        let stem = path[..n].join("/");
        [format!("{stem}.rs"), format!("{stem}/mod.rs")].into_iter().find(|f| files.contains(f))
    })
}

/// Every file each file uses through `crate::` paths.
fn uses() -> BTreeMap<String, BTreeSet<String>> {
    let files = common::files_under_src("rs");
    let mut out = BTreeMap::new();
    for file in &files {
        let text = std::fs::read_to_string(src().join(file)).unwrap();
        let mut used = BTreeSet::new();
        for line in text.lines().filter(|l| !l.trim_start().starts_with("//")) {
            let mut rest = line;
            while let Some(i) = rest.find("crate::") {
                // `$crate::` (a macro's own crate) is the same.
                let after = &rest[i + 7..];
                let path: Vec<&str> = after.split("::").map(|s| s.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).next().unwrap_or("")).collect();
                let path: Vec<&str> = path.into_iter().take_while(|s| !s.is_empty() && s.chars().next().is_some_and(|c| c.is_ascii_lowercase())).collect();
                if let Some(target) = file_of(&path, &files) {
                    if &target != file {
                        used.insert(target);
                    }
                }
                rest = after;
            }
        }
        out.insert(file.clone(), used);
    }
    out
}

#[test]
fn every_module_uses_only_its_layer_and_those_below() {
    let mut wrong = Vec::new();
    for (file, used) in uses() {
        for target in used {
            if rank(&target) < rank(&file) && file != "lib.rs" {
                wrong.push(format!("{file} (layer {}) uses {target} (layer {})", rank(&file), rank(&target)));
            }
        }
    }
    assert!(wrong.is_empty(), "uses against the layers:\n{}", wrong.join("\n"));
}

#[test]
fn no_method_is_named_below_the_methods_and_no_method_uses_another() {
    let folder = |f: &str| f.strip_prefix("methods/").and_then(|r| r.split_once('/')).map(|(m, _)| m.to_owned());
    let mut wrong = Vec::new();
    for (file, used) in uses() {
        for target in used.iter().filter_map(|t| folder(t).map(|m| (t, m))) {
            let ok = file == "lib.rs" || file == "methods/mod.rs" || folder(&file).as_ref() == Some(&target.1);
            if !ok {
                wrong.push(format!("{file} uses {}", target.0));
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn no_two_modules_use_each_other_round_a_circle() {
    let graph = uses();
    fn visit(f: &str, graph: &BTreeMap<String, BTreeSet<String>>, stack: &mut Vec<String>, done: &mut BTreeSet<String>) -> Result<(), String> {
        if done.contains(f) {
            return Ok(());
        }
        if let Some(i) = stack.iter().position(|s| s == f) {
            return Err(format!("{} -> {f}", stack[i..].join(" -> ")));
        }
        stack.push(f.to_owned());
        for t in &graph[f] {
            // A parent module declares its children (`pub mod x;`); only uses count.
            visit(t, graph, stack, done)?;
        }
        stack.pop();
        done.insert(f.to_owned());
        Ok(())
    }
    let mut done = BTreeSet::new();
    for f in graph.keys().filter(|f| f.as_str() != "lib.rs") {
        visit(f, &graph, &mut Vec::new(), &mut done).unwrap_or_else(|e| panic!("a circle: {e}"));
    }
}

#[test]
fn the_layers_are_read_from_the_sources() {
    let graph = uses();
    // The reading sees what it must: the renderer uses the registry, a method the trait.
    assert!(graph["renderer.rs"].contains("methods/mod.rs"));
    assert!(graph["methods/pcss/mod.rs"].contains("method.rs"));
    assert!(graph["methods/pcss/mod.rs"].contains("passes/centre_map.rs"));
    assert!(graph.len() > 40);
}
