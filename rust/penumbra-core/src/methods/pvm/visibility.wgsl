#import shaders/receiver.wgsl
#import passes/shadow_test.wgsl

// PVM pass 3 (Cournia 4.2, listing 4.2): light visibility per camera pixel.
// Inside a penumbra volume (the PVDM is nearer the light than the pixel),
// visibility is the fraction of a disk of the light's radius, centred on the
// light and perpendicular to the cutting plane through the stored silhouette
// edge and the pixel, that lies on the unoccluded side (Eq. 4.1, 4.2), with
// the optional 3k^2 - 2k^3 falloff; outside, the shadow-map test decides.

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
@group(0) @binding(3) var volume_depth: texture_depth_2d_array;
@group(0) @binding(4) var edge0_map: texture_2d_array<f32>;
@group(0) @binding(5) var edge1_map: texture_2d_array<f32>;
// mode.y bit 0: falloff.
@group(0) @binding(6) var<storage, read> pvm: ShadowTest;
@group(0) @binding(7) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(8) var membership_out: texture_storage_2d<r32float, write>;
@group(0) @binding(9) var<storage, read_write> pixels_in_volume: atomic<u32>;

// Eq. 4.1 and 4.2: the fraction of a disk of radius r whose centre lies at
// signed distance s from a line, on the far side of the line from the centre
// when s > 0 (and on the centre's side when s < 0). Continuous in s, 1/2 at 0.
fn disk_fraction(s: f32, r: f32) -> f32 {
    let c = clamp(s / r, -1.0, 1.0);
    // a = acos(s/r) r^2 / 2 - s sqrt(r^2 - s^2) / 2; k = 2a / (pi r^2), in units of r.
    let a = 0.5 * acos(c) - 0.5 * c * sqrt(max(1.0 - c * c, 0.0));
    return clamp(2.0 * a / PI, 0.0, 1.0);
}

fn volume_visibility(p: vec3<f32>, h0: vec3<f32>, h1: vec3<f32>) -> f32 {
    let r = pvm.center.w;
    let l = pvm.center.xyz;
    // Cutting plane through h0, h1 and p (4.2). Silhouette edges are oriented
    // so that (h1 - h0) x (h0 - l), the hard-shadow plane's normal, points
    // away from the occluder; so does this normal, which turns continuously
    // with p through the hard-shadow plane.
    let m = cross(h1 - h0, p - h0);
    let len = length(m);
    // p on the edge's line: the plane is undefined; half the light is the limit.
    if (len <= 1e-12 * max(dot(h1 - h0, h1 - h0), 1e-30)) {
        return 0.5;
    }
    let n = m / len;
    // Signed distance of the light centre from the plane, measured towards the
    // occluder: the visible part of the disk is the part beyond the plane from
    // an occluded centre, so Eq. 4.1 applies with this s.
    let s = -(dot(n, l) - dot(n, h0));
    let k = disk_fraction(s, r);
    if ((pvm.mode.y & 1u) != 0u) {
        // Parker et al.'s sinusoidal falloff, as the Bernstein interpolant (4.2).
        return k * k * (3.0 - 2.0 * k);
    }
    return k;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(id);
    if (!pixel.inside) {
        return;
    }
    let px = pixel.px;
    var v = 0.0;
    var inside = 0.0;
    if (pixel.geometry) {
        let p = pixel.p;
        let n = pixel.n;
        let cos_theta = light_cosine(pvm, p, n);
        // Centre below the surface's horizon: the surface itself hides it.
        if (cos_theta > 0.0) {
            let q = biased_receiver(pvm, p, n, cos_theta);
            // Listing 4.2: in a volume when the PVDM is nearer the light than the pixel.
            if (map_depth(pvm, volume_depth, q.xyz) < q.w) {
                let m = light_map_point(pvm.light_space, q.xyz);
                let t = map_texel(textureDimensions(edge0_map), m);
                v = volume_visibility(p, textureLoad(edge0_map, t, m.layer, 0).xyz, textureLoad(edge1_map, t, m.layer, 0).xyz);
                inside = 1.0;
                atomicAdd(&pixels_in_volume, 1u);
            } else {
                v = select(0.0, 1.0, q.w <= map_depth(pvm, shadow_map, q.xyz));
            }
        }
    }
    textureStore(visibility_out, px, vec4<f32>(v, 0.0, 0.0, 0.0));
    textureStore(membership_out, px, vec4<f32>(inside, 0.0, 0.0, 0.0));
}
