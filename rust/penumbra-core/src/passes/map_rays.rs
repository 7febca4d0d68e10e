//! The map bound (beyond the papers, issue 28) that `pvm`, `wedges` and `pvmf`
//! share: rays from a pixel to points of the light's disk followed through
//! the centre's shadow map (passes/map_rays.wgsl), and their parameters.

use crate::params::{ParamSet, ParamSpec};

/// `pvm`'s `map_samples` default: 32 points since issue 28's stop 64, with
/// `map_bound = "solid"` (16 before: docs/methods/pvm.md has both). `wedges`
/// takes 32 too (`methods/wedges/mod.rs`), `pvmf` 16.
pub const SAMPLES_DEFAULT: i64 = 32;
/// `map_march`'s default: 8 light depths (4 and 16 did worse: docs/methods/pvm.md).
pub const MARCH_DEFAULT: i64 = 8;

/// `map_solids`' default.
pub const SOLIDS_DEFAULT: bool = true;

/// `map_samples`, `map_bound`, `map_march` and `map_solids`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MapBound {
    /// Points of the light's disk whose rays are followed (0: no bound).
    pub samples: u32,
    /// `map_bound = "both"`: where the map sees the light's centre, the
    /// visibility is also at least the rays' fraction less the margin;
    /// `"upper"`: at most the fraction plus it, only.
    pub both: bool,
    /// `map_bound = "solid"`: `both`, and also where the surface hiding the
    /// light's centre is a solid caster's front (`solid_in_front` in
    /// passes/map_rays.wgsl; needs `map_solids` and `map_march` > 0).
    pub solid: bool,
    /// Light depths at which a ray the map's search leaves seen is sampled
    /// again (`ray_marched_hidden`; 0: the search alone).
    pub march: u32,
    /// `map_solids`: rays passing inside a solid caster behind the map's
    /// surface are hidden (passes/solid_layers.rs).
    pub solids: bool,
}

impl MapBound {
    /// The three parameters; `samples` is the method's default number of
    /// points, `samples_doc` says what the bound bounds and what 0 leaves
    /// (the method's own visibility).
    pub fn specs(samples: i64, samples_doc: &'static str) -> [ParamSpec; 4] {
        [
            ParamSpec::int("map_samples", samples, 0, 256, samples_doc),
            // Where the map sees the light's centre, an edge model may hide
            // more of the light than the caster does (the far tip of a
            // grazing shadow, where the caster ends along its edge), and so
            // it may where it hides it. There the rays are trusted to raise
            // the visibility only behind a solid caster's front whose
            // layers hold every surface behind it ("solid", the default
            // since issue 28's stop 64): a surface the map cannot see (a
            // boot's toe seen from below, generated seed 38; the inside of
            // an open shell) leaves them seen, and "both" before the solid
            // layers lit such umbrae (docs/methods/pvm.md).
            ParamSpec::choice(
                "map_bound",
                "solid",
                &["upper", "both", "solid"],
                "with map_samples > 0: upper, the visibility is at most the map's fraction plus 1.2 n^-0.7 and the texel band (the share of the light whose rays pass within a map texel of the occluder's outline); both, and where the shadow map sees the light's centre, at least the fraction less that; solid, both, and also where the surface hiding the light's centre is the front of a closed caster whose layers (map_solids) hold every surface behind it on the centre's ray (with map_march > 0; else as both)",
            ),
            // The search jumps from surface to surface as the map shows them
            // and passes by what lies between: the rays' seen fraction errs
            // high (docs/methods/pvm.md).
            ParamSpec::int(
                "map_march",
                MARCH_DEFAULT,
                0,
                64,
                "with map_samples > 0: a ray the shadow map's surface-to-surface search leaves seen is sampled again at this many light depths, from the pixel to the map's near plane, and hidden where a sample lies just behind the map's surface; 0: the search alone",
            ),
            // The map holds the first surface alone: a ray behind it through
            // a body it cannot see (a boot under a floating cube; the floor
            // at a resting mesh's contact) was taken for seen, and the umbra
            // lit (docs/methods/wedges.md).
            ParamSpec::bool(
                "map_solids",
                SOLIDS_DEFAULT,
                "with map_samples > 0: the rays are also hidden where they pass inside a closed caster that does not hold the light, as the first four of such casters' surfaces along the light centre's rays show (one more raster pass from the light)",
            ),
        ]
    }

    pub fn parse(p: &ParamSet) -> Self {
        Self {
            // Within the specs' ranges.
            samples: p.int("map_samples").clamp(0, 256) as u32,
            both: matches!(p.choice("map_bound"), "both" | "solid"),
            // The search alone passes by surfaces (its seen fraction errs
            // high, most in the inner penumbra, where the map hides the
            // centre): without the march its rays lifted a straight edge's
            // exact k (tests/test_pvm.py's straight edges), and "solid"
            // raises no more than "both".
            solid: p.choice("map_bound") == "solid" && p.int("map_march") > 0,
            march: p.int("map_march").clamp(0, 64) as u32,
            solids: p.bool("map_solids"),
        }
    }

    /// The shadow test's `mode.z` and `mode.w` (passes/map_rays.wgsl's `n`
    /// and `march`).
    pub fn mode(&self) -> [u32; 2] {
        [self.samples, self.march]
    }
}
