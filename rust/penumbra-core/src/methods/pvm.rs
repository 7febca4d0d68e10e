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

use std::collections::{BTreeMap, HashMap};

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
pub use crate::methods::silhouettes::{silhouette, OpenEdges, SilhouetteCache, SilhouetteEdge};

pub const EDGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

#[derive(Debug, Clone, PartialEq)]
pub struct PvmParams {
    pub shadow: ShadowMapSettings,
    /// The 3k^2 - 2k^3 interpolant of 4.2.
    pub falloff: bool,
    pub open_edges: OpenEdges,
}

impl PvmParams {
    pub fn read(r: &mut ParamReader<'_>) -> Result<Self> {
        Ok(Self {
            shadow: ShadowMapSettings::read(r)?,
            falloff: r.bool("falloff", true)?,
            open_edges: OpenEdges::parse(r.choice("open_edges", "error", &OpenEdges::NAMES)?),
        })
    }

    pub fn effective(&self) -> BTreeMap<String, ParamValue> {
        let mut out = self.shadow.effective();
        out.insert("falloff".into(), ParamValue::Bool(self.falloff));
        out.insert("open_edges".into(), ParamValue::Str(self.open_edges.name().into()));
        out
    }
}

/// One corner of a volume quadrilateral with the silhouette edge it comes from.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VolumeVertex {
    pub position: [f32; 3],
    pub h0: [f32; 3],
    pub h1: [f32; 3],
}

#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct VolumeStats {
    pub silhouette_edges: usize,
    /// Quadrilaterals rendered (two per edge: outer and inner).
    pub volume_quads: usize,
    /// Silhouette vertices without exactly one incoming and one outgoing edge.
    pub junction_vertices: usize,
    /// Edges seen end-on from the light (no hard-shadow plane): no volume.
    pub light_parallel_edges: usize,
}

/// The planes of one silhouette edge (4.1.2).
struct EdgePlanes {
    /// Hard-shadow plane normal n.
    n: DVec3,
    /// Outer and inner penumbra plane normals n- and n+.
    outer: DVec3,
    inner: DVec3,
    /// Displaced light positions d- and d+.
    d_outer: DVec3,
    d_inner: DVec3,
}

fn edge_planes(e: &SilhouetteEdge, l: DVec3, r: f64) -> Option<EdgePlanes> {
    let along = e.b - e.a;
    let cross = along.cross(e.a - l);
    // An edge pointing at the light has no hard-shadow plane.
    if cross.length() <= 1e-9 * along.length() * (e.a - l).length() {
        return None;
    }
    let n = cross.normalize();
    let d_outer = l - n * r;
    let d_inner = l + n * r;
    // The edge is off the displaced positions (they lie on the light's sphere,
    // and no surface touches the light), so these crosses are non-zero.
    let outer = along.cross(e.a - d_outer).normalize_or_zero();
    let inner = along.cross(e.a - d_inner).normalize_or_zero();
    Some(EdgePlanes { n, outer, inner, d_outer, d_inner })
}

/// Extrusion vector at vertex `v` shared by the planes with normals `n_in`
/// (incoming edge) and `n_out` (outgoing edge), both through `v` (4.1.2).
fn extrusion(v: DVec3, n_in: DVec3, n_out: DVec3, d: DVec3, l: DVec3) -> DVec3 {
    let line = n_out.cross(n_in);
    // Coincident (or nearly) planes: the paper's rule, away from the displaced light.
    let mut dir = if line.length() < 1e-9 { (v - d).normalize_or_zero() } else { line.normalize() };
    // Cournia negates v^ when v1 lies in the negative half-space of (v0, v2, l);
    // that picks, of the two directions of the intersection line, the one that
    // continues the rays from the displaced light position d through v. We
    // test for that directly, which holds for either loop orientation (and,
    // unlike a test against the light centre, for lights large against their
    // distance).
    if dir.dot(v - d) < 0.0 {
        dir = -dir;
    }
    // Every ray of the true penumbra through v leaves the light: it lies in
    // the cone of half-angle asin(r / |v - l|) about v - l. For a light large
    // against its distance, the two planes can meet in a line that turns back
    // past the plane through v perpendicular to v - l (found by the property
    // tests: r = 1.8, |v - l| = 2.7 gave a line 94 degrees off v - l), and the
    // volume then sweeps over space in front of the silhouette. There the
    // vertex takes its own plane's ray from d instead, which always leaves
    // the light: n is orthogonal to v - l, so (v - d).(v - l) = |v - l|^2 > 0.
    if dir.dot(v - l) <= 0.0 {
        return (v - d).normalize_or_zero();
    }
    dir
}

/// Builds the outer and inner quadrilaterals of every silhouette edge,
/// extruded by `reach` (beyond the light's far plane).
pub fn penumbra_volumes(edges: &[SilhouetteEdge], l: DVec3, r: f64, reach: f64) -> (Vec<VolumeVertex>, VolumeStats) {
    let mut stats = VolumeStats { silhouette_edges: edges.len(), ..Default::default() };
    let planes: Vec<Option<EdgePlanes>> = edges.iter().map(|e| edge_planes(e, l, r)).collect();
    // Loop connectivity: the incoming and outgoing edges of each vertex.
    let mut incoming: HashMap<u32, Vec<usize>> = HashMap::new();
    let mut outgoing: HashMap<u32, Vec<usize>> = HashMap::new();
    for (i, e) in edges.iter().enumerate() {
        if planes[i].is_some() {
            outgoing.entry(e.ia).or_default().push(i);
            incoming.entry(e.ib).or_default().push(i);
        }
    }
    let paired = |v: u32| -> Option<(usize, usize)> {
        match (incoming.get(&v).map(Vec::as_slice), outgoing.get(&v).map(Vec::as_slice)) {
            (Some([i]), Some([o])) => Some((*i, *o)),
            _ => None,
        }
    };
    let mut junctions: Vec<u32> = incoming.keys().chain(outgoing.keys()).copied().filter(|&v| paired(v).is_none()).collect();
    junctions.sort_unstable();
    junctions.dedup();
    stats.junction_vertices = junctions.len();

    let mut vertices = Vec::with_capacity(edges.len() * 12);
    let f = |p: DVec3| p.as_vec3().to_array();
    for (i, e) in edges.iter().enumerate() {
        let Some(own) = &planes[i] else {
            stats.light_parallel_edges += 1;
            continue;
        };
        // Extrusion vectors at a (shared with the incoming edge) and b (with the outgoing one).
        let at = |v: DVec3, vi: u32, start: bool| -> (DVec3, DVec3) {
            let neighbour = paired(vi).map(|(inc, out)| if start { inc } else { out });
            match neighbour.and_then(|j| planes[j].as_ref()) {
                Some(other) => {
                    let (n_in, n_out) = if start { (other, own) } else { (own, other) };
                    (
                        extrusion(v, n_in.outer, n_out.outer, own.d_outer, l),
                        extrusion(v, n_in.inner, n_out.inner, own.d_inner, l),
                    )
                }
                // Unpaired: this edge's own plane alone (coincident-plane rule).
                None => ((v - own.d_outer).normalize_or_zero(), (v - own.d_inner).normalize_or_zero()),
            }
        };
        let (a_out, a_in) = at(e.a, e.ia, true);
        let (b_out, b_in) = at(e.b, e.ib, false);
        debug_assert!(own.n.is_finite());
        for (va, vb) in [(a_out, b_out), (a_in, b_in)] {
            let quad = [e.a, e.a + va * reach, e.b + vb * reach, e.b];
            for k in [0, 1, 2, 0, 2, 3] {
                vertices.push(VolumeVertex { position: f(quad[k]), h0: f(e.a), h1: f(e.b) });
            }
            stats.volume_quads += 1;
        }
    }
    (vertices, stats)
}

pub struct PenumbraVolumeMaps {
    volume_pass: VolumePass,
    visibility_pipeline: wgpu::ComputePipeline,
    visibility_layout: wgpu::BindGroupLayout,
}

/// The penumbra volume map (pass 2): what the renderer's pass cache keeps.
pub struct PvmVolumes {
    pub volume_depth: wgpu::Texture,
    pub edge0: wgpu::Texture,
    pub edge1: wgpu::Texture,
    pub stats: VolumeStats,
}

/// What one PVM render produced besides visibility: the volume map (built
/// now or reused) and this frame's membership image and counter.
pub struct PvmFrame {
    pub volumes: std::sync::Arc<PvmVolumes>,
    pub membership: wgpu::Texture,
    pub counter: wgpu::Buffer,
}

/// What pass 2 reads besides the geometry: the light, the frustum, the map
/// size and `open_edges` (appended to the pass-cache key).
pub fn volumes_key(params: &PvmParams, frustum: &LightFrustum, (l, r): (DVec3, f64), key: &mut PassKey) {
    key.f64s(&l.to_array())
        .f64s(&[r])
        .bytes(params.open_edges.name().as_bytes())
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
        Self { volumes, membership, counter }
    }
}


impl PenumbraVolumeMaps {
    pub fn new(device: &wgpu::Device) -> Self {
        let volume_pass = VolumePass::new::<VolumeVertex>(
            device,
            "pvm::volume_pass",
            crate::shaders::pvm_volumes(),
            ("vs_main", "fs_main"),
            &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3],
            &[EDGE_FORMAT, EDGE_FORMAT],
        );
        let visibility_layout = layout::bind_group_layout(
            device,
            "pvm::visibility_layout",
            &[
                layout::float_texture(0),
                layout::float_texture(1),
                layout::depth_texture(2),
                layout::depth_texture(3),
                layout::float_texture(4),
                layout::float_texture(5),
                layout::parameters(6),
                layout::storage_texture(7, VISIBILITY_FORMAT),
                layout::storage_texture(8, VISIBILITY_FORMAT),
                layout::storage_buffer_rw(9),
            ],
        );
        let visibility_pipeline = layout::compute_pipeline(device, "pvm::visibility_pipeline", crate::shaders::pvm(), &visibility_layout);
        Self {
            volume_pass,
            visibility_pipeline,
            visibility_layout,
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
        let (mut stats, mut cache_hits, vertices) = (VolumeStats::default(), 0, Vec::new());
        let mut vertices = vertices;
        // A point light has no penumbra: skip the volumes entirely.
        if r > 0.0 {
            let (edges, hits) = silhouettes.edges(scene, l, params.open_edges)?;
            cache_hits = hits;
            let reach = 4.0 * frustum.far as f64 + 4.0 * r;
            let (v, s) = penumbra_volumes(&edges, l, r, reach);
            vertices = v;
            stats = s;
        }
        let edge_usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
        let edge0 = layout::create_texture(device, "pvm::edge0_map", (map, map), EDGE_FORMAT, edge_usage);
        let edge1 = layout::create_texture(device, "pvm::edge1_map", (map, map), EDGE_FORMAT, edge_usage);
        let volume_depth = self.volume_pass.record(device, encoder, frustum, &vertices, map, &[&edge0, &edge1], timestamps)?;
        Ok((PvmVolumes { volume_depth, edge0, edge1, stats }, cache_hits))
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
        let flags = u32::from(params.falloff);
        let uniforms = layout::parameter_buffer(device, "pvm::visibility_uniforms", &params.shadow.uniform(frustum, light.0, light.1, flags));
        let v = &frame.volumes;
        let views = [shadow_map, &v.volume_depth, &v.edge0, &v.edge1, visibility, &frame.membership].map(layout::view);
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
                wgpu::BindingResource::TextureView(&views[3]),
                uniforms.as_entire_binding(),
                wgpu::BindingResource::TextureView(&views[4]),
                wgpu::BindingResource::TextureView(&views[5]),
                frame.counter.as_entire_binding(),
            ],
        );
        layout::dispatch_per_pixel(encoder, "pvm::visibility_pass", &self.visibility_pipeline, &bind_group, gbuffer.size, timestamps);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube centred at (0, 2, 0), outward faces.
    fn cube() -> Topology {
        let mut p = Vec::new();
        for i in 0..8 {
            p.push(DVec3::new(
                if i & 1 == 0 { -0.5 } else { 0.5 },
                2.0 + if i & 2 == 0 { -0.5 } else { 0.5 },
                if i & 4 == 0 { -0.5 } else { 0.5 },
            ));
        }
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let faces: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        Topology::build(&p, &faces)
    }

    use crate::topology::Topology;

    #[test]
    fn cube_under_a_light_has_one_square_loop() {
        let l = DVec3::new(0.0, 6.0, 0.0);
        let edges = silhouette(&cube(), l, false);
        // Seen from straight above, the silhouette is the top face's rim... of the
        // whole cube: the four vertical-face/top-face edges.
        assert_eq!(edges.len(), 4);
        for e in &edges {
            let n = (e.b - e.a).cross(e.a - l);
            // Normal points away from the cube's centre (the occluder).
            assert!(n.dot(e.a - DVec3::new(0.0, 2.0, 0.0)) > 0.0, "{e:?}");
        }
        let (vertices, stats) = penumbra_volumes(&edges, l, 0.5, 100.0);
        assert_eq!(stats.junction_vertices, 0);
        assert_eq!(stats.volume_quads, 8);
        assert_eq!(vertices.len(), 8 * 6);
        assert!(vertices.iter().all(|v| v.position.iter().all(|c| c.is_finite())));
        // Extruded corners go away from the light (downwards here).
        assert!(vertices.iter().all(|v| v.position[1] <= 2.5 + 1e-6));
    }

    #[test]
    fn outer_volume_leans_outwards_and_inner_inwards() {
        let l = DVec3::new(0.0, 6.0, 0.0);
        let edges = silhouette(&cube(), l, false);
        let (vertices, _) = penumbra_volumes(&edges, l, 0.5, 10.0);
        // Far corners: outer quads spread beyond the hard shadow's, inner ones inside it.
        let hard_spread = |y: f32| 0.5 * (6.0 - y) / (6.0 - 2.5);
        let (outer, inner) = vertices.split_at(6);
        let far_outer = outer.iter().map(|v| v.position).min_by(|a, b| a[1].total_cmp(&b[1])).unwrap();
        let far_inner = vertices[6..12].iter().map(|v| v.position).min_by(|a, b| a[1].total_cmp(&b[1])).unwrap();
        let spread = |p: [f32; 3]| p[0].abs().max(p[2].abs());
        assert!(spread(far_outer) > hard_spread(far_outer[1]), "{far_outer:?}");
        assert!(spread(far_inner) < hard_spread(far_inner[1]), "{far_inner:?}");
        let _ = inner;
    }

    #[test]
    fn degenerate_edges_produce_no_nan() {
        // An edge pointing at the light and collinear silhouette edges.
        let l = DVec3::new(0.0, 5.0, 0.0);
        let edges = vec![
            SilhouetteEdge { a: DVec3::new(0.0, 1.0, 0.0), b: DVec3::new(0.0, 2.0, 0.0), ia: 0, ib: 1 },
            SilhouetteEdge { a: DVec3::new(1.0, 1.0, 0.0), b: DVec3::new(2.0, 1.0, 0.0), ia: 2, ib: 3 },
            SilhouetteEdge { a: DVec3::new(2.0, 1.0, 0.0), b: DVec3::new(3.0, 1.0, 0.0), ia: 3, ib: 4 },
        ];
        let (vertices, stats) = penumbra_volumes(&edges, l, 0.5, 10.0);
        assert_eq!(stats.light_parallel_edges, 1);
        assert!(vertices.iter().all(|v| v.position.iter().chain(&v.h0).chain(&v.h1).all(|c| c.is_finite())));
        // Radius 0: all planes coincide with the hard-shadow plane; still finite.
        let (vertices, _) = penumbra_volumes(&edges, l, 0.0, 10.0);
        assert!(vertices.iter().all(|v| v.position.iter().all(|c| c.is_finite())));
    }
}
