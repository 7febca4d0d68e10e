//! The frame: everything one render's passes read and leave behind, handed
//! by the renderer to the method it renders with.
//!
//! [`FrameContext`] is fixed before the method records: device, pool,
//! scene, camera, the light and its shadow-map projections, the G-buffer's
//! images, the silhouette cache and the resource helpers. It names no pass:
//! the passes (`passes/`) read it, and a pass several methods record is
//! shared through the pool (`ResourcePool::shared`). [`Frame`] adds what a
//! method records into: named passes (timed by the profiler), the pass
//! cache ([`Frame::cached`]), pooled resources that stay in use until the
//! frame's work is done, stats, counters read back into stats, and
//! intermediate images.

use std::any::Any;
use std::collections::BTreeMap;
use std::sync::Arc;

use glam::{DVec3, Vec3};

use crate::error::{Error, Result};
use crate::gpu::formats;
use crate::gpu::{PassTimestamps, Profiler};
use crate::gpu::pool::{PooledBuffer, PooledTexture, ResourcePool, TextureKey};
use crate::casters::Casters;
use crate::light_frustum::{LightProjection, ProjectionMode};
use crate::occluders::Occluders;
use crate::pass_cache::{Entry, PassCache, PassKey};
pub use crate::geometry_cache::GeometryBuffers;
use crate::geometry_cache::{LightGeometry, SceneGeometry};
use crate::scene::{Camera, PreparedScene, Scene};
use crate::silhouettes::{SilhouetteCache, SilhouetteStats};

/// The sphere light, in the precisions the passes use.
#[derive(Debug, Clone, Copy)]
pub struct Light {
    /// As the scene gives it (what uniforms carry).
    pub center_f32: [f32; 3],
    pub radius_f32: f32,
    /// The same values in double precision (CPU geometry).
    pub center: DVec3,
    pub radius: f64,
}

/// A method's intermediate image, read back on request: (rows, columns) or
/// (rows, columns, channels), with a leading layer axis for a texture of
/// several layers (cube faces).
pub struct Intermediate {
    pub name: &'static str,
    pub texture: wgpu::Texture,
    pub aspect: wgpu::TextureAspect,
    /// Channels kept of those stored.
    pub channels: usize,
    /// Multiplies the stored values: a linear-depth map stores depth / far
    /// and is read back in world units (`far`); 1 for other images.
    pub scale: f32,
}

impl Intermediate {
    /// A linear-depth map of a projection whose far plane is `far`.
    pub fn depth(name: &'static str, texture: &wgpu::Texture, far: f32) -> Self {
        Self { name, texture: texture.clone(), aspect: wgpu::TextureAspect::DepthOnly, channels: 1, scale: far }
    }

    pub fn color(name: &'static str, texture: &wgpu::Texture, channels: usize) -> Self {
        Self { name, texture: texture.clone(), aspect: wgpu::TextureAspect::All, channels, scale: 1.0 }
    }

    /// Whether the readback can take this image (`readable`).
    pub fn readable(&self) -> Result<()> {
        readable(self.name, self.texture.format(), self.aspect, self.channels)
    }
}

/// Whether the readback can take `channels` of a texture of `format`: 32
/// bits per stored channel (it reads texels as float32 words) and at least
/// `channels` of them.
fn readable(name: &str, format: wgpu::TextureFormat, aspect: wgpu::TextureAspect, channels: usize) -> Result<()> {
    let stored = format.components_with_aspect(aspect) as usize;
    if stored == 0 || format.block_copy_size(Some(aspect)) != Some(4 * stored as u32) || channels == 0 || channels > stored {
        return Err(Error::Gpu(format!(
            "intermediate image {name}: its texture ({format:?}, {channels} channel(s) asked) is not 32 bits a channel, so it cannot be read back"
        )));
    }
    Ok(())
}

/// The camera's G-buffer images of one frame, in pooled textures (the
/// G-buffer pass, `passes::gbuffer`, draws them): world position with view
/// depth, and shading normal with mesh index.
pub struct GBuffer {
    pub position: PooledTexture,
    pub normal: PooledTexture,
    pub(crate) depth: PooledTexture,
    pub size: (u32, u32),
}

impl GBuffer {
    pub fn new(device: &wgpu::Device, pool: &ResourcePool, size: (u32, u32)) -> Self {
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        Self {
            position: pool.texture(device, "gbuffer::position", TextureKey::plain(size, formats::POSITION, usage)),
            normal: pool.texture(device, "gbuffer::normal", TextureKey::plain(size, formats::NORMAL, usage)),
            depth: pool.texture(device, "gbuffer::depth", TextureKey::plain(size, formats::DEPTH, wgpu::TextureUsages::RENDER_ATTACHMENT)),
            size,
        }
    }
}

/// What every pass of one render reads.
pub struct FrameContext<'r> {
    pub device: &'r wgpu::Device,
    pub queue: &'r wgpu::Queue,
    /// Topology and silhouettes, cached by mesh content and light centre.
    pub silhouettes: &'r SilhouetteCache,
    pub pool: &'r ResourcePool,
    pub scene: &'r Scene,
    pub prepared: &'r PreparedScene,
    pub camera: &'r Camera,
    /// Image size in pixels.
    pub size: (u32, u32),
    pub light: Light,
    pub gbuffer: Arc<GBuffer>,
    /// The G-buffer's pass-cache key (passes that read it include it in theirs).
    pub gbuffer_key: PassKey,
    /// The geometry's hash as key bytes (zero when there is no pass cache).
    pub geometry: [u8; 8],
    /// What the renderer keeps of the scene's geometry from render to
    /// render (`geometry_cache.rs`): its drawable buffers, uploaded on first
    /// use, and its corner positions, for projection fits.
    kept: &'r SceneGeometry,
    /// What it keeps per light of that geometry: the triangles that can cast
    /// a shadow (`casters::caster_indices`), their indices uploaded on first
    /// use, their points, and per cube face around any point of the light
    /// the caster triangles that may reach its cone (one index buffer with a
    /// range per face).
    kept_light: &'r LightGeometry,
    /// The light centre's projections fitted so far, by mode.
    projections: std::cell::RefCell<Vec<(ProjectionMode, Arc<LightProjection>)>>,
    /// Pooled resources this frame took: in use until the frame ends.
    held: std::cell::RefCell<Vec<Arc<dyn Any + Send + Sync>>>,
}

impl<'r> FrameContext<'r> {
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        device: &'r wgpu::Device,
        queue: &'r wgpu::Queue,
        silhouettes: &'r SilhouetteCache,
        pool: &'r ResourcePool,
        scene: &'r Scene,
        kept: (&'r SceneGeometry, &'r LightGeometry),
        camera: &'r Camera,
        gbuffer: (Arc<GBuffer>, PassKey),
        geometry: [u8; 8],
    ) -> Self {
        let l = &scene.light;
        let light = Light {
            center_f32: l.center,
            radius_f32: l.radius,
            center: glam::Vec3::from(l.center).as_dvec3(),
            radius: l.radius as f64,
        };
        Self {
            device,
            queue,
            silhouettes,
            pool,
            scene,
            prepared: &kept.0.prepared,
            camera,
            size: (camera.width, camera.height),
            light,
            gbuffer: gbuffer.0,
            gbuffer_key: gbuffer.1,
            geometry,
            kept: kept.0,
            kept_light: kept.1,
            projections: Default::default(),
            held: Default::default(),
        }
    }

    /// The triangle corners' positions, three per triangle.
    pub fn corner_positions(&self) -> &[Vec3] {
        self.kept.corner_positions.get_or_init(|| self.prepared.corners.iter().map(|c| Vec3::from(c.position)).collect())
    }

    /// A bounding volume hierarchy over the triangles of
    /// [`Self::corner_positions`] (every triangle, in the hierarchy's own
    /// order; corners exact in float32), kept with the geometry.
    pub fn corner_hierarchy(&self) -> Arc<Occluders> {
        self.kept
            .corner_hierarchy
            .get_or_init(|| {
                let corners = self.corner_positions();
                Arc::new(Occluders::build(corners.chunks_exact(3).map(|t| [t[0].as_dvec3(), t[1].as_dvec3(), t[2].as_dvec3()]).collect()))
            })
            .clone()
    }

    /// The positions of the casting triangles' corners (each vertex once):
    /// what a light map's frustum is fitted around ([`LightProjection::fit`]).
    pub fn caster_points(&self) -> &[Vec3] {
        self.kept_light.caster_points.get_or_init(|| {
            let positions = &self.prepared.positions;
            let mut seen = vec![false; positions.len()];
            let mut points = Vec::new();
            for &i in &self.casters().1.indices {
                if !std::mem::replace(&mut seen[i as usize], true) {
                    points.push(Vec3::from(positions[i as usize]));
                }
            }
            points
        })
    }

    /// The projection of a light map from `origin` (the centre, or a light
    /// sample with `radius` 0) that `mode` asks for: a frustum fitted around
    /// the casters and the penumbrae they may cast, or cube faces.
    pub fn fit_projection(&self, origin: Vec3, radius: f32, mode: ProjectionMode) -> Result<LightProjection> {
        let corners = self.corner_positions();
        LightProjection::fit(origin, radius, self.caster_points(), corners, (self.prepared.bounds_min, self.prepared.bounds_max), mode)
    }

    /// [`Self::fit_projection`] from each of `origins` (light samples, radius
    /// 0), in order. Each fit passes over every caster point two or three
    /// times (`LightFrustum::fit_balls`), for each of `reference`'s hundreds
    /// of samples, so the fits run in bands over up to 8 host threads where
    /// there is that much work; each fit is the same computation either way.
    pub fn fit_projections(&self, origins: &[Vec3], radius: f32, mode: ProjectionMode) -> Vec<Result<LightProjection>> {
        let (casters, corners) = (self.caster_points(), self.corner_positions());
        let bounds = (self.prepared.bounds_min, self.prepared.bounds_max);
        let fit = |o: &Vec3| LightProjection::fit(*o, radius, casters, corners, bounds, mode);
        // Below about a million point visits, threads cost more than they save.
        let work = origins.len() * casters.len().max(corners.len() / 3);
        let threads = if work < 1 << 20 { 1 } else { std::thread::available_parallelism().map_or(1, |n| n.get()).min(8) };
        map_in_bands(origins, threads, fit)
    }

    /// The shadow-map projection from the light centre that `mode` asks for
    /// (fitted once per frame and mode): the fitted frustum, or cube faces.
    pub fn projection(&self, mode: ProjectionMode) -> Result<Arc<LightProjection>> {
        if let Some((_, p)) = self.projections.borrow().iter().find(|(m, _)| *m == mode) {
            return Ok(p.clone());
        }
        let fitted = Arc::new(self.fit_projection(Vec3::from(self.light.center_f32), self.light.radius_f32, mode)?);
        self.projections.borrow_mut().push((mode, fitted.clone()));
        Ok(fitted)
    }

    /// The triangles as the camera's G-buffer draws them: vertices
    /// (`CornerVertex`), indices and the index count. Uploaded only when a
    /// pass draws them: not when the pass cache supplies the G-buffer and the
    /// shadow map.
    pub fn surface(&self) -> (&wgpu::Buffer, &wgpu::Buffer, u32) {
        let g = self.geometry_buffers();
        (&g.surface_vertices, &g.surface_indices, self.prepared.surface_indices.len() as u32)
    }

    /// The triangles as the light's raster passes draw them: world positions
    /// (`[f32; 3]`), indices and the index count. Only the triangles that can
    /// hide part of the light from some point of the scene are drawn
    /// (`casters.rs`): a floor slab under everything is not.
    pub fn light_geometry(&self) -> (&wgpu::Buffer, &wgpu::Buffer, u32) {
        let g = self.geometry_buffers();
        let (indices, casters) = self.casters();
        (&g.positions, indices, casters.indices.len() as u32)
    }

    /// The triangles a raster pass draws into layer `layer` of `projection`:
    /// [`Self::light_geometry`]'s, less, on a cube around a point of the
    /// light (its centre, a light sample), those that reach nothing of the
    /// face's cone from any point of the light and would be clipped away
    /// whole (`light_frustum::faces_reached`): each triangle is drawn into
    /// one or two faces instead of every face. Positions, indices, and the
    /// range of indices to draw.
    pub fn light_geometry_for(&self, projection: &LightProjection, layer: u32) -> (&wgpu::Buffer, &wgpu::Buffer, std::ops::Range<u32>) {
        let g = self.geometry_buffers();
        let reach = self.face_reach();
        if projection.is_cube() && projection.origin.as_dvec3().distance(self.light.center) <= reach {
            let (indices, ranges) = self.face_casters();
            return (&g.positions, indices, ranges[layer as usize].clone());
        }
        let (indices, casters) = self.casters();
        (&g.positions, indices, 0..casters.indices.len() as u32)
    }

    /// How far from the light's centre the apexes of [`Self::face_casters`]
    /// may lie: the radius and a margin (1e-4 of it, and 1e-6 of the scene's
    /// extent) far above float32 rounding of the clip coordinates, so that
    /// a triangle left out of a face is clipped away there by a margin too.
    fn face_reach(&self) -> f64 {
        let extent = (self.prepared.bounds_max - self.prepared.bounds_min).max_element() as f64;
        self.light.radius * (1.0 + 1e-4) + 1e-6 * extent
    }

    fn face_casters(&self) -> &(PooledBuffer, Vec<std::ops::Range<u32>>) {
        self.kept_light.face_casters.get_or_init(|| {
            let casters = &self.casters().1.indices;
            let positions = &self.prepared.positions;
            let reach = self.face_reach();
            let masks: Vec<u32> = casters
                .chunks_exact(3)
                .map(|t| crate::light_frustum::faces_reached(self.light.center, reach, [t[0], t[1], t[2]].map(|i| Vec3::from(positions[i as usize]).as_dvec3())))
                .collect();
            let (mut indices, mut ranges) = (Vec::new(), Vec::with_capacity(6));
            for f in 0..6 {
                let start = indices.len() as u32;
                for (t, mask) in casters.chunks_exact(3).zip(&masks) {
                    if mask & (1 << f) != 0 {
                        indices.extend_from_slice(t);
                    }
                }
                ranges.push(start..indices.len() as u32);
            }
            (self.upload("frame::face_caster_indices", bytemuck::cast_slice(&indices), wgpu::BufferUsages::INDEX), ranges)
        })
    }

    /// Per mesh: the range of its triangles in [`Self::light_geometry`]'s
    /// indices (three per triangle), for passes that draw mesh by mesh.
    pub fn light_geometry_meshes(&self) -> &[std::ops::Range<u32>] {
        &self.casters().1.mesh_ranges
    }

    /// How many triangles the light's raster passes leave out as casting no
    /// shadow. For a fixed geometry and light centre, a larger radius leaves
    /// out a subset of a smaller one's, so the count tells the sets apart
    /// (the shadow map's pass-cache key includes it).
    pub fn non_casters(&self) -> usize {
        self.casters().1.culled
    }

    fn casters(&self) -> &(PooledBuffer, Casters) {
        self.kept_light.casters.get_or_init(|| {
            let casters = crate::casters::caster_indices(self.scene, self.prepared, &self.silhouettes.scene_topology(self.prepared), self.light.center, self.light.radius);
            (self.upload("frame::caster_indices", bytemuck::cast_slice(&casters.indices), wgpu::BufferUsages::INDEX), casters)
        })
    }

    /// A pooled buffer of `usage` (and COPY_DST) holding `bytes` (at least 4 bytes long).
    fn upload(&self, label: &str, bytes: &[u8], usage: wgpu::BufferUsages) -> PooledBuffer {
        let buffer = self.buffer(label, (bytes.len() as u64).max(4), usage | wgpu::BufferUsages::COPY_DST);
        if !bytes.is_empty() {
            self.queue.write_buffer(&buffer, 0, bytes);
        }
        buffer
    }

    fn geometry_buffers(&self) -> &GeometryBuffers {
        self.kept.buffers.get_or_init(|| {
            let upload = |label: &str, bytes: &[u8], usage| self.upload(label, bytes, usage);
            let p = self.prepared;
            let (vertex, index) = (wgpu::BufferUsages::VERTEX, wgpu::BufferUsages::INDEX);
            Arc::new(GeometryBuffers {
                surface_vertices: upload("frame::surface_vertices", bytemuck::cast_slice(&p.surface_vertices), vertex),
                surface_indices: upload("frame::surface_indices", bytemuck::cast_slice(&p.surface_indices), index),
                positions: upload("frame::positions", bytemuck::cast_slice(&p.positions), vertex),
            })
        })
    }

    fn hold<T: Any + Send + Sync>(&self, handle: &Arc<T>) {
        self.held.borrow_mut().push(handle.clone());
    }

    /// A pooled texture, in use until the frame ends.
    pub fn texture(&self, label: &str, size: (u32, u32), format: wgpu::TextureFormat, usage: wgpu::TextureUsages) -> PooledTexture {
        self.texture_of(label, TextureKey::plain(size, format, usage))
    }

    /// A pooled light-space image of one layer per projection face
    /// (shadow maps and what else is rendered from the light), in use until
    /// the frame ends.
    pub fn light_texture(&self, label: &str, map_size: u32, layers: u32, format: wgpu::TextureFormat, usage: wgpu::TextureUsages) -> PooledTexture {
        self.texture_of(label, TextureKey { size: (map_size, map_size), format, usage, layers })
    }

    fn texture_of(&self, label: &str, key: TextureKey) -> PooledTexture {
        let texture = self.pool.texture(self.device, label, key);
        self.hold(&texture);
        texture
    }

    /// A pooled buffer, in use until the frame ends; its contents are stale.
    pub fn buffer(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> PooledBuffer {
        let buffer = self.pool.buffer(self.device, label, size, usage);
        self.hold(&buffer);
        buffer
    }

    /// A pooled buffer holding `value` for a `layout::parameters` binding.
    pub fn parameters<T: bytemuck::Pod>(&self, label: &str, value: &T) -> PooledBuffer {
        let bytes = bytemuck::bytes_of(value);
        let buffer = self.buffer(label, bytes.len() as u64, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
        self.queue.write_buffer(&buffer, 0, bytes);
        buffer
    }

    /// A pooled storage buffer of `count` u32 counters, cleared to zero in
    /// `encoder` before any later pass (readable back with `Frame::counters`).
    pub fn counters(&self, label: &str, count: usize, encoder: &mut wgpu::CommandEncoder) -> PooledBuffer {
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let buffer = self.buffer(label, 4 * count.max(1) as u64, usage);
        encoder.clear_buffer(&buffer, 0, None);
        buffer
    }

    /// A visibility-format image of the camera's size that a compute pass
    /// writes and later passes read.
    pub fn screen_texture(&self, label: &str) -> PooledTexture {
        self.texture(
            label,
            self.size,
            crate::gpu::formats::VISIBILITY,
            wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC,
        )
    }

    /// The side of a light-space image that is read only at the visible
    /// receivers' projections (pvm's penumbra volume map, pvmf's mask): the
    /// automatic map size (`map_size`: a texel per pixel on every visible
    /// receiver), at most `map`, the shadow map's side, which the image's
    /// coordinates scale from (`shadow_test.wgsl`'s `map_point_in`). Such an
    /// image's cost is its volumes' area in texels, and at the map's size it
    /// resolves no more of the image (issue 30). O(triangles) on the CPU.
    pub fn receiver_image_size(&self, map: u32, projection: &LightProjection) -> u32 {
        crate::map_size::auto_map_size(projection, self.camera, self.prepared, self.max_texture_side()).min(map)
    }

    /// The largest texture side the adapter allows.
    pub fn max_texture_side(&self) -> u32 {
        self.device.limits().max_texture_dimension_2d
    }

    /// The largest storage buffer the adapter binds, in bytes.
    pub fn max_storage_buffer(&self) -> u64 {
        let limits = self.device.limits();
        limits.max_storage_buffer_binding_size.min(limits.max_buffer_size)
    }

    /// Refuses a storage buffer of `bytes` beyond the adapter's limit for
    /// `method`, naming what it holds and what to reduce.
    pub fn check_buffer(&self, method: &str, what: &str, bytes: u64, reduce: &str) -> Result<()> {
        let limit = self.max_storage_buffer();
        if bytes > limit {
            return Err(Error::InvalidParameter(format!(
                "method '{method}': {what} would take {bytes} bytes, beyond this adapter's storage-buffer limit of {limit}; reduce {reduce}"
            )));
        }
        Ok(())
    }
}

/// One render in progress.
pub struct Frame<'r> {
    pub ctx: FrameContext<'r>,
    profiler: Profiler<'r>,
    cache: &'r PassCache,
    /// Outputs of cacheable passes that ran: cached once the frame's work is done.
    fresh: Vec<(&'static str, PassKey, Entry)>,
    reused: Vec<&'static str>,
    stats: BTreeMap<String, i64>,
    counters: Vec<(wgpu::Buffer, &'static [&'static str])>,
    intermediates: Vec<Intermediate>,
    want_intermediates: bool,
}

/// What a frame recorded besides its passes, for the renderer to read back.
pub(crate) struct FrameRecord<'r> {
    pub profiler: Profiler<'r>,
    pub fresh: Vec<(&'static str, PassKey, Entry)>,
    pub reused: Vec<&'static str>,
    pub stats: BTreeMap<String, i64>,
    pub counters: Vec<(wgpu::Buffer, &'static [&'static str])>,
    pub intermediates: Vec<Intermediate>,
    pub held: Vec<Arc<dyn Any + Send + Sync>>,
}

impl<'r> Frame<'r> {
    pub(crate) fn new(ctx: FrameContext<'r>, profiler: Profiler<'r>, cache: &'r PassCache, want_intermediates: bool) -> Self {
        Self {
            ctx,
            profiler,
            cache,
            fresh: Vec::new(),
            reused: Vec::new(),
            stats: BTreeMap::new(),
            counters: Vec::new(),
            intermediates: Vec::new(),
            want_intermediates,
        }
    }

    /// Records one named pass (its time is `timings[name]`): `record` gets
    /// the frame's context, the encoder and, with GPU timestamps, where its
    /// wgpu pass (or the first and last of several) writes them.
    pub fn pass<T>(
        &mut self,
        name: &str,
        record: impl FnOnce(&FrameContext<'r>, &mut wgpu::CommandEncoder, Option<PassTimestamps<'_>>) -> T,
    ) -> Result<T> {
        let ctx = &self.ctx;
        let mut out = None;
        self.profiler.pass(name, |encoder, ts| out = Some(record(ctx, encoder, ts)))?;
        out.ok_or_else(|| Error::Gpu(format!("pass '{name}' did not run")))
    }

    /// Untimed work (buffer clears and copies between passes).
    pub fn untimed<T>(&mut self, record: impl FnOnce(&FrameContext<'r>, &mut wgpu::CommandEncoder) -> T) -> T {
        record(&self.ctx, self.profiler.encoder())
    }

    /// The output of cacheable pass `name` for `key`: the cached one when the
    /// pass cache holds it (the pass is then `reused`), else what `record`
    /// makes, which enters the cache once this frame's work is done.
    pub fn cached<T: Any + Send + Sync>(
        &mut self,
        name: &'static str,
        key: PassKey,
        record: impl FnOnce(&mut Self) -> Result<Arc<T>>,
    ) -> Result<Arc<T>> {
        if let Some(hit) = self.cache.get::<T>(name, &key) {
            self.reused.push(name);
            return Ok(hit);
        }
        let value = record(self)?;
        if self.cache.enabled() {
            self.fresh.push((name, key, value.clone()));
        }
        Ok(value)
    }

    /// Marks cacheable pass `name` as reused from the cache (for passes the
    /// renderer looks up itself).
    pub(crate) fn reused(&mut self, name: &'static str) {
        self.reused.push(name);
    }

    /// An output of cacheable pass `name` that ran in this frame, to cache
    /// once the frame's work is done.
    pub(crate) fn fresh<T: Any + Send + Sync>(&mut self, name: &'static str, key: PassKey, value: Arc<T>) {
        if self.cache.enabled() {
            self.fresh.push((name, key, value));
        }
    }

    /// The first `bytes` (a multiple of 4) of `buffer` now: everything
    /// recorded so far is submitted and waited for (a method whose next
    /// passes depend on a count its passes made; `Profiler::read_buffer`).
    pub fn read_now(&mut self, buffer: &wgpu::Buffer, bytes: u32) -> Result<Vec<u8>> {
        self.profiler.read_buffer(buffer, bytes)
    }

    /// Sets a stat (counts that explain the cost).
    pub fn stat(&mut self, name: &str, value: i64) {
        self.stats.insert(name.to_owned(), value);
    }

    /// The stats of the silhouettes a method's volumes or wedges were built
    /// from ([`SilhouetteStats::named`]), and `silhouette_cache_hits`: the
    /// meshes whose silhouettes came from the silhouette cache when this frame
    /// built them (`fresh`), 0 when the pass cache held what they built.
    pub fn silhouette_stats(&mut self, stats: &SilhouetteStats, cache_hits: usize, fresh: bool) {
        for (name, value) in stats.named() {
            self.stat(name, value);
        }
        self.stat("silhouette_cache_hits", if fresh { cache_hits as i64 } else { 0 });
    }

    /// Reads `buffer`'s first `names.len()` u32 counters back into the stats of those names.
    pub fn counters(&mut self, buffer: &wgpu::Buffer, names: &'static [&'static str]) {
        self.counters.push((buffer.clone(), names));
    }

    /// Whether intermediate images were asked for.
    pub fn wants_intermediates(&self) -> bool {
        self.want_intermediates
    }

    /// Reads an intermediate image back (when they were asked for). The
    /// readback takes 32-bit channels ([`Intermediate::readable`]): another
    /// texture is an error here rather than a panic at the readback.
    pub fn intermediate(&mut self, image: Intermediate) -> Result<()> {
        if self.want_intermediates {
            image.readable()?;
            self.intermediates.push(image);
        }
        Ok(())
    }

    pub(crate) fn into_record(self) -> FrameRecord<'r> {
        let mut held = self.ctx.held.into_inner();
        held.push(self.ctx.gbuffer);
        if let Some(geometry) = self.ctx.kept.buffers.get() {
            held.push(geometry.clone());
        }
        FrameRecord {
            profiler: self.profiler,
            fresh: self.fresh,
            reused: self.reused,
            stats: self.stats,
            counters: self.counters,
            intermediates: self.intermediates,
            held,
        }
    }
}

/// `items.iter().map(f)`, in order, with the items split into up to
/// `threads` bands, each mapped on its own scoped thread (a panic in one is
/// the caller's).
fn map_in_bands<T: Sync, R: Send>(items: &[T], threads: usize, f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = threads.min(items.len());
    if threads <= 1 {
        return items.iter().map(f).collect();
    }
    let band = items.len().div_ceil(threads);
    std::thread::scope(|scope| {
        let f = &f;
        let handles: Vec<_> = items.chunks(band).map(|chunk| scope.spawn(move || chunk.iter().map(f).collect::<Vec<_>>())).collect();
        handles.into_iter().flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_keep_the_order_of_a_sequential_map() {
        let items: Vec<u32> = (0..37).collect();
        let want: Vec<u64> = items.iter().map(|&i| u64::from(i) * 3 + 1).collect();
        for threads in [0, 1, 2, 3, 8, 64] {
            assert_eq!(map_in_bands(&items, threads, |&i| u64::from(i) * 3 + 1), want, "{threads} threads");
        }
        assert!(map_in_bands(&[] as &[u32], 4, |&i| i).is_empty());
    }

    #[test]
    fn only_32_bit_channels_are_read_back_as_intermediates() {
        use wgpu::{TextureAspect as A, TextureFormat as F};
        for (format, aspect, channels) in [(F::R32Float, A::All, 1), (F::Rgba32Float, A::All, 3), (F::R32Uint, A::All, 1), (F::Depth32Float, A::DepthOnly, 1)] {
            assert!(readable("x", format, aspect, channels).is_ok(), "{format:?}");
        }
        // pvmf's farthest-edge channel is R16Float: it used to panic in the readback.
        for (format, aspect, channels) in [(F::R16Float, A::All, 1), (F::Rgba8Unorm, A::All, 1), (F::Depth24Plus, A::DepthOnly, 1), (F::R32Float, A::All, 2), (F::R32Float, A::All, 0)] {
            let err = readable("pvmf_far", format, aspect, channels).unwrap_err().to_string();
            assert!(err.contains("pvmf_far") && err.contains("32 bits"), "{format:?}: {err}");
        }
    }
}
