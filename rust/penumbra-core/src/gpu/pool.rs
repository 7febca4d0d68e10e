//! Pools of GPU resources reused across renders (rerun's `wgpu_resources`
//! is the model): textures and buffers keyed by their descriptor, and bind
//! groups keyed by their layout and the resources they bind.
//!
//! A pooled resource is handed out as an [`Arc`]; while anyone (a frame, the
//! pass cache, a cached output) holds a handle besides the pool, it is in
//! use, and once only the pool holds it, the next request with the same
//! descriptor gets it back. A frame keeps a handle to everything it took
//! until its work has been submitted and waited for, so a concurrent render
//! never receives a resource that is still being written. Reused resources
//! keep their contents: whoever takes one writes or clears all of it
//! before reading (render passes clear their targets, per-pixel passes write
//! every pixel, counters and accumulators are cleared with
//! `clear_buffer`).
//!
//! Every pooled resource has an id that is never reused, so a cached bind
//! group's key names exactly the resources it binds; resources owned
//! elsewhere (samplers) take an id from [`ResourcePool::new_id`].
//!
//! Memory is bounded: after each render, free resources beyond
//! [`ResourcePool::max_free_bytes`] are released, least recently used first,
//! with the bind groups that name them. [`ResourcePool::clear`] releases
//! everything free.

use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::hash::Hash;
use std::ops::Deref;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

/// A pooled resource with its id.
#[derive(Debug)]
pub struct Pooled<T> {
    pub id: u64,
    pub resource: T,
    bytes: u64,
}

impl<T> Deref for Pooled<T> {
    type Target = T;
    fn deref(&self) -> &T {
        &self.resource
    }
}

/// A texture from the pool, with its default view (an array view for an
/// array texture) and, for an array, a view of each layer (render targets).
#[derive(Debug)]
pub struct PoolTexture {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    pub layer_views: Vec<wgpu::TextureView>,
}

impl Deref for PoolTexture {
    type Target = wgpu::Texture;
    fn deref(&self) -> &wgpu::Texture {
        &self.texture
    }
}

pub type PooledTexture = Arc<Pooled<PoolTexture>>;
pub type PooledBuffer = Arc<Pooled<wgpu::Buffer>>;

/// What makes two textures interchangeable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TextureKey {
    pub size: (u32, u32),
    pub format: wgpu::TextureFormat,
    pub usage: wgpu::TextureUsages,
    /// Array layers, or 0 for a plain 2D texture (bound as `texture_2d`).
    pub layers: u32,
}

impl TextureKey {
    pub fn plain(size: (u32, u32), format: wgpu::TextureFormat, usage: wgpu::TextureUsages) -> Self {
        Self { size, format, usage, layers: 0 }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct BufferKey {
    size: u64,
    usage: wgpu::BufferUsages,
}

struct Slot<T> {
    handle: Arc<Pooled<T>>,
    last_used: u64,
}

/// A free slot of `slots` (only the pool holds its handle), marked used now.
fn take_free<T>(slots: &mut [Slot<T>], now: u64) -> Option<Arc<Pooled<T>>> {
    let slot = slots.iter_mut().find(|s| Arc::strong_count(&s.handle) == 1)?;
    slot.last_used = now;
    Some(slot.handle.clone())
}

/// A resource a bind group binds: its id and what to bind.
pub enum Binding<'a> {
    Texture(&'a Pooled<PoolTexture>),
    Buffer(&'a Pooled<wgpu::Buffer>),
    /// `size` bytes of a buffer from `offset` (a multiple of the adapter's
    /// storage-offset alignment).
    BufferRange(&'a Pooled<wgpu::Buffer>, u64, u64),
    /// A resource owned elsewhere, with an id from [`ResourcePool::new_id`]
    /// that names it for as long as it lives.
    Other(u64, wgpu::BindingResource<'a>),
}

impl Binding<'_> {
    /// What names the binding in a cached bind group's key.
    fn key(&self) -> (u64, u64) {
        match self {
            Binding::Texture(t) => (t.id, 0),
            Binding::Buffer(b) => (b.id, u64::MAX),
            Binding::BufferRange(b, offset, _) => (b.id, *offset),
            Binding::Other(id, _) => (*id, 0),
        }
    }

    /// The same binding, borrowed again.
    pub fn reborrow(&self) -> Binding<'_> {
        match self {
            Binding::Texture(t) => Binding::Texture(t),
            Binding::Buffer(b) => Binding::Buffer(b),
            Binding::BufferRange(b, offset, size) => Binding::BufferRange(b, *offset, *size),
            Binding::Other(id, resource) => Binding::Other(*id, resource.clone()),
        }
    }
}

/// A bind-group layout with an id, so that bind groups made for it can be cached.
pub struct Layout {
    pub id: u64,
    pub layout: wgpu::BindGroupLayout,
}

impl Deref for Layout {
    type Target = wgpu::BindGroupLayout;
    fn deref(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }
}

struct CachedBindGroup {
    layout: u64,
    ids: Vec<(u64, u64)>,
    group: wgpu::BindGroup,
    last_used: u64,
}

/// Most bind groups kept; beyond it the least recently used go.
const BIND_GROUPS: usize = 256;

pub struct ResourcePool {
    textures: Mutex<HashMap<TextureKey, Vec<Slot<PoolTexture>>>>,
    buffers: Mutex<HashMap<BufferKey, Vec<Slot<wgpu::Buffer>>>>,
    bind_groups: Mutex<Vec<CachedBindGroup>>,
    /// One object per type that several methods build alike (a pass's
    /// pipelines, samplers): [`Self::shared`].
    shared: Mutex<HashMap<TypeId, Arc<dyn Any + Send + Sync>>>,
    next_id: AtomicU64,
    clock: AtomicU64,
    /// Free resources kept beyond this many bytes are released after a render.
    pub max_free_bytes: u64,
}

/// Bytes the pool holds, in use and free.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PoolStats {
    pub textures: usize,
    pub buffers: usize,
    pub bind_groups: usize,
    pub bytes_in_use: u64,
    pub bytes_free: u64,
}

fn texture_bytes(key: &TextureKey) -> u64 {
    let texel = key.format.block_copy_size(None).or_else(|| key.format.block_copy_size(Some(wgpu::TextureAspect::DepthOnly)));
    key.size.0 as u64 * key.size.1 as u64 * key.layers.max(1) as u64 * texel.unwrap_or(4) as u64
}

impl Default for ResourcePool {
    fn default() -> Self {
        Self::new(256 << 20)
    }
}

impl ResourcePool {
    pub fn new(max_free_bytes: u64) -> Self {
        Self {
            textures: Mutex::default(),
            buffers: Mutex::default(),
            bind_groups: Mutex::default(),
            shared: Mutex::default(),
            next_id: AtomicU64::new(1),
            clock: AtomicU64::new(0),
            max_free_bytes,
        }
    }

    /// The one `T` of this pool, made by `make` the first time it is asked
    /// for: a pass several methods record (the light's shadow map) or the
    /// samplers they bind, built once per device and shared, without a list
    /// of them below the methods. Never released by [`Self::clear`].
    pub fn shared<T: Any + Send + Sync>(&self, make: impl FnOnce() -> T) -> Arc<T> {
        let get = |map: &HashMap<TypeId, Arc<dyn Any + Send + Sync>>| map.get(&TypeId::of::<T>()).cloned();
        let found = get(&self.shared.lock().unwrap_or_else(|e| e.into_inner()));
        // `make` runs without the lock: it may ask the pool for layouts (or for another shared object).
        let value = found.unwrap_or_else(|| {
            let made: Arc<dyn Any + Send + Sync> = Arc::new(make());
            let mut map = self.shared.lock().unwrap_or_else(|e| e.into_inner());
            map.entry(TypeId::of::<T>()).or_insert(made).clone()
        });
        value.downcast::<T>().unwrap_or_else(|_| unreachable!("the map holds a T under T's TypeId"))
    }

    /// A fresh id for a resource owned outside the pool.
    pub fn new_id(&self) -> u64 {
        self.next_id.fetch_add(1, Ordering::Relaxed)
    }

    fn now(&self) -> u64 {
        self.clock.load(Ordering::Relaxed)
    }

    /// A bind-group layout with an id.
    pub fn layout(&self, device: &wgpu::Device, label: &str, entries: &[wgpu::BindGroupLayoutEntry]) -> Layout {
        Layout { id: self.new_id(), layout: crate::gpu::layout::bind_group_layout(device, label, entries) }
    }

    /// A free texture of this descriptor, or a new one.
    pub fn texture(&self, device: &wgpu::Device, label: &str, key: TextureKey) -> PooledTexture {
        let now = self.now();
        let mut textures = self.textures.lock().unwrap_or_else(|e| e.into_inner());
        let slots = textures.entry(key).or_default();
        if let Some(handle) = take_free(slots, now) {
            return handle;
        }
        let (texture, view, layer_views) = if key.layers == 0 {
            let texture = crate::gpu::layout::create_texture(device, label, key.size, key.format, key.usage);
            let view = crate::gpu::layout::view(&texture);
            (texture, view, Vec::new())
        } else {
            let texture = crate::gpu::layout::create_array_texture(device, label, key.size, key.layers, key.format, key.usage);
            let view = texture.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            });
            let layers = (0..key.layers)
                .map(|layer| {
                    texture.create_view(&wgpu::TextureViewDescriptor {
                        dimension: Some(wgpu::TextureViewDimension::D2),
                        base_array_layer: layer,
                        array_layer_count: Some(1),
                        ..Default::default()
                    })
                })
                .collect();
            (texture, view, layers)
        };
        let handle = Arc::new(Pooled { id: self.new_id(), resource: PoolTexture { texture, view, layer_views }, bytes: texture_bytes(&key) });
        slots.push(Slot { handle: handle.clone(), last_used: now });
        handle
    }

    /// A free buffer of this size and usage, or a new one. Its contents are
    /// whatever its last user left.
    pub fn buffer(&self, device: &wgpu::Device, label: &str, size: u64, usage: wgpu::BufferUsages) -> PooledBuffer {
        let key = BufferKey { size, usage };
        let now = self.now();
        let mut buffers = self.buffers.lock().unwrap_or_else(|e| e.into_inner());
        let slots = buffers.entry(key).or_default();
        if let Some(handle) = take_free(slots, now) {
            return handle;
        }
        let buffer = device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false });
        let handle = Arc::new(Pooled { id: self.new_id(), resource: buffer, bytes: size });
        slots.push(Slot { handle: handle.clone(), last_used: now });
        handle
    }

    /// A bind group of `layout` binding `entries` as bindings 0, 1, 2, ...:
    /// the one made before for the same resources, or a new one.
    pub fn bind_group(&self, device: &wgpu::Device, label: &str, layout: &Layout, entries: &[Binding<'_>]) -> wgpu::BindGroup {
        let ids: Vec<(u64, u64)> = entries.iter().map(Binding::key).collect();
        let now = self.now();
        let mut groups = self.bind_groups.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(cached) = groups.iter_mut().find(|g| g.layout == layout.id && g.ids == ids) {
            cached.last_used = now;
            return cached.group.clone();
        }
        let resources: Vec<wgpu::BindingResource<'_>> = entries
            .iter()
            .map(|e| match e {
                Binding::Texture(t) => wgpu::BindingResource::TextureView(&t.view),
                Binding::Buffer(b) => b.as_entire_binding(),
                Binding::BufferRange(b, offset, size) => {
                    wgpu::BindingResource::Buffer(wgpu::BufferBinding { buffer: b, offset: *offset, size: wgpu::BufferSize::new(*size) })
                }
                Binding::Other(_, r) => r.clone(),
            })
            .collect();
        let group = crate::gpu::layout::bind_group(device, label, layout, &resources);
        if groups.len() >= BIND_GROUPS {
            if let Some(oldest) = groups.iter().enumerate().min_by_key(|(_, g)| g.last_used).map(|(i, _)| i) {
                groups.swap_remove(oldest);
            }
        }
        groups.push(CachedBindGroup { layout: layout.id, ids, group: group.clone(), last_used: now });
        group
    }

    /// Ends a render: advances the clock and releases free resources beyond
    /// the budget, least recently used first.
    pub fn end_frame(&self) {
        self.clock.fetch_add(1, Ordering::Relaxed);
        self.release(self.max_free_bytes);
    }

    /// Releases every free resource (and the bind groups naming them).
    pub fn clear(&self) {
        self.release(0);
        if let Ok(mut groups) = self.bind_groups.lock() {
            groups.clear();
        }
    }

    fn release(&self, keep_bytes: u64) {
        let mut textures = self.textures.lock().unwrap_or_else(|e| e.into_inner());
        let mut buffers = self.buffers.lock().unwrap_or_else(|e| e.into_inner());
        // Free resources, most recently used first.
        let mut free: Vec<(u64, u64, u64)> = free_slots(&textures).chain(free_slots(&buffers)).collect();
        free.sort_by_key(|f| std::cmp::Reverse(f.0));
        let mut kept = 0u64;
        let mut released = std::collections::HashSet::new();
        for (_, id, bytes) in free {
            kept += bytes;
            if kept > keep_bytes {
                released.insert(id);
            }
        }
        if released.is_empty() {
            return;
        }
        retain_slots(&mut textures, &released);
        retain_slots(&mut buffers, &released);
        drop((textures, buffers));
        if let Ok(mut groups) = self.bind_groups.lock() {
            groups.retain(|g| !g.ids.iter().any(|(id, _)| released.contains(id)));
        }
    }

    pub fn stats(&self) -> PoolStats {
        let mut stats = PoolStats::default();
        let mut tally = |slots: &mut dyn Iterator<Item = (u64, bool)>| {
            let mut n = 0;
            for (bytes, free) in slots {
                n += 1;
                if free {
                    stats.bytes_free += bytes;
                } else {
                    stats.bytes_in_use += bytes;
                }
            }
            n
        };
        let textures = self.textures.lock().map(|t| tally(&mut all_slots(&t))).unwrap_or(0);
        let buffers = self.buffers.lock().map(|b| tally(&mut all_slots(&b))).unwrap_or(0);
        stats.textures = textures;
        stats.buffers = buffers;
        stats.bind_groups = self.bind_groups.lock().map(|g| g.len()).unwrap_or(0);
        stats
    }
}

/// (last used, id, bytes) of every free slot.
fn free_slots<K, T>(map: &HashMap<K, Vec<Slot<T>>>) -> impl Iterator<Item = (u64, u64, u64)> + '_ {
    map.values().flatten().filter(|s| Arc::strong_count(&s.handle) == 1).map(|s| (s.last_used, s.handle.id, s.handle.bytes))
}

/// (bytes, free) of every slot.
fn all_slots<K, T>(map: &HashMap<K, Vec<Slot<T>>>) -> impl Iterator<Item = (u64, bool)> + '_ {
    map.values().flatten().map(|s| (s.handle.bytes, Arc::strong_count(&s.handle) == 1))
}

fn retain_slots<K: Eq + Hash, T>(map: &mut HashMap<K, Vec<Slot<T>>>, released: &std::collections::HashSet<u64>) {
    map.values_mut().for_each(|slots| slots.retain(|s| !released.contains(&s.handle.id)));
    map.retain(|_, slots| !slots.is_empty());
}
