//! The structured rectangle, with its multigrid hierarchy and its named sides.

use super::size::MAX_STRUCTURED_TRIANGLES;
use crate::error::{Error, Result};
use crate::mesh::refine::{Hierarchy, Refinement};
use crate::mesh::{BoundaryRegions, Mesh};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::str::FromStr;

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
pub(super) fn lerp(a: f64, b: f64, i: usize, n: usize) -> f64 {
    let t = i as f64 / n as f64;
    a * (1.0 - t) + b * t
}

/// The structured mesh of `spec`'s rectangle with `nx × ny` cells.
pub(super) fn structured(spec: &RectangleSpec, nx: usize, ny: usize) -> Mesh {
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
pub(super) fn rectangle_sides(nx: usize, ny: usize) -> BoundaryRegions {
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
    BoundaryRegions { edges, tags, names }
}

/// The parents of the `2cx × 2cy` structured mesh's vertices in the `cx × cy` one, computed
/// from the grid indices: even/even sits on a coarse vertex, the others are midpoints of a
/// horizontal, vertical or diagonal coarse edge.
pub(super) fn structured_parents(cx: usize, cy: usize, diagonal: Diagonal) -> Refinement {
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
