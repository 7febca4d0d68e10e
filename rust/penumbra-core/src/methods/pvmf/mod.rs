//! Method `pvmf`: penumbra volume mask filtering (Cournia chapter 5).
//!
//! Pass 1 is a depth shadow map from the light centre (5.5 uses a
//! second-depth map; the default here is `hard`'s `slope` bias, see
//! `PvmfParams::read`). Pass 2 builds, on the CPU, an overestimated penumbra
//! volume for every silhouette edge on its own (5.1) and renders them from
//! the light into the penumbra volume mask: depth plus d_e. Pass 3 estimates
//! visibility (5.2): pixels inside a volume, or failing the shadow-map test,
//! take a jittered n_pcf x n_pcf percentage-closer filter of width w_pcf;
//! the rest take no taps. Passes 4 and 5 blur the estimate separably over
//! texels of the same object, only where the blur mask says (5.3). The
//! shared shading composites (5.4).
//!
//! Options beyond the paper, each measured against it (README): `offsets =
//! "radius"` scales the paper's unit extrusion offsets by the light's radius
//! (the paper's volumes do not depend on r at all, so they miss penumbrae of
//! lights larger than one scene unit and waste work for small ones);
//! `kernel = "disk"` samples the disk the light projects to rather than a
//! square; `umbra = "skip"` gives pixels that fail the test outside every
//! volume v = 0 without filtering; `bias = "midpoint"` is the mid-point map
//! the paper names as future work.

use std::collections::BTreeMap;

use glam::DVec3;
use wgpu::util::DeviceExt;

use crate::error::{Error, Result};
use crate::gpu::{layout, PassTimestamps};
use crate::light_frustum::LightFrustum;
use crate::pass_cache::PassKey;
use crate::methods::hard::{ShadowMapSettings, ShadowTestUniform};
use crate::methods::pcf::{ComparisonSamplers, Filter};
use crate::silhouettes::{OpenEdges, Repairs, SceneSilhouette, SilhouetteCache};

pub mod geometry;
pub use geometry::{mask_volumes, MaskStats, MaskVertex, Offsets};
use crate::methods::{ParamReader, ParamValue};
use crate::passes::gbuffer::GBuffer;
use crate::passes::shading::{ShadingPass, VISIBILITY_FORMAT};
use crate::passes::volumes::VolumePass;
use crate::scene::PreparedScene;

/// The d_e channel of the mask.
pub const DISTANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;


#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kernel {
    /// The paper's n_pcf x n_pcf cells, w_pcf / n_pcf square.
    Square,
    /// The same stratified cells mapped onto the disk inscribed in that square.
    Disk,
}

#[derive(Debug, Clone, PartialEq)]
pub struct PvmfParams {
    pub shadow: ShadowMapSettings,
    /// Overestimation of the volumes, in (0, 1] (5.1).
    pub s_e: f64,
    /// Scale of the filter width (5.2). The paper gives no value; w_pcf is the
    /// radius of the light's projection into the map through the occluder,
    /// so 2 makes the kernel span its diameter (the default).
    pub s_p: f64,
    /// Filter taps per axis (5.2).
    pub n_pcf: u32,
    /// Blur taps per axis beyond the centre (5.3); 0 leaves the raw estimate.
    pub n_blur: u32,
    /// Fixes the filter's jitter.
    pub seed: u64,
    /// Hardware 2x2 bilinear comparison per tap (5.5), or the nearest texel.
    pub filter: Filter,
    pub offsets: Offsets,
    pub kernel: Kernel,
    /// Filter pixels that fail the shadow-map test outside every volume (5.2).
    pub filter_umbra: bool,
    pub open_edges: OpenEdges,
    /// Departures from the paper for real meshes (`Repairs`: `hidden`, `horizon` and `distance` apply).
    pub repairs: Repairs,
}

/// The values of `repairs`: cumulative, in the order docs/real_meshes.md
/// measures them; "all" (the default) adds the local edge distance to the last.
pub const REPAIR_LEVELS: [&str; 4] = ["all", "none", "hidden", "hidden+horizon"];

impl PvmfParams {
    pub fn read(r: &mut ParamReader<'_>) -> Result<Self> {
        // Departure from 5.5 (second-depth maps): `slope`, the default of
        // `hard`. A closed caster thinner than the depth a texel spans along
        // its slope shadowed its own lit face in the second-depth map (a plate
        // 1e-4 thick: visibility 0.57-0.75 on its top, issue 22), and an open
        // surface facing the light is culled from it and casts no shadow (the
        // open bunny: penumbra RMSE 0.107 against 0.079). On the closed real
        // meshes the two are equal to 0.01 (docs/real_meshes.md); a minimum
        // separation added to `second_depth` instead let light leak where a
        // caster meets the ground (0.067 against 0.027 on the cube).
        let shadow = ShadowMapSettings::read_with_bias(r, "slope")?;
        let s_e = r.float("s_e", 0.5, 0.0, 1.0)?;
        if s_e <= 0.0 {
            return Err(Error::InvalidParameter(format!("parameter 's_e' of method 'pvmf' must be in (0, 1], got {s_e}")));
        }
        Ok(Self {
            shadow,
            s_e,
            s_p: r.float("s_p", 2.0, 0.0, 100.0)?,
            n_pcf: r.int("n_pcf", 7, 1, 32)? as u32,
            n_blur: r.int("n_blur", 12, 0, 64)? as u32,
            seed: r.int("seed", 0, 0, u32::MAX as i64)? as u64,
            filter: Filter::read(r)?,
            offsets: match r.choice("offsets", "unit", &["unit", "radius"])? {
                "radius" => Offsets::Radius,
                _ => Offsets::Unit,
            },
            kernel: match r.choice("kernel", "square", &["square", "disk"])? {
                "disk" => Kernel::Disk,
                _ => Kernel::Square,
            },
            filter_umbra: r.choice("umbra", "filter", &["filter", "skip"])? == "filter",
            open_edges: OpenEdges::parse(r.choice("open_edges", "silhouette", &OpenEdges::NAMES)?),
            repairs: Repairs::parse(r.choice("repairs", "all", &REPAIR_LEVELS)?),
        })
    }

    pub fn effective(&self) -> BTreeMap<String, ParamValue> {
        let mut out = self.shadow.effective();
        let s = |v: &str| ParamValue::Str(v.into());
        out.insert("s_e".into(), ParamValue::Float(self.s_e));
        out.insert("s_p".into(), ParamValue::Float(self.s_p));
        out.insert("n_pcf".into(), ParamValue::Int(self.n_pcf as i64));
        out.insert("n_blur".into(), ParamValue::Int(self.n_blur as i64));
        out.insert("seed".into(), ParamValue::Int(self.seed as i64));
        out.insert("filter".into(), s(self.filter.name()));
        out.insert("offsets".into(), s(if self.offsets == Offsets::Unit { "unit" } else { "radius" }));
        out.insert("kernel".into(), s(if self.kernel == Kernel::Square { "square" } else { "disk" }));
        out.insert("umbra".into(), s(if self.filter_umbra { "filter" } else { "skip" }));
        out.insert("open_edges".into(), s(self.open_edges.name()));
        out.insert("repairs".into(), s(REPAIR_LEVELS.iter().copied().find(|&n| Repairs::parse(n) == self.repairs).unwrap_or("all")));
        out
    }
}


/// Uniform layout of `PvmfSettings` in pvmf/estimate.wgsl.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct SettingsUniform {
    s_p: f32,
    n_pcf: u32,
    seed: u32,
    flags: u32,
}

/// Uniform layout of `BlurSettings` in pvmf/blur.wgsl.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BlurUniform {
    step: [i32; 2],
    half_width: i32,
    count: u32,
}

/// Named counters, in the order of pvmf/estimate.wgsl's `counters`.
pub const COUNTERS: [&str; 3] = ["masked_pixels", "filtered_pixels", "blurred_pixels"];

pub struct PenumbraVolumeMaskFiltering {
    mask_pass: VolumePass,
    estimate_pipeline: wgpu::ComputePipeline,
    estimate_layout: wgpu::BindGroupLayout,
    blur_pipeline: wgpu::ComputePipeline,
    blur_layout: wgpu::BindGroupLayout,
}

/// The penumbra volume mask (pass 2), as the renderer's pass cache keeps it.
pub struct PvmfMask {
    pub mask_depth: wgpu::Texture,
    pub edge_distance: wgpu::Texture,
    pub stats: MaskStats,
}

/// The visibility estimate (pass 3) with what it writes besides, as the
/// renderer's pass cache keeps it: the blur passes read it and write only
/// the frame's visibility and the `blurred_pixels` counter.
pub struct PvmfEstimate {
    /// The raw estimate (the frame's visibility when nothing is blurred).
    pub raw: wgpu::Texture,
    pub blur_mask: wgpu::Texture,
    pub filter_width: wgpu::Texture,
    /// `COUNTERS` as the estimate left them (`blurred_pixels` still 0).
    pub counters: wgpu::Buffer,
}

impl PvmfEstimate {
    pub fn new(device: &wgpu::Device, size: (u32, u32)) -> Self {
        Self {
            raw: ShadingPass::create_visibility(device, size),
            blur_mask: ShadingPass::create_visibility(device, size),
            filter_width: ShadingPass::create_visibility(device, size),
            counters: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("pvmf::estimate_counters"),
                contents: &[0u8; 4 * COUNTERS.len()],
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            }),
        }
    }
}

/// Whether passes 4 and 5 run: not for n_blur = 0, nor for a point light
/// (nothing is masked, so nothing would be blurred).
pub fn blurs(params: &PvmfParams, radius: f64) -> bool {
    params.n_blur > 0 && radius > 0.0
}

/// This frame's counters: the estimate's, to which the blur adds its own.
pub fn frame_counters(device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, estimate: &PvmfEstimate) -> wgpu::Buffer {
    let size = 4 * COUNTERS.len() as u64;
    let counters = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("pvmf::counters"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_buffer_to_buffer(&estimate.counters, 0, &counters, 0, size);
    counters
}

/// What pass 2 reads besides the geometry: the light, the frustum, the map
/// size and the volume parameters (appended to the pass-cache key).
pub fn mask_key(params: &PvmfParams, frustum: &LightFrustum, (l, r): (DVec3, f64), key: &mut PassKey) {
    let offsets = if params.offsets == Offsets::Unit { "unit" } else { "radius" };
    key.f64s(&l.to_array())
        .f64s(&[r, params.s_e])
        .bytes(offsets.as_bytes())
        .bytes(params.open_edges.name().as_bytes())
        .bytes(&[u8::from(params.repairs.hidden), u8::from(params.repairs.distance)])
        .frustum(frustum)
        .u32(params.shadow.map_size);
}

/// The uniform blocks of pass 3.
fn estimate_uniforms(params: &PvmfParams, frustum: &LightFrustum, light: ([f32; 3], f32)) -> (ShadowTestUniform, SettingsUniform) {
    let test = params.shadow.uniform(frustum, light.0, light.1, 0);
    let flags = u32::from(params.kernel == Kernel::Disk) | (u32::from(!params.filter_umbra) << 1) | (u32::from(params.repairs.horizon) << 2);
    let settings = SettingsUniform { s_p: params.s_p as f32, n_pcf: params.n_pcf, seed: params.seed as u32, flags };
    (test, settings)
}

/// What pass 3 reads besides the G-buffer, the shadow map and the mask: its
/// uniform blocks, bit for bit, and the comparison sampler.
pub fn estimate_key(params: &PvmfParams, frustum: &LightFrustum, light: ([f32; 3], f32), key: &mut PassKey) {
    let (test, settings) = estimate_uniforms(params, frustum, light);
    key.pod(&test).pod(&settings).bytes(params.filter.name().as_bytes());
}

impl PenumbraVolumeMaskFiltering {
    pub fn new(device: &wgpu::Device) -> Self {
        let mask_pass = VolumePass::new::<MaskVertex>(
            device,
            "pvmf::mask_pass",
            crate::shaders::pvmf_mask(),
            ("vs_mask", "fs_mask"),
            &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32, 2 => Float32],
            &[DISTANCE_FORMAT],
        );
        let estimate_layout = layout::bind_group_layout(
            device,
            "pvmf::estimate_layout",
            &[
                layout::float_texture(0),
                layout::float_texture(1),
                layout::depth_texture(2),
                layout::depth_texture(3),
                layout::float_texture(4),
                layout::comparison_sampler(5),
                layout::parameters(6),
                layout::parameters(7),
                layout::storage_texture(8, VISIBILITY_FORMAT),
                layout::storage_texture(9, VISIBILITY_FORMAT),
                layout::storage_texture(10, VISIBILITY_FORMAT),
                layout::storage_buffer_rw(11),
            ],
        );
        let estimate_pipeline = layout::compute_pipeline(device, "pvmf::estimate_pipeline", crate::shaders::pvmf(), &estimate_layout);
        let blur_layout = layout::bind_group_layout(
            device,
            "pvmf::blur_layout",
            &[
                layout::float_texture(0),
                layout::float_texture(1),
                layout::float_texture(2),
                layout::parameters(3),
                layout::storage_texture(4, VISIBILITY_FORMAT),
                layout::storage_buffer_rw(5),
            ],
        );
        let blur_pipeline = layout::compute_pipeline(device, "pvmf::blur_pipeline", crate::shaders::pvmf_blur(), &blur_layout);
        Self {
            mask_pass,
            estimate_pipeline,
            estimate_layout,
            blur_pipeline,
            blur_layout,
        }
    }

    /// Pass 2: builds and renders the penumbra volume mask (5.1).
    #[allow(clippy::too_many_arguments)]
    pub fn record_mask(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        params: &PvmfParams,
        silhouettes: &SilhouetteCache,
        scene: &PreparedScene,
        frustum: &LightFrustum,
        (l, r): (DVec3, f64),
        timestamps: Option<PassTimestamps<'_>>,
    ) -> Result<(PvmfMask, usize)> {
        let map = params.shadow.map_size;
        let (mut stats, mut cache_hits, mut vertices) = (MaskStats::default(), 0, Vec::new());
        // A point light has no penumbra: no volumes, and nothing is filtered.
        if r > 0.0 {
            let silhouette = if params.repairs.hidden {
                silhouettes.seen_from_light(scene, l, params.open_edges)?
            } else {
                let (edges, cache_hits) = silhouettes.edges(scene, l, params.open_edges)?;
                SceneSilhouette { edges, cache_hits, hidden_edges: 0 }
            };
            cache_hits = silhouette.cache_hits;
            // Beyond the far plane from any moved point (they lie between l and the edges).
            let reach = 4.0 * frustum.far as f64 + 4.0 * r;
            (vertices, stats) = mask_volumes(&silhouette.edges, l, r, params.s_e, params.offsets, reach, params.repairs.distance);
            stats.hidden_edges = silhouette.hidden_edges;
            stats.silhouette_edges += silhouette.hidden_edges;
        }
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
        // d_e = 0 (the clear value) marks texels without a volume.
        let edge_distance = layout::create_texture(device, "pvmf::edge_distance", (map, map), DISTANCE_FORMAT, usage);
        // The moved points lie between the light and the edges, nearer than
        // the scene's near plane: clip only what is (almost) at the light.
        let mask_frustum = frustum.with_near(frustum.far * 1e-4);
        let mask_depth = self.mask_pass.record(device, encoder, &mask_frustum, &vertices, map, &[&edge_distance], timestamps)?;
        Ok((PvmfMask { mask_depth, edge_distance, stats }, cache_hits))
    }

    /// Pass 3: the visibility estimate (5.2), into `estimate.raw`, with the
    /// blur mask and filter widths beside it.
    #[allow(clippy::too_many_arguments)]
    pub fn record_estimate(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        params: &PvmfParams,
        samplers: &ComparisonSamplers,
        mask: &PvmfMask,
        estimate: &PvmfEstimate,
        gbuffer: &GBuffer,
        shadow_map: &wgpu::Texture,
        frustum: &LightFrustum,
        light: ([f32; 3], f32),
        timestamps: Option<PassTimestamps<'_>>,
    ) {
        let size = gbuffer.size;
        let (test, settings) = estimate_uniforms(params, frustum, light);
        let test = layout::parameter_buffer(device, "pvmf::test_uniforms", &test);
        let settings = layout::parameter_buffer(device, "pvmf::settings", &settings);
        let e = estimate;
        let views = [shadow_map, &mask.mask_depth, &mask.edge_distance, &e.raw, &e.blur_mask, &e.filter_width].map(layout::view);
        let bind_group = layout::bind_group(
            device,
            "pvmf::estimate_bind_group",
            &self.estimate_layout,
            &[
                wgpu::BindingResource::TextureView(&gbuffer.position_view),
                wgpu::BindingResource::TextureView(&gbuffer.normal_view),
                wgpu::BindingResource::TextureView(&views[0]),
                wgpu::BindingResource::TextureView(&views[1]),
                wgpu::BindingResource::TextureView(&views[2]),
                wgpu::BindingResource::Sampler(samplers.get(params.filter)),
                test.as_entire_binding(),
                settings.as_entire_binding(),
                wgpu::BindingResource::TextureView(&views[3]),
                wgpu::BindingResource::TextureView(&views[4]),
                wgpu::BindingResource::TextureView(&views[5]),
                e.counters.as_entire_binding(),
            ],
        );
        layout::dispatch_per_pixel(encoder, "pvmf::estimate_pass", &self.estimate_pipeline, &bind_group, size, timestamps);
    }

    /// Passes 4 and 5: the separable, object-aware blur (5.3) of the
    /// estimate, horizontal into a temporary buffer, then vertical into
    /// `visibility`; `counters` are this frame's (see [`frame_counters`]).
    #[allow(clippy::too_many_arguments)]
    pub fn record_blur(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        params: &PvmfParams,
        estimate: &PvmfEstimate,
        counters: &wgpu::Buffer,
        gbuffer: &GBuffer,
        visibility: &wgpu::Texture,
        timestamps: Option<PassTimestamps<'_>>,
    ) {
        let raw = &estimate.raw;
        let temporary = ShadingPass::create_visibility(device, gbuffer.size);
        let half_width = (params.n_blur / 2) as i32;
        let steps = [(raw, &temporary, [1, 0], true), (&temporary, visibility, [0, 1], false)];
        for (source, destination, step, first) in steps {
            let uniforms = layout::parameter_buffer(device, "pvmf::blur_uniforms", &BlurUniform { step, half_width, count: u32::from(first) });
            let views = [source, &estimate.blur_mask, destination].map(layout::view);
            let bind_group = layout::bind_group(
                device,
                "pvmf::blur_bind_group",
                &self.blur_layout,
                &[
                    wgpu::BindingResource::TextureView(&gbuffer.normal_view),
                    wgpu::BindingResource::TextureView(&views[0]),
                    wgpu::BindingResource::TextureView(&views[1]),
                    uniforms.as_entire_binding(),
                    wgpu::BindingResource::TextureView(&views[2]),
                    counters.as_entire_binding(),
                ],
            );
            let writes = timestamps.and_then(|t| t.compute_part(first, !first));
            layout::dispatch_per_pixel_writes(encoder, "pvmf::blur_pass", &self.blur_pipeline, &bind_group, gbuffer.size, writes);
        }
    }
}


