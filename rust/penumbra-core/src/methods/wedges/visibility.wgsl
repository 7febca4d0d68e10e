#import shaders/receiver.wgsl
#import passes/shadow_test.wgsl

// Method `wedges` (Akenine-Möller & Assarsson 2002): light intensity per
// camera pixel. The hard shadow from the light centre (the shadow map of
// `hard`) stands for the shadow-volume count; every penumbra wedge that
// holds the pixel's point p then adds s(p) - h(p) to the light-intensity
// sum, where s is the interpolated intensity of 4.2 (Eq. 1-3) and h the
// hard shadow that wedge's shadow-volume quad gives p (1 on its lit side,
// 0 behind it). That is the paper's per-wedge term s(p_i) - s(p_f) with the
// quad's own step subtracted: the entry and exit terms of wedges the camera
// ray crosses sum to the shadow-volume count, which the map already holds.
// The sum is clamped to [0, 1] (4, after the pseudocode).

struct Wedge {
    a: vec4<f32>,
    b: vec4<f32>,
    dir: vec4<f32>,
    front: vec4<f32>,
    back: vec4<f32>,
    hard: vec4<f32>,
    left: vec4<f32>,
    right: vec4<f32>,
    u_left: vec4<f32>,
    u_right: vec4<f32>,
};

struct WedgeSettings {
    // x: tile size in pixels; y: tiles per row; z: flags (bit 0: falloff,
    // bit 1: repair "horizon", bit 2: hard_term "lit_side"); w: wedge count.
    tiles: vec4<u32>,
};

@group(0) @binding(2) var shadow_map: texture_depth_2d_array;
@group(0) @binding(3) var<storage, read> wedge_test: ShadowTest;
@group(0) @binding(4) var<storage, read> wedges: array<Wedge>;
@group(0) @binding(5) var<storage, read> tile_offsets: array<u32>;
@group(0) @binding(6) var<storage, read> tile_wedges: array<u32>;
@group(0) @binding(7) var<storage, read> settings: WedgeSettings;
@group(0) @binding(8) var visibility_out: texture_storage_2d<r32float, write>;
@group(0) @binding(9) var hard_out: texture_storage_2d<r32float, write>;
@group(0) @binding(10) var intensity_out: texture_storage_2d<r32float, write>;
@group(0) @binding(11) var<storage, read_write> pixels_in_wedge: atomic<u32>;

// Eq. 1-2 along the side ray u: p's distances to the front plane (F <= 0
// inside) and the back plane (B >= 0 inside), as fractions of the chord.
// The ray meets the front plane ahead (N_f.u > 0) and the back plane behind
// (N_b.u > 0) for any light smaller than its distance; the floors keep the
// quotient finite otherwise, and a point on the edge's line takes 1/2.
fn side_intensity(f: f32, b: f32, w: Wedge, u: vec3<f32>) -> f32 {
    let tf = -f / max(dot(w.front.xyz, u), 1e-6);
    let tb = b / max(dot(w.back.xyz, u), 1e-6);
    let sum = tf + tb;
    if (sum <= 0.0) {
        return 0.5;
    }
    return clamp(tb / sum, 0.0, 1.0);
}

// The contribution s(p) - h(p) of wedge w at p, or none (x = 0 flag in y).
fn wedge_term(w: Wedge, p: vec3<f32>) -> vec2<f32> {
    let pa = p - w.a.xyz;
    let f = dot(w.front.xyz, pa);
    if (f > 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let b = dot(w.back.xyz, pa);
    if (b < 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let tl_plane = dot(w.left.xyz, pa);
    if (tl_plane < 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    let tr_plane = dot(w.right.xyz, p - w.b.xyz);
    if (tr_plane < 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    // Eq. 2 in each side plane, then Eq. 3 along the edge's direction.
    let s_l = side_intensity(f, b, w, w.u_left.xyz);
    let s_r = side_intensity(f, b, w, w.u_right.xyz);
    let t_l = tl_plane / max(dot(w.left.xyz, w.dir.xyz), 1e-6);
    let t_r = tr_plane / max(-dot(w.right.xyz, w.dir.xyz), 1e-6);
    var s = 0.5 * (s_l + s_r);
    if (t_l + t_r > 0.0) {
        s = (t_r * s_l + t_l * s_r) / (t_l + t_r);
    }
    if ((settings.tiles.z & 1u) != 0u) {
        // Parker et al.'s sinusoidal attenuation, s' = 3s^2 - 2s^3 (4.2).
        s = s * s * (3.0 - 2.0 * s);
    }
    // h: the quad's step, or 1 where the map is read on every quad's lit side.
    let h = select(0.0, 1.0, dot(w.hard.xyz, pa) > 0.0 || (settings.tiles.z & 4u) != 0u);
    return vec2<f32>(s - h, 1.0);
}

// Texels (besides the normal offset) a pixel near a wedge's quad plane is
// moved off it for the shadow-map read (see main).
const CONSISTENCY_TEXELS: f32 = 2.0;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let pixel = screen_pixel(id);
    if (!pixel.inside) {
        return;
    }
    let px = pixel.px;
    var v = 0.0;
    var hard = 0.0;
    var intensity = 0.0;
    if (pixel.geometry) {
        let p = pixel.p;
        let n = pixel.n;
        let r = wedge_test.center.w;
        let cos_theta = light_cosine(wedge_test, p, n);
        let horizon = (settings.tiles.z & 2u) != 0u && r > 0.0;
        var k_h = 1.0;
        if (horizon) {
            k_h = horizon_fraction(wedge_test, p, n);
        }
        if (cos_theta > 0.0) {
            // The shadow map and a wedge's quad plane draw the same hard
            // boundary only to within a texel or two (rasterisation and
            // bias). Where p lies that close to the quad plane of a wedge
            // holding it, the map is read at p moved, in its tangent plane,
            // to CONSISTENCY_TEXELS off that plane on the side h(p) gives,
            // so that the map's count and the wedge's step agree (otherwise
            // a lone pixel gets 1 + s or s - 1).
            let texel = light_texel_size(wedge_test.light_space, light_view_depth(wedge_test.light_space, p));
            let margin = (CONSISTENCY_TEXELS + wedge_test.bias.x) * texel;
            var push = vec3<f32>(0.0);
            var terms = 0.0;
            let tile = vec2<u32>(px) / settings.tiles.x;
            let t = tile.y * settings.tiles.y + tile.x;
            let start = tile_offsets[t];
            let end = tile_offsets[t + 1u];
            var inside = false;
            for (var i = start; i < end; i = i + 1u) {
                let w = wedges[tile_wedges[i]];
                let term = wedge_term(w, p);
                if (term.y > 0.0) {
                    terms = terms + term.x;
                    inside = true;
                    let d = dot(w.hard.xyz, p - w.a.xyz);
                    // The side the map is read on: h(p)'s, or always the lit one.
                    let lit = d > 0.0 || (settings.tiles.z & 4u) != 0u;
                    if (abs(d) < margin || (lit && d < margin)) {
                        let along = w.hard.xyz - n * dot(w.hard.xyz, n);
                        // How fast moving along `along` leaves the plane;
                        // a quad plane nearly parallel to the receiver is
                        // left alone (the move would be long).
                        let rate = dot(along, w.hard.xyz);
                        if (rate > 0.05) {
                            push = push + along * ((select(-margin, margin, lit) - d) / rate);
                        }
                    }
                }
            }
            // p + push lies in p's tangent plane: its biased depth is the receiver's there.
            let q = biased_receiver(wedge_test, p + push, n, cos_theta);
            hard = select(0.0, 1.0, q.w <= map_depth(wedge_test, shadow_map, q.xyz));
            intensity = hard + terms;
            if (inside) {
                atomicAdd(&pixels_in_wedge, 1u);
            }
            v = clamp(intensity, 0.0, 1.0);
            if (horizon) {
                v = min(v, k_h);
            }
        } else if (horizon) {
            v = k_h;
        }
    }
    textureStore(visibility_out, px, vec4<f32>(v, 0.0, 0.0, 0.0));
    textureStore(hard_out, px, vec4<f32>(hard, 0.0, 0.0, 0.0));
    textureStore(intensity_out, px, vec4<f32>(intensity, 0.0, 0.0, 0.0));
}
