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

use std::sync::Arc;

use glam::DVec3;

use crate::error::Result;
use crate::frame::{Frame, Intermediate};
use crate::gpu::layout;
use crate::gpu::pool::{Binding, PooledTexture, ResourcePool};
use crate::light_frustum::LightProjection;
use crate::methods::{Method, MethodOutput, ParamSet, ParamSpec};
use crate::pass_cache::{CachedPass, PassKey};
use crate::passes::shading::VISIBILITY_FORMAT;
use crate::passes::screen::ScreenPass;
use crate::passes::shadow_map::{self, CENTRE_MAP};
use crate::passes::shadow_test::ShadowMapSettings;
use crate::passes::volumes::VolumePass;
pub use crate::silhouettes::{silhouette, OpenEdges, SilhouetteCache, SilhouetteEdge};

pub mod geometry;
pub use geometry::{penumbra_volumes, VolumeStats, VolumeVertex};

pub const EDGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The penumbra volume map (pass 2), as the pass cache keeps it.
pub const PENUMBRA_VOLUMES: CachedPass = CachedPass { name: "penumbra_volumes", capacity: 1 };

#[derive(Debug, Clone, PartialEq)]
pub struct PvmParams {
    pub shadow: ShadowMapSettings,
    /// The 3k^2 - 2k^3 interpolant of 4.2.
    pub falloff: bool,
    pub open_edges: OpenEdges,
}

/// The penumbra volume map (pass 2).
pub struct PvmVolumes {
    pub volume_depth: PooledTexture,
    pub edge0: PooledTexture,
    pub edge1: PooledTexture,
    pub stats: VolumeStats,
    /// Meshes whose silhouettes came from the silhouette cache.
    pub silhouette_cache_hits: usize,
}

/// What pass 2 reads besides the geometry: the light, the projection, the
/// map size and `open_edges` (appended to the pass-cache key).
pub fn volumes_key(params: &PvmParams, projection: &LightProjection, (l, r): (DVec3, f64), key: &mut PassKey) {
    key.f64s(&l.to_array())
        .f64s(&[r])
        .bytes(params.open_edges.name().as_bytes())
        .projection(projection)
        .u32(params.shadow.map_size);
}

pub struct PenumbraVolumeMaps {
    volume_pass: VolumePass,
    visibility: ScreenPass,
}

impl Method for PenumbraVolumeMaps {
    const NAME: &'static str = "pvm";
    const PAPER: &'static str = "penumbra volume maps (Cournia ch. 4)";
    type Params = PvmParams;

    fn specs() -> Vec<ParamSpec> {
        let mut specs = ShadowMapSettings::specs("slope");
        specs.extend([
            ParamSpec::bool("falloff", true, "the 3k^2 - 2k^3 interpolant of 4.2 (false: the disk fraction k)"),
            ParamSpec::choice(
                "open_edges",
                "error",
                &OpenEdges::NAMES,
                "casters with boundary edges: refuse them, or treat boundary edges as silhouette edges",
            ),
        ]);
        specs
    }

    fn params(p: &ParamSet) -> Result<PvmParams> {
        Ok(PvmParams {
            shadow: ShadowMapSettings::from_params(p),
            falloff: p.bool("falloff"),
            open_edges: OpenEdges::parse(p.choice("open_edges")),
        })
    }

    fn cached_passes() -> &'static [CachedPass] {
        &[CENTRE_MAP, PENUMBRA_VOLUMES]
    }

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        let volume_pass = VolumePass::new::<VolumeVertex>(
            device,
            pool,
            "pvm::volume_pass",
            crate::shaders::compose("methods/pvm/volumes.wgsl"),
            ("vs_main", "fs_main"),
            &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3],
            &[EDGE_FORMAT, EDGE_FORMAT],
        );
        let visibility = ScreenPass::new(
            device,
            pool,
            "pvm::visibility_pass",
            crate::shaders::compose("methods/pvm/visibility.wgsl"),
            &[
                layout::depth_array,
                layout::depth_array,
                layout::float_array,
                layout::float_array,
                layout::parameters,
                |b| layout::storage_texture(b, VISIBILITY_FORMAT),
                |b| layout::storage_texture(b, VISIBILITY_FORMAT),
                layout::storage_buffer_rw,
            ],
            &["main"],
        );
        Self { volume_pass, visibility }
    }

    fn record(&self, frame: &mut Frame<'_>, params: &PvmParams) -> Result<MethodOutput> {
        let (map, projection) = shadow_map::centre_map(frame, &params.shadow)?;
        let light = frame.ctx.light;
        let (l, r) = (light.center, light.radius);
        let mut key = PassKey::new(PENUMBRA_VOLUMES.name);
        key.bytes(&frame.ctx.geometry);
        volumes_key(params, &projection, (l, r), &mut key);
        let mut fresh = false;
        let volumes = frame.cached(PENUMBRA_VOLUMES.name, key.finish(), |frame| {
            fresh = true;
            self.record_volumes(frame, params, &projection).map(Arc::new)
        })?;
        let visibility = frame.ctx.screen_texture("pvm::visibility");
        let membership = frame.ctx.screen_texture("pvm::in_volume");
        let counter = frame.pass("visibility", |ctx, encoder, ts| {
            let counter = ctx.counters("pvm::pixels_in_volume", 1, encoder);
            let flags = u32::from(params.falloff);
            let uniforms = ctx.parameters(
                "pvm::visibility_uniforms",
                &params.shadow.uniform(&projection, light.center_f32, light.radius_f32, flags),
            );
            let resources = [
                Binding::Texture(&map),
                Binding::Texture(&volumes.volume_depth),
                Binding::Texture(&volumes.edge0),
                Binding::Texture(&volumes.edge1),
                Binding::Buffer(&uniforms),
                Binding::Texture(&visibility),
                Binding::Texture(&membership),
                Binding::Buffer(&counter),
            ];
            self.visibility.run(ctx, encoder, &resources, ts);
            counter
        })?;
        let s = &volumes.stats;
        frame.stat("silhouette_edges", s.silhouette_edges as i64);
        frame.stat("penumbra_volumes", s.volume_quads as i64);
        frame.stat("silhouette_junction_vertices", s.junction_vertices as i64);
        frame.stat("light_parallel_edges", s.light_parallel_edges as i64);
        frame.stat("silhouette_cache_hits", if fresh { volumes.silhouette_cache_hits as i64 } else { 0 });
        frame.counters(&counter, &["pixels_in_volume"]);
        frame.intermediate(Intermediate::depth("pvm_volume_depth", &volumes.volume_depth, projection.far()));
        frame.intermediate(Intermediate::color("pvm_edge0", &volumes.edge0, 3));
        frame.intermediate(Intermediate::color("pvm_edge1", &volumes.edge1, 3));
        frame.intermediate(Intermediate::color("pvm_in_volume", &membership, 1));
        Ok(MethodOutput { visibility })
    }
}

impl PenumbraVolumeMaps {
    /// Pass 2: builds the penumbra volumes of every silhouette edge (4.1.2)
    /// and renders them into the penumbra volume map (4.1.3).
    fn record_volumes(&self, frame: &mut Frame<'_>, params: &PvmParams, projection: &LightProjection) -> Result<PvmVolumes> {
        let map = params.shadow.map_size;
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
        let edge0 = frame.ctx.light_texture("pvm::edge0_map", map, projection.layers(), EDGE_FORMAT, usage);
        let edge1 = frame.ctx.light_texture("pvm::edge1_map", map, projection.layers(), EDGE_FORMAT, usage);
        // The CPU work (silhouettes and volumes) is part of the pass's time.
        let (volume_depth, stats, silhouette_cache_hits) = frame.pass("penumbra_volumes", |ctx, encoder, ts| -> Result<_> {
            let (l, r) = (ctx.light.center, ctx.light.radius);
            let (mut stats, mut cache_hits, mut vertices) = (VolumeStats::default(), 0, Vec::new());
            // A point light has no penumbra: skip the volumes entirely.
            if r > 0.0 {
                let (edges, hits) = ctx.shared.silhouettes.edges(ctx.prepared, l, params.open_edges)?;
                cache_hits = hits;
                // Beyond the far plane of every face (at most sqrt(3) far from the light).
                let reach = 4.0 * projection.far() as f64 + 4.0 * r;
                (vertices, stats) = penumbra_volumes(&edges, l, r, reach);
            }
            let depth = self.volume_pass.record(ctx, encoder, projection, &vertices, map, &[&edge0, &edge1], ts)?;
            Ok((depth, stats, cache_hits))
        })??;
        Ok(PvmVolumes { volume_depth, edge0, edge1, stats, silhouette_cache_hits })
    }
}
