//! The light's shadow-map frustum: a perspective view from the light centre,
//! fitted to the scene's geometry (SPEC section 3).
//!
//! The frustum is off-centre: its window on the plane at unit depth is the
//! bounding rectangle of every vertex's projection, so no texel is spent on
//! empty space beside the geometry. Shadow maps store *linear* light-view depth
//! (distance along the light's axis), so biases can be stated in world units.

use glam::{Mat4, Vec3, Vec4};

use crate::error::{Error, Result};

/// Widest half-angle (per axis) one frustum may cover. Beyond it texels
/// stretch without bound; geometry there needs an omnidirectional map.
pub const MAX_HALF_ANGLE_DEGREES: f32 = 80.0;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightFrustum {
    /// World to light view (right-handed, looking down -z).
    pub view: Mat4,
    /// Light view to clip space, wgpu depth range.
    pub projection: Mat4,
    /// Window on the unit-depth plane: x0, x1, y0, y1.
    pub window: Vec4,
    pub near: f32,
    pub far: f32,
}

/// Why no frustum fits.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Unfit {
    NoGeometry,
    /// The directions to the vertices cancel out: geometry on every side.
    EverySide,
    /// A vertex lies this many degrees off the best axis.
    TooWide(f32),
}

impl Unfit {
    fn error(self) -> Error {
        Error::InvalidScene(match self {
            Unfit::NoGeometry => "has no geometry to fit a shadow map to".into(),
            Unfit::EverySide => format!(
                "geometry surrounds the light: the directions from the light's centre to the \
                 vertices cancel out (geometry on every side), so no frustum of \
                 {MAX_HALF_ANGLE_DEGREES} degrees half-angle covers it (omnidirectional shadow \
                 maps are not supported yet; move the light outside the geometry's bounding region)"
            ),
            Unfit::TooWide(angle) => format!(
                "geometry surrounds the light: a vertex lies {angle:.1} degrees off the shadow-map \
                 axis, beyond the {MAX_HALF_ANGLE_DEGREES} degrees one frustum covers \
                 (omnidirectional shadow maps are not supported yet; move the light outside the \
                 geometry's bounding region)"
            ),
        })
    }

    /// The error from one of `count` samples on the light's sphere: which
    /// sample, and what to do. The light's centre may see the geometry within
    /// one frustum where a sample on the light's surface does not.
    fn sample_error(self, method: &str, sample: usize, count: usize, position: Vec3) -> Error {
        let sees = match self {
            Unfit::NoGeometry => return self.error(),
            Unfit::EverySide => "geometry on every side".to_owned(),
            Unfit::TooWide(angle) => format!("a vertex {angle:.1} degrees off its shadow-map axis"),
        };
        Error::InvalidScene(format!(
            "method '{method}': geometry surrounds the light as its light sample {sample} of \
             {count} sees it (at {:?}, on the light's sphere): {sees}, beyond the \
             {MAX_HALF_ANGLE_DEGREES} degrees one shadow-map frustum covers. The light's centre \
             sees the geometry within one frustum, so the other methods render this scene; until \
             omnidirectional shadow maps exist, raise the light further above the geometry, \
             shrink its radius, or narrow the geometry around it",
            position.to_array()
        ))
    }
}

impl LightFrustum {
    /// Fits a frustum from `center` around all `points`.
    pub fn fit(center: Vec3, points: impl Iterator<Item = Vec3> + Clone) -> Result<Self> {
        Self::try_fit(center, points).map_err(Unfit::error)
    }

    /// [`LightFrustum::fit`] from sample `sample` (1-based) of `count` on the
    /// light's sphere (the `reference` method's), whose error says which
    /// sample and what to do.
    pub fn fit_light_sample(
        position: Vec3,
        points: impl Iterator<Item = Vec3> + Clone,
        method: &str,
        sample: usize,
        count: usize,
    ) -> Result<Self> {
        Self::try_fit(position, points).map_err(|u| u.sample_error(method, sample, count, position))
    }

    fn try_fit(center: Vec3, points: impl Iterator<Item = Vec3> + Clone) -> Result<Self, Unfit> {
        // Aim at the mean direction to the geometry, then re-aim once at the
        // centre of the projected window so the window is roughly symmetric.
        let mut sum = Vec3::ZERO;
        let mut count = 0usize;
        for p in points.clone() {
            // Normalisation is safe: the scene check keeps every surface off the
            // light. Where the squared length would underflow or overflow
            // float32 (a scene 1e-25 across, or 1e19), dividing by the largest
            // component first brings it into [1, 3].
            let d = p - center;
            let length_squared = d.length_squared();
            sum += if length_squared.is_normal() && length_squared.is_finite() {
                d.normalize_or_zero()
            } else {
                let m = d.abs().max_element();
                if m > 0.0 { (d / m).normalize_or_zero() } else { Vec3::ZERO }
            };
            count += 1;
        }
        if count == 0 {
            return Err(Unfit::NoGeometry);
        }
        let mut axis = sum.normalize_or_zero();
        if axis == Vec3::ZERO || sum.length() < 1e-3 * count as f32 {
            return Err(Unfit::EverySide);
        }
        let mut fitted = Self::fit_along(center, axis, points.clone())?;
        let w = fitted.window;
        let mid = Vec3::new(0.5 * (w.x + w.y), 0.5 * (w.z + w.w), -1.0);
        let recentred = fitted.view.inverse().transform_vector3(mid).normalize_or_zero();
        if recentred != Vec3::ZERO {
            axis = recentred;
            if let Ok(better) = Self::fit_along(center, axis, points) {
                fitted = better;
            }
        }
        Ok(fitted)
    }

    fn fit_along(center: Vec3, axis: Vec3, points: impl Iterator<Item = Vec3>) -> Result<Self, Unfit> {
        // Any up vector not parallel to the axis gives a valid basis.
        let up = if axis.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
        let view = glam::camera::rh::view::look_to_mat4(center, axis, up);
        let max_tan = MAX_HALF_ANGLE_DEGREES.to_radians().tan();
        let (mut x0, mut x1, mut y0, mut y1) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
        let (mut z_min, mut z_max) = (f32::MAX, 0.0f32);
        for p in points {
            let q = view.transform_point3(p);
            let z = -q.z;
            let (u, v) = (q.x / z.max(f32::MIN_POSITIVE), q.y / z.max(f32::MIN_POSITIVE));
            // z <= 0 is behind the light; |u| or |v| > max_tan is too wide for one map.
            if z <= 0.0 || u.abs() > max_tan || v.abs() > max_tan {
                let angle = q.truncate().length().atan2(z).to_degrees();
                return Err(Unfit::TooWide(angle));
            }
            x0 = x0.min(u);
            x1 = x1.max(u);
            y0 = y0.min(v);
            y1 = y1.max(v);
            z_min = z_min.min(z);
            z_max = z_max.max(z);
        }
        // Pad by 1% (and at least a small absolute amount) so silhouettes on the
        // border stay inside; a zero-width window (all points on one ray) gets a width.
        let pad_x = 0.01 * (x1 - x0) + 1e-4;
        let pad_y = 0.01 * (y1 - y0) + 1e-4;
        let window = Vec4::new(x0 - pad_x, x1 + pad_x, y0 - pad_y, y1 + pad_y);
        let far = z_max * 1.02;
        let near = (z_min * 0.98).max(far * 1e-6);
        Ok(Self {
            view,
            projection: off_centre_perspective(window, near, far),
            window,
            near,
            far,
        })
    }

    /// The same frustum with its near plane moved to `near` (0 < near < far):
    /// for geometry that starts nearer the light than the scene does (PVMF's
    /// moved edge points). Maps store linear depth, so only clipping changes.
    pub fn with_near(&self, near: f32) -> Self {
        let near = near.clamp(self.far * 1e-6, self.near);
        Self { projection: off_centre_perspective(self.window, near, self.far), near, ..*self }
    }

    /// World-space size of one texel at light-view depth `z`, for a `map_size` map.
    pub fn texel_size_at(&self, z: f32, map_size: u32) -> f32 {
        let w = self.window;
        (w.y - w.x).max(w.w - w.z) * z / map_size as f32
    }
}

/// Perspective projection whose window on the unit-depth plane is
/// `[x0, x1] x [y0, y1]`, mapping depth `near..far` to 0..1.
fn off_centre_perspective(window: Vec4, near: f32, far: f32) -> Mat4 {
    let (x0, x1, y0, y1) = (window.x, window.y, window.z, window.w);
    let sx = 2.0 / (x1 - x0);
    let sy = 2.0 / (y1 - y0);
    let range = far / (near - far);
    Mat4::from_cols(
        Vec4::new(sx, 0.0, 0.0, 0.0),
        Vec4::new(0.0, sy, 0.0, 0.0),
        Vec4::new((x1 + x0) / (x1 - x0), (y1 + y0) / (y1 - y0), range, -1.0),
        Vec4::new(0.0, 0.0, near * range, 0.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane_points() -> Vec<Vec3> {
        vec![
            Vec3::new(-5.0, 0.0, -5.0),
            Vec3::new(5.0, 0.0, -5.0),
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(-5.0, 0.0, 5.0),
            Vec3::new(0.0, 1.0, 0.0),
        ]
    }

    #[test]
    fn every_point_projects_inside_the_window() {
        let points = plane_points();
        let f = LightFrustum::fit(Vec3::new(1.0, 4.0, 0.5), points.iter().copied()).unwrap();
        for p in points {
            let clip = f.projection * f.view * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0, "{p} -> {ndc}");
            assert!((0.0..=1.0).contains(&ndc.z), "{p} -> depth {}", ndc.z);
        }
    }

    #[test]
    fn geometry_around_the_light_is_refused() {
        let points = plane_points();
        let err = LightFrustum::fit(Vec3::new(0.0, 0.5, 0.0), points.iter().copied()).unwrap_err();
        assert!(err.to_string().contains("surrounds the light"), "{err}");
        // A light at the centre of a cube's corners: no mean direction at all.
        let cube: Vec<Vec3> = (0..8).map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32) * 2.0 - 1.0).collect();
        let err = LightFrustum::fit(Vec3::ZERO, cube.iter().copied()).unwrap_err().to_string();
        assert!(err.contains("every side") && !err.contains("180"), "{err}");
    }

    #[test]
    fn a_light_sample_error_names_the_sample_and_the_remedy() {
        let points = plane_points();
        let err = LightFrustum::fit_light_sample(Vec3::new(0.0, 0.5, 0.0), points.iter().copied(), "reference", 3, 16)
            .unwrap_err()
            .to_string();
        assert!(err.contains("light sample 3 of 16") && err.contains("degrees off") && err.contains("shrink its radius"), "{err}");
    }
}
