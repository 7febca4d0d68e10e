//! The pass cache: outputs of the passes that a change of a late parameter
//! does not affect, kept between renders and keyed by exactly the inputs
//! that determine them.
//!
//! A key is the byte string of everything a pass reads: a 64-bit hash of the
//! scene's geometry (the triangle corners the rasterising passes draw and
//! the meshes the silhouette methods weld), the matrices, light values and
//! uniform blocks the pass uploads (their bit patterns: `-0.0` and `0.0` are
//! different keys), texture sizes, and the keys of the cached passes it
//! reads. A lookup compares whole keys, so two renders share an entry only
//! when the pass would have read the same bits; only the geometry is hashed.
//!
//! Memory is bounded by a small LRU per pass kind ([`CAPACITY`]); an entry
//! is released when it falls out (or on [`PassCache::clear`]). Entries are
//! inserted only after the render that made them has been submitted and
//! waited for, so a concurrent render never reads a pass still in flight.

use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex};

use crate::light_frustum::LightFrustum;
use crate::scene::PreparedScene;

/// The pass kinds that are cached, with their names in `timings` and `stats`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassKind {
    GBuffer,
    ShadowMap,
    PenumbraVolumes,
    Mask,
    Estimation,
}

impl PassKind {
    /// The pass's name, as in `timings`.
    pub fn name(self) -> &'static str {
        match self {
            PassKind::GBuffer => "gbuffer",
            PassKind::ShadowMap => "shadow_map",
            PassKind::PenumbraVolumes => "penumbra_volumes",
            PassKind::Mask => "mask",
            PassKind::Estimation => "estimation",
        }
    }

    /// Entries kept of this kind. At 512 x 512 pixels and the default
    /// 2048-texel maps: G-buffers 36 bytes a pixel (9 MiB each), shadow maps
    /// 4 bytes a texel (16 MiB), PVM volume maps 36 bytes a texel (144 MiB),
    /// PVMF masks 8 bytes a texel (32 MiB), PVMF estimates 12 bytes a pixel
    /// (3 MiB): at most about 250 MiB in all.
    pub fn capacity(self) -> usize {
        match self {
            // Two cameras (or image sizes) alternating.
            PassKind::GBuffer => 2,
            // The map-depth schemes of several methods compared on one scene.
            PassKind::ShadowMap => 3,
            PassKind::PenumbraVolumes | PassKind::Mask | PassKind::Estimation => 1,
        }
    }
}

/// Entries of every kind, for documentation and tests.
pub const CAPACITY: [(PassKind, usize); 5] = [
    (PassKind::GBuffer, 2),
    (PassKind::ShadowMap, 3),
    (PassKind::PenumbraVolumes, 1),
    (PassKind::Mask, 1),
    (PassKind::Estimation, 1),
];

/// The exact inputs of one pass, as bytes.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct PassKey(Vec<u8>);

impl PassKey {
    pub fn new(kind: PassKind) -> Self {
        let mut key = Self(Vec::with_capacity(128));
        key.bytes(kind.name().as_bytes());
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

    pub fn finish(&mut self) -> Self {
        std::mem::take(self)
    }
}

/// A 64-bit hash of what the passes read of a scene's geometry: the corners
/// (positions, normals and mesh indices) and every mesh's vertices and faces.
pub fn geometry_hash(scene: &PreparedScene) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    let corners: &[u8] = bytemuck::cast_slice(&scene.corners);
    corners.hash(&mut h);
    scene.meshes.len().hash(&mut h);
    for mesh in &scene.meshes {
        mesh.faces.hash(&mut h);
        mesh.vertices.len().hash(&mut h);
        for v in &mesh.vertices {
            v.to_array().map(f64::to_bits).hash(&mut h);
        }
    }
    h.finish()
}

/// One kind's entries, most recently used first.
struct Lru<V> {
    kind: PassKind,
    entries: Mutex<Vec<(PassKey, Arc<V>)>>,
}

impl<V> Lru<V> {
    fn new(kind: PassKind) -> Self {
        Self { kind, entries: Mutex::new(Vec::new()) }
    }

    fn get(&self, key: &PassKey) -> Option<Arc<V>> {
        let mut entries = self.entries.lock().ok()?;
        let index = entries.iter().position(|(k, _)| k == key)?;
        let entry = entries.remove(index);
        let value = entry.1.clone();
        entries.insert(0, entry);
        Some(value)
    }

    fn insert(&self, key: PassKey, value: Arc<V>) {
        if let Ok(mut entries) = self.entries.lock() {
            entries.retain(|(k, _)| *k != key);
            entries.insert(0, (key, value));
            entries.truncate(self.kind.capacity());
        }
    }

    fn clear(&self) {
        if let Ok(mut entries) = self.entries.lock() {
            entries.clear();
        }
    }

    fn len(&self) -> usize {
        self.entries.lock().map(|e| e.len()).unwrap_or(0)
    }
}

/// The renderer's cache of pass outputs, one LRU per kind. `V*` are the
/// output types, so that this module need not know the methods.
pub struct PassCache<G, S, V, M, E> {
    pub gbuffer: CacheSlot<G>,
    pub shadow_map: CacheSlot<S>,
    pub penumbra_volumes: CacheSlot<V>,
    pub mask: CacheSlot<M>,
    pub estimation: CacheSlot<E>,
}

/// One kind's LRU, or nothing when the cache is off.
pub struct CacheSlot<V>(Option<Lru<V>>);

impl<V> CacheSlot<V> {
    fn new(kind: PassKind, enabled: bool) -> Self {
        Self(enabled.then(|| Lru::new(kind)))
    }

    /// The cached output for `key`; always None when the cache is off.
    pub fn get(&self, key: &PassKey) -> Option<Arc<V>> {
        self.0.as_ref().and_then(|lru| lru.get(key))
    }

    pub fn insert(&self, key: PassKey, value: Arc<V>) {
        if let Some(lru) = &self.0 {
            lru.insert(key, value);
        }
    }

    fn clear(&self) {
        if let Some(lru) = &self.0 {
            lru.clear();
        }
    }

    pub fn len(&self) -> usize {
        self.0.as_ref().map_or(0, Lru::len)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl<G, S, V, M, E> PassCache<G, S, V, M, E> {
    pub fn new(enabled: bool) -> Self {
        Self {
            gbuffer: CacheSlot::new(PassKind::GBuffer, enabled),
            shadow_map: CacheSlot::new(PassKind::ShadowMap, enabled),
            penumbra_volumes: CacheSlot::new(PassKind::PenumbraVolumes, enabled),
            mask: CacheSlot::new(PassKind::Mask, enabled),
            estimation: CacheSlot::new(PassKind::Estimation, enabled),
        }
    }

    pub fn enabled(&self) -> bool {
        self.gbuffer.0.is_some()
    }

    /// Drops every entry (and the GPU memory it holds).
    pub fn clear(&self) {
        self.gbuffer.clear();
        self.shadow_map.clear();
        self.penumbra_volumes.clear();
        self.mask.clear();
        self.estimation.clear();
    }

    /// Entries held per kind.
    pub fn entries(&self) -> Vec<(&'static str, usize)> {
        vec![
            (PassKind::GBuffer.name(), self.gbuffer.len()),
            (PassKind::ShadowMap.name(), self.shadow_map.len()),
            (PassKind::PenumbraVolumes.name(), self.penumbra_volumes.len()),
            (PassKind::Mask.name(), self.mask.len()),
            (PassKind::Estimation.name(), self.estimation.len()),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_differ_by_any_field_and_by_field_boundaries() {
        let a = PassKey::new(PassKind::ShadowMap).f32s(&[0.0]).u32(1).finish();
        let b = PassKey::new(PassKind::ShadowMap).f32s(&[-0.0]).u32(1).finish();
        let c = PassKey::new(PassKind::ShadowMap).f32s(&[0.0]).u32(2).finish();
        let d = PassKey::new(PassKind::GBuffer).f32s(&[0.0]).u32(1).finish();
        assert!(a != b && a != c && a != d);
        let joined = PassKey::new(PassKind::Mask).bytes(&[1, 2]).bytes(&[3]).finish();
        let split = PassKey::new(PassKind::Mask).bytes(&[1]).bytes(&[2, 3]).finish();
        assert_ne!(joined, split);
    }

    #[test]
    fn lru_keeps_the_most_recent_entries() {
        let slot = CacheSlot::<u32>::new(PassKind::ShadowMap, true);
        let key = |i: u32| PassKey::new(PassKind::ShadowMap).u32(i).finish();
        for i in 0..3 {
            slot.insert(key(i), Arc::new(i));
        }
        // Touch 0, then add 3: 1 is the least recently used and goes.
        assert_eq!(slot.get(&key(0)).as_deref(), Some(&0));
        slot.insert(key(3), Arc::new(3));
        assert_eq!(slot.len(), PassKind::ShadowMap.capacity());
        assert!(slot.get(&key(1)).is_none());
        assert!(slot.get(&key(0)).is_some() && slot.get(&key(2)).is_some() && slot.get(&key(3)).is_some());
        let off = CacheSlot::<u32>::new(PassKind::ShadowMap, false);
        off.insert(key(0), Arc::new(0));
        assert!(off.get(&key(0)).is_none() && off.is_empty());
    }

    #[test]
    fn capacity_table_matches() {
        for (kind, n) in CAPACITY {
            assert_eq!(kind.capacity(), n);
        }
    }
}
