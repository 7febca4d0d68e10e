//! The long-lived renderer: owns the device and every pipeline (built once),
//! and serves renders of any scene with any method.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::error::{Error, Result};
use crate::gpu::readback::{self, PendingReadback};
use crate::gpu::{AdapterSummary, GpuContext, Profiler, Timings};
use crate::light_frustum::LightFrustum;
use crate::methods::hard::HardShadow;
use crate::methods::pcf::{ComparisonSamplers, PercentageCloserFiltering};
use crate::methods::pcss::PercentageCloserSoftShadows;
use crate::methods::pvm::{PenumbraVolumeMaps, PvmFrame, PvmVolumes};
use crate::methods::pvmf::{PenumbraVolumeMaskFiltering, PvmfEstimate, PvmfMask};
use crate::methods::reference::ReferenceShadows;
use crate::silhouettes::SilhouetteCache;
use crate::methods::{MethodConfig, ParamValue};
use crate::pass_cache::{PassCache, PassKey, PassKind};
use crate::passes::gbuffer::{GBuffer, GBufferPass};
use crate::passes::shading::{ShadingPass, RADIANCE_FORMAT};
use crate::passes::shadow_map::ShadowMapPass;
use crate::scene::{Camera, PreparedScene, Scene};

/// Pixel data of one output image.
#[derive(Debug, Clone, PartialEq)]
pub enum ImageData {
    F32(Vec<f32>),
    I32(Vec<i32>),
}

/// A named output image: `shape` is (rows, columns) or (rows, columns, channels).
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

/// A method's intermediate image, read back on request.
struct Intermediate<'a> {
    name: &'static str,
    texture: &'a wgpu::Texture,
    aspect: wgpu::TextureAspect,
    /// Channels kept of those stored.
    channels: usize,
    /// A linear-depth map storing depth / far.
    linear_depth: bool,
}

impl<'a> Intermediate<'a> {
    fn depth(name: &'static str, texture: &'a wgpu::Texture) -> Self {
        Self { name, texture, aspect: wgpu::TextureAspect::DepthOnly, channels: 1, linear_depth: true }
    }
    fn color(name: &'static str, texture: &'a wgpu::Texture, channels: usize) -> Self {
        Self { name, texture, aspect: wgpu::TextureAspect::All, channels, linear_depth: false }
    }
}

/// The renderer's pass cache (see [`crate::pass_cache`]).
type RendererCache = PassCache<GBuffer, wgpu::Texture, PvmVolumes, PvmfMask, PvmfEstimate>;

/// Outputs of passes that ran in this render, with their keys: they enter
/// the cache once the render has been submitted and waited for.
#[derive(Default)]
struct FreshEntries {
    gbuffer: Option<(PassKey, Arc<GBuffer>)>,
    shadow_map: Option<(PassKey, Arc<wgpu::Texture>)>,
    penumbra_volumes: Option<(PassKey, Arc<PvmVolumes>)>,
    mask: Option<(PassKey, Arc<PvmfMask>)>,
    estimation: Option<(PassKey, Arc<PvmfEstimate>)>,
}

impl FreshEntries {
    fn store(self, cache: &RendererCache) {
        if let Some((k, v)) = self.gbuffer {
            cache.gbuffer.insert(k, v);
        }
        if let Some((k, v)) = self.shadow_map {
            cache.shadow_map.insert(k, v);
        }
        if let Some((k, v)) = self.penumbra_volumes {
            cache.penumbra_volumes.insert(k, v);
        }
        if let Some((k, v)) = self.mask {
            cache.mask.insert(k, v);
        }
        if let Some((k, v)) = self.estimation {
            cache.estimation.insert(k, v);
        }
    }
}

pub struct Renderer {
    ctx: GpuContext,
    use_timestamps: bool,
    gbuffer: GBufferPass,
    shadow_map: ShadowMapPass,
    shading: ShadingPass,
    hard: HardShadow,
    comparison_samplers: ComparisonSamplers,
    pcf: PercentageCloserFiltering,
    pcss: PercentageCloserSoftShadows,
    pvm: PenumbraVolumeMaps,
    reference: ReferenceShadows,
    pvmf: PenumbraVolumeMaskFiltering,
    silhouettes: SilhouetteCache,
    cache: RendererCache,
}

impl Renderer {
    /// Creates the device and builds every pipeline. `use_timestamps` asks for
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
        let device = &ctx.device;
        let (gbuffer, shadow_map, shading, hard, pvm, reference, pvmf) = ctx.scoped(|| {
            Ok((
                GBufferPass::new(device),
                ShadowMapPass::new(device),
                ShadingPass::new(device),
                HardShadow::new(device),
                PenumbraVolumeMaps::new(device),
                ReferenceShadows::new(device),
                PenumbraVolumeMaskFiltering::new(device),
            ))
        })?;
        let (comparison_samplers, pcf, pcss) = ctx.scoped(|| {
            Ok((
                ComparisonSamplers::new(device),
                PercentageCloserFiltering::new(device),
                PercentageCloserSoftShadows::new(device),
            ))
        })?;
        let silhouettes = SilhouetteCache::default();
        let cache = PassCache::new(pass_cache);
        Ok(Self { ctx, use_timestamps, gbuffer, shadow_map, shading, hard, comparison_samplers, pcf, pcss, pvm, reference, pvmf, silhouettes, cache })
    }

    /// Whether renders reuse cached pass outputs.
    pub fn pass_cache_enabled(&self) -> bool {
        self.cache.enabled()
    }

    /// Entries the pass cache holds, per pass kind.
    pub fn pass_cache_entries(&self) -> Vec<(&'static str, usize)> {
        self.cache.entries()
    }

    /// Drops every cached pass output and the GPU memory it holds.
    pub fn clear_pass_cache(&self) {
        self.cache.clear();
    }

    pub fn adapter(&self) -> &AdapterSummary {
        &self.ctx.summary
    }

    /// Whether this renderer's timings come from GPU timestamps.
    pub fn uses_timestamps(&self) -> bool {
        self.use_timestamps && self.ctx.has_timestamps()
    }

    fn check_limits(&self, camera: &Camera, method: &MethodConfig) -> Result<()> {
        let max = self.ctx.device.limits().max_texture_dimension_2d;
        if camera.width > max || camera.height > max {
            return Err(Error::InvalidCamera(format!(
                "image of {}x{} exceeds this adapter's largest texture side, {max}",
                camera.width, camera.height
            )));
        }
        let p = method.shadow_map();
        if p.map_size > max {
            return Err(Error::InvalidParameter(format!(
                "map_size {} exceeds this adapter's largest texture side, {max}",
                p.map_size
            )));
        }
        Ok(())
    }

    pub fn render(
        &self,
        scene: &Scene,
        camera: &Camera,
        method: &MethodConfig,
        options: &RenderOptions,
    ) -> Result<RenderResult> {
        let start = Instant::now();
        camera.validate()?;
        self.check_limits(camera, method)?;
        let prepared = scene.prepare()?;
        let corner_bytes = (prepared.corners.len() * std::mem::size_of::<crate::scene::CornerVertex>()) as u64;
        if prepared.corners.len() > u32::MAX as usize || corner_bytes > self.ctx.device.limits().max_buffer_size {
            return Err(Error::InvalidScene(format!(
                "{} triangles exceed what this adapter can hold in one buffer",
                prepared.triangle_count
            )));
        }
        let frustum = LightFrustum::fit(
            Vec3::from(scene.light.center),
            prepared.corners.iter().map(|c| Vec3::from(c.position)),
        )?;
        let mut result = self.ctx.scoped(|| self.record_and_read(scene, camera, method, options, &prepared, &frustum))?;
        result.total_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(result)
    }

    fn record_and_read(
        &self,
        scene: &Scene,
        camera: &Camera,
        method: &MethodConfig,
        options: &RenderOptions,
        prepared: &PreparedScene,
        frustum: &LightFrustum,
    ) -> Result<RenderResult> {
        let device = &self.ctx.device;
        let size = (camera.width, camera.height);
        let vertex_count = prepared.corners.len() as u32;
        // Uploaded only when a pass draws the geometry: not when the pass
        // cache supplies the G-buffer and the shadow map (a sweep of filter
        // settings re-uploads nothing).
        let vertex_buffer = std::cell::OnceCell::new();
        let vertices = || {
            vertex_buffer.get_or_init(|| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("renderer::corners"),
                    contents: bytemuck::cast_slice(&prepared.corners),
                    usage: wgpu::BufferUsages::VERTEX,
                })
            })
        };
        let visibility = ShadingPass::create_visibility(device, size);
        let radiance = crate::gpu::layout::create_texture(
            device,
            "renderer::radiance",
            size,
            RADIANCE_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
        );
        let (projection, _, _) = camera.projection(prepared.bounds_min, prepared.bounds_max);
        let view = camera.view();
        let mut profiler = Profiler::new(&self.ctx, self.use_timestamps);
        // Pass-cache keys (crate::pass_cache): the geometry is hashed once, and
        // only when there is a cache to look in.
        let geometry = if self.cache.enabled() { crate::pass_cache::geometry_hash(prepared) } else { 0 };
        let geometry = geometry.to_le_bytes();
        let mut fresh = FreshEntries::default();
        let mut reused: Vec<PassKind> = Vec::new();
        // The G-buffer reads the geometry and the camera's matrices and size.
        let gbuffer_key = PassKey::new(PassKind::GBuffer)
            .bytes(&geometry)
            .f32s(&view.to_cols_array())
            .f32s(&projection.to_cols_array())
            .u32(size.0)
            .u32(size.1)
            .finish();
        let gbuffer = match self.cache.gbuffer.get(&gbuffer_key) {
            Some(cached) => {
                reused.push(PassKind::GBuffer);
                cached
            }
            None => {
                let gbuffer = Arc::new(GBuffer::new(device, size));
                profiler.pass("gbuffer", |encoder, ts| {
                    self.gbuffer.record(device, encoder, &gbuffer, vertices(), vertex_count, view, projection, ts)
                })?;
                fresh.gbuffer = Some((gbuffer_key.clone(), gbuffer.clone()));
                gbuffer
            }
        };
        let mut stats = BTreeMap::from([
            ("triangles".to_owned(), prepared.triangle_count as i64),
            ("degenerate_triangles".to_owned(), prepared.degenerate_triangles as i64),
            ("pass_cache".to_owned(), i64::from(self.cache.enabled())),
        ]);
        let mut intermediates: Vec<Intermediate<'_>> = Vec::new();
        // Pass 1 of every method but `reference`: the shadow map from the light centre.
        let settings = method.shadow_map();
        let centre_map = !matches!(method, MethodConfig::Reference(_));
        // It reads the geometry, the frustum, the map's size and which surface it keeps.
        let map_depth = settings.bias.map_depth();
        let shadow_key = PassKey::new(PassKind::ShadowMap)
            .bytes(&geometry)
            .frustum(frustum)
            .u32(settings.map_size)
            .bytes(format!("{map_depth:?}").as_bytes())
            .finish();
        let shadow_map = match centre_map.then(|| self.cache.shadow_map.get(&shadow_key)).flatten() {
            Some(cached) => {
                reused.push(PassKind::ShadowMap);
                stats.insert("shadow_maps_rendered".into(), 0);
                cached
            }
            None => {
                let shadow_map = Arc::new(ShadowMapPass::create_map(device, if centre_map { settings.map_size } else { 1 }));
                if centre_map {
                    profiler.pass("shadow_map", |encoder, ts| {
                        self.shadow_map.record(device, encoder, &shadow_map, frustum, map_depth, vertices(), vertex_count, ts)
                    })?;
                    stats.insert("shadow_maps_rendered".into(), 1);
                    fresh.shadow_map = Some((shadow_key.clone(), shadow_map.clone()));
                }
                shadow_map
            }
        };
        if centre_map {
            intermediates.push(Intermediate::depth("shadow_map", &shadow_map));
        }
        stats.insert("map_size".into(), settings.map_size as i64);
        let light = (scene.light.center, scene.light.radius);
        let pvm_frame;
        let pvmf_mask;
        let pvmf_estimate;
        let pvmf_counters;
        let pcss_frame;
        // The texture shading reads and visibility is read back from.
        let mut visibility_out = &visibility;
        // A method's atomic counters and the stats they fill, in order.
        let mut counters: Option<(&wgpu::Buffer, &[&str])> = None;
        match method {
            MethodConfig::Hard(params) => {
                profiler.pass("visibility", |encoder, ts| {
                    self.hard.record_visibility(
                        device, encoder, params, &gbuffer, &shadow_map, frustum, scene.light.center, &visibility, ts,
                    )
                })?;
            }
            MethodConfig::Pcf(params) => {
                profiler.pass("visibility", |encoder, ts| {
                    self.pcf.record_visibility(
                        device, encoder, params, &self.comparison_samplers, &gbuffer, &shadow_map, frustum, scene.light.center, &visibility, ts,
                    )
                })?;
            }
            MethodConfig::Pcss(params) => {
                let mut recorded = None;
                profiler.pass("visibility", |encoder, ts| {
                    recorded = Some(self.pcss.record_visibility(
                        device, encoder, params, &self.comparison_samplers, &gbuffer, &shadow_map, frustum, light, &visibility, ts,
                    ));
                })?;
                pcss_frame = recorded.expect("the pass ran");
                counters = Some((&pcss_frame.counters, crate::methods::pcss::COUNTER_NAMES));
                intermediates.push(Intermediate::color("pcss_penumbra_width", &pcss_frame.penumbra_width, 1));
                intermediates.push(Intermediate::color("pcss_blocker_depth", &pcss_frame.blocker_depth, 1));
            }
            MethodConfig::Reference(params) => {
                let l = glam::Vec3::from(light.0).as_dvec3();
                let mut used = Ok(0);
                profiler.pass("light_samples", |encoder, ts| {
                    used = self.reference.record(
                        device, encoder, &self.shadow_map, params, prepared, (l, light.1 as f64), (vertices(), vertex_count), &gbuffer, &visibility, ts,
                    );
                })?;
                let used = used?;
                stats.insert("light_samples".into(), used as i64);
                stats.insert("shadow_maps_rendered".into(), used as i64);
            }
            MethodConfig::Pvm(params) => {
                let l = glam::Vec3::from(light.0).as_dvec3();
                let mut key = PassKey::new(PassKind::PenumbraVolumes);
                key.bytes(&geometry);
                crate::methods::pvm::volumes_key(params, frustum, (l, light.1 as f64), &mut key);
                let (volumes, cache_hits) = match self.cache.penumbra_volumes.get(&key) {
                    Some(cached) => {
                        reused.push(PassKind::PenumbraVolumes);
                        (cached, 0)
                    }
                    None => {
                        let mut built = None;
                        profiler.pass("penumbra_volumes", |encoder, ts| {
                            built = Some(self.pvm.record_volumes(device, encoder, params, &self.silhouettes, prepared, frustum, (l, light.1 as f64), ts));
                        })?;
                        let (volumes, hits) = built.expect("the pass ran")?;
                        let volumes = Arc::new(volumes);
                        fresh.penumbra_volumes = Some((key.finish(), volumes.clone()));
                        (volumes, hits)
                    }
                };
                pvm_frame = {
                    let mut frame = PvmFrame::new(device, volumes, size);
                    if options.intermediates {
                        frame.edge_maps = Some(self.pvm.record_edge_maps(device, profiler.encoder(), &frame.volumes));
                    }
                    frame
                };
                profiler.pass("visibility", |encoder, ts| {
                    self.pvm.record_visibility(
                        device, encoder, params, &pvm_frame, &gbuffer, &shadow_map, frustum, light, &visibility, ts,
                    )
                })?;
                let s = &pvm_frame.volumes.stats;
                stats.insert("silhouette_edges".into(), s.silhouette_edges as i64);
                stats.insert("penumbra_volumes".into(), s.volume_quads as i64);
                stats.insert("silhouette_junction_vertices".into(), s.junction_vertices as i64);
                stats.insert("extrusions_outside_light_cone".into(), s.extrusions_outside_cone as i64);
                stats.insert("light_parallel_edges".into(), s.light_parallel_edges as i64);
                stats.insert("hidden_silhouette_edges".into(), s.hidden_edges as i64);
                stats.insert("silhouette_cache_hits".into(), cache_hits as i64);
                counters = Some((&pvm_frame.counter, &["pixels_in_volume"]));
                intermediates.push(Intermediate::depth("pvm_volume_depth", &pvm_frame.volumes.volume_depth));
                if let Some((edge0, edge1)) = &pvm_frame.edge_maps {
                    intermediates.push(Intermediate::color("pvm_edge0", edge0, 3));
                    intermediates.push(Intermediate::color("pvm_edge1", edge1, 3));
                }
                intermediates.push(Intermediate::color("pvm_in_volume", &pvm_frame.membership, 1));
            }
            MethodConfig::Pvmf(params) => {
                use crate::methods::pvmf;
                let r = light.1 as f64;
                let l = glam::Vec3::from(light.0).as_dvec3();
                let mut mask_key = PassKey::new(PassKind::Mask);
                mask_key.bytes(&geometry);
                pvmf::mask_key(params, frustum, (l, r), &mut mask_key);
                let mask_key = mask_key.finish();
                let mut cache_hits = 0;
                pvmf_mask = match self.cache.mask.get(&mask_key) {
                    Some(cached) => {
                        reused.push(PassKind::Mask);
                        cached
                    }
                    None => {
                        let mut built = None;
                        profiler.pass("mask", |encoder, ts| {
                            built = Some(self.pvmf.record_mask(device, encoder, params, &self.silhouettes, prepared, frustum, (l, r), ts));
                        })?;
                        let (mask, hits) = built.expect("the pass ran")?;
                        cache_hits = hits;
                        let mask = Arc::new(mask);
                        fresh.mask = Some((mask_key.clone(), mask.clone()));
                        mask
                    }
                };
                // The estimate reads the G-buffer, the shadow map and the mask (their
                // keys), and its own uniforms: everything but n_blur.
                let mut key = PassKey::new(PassKind::Estimation);
                key.key(&gbuffer_key).key(&shadow_key).key(&mask_key);
                pvmf::estimate_key(params, frustum, light, &mut key);
                let key = key.finish();
                pvmf_estimate = match self.cache.estimation.get(&key) {
                    Some(cached) => {
                        reused.push(PassKind::Estimation);
                        cached
                    }
                    None => {
                        let estimate = Arc::new(PvmfEstimate::new(device, size));
                        profiler.pass("estimation", |encoder, ts| {
                            self.pvmf.record_estimate(
                                device, encoder, params, &self.comparison_samplers, &pvmf_mask, &estimate, &gbuffer, &shadow_map, frustum, light, ts,
                            )
                        })?;
                        fresh.estimation = Some((key, estimate.clone()));
                        estimate
                    }
                };
                pvmf_counters = pvmf::frame_counters(device, profiler.encoder(), &pvmf_estimate);
                if pvmf::blurs(params, r) {
                    profiler.pass("blur", |encoder, ts| {
                        self.pvmf.record_blur(device, encoder, params, &pvmf_estimate, &pvmf_counters, &gbuffer, &visibility, ts)
                    })?;
                } else {
                    visibility_out = &pvmf_estimate.raw;
                }
                let s = &pvmf_mask.stats;
                stats.insert("silhouette_edges".into(), s.silhouette_edges as i64);
                stats.insert("mask_quads".into(), s.mask_quads as i64);
                stats.insert("light_parallel_edges".into(), s.light_parallel_edges as i64);
                stats.insert("hidden_silhouette_edges".into(), s.hidden_edges as i64);
                stats.insert("silhouette_cache_hits".into(), cache_hits as i64);
                counters = Some((&pvmf_counters, &pvmf::COUNTERS));
                intermediates.push(Intermediate::depth("pvmf_mask_depth", &pvmf_mask.mask_depth));
                intermediates.push(Intermediate::color("pvmf_edge_distance", &pvmf_mask.edge_distance, 1));
                intermediates.push(Intermediate::color("pvmf_visibility_raw", &pvmf_estimate.raw, 1));
                intermediates.push(Intermediate::color("pvmf_blur_mask", &pvmf_estimate.blur_mask, 1));
                intermediates.push(Intermediate::color("pvmf_filter_width", &pvmf_estimate.filter_width, 1));
            }
        }
        // What was reused: a count, and a flag for each cacheable pass this method has.
        let mut cacheable = vec![PassKind::GBuffer];
        match method {
            MethodConfig::Reference(_) => {}
            MethodConfig::Pvm(_) => cacheable.extend([PassKind::ShadowMap, PassKind::PenumbraVolumes]),
            MethodConfig::Pvmf(_) => cacheable.extend([PassKind::ShadowMap, PassKind::Mask, PassKind::Estimation]),
            _ => cacheable.push(PassKind::ShadowMap),
        }
        for kind in cacheable {
            stats.insert(format!("reused_{}", kind.name()), i64::from(reused.contains(&kind)));
        }
        stats.insert("reused_passes".into(), reused.len() as i64);
        profiler.pass("shading", |encoder, ts| {
            self.shading.record(
                device, encoder, &gbuffer, visibility_out, &radiance, scene, prepared, camera.eye, ts,
            )
        })?;
        let (timings, mut encoder) = profiler.finish()?;

        let readback_start = Instant::now();
        let all = wgpu::TextureAspect::All;
        let mut pending: Vec<PendingReadback> = vec![
            readback::copy_texture(device, &mut encoder, &radiance, all),
            readback::copy_texture(device, &mut encoder, visibility_out, all),
            readback::copy_texture(device, &mut encoder, &gbuffer.position, all),
            readback::copy_texture(device, &mut encoder, &gbuffer.normal, all),
        ];
        if !options.intermediates {
            intermediates.clear();
        }
        if let Some((buffer, names)) = counters {
            pending.push(readback::copy_buffer(device, &mut encoder, buffer, 4 * names.len() as u32));
        }
        for i in &intermediates {
            pending.push(readback::copy_texture(device, &mut encoder, i.texture, i.aspect));
        }
        self.ctx.queue.submit([encoder.finish()]);
        let mut bytes = readback::map_all(&self.ctx, &pending)?.into_iter();
        // Submitted and waited for: what ran may now be reused.
        fresh.store(&self.cache);
        let mut next = || readback::cast_vec::<f32>(bytes.next().unwrap_or_default());
        let (w, h) = (size.0 as usize, size.1 as usize);
        let rgba = next();
        let radiance: Vec<f32> = rgba.chunks_exact(4).flat_map(|t| [t[0], t[1], t[2]]).collect();
        let visibility = next();
        let position = next();
        let normal = next();
        let mut images = vec![
            Image { name: "radiance".into(), shape: vec![h, w, 3], data: ImageData::F32(radiance) },
            Image { name: "visibility".into(), shape: vec![h, w], data: ImageData::F32(visibility) },
            Image {
                name: "depth".into(),
                shape: vec![h, w],
                data: ImageData::F32(position.chunks_exact(4).map(|t| t[3]).collect()),
            },
            Image {
                name: "position".into(),
                shape: vec![h, w, 3],
                data: ImageData::F32(position.chunks_exact(4).flat_map(|t| [t[0], t[1], t[2]]).collect()),
            },
            Image {
                name: "normal".into(),
                shape: vec![h, w, 3],
                data: ImageData::F32(normal.chunks_exact(4).flat_map(|t| [t[0], t[1], t[2]]).collect()),
            },
        ];
        let object_id: Vec<i32> = normal
            .chunks_exact(4)
            .map(|t| if t[3] < 0.0 { -1 } else { prepared.materials.get(t[3] as usize).map_or(-1, |m| m.1) })
            .collect();
        stats.insert("geometry_pixels".into(), object_id.iter().filter(|&&i| i >= 0).count() as i64);
        images.push(Image { name: "object_id".into(), shape: vec![h, w], data: ImageData::I32(object_id) });
        if let Some((_, names)) = counters {
            let counts: Vec<u32> = readback::cast_vec(bytes.next().unwrap_or_default());
            for (i, name) in names.iter().enumerate() {
                stats.insert((*name).into(), counts.get(i).copied().unwrap_or(0) as i64);
            }
        }
        for i in &intermediates {
            let raw = readback::cast_vec::<f32>(bytes.next().unwrap_or_default());
            let (w, h) = (i.texture.width() as usize, i.texture.height() as usize);
            let stored = raw.len() / (w * h).max(1);
            let mut data: Vec<f32> = if stored == i.channels {
                raw
            } else {
                raw.chunks_exact(stored).flat_map(|t| t[..i.channels].to_vec()).collect()
            };
            if i.linear_depth {
                // Stored as depth / far: hand back world-unit light depth.
                data.iter_mut().for_each(|d| *d *= frustum.far);
            }
            let shape = if i.channels == 1 { vec![h, w] } else { vec![h, w, i.channels] };
            images.push(Image { name: i.name.into(), shape, data: ImageData::F32(data) });
        }
        let mut timings = timings;
        timings.passes.push(("readback".into(), readback_start.elapsed().as_secs_f64() * 1e3));
        Ok(RenderResult {
            method: method.name(),
            params: method.effective_params(),
            images,
            timings,
            total_ms: 0.0,
            stats,
        })
    }
}
