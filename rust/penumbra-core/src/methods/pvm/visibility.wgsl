#import shaders/receiver.wgsl
#import passes/shadow_test.wgsl
#import shaders/per_pixel.wgsl

// PVM pass 3 (Cournia 4.2, listing 4.2): light visibility per camera pixel.
// Inside a penumbra volume (the PVDM is nearer the light than the pixel),
// visibility is the fraction of a disk of the light's radius, centred on the
// light and perpendicular to the cutting plane through the stored silhouette
// edge and the pixel, that lies on the unoccluded side (Eq. 4.1, 4.2), with
// the optional 3k^2 - 2k^3 falloff; outside, the shadow-map test decides.

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
@group(0) @binding(3) var volume_depth: texture_depth_2d_array;
// The penumbra volume edge map (4.1.3), by index into `edges` (`EDGE_INDEX_FORMAT` in pvm/mod.rs).
@group(0) @binding(4) var edge_index: texture_2d_array<u32>;
struct EdgePoints {
    h0: vec4<f32>,
    h1: vec4<f32>,
};
@group(0) @binding(5) var<storage, read> edges: array<EdgePoints>;
// mode.y bit 0: falloff; bit 1: repair "centre"; bit 2: repair "horizon".
@group(0) @binding(6) var<storage, read> pvm: ShadowTest;
@group(0) @binding(7) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(8) var membership_out: texture_storage_2d<r32float, write>;
@group(0) @binding(9) var<storage, read_write> pixels_in_volume: atomic<u32>;
// The object map and each mesh's object (passes/object_map.rs), for the horizon repair.
@group(0) @binding(10) var object_map: texture_2d_array<u32>;
@group(0) @binding(11) var<storage, read> mesh_objects: array<u32>;

// v / |v| without overflow or underflow for any finite v (zero for zero):
// scaled by its largest component first, so that the squares stay near 1.
fn unit(v: vec3<f32>) -> vec3<f32> {
    let big = max(max(abs(v.x), abs(v.y)), abs(v.z));
    if (big == 0.0) {
        return v;
    }
    let w = v / big;
    return w / length(w);
}

// k of Eq. 4.2 for the silhouette edge h0-h1 and the receiver p
// (disk_fraction, Eq. 4.1, is in passes/shadow_test.wgsl).
fn volume_visibility(p: vec3<f32>, h0: vec3<f32>, h1: vec3<f32>) -> f32 {
    let r = pvm.center.w;
    let l = pvm.center.xyz;
    // Cutting plane through h0, h1 and p (4.2). Silhouette edges are oriented
    // so that (h1 - h0) x (h0 - l), the hard-shadow plane's normal, points
    // away from the occluder; so does this normal, which turns continuously
    // with p through the hard-shadow plane.
    // Both factors are made unit first: the cross product of raw differences
    // squares the scene's scale, and its length the square again, which
    // overflows f32 beyond coordinates of about 1e9 (issue 22: visibility
    // 1/2 everywhere in the volumes of a scene scaled by 1e10).
    let m = cross(unit(h1 - h0), unit(p - h0));
    let len = length(m);
    // p on the edge's line: the plane is undefined; half the light is the limit.
    if (len <= 1e-7) {
        return 0.5;
    }
    let n = m / len;
    // Signed distance of the light centre from the plane, measured towards the
    // occluder: the visible part of the disk is the part beyond the plane from
    // an occluded centre, so Eq. 4.1 applies with this s.
    let s = -(dot(n, l) - dot(n, h0));
    return disk_fraction(s, r);
}

// How far (in k) a volume's visibility may disagree with the shadow-map test
// at the light's centre before the volume is taken for another edge's: the
// test and the volume map are rasterised separately, so within a texel or
// two of the hard-shadow boundary they disagree by design.
const CENTRE_TOLERANCE: f32 = 0.1;

// Once per pixel inside the image (the entry point: shaders/per_pixel.wgsl).
fn shade(pixel: ScreenPixel) {
    let px = pixel.px;
    var v = 0.0;
    var inside = 0.0;
    if (pixel.geometry) {
        let p = pixel.p;
        let n = pixel.n;
        let cos_theta = light_cosine(pvm, p, n);
        let r = pvm.center.w;
        let horizon = (pvm.mode.y & 4u) != 0u && r > 0.0;
        // Repair "horizon" (beyond the paper, which takes the light's centre
        // for the surface's horizon test): the fraction of the light above
        // the receiver's tangent plane, by Eq. 4.1 with that plane as the
        // cutting plane. It bounds the visibility; a receiver whose centre
        // lies below its horizon sees that fraction of the light, unless the
        // object map says another object than its own hides the centre
        // (`horizon_sliver_seen`).
        var k_h = 1.0;
        if (horizon) {
            k_h = horizon_fraction(pvm, p, n);
        }
        // Centre below the surface's horizon: the surface itself hides it
        // (and only the horizon's sliver of the light can be seen).
        if (cos_theta > 0.0) {
            let q = biased_receiver(pvm, p, n, cos_theta);
            let centre_lit = q.w <= map_depth(pvm, shadow_map, q.xyz);
            v = select(0.0, 1.0, centre_lit);
            // Listing 4.2: in a volume when the PVDM is nearer the light than the pixel.
            if (image_depth(pvm, volume_depth, q.xyz) < q.w) {
                let dims = textureDimensions(edge_index);
                let m = map_point_in(pvm.light_space, light_map_point(pvm.light_space, q.xyz), dims);
                let t = map_texel(dims, m);
                // The depth map and the index map are written together: a
                // texel behind a volume holds an index (clamped all the same).
                let edge = edges[min(max(textureLoad(edge_index, t, m.layer, 0).x, 1u) - 1u, arrayLength(&edges) - 1u)];
                var k = volume_visibility(p, edge.h0.xyz, edge.h1.xyz);
                // Repair "centre" (beyond the paper): the volume nearest the
                // light at this texel need not be the one that shadows p
                // (4.3's overlap): a far edge's inner volume reaching past the
                // occluder's other side, or another edge's volume over an
                // umbra. k >= 1/2 means the centre is visible and k < 1/2 that
                // it is hidden; where the shadow map's test at the centre says
                // otherwise, the volume belongs to another edge and the test
                // decides alone.
                let agrees = select(k <= 0.5 + CENTRE_TOLERANCE, k >= 0.5 - CENTRE_TOLERANCE, centre_lit);
                if ((pvm.mode.y & 2u) == 0u || agrees) {
                    if ((pvm.mode.y & 1u) != 0u) {
                        // Parker et al.'s sinusoidal falloff, as the Bernstein interpolant (4.2).
                        k = k * k * (3.0 - 2.0 * k);
                    }
                    v = k;
                }
                inside = 1.0;
                atomicAdd(&pixels_in_volume, 1u);
            }
            if (horizon) {
                v = min(v, k_h);
            }
        } else if (horizon) {
            let own = mesh_objects[min(u32(pixel.normal_texel.w), arrayLength(&mesh_objects) - 1u)];
            v = select(0.0, k_h, horizon_sliver_seen(pvm, object_map, p, own));
        }
    }
    textureStore(visibility_out, px, vec4<f32>(v, 0.0, 0.0, 0.0));
    textureStore(membership_out, px, vec4<f32>(inside, 0.0, 0.0, 0.0));
}
