//! Built-in mesh generators: rectangle (structured, with its multigrid hierarchy), disc and
//! polygon with holes and named regions (constrained Delaunay refinement with spade).

use super::refine::{Hierarchy, Refinement};
use super::{Circle, Mesh, Point};
use crate::error::{Error, Result};
use rayon::prelude::*;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::str::FromStr;

/// The largest number of triangles the unstructured generators ([`disk`], [`polygon`])
/// agree to build: Delaunay refinement of 10⁷ triangles takes minutes and GiBs.
pub const MAX_TRIANGLES: f64 = 1e7;

/// The largest number of triangles [`rectangle`] agrees to build (its finest level; all
/// levels together take about 40 bytes per finest triangle).
pub const MAX_STRUCTURED_TRIANGLES: f64 = 1.5e8;

/// The unstructured generators make at most about this many triangles by Delaunay
/// refinement: a finer mesh is made coarse and refined uniformly ([`disk_levels`],
/// [`polygon_levels`]), which is many times faster than Delaunay refinement, keeps every
/// angle of the coarse mesh and gives multigrid its levels.
pub const DELAUNAY_TRIANGLES: f64 = 1.5e5;

/// How many uniform refinements (each quarters the element area) bring a mesh of about
/// `estimate` triangles down to at most [`DELAUNAY_TRIANGLES`] on its coarsest level; at
/// least two when any, so that the levels make a multigrid hierarchy `auto` takes.
fn uniform_levels(estimate: f64) -> u32 {
    let mut k = 0;
    let mut e = estimate;
    while e > DELAUNAY_TRIANGLES {
        e /= 4.0;
        k += 1;
    }
    if k > 0 {
        k.max(2)
    } else {
        0
    }
}

/// How each cell of a structured rectangle mesh is cut into triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Diagonal {
    /// Every cell cut along the diagonal from `(x_i, y_j)` to `(x_{i+1}, y_{j+1})`.
    Right,
    /// Every cell cut along the diagonal from `(x_{i+1}, y_j)` to `(x_i, y_{j+1})`.
    Left,
    /// Right and left alternating in a checkerboard ("union jack"): no preferred direction.
    Alternate,
    /// Both diagonals with a centre vertex: four triangles per cell.
    Crossed,
}

impl FromStr for Diagonal {
    type Err = Error;

    fn from_str(s: &str) -> Result<Diagonal> {
        match s.trim().to_ascii_lowercase().as_str() {
            "right" => Ok(Diagonal::Right),
            "left" => Ok(Diagonal::Left),
            "alternate" => Ok(Diagonal::Alternate),
            "crossed" => Ok(Diagonal::Crossed),
            _ => Err(Error::Mesh(format!(
                "unknown diagonal `{s}`: expected one of right, left, alternate, crossed"
            ))),
        }
    }
}

/// A structured mesh of the rectangle `[x0, x1] × [y0, y1]` with `nx × ny` cells.
#[derive(Debug, Clone, PartialEq)]
pub struct RectangleSpec {
    /// Left edge.
    pub x0: f64,
    /// Bottom edge.
    pub y0: f64,
    /// Right edge (> `x0`).
    pub x1: f64,
    /// Top edge (> `y0`).
    pub y1: f64,
    /// Cells along x (≥ 1).
    pub nx: usize,
    /// Cells along y (≥ 1).
    pub ny: usize,
    /// How cells are cut into triangles.
    pub diagonal: Diagonal,
}

/// The structured rectangle mesh of `spec`, with vertices numbered row by row
/// (`v = j (nx + 1) + i` for the grid point `(x_i, y_j)`; centre vertices of crossed cells
/// follow, cell by cell). For the right and left diagonals with `nx`, `ny` both divisible
/// by `2^k`, the result holds the `k + 1` nested meshes `(nx / 2^j) × (ny / 2^j)`,
/// coarsest first, each the uniform refinement of the previous one (the coarsest keeps at
/// least 2 × 2 cells so that it has an interior vertex); otherwise a single level.
pub fn rectangle(spec: &RectangleSpec) -> Result<Hierarchy> {
    let RectangleSpec {
        x0,
        y0,
        x1,
        y1,
        nx,
        ny,
        diagonal,
    } = *spec;
    for (name, v) in [("x0", x0), ("y0", y0), ("x1", x1), ("y1", y1)] {
        if !v.is_finite() {
            return Err(Error::Mesh(format!(
                "rectangle: {name} = {v} is not finite"
            )));
        }
    }
    if x1 <= x0 || y1 <= y0 || !(x1 - x0).is_finite() || !(y1 - y0).is_finite() {
        return Err(Error::Mesh(format!(
            "rectangle: need x0 < x1 and y0 < y1, got [{x0}, {x1}] × [{y0}, {y1}]"
        )));
    }
    if nx == 0 || ny == 0 {
        return Err(Error::Mesh(format!(
            "rectangle: need at least one cell in each direction, got nx = {nx}, ny = {ny}"
        )));
    }
    let per_cell = if diagonal == Diagonal::Crossed { 4 } else { 2 };
    let n_tri = (nx as f64) * (ny as f64) * per_cell as f64;
    // u32 vertex indices and the triangle budget.
    if n_tri > MAX_STRUCTURED_TRIANGLES {
        return Err(Error::Mesh(format!(
            "rectangle: {nx} × {ny} cells make {n_tri:.3e} triangles, more than the limit \
             {MAX_STRUCTURED_TRIANGLES:.1e}"
        )));
    }
    let levels = match diagonal {
        Diagonal::Right | Diagonal::Left => {
            let mut k = 0;
            while (nx >> k) % 2 == 0
                && (ny >> k) % 2 == 0
                && nx >> (k + 1) >= 2
                && ny >> (k + 1) >= 2
            {
                k += 1;
            }
            k
        }
        _ => 0,
    };
    let sizes: Vec<(usize, usize)> = (0..=levels).rev().map(|j| (nx >> j, ny >> j)).collect();
    let meshes: Vec<Mesh> = sizes
        .iter()
        .map(|&(cx, cy)| structured(spec, cx, cy))
        .collect();
    let refinements = sizes[..sizes.len() - 1]
        .iter()
        .map(|&(cx, cy)| structured_parents(cx, cy, diagonal))
        .collect();
    Ok(Hierarchy {
        levels: meshes,
        refinements,
    })
}

/// Grid coordinate `i / n` of `[a, b]`, exact at both ends and identical for the same
/// fraction on nested grids (`2i / 2n` and `i / n` give the same `t`).
#[inline]
fn lerp(a: f64, b: f64, i: usize, n: usize) -> f64 {
    let t = i as f64 / n as f64;
    a * (1.0 - t) + b * t
}

/// The structured mesh of `spec`'s rectangle with `nx × ny` cells.
fn structured(spec: &RectangleSpec, nx: usize, ny: usize) -> Mesh {
    let (x0, y0, x1, y1) = (spec.x0, spec.y0, spec.x1, spec.y1);
    let row = nx + 1;
    let n_grid = row * (ny + 1);
    let crossed = spec.diagonal == Diagonal::Crossed;
    let n_points = n_grid + if crossed { nx * ny } else { 0 };
    let mut points = vec![[0.0; 2]; n_points];
    let xs: Vec<f64> = (0..=nx).map(|i| lerp(x0, x1, i, nx)).collect();
    points[..n_grid]
        .par_chunks_mut(row)
        .enumerate()
        .for_each(|(j, out)| {
            let y = lerp(y0, y1, j, ny);
            for (p, &x) in out.iter_mut().zip(&xs) {
                *p = [x, y];
            }
        });
    if crossed {
        let xc: Vec<f64> = (0..nx).map(|i| lerp(x0, x1, 2 * i + 1, 2 * nx)).collect();
        points[n_grid..]
            .par_chunks_mut(nx)
            .enumerate()
            .for_each(|(j, out)| {
                let y = lerp(y0, y1, 2 * j + 1, 2 * ny);
                for (p, &x) in out.iter_mut().zip(&xc) {
                    *p = [x, y];
                }
            });
    }
    let per_cell = if crossed { 4 } else { 2 };
    let mut triangles = vec![[0u32; 3]; per_cell * nx * ny];
    let diagonal = spec.diagonal;
    triangles
        .par_chunks_mut(per_cell * nx)
        .enumerate()
        .for_each(|(j, out)| {
            for i in 0..nx {
                let v00 = (j * row + i) as u32;
                let (v10, v01) = (v00 + 1, v00 + row as u32);
                let v11 = v01 + 1;
                let t = &mut out[per_cell * i..per_cell * (i + 1)];
                let right = match diagonal {
                    Diagonal::Right => true,
                    Diagonal::Left => false,
                    Diagonal::Alternate => (i + j) % 2 == 0,
                    Diagonal::Crossed => {
                        let c = (n_grid + j * nx + i) as u32;
                        t[0] = [v00, v10, c];
                        t[1] = [v10, v11, c];
                        t[2] = [v11, v01, c];
                        t[3] = [v01, v00, c];
                        continue;
                    }
                };
                if right {
                    t[0] = [v00, v10, v11];
                    t[1] = [v00, v11, v01];
                } else {
                    t[0] = [v00, v10, v01];
                    t[1] = [v10, v11, v01];
                }
            }
        });
    let n_tri = triangles.len();
    Mesh {
        points,
        triangles,
        regions: vec![0; n_tri],
        region_names: BTreeMap::new(),
        curve: None,
        boundary: rectangle_sides(nx, ny),
        numbering: None,
    }
}

/// The boundary tags of the rectangle's sides, in the order of their tags.
pub const RECTANGLE_SIDES: [&str; 4] = ["bottom", "right", "top", "left"];

/// The sides of the structured `nx × ny` rectangle as boundary regions: `bottom` (tag 1),
/// `right` (2), `top` (3), `left` (4), with the grid's row-by-row vertex numbering.
fn rectangle_sides(nx: usize, ny: usize) -> super::BoundaryRegions {
    let row = nx + 1;
    let v = |i: usize, j: usize| (j * row + i) as u32;
    let mut edges = Vec::with_capacity(2 * (nx + ny));
    let mut tags = Vec::with_capacity(2 * (nx + ny));
    for i in 0..nx {
        edges.push([v(i, 0), v(i + 1, 0)]);
        tags.push(1);
    }
    for j in 0..ny {
        edges.push([v(nx, j), v(nx, j + 1)]);
        tags.push(2);
    }
    for i in 0..nx {
        edges.push([v(i + 1, ny), v(i, ny)]);
        tags.push(3);
    }
    for j in 0..ny {
        edges.push([v(0, j + 1), v(0, j)]);
        tags.push(4);
    }
    let names = RECTANGLE_SIDES
        .iter()
        .enumerate()
        .map(|(k, n)| (k as u32 + 1, n.to_string()))
        .collect();
    super::BoundaryRegions { edges, tags, names }
}

/// Tags every boundary edge of `mesh` with `tag_of(midpoint)` and names the tags.
fn tag_boundary(
    mesh: Mesh,
    tag_of: impl Fn(Point) -> u32,
    names: BTreeMap<u32, String>,
) -> Result<Mesh> {
    let edges = mesh.boundary_edges();
    let tags = edges
        .iter()
        .map(|&[a, b]| {
            let (p, q) = (mesh.points[a as usize], mesh.points[b as usize]);
            tag_of([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])])
        })
        .collect();
    mesh.with_boundary_regions(edges, tags, names)
}

/// The parents of the `2cx × 2cy` structured mesh's vertices in the `cx × cy` one, computed
/// from the grid indices: even/even sits on a coarse vertex, the others are midpoints of a
/// horizontal, vertical or diagonal coarse edge.
fn structured_parents(cx: usize, cy: usize, diagonal: Diagonal) -> Refinement {
    let (fx, fy) = (2 * cx, 2 * cy);
    let crow = cx + 1;
    let c = move |i: usize, j: usize| (j * crow + i) as u32;
    let mut parents = vec![[0u32; 2]; (fx + 1) * (fy + 1)];
    parents
        .par_chunks_mut(fx + 1)
        .enumerate()
        .for_each(|(j, out)| {
            for (i, p) in out.iter_mut().enumerate() {
                *p = match (i % 2, j % 2) {
                    (0, 0) => [c(i / 2, j / 2); 2],
                    (1, 0) => [c(i / 2, j / 2), c(i / 2 + 1, j / 2)],
                    (0, 1) => [c(i / 2, j / 2), c(i / 2, j / 2 + 1)],
                    _ => {
                        let (ci, cj) = (i / 2, j / 2);
                        if diagonal == Diagonal::Left {
                            [c(ci + 1, cj), c(ci, cj + 1)]
                        } else {
                            [c(ci, cj), c(ci + 1, cj + 1)]
                        }
                    }
                };
            }
        });
    Refinement { parents }
}

/// An unstructured, shape-regular mesh of the disc of `center` and `radius` with element
/// size about `size`: `⌈2πR / size⌉` boundary vertices exactly on the circle, interior from
/// constrained Delaunay refinement (30° angle limit, area bound `size²·√3/4`). Boundary
/// vertices the refinement adds on chords are projected onto the circle, so every boundary
/// vertex lies on it; `mesh.curve` records the circle for later refinement.
pub fn disk(center: Point, radius: f64, size: f64) -> Result<Mesh> {
    let estimate = disk_estimate(center, radius, size)?;
    let n = ((2.0 * PI * radius / size).ceil() as usize).max(6);
    let on_circle: Vec<Point> = (0..n)
        .map(|k| {
            let a = 2.0 * PI * k as f64 / n as f64;
            [center[0] + radius * a.cos(), center[1] + radius * a.sin()]
        })
        .collect();
    let segments: Vec<[usize; 2]> = (0..n).map(|k| [k, (k + 1) % n]).collect();
    let cdt = refined_cdt(&on_circle, &segments, size, 30.0, true, estimate, "disk")?;
    let mut points: Vec<Point> = cdt
        .vertices()
        .map(|v| [v.position().x, v.position().y])
        .collect();
    // Steiner points that refinement put on boundary chords: move them onto the circle.
    let circle = Circle { center, radius };
    for e in cdt.convex_hull() {
        let v = e.from().fix().index();
        if v >= n {
            points[v] = circle.project(points[v]);
        }
    }
    let mut triangles: Vec<[u32; 3]> = cdt
        .inner_faces()
        .map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect();
    orient_ccw(&points, &mut triangles);
    if let Some(k) = triangles
        .iter()
        .position(|t| super::signed_area(&points, t) <= 0.0)
    {
        return Err(Error::Mesh(format!(
            "disk: triangle {k} turned over when its boundary vertices were moved onto the \
             circle; choose a smaller size (got {size} for radius {radius})"
        )));
    }
    let mut mesh = Mesh::new(points, triangles, vec![], BTreeMap::new())?;
    mesh.curve = Some(circle);
    tag_boundary(mesh, |_| 1, BTreeMap::from([(1, "outer".to_string())]))
}

/// Checks the disc's data and returns the triangle count its mesh will have, refused
/// above [`MAX_TRIANGLES`].
fn disk_estimate(center: Point, radius: f64, size: f64) -> Result<f64> {
    if !center[0].is_finite() || !center[1].is_finite() {
        return Err(Error::Mesh(format!(
            "disk: centre ({}, {}) is not finite",
            center[0], center[1]
        )));
    }
    if !radius.is_finite() || radius <= 0.0 {
        return Err(Error::Mesh(format!(
            "disk: radius must be positive and finite, got {radius}"
        )));
    }
    if !size.is_finite() || size <= 0.0 {
        return Err(Error::Mesh(format!(
            "disk: element size must be positive and finite, got {size}"
        )));
    }
    let estimate = estimated_triangles(PI * radius * radius, size);
    if estimate > MAX_TRIANGLES {
        return Err(Error::Mesh(format!(
            "disk: size {size} is too small for radius {radius}: about {estimate:.2e} \
             triangles, more than the limit {MAX_TRIANGLES:.0e}"
        )));
    }
    Ok(estimate)
}

/// The disc of [`disk`] as a hierarchy: with more than [`DELAUNAY_TRIANGLES`] triangles
/// expected, the disc meshed at `size · 2ᵏ` and refined uniformly `k` times (new boundary
/// vertices on the circle), so that the finest level has element size about `size` and the
/// coarse mesh's angles; otherwise the single mesh of [`disk`].
pub fn disk_levels(center: Point, radius: f64, size: f64) -> Result<Hierarchy> {
    let k = uniform_levels(disk_estimate(center, radius, size)?);
    let coarse = disk(center, radius, size * f64::from(1u32 << k))?;
    Ok(Hierarchy::refined(coarse, k as usize))
}

/// The polygon of [`polygon`] as a hierarchy: with more than [`DELAUNAY_TRIANGLES`]
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
fn padded_domain(spec: &PolygonSpec) -> ([Point; 4], bool, f64) {
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
fn polygon_estimate(spec: &PolygonSpec) -> f64 {
    if spec.outer.len() < 3 {
        return f64::NAN;
    }
    estimated_triangles(padded_domain(spec).2, spec.size)
}

/// The triangle count that Delaunay refinement with area bound `size²·√3/4` typically
/// produces for a domain of `area` (the triangles come out about half the bound).
fn estimated_triangles(area: f64, size: f64) -> f64 {
    2.0 * area / (size * size * 3f64.sqrt() / 4.0)
}

/// Puts every triangle in counter-clockwise order (spade's faces are, but be sure).
fn orient_ccw(points: &[Point], triangles: &mut [[u32; 3]]) {
    triangles.par_iter_mut().for_each(|t| {
        if super::signed_area(points, t) < 0.0 {
            t.swap(1, 2);
        }
    });
}

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// Inserts `vertices` and the constraint `segments` into a constrained Delaunay
/// triangulation and refines it with the angle limit `min_angle` (degrees) and the area
/// bound `size²·√3/4`. `exclude_outer` skips faces outside the constraints (by parity).
/// `estimate` (triangles expected) sizes the vertex budget.
fn refined_cdt(
    vertices: &[Point],
    segments: &[[usize; 2]],
    size: f64,
    min_angle: f64,
    exclude_outer: bool,
    estimate: f64,
    what: &str,
) -> Result<Cdt> {
    let mut cdt = Cdt::new();
    let mut handles = Vec::with_capacity(vertices.len());
    for (i, p) in vertices.iter().enumerate() {
        let h = cdt.insert(Point2::new(p[0], p[1])).map_err(|e| {
            Error::Mesh(format!(
                "{what}: vertex {i} at ({}, {}) cannot be inserted: {e:?}",
                p[0], p[1]
            ))
        })?;
        handles.push(h);
    }
    for s in segments {
        let (a, b) = (handles[s[0]], handles[s[1]]);
        if a != b {
            cdt.add_constraint_and_split(a, b, |p| p);
        }
    }
    let budget = (4.0 * estimate) as usize + 10 * vertices.len() + 1000;
    let params = RefinementParameters::<f64>::new()
        .with_angle_limit(AngleLimit::from_deg(min_angle))
        .with_max_allowed_area(size * size * 3f64.sqrt() / 4.0)
        .with_max_additional_vertices(budget)
        .exclude_outer_faces(exclude_outer);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| cdt.refine(params)))
        .map_err(|_| {
            Error::Mesh(format!(
                "{what}: Delaunay refinement failed (loss of precision); \
                 check the geometry for nearly coincident vertices or edges"
            ))
        })?;
    if !result.refinement_complete {
        return Err(Error::Mesh(format!(
            "{what}: Delaunay refinement did not finish within {budget} added vertices \
             (min_angle {min_angle}°, size {size}); lower min_angle or check for very small \
             input angles"
        )));
    }
    Ok(cdt)
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
                .map(|i| (super::dist(ring[i], ring[(i + 1) % ring.len()]) / size).ceil())
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
        .flat_map(|a| hull.iter().map(move |b| super::dist(*a, *b)))
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

/// The distance from `p` to the segment `ab`.
fn segment_distance(p: Point, a: Point, b: Point) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let s = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    super::dist(p, [a[0] + s * dx, a[1] + s * dy])
}

/// The region tag of a point of the domain, or `None` outside it (or in a hole).
fn classify(p: Point, spec: &PolygonSpec) -> Option<u32> {
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
fn subdivide(a: Point, b: Point, size: f64) -> Vec<Point> {
    let n = ((super::dist(a, b) / size).ceil() as usize).max(1);
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
fn split_at_vertices(ring: &[Point], all: &[Point], eps: f64) -> Vec<Point> {
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
                (t > 0.0 && t < 1.0 && super::dist(p, q) <= eps).then_some((t, p))
            })
            .collect();
        on.sort_by(|x, y| x.0.total_cmp(&y.0));
        on.dedup_by(|x, y| x.1 == y.1);
        out.extend(on.into_iter().map(|(_, p)| p));
    }
    out
}

/// Checks one ring: at least 3 finite vertices, non-zero area, no self-intersection.
fn check_ring(ring: &[Point], what: &str) -> Result<()> {
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
fn ring_area(ring: &[Point]) -> f64 {
    let n = ring.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
}

/// `(b - a) × (c - a)`.
fn orient(a: Point, b: Point, c: Point) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
}

/// `p` on the closed segment `ab`.
fn on_segment(p: Point, a: Point, b: Point) -> bool {
    orient(a, b, p) == 0.0
        && p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// Whether the closed segments `ab` and `cd` have a point in common.
fn segments_meet(a: Point, b: Point, c: Point, d: Point) -> bool {
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
fn sweep_pairs(
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
fn self_intersection(ring: &[Point]) -> Option<(usize, usize)> {
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
fn rings_touch(a: &[Point], b: &[Point]) -> Option<(usize, usize)> {
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
fn inside(p: Point, ring: &[Point]) -> bool {
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
fn on_ring(p: Point, ring: &[Point]) -> bool {
    let n = ring.len();
    (0..n).any(|i| on_segment(p, ring[i], ring[(i + 1) % n]))
}

/// The convex hull of a point set (monotone chain), counter-clockwise.
fn convex_hull(points: &[Point]) -> Vec<Point> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::refine::refine_uniform;

    fn revalidate(m: &Mesh) -> Mesh {
        Mesh::new(
            m.points.clone(),
            m.triangles.clone(),
            m.regions.clone(),
            m.region_names.clone(),
        )
        .unwrap()
    }

    fn spec(nx: usize, ny: usize, diagonal: Diagonal) -> RectangleSpec {
        RectangleSpec {
            x0: -0.3,
            y0: 0.1,
            x1: 1.7,
            y1: 0.7,
            nx,
            ny,
            diagonal,
        }
    }

    /// The triangles of a mesh as sorted triples of rounded corner coordinates.
    fn triangle_set(m: &Mesh) -> Vec<[[i64; 2]; 3]> {
        let key = |p: Point| [(p[0] * 1e9).round() as i64, (p[1] * 1e9).round() as i64];
        let mut s: Vec<_> = (0..m.triangles.len())
            .map(|k| {
                let mut c = m.corners(k).map(key);
                c.sort();
                c
            })
            .collect();
        s.sort();
        s
    }

    #[test]
    fn diagonal_parses() {
        assert_eq!("Right".parse::<Diagonal>().unwrap(), Diagonal::Right);
        assert_eq!("left".parse::<Diagonal>().unwrap(), Diagonal::Left);
        assert_eq!(
            "alternate".parse::<Diagonal>().unwrap(),
            Diagonal::Alternate
        );
        assert_eq!("crossed".parse::<Diagonal>().unwrap(), Diagonal::Crossed);
        let e = "diagonal".parse::<Diagonal>().unwrap_err().to_string();
        assert!(e.contains("right, left, alternate, crossed"), "{e}");
    }

    #[test]
    fn rectangle_counts_area_and_orientation() {
        for d in [
            Diagonal::Right,
            Diagonal::Left,
            Diagonal::Alternate,
            Diagonal::Crossed,
        ] {
            let h = rectangle(&spec(5, 3, d)).unwrap();
            assert_eq!(h.depth(), 1);
            let m = revalidate(h.finest());
            assert_eq!(m.triangles, h.finest().triangles, "{d:?} must be CCW");
            let q = m.quality();
            let crossed = d == Diagonal::Crossed;
            assert_eq!(q.vertices, 6 * 4 + if crossed { 15 } else { 0 });
            assert_eq!(q.triangles, if crossed { 60 } else { 30 });
            assert!((q.area - 2.0 * 0.6).abs() < 1e-12);
            assert_eq!(m.boundary_edges().len(), 2 * (5 + 3));
            assert_eq!(q.unknowns, 4 * 2 + if crossed { 15 } else { 0 });
            // lexicographic numbering: vertex j (nx+1) + i at (x_i, y_j)
            assert_eq!(m.points[0], [-0.3, 0.1]);
            assert_eq!(m.points[5], [1.7, 0.1]);
            assert_eq!(m.points[23], [1.7, 0.7]);
        }
    }

    #[test]
    fn diagonals_run_the_right_way() {
        let right = rectangle(&spec(1, 1, Diagonal::Right)).unwrap();
        let left = rectangle(&spec(1, 1, Diagonal::Left)).unwrap();
        let has_edge =
            |m: &Mesh, a: u32, b: u32| m.triangles.iter().any(|t| t.contains(&a) && t.contains(&b));
        assert!(has_edge(right.finest(), 0, 3) && !has_edge(right.finest(), 1, 2));
        assert!(has_edge(left.finest(), 1, 2) && !has_edge(left.finest(), 0, 3));
        // Alternate: the four cells around the centre vertex of a 2×2 grid all use it.
        let alt = rectangle(&spec(2, 2, Diagonal::Alternate)).unwrap();
        let uses = alt
            .finest()
            .triangles
            .iter()
            .filter(|t| t.contains(&4))
            .count();
        assert_eq!(uses, 8);
    }

    #[test]
    fn rectangle_hierarchy_matches_uniform_refinement() {
        for d in [Diagonal::Right, Diagonal::Left] {
            let h = rectangle(&spec(12, 8, d)).unwrap();
            // 12 × 8 halves twice (3 × 2 keeps an interior vertex): 3×2, 6×4, 12×8.
            let sizes: Vec<usize> = h.levels.iter().map(|m| m.triangles.len()).collect();
            assert_eq!(sizes, vec![12, 48, 192]);
            assert_eq!(h.refinements.len(), 2);
            for level in 0..2 {
                let (coarse, fine) = (&h.levels[level], &h.levels[level + 1]);
                let (refined, r) = refine_uniform(coarse);
                assert_eq!(triangle_set(&refined), triangle_set(fine));
                // Parents: the same relation, vertex by vertex through coordinates.
                for (v, p) in fine.points.iter().enumerate() {
                    let [a, b] = h.refinements[level].parents[v];
                    let (pa, pb) = (coarse.points[a as usize], coarse.points[b as usize]);
                    assert!((p[0] - 0.5 * (pa[0] + pb[0])).abs() < 1e-14);
                    assert!((p[1] - 0.5 * (pa[1] + pb[1])).abs() < 1e-14);
                    // and (a, b) is an edge of the coarse mesh or a == b
                    if a != b {
                        assert!(coarse
                            .triangles
                            .iter()
                            .any(|t| t.contains(&a) && t.contains(&b)));
                    }
                }
                assert_eq!(r.parents.len(), fine.points.len());
                // Coarse vertices sit exactly on fine grid vertices.
                for (v, &[a, b]) in h.refinements[level].parents.iter().enumerate() {
                    if a == b {
                        assert_eq!(fine.points[v], coarse.points[a as usize]);
                    }
                }
            }
            let lin = |p: Point| 2.0 * p[0] + 5.0 * p[1] - 1.0;
            let c: Vec<f64> = h.levels[0].points.iter().map(|&p| lin(p)).collect();
            let f = h.prolongate(1, &h.prolongate(0, &c));
            for (v, p) in h.finest().points.iter().enumerate() {
                assert!((f[v] - lin(*p)).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn hierarchy_depth_rules() {
        let depth = |nx, ny, d| rectangle(&spec(nx, ny, d)).unwrap().depth();
        assert_eq!(depth(64, 64, Diagonal::Right), 6); // 2, 4, ..., 64
        assert_eq!(depth(64, 16, Diagonal::Left), 4); // 8×2, ..., 64×16
        assert_eq!(depth(2, 2, Diagonal::Right), 1);
        assert_eq!(depth(4, 4, Diagonal::Right), 2);
        assert_eq!(depth(6, 10, Diagonal::Right), 2); // 3×5, 6×10
        assert_eq!(depth(7, 8, Diagonal::Right), 1);
        assert_eq!(depth(64, 64, Diagonal::Alternate), 1);
        assert_eq!(depth(64, 64, Diagonal::Crossed), 1);
        let h = rectangle(&spec(64, 16, Diagonal::Left)).unwrap();
        assert_eq!(h.levels[0].points.len(), 9 * 3);
    }

    #[test]
    fn rectangle_rejects_bad_input() {
        let mut s = spec(2, 2, Diagonal::Right);
        s.x1 = s.x0;
        assert!(rectangle(&s).unwrap_err().to_string().contains("x0 < x1"));
        let mut s = spec(2, 0, Diagonal::Right);
        assert!(rectangle(&s).unwrap_err().to_string().contains("ny = 0"));
        s.ny = 2;
        s.y0 = f64::NAN;
        assert!(rectangle(&s).unwrap_err().to_string().contains("y0"));
        let s = spec(100_000, 100_000, Diagonal::Right);
        assert!(rectangle(&s).unwrap_err().to_string().contains("limit"));
    }

    #[test]
    fn disk_is_shape_regular_and_on_the_circle() {
        let (c, r, h) = ([0.5, -1.0], 2.0, 0.2);
        let m = disk(c, r, h).unwrap();
        assert_eq!(
            m.curve,
            Some(Circle {
                center: c,
                radius: r
            })
        );
        let q = m.quality();
        assert!(q.min_angle_deg > 25.0, "{q:?}");
        assert!(q.l_n < 2.0 * h, "{q:?}");
        let boundary = m.boundary_vertices();
        let nb = boundary.iter().filter(|b| **b).count();
        let expected = 2.0 * PI * r / h;
        assert!(
            nb as f64 >= expected && (nb as f64) < 1.5 * expected,
            "{nb}"
        );
        for (v, p) in m.points.iter().enumerate() {
            let d = crate::mesh::dist(*p, c);
            if boundary[v] {
                assert!((d - r).abs() < 1e-12 * r, "boundary vertex {v} at {d}");
            } else {
                assert!(d < r);
            }
        }
        // Inscribed polygon with chords ≤ h: area error ≤ n·h³/(12 r).
        let err = PI * r * r - q.area;
        assert!(
            err > 0.0 && err < nb as f64 * h.powi(3) / (12.0 * r),
            "{err}"
        );
        // Refining keeps the boundary on the circle and the area converges.
        let (f, _) = refine_uniform(&m);
        assert!(PI * r * r - f.total_area() < err / 3.0);
    }

    #[test]
    fn fine_disks_and_polygons_are_coarse_meshes_refined_with_their_guarantees() {
        // Small: one Delaunay mesh, as `disk` makes it.
        let small = disk_levels([0.0, 0.0], 1.0, 0.1).unwrap();
        assert_eq!(small.levels.len(), 1);
        assert_eq!(
            triangle_set(small.finest()),
            triangle_set(&disk([0.0, 0.0], 1.0, 0.1).unwrap())
        );
        // Fine: about 4× more triangles than the limit of Delaunay refinement.
        let (c, r, h) = ([0.3, -0.2], 1.0, 0.005);
        let levels = disk_levels(c, r, h).unwrap();
        assert!(levels.levels.len() >= 3, "at least two uniform refinements");
        let m = levels.finest();
        let q = revalidate(m).quality();
        let expected = estimated_triangles(PI * r * r, h);
        assert!(
            (0.6 * expected..1.4 * expected).contains(&(q.triangles as f64)),
            "{} triangles for {expected:.0} expected",
            q.triangles
        );
        // The size and angle guarantees of `disk` (snapping to the circle costs a little
        // of the 30° at the boundary), every boundary vertex on the circle.
        assert!(q.min_angle_deg > 25.0, "{q:?}");
        assert!(q.l_n < 2.0 * h, "{q:?}");
        let boundary = m.boundary_vertices();
        for (v, p) in m.points.iter().enumerate() {
            if boundary[v] {
                let d = crate::mesh::dist(*p, c);
                assert!((d - r).abs() < 1e-12, "boundary vertex {v} at {d}");
            }
        }
        assert_eq!(m.boundary.names.get(&1).map(String::as_str), Some("outer"));

        // A polygon with a hole and a region: areas exact, regions and boundary regions
        // carried to the finest level, angles at least the coarse mesh's.
        let spec = PolygonSpec {
            outer: square(0.0, 2.0),
            holes: vec![square(0.2, 0.6)],
            regions: vec![(
                "clay".into(),
                vec![[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]],
            )],
            size: 0.006,
            min_angle: 28.0,
        };
        let levels = polygon_levels(&spec).unwrap();
        assert!(levels.levels.len() >= 3);
        let m = levels.finest();
        let q = revalidate(m).quality();
        assert!((q.area - (4.0 - 0.16)).abs() < 1e-9, "{}", q.area);
        assert!(q.min_angle_deg > 27.9, "{q:?}");
        assert!(q.l_n < 2.0 * spec.size, "{q:?}");
        let clay: f64 = (0..m.triangles.len())
            .filter(|&k| m.regions[k] == 1)
            .map(|k| m.area(k))
            .sum();
        assert!((clay - 1.0).abs() < 1e-9, "{clay}");
        assert_eq!(m.region_name(1), "clay");
        let names: Vec<&str> = m.boundary.names.values().map(String::as_str).collect();
        assert_eq!(names, ["outer", "hole1"]);
        // Too fine is refused as by `polygon`.
        let e = polygon_levels(&PolygonSpec { size: 1e-5, ..spec }).unwrap_err();
        assert!(e.to_string().contains("limit"), "{e}");
    }

    #[test]
    fn disk_rejects_bad_input() {
        assert!(disk([0.0, 0.0], -1.0, 0.1)
            .unwrap_err()
            .to_string()
            .contains("radius"));
        assert!(disk([0.0, 0.0], 1.0, 0.0)
            .unwrap_err()
            .to_string()
            .contains("size"));
        assert!(disk([0.0, 0.0], 1.0, 1e-5)
            .unwrap_err()
            .to_string()
            .contains("limit"));
        assert!(disk([f64::NAN, 0.0], 1.0, 0.1).is_err());
    }

    fn square(a: f64, b: f64) -> Vec<Point> {
        vec![[a, a], [b, a], [b, b], [a, b]]
    }

    #[test]
    fn polygon_with_hole_and_regions() {
        let s = PolygonSpec {
            outer: vec![
                [0.0, 0.0],
                [4.0, 0.0],
                [4.0, 2.0],
                [2.0, 2.0],
                [2.0, 4.0],
                [0.0, 4.0],
            ],
            holes: vec![vec![[0.5, 0.5], [1.0, 0.5], [1.0, 1.0], [0.5, 1.0]]],
            regions: vec![
                // a layer along the bottom edge, sharing boundary with the outer polygon
                (
                    "clay".into(),
                    vec![[2.0, 0.0], [4.0, 0.0], [4.0, 1.0], [2.0, 1.0]],
                ),
                // a triangle strictly inside
                ("sand".into(), vec![[0.5, 2.5], [1.5, 2.5], [1.0, 3.5]]),
            ],
            size: 0.2,
            min_angle: 28.0,
        };
        let m = polygon(&s).unwrap();
        let q = m.quality();
        assert!((q.area - (12.0 - 0.25)).abs() < 1e-9, "{}", q.area);
        assert!(q.min_angle_deg > 20.0, "{q:?}");
        assert!(q.l_n < 2.0 * s.size, "{q:?}");
        let area_of = |tag: u32| -> f64 {
            (0..m.triangles.len())
                .filter(|&k| m.regions[k] == tag)
                .map(|k| m.area(k))
                .sum()
        };
        assert!((area_of(1) - 2.0).abs() < 1e-9);
        assert!((area_of(2) - 0.5).abs() < 1e-9);
        assert!((area_of(0) - (12.0 - 0.25 - 2.5)).abs() < 1e-9);
        assert_eq!(m.region_name(0), "default");
        assert_eq!(m.region_name(1), "clay");
        assert_eq!(m.region_name(2), "sand");
        // The hole's corners are boundary vertices; no triangle inside the hole.
        for k in 0..m.triangles.len() {
            let c = m.corners(k);
            let g = [
                (c[0][0] + c[1][0] + c[2][0]) / 3.0,
                (c[0][1] + c[1][1] + c[2][1]) / 3.0,
            ];
            assert!(!inside(g, &s.holes[0]));
        }
        // Two boundary loops of total length 18: at least 18 / size boundary edges (more
        // where refinement on both sides of the boundary split them further).
        let nb = m.boundary_edges().len();
        assert!((90..180).contains(&nb), "{nb}");
    }

    #[test]
    fn a_long_thin_polygon_is_refused_before_its_boundary_is_subdivided() {
        // Area 1, boundary 2e9: 2e12 boundary points at size 1e-3.
        let e = polygon(&PolygonSpec {
            outer: vec![[0.0, 0.0], [1e9, 0.0], [1e9, 1e-9], [0.0, 1e-9]],
            size: 1e-3,
            min_angle: 25.0,
            ..PolygonSpec::default()
        })
        .unwrap_err();
        assert!(e.to_string().contains("boundary points"), "{e}");
    }

    #[test]
    fn subdivided_hull_edges_make_no_flat_triangle() {
        // A quadrilateral whose subdivided edges round a point a hair outside its edge's
        // line: once a flat triangle on the convex hull (refused by the mesh checks), and
        // with an inner region an endless refinement.
        let ring = |scale: f64| -> Vec<Point> {
            [
                [0.8314008957461496, 0.4732346134033799],
                [-0.6364938189611482, 0.7629665477107125],
                [-0.5407696944244654, -0.6194612298086862],
                [0.74945108207679, -0.4166310906170837],
            ]
            .iter()
            .map(|p| [scale * p[0], scale * p[1]])
            .collect()
        };
        for regions in [vec![], vec![("core".to_string(), ring(0.5))]] {
            let m = polygon(&PolygonSpec {
                outer: ring(1.0),
                holes: vec![],
                regions,
                size: 0.28482042467643337,
                min_angle: 25.0,
            })
            .unwrap();
            assert!((m.quality().area - ring_area(&ring(1.0)).abs()).abs() < 1e-12);
        }
    }

    #[test]
    fn polygon_without_regions_has_no_names() {
        let s = PolygonSpec {
            outer: square(0.0, 1.0),
            holes: vec![],
            regions: vec![],
            size: 0.1,
            min_angle: 30.0,
        };
        let m = polygon(&s).unwrap();
        assert!(m.region_names.is_empty());
        assert!(m.regions.iter().all(|&r| r == 0));
        assert!((m.total_area() - 1.0).abs() < 1e-12);
        assert!(m.quality().min_angle_deg > 25.0);
    }

    #[test]
    fn polygon_rejects_bad_input() {
        let ok = PolygonSpec {
            outer: square(0.0, 1.0),
            holes: vec![],
            regions: vec![],
            size: 0.1,
            min_angle: 25.0,
        };
        let err = |s: PolygonSpec| polygon(&s).unwrap_err().to_string();
        let mut s = ok.clone();
        s.outer.truncate(2);
        assert!(err(s).contains("at least 3"));
        let mut s = ok.clone();
        s.outer = vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(err(s).contains("self-intersecting"));
        let mut s = ok.clone();
        s.outer[2][0] = f64::INFINITY;
        assert!(err(s).contains("not finite"));
        let mut s = ok.clone();
        s.holes = vec![square(2.0, 3.0)];
        assert!(err(s).contains("outside"));
        let mut s = ok.clone();
        s.holes = vec![square(0.5, 1.5)];
        assert!(err(s).contains("crosses"));
        let mut s = ok.clone();
        s.holes = vec![square(0.2, 0.5), square(0.4, 0.7)];
        assert!(err(s).contains("overlap"));
        let mut s = ok.clone();
        s.holes = vec![square(0.2, 0.8), square(0.4, 0.6)];
        assert!(err(s).contains("overlap"));
        let mut s = ok.clone();
        s.min_angle = 35.0;
        assert!(err(s).contains("min_angle"));
        let mut s = ok.clone();
        s.min_angle = 0.0;
        assert!(err(s).contains("min_angle"));
        let mut s = ok.clone();
        s.size = -1.0;
        assert!(err(s).contains("size"));
        let mut s = ok.clone();
        s.size = 1e-5;
        assert!(err(s).contains("limit"));
        let mut s = ok.clone();
        s.regions = vec![("out".into(), square(0.5, 2.0))];
        assert!(err(s).contains("outside"));
        let mut s = ok;
        s.outer = vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
        let e = err(s);
        assert!(
            e.contains("self-intersecting") || e.contains("zero area"),
            "{e}"
        );
    }

    #[test]
    fn convex_hull_of_l_shape() {
        let l = vec![
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ];
        let h = convex_hull(&l);
        assert_eq!(h.len(), 5);
        assert!((ring_area(&h) - 3.5).abs() < 1e-15);
    }
    #[test]
    fn layer_ending_mid_edge_shares_the_boundary_cleanly() {
        // A 0.7-thick layer along the bottom of an L: its sides end in the middle of the
        // outer edges, whose subdivision (0.2) does not match the layer's (0.175).
        let outer = vec![
            [0.0, 0.0],
            [4.0, 0.0],
            [4.0, 2.0],
            [2.0, 2.0],
            [2.0, 4.0],
            [0.0, 4.0],
        ];
        let layer = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 0.7], [0.0, 0.7]];
        let s = PolygonSpec {
            outer,
            holes: vec![],
            regions: vec![("layer".into(), layer)],
            size: 0.2,
            min_angle: 28.0,
        };
        let m = polygon(&s).unwrap();
        let shortest = m
            .boundary_edges()
            .iter()
            .map(|&[a, b]| crate::mesh::dist(m.points[a as usize], m.points[b as usize]))
            .fold(f64::INFINITY, f64::min);
        assert!(shortest > 0.05, "{shortest}");
        assert!(m.quality().min_angle_deg > 20.0);
        let layer_area: f64 = (0..m.triangles.len())
            .filter(|&k| m.regions[k] == 1)
            .map(|k| m.area(k))
            .sum();
        assert!((layer_area - 2.8).abs() < 1e-9, "{layer_area}");
        assert!((m.total_area() - 12.0).abs() < 1e-9);
    }
    /// Timings for the report: `cargo test --release -p memcontact --lib timings -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn timings() {
        for n in [1024, 4096] {
            let t = std::time::Instant::now();
            let h = rectangle(&spec(n, n, Diagonal::Right)).unwrap();
            let dt = t.elapsed();
            let tri: usize = h.levels.iter().map(|m| m.triangles.len()).sum();
            eprintln!(
                "rectangle {n}²: {dt:?}, {} levels, finest {} vertices / {} triangles, all levels {tri} triangles",
                h.depth(),
                h.finest().points.len(),
                h.finest().triangles.len()
            );
        }
        let coarse = rectangle(&spec(708, 708, Diagonal::Alternate))
            .unwrap()
            .levels
            .pop()
            .unwrap();
        let t = std::time::Instant::now();
        let (f, _) = refine_uniform(&coarse);
        eprintln!(
            "refine_uniform {} -> {} triangles: {:?}",
            coarse.triangles.len(),
            f.triangles.len(),
            t.elapsed()
        );
        let t = std::time::Instant::now();
        let d = disk([0.0, 0.0], 1.0, 0.005).unwrap();
        eprintln!(
            "disk size 0.005: {} triangles in {:?}",
            d.triangles.len(),
            t.elapsed()
        );
    }
}
