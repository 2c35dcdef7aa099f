//! Polygons with holes and named regions, by constrained Delaunay refinement.

use super::delaunay::{orient_ccw, refined_cdt, tag_boundary};
use super::geometry::*;
use super::size::{estimated_triangles, uniform_levels, MAX_TRIANGLES};
use crate::error::{Error, Result};
use crate::mesh::refine::Hierarchy;
use crate::mesh::{Mesh, Point};
use spade::Triangulation;
use std::collections::BTreeMap;

/// The polygon of [`polygon`] as a hierarchy: with more than [`super::DELAUNAY_TRIANGLES`]
/// triangles expected, meshed at `size · 2ᵏ` and refined uniformly `k` times (regions and
/// boundary regions inherited), so that the finest level has element size about `size` and
/// the coarse mesh's angles (at least `min_angle`); otherwise the single mesh of
/// [`polygon`].
pub fn polygon_levels(spec: &PolygonSpec) -> Result<Hierarchy> {
    let estimate = polygon_estimate(spec);
    if !(estimate.is_finite() && estimate <= MAX_TRIANGLES) {
        // Bad data or too many triangles: the direct generator names the problem.
        return polygon(spec).map(Hierarchy::single);
    }
    let k = uniform_levels(estimate);
    let coarse = polygon(&PolygonSpec {
        size: spec.size * f64::from(1u32 << k),
        ..spec.clone()
    })?;
    Ok(Hierarchy::refined(coarse, k as usize))
}

/// The box that pads a polygon's triangulation, whether faces outside the constraints are
/// excluded during refinement, and the area refinement fills.
pub(super) fn padded_domain(spec: &PolygonSpec) -> ([Point; 4], bool, f64) {
    // The triangulation is padded by a box around the polygon: its boundary points then
    // never form the triangulation's convex hull, where three nearly collinear points of a
    // subdivided edge (one rounded a hair outside the others' line) would be forced into a
    // flat triangle. The padding lies outside the polygon and is dropped.
    let (lo, hi) = spec.outer.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    );
    let margin = spec.size.max(0.05 * (hi[0] - lo[0]).max(hi[1] - lo[1]));
    let padding = [
        [lo[0] - margin, lo[1] - margin],
        [hi[0] + margin, lo[1] - margin],
        [hi[0] + margin, hi[1] + margin],
        [lo[0] - margin, hi[1] + margin],
    ];
    // With regions the parity rule that excludes outer faces would also exclude regions:
    // refine the whole padded box then, and drop the outside afterwards.
    let exclude_outer = spec.regions.is_empty();
    let refined_area = if exclude_outer {
        ring_area(&spec.outer).abs() - spec.holes.iter().map(|h| ring_area(h).abs()).sum::<f64>()
    } else {
        ring_area(&padding).abs()
    };
    (padding, exclude_outer, refined_area)
}

/// The triangle count [`polygon`] will make for `spec` (not checked: `NaN` or huge for bad
/// data).
pub(super) fn polygon_estimate(spec: &PolygonSpec) -> f64 {
    if spec.outer.len() < 3 {
        return f64::NAN;
    }
    estimated_triangles(padded_domain(spec).2, spec.size)
}

/// A polygonal domain with holes and named sub-regions, meshed by constrained Delaunay
/// refinement.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PolygonSpec {
    /// The outer boundary (either orientation, not closed: the last vertex joins the first).
    pub outer: Vec<Point>,
    /// Holes strictly inside `outer`, pairwise disjoint; their triangles are removed.
    pub holes: Vec<Vec<Point>>,
    /// Named sub-polygons (different soils...): triangles whose centroid lies in region `i`
    /// (the first that contains it) get tag `i + 1`; the others tag 0, named "default".
    pub regions: Vec<(String, Vec<Point>)>,
    /// Target element size: boundary segments are split to about this length and the
    /// triangle area is bounded by `size²·√3/4`.
    pub size: f64,
    /// Smallest angle in degrees that refinement aims for, in (0, 30].
    pub min_angle: f64,
}

/// Meshes `spec`'s polygon minus its holes: boundary edges split to about `size`, region
/// edges inserted as constraints, then Delaunay refinement. Every triangle is tagged with
/// its region (see [`PolygonSpec::regions`]).
pub fn polygon(spec: &PolygonSpec) -> Result<Mesh> {
    let size = spec.size;
    if !size.is_finite() || size <= 0.0 {
        return Err(Error::Mesh(format!(
            "polygon: element size must be positive and finite, got {size}"
        )));
    }
    if !(spec.min_angle > 0.0 && spec.min_angle <= 30.0) {
        return Err(Error::Mesh(format!(
            "polygon: min_angle must be in (0, 30] degrees, got {}",
            spec.min_angle
        )));
    }
    check_ring(&spec.outer, "outer polygon")?;
    for (h, hole) in spec.holes.iter().enumerate() {
        let what = format!("hole {h}");
        check_ring(hole, &what)?;
        if let Some((i, j)) = rings_touch(hole, &spec.outer) {
            return Err(Error::Mesh(format!(
                "polygon: {what} touches or crosses the outer polygon (its edge {i} meets \
                 outer edge {j})"
            )));
        }
        if !inside(hole[0], &spec.outer) {
            return Err(Error::Mesh(format!(
                "polygon: {what} lies outside the outer polygon (vertex 0 at ({}, {}))",
                hole[0][0], hole[0][1]
            )));
        }
        for (g, other) in spec.holes[..h].iter().enumerate() {
            if rings_touch(hole, other).is_some()
                || inside(hole[0], other)
                || inside(other[0], hole)
            {
                return Err(Error::Mesh(format!("polygon: holes {g} and {h} overlap")));
            }
        }
    }
    for (r, (name, ring)) in spec.regions.iter().enumerate() {
        let what = format!("region {r} (`{name}`)");
        check_ring(ring, &what)?;
        for (i, p) in ring.iter().enumerate() {
            if !inside(*p, &spec.outer) && !on_ring(*p, &spec.outer) {
                return Err(Error::Mesh(format!(
                    "polygon: {what} vertex {i} at ({}, {}) lies outside the outer polygon",
                    p[0], p[1]
                )));
            }
        }
    }
    let (padding, exclude_outer, refined_area) = padded_domain(spec);
    let estimate = estimated_triangles(refined_area, size);
    if estimate > MAX_TRIANGLES {
        return Err(Error::Mesh(format!(
            "polygon: size {size} is too small for this domain (area {refined_area:e}): \
             about {estimate:.2e} triangles, more than the limit {MAX_TRIANGLES:.0e}"
        )));
    }
    // The boundary points the subdivision will make, counted before any is made: a long
    // thin polygon can need far more of them than its area suggests.
    let boundary_points: f64 = std::iter::once(&spec.outer)
        .chain(spec.holes.iter())
        .chain(spec.regions.iter().map(|r| &r.1))
        .flat_map(|ring| {
            (0..ring.len())
                .map(|i| (crate::mesh::dist(ring[i], ring[(i + 1) % ring.len()]) / size).ceil())
        })
        .sum();
    if boundary_points > MAX_TRIANGLES {
        return Err(Error::Mesh(format!(
            "polygon: size {size} is too small for the length of the boundary: about \
             {boundary_points:.2e} boundary points, more than the limit {MAX_TRIANGLES:.0e}"
        )));
    }
    let mut vertices = Vec::new();
    let mut segments = Vec::new();
    let rings = std::iter::once(&spec.outer)
        .chain(spec.holes.iter())
        .chain(spec.regions.iter().map(|r| &r.1));
    // Input vertices lying on another ring's edge (a layer ending on the outer boundary)
    // split that edge first, so that shared stretches get bit-identical subdivisions.
    let rings: Vec<&Vec<Point>> = rings.collect();
    let all: Vec<Point> = rings.iter().flat_map(|r| r.iter().copied()).collect();
    let hull = convex_hull(&spec.outer);
    let scale = hull
        .iter()
        .flat_map(|a| hull.iter().map(move |b| crate::mesh::dist(*a, *b)))
        .fold(0.0, f64::max);
    for ring in rings {
        let ring = split_at_vertices(ring, &all, 1e-12 * scale);
        let first = vertices.len();
        for (i, &a) in ring.iter().enumerate() {
            vertices.extend(subdivide(a, ring[(i + 1) % ring.len()], size));
        }
        let n = vertices.len() - first;
        segments.extend((0..n).map(|k| [first + k, first + (k + 1) % n]));
    }
    vertices.extend(padding);
    let cdt = refined_cdt(
        &vertices,
        &segments,
        size,
        spec.min_angle,
        exclude_outer,
        estimate,
        "polygon",
    )?;

    // Faces joined across non-constraint edges form components that lie wholly inside or
    // outside every input polygon: classify one face per component.
    let n_faces = cdt.num_all_faces();
    let mut component = vec![u32::MAX; n_faces];
    let mut class: Vec<Option<u32>> = Vec::new();
    let mut stack = Vec::new();
    for face in cdt.inner_faces() {
        let f = face.fix().index();
        if component[f] != u32::MAX {
            continue;
        }
        let id = class.len() as u32;
        let c = face.center();
        class.push(classify([c.x, c.y], spec));
        component[f] = id;
        stack.push(face);
        while let Some(g) = stack.pop() {
            for e in g.adjacent_edges() {
                if e.is_constraint_edge() {
                    continue;
                }
                if let Some(n) = e.rev().face().as_inner() {
                    let i = n.fix().index();
                    if component[i] == u32::MAX {
                        component[i] = id;
                        stack.push(n);
                    }
                }
            }
        }
    }
    let all_points: Vec<Point> = cdt
        .vertices()
        .map(|v| [v.position().x, v.position().y])
        .collect();
    let mut new_index = vec![u32::MAX; all_points.len()];
    let mut points = Vec::new();
    let mut triangles = Vec::new();
    let mut regions = Vec::new();
    for face in cdt.inner_faces() {
        if let Some(tag) = class[component[face.fix().index()] as usize] {
            let t = face.vertices().map(|v| {
                let i = v.fix().index();
                if new_index[i] == u32::MAX {
                    new_index[i] = points.len() as u32;
                    points.push(all_points[i]);
                }
                new_index[i]
            });
            triangles.push(t);
            regions.push(tag);
        }
    }
    orient_ccw(&points, &mut triangles);
    let mut names = BTreeMap::new();
    if !spec.regions.is_empty() {
        names.insert(0, "default".to_string());
        for (r, (name, _)) in spec.regions.iter().enumerate() {
            names.insert(r as u32 + 1, name.clone());
        }
    }
    let mesh = Mesh::new(points, triangles, regions, names)?;
    // Boundary regions: `outer` (tag 1) and `hole1`, `hole2`, ... (tags 2, 3, ...), each
    // boundary edge on the ring nearest to its midpoint.
    let rings: Vec<&Vec<Point>> = std::iter::once(&spec.outer).chain(&spec.holes).collect();
    let mut side_names = BTreeMap::from([(1, "outer".to_string())]);
    for h in 0..spec.holes.len() {
        side_names.insert(h as u32 + 2, format!("hole{}", h + 1));
    }
    tag_boundary(
        mesh,
        |m| {
            let d = |ring: &[Point]| {
                (0..ring.len())
                    .map(|i| segment_distance(m, ring[i], ring[(i + 1) % ring.len()]))
                    .fold(f64::INFINITY, f64::min)
            };
            let mut best = (f64::INFINITY, 1);
            for (k, ring) in rings.iter().enumerate() {
                let dk = d(ring);
                if dk < best.0 {
                    best = (dk, k as u32 + 1);
                }
            }
            best.1
        },
        side_names,
    )
}

/// The region tag of a point of the domain, or `None` outside it (or in a hole).
pub(super) fn classify(p: Point, spec: &PolygonSpec) -> Option<u32> {
    if !inside(p, &spec.outer) || spec.holes.iter().any(|h| inside(p, h)) {
        return None;
    }
    Some(
        spec.regions
            .iter()
            .position(|(_, ring)| inside(p, ring))
            .map_or(0, |r| r as u32 + 1),
    )
}

/// The points splitting segment `a → b` into `⌈|ab| / size⌉` equal parts, `a` included,
/// `b` excluded. Computed from the lexicographically smaller end so that an edge shared
/// by two rings (in either direction) gets bit-identical points.
pub(super) fn subdivide(a: Point, b: Point, size: f64) -> Vec<Point> {
    let n = ((crate::mesh::dist(a, b) / size).ceil() as usize).max(1);
    let (p, q, flip) = if (a[0], a[1]) <= (b[0], b[1]) {
        (a, b, false)
    } else {
        (b, a, true)
    };
    (0..n)
        .map(|k| {
            let k = if flip { n - k } else { k };
            if k == 0 {
                return p;
            }
            if k == n {
                return q;
            }
            let t = k as f64 / n as f64;
            [p[0] * (1.0 - t) + q[0] * t, p[1] * (1.0 - t) + q[1] * t]
        })
        .collect()
}

/// The ring with every point of `all` that lies within `eps` of one of its edges (and not
/// at its ends) inserted into that edge, in order along it.
pub(super) fn split_at_vertices(ring: &[Point], all: &[Point], eps: f64) -> Vec<Point> {
    let n = ring.len();
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        out.push(a);
        let d = [b[0] - a[0], b[1] - a[1]];
        let len2 = d[0] * d[0] + d[1] * d[1];
        let mut on: Vec<(f64, Point)> = all
            .iter()
            .filter_map(|&p| {
                if p == a || p == b {
                    return None;
                }
                let t = ((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2;
                let q = [a[0] + t * d[0], a[1] + t * d[1]];
                (t > 0.0 && t < 1.0 && crate::mesh::dist(p, q) <= eps).then_some((t, p))
            })
            .collect();
        on.sort_by(|x, y| x.0.total_cmp(&y.0));
        on.dedup_by(|x, y| x.1 == y.1);
        out.extend(on.into_iter().map(|(_, p)| p));
    }
    out
}
