//! The long-lived renderer: owns the device and every pipeline (built once),
//! and serves renders of any scene with any method.

use std::collections::BTreeMap;
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
use crate::methods::pvm::PenumbraVolumeMaps;
use crate::methods::pvmf::PenumbraVolumeMaskFiltering;
use crate::methods::reference::ReferenceShadows;
use crate::methods::silhouettes::SilhouetteCache;
use crate::methods::{MethodConfig, ParamValue};
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
}

impl Renderer {
    /// Creates the device and builds every pipeline. `use_timestamps` asks for
    /// GPU timestamps; they are used only where the adapter has them.
    pub fn new(use_timestamps: bool) -> Result<Self> {
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
        Ok(Self { ctx, use_timestamps, gbuffer, shadow_map, shading, hard, comparison_samplers, pcf, pcss, pvm, reference, pvmf, silhouettes })
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
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("renderer::corners"),
            contents: bytemuck::cast_slice(&prepared.corners),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let gbuffer = GBuffer::new(device, size);
        let visibility = ShadingPass::create_visibility(device, size);
        let radiance = crate::gpu::layout::create_texture(
            device,
            "renderer::radiance",
            size,
            RADIANCE_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
        );
        let (projection, _, _) = camera.projection(prepared.bounds_min, prepared.bounds_max);
        let mut profiler = Profiler::new(&self.ctx, self.use_timestamps);
        profiler.pass("gbuffer", |encoder, ts| {
            self.gbuffer.record(device, encoder, &gbuffer, &vertices, vertex_count, camera.view(), projection, ts)
        })?;
        let mut stats = BTreeMap::from([
            ("triangles".to_owned(), prepared.triangle_count as i64),
            ("degenerate_triangles".to_owned(), prepared.degenerate_triangles as i64),
        ]);
        let mut intermediates: Vec<Intermediate<'_>> = Vec::new();
        // Pass 1 of every method but `reference`: the shadow map from the light centre.
        let settings = method.shadow_map();
        let centre_map = !matches!(method, MethodConfig::Reference(_));
        let shadow_map = ShadowMapPass::create_map(device, if centre_map { settings.map_size } else { 1 });
        if centre_map {
            profiler.pass("shadow_map", |encoder, ts| {
                self.shadow_map.record(device, encoder, &shadow_map, frustum, settings.bias.map_depth(), &vertices, vertex_count, ts)
            })?;
            stats.insert("shadow_maps_rendered".into(), 1);
            intermediates.push(Intermediate::depth("shadow_map", &shadow_map));
        }
        stats.insert("map_size".into(), settings.map_size as i64);
        let light = (scene.light.center, scene.light.radius);
        let pvm_frame;
        let pvmf_frame;
        let pcss_frame;
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
                        device, encoder, &self.shadow_map, params, prepared, (l, light.1 as f64), (&vertices, vertex_count), &gbuffer, &visibility, ts,
                    );
                })?;
                let used = used?;
                stats.insert("light_samples".into(), used as i64);
                stats.insert("shadow_maps_rendered".into(), used as i64);
            }
            MethodConfig::Pvm(params) => {
                let l = glam::Vec3::from(light.0).as_dvec3();
                let mut built = None;
                profiler.pass("penumbra_volumes", |encoder, ts| {
                    built = Some(self.pvm.record_volumes(device, encoder, params, &self.silhouettes, prepared, frustum, (l, light.1 as f64), size, ts));
                })?;
                pvm_frame = built.expect("the pass ran")?;
                profiler.pass("visibility", |encoder, ts| {
                    self.pvm.record_visibility(
                        device, encoder, params, &pvm_frame, &gbuffer, &shadow_map, frustum, light, &visibility, ts,
                    )
                })?;
                let s = &pvm_frame.stats;
                stats.insert("silhouette_edges".into(), s.silhouette_edges as i64);
                stats.insert("penumbra_volumes".into(), s.volume_quads as i64);
                stats.insert("silhouette_junction_vertices".into(), s.junction_vertices as i64);
                stats.insert("light_parallel_edges".into(), s.light_parallel_edges as i64);
                stats.insert("silhouette_cache_hits".into(), pvm_frame.cache_hits as i64);
                counters = Some((&pvm_frame.counter, &["pixels_in_volume"]));
                intermediates.push(Intermediate::depth("pvm_volume_depth", &pvm_frame.volume_depth));
                intermediates.push(Intermediate::color("pvm_edge0", &pvm_frame.edge0, 3));
                intermediates.push(Intermediate::color("pvm_edge1", &pvm_frame.edge1, 3));
                intermediates.push(Intermediate::color("pvm_in_volume", &pvm_frame.membership, 1));
            }
            MethodConfig::Pvmf(params) => {
                let l = glam::Vec3::from(light.0).as_dvec3();
                let mut built = None;
                profiler.pass("mask", |encoder, ts| {
                    built = Some(self.pvmf.record_mask(
                        device, encoder, params, &self.silhouettes, prepared, frustum, (l, light.1 as f64), size, ts,
                    ));
                })?;
                pvmf_frame = built.expect("the pass ran")?;
                profiler.pass("estimation", |encoder, ts| {
                    self.pvmf.record_estimate(
                        device, encoder, params, &self.comparison_samplers, &pvmf_frame, &gbuffer, &shadow_map, frustum, light, &visibility, ts,
                    )
                })?;
                if pvmf_frame.raw.is_some() {
                    profiler.pass("blur", |encoder, ts| {
                        self.pvmf.record_blur(device, encoder, params, &pvmf_frame, &gbuffer, &visibility, ts)
                    })?;
                }
                let s = &pvmf_frame.stats;
                stats.insert("silhouette_edges".into(), s.silhouette_edges as i64);
                stats.insert("mask_quads".into(), s.mask_quads as i64);
                stats.insert("light_parallel_edges".into(), s.light_parallel_edges as i64);
                stats.insert("silhouette_cache_hits".into(), pvmf_frame.cache_hits as i64);
                counters = Some((&pvmf_frame.counters, &crate::methods::pvmf::COUNTERS));
                intermediates.push(Intermediate::depth("pvmf_mask_depth", &pvmf_frame.mask_depth));
                intermediates.push(Intermediate::color("pvmf_edge_distance", &pvmf_frame.edge_distance, 1));
                intermediates.push(Intermediate::color(
                    "pvmf_visibility_raw",
                    pvmf_frame.raw.as_ref().unwrap_or(&visibility),
                    1,
                ));
                intermediates.push(Intermediate::color("pvmf_blur_mask", &pvmf_frame.blur_mask, 1));
                intermediates.push(Intermediate::color("pvmf_filter_width", &pvmf_frame.filter_width, 1));
            }
        }
        profiler.pass("shading", |encoder, ts| {
            self.shading.record(
                device, encoder, &gbuffer, &visibility, &radiance, scene, prepared, camera.eye, ts,
            )
        })?;
        let (timings, mut encoder) = profiler.finish()?;

        let readback_start = Instant::now();
        let all = wgpu::TextureAspect::All;
        let mut pending: Vec<PendingReadback> = vec![
            readback::copy_texture(device, &mut encoder, &radiance, all),
            readback::copy_texture(device, &mut encoder, &visibility, all),
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
