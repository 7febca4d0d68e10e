//! The long-lived renderer: owns the device, the shared passes, the
//! resource pool and the pass cache, builds each method's pipelines once (on
//! its first render), and serves renders of any scene with any registered
//! method. It names no method: a render prepares the scene, draws (or
//! reuses) the G-buffer, hands a [`Frame`] to the method, shades the
//! visibility the method returns and reads back what was asked.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use crate::error::{Error, Result};
use crate::frame::{Frame, FrameContext, GBuffer};
use crate::geometry_cache::{GeometryCache, Prepared};
use crate::gpu::{AdapterSummary, GpuContext, Profiler, Timings};
use crate::gpu::formats;
use crate::gpu::pool::{PoolStats, PooledTexture, ResourcePool};
use crate::gpu::readback::{self, PendingReadback};
use crate::method::{DynMethod, Registered};
use crate::methods::{MethodConfig, REGISTRY};
use crate::params::ParamValue;
use crate::pass_cache::{CachedPass, PassCache, PassKey};
use crate::passes::gbuffer::{GBufferPass, GBUFFER};
use crate::passes::samplers::ComparisonSamplers;
use crate::passes::shading::{object_id_texture, ObjectIdPass, ShadingPass};
use crate::passes::shadow_map::ShadowMapPass;
use crate::scene::{Camera, PreparedScene, Scene};
use crate::silhouettes::SilhouetteCache;

/// Pixel data of one output image.
#[derive(Debug, Clone, PartialEq)]
pub enum ImageData {
    F32(Vec<f32>),
    I32(Vec<i32>),
}

/// A named output image: `shape` is (rows, columns), (rows, columns, channels), or
/// with the layers first for a cube map's intermediates (layers, rows, columns[, channels]).
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    pub name: String,
    pub shape: Vec<usize>,
    pub data: ImageData,
}

impl Image {
    pub fn f32(&self) -> Option<&[f32]> {
        match &self.data {
            ImageData::F32(v) => Some(v),
            ImageData::I32(_) => None,
        }
    }
}

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RenderOptions {
    /// Also read back each method's intermediate images (shadow maps, masks).
    pub intermediates: bool,
    /// Which images to read back (all by default).
    pub outputs: Outputs,
}

/// The images a render can return (SPEC section 5), in order.
pub const OUTPUTS: [&str; 6] = ["radiance", "visibility", "depth", "position", "normal", "object_id"];

/// A set of [`OUTPUTS`]: a render reads back only these, and runs the shading
/// pass only when `radiance` is among them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Outputs(u8);

impl Default for Outputs {
    fn default() -> Self {
        Self::ALL
    }
}

impl Outputs {
    pub const ALL: Outputs = Outputs((1 << OUTPUTS.len()) - 1);
    pub const NONE: Outputs = Outputs(0);

    /// The set of the names given; an unknown name is an error naming the choices.
    pub fn parse<'a>(names: impl IntoIterator<Item = &'a str>) -> Result<Self> {
        let mut bits = 0;
        for name in names {
            let i = OUTPUTS.iter().position(|o| *o == name).ok_or_else(|| {
                Error::InvalidParameter(format!("unknown output '{name}'; outputs are {}", OUTPUTS.join(", ")))
            })?;
            bits |= 1 << i;
        }
        Ok(Self(bits))
    }

    pub fn has(self, name: &str) -> bool {
        OUTPUTS.iter().position(|o| *o == name).is_some_and(|i| self.0 & (1 << i) != 0)
    }
}

#[derive(Debug, Clone)]
pub struct RenderResult {
    pub method: &'static str,
    pub params: BTreeMap<String, ParamValue>,
    pub images: Vec<Image>,
    pub timings: Timings,
    /// Wall-clock time of the whole call, upload and readback included.
    pub total_ms: f64,
    pub stats: BTreeMap<String, i64>,
}

impl RenderResult {
    pub fn image(&self, name: &str) -> Option<&Image> {
        self.images.iter().find(|i| i.name == name)
    }
}

/// Every pass the cache may hold: the G-buffer and each method's declared
/// passes (each name once).
fn cached_passes() -> Vec<CachedPass> {
    let mut passes = vec![GBUFFER];
    for pass in REGISTRY.iter().flat_map(|r| (r.cached_passes)().iter()) {
        if !passes.iter().any(|p| p.name == pass.name) {
            passes.push(*pass);
        }
    }
    passes
}

pub struct Renderer {
    ctx: GpuContext,
    use_timestamps: bool,
    pool: ResourcePool,
    gbuffer: GBufferPass,
    shading: ShadingPass,
    object_ids: ObjectIdPass,
    /// Topology and silhouettes, cached by mesh content and light centre.
    silhouettes: SilhouetteCache,
    /// The last geometry rendered, prepared and uploaded, and its casters per light.
    geometry: GeometryCache,
    /// Each method rendered so far, by its registry entry, built on its first render.
    methods: Mutex<Vec<(&'static Registered, Arc<dyn DynMethod>)>>,
    cache: PassCache,
}

impl Renderer {
    /// Creates the device and the shared passes. `use_timestamps` asks for
    /// GPU timestamps; they are used only where the adapter has them. The
    /// pass cache is on.
    pub fn new(use_timestamps: bool) -> Result<Self> {
        Self::with_pass_cache(use_timestamps, true)
    }

    /// [`Self::new`], with the pass cache on or off. Off, every render runs
    /// every pass from scratch (what benchmarks of repeated renders want);
    /// on, a render reuses the outputs of passes whose inputs are unchanged
    /// since a recent render, with bit-identical results.
    pub fn with_pass_cache(use_timestamps: bool, pass_cache: bool) -> Result<Self> {
        let ctx = GpuContext::new()?;
        let pool = ResourcePool::default();
        let device = &ctx.device;
        let (gbuffer, shading, object_ids) = ctx.scoped(|| {
            // The pool's shared passes, built here so that a device error
            // surfaces now and no method's first render pays for them.
            ShadowMapPass::shared(device, &pool);
            ComparisonSamplers::shared(device, &pool);
            Ok((GBufferPass::new(device, &pool), ShadingPass::new(device, &pool), ObjectIdPass::new(device, &pool)))
        })?;
        let methods = Mutex::default();
        let cache = PassCache::new(pass_cache, cached_passes());
        Ok(Self { ctx, use_timestamps, pool, gbuffer, shading, object_ids, silhouettes: SilhouetteCache::default(), geometry: GeometryCache::default(), methods, cache })
    }

    /// Whether renders reuse cached pass outputs.
    pub fn pass_cache_enabled(&self) -> bool {
        self.cache.enabled()
    }

    /// Entries the pass cache holds, per cacheable pass.
    pub fn pass_cache_entries(&self) -> Vec<(&'static str, usize)> {
        self.cache.entries()
    }

    /// Drops every cached pass output and kept geometry, and the GPU memory
    /// they hold.
    pub fn clear_pass_cache(&self) {
        self.cache.clear();
        self.geometry.clear();
        self.pool.clear();
    }

    /// What the resource pool holds.
    pub fn pool_stats(&self) -> PoolStats {
        self.pool.stats()
    }

    /// Releases every pooled resource not in use (or held by the pass
    /// cache), the kept geometry's buffers included.
    pub fn clear_pool(&self) {
        self.geometry.clear();
        self.pool.clear();
    }

    pub fn adapter(&self) -> &AdapterSummary {
        &self.ctx.summary
    }

    /// Whether this renderer's timings come from GPU timestamps.
    pub fn uses_timestamps(&self) -> bool {
        self.use_timestamps && self.ctx.has_timestamps()
    }

    /// The built method of `entry` (its pipelines built on its first render).
    fn method(&self, entry: &'static Registered) -> Arc<dyn DynMethod> {
        let mut methods = self.methods.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, built)) = methods.iter().find(|(e, _)| std::ptr::eq(*e, entry)) {
            return built.clone();
        }
        let built: Arc<dyn DynMethod> = Arc::from((entry.build)(&self.ctx.device, &self.pool));
        methods.push((entry, built.clone()));
        built
    }

    pub fn render(&self, scene: &Scene, camera: &Camera, method: &MethodConfig, options: &RenderOptions) -> Result<RenderResult> {
        let start = Instant::now();
        camera.validate()?;
        let max = self.ctx.device.limits().max_texture_dimension_2d;
        if camera.width > max || camera.height > max {
            return Err(Error::InvalidCamera(format!(
                "image of {}x{} exceeds this adapter's largest texture side, {max}",
                camera.width, camera.height
            )));
        }
        // Prepared and uploaded once while the meshes are unchanged (geometry_cache.rs).
        let kept = self.geometry.prepare(scene)?;
        let prepared = &kept.geometry.prepared;
        let corner_bytes = (prepared.corners.len() * std::mem::size_of::<crate::scene::CornerVertex>()) as u64;
        if prepared.corners.len() > u32::MAX as usize || corner_bytes > self.ctx.device.limits().max_buffer_size {
            return Err(Error::InvalidScene(format!(
                "{} triangles exceed what this adapter can hold in one buffer",
                prepared.triangle_count
            )));
        }
        let chosen_map_size = std::cell::Cell::new(None);
        let result = self.ctx.scoped(|| self.record_and_read(scene, camera, method, options, &kept, &chosen_map_size));
        // Every handle of the frame is dropped: its resources are free again.
        self.pool.end_frame();
        let (mut result, fresh) = match result {
            Ok(done) => done,
            Err(e) => {
                // A resource whose allocation failed is invalid in every later
                // call, and a free one could be handed to the next render:
                // release them all (the pass cache only takes a render's
                // outputs once it succeeded, below).
                if matches!(e, Error::OutOfMemory(_) | Error::Gpu(_)) {
                    self.geometry.clear();
                    self.pool.clear();
                }
                return Err(match e {
                    Error::OutOfMemory(detail) => {
                        Error::OutOfMemory(out_of_memory_message(method, camera, chosen_map_size.get(), prepared.triangle_count, &detail))
                    }
                    e => e,
                });
            }
        };
        // Submitted, waited for and free of GPU errors: what ran may now be reused.
        for (name, key, value) in fresh {
            self.cache.insert(name, key, value);
        }
        result.total_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(result)
    }

    /// One render inside the device's error scope: the G-buffer, the method
    /// (its map size resolved first when asked for `"auto"`), shading, and
    /// the readback of what `options` asks for.
    fn record_and_read(
        &self,
        scene: &Scene,
        camera: &Camera,
        method: &MethodConfig,
        options: &RenderOptions,
        kept: &Prepared,
        chosen_map_size: &std::cell::Cell<Option<u32>>,
    ) -> Result<(RenderResult, FreshPasses)> {
        let prepared = &kept.geometry.prepared;
        let mut frame = self.begin_frame(scene, camera, kept, options.intermediates)?;
        let resolved = Self::resolve_map_size(&mut frame, method, chosen_map_size)?;
        let method = resolved.as_ref().unwrap_or(method);
        let output = self.method(method.entry()).record(&mut frame, method.typed())?;
        let (radiance, object_ids) = self.shade(&mut frame, &output.visibility, options.outputs)?;
        let gbuffer = frame.ctx.gbuffer.clone();
        let mut record = frame.into_record();
        let mut stats = BTreeMap::from([
            ("triangles".to_owned(), prepared.triangle_count as i64),
            ("degenerate_triangles".to_owned(), prepared.degenerate_triangles as i64),
            ("pass_cache".to_owned(), i64::from(self.cache.enabled())),
            ("reused_geometry".to_owned(), i64::from(kept.reused)),
        ]);
        stats.extend(std::mem::take(&mut record.stats));
        // What was reused: a count, and a flag for each cacheable pass this method has.
        let cacheable = std::iter::once(&GBUFFER).chain((method.entry().cached_passes)());
        for pass in cacheable {
            stats.insert(format!("reused_{}", pass.name), i64::from(record.reused.contains(&pass.name)));
        }
        stats.insert("reused_passes".into(), record.reused.len() as i64);
        let targets = Targets {
            radiance: radiance.as_ref().map(|r| &r.resource.texture),
            object_ids: object_ids.as_ref().map(|o| &o.resource.texture),
            visibility: &output.visibility,
            gbuffer: &gbuffer,
        };
        let (images, timings, fresh) = self.read_back(record, targets, options.outputs, prepared, &mut stats)?;
        let result = RenderResult { method: method.name(), params: method.effective_params(), images, timings, total_ms: 0.0, stats };
        Ok((result, fresh))
    }

    /// The frame of one render, with its G-buffer drawn or reused from the
    /// pass cache (keyed by the geometry, the camera's matrices and the size).
    fn begin_frame<'r>(&'r self, scene: &'r Scene, camera: &'r Camera, kept: &'r Prepared, intermediates: bool) -> Result<Frame<'r>> {
        let prepared = &kept.geometry.prepared;
        let device = &self.ctx.device;
        let size = (camera.width, camera.height);
        let (projection, _, _) = camera.projection(prepared.bounds_min, prepared.bounds_max);
        let view = camera.view();
        // Pass-cache keys (crate::pass_cache): the geometry is hashed once, and
        // only when there is a cache to look in.
        let geometry = if self.cache.enabled() { *kept.geometry.hash.get_or_init(|| crate::pass_cache::geometry_hash(prepared)) } else { 0 }.to_le_bytes();
        let gbuffer_key = PassKey::new(GBUFFER.name)
            .bytes(&geometry)
            .f32s(&view.to_cols_array())
            .f32s(&projection.to_cols_array())
            .u32(size.0)
            .u32(size.1)
            .finish();
        let cached_gbuffer = self.cache.get::<GBuffer>(GBUFFER.name, &gbuffer_key);
        let gbuffer = cached_gbuffer.clone().unwrap_or_else(|| Arc::new(GBuffer::new(device, &self.pool, size)));
        let ctx = FrameContext::new(
            device,
            &self.ctx.queue,
            &self.silhouettes,
            &self.pool,
            scene,
            (&kept.geometry, &kept.light),
            camera,
            (gbuffer.clone(), gbuffer_key.clone()),
            geometry,
        );
        let mut frame = Frame::new(ctx, Profiler::new(&self.ctx, &self.pool, self.use_timestamps), &self.cache, intermediates);
        if cached_gbuffer.is_some() {
            frame.reused(GBUFFER.name);
        } else {
            frame.pass(GBUFFER.name, |ctx, encoder, ts| self.gbuffer.record(ctx, encoder, view, projection, ts))?;
            frame.fresh(GBUFFER.name, gbuffer_key, gbuffer);
        }
        Ok(frame)
    }

    /// `map_size="auto"` (the default): the method's configuration with the
    /// size chosen from the image for the projection its maps use
    /// ([`crate::map_size`]); None when the size was given.
    fn resolve_map_size(frame: &mut Frame<'_>, method: &MethodConfig, chosen: &std::cell::Cell<Option<u32>>) -> Result<Option<MethodConfig>> {
        let Some((name, mode)) = method.auto_map_size() else { return Ok(None) };
        let projection = frame.ctx.projection(mode)?;
        let map_size = crate::map_size::auto_map_size(&projection, frame.ctx.camera, frame.ctx.prepared, frame.ctx.max_texture_side());
        chosen.set(Some(map_size));
        frame.stat("map_size_auto", 1);
        method.with_map_size(name, map_size).map(Some)
    }

    /// Shading (SPEC section 3) of the method's visibility, only where
    /// radiance is asked for, and the object id image (written by the same
    /// pass; by its own where object ids are asked for without radiance and
    /// without normals, which hold them too).
    fn shade(&self, frame: &mut Frame<'_>, visibility: &PooledTexture, outputs: Outputs) -> Result<(Option<PooledTexture>, Option<PooledTexture>)> {
        if !outputs.has("radiance") {
            if !outputs.has("object_id") || outputs.has("normal") {
                return Ok((None, None));
            }
            let object_ids = object_id_texture(&frame.ctx);
            frame.pass("object_ids", |ctx, encoder, ts| self.object_ids.record(ctx, encoder, &object_ids, ts))?;
            return Ok((None, Some(object_ids)));
        }
        let usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC;
        let radiance = frame.ctx.texture("renderer::radiance", frame.ctx.size, formats::RADIANCE, usage);
        let object_ids = object_id_texture(&frame.ctx);
        frame.pass("shading", |ctx, encoder, ts| self.shading.record(ctx, encoder, visibility, (&radiance, &object_ids), ts))?;
        Ok((Some(radiance), Some(object_ids)))
    }

    /// Copies what `outputs` asks for (and the frame's counters, intermediates
    /// and timestamps) into readback buffers, submits and waits once, and
    /// unpacks them into images and stats. Returns the images, the timings and
    /// the fresh pass outputs for the pass cache.
    fn read_back(
        &self,
        record: crate::frame::FrameRecord<'_>,
        targets: Targets<'_>,
        outputs: Outputs,
        prepared: &PreparedScene,
        stats: &mut BTreeMap<String, i64>,
    ) -> Result<(Vec<Image>, Timings, FreshPasses)> {
        let device = &self.ctx.device;
        let size = targets.gbuffer.size;
        let (profile, mut encoder, timestamps) = record.profiler.finish()?;
        let uses_timestamps = timestamps.is_some();
        let mut readback_start = Instant::now();
        let all = wgpu::TextureAspect::All;
        let copy = |encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture, aspect| {
            readback::copy_texture(device, &self.pool, encoder, texture, aspect)
        };
        // Object ids come from their own image where there is one and the
        // normals (16 bytes a pixel against 4) are not asked for.
        let ids_image = targets.object_ids.filter(|_| outputs.has("object_id") && !outputs.has("normal"));
        let (want_position, want_normal) = (outputs.has("depth") || outputs.has("position"), outputs.has("normal") || (outputs.has("object_id") && ids_image.is_none()));
        let mut pending: Vec<PendingReadback> = Vec::new();
        if let Some(radiance) = targets.radiance {
            pending.push(copy(&mut encoder, radiance, all));
        }
        if outputs.has("visibility") {
            pending.push(copy(&mut encoder, targets.visibility, all));
        }
        if want_position {
            pending.push(copy(&mut encoder, &targets.gbuffer.position, all));
        }
        if want_normal {
            pending.push(copy(&mut encoder, &targets.gbuffer.normal, all));
        }
        if let Some(ids) = ids_image {
            pending.push(copy(&mut encoder, ids, all));
        }
        for (buffer, names) in &record.counters {
            pending.push(readback::copy_buffer(device, &self.pool, &mut encoder, buffer, 4 * names.len() as u32));
        }
        for i in &record.intermediates {
            pending.push(copy(&mut encoder, &i.texture, i.aspect));
        }
        let has_timestamps = timestamps.is_some();
        pending.extend(timestamps);
        // One submission of what is left and one wait for it all. With
        // timestamps nothing was submitted before (the whole frame runs now):
        // `readback` is then the host's part alone, mapping and unpacking;
        // with CPU clocks every pass was waited for, and it also holds the
        // copies' own time.
        self.ctx.queue.submit([encoder.finish()]);
        readback::wait_mapped(&self.ctx, &pending)?;
        if uses_timestamps {
            readback_start = Instant::now();
        }
        let mut all = readback::read_all_words(&pending)?;
        let ticks = if has_timestamps { all.pop().map(|w| bytemuck::cast_slice::<u32, u8>(&w).to_vec()) } else { None };
        let mut timings = profile.timings(ticks);
        let mut bytes = all.into_iter();
        let mut next = || readback::words_as::<f32>(bytes.next().unwrap_or_default());
        let (w, h) = (size.0 as usize, size.1 as usize);
        let mut images = Vec::new();
        let rgb = |texels: &[f32]| readback::convert(texels, 4, 3, |t, d: &mut [f32]| d.copy_from_slice(&t[..3]));
        if targets.radiance.is_some() {
            images.push(Image { name: "radiance".into(), shape: vec![h, w, 3], data: ImageData::F32(rgb(&next())) });
        }
        if outputs.has("visibility") {
            images.push(Image { name: "visibility".into(), shape: vec![h, w], data: ImageData::F32(next()) });
        }
        if want_position {
            let position = next();
            if outputs.has("depth") {
                let depth = readback::convert(&position, 4, 1, |t, d: &mut [f32]| d[0] = t[3]);
                images.push(Image { name: "depth".into(), shape: vec![h, w], data: ImageData::F32(depth) });
            }
            if outputs.has("position") {
                images.push(Image { name: "position".into(), shape: vec![h, w, 3], data: ImageData::F32(rgb(&position)) });
            }
        }
        let mut object_id: Option<Vec<i32>> = None;
        if want_normal {
            let normal = next();
            if outputs.has("normal") {
                images.push(Image { name: "normal".into(), shape: vec![h, w, 3], data: ImageData::F32(rgb(&normal)) });
            }
            object_id = Some(readback::convert(&normal, 4, 1, |t, d: &mut [i32]| {
                d[0] = if t[3] < 0.0 { -1 } else { prepared.materials.get(t[3] as usize).map_or(-1, |m| m.1) };
            }));
        }
        if ids_image.is_some() {
            object_id = Some(readback::words_as::<i32>(bytes.next().unwrap_or_default()));
        }
        if let Some(object_id) = object_id {
            // Known where object ids are read back (`normal` or `object_id` asked for).
            stats.insert("geometry_pixels".into(), object_id.iter().filter(|&&i| i >= 0).count() as i64);
            if outputs.has("object_id") {
                images.push(Image { name: "object_id".into(), shape: vec![h, w], data: ImageData::I32(object_id) });
            }
        }
        for (_, names) in &record.counters {
            let counts: Vec<u32> = bytes.next().unwrap_or_default();
            for (i, name) in names.iter().enumerate() {
                stats.insert((*name).into(), counts.get(i).copied().unwrap_or(0) as i64);
            }
        }
        for i in &record.intermediates {
            images.push(intermediate_image(i, readback::words_as::<f32>(bytes.next().unwrap_or_default())));
        }
        timings.passes.push(("readback".into(), readback_start.elapsed().as_secs_f64() * 1e3));
        drop(record.held);
        // Submitted and waited for: what ran may be reused once the error
        // scope shows the render free of GPU errors (`render`).
        Ok((images, timings, record.fresh))
    }
}

/// Outputs of cacheable passes that ran in a render: cached once it succeeded.
type FreshPasses = Vec<(&'static str, PassKey, crate::pass_cache::Entry)>;

/// The images a render reads back besides the frame's own.
struct Targets<'a> {
    radiance: Option<&'a wgpu::Texture>,
    /// The object id image, where a pass wrote one.
    object_ids: Option<&'a wgpu::Texture>,
    visibility: &'a wgpu::Texture,
    gbuffer: &'a GBuffer,
}

/// A method's intermediate image from its texels as read back: the channels
/// it keeps, depth scaled to world units, a leading axis for several layers.
fn intermediate_image(i: &crate::frame::Intermediate, raw: Vec<f32>) -> Image {
    let (w, h, layers) = (i.texture.width() as usize, i.texture.height() as usize, i.texture.depth_or_array_layers() as usize);
    let stored = raw.len() / (w * h * layers).max(1);
    let mut data: Vec<f32> = if stored == i.channels { raw } else { raw.chunks_exact(stored).flat_map(|t| t[..i.channels].to_vec()).collect() };
    if i.scale != 1.0 {
        // A linear-depth map stores depth / far: hand back world-unit light depth.
        data.iter_mut().for_each(|d| *d *= i.scale);
    }
    let mut shape = if i.channels == 1 { vec![h, w] } else { vec![h, w, i.channels] };
    if layers > 1 {
        shape.insert(0, layers);
    }
    Image { name: i.name.into(), shape, data: ImageData::F32(data) }
}

/// Bytes of one shadow-map face (`gpu::formats::DEPTH`, 32-bit depth).
const MAP_TEXEL_BYTES: u64 = 4;

fn gib(bytes: u64) -> String {
    format!("{:.1} GiB", bytes as f64 / (1u64 << 30) as f64)
}

/// The out-of-memory message of a render: what it asked for (image, map size
/// and projection, with the maps' memory) and what to lower, then the
/// adapter's own words (`detail`).
fn out_of_memory_message(method: &MethodConfig, camera: &Camera, chosen_map_size: Option<u32>, triangles: usize, detail: &str) -> String {
    let params = method.effective_params();
    let mut asked = vec![format!("an image of {}x{}", camera.width, camera.height)];
    let mut fixes = Vec::new();
    let map_size = match params.get("map_size") {
        Some(ParamValue::Int(n)) => Some((format!("map_size {n}"), *n as u64)),
        Some(_) => chosen_map_size.map(|n| (format!("map_size 'auto' (chose {n})"), n as u64)),
        None => None,
    };
    if let Some((words, side)) = &map_size {
        let side = *side;
        let face = side * side * MAP_TEXEL_BYTES;
        let projection = match params.get("projection") {
            Some(ParamValue::Str(p)) => p.clone(),
            _ => "frustum".into(),
        };
        let maps = match projection.as_str() {
            "cube" => format!("a cube map of six {side}x{side} faces takes {}", gib(6 * face)),
            "frustum" => format!("a {side}x{side} map takes {}", gib(face)),
            _ => format!("a {side}x{side} frustum map takes {}, a cube map of six faces {}", gib(face), gib(6 * face)),
        };
        asked.push(format!("{words} and projection '{projection}' ({maps})"));
        fixes.push("a smaller map_size (or 'auto', sized to the image)".to_owned());
        if projection != "frustum" {
            fixes.push("projection='frustum' (one map where a cube map has six faces)".to_owned());
        }
    }
    if let Some(ParamValue::Int(depth)) = params.get("max_depth") {
        asked.push(format!("max_depth {depth}"));
        fixes.push("a lower max_depth (each level up to four times the maps)".to_owned());
    }
    fixes.push("a smaller image".to_owned());
    if map_size.is_none() {
        fixes.push(format!("fewer triangles (the scene has {triangles})"));
    }
    let last = fixes.pop().unwrap_or_default();
    let fixes = if fixes.is_empty() { last } else { format!("{} or {last}", fixes.join(", ")) };
    let detail = detail.strip_prefix("out of GPU memory: ").unwrap_or(detail);
    format!(
        "out of GPU memory rendering method '{}' with {}: try {fixes}. (The adapter said: {detail}.)",
        method.name(),
        asked.join(", "),
    )
}
