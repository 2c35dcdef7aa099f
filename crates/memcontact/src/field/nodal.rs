//! Data given by its values at the mesh vertices: the P1 interpolant of those values.
//!
//! A field f, h or φ may be given as one number per vertex (measured soil stiffness, a
//! surveyed obstacle surface, a load computed elsewhere). Assembly evaluates coefficients
//! at points (its quadrature points, the vertices); [`NodalP1`] answers those evaluations
//! with the P1 interpolant, so that f and h enter the quadrature of the paper's D and L as
//! the piecewise-linear function, and φ sampled at a vertex is exactly the value given
//! there. Points are located with a uniform grid of triangle buckets.

use crate::error::{Error, Result};
use crate::mesh::{Mesh, Point};
use std::sync::Arc;

/// The P1 interpolant of values at the vertices of a mesh, evaluable at any point of the
/// mesh (NaN outside it).
pub struct NodalP1 {
    points: Vec<Point>,
    triangles: Vec<[u32; 3]>,
    values: Arc<[f64]>,
    grid: Grid,
}

impl std::fmt::Debug for NodalP1 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "NodalP1({} vertex values)", self.values.len())
    }
}

/// Triangles bucketed by the cells of a uniform grid their bounding boxes overlap.
struct Grid {
    origin: Point,
    inv_cell: [f64; 2],
    dims: [usize; 2],
    /// `start[c]..start[c + 1]` indexes `items` for cell `c`.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl Grid {
    fn new(points: &[Point], triangles: &[[u32; 3]]) -> Grid {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        // About one cell per triangle, square-ish cells.
        let w = (hi[0] - lo[0]).max(f64::MIN_POSITIVE);
        let h = (hi[1] - lo[1]).max(f64::MIN_POSITIVE);
        let n = triangles.len().max(1) as f64;
        let nx = ((n * w / h).sqrt().ceil() as usize).clamp(1, 1 << 14);
        let ny = ((n / nx as f64).ceil() as usize).clamp(1, 1 << 14);
        let mut grid = Grid {
            origin: lo,
            inv_cell: [nx as f64 / w, ny as f64 / h],
            dims: [nx, ny],
            start: vec![0; nx * ny + 1],
            items: Vec::new(),
        };
        let span = |g: &Grid, t: &[u32; 3]| {
            let (mut a, mut b) = ([usize::MAX; 2], [0usize; 2]);
            for &v in t {
                let c = g.cell(points[v as usize]);
                for d in 0..2 {
                    a[d] = a[d].min(c[d]);
                    b[d] = b[d].max(c[d]);
                }
            }
            (a, b)
        };
        for t in triangles {
            let (a, b) = span(&grid, t);
            for j in a[1]..=b[1] {
                for i in a[0]..=b[0] {
                    grid.start[j * nx + i + 1] += 1;
                }
            }
        }
        for c in 0..nx * ny {
            grid.start[c + 1] += grid.start[c];
        }
        let mut fill = grid.start.clone();
        grid.items = vec![0; grid.start[nx * ny] as usize];
        for (k, t) in triangles.iter().enumerate() {
            let (a, b) = span(&grid, t);
            for j in a[1]..=b[1] {
                for i in a[0]..=b[0] {
                    let c = j * nx + i;
                    grid.items[fill[c] as usize] = k as u32;
                    fill[c] += 1;
                }
            }
        }
        grid
    }

    /// The cell holding `p` (clamped to the grid).
    fn cell(&self, p: Point) -> [usize; 2] {
        let mut c = [0; 2];
        for d in 0..2 {
            let x = ((p[d] - self.origin[d]) * self.inv_cell[d]).floor();
            c[d] = if x.is_nan() || x < 0.0 {
                0
            } else {
                (x as usize).min(self.dims[d] - 1)
            };
        }
        c
    }

    fn candidates(&self, p: Point) -> &[u32] {
        let [i, j] = self.cell(p);
        let c = j * self.dims[0] + i;
        &self.items[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

impl NodalP1 {
    /// The interpolant of `values` (one per vertex of `mesh`, in the user's numbering: see
    /// [`Mesh::numbering`]). `name` names the field in errors.
    pub fn new(name: &str, mesh: &Mesh, values: Arc<[f64]>) -> Result<NodalP1> {
        if values.len() != mesh.n_vertices() {
            return Err(Error::Data(format!(
                "{name}: {} nodal values for a mesh of {} vertices (give one value per \
                 vertex, in the mesh's vertex order)",
                values.len(),
                mesh.n_vertices()
            )));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(Error::Data(format!(
                "{name}: the value at vertex {i} is not finite ({})",
                values[i]
            )));
        }
        // The values follow the user's numbering; a renumbered mesh takes them in its own.
        let values: Arc<[f64]> = match &mesh.numbering {
            Some(_) => mesh.vertex_values_from_user(&values).into(),
            None => values,
        };
        Ok(NodalP1 {
            grid: Grid::new(&mesh.points, &mesh.triangles),
            points: mesh.points.clone(),
            triangles: mesh.triangles.clone(),
            values,
        })
    }

    /// The barycentric coordinates of `p` in triangle `k`.
    #[inline]
    fn barycentric(&self, k: usize, p: Point) -> [f64; 3] {
        let [a, b, c] = self.triangles[k].map(|v| self.points[v as usize]);
        let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (p[1] - a[1])) / det;
        let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])) / det;
        [1.0 - l1 - l2, l1, l2]
    }

    /// The interpolant at `p`: the value given at a vertex, the P1 interpolant of the
    /// triangle holding `p` elsewhere, NaN outside the mesh.
    pub fn eval(&self, p: Point) -> f64 {
        let Some((k, l)) = self.locate(p) else {
            return f64::NAN;
        };
        let t = self.triangles[k];
        // At a vertex, the value given there, exactly.
        for &v in &t {
            if self.points[v as usize] == p {
                return self.values[v as usize];
            }
        }
        l[0] * self.values[t[0] as usize]
            + l[1] * self.values[t[1] as usize]
            + l[2] * self.values[t[2] as usize]
    }

    /// The triangle holding `p` and its barycentric coordinates there: the first triangle
    /// holding p, else the one p is closest to being in (p on an edge, within rounding);
    /// `None` outside the mesh.
    pub fn locate(&self, p: Point) -> Option<(usize, [f64; 3])> {
        let mut best = (f64::NEG_INFINITY, [0.0; 3], 0usize);
        for &k in self.grid.candidates(p) {
            let l = self.barycentric(k as usize, p);
            let depth = l[0].min(l[1]).min(l[2]);
            if depth > best.0 {
                best = (depth, l, k as usize);
                if depth >= 0.0 {
                    break;
                }
            }
        }
        (best.0 >= -1e-9).then_some((best.2, best.1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::quadrature::{map, DEGREE5};

    #[test]
    fn reproduces_linear_functions_and_vertex_values() {
        let mesh = generate::disk([0.3, -0.2], 1.5, 0.2).unwrap();
        let f = |p: Point| 2.0 - 3.0 * p[0] + 0.5 * p[1];
        let values: Arc<[f64]> = mesh.points.iter().map(|&p| f(p)).collect();
        let n = NodalP1::new("f", &mesh, values.clone()).unwrap();
        for (i, &p) in mesh.points.iter().enumerate() {
            assert_eq!(n.eval(p), values[i]);
        }
        for k in 0..mesh.n_triangles() {
            let c = mesh.corners(k);
            for (l, _) in DEGREE5.iter() {
                let p = map(&c, l);
                assert!((n.eval(p) - f(p)).abs() <= 1e-13, "{k}");
            }
        }
        assert!(n.eval([10.0, 10.0]).is_nan());
    }

    #[test]
    fn interpolates_inside_each_triangle() {
        let mesh = generate::disk([0.0, 0.0], 1.0, 0.3).unwrap();
        let values: Arc<[f64]> = (0..mesh.n_vertices())
            .map(|i| ((i * 7919) % 13) as f64)
            .collect();
        let n = NodalP1::new("h", &mesh, values.clone()).unwrap();
        for (k, t) in mesh.triangles.iter().enumerate() {
            let c = mesh.corners(k);
            let l = [0.2, 0.3, 0.5];
            let p = map(&c, &l);
            let expect: f64 = (0..3).map(|a| l[a] * values[t[a] as usize]).sum();
            assert!((n.eval(p) - expect).abs() <= 1e-12 * 13.0, "{k}");
        }
    }

    #[test]
    fn refuses_wrong_lengths_and_non_finite_values() {
        let mesh = generate::disk([0.0, 0.0], 1.0, 0.5).unwrap();
        let e = NodalP1::new("membrane.load", &mesh, Arc::from(vec![1.0; 3])).unwrap_err();
        assert!(e.to_string().contains("3 nodal values"), "{e}");
        let mut v = vec![1.0; mesh.n_vertices()];
        v[2] = f64::NAN;
        let e = NodalP1::new("membrane.load", &mesh, Arc::from(v)).unwrap_err();
        assert!(e.to_string().contains("vertex 2"), "{e}");
    }

    #[test]
    fn nodal_data_solve_like_the_expressions_they_interpolate() {
        use crate::discretization::Discretization;
        use crate::field::{Field, Stiffness};
        use crate::mesh::refine::Hierarchy;
        use crate::model::Foundation;
        use crate::problem::{Membrane, MeshSpec, Obstacle, Problem, SamplingKind};
        use crate::solve::{Settings, Silent};
        // Linear f, h, φ: the P1 interpolants are the functions themselves.
        let mesh = generate::disk([0.0, 0.0], 1.0, 0.15).unwrap();
        let (f, h, phi) = ("6 + 2*x - y", "80 + 30*x + 10*y", "0.9 - 0.2*x + 0.1*y");
        let nodal = |e: &str| {
            let e = crate::field::expr::Expr::parse(e).unwrap();
            Field::Nodal(mesh.points.iter().map(|p| e.eval(p[0], p[1])).collect())
        };
        for foundation in [Foundation::Consistent, Foundation::Lumped] {
            let problem = |load: Field, h: Field, shape: Field| Problem {
                mesh: MeshSpec::file("unused"),
                membrane: Membrane { tension: 1.5, load },
                obstacle: Obstacle {
                    shape,
                    stiffness: Stiffness::Elastic(h),
                    foundation,
                    sampling: SamplingKind::Nodal,
                    epsilon: None,
                },
                boundary: Default::default(),
                lower: None,
            };
            let solve = |p: Problem| {
                let d = Discretization::assemble(&p, Hierarchy::single(mesh.clone()), &mut Silent)
                    .unwrap();
                let r = d.solve(&Settings::default(), &mut Silent).unwrap();
                assert!(r.status.is_converged());
                (d, r)
            };
            let (de, re) = solve(problem(
                Field::parse(f).unwrap(),
                Field::parse(h).unwrap(),
                Field::parse(phi).unwrap(),
            ));
            let (dn, rn) = solve(problem(nodal(f), nodal(h), nodal(phi)));
            assert!(
                re.u.iter().zip(&de.model.phi).any(|(u, p)| u > p),
                "no contact"
            );
            for (a, b) in re.u.iter().zip(&rn.u) {
                assert!((a - b).abs() <= 1e-12, "{foundation:?}: {a} vs {b}");
            }
            assert_eq!(de.model.phi, dn.model.phi);
        }
    }
}
