//! Occlusion queries against a scene's triangles on the CPU: a bounding
//! volume hierarchy and "is this segment blocked". The silhouette methods use
//! it to tell silhouette edges the light's centre sees from those hidden
//! behind other geometry (`silhouettes::visible_from_light`).

use glam::DVec3;

/// Triangles per leaf at most.
const LEAF: usize = 4;

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first triangle and count (count > 0). Inner: `start` is the
    /// right child (the left child follows this node), count 0.
    start: u32,
    count: u32,
}

/// A bounding volume hierarchy over world-space triangles.
#[derive(Debug, Clone, Default)]
pub struct Occluders {
    nodes: Vec<Node>,
    triangles: Vec<[DVec3; 3]>,
}

impl Occluders {
    /// Builds the hierarchy (median splits on the longest axis of the centroids).
    pub fn build(triangles: Vec<[DVec3; 3]>) -> Self {
        let mut out = Self { nodes: Vec::with_capacity(2 * triangles.len() / LEAF + 1), triangles };
        if !out.triangles.is_empty() {
            let n = out.triangles.len();
            out.split(0, n);
        }
        out
    }

    /// Triangles of every mesh, in world space.
    pub fn from_meshes<'a>(meshes: impl IntoIterator<Item = (&'a [DVec3], &'a [[u32; 3]])>) -> Self {
        let mut triangles = Vec::new();
        for (vertices, faces) in meshes {
            triangles.extend(faces.iter().map(|f| f.map(|i| vertices[i as usize])));
        }
        Self::build(triangles)
    }

    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    fn bounds(triangles: &[[DVec3; 3]]) -> (DVec3, DVec3) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for t in triangles {
            for p in t {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        (lo, hi)
    }

    /// Builds the node for triangles[start..end]; returns its index.
    fn split(&mut self, start: usize, end: usize) -> usize {
        let (lo, hi) = Self::bounds(&self.triangles[start..end]);
        let index = self.nodes.len();
        self.nodes.push(Node { lo, hi, start: start as u32, count: (end - start) as u32 });
        if end - start <= LEAF {
            return index;
        }
        let centroid = |t: &[DVec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
        let (clo, chi) = self.triangles[start..end].iter().map(centroid).fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(a, b), c| (a.min(c), b.max(c)));
        let extent = chi - clo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = (end - start) / 2;
        self.triangles[start..end].select_nth_unstable_by(mid, |a, b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
        self.split(start, start + mid);
        let right = self.split(start + mid, end);
        self.nodes[index].start = right as u32;
        self.nodes[index].count = 0;
        index
    }

    /// Whether a triangle crosses the open segment from `from` to `to`
    /// (its ends excluded by `1e-9` of its length).
    pub fn blocks(&self, from: DVec3, to: DVec3) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let d = to - from;
        // 1/0 is +-inf in IEEE arithmetic, which the slab test handles.
        let inv = DVec3::ONE / d;
        let (t_min, t_max) = (1e-9, 1.0 - 1e-9);
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let node = self.nodes[i];
            if !slab(node.lo, node.hi, from, inv, t_min, t_max) {
                continue;
            }
            if node.count > 0 {
                let range = node.start as usize..(node.start + node.count) as usize;
                if self.triangles[range].iter().any(|t| crosses(t, from, d, t_min, t_max)) {
                    return true;
                }
            } else {
                stack.push(node.start as usize);
                stack.push(i + 1);
            }
        }
        false
    }
}

/// Whether the segment from + t d, t in [t0, t1], meets the box.
fn slab(lo: DVec3, hi: DVec3, from: DVec3, inv: DVec3, t0: f64, t1: f64) -> bool {
    let a = (lo - from) * inv;
    let b = (hi - from) * inv;
    // 0 * inf is NaN for a segment lying in a slab's plane: max/min ignore NaN.
    let near = a.min(b).max_element().max(t0);
    let far = a.max(b).min_element().min(t1);
    near <= far
}

/// Möller-Trumbore: whether the segment from + t d, t in (t0, t1), crosses triangle `t`.
fn crosses(t: &[DVec3; 3], from: DVec3, d: DVec3, t0: f64, t1: f64) -> bool {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let h = d.cross(e2);
    let det = e1.dot(h);
    // Parallel to the triangle's plane (or a degenerate triangle): no crossing.
    if det.abs() <= 1e-300 || !det.is_finite() {
        return false;
    }
    let s = from - t[0];
    let u = s.dot(h) / det;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = e2.dot(q) / det;
    t > t0 && t < t1
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize, y: f64) -> Vec<[DVec3; 3]> {
        let mut out = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (x, z) = (i as f64, j as f64);
                out.push([DVec3::new(x, y, z), DVec3::new(x, y, z + 1.0), DVec3::new(x + 1.0, y, z)]);
                out.push([DVec3::new(x + 1.0, y, z), DVec3::new(x, y, z + 1.0), DVec3::new(x + 1.0, y, z + 1.0)]);
            }
        }
        out
    }

    #[test]
    fn segments_through_a_plane_of_triangles_are_blocked_and_others_not() {
        let occ = Occluders::build(grid(8, 1.0));
        assert_eq!(occ.len(), 128);
        // Through the plane, anywhere over it (including across shared edges).
        for (x, z) in [(0.5, 0.5), (3.0, 4.0), (7.9, 0.1), (4.0, 4.0)] {
            assert!(occ.blocks(DVec3::new(x, 3.0, z), DVec3::new(x, -1.0, z)), "({x}, {z})");
        }
        // Beside it, stopping short of it, or lying in a parallel plane.
        assert!(!occ.blocks(DVec3::new(9.0, 3.0, 4.0), DVec3::new(9.0, -1.0, 4.0)));
        assert!(!occ.blocks(DVec3::new(4.0, 3.0, 4.0), DVec3::new(4.0, 1.5, 4.0)));
        assert!(!occ.blocks(DVec3::new(-1.0, 2.0, 4.0), DVec3::new(9.0, 2.0, 4.0)));
        // Axis-aligned segments (zero direction components) and an empty set.
        assert!(occ.blocks(DVec3::new(2.5, 0.0, 2.5), DVec3::new(2.5, 2.0, 2.5)));
        assert!(!Occluders::build(Vec::new()).blocks(DVec3::ZERO, DVec3::ONE));
    }

    #[test]
    fn agrees_with_brute_force_on_random_segments() {
        // A deterministic scatter of triangles and segments (an LCG, no extra crate).
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut point = || DVec3::new(next(), next(), next()) * 10.0;
        let triangles: Vec<[DVec3; 3]> = (0..300)
            .map(|_| {
                let c = point();
                [c, c + (point() - DVec3::splat(5.0)) * 0.2, c + (point() - DVec3::splat(5.0)) * 0.2]
            })
            .collect();
        let occ = Occluders::build(triangles.clone());
        let mut blocked = 0;
        for _ in 0..2000 {
            let (a, b) = (point(), point());
            let brute = triangles.iter().any(|t| crosses(t, a, b - a, 1e-9, 1.0 - 1e-9));
            assert_eq!(occ.blocks(a, b), brute, "{a} -> {b}");
            blocked += usize::from(brute);
        }
        assert!(blocked > 100 && blocked < 1900, "{blocked}");
    }
}
