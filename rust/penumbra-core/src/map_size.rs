//! `map_size="auto"`: the shadow map's resolution from the image.
//!
//! A shadow map is fine enough when one of its texels, projected onto a
//! receiver the camera sees, is no larger than one of the image's pixels
//! there (perspective aliasing: Stamminger and Drettakis 2002, Lloyd et al.
//! 2008 state it the same way). At a point `p` seen at camera depth `z_c`,
//! a pixel spans `2 z_c tan(fov_y / 2) / height` world units; in a light
//! face whose window spans `w` units on its unit-depth plane, a texel of an
//! `n`-texel map spans `w z_l / n` at light depth `z_l`. Both ignore the
//! receiver's slant, which stretches the two footprints alike when the light
//! is near the camera and in the light's favour when it looks down on what
//! the camera sees at a grazing angle. So the map needs
//! `n >= TEXELS_PER_PIXEL * max over visible p of (w z_l(p)) / (pixel(p))`.
//!
//! The maximum is taken over the scene's triangles clipped to the camera's
//! frustum. On each such polygon (and each light face) the ratio is a
//! quotient of two affine functions of `p`, whose maximum over a convex
//! polygon lies at one of its corners; for cube maps the light depth is the
//! largest of the faces' (the max-norm of `p` in the light's frame), which
//! keeps that property. Occlusion is ignored (a hidden triangle can only ask
//! for more texels than needed, never fewer). The result is rounded up to a
//! power of two and held to [`MIN_AUTO`, the adapter's largest texture side,
//! [`MAX_AUTO`] or [`MAX_AUTO_CUBE`] per cube face].
//!
//! Not the default (`penumbra bench --config benchmarks/map_size.toml`, docs/scaling.md): matching
//! texels to pixels removes the aliasing, and on the built-in scenes at
//! 128x128 the maps it picks (256-512) are within the ground truth's noise of
//! 2048 at a fraction of the time; but the methods' other errors scale with
//! the texel too (biases counted in texels, shadow edges quantised to texels
//! under pixels that Mitsuba integrates), and on the real meshes with a small
//! light seen close the 256 maps it picks lose up to 0.17 penumbra RMSE
//! against 2048. A user who wants speed at small sizes asks for it.

use glam::DVec3;

use crate::light_frustum::{clip_to_cone, LightProjection};
use crate::scene::{Camera, PreparedScene};

/// Texels per pixel along a side, on the receiver where they are densest
/// relative to the pixels. 1 matches one texel to one pixel (the aliasing
/// criterion); measured by `penumbra bench --config benchmarks/map_size.toml` against maps of 2048
/// (docs/scaling.md).
pub const TEXELS_PER_PIXEL: f64 = 1.0;

/// The smallest automatic map: below it the maps are too coarse for the
/// kernels that count in texels (PCF's) on tiny images, and cost nothing.
pub const MIN_AUTO: u32 = 256;
/// The largest automatic map of one frustum (64 MiB of 32-bit depth).
pub const MAX_AUTO: u32 = 4096;
/// The largest automatic cube-map face (six of them: 96 MiB).
pub const MAX_AUTO_CUBE: u32 = 2048;

/// The automatic `map_size` for `projection`, `camera` and the scene's
/// triangles, at most `max_side` (the adapter's largest texture side).
pub fn auto_map_size(projection: &LightProjection, camera: &Camera, scene: &PreparedScene, max_side: u32) -> u32 {
    let needed = needed_texels(projection, camera, scene);
    let cap = if projection.is_cube() { MAX_AUTO_CUBE } else { MAX_AUTO }.min(max_side);
    // needed is finite and >= 0 (or NaN, which the float-to-int cast makes 0).
    let n = (needed.min(cap as f64).ceil() as u32).max(1).next_power_of_two();
    n.clamp(MIN_AUTO.min(cap), cap)
}

/// `TEXELS_PER_PIXEL * max (w z_l) / pixel` over the visible triangles: the
/// map resolution that gives every visible receiver a texel no larger than
/// its pixel; 0 when no triangle is in view.
pub fn needed_texels(projection: &LightProjection, camera: &Camera, scene: &PreparedScene) -> f64 {
    let eye = DVec3::from(camera.eye.map(f64::from));
    let view = camera.view().as_dmat4();
    let inverse = view.inverse();
    // Camera basis: right, up and forward (view space looks down -z).
    let (right, up, forward) = (
        inverse.transform_vector3(DVec3::X).normalize_or_zero(),
        inverse.transform_vector3(DVec3::Y).normalize_or_zero(),
        inverse.transform_vector3(DVec3::NEG_Z).normalize_or_zero(),
    );
    let tan_y = (f64::from(camera.fov_y_degrees).to_radians() * 0.5).tan();
    let tan_x = tan_y * f64::from(camera.width) / f64::from(camera.height);
    // Inward normals of the four side planes through the eye.
    let planes = [forward * tan_x - right, forward * tan_x + right, forward * tan_y - up, forward * tan_y + up];
    let (_, near, _) = camera.projection(scene.bounds_min, scene.bounds_max);
    // The pixel footprint per unit camera depth; the depth is held at the
    // near plane, where the camera starts seeing (camera.validate keeps the
    // fov in (0, 180) and the height positive, so this is finite and > 0).
    let pixel_per_depth = 2.0 * tan_y / f64::from(camera.height);
    let near = f64::from(near).max(f64::MIN_POSITIVE);
    let faces: Vec<(glam::DMat4, f64)> = projection
        .active_layers()
        .map(|(_, face)| {
            let w = face.window;
            (face.view.as_dmat4(), f64::from((w.y - w.x).max(w.w - w.z)))
        })
        .collect();
    let ratio = |d: DVec3| -> f64 {
        // d is relative to the eye; the light works in world space.
        let p = eye + d;
        let z_c = d.dot(forward).max(near);
        let texel = faces
            .iter()
            .map(|(v, w)| {
                let z_l = -v.transform_point3(p).z;
                if z_l > 0.0 { w * z_l } else { 0.0 }
            })
            .fold(0.0f64, f64::max);
        texel / (z_c * pixel_per_depth)
    };
    let mut worst = 0.0f64;
    for mesh in &scene.meshes {
        // Per vertex: relative to the eye, and inside all four planes.
        let rel: Vec<DVec3> = mesh.vertices.iter().map(|v| *v - eye).collect();
        let inside: Vec<u8> = rel.iter().map(|d| planes.iter().fold(0u8, |m, n| (m << 1) | u8::from(n.dot(*d) >= 0.0))).collect();
        let mut vertex_ratio: Vec<f64> = vec![f64::NAN; rel.len()];
        for face in &mesh.faces {
            let [a, b, c] = face.map(|i| i as usize);
            let (ia, ib, ic) = (inside[a], inside[b], inside[c]);
            if ia & ib & ic == 0b1111 {
                // Wholly inside the side planes: the corners' own ratios.
                for i in [a, b, c] {
                    if vertex_ratio[i].is_nan() {
                        vertex_ratio[i] = ratio(rel[i]);
                    }
                    worst = worst.max(vertex_ratio[i]);
                }
            } else if ia | ib | ic == 0b1111 {
                // Possibly straddling: clip (a triangle outside one plane
                // with every corner comes back empty).
                for d in clip_to_cone([rel[a], rel[b], rel[c]], &planes) {
                    worst = worst.max(ratio(d));
                }
            }
        }
    }
    TEXELS_PER_PIXEL * worst
}
