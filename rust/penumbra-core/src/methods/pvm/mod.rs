//! Method `pvm`: penumbra volume maps (Cournia chapter 4).
//!
//! Pass 1 is the shadow map of `hard`. Pass 2 builds, on the CPU, the
//! penumbra volumes of every silhouette edge (4.1.1, 4.1.2) and renders their
//! quadrilaterals from the light into the penumbra volume map (4.1.3). Pass 3
//! estimates visibility per camera pixel (4.2, listing 4.2).
//!
//! Silhouettes are found with respect to the light centre. Each silhouette
//! edge is oriented so that its hard-shadow plane normal points away from the
//! occluder; consecutive edges then form loops. The paper's structure assumes
//! two silhouette edges per silhouette vertex; at a vertex with any other
//! number (possible on non-convex meshes, and at the ends of open boundaries)
//! the edges meeting there are not paired, and each is extruded along its own
//! plane, as the paper's coincident-plane rule does. The volumes then meet
//! in a sliver rather than a shared extrusion vector: never NaN, at most a
//! thin gap where the shadow-map test takes over. `stats` counts such vertices.

use std::collections::BTreeMap;

use glam::DVec3;
use wgpu::util::DeviceExt;

use crate::error::Result;
use crate::gpu::{layout, PassTimestamps};
use crate::light_frustum::LightFrustum;
use crate::methods::hard::ShadowMapSettings;
use crate::methods::{ParamReader, ParamValue};
use crate::passes::gbuffer::GBuffer;
use crate::passes::shading::VISIBILITY_FORMAT;
use crate::passes::volumes::VolumePass;
use crate::scene::PreparedScene;
use crate::pass_cache::PassKey;
pub use crate::silhouettes::{silhouette, OpenEdges, Repairs, SilhouetteCache, SilhouetteEdge};

pub mod geometry;
pub use geometry::{penumbra_volumes, EdgePoints, VolumeGeometry, VolumeStats, VolumeVertex};

/// The penumbra volume edge map: the index + 1 of the edge whose volume is
/// nearest the light (0: none); pvm/volumes.wgsl says why not the paper's points.
pub const EDGE_INDEX_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// The `pvm_edge0` / `pvm_edge1` intermediates: the paper's edge maps.
pub const EDGE_POINT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

#[derive(Debug, Clone, PartialEq)]
pub struct PvmParams {
    pub shadow: ShadowMapSettings,
    /// The 3k^2 - 2k^3 interpolant of 4.2.
    pub falloff: bool,
    pub open_edges: OpenEdges,
    /// Departures from the paper for real meshes (`Repairs`).
    pub repairs: Repairs,
}

/// The values of `repairs`: cumulative, in the order docs/real_meshes.md
/// measures them; "all" (the default) adds the horizon to the last.
pub const REPAIR_LEVELS: [&str; 5] = ["all", "none", "cone", "cone+hidden", "cone+hidden+centre"];

impl PvmParams {
    pub fn read(r: &mut ParamReader<'_>) -> Result<Self> {
        Ok(Self {
            shadow: ShadowMapSettings::read(r)?,
            falloff: r.bool("falloff", true)?,
            open_edges: OpenEdges::parse(r.choice("open_edges", "silhouette", &OpenEdges::NAMES)?),
            repairs: Repairs::parse(r.choice("repairs", "all", &REPAIR_LEVELS)?),
        })
    }

    pub fn effective(&self) -> BTreeMap<String, ParamValue> {
        let mut out = self.shadow.effective();
        out.insert("falloff".into(), ParamValue::Bool(self.falloff));
        out.insert("open_edges".into(), ParamValue::Str(self.open_edges.name().into()));
        out.insert("repairs".into(), ParamValue::Str(self.repairs_name().into()));
        out
    }

    fn repairs_name(&self) -> &'static str {
        REPAIR_LEVELS.iter().copied().find(|&n| Repairs::parse(n) == self.repairs).unwrap_or("all")
    }
}

pub struct PenumbraVolumeMaps {
    volume_pass: VolumePass,
    visibility_pipeline: wgpu::ComputePipeline,
    visibility_layout: wgpu::BindGroupLayout,
    edge_maps_pipeline: wgpu::ComputePipeline,
    edge_maps_layout: wgpu::BindGroupLayout,
}

/// The penumbra volume map (pass 2): what the renderer's pass cache keeps.
pub struct PvmVolumes {
    pub volume_depth: wgpu::Texture,
    /// Per texel, the index + 1 into `edges` of the volume nearest the light (0: none).
    pub edge_index: wgpu::Texture,
    /// The silhouette edges' end points ([`EdgePoints`]; one zeroed entry when there is none).
    pub edges: wgpu::Buffer,
    pub stats: VolumeStats,
}

/// What one PVM render produced besides visibility: the volume map (built
/// now or reused), this frame's membership image and counter, and, when
/// intermediates are asked for, the paper's two edge maps.
pub struct PvmFrame {
    pub volumes: std::sync::Arc<PvmVolumes>,
    pub membership: wgpu::Texture,
    pub counter: wgpu::Buffer,
    /// `pvm_edge0` and `pvm_edge1` ([`PenumbraVolumeMaps::record_edge_maps`]).
    pub edge_maps: Option<(wgpu::Texture, wgpu::Texture)>,
}

/// What pass 2 reads besides the geometry: the light, the frustum, the map
/// size, `open_edges` and the geometric repairs (appended to the pass-cache key).
pub fn volumes_key(params: &PvmParams, frustum: &LightFrustum, (l, r): (DVec3, f64), key: &mut PassKey) {
    key.f64s(&l.to_array())
        .f64s(&[r])
        .bytes(params.open_edges.name().as_bytes())
        .bytes(&[u8::from(params.repairs.cone), u8::from(params.repairs.hidden)])
        .frustum(frustum)
        .u32(params.shadow.map_size);
}

impl PvmFrame {
    pub fn new(device: &wgpu::Device, volumes: std::sync::Arc<PvmVolumes>, size: (u32, u32)) -> Self {
        let membership = crate::passes::shading::ShadingPass::create_visibility(device, size);
        let counter = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("pvm::pixels_in_volume"),
            contents: &[0u8; 4],
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
        Self { volumes, membership, counter, edge_maps: None }
    }
}


impl PenumbraVolumeMaps {
    pub fn new(device: &wgpu::Device) -> Self {
        let volume_pass = VolumePass::new::<VolumeVertex>(
            device,
            "pvm::volume_pass",
            crate::shaders::pvm_volumes(),
            ("vs_main", "fs_main"),
            &wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32],
            &[EDGE_INDEX_FORMAT],
        );
        let visibility_layout = layout::bind_group_layout(
            device,
            "pvm::visibility_layout",
            &[
                layout::float_texture(0),
                layout::float_texture(1),
                layout::depth_texture(2),
                layout::depth_texture(3),
                layout::texture(4, wgpu::TextureSampleType::Uint),
                layout::parameters(5),
                layout::parameters(6),
                layout::storage_texture(7, VISIBILITY_FORMAT),
                layout::storage_texture(8, VISIBILITY_FORMAT),
                layout::storage_buffer_rw(9),
            ],
        );
        let visibility_pipeline = layout::compute_pipeline(device, "pvm::visibility_pipeline", crate::shaders::pvm(), &visibility_layout);
        let edge_maps_layout = layout::bind_group_layout(
            device,
            "pvm::edge_maps_layout",
            &[
                layout::texture(0, wgpu::TextureSampleType::Uint),
                layout::parameters(1),
                layout::storage_texture(2, EDGE_POINT_FORMAT),
                layout::storage_texture(3, EDGE_POINT_FORMAT),
            ],
        );
        let edge_maps_pipeline = layout::compute_pipeline(device, "pvm::edge_maps_pipeline", crate::shaders::pvm_edge_maps(), &edge_maps_layout);
        Self {
            volume_pass,
            visibility_pipeline,
            visibility_layout,
            edge_maps_pipeline,
            edge_maps_layout,
        }
    }

    /// Pass 2: builds and renders the penumbra volume map; also returns the
    /// silhouette cache hits. It reads the geometry, the frustum, the light,
    /// `map_size` and `open_edges` (the renderer's pass-cache key).
    #[allow(clippy::too_many_arguments)]
    pub fn record_volumes(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        params: &PvmParams,
        silhouettes: &SilhouetteCache,
        scene: &PreparedScene,
        frustum: &LightFrustum,
        light: (DVec3, f64),
        timestamps: Option<PassTimestamps<'_>>,
    ) -> Result<(PvmVolumes, usize)> {
        let (l, r) = light;
        let map = params.shadow.map_size;
        let (mut cache_hits, mut geometry) = (0, VolumeGeometry::default());
        // A point light has no penumbra: skip the volumes entirely.
        if r > 0.0 {
            let silhouette = if params.repairs.hidden {
                silhouettes.seen_from_light(scene, l, params.open_edges)?
            } else {
                let (edges, cache_hits) = silhouettes.edges(scene, l, params.open_edges)?;
                crate::silhouettes::SceneSilhouette { edges, cache_hits, hidden_edges: 0 }
            };
            cache_hits = silhouette.cache_hits;
            let reach = 4.0 * frustum.far as f64 + 4.0 * r;
            geometry = penumbra_volumes(&silhouette.edges, l, r, reach, params.repairs.cone);
            geometry.stats.hidden_edges = silhouette.hidden_edges;
            geometry.stats.silhouette_edges += silhouette.hidden_edges;
        }
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let edge_index = layout::create_texture(device, "pvm::edge_index_map", (map, map), EDGE_INDEX_FORMAT, usage);
        // A storage binding may not be empty: one zeroed entry stands for no edges.
        let points = if geometry.edges.is_empty() { vec![EdgePoints { h0: [0.0; 4], h1: [0.0; 4] }] } else { geometry.edges };
        let edges = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("pvm::edges"),
            contents: bytemuck::cast_slice(&points),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let volume_depth = self.volume_pass.record(device, encoder, frustum, &geometry.vertices, map, &[&edge_index], timestamps)?;
        Ok((PvmVolumes { volume_depth, edge_index, edges, stats: geometry.stats }, cache_hits))
    }

    /// The paper's two edge maps (4.1.3) rebuilt from the edge-index map,
    /// for the `pvm_edge0` and `pvm_edge1` intermediates.
    pub fn record_edge_maps(&self, device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, volumes: &PvmVolumes) -> (wgpu::Texture, wgpu::Texture) {
        let size = volumes.edge_index.size();
        let usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC;
        let edge0 = layout::create_texture(device, "pvm::edge0_map", (size.width, size.height), EDGE_POINT_FORMAT, usage);
        let edge1 = layout::create_texture(device, "pvm::edge1_map", (size.width, size.height), EDGE_POINT_FORMAT, usage);
        let views = [&volumes.edge_index, &edge0, &edge1].map(layout::view);
        let bind_group = layout::bind_group(
            device,
            "pvm::edge_maps_bind_group",
            &self.edge_maps_layout,
            &[
                wgpu::BindingResource::TextureView(&views[0]),
                volumes.edges.as_entire_binding(),
                wgpu::BindingResource::TextureView(&views[1]),
                wgpu::BindingResource::TextureView(&views[2]),
            ],
        );
        layout::dispatch_per_pixel(encoder, "pvm::edge_maps_pass", &self.edge_maps_pipeline, &bind_group, (size.width, size.height), None);
        (edge0, edge1)
    }

    /// Pass 3: visibility per camera pixel.
    #[allow(clippy::too_many_arguments)]
    pub fn record_visibility(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        params: &PvmParams,
        frame: &PvmFrame,
        gbuffer: &GBuffer,
        shadow_map: &wgpu::Texture,
        frustum: &LightFrustum,
        light: ([f32; 3], f32),
        visibility: &wgpu::Texture,
        timestamps: Option<PassTimestamps<'_>>,
    ) {
        let flags = u32::from(params.falloff) | (u32::from(params.repairs.centre) << 1) | (u32::from(params.repairs.horizon) << 2);
        let uniforms = layout::parameter_buffer(device, "pvm::visibility_uniforms", &params.shadow.uniform(frustum, light.0, light.1, flags));
        let v = &frame.volumes;
        let views = [shadow_map, &v.volume_depth, &v.edge_index, visibility, &frame.membership].map(layout::view);
        let bind_group = layout::bind_group(
            device,
            "pvm::visibility_bind_group",
            &self.visibility_layout,
            &[
                wgpu::BindingResource::TextureView(&gbuffer.position_view),
                wgpu::BindingResource::TextureView(&gbuffer.normal_view),
                wgpu::BindingResource::TextureView(&views[0]),
                wgpu::BindingResource::TextureView(&views[1]),
                wgpu::BindingResource::TextureView(&views[2]),
                v.edges.as_entire_binding(),
                uniforms.as_entire_binding(),
                wgpu::BindingResource::TextureView(&views[3]),
                wgpu::BindingResource::TextureView(&views[4]),
                frame.counter.as_entire_binding(),
            ],
        );
        layout::dispatch_per_pixel(encoder, "pvm::visibility_pass", &self.visibility_pipeline, &bind_group, gbuffer.size, timestamps);
    }
}

