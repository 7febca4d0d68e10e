//! The pass cache: outputs of the passes that a change of a late parameter
//! does not affect, kept between renders and keyed by exactly the inputs
//! that determine them. It knows no method: entries are keyed by the pass's
//! name and its [`PassKey`], and hold any output type.
//!
//! A key is the byte string of everything a pass reads: a 64-bit hash of the
//! scene's geometry (the triangle corners the rasterising passes draw and
//! the meshes the silhouette methods weld), the matrices, light values and
//! uniform blocks the pass uploads (their bit patterns: `-0.0` and `0.0` are
//! different keys), texture sizes, and the keys of the cached passes it
//! reads. A lookup compares whole keys, so two renders share an entry only
//! when the pass would have read the same bits; only the geometry is hashed.
//!
//! Memory is bounded by a small LRU per pass ([`CachedPass::capacity`],
//! declared by whoever owns the pass: the renderer for the G-buffer and the
//! shadow map, each method for its own); an entry is released when it falls
//! out (or on [`PassCache::clear`]). Entries are inserted only after the
//! render that made them has been submitted and waited for (the frame holds
//! them until then), so a concurrent render never reads a pass still in
//! flight.

use std::any::Any;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex};

use crate::light_frustum::{LightFrustum, LightProjection};
use crate::scene::PreparedScene;

/// A pass whose output may be cached: its name (as in `timings` and in the
/// `reused_<name>` stats) and how many entries are kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CachedPass {
    pub name: &'static str,
    pub capacity: usize,
}

/// The exact inputs of one pass, as bytes.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct PassKey(Vec<u8>);

impl PassKey {
    pub fn new(pass: &str) -> Self {
        let mut key = Self(Vec::with_capacity(128));
        key.bytes(pass.as_bytes());
        key
    }

    /// Length-prefixed, so that consecutive fields cannot run into each other.
    pub fn bytes(&mut self, b: &[u8]) -> &mut Self {
        self.0.extend_from_slice(&(b.len() as u64).to_le_bytes());
        self.0.extend_from_slice(b);
        self
    }

    pub fn u32(&mut self, v: u32) -> &mut Self {
        self.bytes(&v.to_le_bytes())
    }

    pub fn f32s(&mut self, v: &[f32]) -> &mut Self {
        self.bytes(bytemuck::cast_slice(v))
    }

    pub fn f64s(&mut self, v: &[f64]) -> &mut Self {
        self.bytes(bytemuck::cast_slice(v))
    }

    pub fn pod<T: bytemuck::Pod>(&mut self, v: &T) -> &mut Self {
        self.bytes(bytemuck::bytes_of(v))
    }

    /// Another pass's key: this pass reads that pass's output.
    pub fn key(&mut self, other: &PassKey) -> &mut Self {
        self.bytes(&other.0)
    }

    pub fn frustum(&mut self, f: &LightFrustum) -> &mut Self {
        self.f32s(&f.view.to_cols_array())
            .f32s(&f.projection.to_cols_array())
            .f32s(&f.window.to_array())
            .f32s(&[f.near, f.far])
    }

    /// Every face of a projection and which are rendered.
    pub fn projection(&mut self, p: &LightProjection) -> &mut Self {
        self.u32(p.active).f32s(&p.origin.to_array());
        for face in &p.faces {
            self.frustum(face);
        }
        self
    }

    pub fn finish(&mut self) -> Self {
        std::mem::take(self)
    }
}

/// A 64-bit hash of what the passes read of a scene's geometry: the corners
/// (positions, normals and mesh indices) and every mesh's vertices and faces
/// (`PreparedScene::mesh_keys`, hashed once and shared with the silhouette caches).
pub fn geometry_hash(scene: &PreparedScene) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    let corners: &[u8] = bytemuck::cast_slice(&scene.corners);
    corners.hash(&mut h);
    scene.mesh_keys().hash(&mut h);
    h.finish()
}

/// A cached output of any type.
pub type Entry = Arc<dyn Any + Send + Sync>;

/// One pass's entries, most recently used first.
struct Lru {
    pass: CachedPass,
    entries: Vec<(PassKey, Entry)>,
}

/// The renderer's cache of pass outputs, one LRU per declared pass; when
/// disabled it keeps nothing.
pub struct PassCache {
    enabled: bool,
    passes: Mutex<Vec<Lru>>,
}

impl PassCache {
    /// A cache of `passes` (their names must differ), or none when not `enabled`.
    pub fn new(enabled: bool, passes: impl IntoIterator<Item = CachedPass>) -> Self {
        let lrus: Vec<Lru> = passes.into_iter().map(|pass| Lru { pass, entries: Vec::new() }).collect();
        debug_assert!(
            lrus.iter().enumerate().all(|(i, a)| lrus[..i].iter().all(|b| b.pass.name != a.pass.name)),
            "a cached pass is declared twice"
        );
        Self { enabled, passes: Mutex::new(lrus) }
    }

    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// The output cached for `key` of pass `name`, if any and of type `T`.
    pub fn get<T: Any + Send + Sync>(&self, name: &str, key: &PassKey) -> Option<Arc<T>> {
        if !self.enabled {
            return None;
        }
        let mut lrus = self.passes.lock().ok()?;
        let lru = lrus.iter_mut().find(|l| l.pass.name == name)?;
        let index = lru.entries.iter().position(|(k, _)| k == key)?;
        let entry = lru.entries.remove(index);
        let value = entry.1.clone();
        lru.entries.insert(0, entry);
        value.downcast::<T>().ok()
    }

    /// Keeps `value` as the output of pass `name` for `key` (a pass that was
    /// not declared is not cached).
    pub fn insert(&self, name: &str, key: PassKey, value: Entry) {
        if !self.enabled {
            return;
        }
        let Ok(mut lrus) = self.passes.lock() else { return };
        if let Some(lru) = lrus.iter_mut().find(|l| l.pass.name == name) {
            lru.entries.retain(|(k, _)| *k != key);
            lru.entries.insert(0, (key, value));
            lru.entries.truncate(lru.pass.capacity);
        }
    }

    /// Drops every entry (and the GPU memory it holds).
    pub fn clear(&self) {
        if let Ok(mut lrus) = self.passes.lock() {
            lrus.iter_mut().for_each(|l| l.entries.clear());
        }
    }

    /// Entries held per declared pass (all zero when disabled).
    pub fn entries(&self) -> Vec<(&'static str, usize)> {
        match self.passes.lock() {
            Ok(lrus) => lrus.iter().map(|l| (l.pass.name, l.entries.len())).collect(),
            Err(_) => Vec::new(),
        }
    }

    /// The declared passes.
    pub fn passes(&self) -> Vec<CachedPass> {
        self.passes.lock().map(|lrus| lrus.iter().map(|l| l.pass).collect()).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_differ_by_any_field_and_by_field_boundaries() {
        let a = PassKey::new("shadow_map").f32s(&[0.0]).u32(1).finish();
        let b = PassKey::new("shadow_map").f32s(&[-0.0]).u32(1).finish();
        let c = PassKey::new("shadow_map").f32s(&[0.0]).u32(2).finish();
        let d = PassKey::new("gbuffer").f32s(&[0.0]).u32(1).finish();
        assert!(a != b && a != c && a != d);
        let joined = PassKey::new("mask").bytes(&[1, 2]).bytes(&[3]).finish();
        let split = PassKey::new("mask").bytes(&[1]).bytes(&[2, 3]).finish();
        assert_ne!(joined, split);
    }

    #[test]
    fn lru_keeps_the_most_recent_entries_of_each_pass() {
        let passes = [CachedPass { name: "a", capacity: 3 }, CachedPass { name: "b", capacity: 1 }];
        let cache = PassCache::new(true, passes);
        let key = |i: u32| PassKey::new("a").u32(i).finish();
        for i in 0..3u32 {
            cache.insert("a", key(i), Arc::new(i));
        }
        // Touch 0, then add 3: 1 is the least recently used and goes.
        assert_eq!(cache.get::<u32>("a", &key(0)).as_deref(), Some(&0));
        cache.insert("a", key(3), Arc::new(3u32));
        assert_eq!(cache.entries(), vec![("a", 3), ("b", 0)]);
        assert!(cache.get::<u32>("a", &key(1)).is_none());
        assert!([0, 2, 3].iter().all(|&i| cache.get::<u32>("a", &key(i)).is_some()));
        // Another pass's entries are apart; a wrong type is a miss; an undeclared pass is not kept.
        cache.insert("b", key(0), Arc::new(String::from("x")));
        assert!(cache.get::<u32>("b", &key(0)).is_none());
        assert_eq!(cache.get::<String>("b", &key(0)).as_deref().map(String::as_str), Some("x"));
        cache.insert("c", key(0), Arc::new(0u32));
        assert!(cache.get::<u32>("c", &key(0)).is_none());
        cache.clear();
        assert_eq!(cache.entries(), vec![("a", 0), ("b", 0)]);
        let off = PassCache::new(false, passes);
        off.insert("a", key(0), Arc::new(0u32));
        assert!(off.get::<u32>("a", &key(0)).is_none() && !off.enabled());
        assert_eq!(off.entries(), vec![("a", 0), ("b", 0)]);
    }
}
