//! The shadow-map test from a light point with its bias schemes, shared by
//! every shadow-map method (its WGSL is `shadow_test.wgsl` beside this file).
//!
//! Bias (Cournia ch. 3 surveys the options). The default, `slope`, offsets the
//! receiver's lookup along its normal by `normal_offset` texels and subtracts
//! `constant_bias + slope_bias * tan(theta)` texels of depth, where a texel is
//! the map's footprint at the receiver's light depth. Both terms scale with
//! the texel, so they remove acne at any map size and scene scale while
//! moving the shadow boundary by about one texel, which is below the visible
//! light leak of a fixed world-space bias. `second_depth` (Wang and Molnar
//! 1994, Cournia 5.5) needs no bias but only works for closed casters;
//! `midpoint` (Woo 1992) compares against the depth half-way between the
//! first and second surfaces, also without bias; `none` shows the raw acne.

use crate::error::{Error, Result};
use crate::light_frustum::{LightProjection, ProjectionMode};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::passes::shadow_map::{LightSpaceUniform, MapDepth};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BiasMode {
    Slope,
    SecondDepth,
    Midpoint,
    None,
}

impl BiasMode {
    pub const NAMES: [&'static str; 4] = ["slope", "second_depth", "midpoint", "none"];

    pub fn name(self) -> &'static str {
        match self {
            BiasMode::Slope => "slope",
            BiasMode::SecondDepth => "second_depth",
            BiasMode::Midpoint => "midpoint",
            BiasMode::None => "none",
        }
    }

    fn parse(name: &str) -> Self {
        match name {
            "second_depth" => BiasMode::SecondDepth,
            "midpoint" => BiasMode::Midpoint,
            "none" => BiasMode::None,
            _ => BiasMode::Slope,
        }
    }

    /// The surface the shadow map stores for this scheme.
    pub fn map_depth(self) -> MapDepth {
        match self {
            BiasMode::SecondDepth => MapDepth::Second,
            BiasMode::Midpoint => MapDepth::Midpoint,
            _ => MapDepth::First,
        }
    }
}

/// The shadow map and its test, as every shadow-map method takes them.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowMapSettings {
    /// Texels per side; 0 for `"auto"` until the renderer resolves it
    /// ([`crate::map_size`]) before the method records.
    pub map_size: u32,
    /// Which projection the maps use (SPEC section 3).
    pub projection: ProjectionMode,
    pub bias: BiasMode,
    pub normal_offset: f32,
    pub constant_bias: f32,
    pub slope_bias: f32,
}

/// The parameters of the map and its test, as every shadow-map method takes
/// them (`hard` takes these alone).
impl MethodParams for ShadowMapSettings {
    fn specs() -> Vec<ParamSpec> {
        vec![
            ParamSpec::map_size(
                "map_size",
                2048,
                16,
                16384,
                "shadow-map resolution in texels per side (per face for cube maps); 'auto': a texel no larger than a pixel on the visible receivers (stats['map_size'] is the size chosen; docs/scaling.md: faster, and within noise of 2048 on the built-in scenes at 128 px, but not on real meshes with small lights)",
            ),
            ParamSpec::choice(
                "projection",
                "auto",
                &ProjectionMode::NAMES,
                "shadow maps over one frustum fitted around the casters and the penumbrae they may cast, six cube faces, or the frustum where it covers them within 80 degrees and the cube elsewhere",
            ),
            ParamSpec::choice("bias", "slope", &BiasMode::NAMES, "acne control of the shadow-map test"),
            ParamSpec::float("normal_offset", 1.0, 0.0, 100.0, "receiver offset along its normal, texels (slope bias)"),
            ParamSpec::float("constant_bias", 0.5, 0.0, 100.0, "constant depth bias, texels (slope bias)"),
            ParamSpec::float("slope_bias", 1.0, 0.0, 100.0, "depth bias per unit tan(theta), texels (slope bias)"),
        ]
    }

    fn parse(set: &ParamSet) -> Result<Self> {
        Ok(Self::from_params(set))
    }
}

/// Largest tan(theta) the slope term uses: beyond ~84 degrees the receiver is
/// nearly edge-on to the light and its irradiance is almost zero anyway.
const MAX_SLOPE: f32 = 10.0;

impl ShadowMapSettings {
    /// A method's parameters: those of the map and its test
    /// ([`MethodParams::specs`]) and then the method's own.
    pub fn specs_and(own: impl IntoIterator<Item = ParamSpec>) -> Vec<ParamSpec> {
        let mut specs = Self::specs();
        specs.extend(own);
        specs
    }

    pub fn from_params(p: &ParamSet) -> Self {
        Self {
            map_size: p.int_or_auto("map_size").unwrap_or(0) as u32,
            projection: ProjectionMode::parse(p.choice("projection")),
            bias: BiasMode::parse(p.choice("bias")),
            normal_offset: p.float("normal_offset") as f32,
            constant_bias: p.float("constant_bias") as f32,
            slope_bias: p.float("slope_bias") as f32,
        }
    }

    /// Refuses a map larger than the adapter's largest texture.
    pub fn check_limits(&self, max_texture_side: u32) -> Result<()> {
        if self.map_size == 0 {
            return Err(Error::InvalidParameter("map_size 'auto' reached a method unresolved (a bug of penumbra: the renderer resolves it)".into()));
        }
        if self.map_size > max_texture_side {
            return Err(Error::InvalidParameter(format!(
                "map_size {} exceeds this adapter's largest texture side, {max_texture_side}",
                self.map_size
            )));
        }
        Ok(())
    }

    /// The `ShadowTest` block of `shadow_test.wgsl`.
    pub fn uniform(&self, projection: &LightProjection, center: [f32; 3], radius: f32, flags: u32) -> ShadowTestUniform {
        let mode = match self.bias {
            BiasMode::Slope => 0,
            BiasMode::SecondDepth => 1,
            BiasMode::None => 2,
            BiasMode::Midpoint => 3,
        };
        ShadowTestUniform {
            light_space: LightSpaceUniform::new(projection, self.map_size),
            center: [center[0], center[1], center[2], radius],
            bias: [self.normal_offset, self.constant_bias, self.slope_bias, MAX_SLOPE],
            mode: [mode, flags, 0, 0],
        }
    }
}

crate::gpu_type! {
    pub struct ShadowTestUniform => "ShadowTest" in "passes/shadow_test.wgsl" {
        pub light_space: LightSpaceUniform,
        pub center: [f32; 4],
        pub bias: [f32; 4],
        pub mode: [u32; 4],
    }
}

impl ShadowTestUniform {
    /// The method-specific fourth component of `center` (PVM: the light's radius;
    /// `reference`: the sample's weight).
    pub fn set_center_w(&mut self, w: f32) {
        self.center[3] = w;
    }
}
