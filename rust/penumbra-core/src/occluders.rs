//! Occlusion queries against a scene's triangles on the CPU: a bounding
//! volume hierarchy and "is this segment blocked". The silhouette methods use
//! it to tell silhouette edges the light's centre sees from those hidden
//! behind other geometry (`silhouettes::visible_from_light`).

use glam::DVec3;

/// Triangles per leaf at most.
const LEAF: usize = 4;
/// Levels split by the surface area heuristic; below them median splits,
/// which bound the depth at `SAH_DEPTH + log2(triangles / LEAF) + 2`.
const SAH_DEPTH: usize = 24;

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
    /// Builds the hierarchy: binned surface-area-heuristic splits (a floor's
    /// large triangles apart from a mesh's small ones, so that boxes stay
    /// tight), median splits on the centroids' longest axis past `SAH_DEPTH`
    /// levels or where no bin boundary separates the centroids.
    pub fn build(triangles: Vec<[DVec3; 3]>) -> Self {
        let mut out = Self { nodes: Vec::with_capacity(2 * triangles.len() / LEAF + 1), triangles };
        if !out.triangles.is_empty() {
            let n = out.triangles.len();
            out.split(0, n, 0);
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

    /// The triangles in the hierarchy's order (a leaf's are contiguous).
    pub fn triangles(&self) -> &[[DVec3; 3]] {
        &self.triangles
    }

    /// The nodes depth first (a node's left child follows it): box, then
    /// `(first triangle, count)` for a leaf (count > 0, at most 4) or
    /// `(right child, 0)` for an inner node. The root is node 0.
    pub fn nodes(&self) -> impl Iterator<Item = (DVec3, DVec3, u32, u32)> + '_ {
        self.nodes.iter().map(|n| (n.lo, n.hi, n.start, n.count))
    }

    /// Nodes on the longest path from the root to a leaf (0 when empty):
    /// at most `SAH_DEPTH + log2(triangles / LEAF) + 2`; a traversal's
    /// stack of `depth()` entries never overflows.
    pub fn depth(&self) -> usize {
        fn down(nodes: &[Node], i: usize) -> usize {
            let n = nodes[i];
            if n.count > 0 {
                1
            } else {
                1 + down(nodes, i + 1).max(down(nodes, n.start as usize))
            }
        }
        if self.nodes.is_empty() {
            0
        } else {
            down(&self.nodes, 0)
        }
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

    /// Builds the node for triangles[start..end] at `depth` (the root's 0);
    /// returns its index.
    fn split(&mut self, start: usize, end: usize, depth: usize) -> usize {
        let (lo, hi) = Self::bounds(&self.triangles[start..end]);
        let index = self.nodes.len();
        self.nodes.push(Node { lo, hi, start: start as u32, count: (end - start) as u32 });
        if end - start <= LEAF {
            return index;
        }
        let centroid = |t: &[DVec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
        let (clo, chi) = self.triangles[start..end].iter().map(centroid).fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(a, b), c| (a.min(c), b.max(c)));
        let extent = chi - clo;
        let longest = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = match (depth < SAH_DEPTH).then(|| self.sah_split(start, end, clo, extent)).flatten() {
            Some(mid) => mid,
            None => {
                let mid = (end - start) / 2;
                self.triangles[start..end].select_nth_unstable_by(mid, |a, b| centroid(a)[longest].total_cmp(&centroid(b)[longest]));
                mid
            }
        };
        self.split(start, start + mid, depth + 1);
        let right = self.split(start + mid, end, depth + 1);
        self.nodes[index].start = right as u32;
        self.nodes[index].count = 0;
        index
    }

    /// The surface area heuristic over `BINS` bins of the centroids per
    /// axis (Wald, "On fast Construction of SAH-based Bounding Volume
    /// Hierarchies", 2007): the cut that minimises the children's areas
    /// times their triangle counts. Partitions triangles[start..end] at it
    /// and returns the left part's length; None when no cut separates the
    /// centroids (all in one bin on every axis), for a median split.
    fn sah_split(&mut self, start: usize, end: usize, clo: DVec3, extent: DVec3) -> Option<usize> {
        const BINS: usize = 16;
        let centroid = |t: &[DVec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
        let area = |lo: DVec3, hi: DVec3| {
            let d = (hi - lo).max(DVec3::ZERO);
            d.x * d.y + d.y * d.z + d.z * d.x
        };
        let empty = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let mut best: Option<(f64, usize, usize)> = None;
        for axis in 0..3 {
            // An axis along which the centroids do not spread has no cut.
            if !(extent[axis] > 0.0) {
                continue;
            }
            let scale = BINS as f64 / extent[axis];
            let bin = |t: &[DVec3; 3]| (((centroid(t)[axis] - clo[axis]) * scale) as usize).min(BINS - 1);
            let mut counts = [0usize; BINS];
            let mut boxes = [empty; BINS];
            for t in &self.triangles[start..end] {
                let b = bin(t);
                counts[b] += 1;
                for p in t {
                    boxes[b].0 = boxes[b].0.min(*p);
                    boxes[b].1 = boxes[b].1.max(*p);
                }
            }
            // Areas and counts of the bins left of each cut, then right of it.
            let mut left = [(0.0, 0usize); BINS];
            let (mut b, mut n) = (empty, 0);
            for i in 0..BINS - 1 {
                b = (b.0.min(boxes[i].0), b.1.max(boxes[i].1));
                n += counts[i];
                left[i] = (if n > 0 { area(b.0, b.1) } else { 0.0 }, n);
            }
            let (mut b, mut n) = (empty, 0);
            for i in (1..BINS).rev() {
                b = (b.0.min(boxes[i].0), b.1.max(boxes[i].1));
                n += counts[i];
                let (left_area, left_n) = left[i - 1];
                if left_n == 0 || n == 0 {
                    continue;
                }
                let cost = left_area * left_n as f64 + area(b.0, b.1) * n as f64;
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, i));
                }
            }
        }
        let (_, axis, cut) = best?;
        let scale = BINS as f64 / extent[axis];
        let bin = |t: &[DVec3; 3]| (((centroid(t)[axis] - clo[axis]) * scale) as usize).min(BINS - 1);
        // Partition: the triangles of bins below `cut` first.
        let slice = &mut self.triangles[start..end];
        let mut i = 0;
        for j in 0..slice.len() {
            if bin(&slice[j]) < cut {
                slice.swap(i, j);
                i += 1;
            }
        }
        // Both sides hold triangles (the cut's counts were both positive).
        Some(i)
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
        // The flattened nodes: every triangle in exactly one leaf, inside
        // its box and its ancestors'; the depth within the median bound.
        let nodes: Vec<_> = occ.nodes().collect();
        let mut seen = vec![0; occ.len()];
        fn visit(nodes: &[(DVec3, DVec3, u32, u32)], tris: &[[DVec3; 3]], i: usize, lo: DVec3, hi: DVec3, seen: &mut [u32]) {
            let (a, b, start, count) = nodes[i];
            assert!(a.cmpge(lo).all() && b.cmple(hi).all());
            if count > 0 {
                for t in start..start + count {
                    seen[t as usize] += 1;
                    assert!(tris[t as usize].iter().all(|p| p.cmpge(a).all() && p.cmple(b).all()));
                }
            } else {
                visit(nodes, tris, i + 1, a, b, seen);
                visit(nodes, tris, start as usize, a, b, seen);
            }
        }
        visit(&nodes, occ.triangles(), 0, nodes[0].0, nodes[0].1, &mut seen);
        assert!(seen.iter().all(|&k| k == 1));
        assert!(occ.depth() <= SAH_DEPTH + (300f64 / 4.0).log2().ceil() as usize + 2, "{}", occ.depth());
        assert_eq!(Occluders::build(Vec::new()).depth(), 0);
    }
}
