//! P1 finite elements: element geometry, local matrices and the global assembly of the
//! paper's S, L and D (SPEC §2) over the interior vertices.
//!
//! Assembly is row-wise: every unknown gathers the contributions of the triangles around
//! it. Rows are independent, so they are built in parallel and the result does not depend
//! on the number of threads.

pub use crate::mesh::VertexTriangles;
use crate::mesh::{DofMap, Mesh, Point};
use crate::quadrature::{map, DEGREE5};
use crate::sparse::{Csr, Pattern};
use rayon::prelude::*;
use std::sync::Arc;

/// A coefficient (f, h, ...) that assembly can evaluate.
pub trait Coefficient: Sync {
    /// The value at point `p` inside a triangle of region `region`.
    fn at(&self, p: Point, region: u32) -> f64;
    /// The value on a whole region, when constant there (assembly then uses exact
    /// closed-form element integrals instead of quadrature).
    fn on_region(&self, region: u32) -> Option<f64>;
}

impl Coefficient for f64 {
    fn at(&self, _: Point, _: u32) -> f64 {
        *self
    }
    fn on_region(&self, _: u32) -> Option<f64> {
        Some(*self)
    }
}

/// A coefficient given by a closure of the point (tests, manufactured loads).
pub struct FnCoefficient<F: Fn(Point) -> f64 + Sync>(pub F);

impl<F: Fn(Point) -> f64 + Sync> Coefficient for FnCoefficient<F> {
    fn at(&self, p: Point, _: u32) -> f64 {
        (self.0)(p)
    }
    fn on_region(&self, _: u32) -> Option<f64> {
        None
    }
}

/// Geometry of one P1 triangle: area and the (constant) gradients of the barycentric
/// coordinates λ₀, λ₁, λ₂.
#[derive(Debug, Clone, Copy)]
pub struct Element {
    /// Corner coordinates.
    pub corners: [Point; 3],
    /// Area (positive: meshes are counter-clockwise).
    pub area: f64,
    /// ∇λ_k.
    pub grad: [[f64; 2]; 3],
}

impl Element {
    /// The element of triangle `k` of `mesh`.
    pub fn of(mesh: &Mesh, k: usize) -> Element {
        Element::new(mesh.corners(k))
    }

    /// The element with the given corners.
    pub fn new(c: [Point; 3]) -> Element {
        let two_a =
            (c[1][0] - c[0][0]) * (c[2][1] - c[0][1]) - (c[2][0] - c[0][0]) * (c[1][1] - c[0][1]);
        let mut grad = [[0.0; 2]; 3];
        for (k, g) in grad.iter_mut().enumerate() {
            let (a, b) = (c[(k + 1) % 3], c[(k + 2) % 3]);
            // ∇λ_k is the inward normal of the opposite edge divided by twice the area.
            *g = [(a[1] - b[1]) / two_a, (b[0] - a[0]) / two_a];
        }
        Element {
            corners: c,
            area: 0.5 * two_a,
            grad,
        }
    }

    /// `∫_T ∇λ_a · ∇λ_b`.
    #[inline]
    pub fn stiffness(&self, a: usize, b: usize) -> f64 {
        self.area * (self.grad[a][0] * self.grad[b][0] + self.grad[a][1] * self.grad[b][1])
    }

    /// `∫_T c λ_a λ_b` (exact for constant c on the region, degree-5 quadrature otherwise).
    #[inline]
    pub fn weighted_mass(&self, c: &dyn Coefficient, region: u32, a: usize, b: usize) -> f64 {
        match c.on_region(region) {
            Some(v) => v * self.area * if a == b { 1.0 / 6.0 } else { 1.0 / 12.0 },
            None => {
                self.area
                    * DEGREE5
                        .iter()
                        .map(|(l, w)| w * c.at(map(&self.corners, l), region) * l[a] * l[b])
                        .sum::<f64>()
            }
        }
    }

    /// `∫_T c λ_a` (exact for constant c, degree-5 quadrature otherwise).
    #[inline]
    pub fn weighted_load(&self, c: &dyn Coefficient, region: u32, a: usize) -> f64 {
        match c.on_region(region) {
            Some(v) => v * self.area / 3.0,
            None => {
                self.area
                    * DEGREE5
                        .iter()
                        .map(|(l, w)| w * c.at(map(&self.corners, l), region) * l[a])
                        .sum::<f64>()
            }
        }
    }
}

/// Collects into `buf` the unknowns sharing a triangle with vertex `v`, sorted and unique.
fn row_columns(mesh: &Mesh, dofs: &DofMap, adj: &VertexTriangles, v: usize, buf: &mut Vec<u32>) {
    buf.clear();
    for &k in adj.of(v) {
        for &w in &mesh.triangles[k as usize] {
            if let Some(j) = dofs.dof[w as usize] {
                buf.push(j);
            }
        }
    }
    buf.sort_unstable();
    buf.dedup();
}

/// Splits `val` into the rows of `pattern`, so that rows can be written in parallel.
fn split_rows<'a, T>(pattern: &Pattern, mut val: &'a mut [T]) -> Vec<&'a mut [T]> {
    let mut rows = Vec::with_capacity(pattern.n());
    for i in 0..pattern.n() {
        let (head, tail) = val.split_at_mut(pattern.row_ptr[i + 1] - pattern.row_ptr[i]);
        rows.push(head);
        val = tail;
    }
    rows
}

/// The sparsity pattern over unknowns: `(i, j)` is stored when vertices `a_i`, `a_j` share
/// a triangle. S and the consistent L live on it. Two parallel passes (lengths, then
/// columns) with one scratch buffer per task: no allocation per row.
pub fn unknowns_pattern(mesh: &Mesh, dofs: &DofMap, adj: &VertexTriangles) -> Pattern {
    let lengths: Vec<usize> = dofs
        .vertex
        .par_iter()
        .with_min_len(4096)
        .map_init(
            || Vec::with_capacity(32),
            |buf, &v| {
                row_columns(mesh, dofs, adj, v as usize, buf);
                buf.len()
            },
        )
        .collect();
    let mut row_ptr = Vec::with_capacity(lengths.len() + 1);
    row_ptr.push(0);
    let mut total = 0;
    for l in &lengths {
        total += l;
        row_ptr.push(total);
    }
    let mut pattern = Pattern {
        row_ptr,
        col: vec![0; total],
    };
    let mut col = std::mem::take(&mut pattern.col);
    split_rows(&pattern, &mut col)
        .into_par_iter()
        .enumerate()
        .with_min_len(4096)
        .for_each_init(
            || Vec::with_capacity(32),
            |buf, (i, row)| {
                row_columns(mesh, dofs, adj, dofs.vertex[i] as usize, buf);
                row.copy_from_slice(buf);
            },
        );
    pattern.col = col;
    pattern
}

/// Assembles the stiffness matrix `S_ij = t ∫ ∇g_i·∇g_j` and, when `h` is given, the
/// consistent foundation matrix `L_ij = ∫ h g_i g_j` on `pattern`, in one pass over the rows
/// (SPEC §2). Entry `(i, j)` sums the element integrals of the triangles around `a_i`; rows
/// are assembled in parallel and element geometry is computed once per (row, triangle).
pub fn assemble_stiffness_and_mass(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    pattern: &Arc<Pattern>,
    t: f64,
    h: Option<&dyn Coefficient>,
) -> (Csr, Option<Csr>) {
    let mut s = Csr::zeros(pattern.clone());
    let mut l = h.map(|_| Csr::zeros(pattern.clone()));
    let s_rows = split_rows(pattern, &mut s.val);
    let l_rows: Vec<Option<&mut [f64]>> = match &mut l {
        Some(l) => split_rows(pattern, &mut l.val)
            .into_iter()
            .map(Some)
            .collect(),
        None => (0..pattern.n()).map(|_| None).collect(),
    };
    s_rows
        .into_par_iter()
        .zip(l_rows)
        .enumerate()
        .with_min_len(1024)
        .for_each(|(i, (srow, mut lrow))| {
            let v = dofs.vertex[i] as usize;
            let cols = &pattern.col[pattern.row_ptr[i]..pattern.row_ptr[i + 1]];
            for &k in adj.of(v) {
                let tri = mesh.triangles[k as usize];
                let e = Element::of(mesh, k as usize);
                let region = mesh.regions[k as usize];
                let a = tri
                    .iter()
                    .position(|&w| w as usize == v)
                    .expect("v in triangle");
                let h_const = h.and_then(|h| h.on_region(region));
                for (b, &w) in tri.iter().enumerate() {
                    let Some(j) = dofs.dof[w as usize] else {
                        continue;
                    };
                    let pos = cols.binary_search(&j).expect("pattern covers the patch");
                    srow[pos] += t * e.stiffness(a, b);
                    if let (Some(lrow), Some(h)) = (lrow.as_deref_mut(), h) {
                        lrow[pos] += match h_const {
                            Some(c) => c * e.area * if a == b { 1.0 / 6.0 } else { 1.0 / 12.0 },
                            None => e.weighted_mass(h, region, a, b),
                        };
                    }
                }
            }
        });
    (s, l)
}

/// Fills a vector over unknowns: entry `i` sums `local(element, region, a)` over the
/// triangles around `a_i` (`a` the local index of `a_i`).
pub fn assemble_vector(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    local: &(dyn Fn(&Element, u32, usize) -> f64 + Sync),
) -> Vec<f64> {
    dofs.vertex
        .par_iter()
        .with_min_len(1024)
        .map(|&v| {
            let v = v as usize;
            adj.of(v)
                .iter()
                .map(|&k| {
                    let t = mesh.triangles[k as usize];
                    let a = t
                        .iter()
                        .position(|&w| w as usize == v)
                        .expect("v in triangle");
                    local(&Element::of(mesh, k as usize), mesh.regions[k as usize], a)
                })
                .sum()
        })
        .collect()
}

/// The lifting of boundary data (SPEC §5): `(S_fix G)_i = t Σ_j ∫ ∇g_i·∇g_j G_j` over the
/// fixed vertices j (those without an unknown), for every unknown i. `g` holds G over all
/// vertices (its values at unknowns are not used).
pub fn assemble_lift(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    t: f64,
    g: &[f64],
) -> Vec<f64> {
    dofs.vertex
        .par_iter()
        .with_min_len(1024)
        .map(|&v| {
            let v = v as usize;
            let mut sum = 0.0;
            for &k in adj.of(v) {
                let tri = mesh.triangles[k as usize];
                if tri.iter().all(|&w| dofs.dof[w as usize].is_some()) {
                    continue;
                }
                let e = Element::of(mesh, k as usize);
                let a = tri
                    .iter()
                    .position(|&w| w as usize == v)
                    .expect("v in triangle");
                for (b, &w) in tri.iter().enumerate() {
                    if dofs.dof[w as usize].is_none() {
                        sum += t * e.stiffness(a, b) * g[w as usize];
                    }
                }
            }
            sum
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// The unit square cut into a 2×2 grid of squares, each split into two triangles:
    /// one interior vertex at the centre.
    fn grid() -> Mesh {
        let mut p = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                p.push([i as f64 * 0.5, j as f64 * 0.5]);
            }
        }
        let mut t = Vec::new();
        for j in 0..2u32 {
            for i in 0..2u32 {
                let a = j * 3 + i;
                t.push([a, a + 1, a + 4]);
                t.push([a, a + 4, a + 3]);
            }
        }
        Mesh::new(p, t, vec![], BTreeMap::new()).unwrap()
    }

    #[test]
    fn element_gradients_reproduce_linear_functions() {
        let e = Element::new([[0.2, 0.1], [1.3, 0.4], [0.5, 1.7]]);
        // u = 2x - 3y + 1 has nodal values u(c_k); Σ u_k ∇λ_k must be (2, -3).
        let u: Vec<f64> = e
            .corners
            .iter()
            .map(|c| 2.0 * c[0] - 3.0 * c[1] + 1.0)
            .collect();
        let g = [0, 1].map(|d| (0..3).map(|k| u[k] * e.grad[k][d]).sum::<f64>());
        assert!((g[0] - 2.0).abs() < 1e-13 && (g[1] + 3.0).abs() < 1e-13);
        // Rows of the local stiffness sum to zero (constants are in the kernel).
        for a in 0..3 {
            let s: f64 = (0..3).map(|b| e.stiffness(a, b)).sum();
            assert!(s.abs() < 1e-14);
        }
    }

    #[test]
    fn quadrature_and_closed_form_agree_for_constant_data() {
        let e = Element::new([[0.2, 0.1], [1.3, 0.4], [0.5, 1.7]]);
        let f = FnCoefficient(|_| 2.5);
        for a in 0..3 {
            assert!((e.weighted_load(&f, 0, a) - e.weighted_load(&2.5, 0, a)).abs() < 1e-14);
            for b in 0..3 {
                let q = e.weighted_mass(&f, 0, a, b);
                let c = e.weighted_mass(&2.5, 0, a, b);
                assert!((q - c).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn assembled_centre_row_is_the_five_point_stencil() {
        let m = grid();
        let dofs = DofMap::new(&m);
        let adj = VertexTriangles::new(&m);
        let pat = Arc::new(unknowns_pattern(&m, &dofs, &adj));
        let (s, l) = assemble_stiffness_and_mass(&m, &dofs, &adj, &pat, 1.0, Some(&2.0));
        // ∫ h g² over the patch = h × 6 × (area/6) with area 1/8 per triangle.
        assert!((l.unwrap().get(0, 0) - 2.0 * 6.0 * (1.0 / 8.0) / 6.0).abs() < 1e-15);
        // P1 on right triangles gives the 5-point stencil: diagonal 4.
        assert_eq!(s.n(), 1);
        assert!((s.get(0, 0) - 4.0).abs() < 1e-14);
        // ∫ g = area of the patch / 3 = (6 triangles × 1/8) / 3.
        let d = assemble_vector(&m, &dofs, &adj, &|e, r, a| e.weighted_load(&1.0, r, a));
        assert!((d[0] - 0.25).abs() < 1e-15);
    }
}
