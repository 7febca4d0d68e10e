//! The light's shadow-map projection (SPEC section 3): a perspective
//! frustum from the light point fitted to what can shadow something (the
//! casters and the penumbrae they may cast) where one frustum covers it,
//! six cube faces where it does not.
//!
//! The frustum is off-centre: its window on the plane at unit depth is the
//! smallest square holding the bounding rectangle of every caster vertex's
//! ball of the light's radius (`LightProjection::fit`), so no texel is
//! spent on a floor that only receives, and a point projecting outside it
//! is lit. It covers at most [`MAX_HALF_ANGLE_DEGREES`] off its axis;
//! beyond that (a light close over a wide caster, or inside a ring of
//! casters) the cube's six 90-degree faces take over, of which only those
//! that see geometry are rendered.
//! Shadow maps store *linear* light-view depth (distance along the face's
//! axis), so biases can be stated in world units.

use glam::{DVec3, Mat4, Vec3, Vec4};

use crate::error::{Error, Result};

/// Which projection shadow maps use (the `projection` parameter).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ProjectionMode {
    /// The fitted frustum where it covers the casters and their penumbrae, cube faces otherwise.
    Auto,
    /// The fitted frustum, or an error naming the angle when it cannot cover the casters and their penumbrae.
    Frustum,
    /// Six cube faces, whatever the geometry.
    Cube,
}

impl ProjectionMode {
    pub const NAMES: [&'static str; 3] = ["auto", "frustum", "cube"];

    pub fn parse(name: &str) -> Self {
        match name {
            "frustum" => ProjectionMode::Frustum,
            "cube" => ProjectionMode::Cube,
            _ => ProjectionMode::Auto,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            ProjectionMode::Auto => "auto",
            ProjectionMode::Frustum => "frustum",
            ProjectionMode::Cube => "cube",
        }
    }
}

/// The axis and up vector of cube face `i` (+x, -x, +y, -y, +z, -z): the same
/// frames as `cube_face_frame` in `shaders/light_space.wgsl`.
pub fn cube_face(i: usize) -> (Vec3, Vec3) {
    match i {
        0 => (Vec3::X, Vec3::Y),
        1 => (Vec3::NEG_X, Vec3::Y),
        2 => (Vec3::Y, Vec3::Z),
        3 => (Vec3::NEG_Y, Vec3::NEG_Z),
        4 => (Vec3::Z, Vec3::Y),
        _ => (Vec3::NEG_Z, Vec3::Y),
    }
}

/// The light's shadow-map projection for one render: one fitted frustum, or
/// the six faces of a cube around the light point.
#[derive(Debug, Clone, PartialEq)]
pub struct LightProjection {
    /// One frustum, or the six cube faces in the order of [`cube_face`].
    pub faces: Vec<LightFrustum>,
    /// Faces that see geometry (bit i: face i), the only ones rendered; 1 for a frustum.
    pub active: u32,
    /// The point the faces look from.
    pub origin: Vec3,
    /// Cube faces: the distance from `origin` to the nearest geometry (the
    /// same whichever way the faces cut, unlike the near plane along each
    /// face's axis); PCSS sizes its blocker search from it. 0 for a frustum.
    pub nearest: f32,
}

impl LightProjection {
    /// The projection from `origin` for the triangles whose corners are
    /// `corners` (three per triangle), as `mode` asks.
    ///
    /// A frustum is fitted around what can shadow something, not around all
    /// geometry: the balls of radius `radius` (the light's) around the
    /// `casters` (the corners of the triangles that may hide part of the
    /// light, `casters.rs`). A point P hidden from some point L of the light
    /// by a caster point C lies on the ray from L through C, whose direction
    /// from `origin` is within asin(radius / |C - origin|) of C's: inside
    /// the cone of the ball around C. The ball around a triangle's every
    /// point lies in the convex hull of the balls around its corners, and
    /// the window of a convex set is that of the sets it is the hull of, so
    /// every point that may lie in shadow or penumbra projects into the
    /// window; a point outside it (or behind the light) is lit, and reads
    /// there clamp to a border ring the raster passes keep empty
    /// (`shadow_map::keep_border_empty`).
    /// The depth range still spans the box `bounds` around all geometry.
    /// With no casters the frustum is fitted around the `corners`.
    pub fn fit(origin: Vec3, radius: f32, casters: &[Vec3], corners: &[Vec3], bounds: (Vec3, Vec3), mode: ProjectionMode) -> Result<Self> {
        if mode != ProjectionMode::Cube {
            let balls = if casters.is_empty() { (corners, 0.0) } else { (casters, radius) };
            let fitted = LightFrustum::fit_balls(origin, balls.0, balls.1, bounds);
            match fitted {
                // `auto` takes the frustum only where no texel of it is
                // coarser than the cube's coarsest: a texel spans at most
                // the window's width / map size on the unit-depth plane
                // (at the axis; less off it), a cube face's 2 / map size.
                Ok(frustum) if mode == ProjectionMode::Frustum || frustum.width() <= AUTO_MAX_WIDTH => {
                    return Ok(Self { faces: vec![frustum], active: 1, origin, nearest: 0.0 })
                }
                Err(e) if mode == ProjectionMode::Frustum => return Err(e),
                _ => {}
            }
        }
        Self::cube(origin, corners)
    }

    /// Six 90-degree faces around `origin`; a face is active when some
    /// triangle may reach into its cone (no vertex-only test: a floor under
    /// the light has its corners in the side faces and its middle below).
    pub fn cube(origin: Vec3, corners: &[Vec3]) -> Result<Self> {
        if corners.is_empty() {
            return Err(Error::InvalidScene("has no geometry to fit a shadow map to".into()));
        }
        let o = origin.as_dvec3();
        // The cone of face f is where a.v >= |b.v| and a.v >= |c.v|: four
        // half-spaces through the origin. A triangle reaches into it when
        // something of it is left after clipping by all four.
        let mut active = 0u32;
        let mut far = 0.0f64;
        // The nearest depth of geometry along any face's axis: the near
        // plane, from which filters size their search regions (PCSS's
        // blocker search reaches across the light's projection onto it).
        let mut nearest = f64::INFINITY;
        let mut nearest_distance = f64::INFINITY;
        for t in corners.chunks_exact(3) {
            nearest_distance = nearest_distance.min(triangle_distance([t[0], t[1], t[2]].map(|p| p.as_dvec3() - o)));
        }
        for f in 0..6 {
            let planes = cone_planes(f);
            let a = cube_face(f).0.as_dvec3();
            for t in corners.chunks_exact(3) {
                let tri = [t[0], t[1], t[2]].map(|p| p.as_dvec3() - o);
                let whole;
                let inside: &[DVec3] = match in_cone(&tri, &planes) {
                    Some(true) => &tri,
                    Some(false) => continue,
                    None => {
                        whole = clip_to_cone(tri, &planes);
                        &whole
                    }
                };
                if !inside.is_empty() {
                    active |= 1 << f;
                    // The depth a.v is linear: its minimum over the clipped
                    // polygon is at one of its corners.
                    nearest = inside.iter().map(|v| a.dot(*v)).fold(nearest, f64::min);
                }
            }
        }
        for p in corners {
            let v = p.as_dvec3() - o;
            far = far.max(v.abs().max_element());
        }
        if !(far > 0.0 && far.is_finite()) {
            return Err(surrounds_error(180.0));
        }
        // Linear depths are stored, so the near plane only clips what is
        // nearer than all geometry (scene validation keeps every surface off
        // the light, so the nearest depth is positive).
        let far = (far * 1.02) as f32;
        let near = ((nearest * 0.98) as f32).clamp(far * 1e-6, far);
        let window = Vec4::new(-1.0, 1.0, -1.0, 1.0);
        let projection = off_centre_perspective(window, near, far);
        let faces = (0..6)
            .map(|i| {
                let (axis, up) = cube_face(i);
                let view = glam::camera::rh::view::look_to_mat4(origin, axis, up);
                LightFrustum { view, projection, window, near, far }
            })
            .collect();
        // Scene validation keeps every surface off the light: the distance is positive.
        Ok(Self { faces, active, origin, nearest: nearest_distance as f32 })
    }

    pub fn is_cube(&self) -> bool {
        self.faces.len() == 6
    }

    /// Texture layers of its maps: 1 or 6.
    pub fn layers(&self) -> u32 {
        self.faces.len() as u32
    }

    /// The far plane (shared by every face).
    pub fn far(&self) -> f32 {
        self.faces[0].far
    }

    /// Faces rendered.
    pub fn active_faces(&self) -> u32 {
        self.active.count_ones()
    }

    /// Each active face with its layer.
    pub fn active_layers(&self) -> impl Iterator<Item = (u32, &LightFrustum)> {
        self.faces.iter().enumerate().filter(|(i, _)| self.active & (1 << i) != 0).map(|(i, f)| (i as u32, f))
    }

    /// The same projection with every face's near plane moved to `near`
    /// (see [`LightFrustum::with_near`]).
    pub fn with_near(&self, near: f32) -> Self {
        Self { faces: self.faces.iter().map(|f| f.with_near(near)).collect(), ..self.clone() }
    }
}

/// The widest window (on the unit-depth plane) that `auto` takes a frustum
/// for: a cube face's, 2, so that the frustum's texels are nowhere coarser
/// than the cube's (a window as wide as the 80 degrees the frustum may
/// cover spreads a texel over 5.7 times the angle of a cube face's centre
/// texel; `backprojection`'s error on a slab's edge 2 below the light, 53
/// degrees off the frustum's axis, was 2.6 times the cube's).
pub const AUTO_MAX_WIDTH: f32 = 2.0;

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

impl LightFrustum {
    /// Fits a frustum from `center` around all `points`.
    pub fn fit(center: Vec3, points: impl Iterator<Item = Vec3> + Clone) -> Result<Self> {
        let points: Vec<Vec3> = points.collect();
        Self::fit_balls(center, &points, 0.0, bounds(&points))
    }

    /// Fits a frustum from `center` around the balls of radius `radius`
    /// around `balls` (see [`LightProjection::fit`]), with a depth range
    /// that also spans every point of the box `bounds` (min, max corners).
    pub fn fit_balls(center: Vec3, balls: &[Vec3], radius: f32, bounds: (Vec3, Vec3)) -> Result<Self> {
        // Linear depth is stored: the far plane spans every point in front
        // that may read the map (no depth along any axis exceeds the distance
        // to the box's farthest corner), the near plane only what is drawn.
        let (c, lo, hi) = (center.as_dvec3(), bounds.0.as_dvec3(), bounds.1.as_dvec3());
        let reach = (lo - c).abs().max((hi - c).abs()).length();
        if balls.is_empty() {
            return Err(Error::InvalidScene("has no geometry to fit a shadow map to".into()));
        }
        // Start from the direction to the centre of the points' bounding box
        // where a frustum along it covers them: min and max are exact and
        // independent of order and multiplicity, so a doubled, split or
        // reordered surface gets the very same frustum and texel grid
        // (issue 27). The mean direction weights each corner once per face:
        // it is only the fallback (the box's centre may lie behind the light),
        // computed only then (a pass over every point; `reference` fits a
        // frustum per light sample).
        let (lo, hi) = balls.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let to_box = (0.5 * lo + 0.5 * hi - center).normalize_or_zero();
        let fit_along = |axis: Vec3| Self::fit_along(center, axis, balls, radius, reach);
        let mut fitted = match (to_box != Vec3::ZERO).then(|| fit_along(to_box)) {
            Some(Ok(f)) => f,
            _ => fit_along(Self::mean_direction(center, balls)?)?,
        };
        // Re-aim once at the centre of the projected window so the window is
        // roughly symmetric.
        let w = fitted.window;
        let mid = Vec3::new(0.5 * (w.x + w.y), 0.5 * (w.z + w.w), -1.0);
        let recentred = fitted.view.inverse().transform_vector3(mid).normalize_or_zero();
        if recentred != Vec3::ZERO {
            if let Ok(better) = fit_along(recentred) {
                fitted = better;
            }
        }
        Ok(fitted)
    }

    /// The mean direction from `center` to `balls` (not empty), or the error
    /// that geometry surrounds the light where the directions cancel out. A
    /// frustum that covers the balls has every direction within 80 degrees
    /// per axis of its axis, so at least 0.12 along it: where one fits, this
    /// check passes, and `fit_balls` needs the mean only where the box's
    /// direction fails.
    fn mean_direction(center: Vec3, balls: &[Vec3]) -> Result<Vec3> {
        let mut sum = Vec3::ZERO;
        for &p in balls {
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
        }
        let axis = sum.normalize_or_zero();
        if axis == Vec3::ZERO || sum.length() < 1e-3 * balls.len() as f32 {
            // No mean direction: geometry on every side of the light.
            return Err(Error::InvalidScene(format!(
                "geometry surrounds the light: the directions from the light to the vertices \
                 cancel out (geometry on every side), so no frustum of {MAX_HALF_ANGLE_DEGREES} \
                 degrees half-angle covers it; projection='auto' (the default) or 'cube' renders \
                 such scenes with cube-map faces"
            )));
        }
        Ok(axis)
    }

    fn fit_along(center: Vec3, axis: Vec3, balls: &[Vec3], radius: f32, reach: f64) -> Result<Self> {
        // Any up vector not parallel to the axis gives a valid basis.
        let up = if axis.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
        let view = glam::camera::rh::view::look_to_mat4(center, axis, up);
        let max_tan = f64::from(MAX_HALF_ANGLE_DEGREES.to_radians().tan());
        let r = f64::from(radius.max(0.0));
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        let (mut z_min, mut z_max) = (f64::MAX, 0.0f64);
        let view64 = view.as_dmat4();
        for p in balls {
            let q = view64.transform_point3(p.as_dvec3());
            let z = -q.z;
            // The ball's extent along x on the unit-depth plane: the planes
            // x = u z through the light touching it, at distance r from its
            // centre: (x - u z)^2 = r^2 (1 + u^2), a quadratic in u whose
            // leading coefficient z^2 - r^2 is positive for a ball wholly in
            // front (checked), so the square root's argument
            // x^2 + z^2 - r^2 > 0 too. r = 0 gives u = x / z.
            let lead = z * z - r * r;
            if z <= 0.0 || !(lead > 1e-6 * z * z) {
                let angle = q.truncate().length().atan2(z).to_degrees() + (r / q.length().max(r)).asin().to_degrees();
                return Err(surrounds_error(angle as f32));
            }
            let extent = |x: f64| {
                let s = r * (x * x + lead).sqrt();
                ((x * z - s) / lead, (x * z + s) / lead)
            };
            let ((u0, u1), (v0, v1)) = (extent(q.x), extent(q.y));
            // |u| or |v| > max_tan is too wide for one map.
            if u0 < -max_tan || u1 > max_tan || v0 < -max_tan || v1 > max_tan {
                let angle = q.truncate().length().atan2(z).to_degrees() + (r / q.length()).asin().to_degrees();
                return Err(surrounds_error(angle as f32));
            }
            x0 = x0.min(u0);
            x1 = x1.max(u1);
            y0 = y0.min(v0);
            y1 = y1.max(v1);
            z_min = z_min.min(z);
            z_max = z_max.max(z);
        }
        z_max = z_max.max(reach);
        let (x0, x1, y0, y1, z_min, z_max) = (x0 as f32, x1 as f32, y0 as f32, y1 as f32, z_min as f32, z_max as f32);
        // Pad by 1% (and at least a small absolute amount) so silhouettes on the
        // border stay inside; a zero-width window (all points on one ray) gets a width.
        // Texels are square: every kernel sizes itself by one texel size
        // (light_texel_size, the wider extent), so the narrower extent is
        // widened about its middle to the wider one.
        let side = (x1 - x0).max(y1 - y0);
        let pad = 0.01 * side + 1e-4;
        let (mx, my) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let half = 0.5 * side + pad;
        let window = Vec4::new(mx - half, mx + half, my - half, my + half);
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

    /// The window's width on the unit-depth plane (it is square).
    pub fn width(&self) -> f32 {
        (self.window.y - self.window.x).max(self.window.w - self.window.z)
    }

    /// World-space size of one texel at light-view depth `z`, for a `map_size` map.
    pub fn texel_size_at(&self, z: f32, map_size: u32) -> f32 {
        let w = self.window;
        (w.y - w.x).max(w.w - w.z) * z / map_size as f32
    }
}

/// The bounding box of `points` (min, max corners; the origin for none).
pub fn bounds(points: &[Vec3]) -> (Vec3, Vec3) {
    let Some(first) = points.first() else { return (Vec3::ZERO, Vec3::ZERO) };
    points.iter().fold((*first, *first), |(lo, hi), p| (lo.min(*p), hi.max(*p)))
}

/// The part of triangle `triangle` where `n.v >= 0` for every one of the
/// four `planes` (Sutherland-Hodgman; each plane adds at most one corner, so
/// seven hold the result); empty when nothing of it is left. A triangle that
/// only touches a plane keeps the touching points.
/// The distance from the origin to the triangle `t` (its closest point:
/// Ericson, Real-Time Collision Detection 5.1.5, by Voronoi regions).
fn triangle_distance(t: [DVec3; 3]) -> f64 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (b - a, c - a, -a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a.length();
    }
    let bp = -b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b.length();
    }
    let vc = d1 * d4 - d3 * d2;
    // Each division below is by a positive sum of the region's barycentric
    // terms (the tests before it exclude the zero cases); a degenerate
    // triangle falls to its vertices or edges.
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (a + ab * (d1 / (d1 - d3))).length();
    }
    let cp = -c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c.length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (a + ac * (d2 / (d2 - d6))).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))).length();
    }
    let sum = va + vb + vc;
    // NaN-safe: a NaN sum (non-finite corners) also takes this branch.
    if sum.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        // Degenerate (zero area) and no region matched: its nearest corner.
        return a.length().min(b.length()).min(c.length());
    }
    (a + ab * (vb / sum) + ac * (vc / sum)).length()
}

/// The four planes through the origin whose positive sides bound cube face
/// `f`'s cone: where a.v >= |b.v| and a.v >= |c.v| (a the face's axis, b its
/// up vector, c their cross product).
fn cone_planes(f: usize) -> [DVec3; 4] {
    let (axis, up) = cube_face(f);
    let (a, b) = (axis.as_dvec3(), up.as_dvec3());
    let c = a.cross(b);
    [a - b, a + b, a - c, a + c]
}

/// Whether triangle `tri` (relative to the cone's apex) lies wholly inside
/// the cone of `planes` (`Some(true)`), wholly behind one of them
/// (`Some(false)`: nothing of it reaches the cone), or across its edge
/// (`None`: [`clip_to_cone`] says how much). Most triangles are one of the
/// first two, which need no clipping: clip_to_cone keeps such a triangle as
/// it is, and leaves nothing of one behind a plane.
fn in_cone(tri: &[DVec3; 3], planes: &[DVec3; 4]) -> Option<bool> {
    if planes.iter().any(|n| tri.iter().all(|v| n.dot(*v) < 0.0)) {
        return Some(false);
    }
    tri.iter().all(|v| planes.iter().all(|n| n.dot(*v) >= 0.0)).then_some(true)
}

/// The cube faces (bit f: face f) whose cone, from any apex within `reach`
/// of `origin`, triangle `tri` may reach: all but those one of whose planes,
/// moved back by `reach`, has the whole triangle strictly behind it. From an
/// apex o' with |o' - o| <= reach, n.(p - o') <= n.(p - o) + reach |n|, so a
/// triangle behind a moved plane is behind the plane itself seen from o',
/// and the face's frustum clips all of it away. A superset: raster passes
/// from such apexes (the light's centre and its samples) may draw only these.
pub fn faces_reached(origin: DVec3, reach: f64, tri: [DVec3; 3]) -> u32 {
    let rel = tri.map(|p| p - origin);
    (0..6)
        .filter(|&f| !cone_planes(f).iter().any(|n| rel.iter().all(|v| n.dot(*v) < -reach * n.length())))
        .fold(0, |mask, f| mask | 1 << f)
}

pub(crate) fn clip_to_cone(triangle: [DVec3; 3], planes: &[DVec3; 4]) -> Vec<DVec3> {
    let mut polygon = [DVec3::ZERO; 8];
    polygon[..3].copy_from_slice(&triangle);
    let mut len = 3;
    for n in planes {
        let mut out = [DVec3::ZERO; 8];
        let mut k = 0;
        for i in 0..len {
            let (p, q) = (polygon[i], polygon[(i + 1) % len]);
            let (dp, dq) = (n.dot(p), n.dot(q));
            if dp >= 0.0 {
                out[k] = p;
                k += 1;
            }
            // The edge crosses the plane: dp and dq have opposite signs, so
            // dp - dq is non-zero.
            if (dp >= 0.0) != (dq >= 0.0) {
                out[k] = p + (q - p) * (dp / (dp - dq));
                k += 1;
            }
        }
        (polygon, len) = (out, k);
        if len == 0 {
            break;
        }
    }
    polygon[..len].to_vec()
}

/// The error of a projection that sample `sample` (1-based) of `count` on
/// the light's sphere (the `reference` method's) cannot have, saying which
/// sample: the light's centre may see the geometry within one frustum where
/// a sample on the light's surface does not.
pub fn light_sample_error(error: Error, method: &str, sample: usize, count: usize, position: Vec3) -> Error {
    match error {
        Error::InvalidScene(message) => Error::InvalidScene(format!(
            "method '{method}', light sample {sample} of {count} (at {:?}, on the light's sphere): \
             {message}. The light's centre may see the geometry within one frustum where its \
             samples do not; a smaller radius or a light further above the geometry also helps",
            position.to_array()
        )),
        other => other,
    }
}

fn surrounds_error(angle: f32) -> Error {
    Error::InvalidScene(format!(
        "geometry surrounds the light: a caster or its penumbra lies {angle:.1} degrees off the shadow-map axis, \
         beyond the {MAX_HALF_ANGLE_DEGREES} degrees one frustum covers; projection='auto' (the \
         default) or 'cube' renders such scenes with cube-map faces"
    ))
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
    fn the_frustum_ignores_the_order_and_multiplicity_of_points() {
        // A doubled surface, or its corners in another order, cast the same
        // shadow: the map's frustum (and so its texel grid) must not move.
        let mut points = plane_points();
        points.extend([Vec3::new(0.3, 1.0, 0.2), Vec3::new(-0.2, 0.8, 0.1)]);
        let light = Vec3::new(1.0, 4.0, 0.5);
        let f = LightFrustum::fit(light, points.iter().copied()).unwrap();
        let mut doubled = points.clone();
        doubled.extend(points.iter().rev().copied());
        doubled.extend(std::iter::repeat_n(points[5], 40));
        assert_eq!(f, LightFrustum::fit(light, doubled.iter().copied()).unwrap());
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
        let err = LightFrustum::fit(Vec3::new(0.0, 0.5, 0.0), points.iter().copied()).unwrap_err();
        let err = light_sample_error(err, "reference", 3, 16, Vec3::new(0.0, 0.5, 0.0)).to_string();
        assert!(err.contains("light sample 3 of 16") && err.contains("degrees off") && err.contains("projection='auto'"), "{err}");
    }

    /// Two triangles of a 10 x 10 floor at y = 0.
    fn floor() -> Vec<Vec3> {
        let [a, b, c, d] = [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)].map(|(x, z)| Vec3::new(x, 0.0, z));
        vec![a, c, b, a, d, c]
    }

    #[test]
    fn auto_keeps_the_frustum_where_it_covers_and_takes_the_cube_elsewhere() {
        let fit = |origin: Vec3, mode| LightProjection::fit(origin, 0.0, &floor(), &floor(), bounds(&floor()), mode);
        let high = fit(Vec3::new(0.0, 20.0, 0.0), ProjectionMode::Auto).unwrap();
        assert!(!high.is_cube() && high.active == 1);
        assert_eq!(high.faces[0], LightFrustum::fit(Vec3::new(0.0, 20.0, 0.0), floor().into_iter()).unwrap());
        // 0.5 above a 10-wide floor: 84 degrees to its corners.
        let low = fit(Vec3::new(0.0, 0.5, 0.0), ProjectionMode::Auto).unwrap();
        assert!(low.is_cube());
        let err = fit(Vec3::new(0.0, 0.5, 0.0), ProjectionMode::Frustum).unwrap_err();
        assert!(err.to_string().contains("degrees"), "{err}");
        assert!(fit(Vec3::new(0.0, 20.0, 0.0), ProjectionMode::Cube).unwrap().is_cube());
    }

    #[test]
    fn cube_faces_that_see_no_triangle_are_inactive() {
        // The floor below the light: its middle is in -y, its corners in the four side faces, nothing in +y.
        let p = LightProjection::cube(Vec3::new(0.0, 0.5, 0.0), &floor()).unwrap();
        assert_eq!(p.active, 0b11_1011, "{:06b}", p.active);
        assert_eq!(p.active_faces(), 5);
        // The floor is 0.5 below the light: the nearest depth of any face.
        assert!((p.faces[0].near - 0.49).abs() < 1e-6 && p.faces.iter().all(|f| f.near == p.faces[0].near), "{}", p.faces[0].near);
        // A floor far below: only -y; a triangle entirely in +x: only +x.
        assert_eq!(LightProjection::cube(Vec3::new(0.0, 50.0, 0.0), &floor()).unwrap().active, 1 << 3);
        let right = [Vec3::new(5.0, -0.1, -0.1), Vec3::new(5.0, 0.1, 0.0), Vec3::new(5.0, -0.1, 0.1)];
        assert_eq!(LightProjection::cube(Vec3::ZERO, &right).unwrap().active, 1);
    }

    #[test]
    fn cube_faces_tile_every_direction_with_their_windows() {
        // A direction's dominant axis picks its face, and the point projects
        // inside that face's window with its depth along the axis.
        let p = LightProjection::cube(Vec3::new(1.0, 2.0, 3.0), &floor()).unwrap();
        for k in 0..500 {
            let t = k as f32 * 0.37;
            let d = Vec3::new(t.sin() * (t * 0.7).cos(), (t * 1.3).cos(), (t * 0.5).sin() + 0.01 * t.cos());
            let abs = d.abs();
            let face = if abs.x >= abs.y && abs.x >= abs.z {
                if d.x > 0.0 { 0 } else { 1 }
            } else if abs.y >= abs.z {
                if d.y > 0.0 { 2 } else { 3 }
            } else if d.z > 0.0 {
                4
            } else {
                5
            };
            let f = &p.faces[face];
            let q = f.view.transform_point3(p.origin + d * 3.0);
            assert!((-q.z - 3.0 * abs.max_element()).abs() < 1e-4, "depth along the axis");
            let (u, v) = (q.x / -q.z, q.y / -q.z);
            assert!(u.abs() <= 1.0 + 1e-5 && v.abs() <= 1.0 + 1e-5, "face {face}: {u} {v}");
        }
    }

    #[test]
    fn the_cube_knows_the_distance_to_the_nearest_geometry_whichever_way_it_is_turned() {
        // The floor 0.5 below the light, first level, then turned 40 degrees
        // about z around the light: the distance stays 0.5 (the near plane
        // along the faces' axes does not).
        let origin = Vec3::new(0.3, 0.5, -0.2);
        let level = LightProjection::cube(origin, &floor()).unwrap();
        assert!((level.nearest - 0.5).abs() < 1e-5, "{}", level.nearest);
        let turn = glam::Mat3::from_rotation_z(40f32.to_radians());
        let turned: Vec<Vec3> = floor().iter().map(|p| origin + turn * (*p - origin)).collect();
        let cube = LightProjection::cube(origin, &turned).unwrap();
        assert!((cube.nearest - 0.5).abs() < 1e-5, "{}", cube.nearest);
        assert!(cube.faces[0].near < 0.45, "the axis near plane moved: {}", cube.faces[0].near);
        // Each Voronoi region of a triangle: a corner, an edge, the inside.
        let t = [DVec3::new(1.0, 0.0, 0.0), DVec3::new(3.0, 0.0, 0.0), DVec3::new(1.0, 2.0, 0.0)];
        let at = |p: DVec3| triangle_distance(t.map(|v| v - p));
        assert!((at(DVec3::new(0.0, -1.0, 0.0)) - 2f64.sqrt()).abs() < 1e-12);
        assert!((at(DVec3::new(2.0, -1.0, 0.0)) - 1.0).abs() < 1e-12);
        assert!((at(DVec3::new(1.5, 0.5, 0.7)) - 0.7).abs() < 1e-12);
        assert!((at(DVec3::new(3.0, 2.0, 0.0)) - 2f64.sqrt()).abs() < 1e-12);
    }

    /// A fixed pseudo-random sequence in [0, 1) (xorshift64) from `state` (not 0).
    fn xorshift(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn a_triangle_left_out_of_a_face_reaches_nothing_of_it_from_any_apex_within_reach() {
        // A fixed pseudo-random walk over triangles and apexes, in [-1, 1).
        let mut uniform = xorshift(0x9e3779b97f4a7c15);
        let mut next = || uniform() * 2.0 - 1.0;
        let reach = 0.3;
        let (mut left_out, mut kept) = (0, 0);
        for _ in 0..3000 {
            let centre = DVec3::new(next(), next(), next()) * 3.0;
            let tri = [0; 3].map(|_| centre + DVec3::new(next(), next(), next()) * 0.5);
            let mask = faces_reached(DVec3::ZERO, reach, tri);
            for f in 0..6 {
                if mask & (1 << f) != 0 {
                    kept += 1;
                    continue;
                }
                left_out += 1;
                for _ in 0..8 {
                    let apex = DVec3::new(next(), next(), next()).normalize_or_zero() * reach * next().abs();
                    assert!(clip_to_cone(tri.map(|p| p - apex), &cone_planes(f)).is_empty(), "{tri:?} reaches face {f} from {apex:?}");
                }
            }
        }
        // Most triangles are left out of most faces.
        assert!(left_out > 2 * kept, "{left_out} left out, {kept} kept");
        // A small triangle straight below the origin: the -y face only.
        let below = [DVec3::new(-0.1, -2.0, -0.1), DVec3::new(0.1, -2.0, -0.1), DVec3::new(0.0, -2.0, 0.1)];
        assert_eq!(faces_reached(DVec3::ZERO, 0.0, below), 1 << 3);
    }

    #[test]
    fn every_point_a_caster_may_shade_from_any_point_of_the_light_projects_into_the_window() {
        // Points P hidden from a light point L by a point C of a caster
        // triangle lie on the ray from L through C beyond it (issue 30: the
        // frustum covers the casters and their penumbrae, not the floor).
        let mut next = xorshift(0x2545f4914f6cdd1d);
        let floor: Vec<Vec3> = [(-20.0, -20.0), (20.0, -20.0), (20.0, 20.0), (-20.0, 20.0)].iter().map(|&(x, z)| Vec3::new(x, -1.0, z)).collect();
        for case in 0..40 {
            let radius = 0.05 + 0.6 * next();
            let origin = DVec3::new(next() - 0.5, 2.0 + next(), next() - 0.5);
            let tris: Vec<[DVec3; 3]> =
                (0..4).map(|_| [0; 3].map(|_| DVec3::new(2.0 * next() - 1.0, next() * 0.8, 2.0 * next() - 1.0))).collect();
            let casters: Vec<Vec3> = tris.iter().flatten().map(|p| p.as_vec3()).collect();
            let mut depths = casters.clone();
            depths.extend(&floor);
            let f = LightFrustum::fit_balls(origin.as_vec3(), &casters, radius as f32, bounds(&depths)).unwrap();
            let w = f.window;
            assert!(((w.y - w.x) - (w.w - w.z)).abs() < 1e-5 * (w.y - w.x), "square texels: {w}");
            let view = f.view.as_dmat4();
            for _ in 0..2000 {
                let l = loop {
                    let d = DVec3::new(2.0 * next() - 1.0, 2.0 * next() - 1.0, 2.0 * next() - 1.0);
                    if d.length() <= 1.0 {
                        break origin + d * radius;
                    }
                };
                let t = tris[(next() * 4.0) as usize % 4];
                let (a, b) = (next(), next());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                let c = t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]);
                let p = l + (c - l) * (1.0 + 50.0 * next());
                let q = view.transform_point3(p);
                let (u, v) = (q.x / -q.z, q.y / -q.z);
                assert!(-q.z > 0.0, "case {case}: {p} behind the light");
                let inside = |x: f64, lo: f32, hi: f32| x >= f64::from(lo) && x <= f64::from(hi);
                assert!(inside(u, w.x, w.y) && inside(v, w.z, w.w), "case {case}: {p} at ({u}, {v}) outside {w}");
            }
            // The far plane spans the floor; the near plane only the casters.
            assert!(f.far > 3.0 && f.near > 0.5 * (origin.y as f32 - 0.8 - radius as f32).max(0.0), "{} {}", f.near, f.far);
        }
        // A light close over a wide caster: its penumbra needs more than one
        // frustum's 80 degrees, and the fit says so.
        let wide = [Vec3::new(-3.0, 0.0, -3.0), Vec3::new(3.0, 0.0, -3.0), Vec3::new(0.0, 0.0, 3.0)];
        assert!(LightFrustum::fit_balls(Vec3::new(0.0, 0.5, 0.0), &wide, 0.4, bounds(&wide)).is_err());
    }
}
