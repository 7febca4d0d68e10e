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

use crate::passes::map_rays::{self, MapBound};
use std::sync::Arc;

use glam::DVec3;

use crate::error::Result;
use crate::frame::{Frame, FrameContext, Intermediate};
use crate::gpu::layout;
use crate::gpu::pool::{Binding, Layout, PooledBuffer, PooledTexture, ResourcePool};
use crate::light_frustum::LightProjection;
use crate::method::{Method, MethodOutput};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::pass_cache::{CachedPass, PassKey};
use crate::passes::centre_map::{self, CENTRE_MAP};
use crate::passes::object_map::{self, OBJECT_MAP};
use crate::passes::solid_layers::{self, SolidLayersPass, SOLID_LAYERS};
use crate::passes::screen::ScreenPass;
use crate::passes::shadow_test::ShadowMapSettings;
use crate::passes::volumes::{Keep, VolumePass};
pub use crate::silhouettes::{silhouette, OpenEdges, Repairs, SilhouetteCache, SilhouetteEdge};

pub mod geometry;
pub use geometry::{penumbra_volumes, EdgePoints, VolumeGeometry, VolumeStats, VolumeVertex};

/// The penumbra volume edge map: the index + 1 of the edge whose volume is
/// nearest the light (0: none), drawn with its depth map by the shared
/// light-id raster (passes/light_ids.wgsl) in one pass (Cournia 4.1.3).
///
/// Departure from 4.1.3: the paper's two edge maps (PVEMs) hold the end
/// points h0 and h1 of the silhouette edge that gave rise to the volume (six
/// floats per texel, 16-bit there, 32-bit here). This map holds the edge's
/// index + 1 and the visibility pass reads h0 and h1 from a buffer of the
/// edges: the same information, 4 bytes per texel instead of 32. On a
/// software rasteriser the pass's cost is the bytes it clears and writes
/// (docs/real_meshes.md).
pub const EDGE_INDEX_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// The `pvm_edge0` / `pvm_edge1` intermediates: the paper's edge maps.
pub const EDGE_POINT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The values of `repairs`: cumulative, in the order docs/real_meshes.md
/// measures them; "all" (the default) adds the horizon to the last.
pub const REPAIR_LEVELS: [&str; 5] = ["all", "none", "cone", "cone+hidden", "cone+hidden+centre"];

/// The penumbra volume map (pass 2), as the pass cache keeps it.
pub const PENUMBRA_VOLUMES: CachedPass = CachedPass { name: "penumbra_volumes", capacity: 1 };

#[derive(Debug, Clone, PartialEq)]
pub struct PvmParams {
    pub shadow: ShadowMapSettings,
    /// The 3k^2 - 2k^3 interpolant of 4.2 (the paper's; not the default).
    pub falloff: bool,
    /// Render the penumbra volume map a texel per pixel on the visible
    /// receivers (`volume_map_size = "auto"`,
    /// `FrameContext::receiver_image_size`) rather than at the shadow map's size
    /// (`"map"`, the paper's 4.1.3).
    pub volume_map_auto: bool,
    /// `edges = "two"` (beyond 4.1.3, which keeps the volume nearest the
    /// light): a second edge map keeps the volume farthest from the light,
    /// and a pixel inside both edges' penumbrae takes the light the two
    /// edges leave it together (`two_edge_visibility` in visibility.wgsl).
    pub two_edges: bool,
    /// `edges = "chain"` (beyond 4.2, which takes the nearest volume's edge
    /// for a half-plane; the default): as `"two"`, and where the shadow map
    /// sees the light's centre the pixel's light is the disk less the part
    /// its edge's silhouette loop covers, walked from that edge both ways
    /// (`chain_visibility` in visibility.wgsl).
    pub chain_edges: bool,
    /// `lookup = "3x3"` (beyond 4.2, which reads the texel under the pixel):
    /// where that texel's volume does not hold the pixel, the neighbour
    /// texels' volumes may (`volume_at` in visibility.wgsl).
    pub lookup_neighbours: bool,
    /// `umbra_test = "rim"` (beyond 4.2): a pixel in a volume whose light
    /// centre and 8 rim points the shadow map hides is in the umbra
    /// (`rim_hidden` in visibility.wgsl).
    pub rim_test: bool,
    /// The map bound (beyond the papers: `map_samples`, `map_bound`,
    /// `map_march`; passes/map_rays.rs).
    pub map: MapBound,
    /// `map_control` (beyond 4.2, the default): where k is the nearest
    /// edge's half-plane fraction, the rays are compared with that
    /// half-plane at the same points, and k moves only by the points where
    /// they disagree beyond one point and the map's texel band
    /// (`map_bound` and `texel_band` in passes/map_rays.wgsl).
    pub map_control: bool,
    pub open_edges: OpenEdges,
    /// Departures from the paper for real meshes (`Repairs`).
    pub repairs: Repairs,
}

/// The penumbra volume map (pass 2).
pub struct PvmVolumes {
    pub volume_depth: PooledTexture,
    /// Per texel, the index + 1 into `edges` of the volume nearest the light (0: none).
    pub edge_index: PooledTexture,
    /// With `edges = "two"`, the same for the volume farthest from the light.
    pub far_edge_index: Option<PooledTexture>,
    /// The silhouette edges' end points ([`EdgePoints`]; one zeroed entry when there is none).
    pub edges: PooledBuffer,
    pub stats: VolumeStats,
    /// Meshes whose silhouettes came from the silhouette cache.
    pub silhouette_cache_hits: usize,
}

/// What pass 2 reads besides the geometry: the light, the projection, the
/// map size, `open_edges` and the geometric repairs (appended to the pass-cache key).
pub fn volumes_key(params: &PvmParams, projection: &LightProjection, (l, r): (DVec3, f64), volume_map: u32, key: &mut PassKey) {
    key.f64s(&l.to_array())
        .f64s(&[r])
        .bytes(params.open_edges.name().as_bytes())
        .bytes(&[u8::from(params.repairs.cone), u8::from(params.repairs.hidden), u8::from(params.two_edges || params.chain_edges)])
        .projection(projection)
        .u32(params.shadow.map_size)
        .u32(volume_map);
}

pub struct PenumbraVolumeMaps {
    volume_pass: VolumePass,
    far_volume_pass: VolumePass,
    object_pass: VolumePass,
    solid_pass: SolidLayersPass,
    visibility: ScreenPass,
    edge_maps_pipeline: wgpu::ComputePipeline,
    edge_maps_layout: Layout,
}

/// A light-space image of edge indices (`texture_2d_array<u32>`).
fn uint_array(binding: u32) -> wgpu::BindGroupLayoutEntry {
    layout::array_texture(binding, wgpu::TextureSampleType::Uint)
}

impl MethodParams for PvmParams {
    fn specs() -> Vec<ParamSpec> {
        ShadowMapSettings::specs_and([
            // Not the paper's default (issue 28): 4.2's curve pushes Eq. 4.1's
            // disk fraction away from 1/2, so the outer penumbra comes out too
            // light and the inner too dark. Without it the penumbra RMSE is
            // lower on every shared-mesh scene (tests/test_real_meshes.py) and
            // at the median over the generated suite (docs/methods/pvm.md).
            ParamSpec::bool("falloff", false, "the 3k^2 - 2k^3 interpolant of 4.2, the paper's (false: Eq. 4.1's disk fraction k)"),
            // Beyond 4.1.3 (issue 28), whose map keeps one edge per texel:
            // where two edges' penumbrae overlap (a shadow thinner than the
            // light's, a convex corner), one edge's disk fraction is wrong.
            // "two", with "auto" and "3x3" below, lowered the penumbra RMSE
            // on 34 of the 40 generated scenes and 53 of the slow suite's 60.
            // "chain" (the default since) walks the edge's silhouette loop
            // where the map sees the light's centre, "two" deciding
            // elsewhere: lower again on 18 of the 40 (higher on 2), 34 of the
            // 60 (1) and 13 of the 15 shared-mesh scenes (0)
            // (docs/methods/pvm.md).
            ParamSpec::choice(
                "edges",
                "chain",
                &["one", "two", "chain"],
                "edges per volume-map texel: one, the volume nearest the light (4.1.3); two, also the farthest, combined where a pixel lies in both penumbrae; chain, as two, and where the map sees the light's centre the disk less what the nearest edge's silhouette loop covers (walked from that edge)",
            ),
            // Beyond 4.1.3, whose volume map is the shadow map's size (issue
            // 30): the volume passes' cost is their texels. Alone, a texel
            // per pixel misses penumbrae narrower than a texel (the teapot
            // close under r = 0.3: 0.039 against 0.024 with edges "two");
            // with lookup "3x3" it is 0.0225.
            ParamSpec::choice(
                "volume_map_size",
                "auto",
                &["map", "auto"],
                "the penumbra volume map's resolution: the shadow map's (4.1.3), or auto: a texel per pixel on the visible receivers (map_size's criterion), at most the map's",
            ),
            // Beyond 4.2 (issue 28): the volume map is a rasterisation at
            // texel centres, so a penumbra narrower than a texel falls
            // between them and its pixels get the hard test; and the volume
            // at a pixel's texel need not be one whose penumbra holds it.
            ParamSpec::choice(
                "lookup",
                "3x3",
                &["texel", "3x3"],
                "where the visibility pass looks up the volume holding a pixel: its texel (4.2), or 3x3: also the 8 neighbours where that texel's volume does not hold it",
            ),
            // Beyond 4.2 (issue 28): the nearest volume's edge, taken for a
            // half-plane, leaves a pixel the light on its lit side even
            // where another part of the mesh hides that side too (umbrae
            // lit to 1/2 under a teapot's knob, a boot's leg). The default:
            // on the generated suite it takes 5 more scenes within issue
            // 28's bar (8 over 0.5% stray pixels to 3), and no scene's
            // penumbra RMSE rises on it, the slow suite or the shared
            // meshes (docs/methods/pvm.md).
            ParamSpec::choice(
                "umbra_test",
                "rim",
                &["none", "rim"],
                "inside a volume, where the shadow map hides the light's centre: none, the edge's k decides (4.2); rim, a pixel whose rays to 8 points of the light's rim the map hides as well is in the umbra",
            ),
        ]
        .into_iter()
        .chain(MapBound::specs(
            map_rays::SAMPLES_DEFAULT,
            "inside a volume, points of the light's disk whose rays from the pixel are followed through the shadow map (as umbra_test rim's): the visibility is at most the fraction seen plus 1.2 n^-0.7 (0.106 at 32, 0.17 at 16: the points' own error under a straight edge) and the texel band; 0: the edge's k alone (4.2)",
        ))
        .chain([
            // A control variate (issue 28): the spiral's error under a
            // straight edge is shared by the rays and the half-plane, so it
            // cancels, and the margin can be one point and the map's texel
            // band instead of map_margin's 0.17 at 16 (docs/methods/pvm.md).
            ParamSpec::bool(
                "map_control",
                true,
                "with map_samples > 0, where k is the nearest edge's half-plane fraction (Eq. 4.1): compare the rays with that half-plane at the same points and move k only by the points where they disagree, beyond one point and the texel band (the rays the search leaves seen, without map_march's); false: compare them with k alone, beyond 1.2 n^-0.7 and the texel band",
            ),
            OpenEdges::spec(),
            ParamSpec::choice(
                "repairs",
                "all",
                &REPAIR_LEVELS,
                "departures from the paper for real meshes, cumulative (docs/real_meshes.md): none, cone, cone+hidden, cone+hidden+centre, all (+horizon)",
            ),
        ]))
    }

    fn parse(p: &ParamSet) -> Result<PvmParams> {
        Ok(PvmParams {
            shadow: ShadowMapSettings::from_params(p),
            falloff: p.bool("falloff"),
            volume_map_auto: p.choice("volume_map_size") == "auto",
            two_edges: p.choice("edges") == "two",
            chain_edges: p.choice("edges") == "chain",
            lookup_neighbours: p.choice("lookup") == "3x3",
            rim_test: p.choice("umbra_test") == "rim",
            map: MapBound::parse(p),
            map_control: p.bool("map_control"),
            open_edges: OpenEdges::parse(p.choice("open_edges")),
            repairs: Repairs::parse(p.choice("repairs")),
        })
    }
}

impl Method for PenumbraVolumeMaps {
    const NAME: &'static str = "pvm";
    const PAPER: &'static str = "penumbra volume maps (Cournia ch. 4)";
    type Params = PvmParams;

    fn cached_passes() -> &'static [CachedPass] {
        &[CENTRE_MAP, PENUMBRA_VOLUMES, OBJECT_MAP, SOLID_LAYERS]
    }

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        // The volume map (4.1.3), and with edges = "two" the same volumes' farthest.
        let volumes = |keep, name| {
            let source = crate::shaders::compose("passes/light_ids.wgsl");
            VolumePass::new::<VolumeVertex>(keep, device, pool, name, source, ("vs_main", "fs_main"), &wgpu::vertex_attr_array![0 => Float32x3, 1 => Uint32], &[EDGE_INDEX_FORMAT])
        };
        let (volume_pass, far_volume_pass) = (volumes(Keep::Nearest, "pvm::volume_pass"), volumes(Keep::Farthest, "pvm::far_volume_pass"));
        // Reads the map, the volume map's depth and edge indices, the edges and
        // the test block; writes visibility, membership and the counter; reads
        // the far edge indices.
        let mut bindings = object_map::with_bindings(&[
            layout::depth_array, layout::depth_array, uint_array, layout::parameters, layout::parameters,
            layout::visibility_storage, layout::visibility_storage, layout::storage_buffer_rw, uint_array,
        ]);
        // The solid layers (map_solids).
        bindings.push(layout::storage_buffer);
        let visibility = ScreenPass::per_pixel(device, pool, "pvm::visibility_pass", crate::shader!("visibility.wgsl"), &bindings);
        let edge_maps_layout = pool.layout(
            device,
            "pvm::edge_maps_layout",
            &[uint_array(0), layout::parameters(1), layout::storage_array_texture(2, EDGE_POINT_FORMAT), layout::storage_array_texture(3, EDGE_POINT_FORMAT)],
        );
        let edge_maps_pipeline =
            layout::compute_pipeline(device, "pvm::edge_maps_pipeline", crate::shader!("edge_maps.wgsl"), &edge_maps_layout);
        let solid_pass = SolidLayersPass::new(device, pool);
        Self { volume_pass, far_volume_pass, object_pass: object_map::pass(device, pool), solid_pass, visibility, edge_maps_pipeline, edge_maps_layout }
    }

    fn record(&self, frame: &mut Frame<'_>, params: &PvmParams) -> Result<MethodOutput> {
        let (map, projection) = centre_map::centre_map(frame, &params.shadow)?;
        let light = frame.ctx.light;
        let (l, r) = (light.center, light.radius);
        let map_size = params.shadow.map_size;
        let volume_map = if params.volume_map_auto { frame.ctx.receiver_image_size(map_size, &projection) } else { map_size };
        let mut key = PassKey::new(PENUMBRA_VOLUMES.name);
        key.bytes(&frame.ctx.geometry);
        volumes_key(params, &projection, (l, r), volume_map, &mut key);
        let mut fresh = false;
        let volumes = frame.cached(PENUMBRA_VOLUMES.name, key.finish(), |frame| {
            fresh = true;
            self.record_volumes(frame, params, &projection, volume_map).map(Arc::new)
        })?;
        let objects = object_map::record_if(frame, params.repairs.horizon && light.radius > 0.0, &self.object_pass, &projection, params.shadow.map_size)?;
        let solids = solid_layers::record_if(frame, params.map.solids && params.map.samples > 0 && r > 0.0, &self.solid_pass, &projection, params.shadow.map_size)?;
        let visibility = frame.ctx.screen_texture("pvm::visibility");
        let membership = frame.ctx.screen_texture("pvm::in_volume");
        let counter = frame.pass("visibility", |ctx, encoder, ts| {
            let counter = ctx.counters("pvm::counters", 5, encoder);
            let flags = u32::from(params.falloff)
                | (u32::from(params.repairs.centre) << 1)
                | (u32::from(params.repairs.horizon) << 2)
                | (u32::from(volumes.far_edge_index.is_some()) << 3)
                | (u32::from(params.lookup_neighbours) << 4)
                | (u32::from(params.rim_test) << 5)
                | (u32::from(params.chain_edges) << 6)
                | (u32::from(params.map.both) << 7)
                | (u32::from(params.map_control) << 8)
                | (u32::from(params.map.solid) << 9);
            let mut test = params.shadow.uniform(&projection, light.center_f32, light.radius_f32, flags);
            [test.mode[2], test.mode[3]] = params.map.mode();
            let uniforms = ctx.parameters("pvm::visibility_uniforms", &test);
            let resources = [
                Binding::Texture(&map),
                Binding::Texture(&volumes.volume_depth),
                Binding::Texture(&volumes.edge_index),
                Binding::Buffer(&volumes.edges),
                Binding::Buffer(&uniforms),
                Binding::Texture(&visibility),
                Binding::Texture(&membership),
                Binding::Buffer(&counter),
                // Without a far map the shader does not read it: the near one stands in.
                Binding::Texture(volumes.far_edge_index.as_ref().unwrap_or(&volumes.edge_index)),
            ];
            let mut resources = objects.after(&resources);
            resources.push(Binding::Buffer(&solids.buffer));
            self.visibility.run(ctx, encoder, &resources, ts);
            counter
        })?;
        let s = &volumes.stats;
        frame.silhouette_stats(&s.silhouette, volumes.silhouette_cache_hits, fresh);
        frame.stat("penumbra_volumes", s.volume_quads as i64);
        frame.stat("volume_map_size", i64::from(volume_map));
        frame.stat("silhouette_junction_vertices", s.junction_vertices as i64);
        frame.stat("extrusions_outside_light_cone", s.extrusions_outside_cone as i64);
        frame.counters(&counter, &["pixels_in_volume", "chain_walks", "chain_pixels", "map_bounded_pixels", "map_raised_pixels"]);
        frame.intermediate(Intermediate::depth("pvm_volume_depth", &volumes.volume_depth, projection.far()))?;
        if frame.wants_intermediates() {
            let (edge0, edge1) = frame.untimed(|ctx, encoder| self.record_edge_maps(ctx, encoder, &volumes, volume_map));
            frame.intermediate(Intermediate::color("pvm_edge0", &edge0, 3))?;
            frame.intermediate(Intermediate::color("pvm_edge1", &edge1, 3))?;
        }
        frame.intermediate(Intermediate::color("pvm_in_volume", &membership, 1))?;
        Ok(MethodOutput { visibility })
    }
}

impl PenumbraVolumeMaps {
    /// Pass 2: builds the penumbra volumes of every silhouette edge (4.1.2)
    /// and renders them into the penumbra volume map (4.1.3).
    fn record_volumes(&self, frame: &mut Frame<'_>, params: &PvmParams, projection: &LightProjection, map: u32) -> Result<PvmVolumes> {
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let edge_index = frame.ctx.light_texture("pvm::edge_index_map", map, projection.layers(), EDGE_INDEX_FORMAT, usage);
        // The CPU work (silhouettes and volumes) is part of the pass's time.
        let (volume_depth, vertices, edges, stats, silhouette_cache_hits) = frame.pass("penumbra_volumes", |ctx, encoder, ts| -> Result<_> {
            let (l, r) = (ctx.light.center, ctx.light.radius);
            let (mut cache_hits, mut geometry) = (0, VolumeGeometry::default());
            // A point light has no penumbra: skip the volumes entirely.
            if r > 0.0 {
                let silhouette = ctx.silhouettes.seen_from_light(ctx.prepared, l, params.open_edges, params.repairs.hidden)?;
                cache_hits = silhouette.cache_hits;
                // Beyond the far plane of every face (at most sqrt(3) far from the light).
                let reach = 4.0 * projection.far() as f64 + 4.0 * r;
                geometry = penumbra_volumes(&silhouette.edges, l, r, reach, params.repairs.cone);
                geometry.stats.silhouette.add_scene(&silhouette);
            }
            // A storage binding may not be empty: one zeroed entry stands for no edges.
            let points = if geometry.edges.is_empty() { vec![EdgePoints { h0: [0.0; 4], h1: [0.0; 4], links: [0; 4] }] } else { std::mem::take(&mut geometry.edges) };
            let bytes: &[u8] = bytemuck::cast_slice(&points);
            let edges = ctx.buffer("pvm::edges", bytes.len() as u64, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST);
            ctx.queue.write_buffer(&edges, 0, bytes);
            let vertices = self.volume_pass.upload(ctx, &geometry.vertices)?;
            let depth = self.volume_pass.record_uploaded(ctx, encoder, projection, &vertices, map, &[&edge_index], ts);
            let depth = depth.expect("a depth pass (Keep::Nearest) returns its depth map");
            Ok((depth, vertices, edges, geometry.stats, cache_hits))
        })??;
        // edges = "two" (and "chain"): the same volumes again, the farthest kept (its own pass, timed apart).
        let far_edge_index = if params.two_edges || params.chain_edges {
            let far = frame.ctx.light_texture("pvm::far_edge_index_map", map, projection.layers(), EDGE_INDEX_FORMAT, usage);
            frame.pass("far_volumes", |ctx, encoder, ts| {
                self.far_volume_pass.record_uploaded(ctx, encoder, projection, &vertices, map, &[&far], ts);
            })?;
            Some(far)
        } else {
            None
        };
        Ok(PvmVolumes { volume_depth, edge_index, far_edge_index, edges, stats, silhouette_cache_hits })
    }

    /// The paper's two edge maps (4.1.3) rebuilt from the edge-index map,
    /// for the `pvm_edge0` and `pvm_edge1` intermediates.
    fn record_edge_maps(&self, ctx: &FrameContext<'_>, encoder: &mut wgpu::CommandEncoder, volumes: &PvmVolumes, map: u32) -> (PooledTexture, PooledTexture) {
        let layers = volumes.edge_index.texture.depth_or_array_layers();
        let usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC;
        let edge0 = ctx.light_texture("pvm::edge0_map", map, layers, EDGE_POINT_FORMAT, usage);
        let edge1 = ctx.light_texture("pvm::edge1_map", map, layers, EDGE_POINT_FORMAT, usage);
        let resources = [Binding::Texture(&volumes.edge_index), Binding::Buffer(&volumes.edges), Binding::Texture(&edge0), Binding::Texture(&edge1)];
        let bind_group = ctx.pool.bind_group(ctx.device, "pvm::edge_maps_bind_group", &self.edge_maps_layout, &resources);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("pvm::edge_maps_pass"), timestamp_writes: None });
        pass.set_pipeline(&self.edge_maps_pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(map.div_ceil(8), map.div_ceil(8), layers);
        drop(pass);
        (edge0, edge1)
    }
}
