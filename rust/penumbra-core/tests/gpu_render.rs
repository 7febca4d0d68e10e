//! GPU tests: they run on whatever adapter the context picks (lavapipe in CI)
//! and skip with a clear reason when there is none.

use std::collections::BTreeMap;
use std::sync::OnceLock;

use glam::Mat4;
use penumbra_core::{Camera, Error, MethodConfig, Mesh, ParamValue, RenderOptions, Renderer, Scene, SphereLight};

/// One renderer for all tests (creating a device on lavapipe is slow).
fn renderer() -> Option<&'static Renderer> {
    static RENDERER: OnceLock<Result<Renderer, Error>> = OnceLock::new();
    match RENDERER.get_or_init(|| Renderer::new(true)) {
        Ok(r) => Some(r),
        Err(Error::GpuUnavailable(why)) => {
            eprintln!("skipping GPU test: {why}");
            None
        }
        Err(e) => panic!("renderer creation failed: {e}"),
    }
}

fn plane(half: f32) -> Mesh {
    Mesh {
        name: "plane".into(),
        vertices: vec![[-half, 0.0, -half], [half, 0.0, -half], [half, 0.0, half], [-half, 0.0, half]],
        faces: vec![[0, 2, 1], [0, 3, 2]],
        normals: None,
        albedo: [0.8; 3],
        object_id: 0,
        transform: Mat4::IDENTITY,
    }
}

/// An axis-aligned box of half-size `h` at `center`, faces outward (CCW).
fn cube(center: [f32; 3], h: f32) -> Mesh {
    let mut vertices = Vec::new();
    for i in 0..8 {
        vertices.push([
            center[0] + if i & 1 == 0 { -h } else { h },
            center[1] + if i & 2 == 0 { -h } else { h },
            center[2] + if i & 4 == 0 { -h } else { h },
        ]);
    }
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let faces = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    Mesh { name: "cube".into(), vertices, faces, normals: None, albedo: [0.5; 3], object_id: 1, transform: Mat4::IDENTITY }
}

fn camera(size: u32) -> Camera {
    Camera { eye: [0.0, 6.0, 6.0], target: [0.0, 0.0, 0.0], up: [0.0, 1.0, 0.0], fov_y_degrees: 45.0, width: size, height: size }
}

fn hard() -> MethodConfig {
    MethodConfig::parse("hard", &BTreeMap::new()).unwrap()
}

#[test]
fn cube_casts_a_shadow_on_the_plane() {
    let Some(r) = renderer() else { return };
    let scene = Scene {
        meshes: vec![plane(4.0), cube([0.0, 1.0, 0.0], 0.5)],
        light: SphereLight { center: [0.0, 5.0, 0.0], radius: 0.0, intensity: [10.0; 3] },
        ambient: [0.0; 3],
    };
    let result = r.render(&scene, &camera(64), &hard(), &RenderOptions { intermediates: true, ..Default::default() }).unwrap();
    let vis = result.image("visibility").unwrap().f32().unwrap();
    let ids = match &result.image("object_id").unwrap().data {
        penumbra_core::ImageData::I32(v) => v.clone(),
        _ => unreachable!(),
    };
    let plane_pixels: Vec<f32> = vis.iter().zip(&ids).filter(|(_, &id)| id == 0).map(|(v, _)| *v).collect();
    let shadowed = plane_pixels.iter().filter(|&&v| v == 0.0).count();
    assert!(shadowed > 20, "the cube's shadow covers plane pixels ({shadowed})");
    assert!(shadowed < plane_pixels.len() / 2, "most of the plane is lit");
    let radiance = result.image("radiance").unwrap().f32().unwrap();
    assert!(radiance.iter().all(|v| v.is_finite() && *v >= 0.0));
    assert!(result.image("shadow_map").is_some());
    assert_eq!(result.timings.passes.iter().map(|p| p.0.as_str()).collect::<Vec<_>>(), ["gbuffer", "shadow_map", "visibility", "shading", "readback"]);
}

#[test]
fn bad_parameters_are_typed_errors() {
    let bad = BTreeMap::from([("map_size".to_owned(), ParamValue::Int(3))]);
    assert!(matches!(MethodConfig::parse("hard", &bad), Err(Error::InvalidParameter(_))));
    let unknown = BTreeMap::from([("kernel".to_owned(), ParamValue::Int(3))]);
    let err = MethodConfig::parse("hard", &unknown).unwrap_err().to_string();
    assert!(err.contains("kernel") && err.contains("map_size"), "{err}");
    assert!(MethodConfig::parse("nope", &BTreeMap::new()).unwrap_err().to_string().contains("unknown method"));
}

/// A method defined outside the crate, as docs/architecture.md describes
/// adding one: a type behind the `Method` trait, its WGSL (here a string, as
/// it is in no `src/` folder), and a registry entry (`method::entry`), here
/// handed to `MethodConfig::of` rather than listed in `methods::REGISTRY`.
/// It sees half the light on every surface.
mod half_light {
    use penumbra_core::frame::Frame;
    use penumbra_core::gpu::pool::{Binding, ResourcePool};
    use penumbra_core::gpu::layout;
    use penumbra_core::method::{Method, MethodOutput};
    use penumbra_core::params::{MethodParams, ParamSet, ParamSpec};
    use penumbra_core::passes::screen::ScreenPass;
    use penumbra_core::Result;

    const WGSL: &str = "
@group(0) @binding(2) var visibility_out: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(id);
    if (pixel.inside) {
        textureStore(visibility_out, pixel.px, vec4<f32>(select(0.0, 0.5, pixel.geometry), 0.0, 0.0, 0.0));
    }
}
";

    pub struct HalfLight {
        visibility: ScreenPass,
    }

    /// One parameter, declared and ignored.
    pub struct Unused;

    impl MethodParams for Unused {
        fn specs() -> Vec<ParamSpec> {
            vec![ParamSpec::float("unused", 1.0, 0.0, 2.0, "a parameter it declares and ignores")]
        }

        fn parse(_: &ParamSet) -> Result<Unused> {
            Ok(Unused)
        }
    }

    impl Method for HalfLight {
        const NAME: &'static str = "half_light";
        const PAPER: &'static str = "a test of the method interface";
        type Params = Unused;

        fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
            let source = format!("{}\n{WGSL}", penumbra_core::shaders::compose("shaders/receiver.wgsl"));
            Self { visibility: ScreenPass::per_pixel(device, pool, "half_light::visibility", source, &[layout::visibility_storage]) }
        }

        fn record(&self, frame: &mut Frame<'_>, _: &Unused) -> Result<MethodOutput> {
            let visibility = frame.ctx.screen_texture("half_light::visibility");
            frame.pass("visibility", |ctx, encoder, ts| self.visibility.run(ctx, encoder, &[Binding::Texture(&visibility)], ts))?;
            frame.stat("half_light_renders", 1);
            Ok(MethodOutput { visibility })
        }
    }
}

#[test]
fn a_method_outside_the_registry_renders_through_the_same_trait() {
    static HALF_LIGHT: penumbra_core::method::Registered = penumbra_core::method::entry::<half_light::HalfLight>();
    let Some(r) = renderer() else { return };
    let scene = Scene { meshes: vec![plane(4.0)], light: SphereLight { center: [0.0, 5.0, 0.0], radius: 0.5, intensity: [10.0; 3] }, ambient: [0.0; 3] };
    let config = MethodConfig::of(&HALF_LIGHT, &BTreeMap::new()).unwrap();
    assert_eq!(config.name(), "half_light");
    assert!(MethodConfig::of(&HALF_LIGHT, &BTreeMap::from([("unused".to_owned(), ParamValue::Float(3.0))])).is_err());
    for _ in 0..2 {
        let result = r.render(&scene, &camera(32), &config, &RenderOptions::default()).unwrap();
        let vis = result.image("visibility").unwrap().f32().unwrap();
        let ids = match &result.image("object_id").unwrap().data {
            penumbra_core::ImageData::I32(v) => v.clone(),
            _ => unreachable!(),
        };
        assert!(ids.iter().any(|&i| i == 0) && ids.iter().any(|&i| i < 0));
        for (v, id) in vis.iter().zip(&ids) {
            assert_eq!(*v, if *id >= 0 { 0.5 } else { 0.0 });
        }
        assert_eq!(result.stats["half_light_renders"], 1);
        assert_eq!(result.method, "half_light");
    }
}
