//! Method `pcss`: percentage-closer soft shadows (Fernando 2005; Cournia
//! ch. 3 surveys it, and 5.2 builds PVMF's filter on it).
//!
//! Pass 1 is the shadow map of `hard`. Pass 2, per camera pixel: a blocker
//! search over the region of the map that can hold occluders of the light
//! (its radius is the light's, scaled by `(d_r - z_near) / d_r` onto the
//! near plane), averaging the raw depths nearer than the receiver's plane
//! (`blocker_depth = "mean"`; by default the farthest of those inside the
//! cone from the receiver to the light, `BlockerDepth`);
//! no blocker means fully lit (the paper's early exit); otherwise the
//! penumbra width `w_p = (d_r - d_b) w_light / d_b` sets the diameter of a
//! percentage-closer filter (`passes/pcf_taps.wgsl` taps). Taps are disk
//! samples, since the light seen from a receiver is a disk: `sampling` =
//! `grid` is a jittered n x n grid through Shirley and Chiu's concentric map,
//! `poisson` the first n x n points of a fixed 64-point Poisson-disk set
//! (so n <= 8); both rotated per pixel by an angle fixed by `seed`. A point
//! light (radius 0) skips the search: the test of `hard`.

use crate::error::{Error, Result};
use crate::frame::{Frame, Intermediate};
use crate::gpu::layout;
use crate::gpu::pool::{Binding, ResourcePool};
use crate::method::{Method, MethodOutput};
use crate::params::{MethodParams, ParamSet, ParamSpec};
use crate::pass_cache::CachedPass;
use crate::passes::centre_map::{self, CENTRE_MAP};
use crate::passes::object_map::{self, OBJECT_MAP};
use crate::passes::samplers::{ComparisonSamplers, Filter};
use crate::passes::screen::ScreenPass;
use crate::passes::shadow_test::ShadowMapSettings;
use crate::passes::volumes::VolumePass;

/// Points in the Poisson-disk set of `methods/pcss/visibility.wgsl`.
pub const POISSON_POINTS: u32 = 64;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sampling {
    Grid,
    Poisson,
}

impl Sampling {
    const NAMES: [&'static str; 2] = ["grid", "poisson"];
}

/// Where the blocker search's taps go: `Uniform`, Fernando's, over the
/// search disk; `Scaled`, spread by scale (a tap at distance rho in the unit
/// disk goes search^rho texels out, the receiver's own texel first: as many
/// taps per octave of the search radius), so that blockers close to the
/// receiver are found where the search radius is large (`visibility.wgsl`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Search {
    Uniform,
    Scaled,
}

impl Search {
    const NAMES: [&'static str; 2] = ["scaled", "uniform"];
}

/// Which texels of the blocker search are blockers: `Plane`, the paper's,
/// those nearer the light than the receiver's plane; `Cone`, of those, the
/// ones inside the cone from the receiver to the light at their own depth
/// (the only points that can hide part of the light from it); `Behind`, of
/// the plane's, the ones whose own surface (as the map stores it, facing the
/// light) has the receiver behind it: the only surfaces a ray from the
/// receiver to the light can leave an occluder through.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlockerTest {
    Plane,
    Cone,
    Behind,
}

impl BlockerTest {
    const NAMES: [&'static str; 3] = ["plane", "cone", "behind"];

    /// The shader's code (`PcssSampling::blocker_test`).
    fn code(self) -> u32 {
        match self {
            BlockerTest::Plane => 0,
            BlockerTest::Cone => 1,
            BlockerTest::Behind => 2,
        }
    }
}

/// The blocker depth d_b of step 2 from the blockers the search found:
/// `Mean`, Fernando's, their mean depth; `ConeFarthest`, the depth of the
/// farthest from the light of those inside the cone from the receiver to
/// the light (the mean where none is): the occluder's rim as the receiver
/// sees it, not the faces between it and the light (`visibility.wgsl`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlockerDepth {
    Mean,
    ConeFarthest,
}

impl BlockerDepth {
    const NAMES: [&'static str; 2] = ["cone_farthest", "mean"];
}

#[derive(Debug, Clone, PartialEq)]
pub struct PcssParams {
    pub shadow: ShadowMapSettings,
    /// Taps per axis of the blocker search.
    pub blocker_samples: u32,
    /// Taps per axis of the percentage-closer filter.
    pub filter_samples: u32,
    pub seed: u32,
    pub filter: Filter,
    pub sampling: Sampling,
    pub blocker_test: BlockerTest,
    pub blocker_depth: BlockerDepth,
    pub search: Search,
    /// The light above the receiver's tangent plane bounds its visibility,
    /// and is all it sees where the centre has set below that plane (the
    /// silhouette methods' `horizon` repair); off: the paper's centre test.
    pub horizon: bool,
    /// The filter's estimate: the fraction of failing taps (Fernando 2005,
    /// step 3), or the part of the light their occluders hide (`"area"`).
    pub area: bool,
}

crate::gpu_type! {
    pub struct PcssUniform => "PcssSampling" in "methods/pcss/visibility.wgsl" {
        pub(crate) blocker_samples: u32,
        pub(crate) filter_samples: u32,
        pub(crate) seed: u32,
        pub(crate) poisson: u32,
        /// `BlockerTest::code`: 0 plane, 1 cone, 2 behind.
        pub(crate) blocker_test: u32,
        /// 1: `Search::Scaled`.
        pub(crate) scaled: u32,
        /// 1: `PcssParams::horizon`.
        pub(crate) horizon: u32,
        /// 1: `PcssParams::area`.
        pub(crate) area: u32,
        /// 1: `BlockerDepth::ConeFarthest`; 0: `Mean`.
        pub(crate) cone_farthest: u32,
    }
}

/// Names of the pass's counters, in order: pixels that ran the blocker
/// search, pixels that ran the filter.
pub const COUNTER_NAMES: &[&str] = &["blocker_search_pixels", "filtered_pixels"];

pub struct PercentageCloserSoftShadows {
    visibility: ScreenPass,
    object_pass: VolumePass,
}

impl MethodParams for PcssParams {
    fn specs() -> Vec<ParamSpec> {
        ShadowMapSettings::specs_and([
            ParamSpec::int("blocker_samples", 4, 1, 32, "taps per axis of the blocker search (at most 8 with 'poisson')"),
            ParamSpec::int("filter_samples", 6, 1, 32, "taps per axis of the filter (at most 8 with 'poisson')"),
            ParamSpec::seed(u32::MAX as i64, "fixes the taps' rotation and jitter"),
            Filter::spec(),
            ParamSpec::choice("sampling", "grid", &Sampling::NAMES, "disk taps: a jittered grid, or a fixed Poisson-disk set"),
            ParamSpec::choice(
                "blocker_test",
                "behind",
                &BlockerTest::NAMES,
                "blockers of the search: plane (the paper's: nearer the light than the receiver's plane), cone (and inside the cone from the receiver to the light at their depth: walls and floors beside a receiver are no blockers), behind (and the receiver lies behind the blocker's own surface, as the map stores it, in the search and for the filter's failing taps: walls and floors beside a receiver are no blockers, an occluder's texels outside the cone still are)",
            ),
            ParamSpec::choice(
                "search",
                "scaled",
                &Search::NAMES,
                "where the blocker search's taps go: scaled (the receiver's texel, then as many taps per octave of the search radius, so that blockers near the receiver are found under a large search radius), uniform (the paper's: over the search disk)",
            ),
            ParamSpec::choice(
                "blocker_depth",
                "cone_farthest",
                &BlockerDepth::NAMES,
                "the blocker depth d_b of the penumbra estimate: cone_farthest (of the blockers found, those inside the cone from the receiver to the light, the farthest from the light: the occluder's rim as the receiver sees it; the mean where none is), mean (the paper's: the mean of the blockers found)",
            ),
            ParamSpec::choice(
                "estimate",
                "pcf",
                &["pcf", "area"],
                "the filter's estimate: the fraction of failing taps (the paper's), or each failing tap weighted by the part of the light its occluder hides, within its light cone (walls beside a receiver hide none)",
            ),
            ParamSpec::bool(
                "horizon",
                true,
                "bound the visibility by the part of the light above the receiver's tangent plane, and where the light's centre has set below it give that sliver, unless another object than the receiver's own hides the centre (the object map; pvm's repair 'horizon'); false: the paper's test of the centre alone",
            ),
        ])
    }

    fn parse(p: &ParamSet) -> Result<PcssParams> {
        let params = PcssParams {
            shadow: ShadowMapSettings::from_params(p),
            blocker_samples: p.int("blocker_samples") as u32,
            filter_samples: p.int("filter_samples") as u32,
            seed: p.int("seed") as u32,
            filter: Filter::from_params(p),
            sampling: if p.choice("sampling") == "poisson" { Sampling::Poisson } else { Sampling::Grid },
            blocker_test: match p.choice("blocker_test") {
                "cone" => BlockerTest::Cone,
                "behind" => BlockerTest::Behind,
                _ => BlockerTest::Plane,
            },
            blocker_depth: if p.choice("blocker_depth") == "mean" { BlockerDepth::Mean } else { BlockerDepth::ConeFarthest },
            search: if p.choice("search") == "uniform" { Search::Uniform } else { Search::Scaled },
            horizon: p.bool("horizon"),
            area: p.choice("estimate") == "area",
        };
        if params.sampling == Sampling::Poisson {
            for (name, n) in [("blocker_samples", params.blocker_samples), ("filter_samples", params.filter_samples)] {
                if n * n > POISSON_POINTS {
                    return Err(Error::InvalidParameter(format!(
                        "parameter '{name}' of method 'pcss' must be at most 8 with sampling 'poisson' \
                         (its set has {POISSON_POINTS} points), got {n}"
                    )));
                }
            }
        }
        Ok(params)
    }
}

impl Method for PercentageCloserSoftShadows {
    const NAME: &'static str = "pcss";
    const PAPER: &'static str = "percentage-closer soft shadows (Fernando 2005): blocker search, penumbra estimate, variable PCF";
    type Params = PcssParams;

    fn cached_passes() -> &'static [CachedPass] {
        &[CENTRE_MAP, OBJECT_MAP]
    }

    fn new(device: &wgpu::Device, pool: &ResourcePool) -> Self {
        // Reads the map (through its sampler), the test and sampling blocks;
        // writes visibility, penumbra width, blocker depth and the counters.
        let bindings = object_map::with_bindings(&[
            layout::depth_array, layout::comparison_sampler, layout::parameters, layout::parameters,
            layout::visibility_storage, layout::visibility_storage, layout::visibility_storage, layout::storage_buffer_rw,
        ]);
        let visibility = ScreenPass::per_pixel(device, pool, "pcss::visibility_pass", crate::shader!("visibility.wgsl"), &bindings);
        Self { visibility, object_pass: object_map::pass(device, pool) }
    }

    /// Blocker search, penumbra estimate and filter per G-buffer pixel.
    fn record(&self, frame: &mut Frame<'_>, params: &PcssParams) -> Result<MethodOutput> {
        let (map, projection) = centre_map::centre_map(frame, &params.shadow)?;
        let objects = object_map::record_if(frame, params.horizon && frame.ctx.light.radius > 0.0, &self.object_pass, &projection, params.shadow.map_size)?;
        let visibility = frame.ctx.screen_texture("pcss::visibility");
        // Estimated penumbra width in map texels and mean blocker depth in
        // world units (camera space, 0 where not computed).
        let penumbra_width = frame.ctx.screen_texture("pcss::penumbra_width");
        let blocker_depth = frame.ctx.screen_texture("pcss::blocker_depth");
        let counters = frame.pass("visibility", |ctx, encoder, ts| {
            let counters = ctx.counters("pcss::counters", COUNTER_NAMES.len(), encoder);
            let test = ctx.parameters(
                "pcss::shadow_test_uniforms",
                &params.shadow.uniform(&projection, ctx.light.center_f32, ctx.light.radius_f32, 0),
            );
            let sampling = PcssUniform {
                blocker_samples: params.blocker_samples,
                filter_samples: params.filter_samples,
                seed: params.seed,
                poisson: u32::from(params.sampling == Sampling::Poisson),
                blocker_test: params.blocker_test.code(),
                scaled: u32::from(params.search == Search::Scaled),
                horizon: u32::from(params.horizon),
                area: u32::from(params.area),
                cone_farthest: u32::from(params.blocker_depth == BlockerDepth::ConeFarthest),
            };
            let sampling = ctx.parameters("pcss::sampling_uniforms", &sampling);
            let samplers = ComparisonSamplers::shared(ctx.device, ctx.pool);
            let resources = [
                Binding::Texture(&map),
                samplers.binding(params.filter),
                Binding::Buffer(&test),
                Binding::Buffer(&sampling),
                Binding::Texture(&visibility),
                Binding::Texture(&penumbra_width),
                Binding::Texture(&blocker_depth),
                Binding::Buffer(&counters),
            ];
            self.visibility.run(ctx, encoder, &objects.after(&resources), ts);
            counters
        })?;
        frame.counters(&counters, COUNTER_NAMES);
        frame.intermediate(Intermediate::color("pcss_penumbra_width", &penumbra_width, 1))?;
        frame.intermediate(Intermediate::color("pcss_blocker_depth", &blocker_depth, 1))?;
        Ok(MethodOutput { visibility })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ParamValue;
    use std::collections::BTreeMap;

    /// The Poisson-disk set as the shader holds it.
    fn poisson_disk() -> Vec<[f32; 2]> {
        let src = include_str!("visibility.wgsl");
        let start = src.find("var<private> poisson_disk").expect("the set is in the shader");
        let body = &src[start..src[start..].find(");").unwrap() + start];
        body.split("vec2<f32>(")
            .skip(1)
            .map(|s| {
                let mut xy = s.split(')').next().unwrap().split(',').map(|v| v.trim().parse::<f32>().unwrap());
                [xy.next().unwrap(), xy.next().unwrap()]
            })
            .collect()
    }

    #[test]
    fn poisson_disk_prefixes_are_spread_in_the_unit_disk() {
        let points = poisson_disk();
        assert_eq!(points.len(), POISSON_POINTS as usize);
        assert!(points.iter().all(|p| p[0].hypot(p[1]) <= 1.0));
        // Every n x n prefix keeps its points apart by a fair share of the
        // disk: at least 0.6 / n (a hexagonal packing of n^2 points in the unit
        // disk spaces them about 1.9 / n apart).
        for n in 2..=8usize {
            let prefix = &points[..n * n];
            let min = prefix
                .iter()
                .enumerate()
                .flat_map(|(i, a)| prefix[i + 1..].iter().map(move |b| (a[0] - b[0]).hypot(a[1] - b[1])))
                .fold(f32::INFINITY, f32::min);
            assert!(min > 0.6 / n as f32, "n = {n}: nearest pair {min}");
        }
    }

    #[test]
    fn poisson_sampling_is_limited_to_its_set() {
        let mut params = BTreeMap::new();
        params.insert("sampling".to_string(), ParamValue::Str("poisson".into()));
        params.insert("filter_samples".to_string(), ParamValue::Int(9));
        let err = crate::methods::MethodConfig::parse("pcss", &params).unwrap_err().to_string();
        assert!(err.contains("filter_samples") && err.contains("at most 8"), "{err}");
        params.insert("filter_samples".to_string(), ParamValue::Int(8));
        let set = ParamSet::parse("pcss", &PcssParams::specs(), &params).unwrap();
        assert_eq!(PcssParams::parse(&set).unwrap().filter_samples, 8);
    }
}
