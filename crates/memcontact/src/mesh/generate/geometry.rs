//! Planar geometry of polygon rings: orientation, areas, intersections, containment.

use crate::error::{Error, Result};
use crate::mesh::Point;

/// The distance from `p` to the segment `ab`.
pub(super) fn segment_distance(p: Point, a: Point, b: Point) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let s = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    crate::mesh::dist(p, [a[0] + s * dx, a[1] + s * dy])
}

/// Checks one ring: at least 3 finite vertices, non-zero area, no self-intersection.
pub(super) fn check_ring(ring: &[Point], what: &str) -> Result<()> {
    if ring.len() < 3 {
        return Err(Error::Mesh(format!(
            "polygon: {what} has {} vertices, at least 3 are needed",
            ring.len()
        )));
    }
    for (i, p) in ring.iter().enumerate() {
        if !p[0].is_finite() || !p[1].is_finite() {
            return Err(Error::Mesh(format!(
                "polygon: {what} vertex {i} ({}, {}) is not finite",
                p[0], p[1]
            )));
        }
    }
    let n = ring.len();
    for i in 0..n {
        if ring[i] == ring[(i + 1) % n] {
            return Err(Error::Mesh(format!(
                "polygon: {what} vertices {i} and {} coincide at ({}, {})",
                (i + 1) % n,
                ring[i][0],
                ring[i][1]
            )));
        }
    }
    if let Some((i, j)) = self_intersection(ring) {
        return Err(Error::Mesh(format!(
            "polygon: {what} is self-intersecting: edges {i} and {j} meet"
        )));
    }
    if ring_area(ring) == 0.0 {
        return Err(Error::Mesh(format!("polygon: {what} has zero area")));
    }
    Ok(())
}

/// Twice-signed-area / 2 of a ring (positive: counter-clockwise).
pub(super) fn ring_area(ring: &[Point]) -> f64 {
    let n = ring.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
}

/// `(b - a) × (c - a)`.
pub(super) fn orient(a: Point, b: Point, c: Point) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
}

/// `p` on the closed segment `ab`.
pub(super) fn on_segment(p: Point, a: Point, b: Point) -> bool {
    orient(a, b, p) == 0.0
        && p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// Whether the closed segments `ab` and `cd` have a point in common.
pub(super) fn segments_meet(a: Point, b: Point, c: Point, d: Point) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if ((o1 > 0.0 && o2 < 0.0) || (o1 < 0.0 && o2 > 0.0))
        && ((o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0))
    {
        return true;
    }
    on_segment(c, a, b) || on_segment(d, a, b) || on_segment(a, c, d) || on_segment(b, c, d)
}

/// Edge pairs of two edge lists whose x-ranges overlap (a sweep over sorted x-ranges), fed
/// to `test` until it returns `true`.
pub(super) fn sweep_pairs(
    edges: &[(Point, Point, usize, usize)],
    mut test: impl FnMut(&(Point, Point, usize, usize), &(Point, Point, usize, usize)) -> bool,
) -> Option<(usize, usize)> {
    let mut order: Vec<usize> = (0..edges.len()).collect();
    let lo = |e: &(Point, Point, usize, usize)| e.0[0].min(e.1[0]);
    let hi = |e: &(Point, Point, usize, usize)| e.0[0].max(e.1[0]);
    order.sort_by(|&i, &j| lo(&edges[i]).total_cmp(&lo(&edges[j])));
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if lo(&edges[j]) > hi(&edges[i]) {
                break;
            }
            if test(&edges[i], &edges[j]) {
                return Some((edges[i].3.min(edges[j].3), edges[i].3.max(edges[j].3)));
            }
        }
    }
    None
}

/// Two non-adjacent edges of the ring that meet, or adjacent edges that fold back.
pub(super) fn self_intersection(ring: &[Point]) -> Option<(usize, usize)> {
    let n = ring.len();
    let edges: Vec<_> = (0..n).map(|i| (ring[i], ring[(i + 1) % n], 0, i)).collect();
    sweep_pairs(&edges, |e, f| {
        let (i, j) = (e.3, f.3);
        if (i + 1) % n == j {
            // e ends where f starts: they fold back if f's end lies on e or e's start on f.
            on_segment(f.1, e.0, e.1) || on_segment(e.0, f.0, f.1)
        } else if (j + 1) % n == i {
            on_segment(e.1, f.0, f.1) || on_segment(f.0, e.0, e.1)
        } else {
            segments_meet(e.0, e.1, f.0, f.1)
        }
    })
}

/// An edge of ring `a` and an edge of ring `b` that meet.
pub(super) fn rings_touch(a: &[Point], b: &[Point]) -> Option<(usize, usize)> {
    let mut edges: Vec<_> = (0..a.len())
        .map(|i| (a[i], a[(i + 1) % a.len()], 0, i))
        .collect();
    edges.extend((0..b.len()).map(|i| (b[i], b[(i + 1) % b.len()], 1, i)));
    let mut pair = None;
    sweep_pairs(&edges, |e, f| {
        let meet = e.2 != f.2 && segments_meet(e.0, e.1, f.0, f.1);
        if meet {
            pair = Some(if e.2 == 0 { (e.3, f.3) } else { (f.3, e.3) });
        }
        meet
    });
    pair
}

/// Whether `p` is inside the ring (crossing number; points on the ring may go either way).
pub(super) fn inside(p: Point, ring: &[Point]) -> bool {
    let n = ring.len();
    let mut odd = false;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                odd = !odd;
            }
        }
    }
    odd
}

/// Whether `p` lies on an edge of the ring.
pub(super) fn on_ring(p: Point, ring: &[Point]) -> bool {
    let n = ring.len();
    (0..n).any(|i| on_segment(p, ring[i], ring[(i + 1) % n]))
}

/// The convex hull of a point set (monotone chain), counter-clockwise.
pub(super) fn convex_hull(points: &[Point]) -> Vec<Point> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let mut hull: Vec<Point> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        for &q in &p {
            while hull.len() >= start + 2
                && orient(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
        if pass == 0 {
            p.reverse();
        }
    }
    hull
}
