//! A straight segment against a triangulation: the stretch of it inside a triangle (for
//! profiles along a line), and whether it crosses the mesh at all.

use rayon::prelude::*;

/// The part of the segment `a + t d`, `t ∈ [0, 1]`, inside the triangle with corners `p`:
/// `[lo, hi]` and the barycentric coordinates `λ_k(t) = α_k + β_k t` as `[α_k, β_k]`;
/// `None` when the segment misses the triangle or only touches it.
pub fn clip(p: [[f64; 2]; 3], a: [f64; 2], d: [f64; 2]) -> Option<([f64; 2], [[f64; 2]; 3])> {
    let b = [a[0] + d[0], a[1] + d[1]];
    let (xmin, xmax) = (
        p[0][0].min(p[1][0]).min(p[2][0]),
        p[0][0].max(p[1][0]).max(p[2][0]),
    );
    let (ymin, ymax) = (
        p[0][1].min(p[1][1]).min(p[2][1]),
        p[0][1].max(p[1][1]).max(p[2][1]),
    );
    if xmax < a[0].min(b[0])
        || xmin > a[0].max(b[0])
        || ymax < a[1].min(b[1])
        || ymin > a[1].max(b[1])
    {
        return None;
    }
    let area =
        (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
    if area == 0.0 {
        return None;
    }
    // λ_k(t) = (α_k + β_k t) / area, the barycentric coordinate of vertex k.
    let mut lo = 0.0f64;
    let mut hi = 1.0f64;
    let mut ab = [[0.0; 2]; 3];
    for k in 0..3 {
        let (q, r) = (p[(k + 1) % 3], p[(k + 2) % 3]);
        let e = |x: [f64; 2]| (r[0] - q[0]) * (x[1] - q[1]) - (r[1] - q[1]) * (x[0] - q[0]);
        let alpha = e(a) / area;
        let beta = ((r[0] - q[0]) * d[1] - (r[1] - q[1]) * d[0]) / area;
        ab[k] = [alpha, beta];
        // alpha + beta t ≥ 0
        if beta > 0.0 {
            lo = lo.max(-alpha / beta);
        } else if beta < 0.0 {
            hi = hi.min(-alpha / beta);
        } else if alpha < 0.0 {
            hi = -1.0;
        }
    }
    (hi - lo > 1e-12).then_some(([lo, hi], ab))
}

/// Whether the segment `a → b` crosses the triangulation (a stretch of positive length
/// inside some triangle): a profile along it can be drawn.
pub fn crosses(points: &[[f64; 2]], triangles: &[[u32; 3]], a: [f64; 2], b: [f64; 2]) -> bool {
    let d = [b[0] - a[0], b[1] - a[1]];
    triangles
        .par_iter()
        .any(|t| clip(t.map(|v| points[v as usize]), a, d).is_some())
}
