//! Light sampling shared by the sampling methods (`reference`, `adaptive`,
//! `raytraced`, `triangle_masks`): stratified jittered grids (Herf 4.5.1),
//! points on the light's disk (Shirley and Chiu's concentric map) and on its
//! sphere with solid-angle weights, and the cap of the sphere the scene can
//! see. `raytraced` is the in-engine truth: it and `reference` take their
//! samples from here, so a change to one method cannot silently move the
//! other's samples.

use glam::{DVec2, DVec3};

use crate::scene::{Camera, PreparedScene};

/// Where the samples lie: jittered in their strata (fixed by a seed), or
/// on the regular grid through the square's corners.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Strata {
    Jittered(u64),
    Centred,
}

impl From<u64> for Strata {
    fn from(seed: u64) -> Self {
        Strata::Jittered(seed)
    }
}

impl Strata {
    /// Another, uncorrelated jitter for a second set of samples.
    pub fn other(self) -> Self {
        match self {
            Strata::Jittered(seed) => Strata::Jittered(seed ^ 0xA5A5_5A5A),
            Strata::Centred => Strata::Centred,
        }
    }
}

/// SplitMix64: a small, well-mixed generator; the samples only need to be
/// deterministic for a seed and uncorrelated across cells.
struct SplitMix(u64);

impl SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Shirley and Chiu's concentric map from the unit square to the unit disk:
/// area-preserving, so a stratified square stays stratified on the disk.
fn concentric_disk(u: DVec2) -> DVec2 {
    let a = 2.0 * u - DVec2::ONE;
    if a == DVec2::ZERO {
        return DVec2::ZERO;
    }
    let (r, phi) = if a.x.abs() > a.y.abs() {
        (a.x, std::f64::consts::FRAC_PI_4 * (a.y / a.x))
    } else {
        (a.y, std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (a.x / a.y))
    };
    DVec2::new(r * phi.cos(), r * phi.sin())
}

/// A stratified grid of at least `n` points in the unit square (Herf
/// 4.5.1): `ceil(sqrt(n))` columns, as many rows as needed, each point
/// jittered in its cell; or, `Strata::Centred`, the regular grid of as many
/// columns and rows through the square's corners (`i / (k - 1)`; one column
/// or row sits at 1/2).
pub fn jittered_grid(n: u32, strata: impl Into<Strata>) -> Vec<DVec2> {
    let columns = (n as f64).sqrt().ceil().max(1.0) as u32;
    let rows = n.div_ceil(columns);
    let mut rng = match strata.into() {
        Strata::Jittered(seed) => Some(SplitMix(seed ^ 0x005E_ED0F_9E37)),
        Strata::Centred => None,
    };
    // k > 1 points through both ends, i / (k - 1); a single one at the middle.
    let regular = |i: u32, k: u32| if k > 1 { i as f64 / (k - 1) as f64 } else { 0.5 };
    let mut out = Vec::with_capacity((columns * rows) as usize);
    for j in 0..rows {
        for i in 0..columns {
            out.push(match rng.as_mut() {
                Some(rng) => DVec2::new((i as f64 + rng.next_f64()) / columns as f64, (j as f64 + rng.next_f64()) / rows as f64),
                None => DVec2::new(regular(i, columns), regular(j, rows)),
            });
        }
    }
    out
}

/// One light sample: its position; for `sphere` sampling the sphere's outward
/// unit normal there (None: equal weights); and its weight: 1/n for equal
/// weights, else the inverse of the density the samples were drawn with
/// (`sphere_samples`), which the shader multiplies by the solid-angle factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightSample {
    pub position: DVec3,
    pub normal: Option<DVec3>,
    pub weight: f64,
}

/// Stratified jittered points on the disk of `radius` around `center`
/// spanned by the unit vectors `basis` (perpendicular to the axis towards
/// the scene: [`camera_basis`], or any frame where nothing turns). A radius
/// of 0 gives the centre once.
pub fn light_samples(center: DVec3, radius: f64, basis: (DVec3, DVec3), n: u32, strata: impl Into<Strata>) -> Vec<DVec3> {
    if radius == 0.0 {
        return vec![center];
    }
    jittered_grid(n, strata).into_iter().map(|u| disk_point(center, radius, basis, u)).collect()
}

/// The point `u` of the unit square on the disk of `radius` around `center`
/// spanned by the unit vectors `basis` (the concentric map).
pub fn disk_point(center: DVec3, radius: f64, (e1, e2): (DVec3, DVec3), u: DVec2) -> DVec3 {
    let d = concentric_disk(u) * radius;
    center + e1 * d.x + e2 * d.y
}

/// Stratified jittered points on the light's sphere (`center`, `radius`) for
/// receivers that see at most the cap around `axis` (unit, towards the scene)
/// of polar angle `acos(cos_max)` (`visible_cap_cos`, at least a hemisphere),
/// with their normals and weights. Two stratified sets, each through Shirley
/// and Chiu's area-preserving concentric map of a jittered grid:
///
/// - about 7/8 of the samples cosine-distributed on the hemisphere facing the
///   scene (the disk lifted onto it, Malley's method): for a receiver on the
///   axis these are the `disk` samples, as well stratified;
/// - about 1/8 uniform over the whole cap (Lambert's azimuthal map
///   `z = 1 - rho^2 (1 - cos_max)`), for what off-axis receivers see beyond
///   the hemisphere and so that no weight is unbounded near its rim.
///
/// A light seen from every side (`cos_max = -1`: a room around it, see
/// [`visible_cap_cos_of`]) gets half of its samples uniform over the
/// whole sphere (measured on the scenes of `penumbra bench --config
/// benchmarks/omnidirectional.toml`: penumbra RMSE at 64 samples against
/// Mitsuba, 1/8 uniform, 1/2, all uniform: Sponza 0.238, 0.106,
/// 0.101; Cornell box 0.042, 0.029, 0.050; wide floor 0.027, 0.027, 0.062).
///
/// Each sample's weight is 1 / (n_c p_c(s) + n_u p_u(s)), the balance
/// heuristic over both sets (Veach's multi-sample estimator), with
/// p_c = max(cos_a, 0) / pi and p_u = 1 / (2 pi (1 - cos_max)) per unit area
/// of the unit sphere: the weighted sum of the solid-angle factors estimates
/// the solid angle each receiver sees. A radius of 0 gives the centre once.
pub fn sphere_samples(center: DVec3, radius: f64, axis: DVec3, cos_max: f64, n: u32, strata: impl Into<Strata>) -> Vec<LightSample> {
    if radius == 0.0 {
        return vec![LightSample { position: center, normal: None, weight: 1.0 }];
    }
    let strata = strata.into();
    let cos_max = cos_max.clamp(-1.0, 0.0);
    let (e1, e2) = axis.any_orthonormal_pair();
    // A light the scene surrounds is seen from every side: no
    // hemisphere faces all receivers, and the cosine set would leave those
    // beside or above it with few samples. Half are then uniform.
    let surrounded = cos_max <= -1.0;
    let n_u = if surrounded { n.div_ceil(2).max(1) } else { n.div_ceil(8).max(1) };
    let cosine = if n > n_u { jittered_grid(n - n_u, strata) } else { Vec::new() };
    let uniform = jittered_grid(n_u, strata.other());
    let (count_c, count_u) = (cosine.len() as f64, uniform.len() as f64);
    let frame = |d: DVec2, z: f64, scale: f64| (axis * z + (e1 * d.x + e2 * d.y) * scale).normalize();
    let normals = cosine
        .into_iter()
        .map(|u| {
            let d = concentric_disk(u);
            // |d| <= 1 up to rounding; the lift is unit length by construction.
            frame(d, (1.0 - d.length_squared()).max(0.0).sqrt(), 1.0)
        })
        .chain(uniform.into_iter().map(|u| {
            let d = concentric_disk(u);
            let z = 1.0 - d.length_squared().min(1.0) * (1.0 - cos_max);
            // sin(theta)^2 = (1 - z)(1 + z) = rho^2 (1 - cos_max)(1 + z), and d / rho
            // is the azimuth's unit vector: the tangential part is d times
            // sqrt((1 - cos_max)(1 + z)), with no division (finite at the pole).
            frame(d, z, ((1.0 - cos_max) * (1.0 + z)).max(0.0).sqrt())
        }));
    // 1 - cos_max >= 1 (the cap holds a hemisphere): p_u is finite.
    let p_u = 1.0 / (std::f64::consts::TAU * (1.0 - cos_max));
    normals
        .map(|normal| {
            let p_c = normal.dot(axis).max(0.0) / std::f64::consts::PI;
            // count_u >= 1 and p_u > 0: the density is positive everywhere.
            let density = count_c * p_c + count_u * p_u;
            LightSample { position: center + normal * radius, normal: Some(normal), weight: 1.0 / density }
        })
        .collect()
}

/// The cosine of the polar angle (around `axis`, the direction from the light
/// centre to the scene's bounding-sphere centre at distance `distance`) of
/// the cap holding every point of the light that a point of the scene (its
/// bounding sphere of radius `bound`) can see. A point `p` sees the points
/// within `acos(r / |p - c|) < 90` degrees of the direction to it, and that
/// direction is within `asin(bound / distance)` of `axis`: the cap's
/// half-angle is at most 90 degrees plus that, the whole sphere when the
/// light is inside the bounding sphere.
pub fn visible_cap_cos(distance: f64, bound: f64) -> f64 {
    // Written so that a NaN distance or bound also gives the whole sphere.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(distance > bound) {
        return -1.0;
    }
    let spread = (bound / distance).clamp(0.0, 1.0).asin();
    (std::f64::consts::FRAC_PI_2 + spread).min(std::f64::consts::PI).cos()
}

/// The cosine of the polar angle around `axis` of the cap holding every
/// point of the light (centre `center`, radius `radius`) that a point of the
/// scene's triangles (corners `points`) can see: at most
/// [`visible_cap_cos`]'s bounding-sphere cap, and tighter when the triangles
/// lie in a narrower cone. If every corner is within `theta < 90` degrees of
/// `axis`, so is every point of the triangles (the cone is convex), and a
/// point sees the light within 90 degrees of its direction: the cap's
/// half-angle is `theta + 90` degrees, `cos = -sin(theta)`. A corner at or
/// beyond 90 degrees (a room around the light: the cone is not convex), or
/// inside the light, gives the whole sphere. So a floor wider than the light
/// is high, whose bounding sphere holds the light, keeps the facing
/// hemisphere's cosine samples.
pub fn visible_cap_cos_of(center: DVec3, radius: f64, axis: DVec3, distance: f64, bound: f64, points: impl IntoIterator<Item = DVec3>) -> f64 {
    let sphere = visible_cap_cos(distance, bound);
    let mut sin_max = 0.0f64;
    for p in points {
        let d = p - center;
        let length = d.length();
        // A corner inside the light (or a NaN one) sees it from every side.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(length > radius) || length == 0.0 {
            return -1.0;
        }
        // length > 0: the division is finite.
        let cos = d.dot(axis) / length;
        if cos <= 0.0 {
            return -1.0;
        }
        sin_max = sin_max.max((1.0 - cos * cos).max(0.0).sqrt());
    }
    sphere.max(-sin_max)
}

/// The unit direction from the light's centre to the centre of the scene's
/// bounding box: the axis the samples are placed around. Where the two
/// (nearly) coincide (within 1e-3 of the box's half-diagonal: a light in a
/// room's middle), that direction is rounding noise, and a rotated copy of
/// the scene would get another: the camera's view direction then, which
/// turns with the scene (issue 31; straight down where the camera has none).
pub fn scene_axis(center: DVec3, scene: &PreparedScene, camera: &Camera) -> DVec3 {
    let scene_center = ((scene.bounds_min + scene.bounds_max) * 0.5).as_dvec3();
    let half = ((scene.bounds_max - scene.bounds_min) * 0.5).as_dvec3().length();
    let to_center = scene_center - center;
    if to_center.length() > 1e-3 * half {
        if let Some(axis) = to_center.try_normalize() {
            return axis;
        }
    }
    let eye = DVec3::from(camera.eye.map(f64::from));
    (DVec3::from(camera.target.map(f64::from)) - eye).try_normalize().unwrap_or(DVec3::NEG_Y)
}

/// Unit vectors `(e1, e2)` spanning the plane perpendicular to `axis` (unit),
/// fixed by the camera rather than by the world's axes: `e1` along the
/// camera's view direction with its `axis` part removed (its right vector
/// where the view runs along `axis`), `e2 = axis x e1`. Turning the whole
/// scene, camera and light included, turns this frame with it, which
/// `any_orthonormal_pair` (built from the world axes) does not: the points a
/// method places on the light with it then stay where they were on the scene
/// (issue 31: `adaptive`'s four corner points, which decide its quadtree).
pub fn camera_basis(axis: DVec3, camera: &Camera) -> (DVec3, DVec3) {
    let eye = DVec3::from(camera.eye.map(f64::from));
    let forward = (DVec3::from(camera.target.map(f64::from)) - eye).try_normalize().unwrap_or(DVec3::NEG_Z);
    let up = DVec3::from(camera.up.map(f64::from));
    let right = forward.cross(up).try_normalize().unwrap_or_else(|| forward.any_orthonormal_vector());
    let reject = |v: DVec3| v - axis * v.dot(axis);
    // forward and right are orthonormal: when forward is within 0.06 degrees
    // of axis (|rejection|^2 < 1e-6), right is within as much of the plane,
    // so its rejection has length about 1 and normalises safely.
    let f = reject(forward);
    let e1 = if f.length_squared() >= 1e-6 { f.normalize() } else { reject(right).try_normalize().unwrap_or_else(|| axis.any_orthonormal_vector()) };
    (e1, axis.cross(e1))
}

/// [`sphere_samples`] of the light (`center`, `radius`) for the receivers of
/// `scene`: around [`scene_axis`], over the cap [`visible_cap_cos_of`] gives
/// for the scene's corners. Shared by `reference` and `raytraced`.
pub fn scene_sphere_samples(center: DVec3, radius: f64, scene: &PreparedScene, camera: &Camera, n: u32, strata: impl Into<Strata>) -> Vec<LightSample> {
    let scene_center = ((scene.bounds_min + scene.bounds_max) * 0.5).as_dvec3();
    let bound = ((scene.bounds_max - scene.bounds_min) * 0.5).as_dvec3().length();
    let axis = scene_axis(center, scene, camera);
    let corners = scene.meshes.iter().flat_map(|m| m.vertices.iter().copied());
    let cos_max = visible_cap_cos_of(center, radius, axis, (scene_center - center).length(), bound, corners);
    sphere_samples(center, radius, axis, cos_max, n, strata)
}

/// The default `ray_offset` of the shadow-segment methods (`raytraced`,
/// `triangle_masks`). `penumbra bench --config benchmarks/ray_offsets.toml` (point light
/// against CPU ray casting, `hard`'s bias scenes and five real meshes at
/// 128x128): no acne from 1e-6 up, one pixel (of spot) at 1e-7, hundreds at
/// 0; light leaks at 1e-3 (3 pixels of the bunny). The default keeps a
/// factor of 100 from acne and of 100 from leaks.
pub const DEFAULT_RAY_OFFSET: f64 = 1e-5;

crate::gpu_type! {
    /// Layout of `LightSample` in `shaders/light_samples.wgsl` (the samples
    /// `raytraced` and `triangle_masks` upload).
    pub struct SampleUniform => "LightSample" in "shaders/light_samples.wgsl" {
        /// The point on the light (xyz) and its weight (w).
        pub(crate) position: [f32; 4],
        /// The sphere's outward unit normal there (xyz); w = 1 for solid-angle weights, 0 for equal weights.
        pub(crate) normal: [f32; 4],
    }
}

impl From<&LightSample> for SampleUniform {
    fn from(s: &LightSample) -> Self {
        let p = s.position.as_vec3();
        let n = s.normal.unwrap_or(DVec3::ZERO).as_vec3();
        Self {
            position: [p.x, p.y, p.z, s.weight as f32],
            normal: [n.x, n.y, n.z, if s.normal.is_some() { 1.0 } else { 0.0 }],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_fill_the_disk_evenly_and_deterministically() {
        let c = DVec3::new(1.0, 5.0, 0.0);
        let axis = DVec3::NEG_Y;
        let basis = axis.any_orthonormal_pair();
        let s = light_samples(c, 0.5, basis, 256, 7);
        assert_eq!(s.len(), 256);
        assert!(s.iter().all(|p| (*p - c).length() <= 0.5 + 1e-12 && (*p - c).dot(axis).abs() < 1e-12));
        // Stratified: the mean is near the centre and each quadrant holds a quarter.
        let mean = s.iter().copied().sum::<DVec3>() / 256.0;
        assert!((mean - c).length() < 0.01, "{mean}");
        let q = s.iter().filter(|p| p.x > c.x && p.z > c.z).count();
        assert!((56..=72).contains(&q), "{q}");
        assert_eq!(s, light_samples(c, 0.5, basis, 256, 7));
        assert_ne!(s, light_samples(c, 0.5, basis, 256, 8));
        assert_eq!(light_samples(c, 0.0, basis, 256, 7), vec![c]);
        assert_eq!(light_samples(c, 0.5, basis, 10, 7).len(), 12, "rounded up to a 4 x 3 grid");
    }

    #[test]
    fn the_camera_basis_turns_with_the_scene_and_survives_a_view_along_the_axis() {
        use glam::DQuat;
        let camera = Camera { eye: [3.0, 2.0, 4.0], target: [0.0, 0.5, 0.0], up: [0.0, 1.0, 0.0], fov_y_degrees: 45.0, width: 8, height: 8 };
        let axis = DVec3::new(0.2, -1.0, 0.1).normalize();
        let (e1, e2) = camera_basis(axis, &camera);
        for (a, b) in [(e1, e1), (e2, e2), (e1, axis), (e2, axis), (e1, e2)] {
            let want = if a == b { 1.0 } else { 0.0 };
            assert!((a.dot(b) - want).abs() < 1e-12);
        }
        assert!((e1.cross(e2) - axis).length() < 1e-12, "right-handed");
        let q = DQuat::from_euler(glam::EulerRot::XYZ, 0.52, 0.35, -0.2);
        let turn = |p: [f32; 3]| (q * DVec3::from(p.map(f64::from))).as_vec3().to_array();
        let turned = Camera { eye: turn(camera.eye), target: turn(camera.target), up: turn(camera.up), ..camera };
        let (t1, t2) = camera_basis(q * axis, &turned);
        assert!((t1 - q * e1).length() < 1e-6 && (t2 - q * e2).length() < 1e-6, "the frame turns with the scene");
        // Looking straight along the axis: the right vector takes over.
        let along = Camera { eye: [0.0, 5.0, 0.0], target: [0.0, 0.0, 0.0], up: [0.0, 0.0, -1.0], ..camera };
        let (a1, a2) = camera_basis(DVec3::NEG_Y, &along);
        assert!(a1.is_finite() && (a1.length() - 1.0).abs() < 1e-12 && a1.dot(DVec3::Y).abs() < 1e-12);
        assert!((a2.length() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn the_axis_of_a_light_at_the_scene_centre_is_the_camera_view_and_turns_with_the_scene() {
        use crate::scene::tests::{quad, scene};
        use glam::{Mat4, Quat};
        // A floor at y = 0 and a ceiling at y = 4: the box's centre is the light's, (0, 2, 0).
        let room = |turn: Quat| {
            let mut s = scene(quad());
            let mut ceiling = quad();
            ceiling.transform = Mat4::from_translation(glam::Vec3::new(0.0, 4.0, 0.0));
            s.meshes.push(ceiling);
            for m in &mut s.meshes {
                m.transform = Mat4::from_quat(turn) * m.transform;
            }
            s.light.center = (turn * glam::Vec3::from(s.light.center)).to_array();
            s
        };
        let camera = Camera { eye: [0.5, 3.0, 0.8], target: [0.0, 0.5, -0.6], up: [0.0, 1.0, 0.0], fov_y_degrees: 60.0, width: 8, height: 8 };
        let s = room(Quat::IDENTITY);
        let axis = scene_axis(DVec3::from(s.light.center.map(f64::from)), &s.prepare_geometry().unwrap(), &camera);
        let forward = (DVec3::from(camera.target.map(f64::from)) - DVec3::from(camera.eye.map(f64::from))).normalize();
        assert!((axis - forward).length() < 1e-12, "{axis}");
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.52, 0.35, 0.0);
        let turned = room(q);
        let turn = |p: [f32; 3]| (q * glam::Vec3::from(p)).to_array();
        let turned_camera = Camera { eye: turn(camera.eye), target: turn(camera.target), up: turn(camera.up), ..camera };
        let t = scene_axis(DVec3::from(turned.light.center.map(f64::from)), &turned.prepare_geometry().unwrap(), &turned_camera);
        assert!((t - q.as_dquat() * axis).length() < 1e-5, "the axis turns with the scene: {t} against {}", q.as_dquat() * axis);
        // Away from the centre: towards it, whatever the camera.
        let above = scene_axis(DVec3::new(0.0, 3.0, 0.0), &s.prepare_geometry().unwrap(), &camera);
        assert!((above - DVec3::NEG_Y).length() < 1e-12);
    }

    #[test]
    fn sphere_sample_weights_estimate_the_solid_angle_from_any_receiver() {
        let (c, r) = (DVec3::new(1.0, 5.0, 0.0), 0.5);
        let axis = DVec3::NEG_Y;
        let (distance, bound) = (5.0, 3.0);
        let cos_max = visible_cap_cos(distance, bound);
        let s = sphere_samples(c, r, axis, cos_max, 1024, 3);
        // 896 cosine samples rounded up to a 30 x 30 grid, 128 uniform ones to 12 x 11.
        assert_eq!(s.len(), 900 + 132);
        assert_eq!(s, sphere_samples(c, r, axis, cos_max, 1024, 3));
        assert_ne!(s, sphere_samples(c, r, axis, cos_max, 1024, 4));
        let (e1, _) = axis.any_orthonormal_pair();
        for p in &s {
            let n = p.normal.expect("weighted");
            assert!((n.length() - 1.0).abs() < 1e-12);
            assert!((p.position - (c + n * r)).length() < 1e-12);
            assert!(n.dot(axis) >= cos_max - 1e-12, "outside the cap");
            assert!(p.weight.is_finite() && p.weight > 0.0);
        }
        // Receivers on the axis and up to 35 degrees off it (inside the
        // bounding sphere's cone, asin(3/5) = 37 degrees), near and far.
        // 4096 samples, seeds 0-7: the solid angle within 1.1% (1.9% with
        // 1024; the worst is 35 degrees off at distance 4, where the rim's
        // cosine samples carry large weights); the halves were within 0.4%
        // of one half with 1024 samples (seed 3). Bounds: 0.02 and 0.01.
        for (seed, (angle, d)) in [(0.0f64, 5.0), (20.0, 5.0), (35.0, 4.0), (35.0, 1.5), (10.0, 20.0)].into_iter().enumerate() {
            let s = sphere_samples(c, r, axis, cos_max, 4096, seed as u64);
            let (sin, cos) = angle.to_radians().sin_cos();
            let p = c + (axis * cos + e1 * sin) * d;
            // The shader's weight: density weight x cos(theta_s) / |p - s|^2 (times r^2 per unit area).
            let f = |x: &LightSample| {
                let to_p = p - x.position;
                x.weight * x.normal.unwrap().dot(to_p).max(0.0) / to_p.length().powi(3) * r * r
            };
            let solid_angle: f64 = s.iter().map(f).sum();
            let exact = std::f64::consts::TAU * (1.0 - (1.0 - (r / d).powi(2)).sqrt());
            assert!((solid_angle / exact - 1.0).abs() < 0.02, "{angle} deg, d {d}: {solid_angle} vs {exact}");
            // Half the visible light lies on either side of a plane through p and c.
            let side = (p - c).cross(axis + e1).normalize();
            let half: f64 = s.iter().filter(|x| (x.position - c).dot(side) > 0.0).map(f).sum();
            assert!((half / solid_angle - 0.5).abs() < 0.01, "{angle} deg, d {d}: {}", half / solid_angle);
        }
        assert_eq!(sphere_samples(c, 0.0, axis, cos_max, 256, 3), vec![LightSample { position: c, normal: None, weight: 1.0 }]);
    }

    #[test]
    fn the_cap_of_a_wide_floor_keeps_the_facing_hemisphere_and_a_room_takes_the_sphere() {
        let (c, r, axis) = (DVec3::new(0.0, 4.0, 0.0), 0.5, DVec3::NEG_Y);
        // A floor 20 wide, 4 below the light: its bounding sphere (radius
        // 10 around the floor's centre, 4 away) holds the light.
        let floor = [(-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)].map(|(x, z)| DVec3::new(x, 0.0, z));
        let cos = visible_cap_cos_of(c, r, axis, 4.0, 200f64.sqrt(), floor);
        let theta = (200f64.sqrt() / 4.0).atan();
        assert!((cos + theta.sin()).abs() < 1e-12, "{cos}");
        assert!(cos > -1.0);
        // A ceiling above the light: a room, the whole sphere.
        let room = floor.into_iter().chain(floor.map(|p| p + DVec3::Y * 5.0));
        assert_eq!(visible_cap_cos_of(c, r, axis, 4.0, 20.0, room), -1.0);
        // A corner inside the light, or NaN: the whole sphere.
        assert_eq!(visible_cap_cos_of(c, r, axis, 4.0, 1.0, [c + DVec3::X * 0.25]), -1.0);
        assert_eq!(visible_cap_cos_of(c, r, axis, 4.0, 1.0, [DVec3::NAN]), -1.0);
        // Never wider than the bounding sphere's cap, tighter with the corners'.
        let far = [DVec3::new(0.5, -96.0, 0.0), DVec3::new(-0.5, -96.0, 0.0)];
        assert!((visible_cap_cos_of(c, r, axis, 100.0, 1.0, far) + 0.5 / 100.00125f64).abs() < 1e-12);
        assert_eq!(visible_cap_cos_of(c, r, axis, 100.0, 1.0, [DVec3::new(50.0, -96.0, 0.0)]), visible_cap_cos(100.0, 1.0));
        // Brute force: the light points a point of the floor's triangles sees are in the cap.
        let all = sphere_samples(c, r, axis, -1.0, 4096, 1);
        for k in 0..400 {
            let (u, v) = ((k as f64 * 0.618).fract(), (k as f64 * 0.381).fract());
            let p = DVec3::new(-10.0 + 20.0 * u, 0.0, -10.0 + 20.0 * v);
            for s in &all {
                let n = s.normal.unwrap();
                if n.dot(p - s.position) > 0.0 {
                    assert!(n.dot(axis) >= cos - 1e-9, "{p} sees {n} outside the cap {cos}");
                }
            }
        }
    }

    #[test]
    fn the_visible_cap_holds_every_point_a_scene_point_sees() {
        // Light inside the scene's bounding sphere: the whole sphere.
        assert_eq!(visible_cap_cos(1.0, 2.0), -1.0);
        assert_eq!(visible_cap_cos(2.0, 2.0), -1.0);
        assert_eq!(visible_cap_cos(f64::NAN, 2.0), -1.0);
        // A far scene: a little more than the facing hemisphere.
        let far = visible_cap_cos(1000.0, 1.0);
        assert!(far < 0.0 && far > -0.002, "{far}");
        // Brute force: points p on the bounding sphere and the light points
        // they see all fall in the cap.
        let (c, r, d, bound) = (DVec3::ZERO, 0.3, 4.0, 2.0);
        let axis = DVec3::NEG_Y;
        let cos_max = visible_cap_cos(d, bound);
        let all = sphere_samples(c, r, axis, -1.0, 4096, 1);
        for k in 0..200 {
            let t = k as f64 * 0.7;
            let dir = DVec3::new(t.cos() * (t * 0.3).sin(), (t * 0.3).cos(), t.sin() * (t * 0.3).sin());
            let p = c + axis * d + dir * bound;
            for s in &all {
                let n = s.normal.unwrap();
                if n.dot(p - s.position) > 0.0 {
                    assert!(n.dot(axis) >= cos_max - 1e-9, "{p} sees {n} outside the cap {cos_max}");
                }
            }
        }
    }
}
