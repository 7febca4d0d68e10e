//! penumbra-core: headless soft-shadow rendering with wgpu. No Python here;
//! `penumbra-py` binds it.

pub mod error;
pub mod casters;
pub mod frame;
pub mod geometry_cache;
pub mod gpu;
pub mod image_io;
pub mod light_frustum;
pub mod light_sampling;
pub mod map_size;
pub mod method;
pub mod methods;
pub mod occluders;
pub mod params;
pub mod pass_cache;
pub mod passes;
pub mod renderer;
pub mod scene;
pub mod shaders;
pub mod silhouettes;
pub mod topology;

pub use error::{Error, Result};
pub use gpu::{adapter_summary, AdapterSummary, TimingMode, TimingSource, Timings};
pub use methods::{methods, MethodConfig, REGISTRY};
pub use params::{ParamKind, ParamSpec, ParamValue};
pub use renderer::{Image, ImageData, Outputs, RenderOptions, RenderResult, Renderer, OUTPUTS};
pub use scene::{Camera, Mesh, Scene, SphereLight};
