//! Discretisation errors of a P1 function against an exact solution
//! (docs/theory.md#manufactured-solutions: the discrete solution must converge at O(l_n) in
//! the H¹ seminorm and about O(l_n²) in L²).
//!
//! `u_h = Σ U_i g_i` lives on the polygon `Ω_n` (the union of the triangles); the exact `u`
//! lives on Ω. Three parts are measured:
//!
//! * **Inside Ω_n**: `‖u - u_h‖_{L²(Ω_n)}` and `|u - u_h|_{H¹(Ω_n)}` by Dunavant's 7-point
//!   degree-5 rule on every triangle (`∇u_h` is constant per triangle). Every vertex and
//!   quadrature point must lie in Ω ([`ExactSolution::contains`]); otherwise the result is an
//!   error naming the triangle, and the exact solution is never evaluated outside Ω.
//! * **The gap `Ω ∖ Ω_n`**, where `u_h = 0` (extended by zero, as `H_n ⊂ H¹₀`): when Ω is a
//!   disc ([`ExactSolution::disk`]) and Ω_n a polygon inscribed in it, the gap is the union
//!   of the circular segments between each boundary edge (a chord) and the arc it cuts off.
//!   On each segment, in polar coordinates `(θ, ρ)` about the centre, with the chord at
//!   `ρ_c(θ) = d / cos(θ - θ_n)` (`d`: distance from the centre to the chord's line, `θ_n`:
//!   direction of its outward normal), `∫ g = ∫_{θ_a}^{θ_b} ∫_{ρ_c(θ)}^{R} g ρ dρ dθ` by a
//!   tensor 8 × 8 Gauss-Legendre rule (on sectors of at most π/16; wider ones are split). `∫ u²` and `∫ |∇u|²` there are the gap's errors;
//!   they enter the totals as `l2 = sqrt(inside² + gap²)` (and the same for H¹), and are
//!   reported separately with the gap's area. Boundary vertices may lie on the circle or
//!   inside it (then the region between chord and arc within the edge's angular sector is
//!   still exactly the gap); each boundary edge must turn counter-clockwise about the
//!   centre by less than π and the edges must turn by 2π in total (one boundary loop around
//!   the centre, no hole), otherwise an error names the edge.
//! * For any other domain (no [`ExactSolution::disk`]), Ω_n is taken to be Ω: the gap is
//!   reported as zero and is not checked.
//!
//! `max_nodal` is `max_i |u(a_i) - U_i|` over all vertices, boundary vertices included.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::quadrature::{gauss_legendre, map, DEGREE5};
use crate::verify::exact::ExactSolution;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Error norms of a P1 function against an exact solution (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ErrorNorms {
    /// `‖u - u_h‖_{L²(Ω)}`, the gap `Ω ∖ Ω_n` included (there `u_h = 0`).
    pub l2: f64,
    /// `|u - u_h|_{H¹(Ω)} = ‖∇(u - u_h)‖_{L²(Ω)}`, the gap included.
    pub h1_semi: f64,
    /// `max_i |u(a_i) - U_i|` over the mesh vertices.
    pub max_nodal: f64,
    /// `meas(Ω ∖ Ω_n)` (0 unless Ω is a disc).
    pub gap_area: f64,
    /// `‖u‖_{L²(Ω ∖ Ω_n)}`: the gap's share of `l2`.
    pub gap_l2: f64,
    /// `‖∇u‖_{L²(Ω ∖ Ω_n)}`: the gap's share of `h1_semi`.
    pub gap_h1_semi: f64,
}

/// Triangles per parallel task; partial sums are added in a fixed order, so the result does
/// not depend on the number of threads.
const CHUNK: usize = 2048;

/// Gauss-Legendre points per direction on each circular segment of the gap.
const GAP_POINTS: usize = 8;

/// The widest angular sector integrated by one tensor rule (wider segments are split).
const MAX_SECTOR: f64 = PI / 16.0;

/// The error norms of `u_h = Σ U_i g_i` (`u_vertices[i] = U_i` on every mesh vertex)
/// against `exact` (see the module documentation for what is integrated, and how).
///
/// Errors: `u_vertices` of the wrong length or not finite ([`Error::Data`]); a vertex or
/// quadrature point outside Ω, or a boundary that is not one loop around the disc's centre
/// ([`Error::Mesh`], naming the triangle or edge).
pub fn error_norms(
    mesh: &Mesh,
    u_vertices: &[f64],
    exact: &dyn ExactSolution,
) -> Result<ErrorNorms> {
    if u_vertices.len() != mesh.n_vertices() {
        return Err(Error::Data(format!(
            "{} vertex values for a mesh of {} vertices",
            u_vertices.len(),
            mesh.n_vertices()
        )));
    }
    if let Some(i) = u_vertices.iter().position(|v| !v.is_finite()) {
        return Err(Error::Data(format!(
            "vertex value U_{i} = {} is not finite",
            u_vertices[i]
        )));
    }
    let n_tri = mesh.n_triangles();
    let parts: Vec<Result<[f64; 2]>> = (0..n_tri.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut sum = [0.0; 2];
            for k in c * CHUNK..((c + 1) * CHUNK).min(n_tri) {
                let e = triangle_errors(mesh, k, u_vertices, exact)?;
                sum[0] += e[0];
                sum[1] += e[1];
            }
            Ok(sum)
        })
        .collect();
    let (mut l2, mut h1) = (0.0, 0.0);
    for p in parts {
        let [a, b] = p?;
        l2 += a;
        h1 += b;
    }
    let mut max_nodal: f64 = 0.0;
    for (i, (&p, &u)) in mesh.points.iter().zip(u_vertices).enumerate() {
        if !exact.contains(p) {
            return Err(Error::Mesh(format!(
                "vertex {i} at ({}, {}) lies outside the domain of {}",
                p[0],
                p[1],
                exact.describe()
            )));
        }
        max_nodal = max_nodal.max((exact.value(p) - u).abs());
    }
    let gap = match exact.disk() {
        Some((c, r)) => disk_gap(mesh, exact, c, r)?,
        None => [0.0; 3],
    };
    Ok(ErrorNorms {
        l2: (l2 + gap[1]).sqrt(),
        h1_semi: (h1 + gap[2]).sqrt(),
        max_nodal,
        gap_area: gap[0],
        gap_l2: gap[1].sqrt(),
        gap_h1_semi: gap[2].sqrt(),
    })
}

/// `[∫_T (u - u_h)², ∫_T |∇(u - u_h)|²]` on triangle `k`, degree-5 quadrature.
fn triangle_errors(
    mesh: &Mesh,
    k: usize,
    u_vertices: &[f64],
    exact: &dyn ExactSolution,
) -> Result<[f64; 2]> {
    let c = mesh.corners(k);
    let tri = mesh.triangles[k];
    for (i, &p) in c.iter().enumerate() {
        if !exact.contains(p) {
            return Err(Error::Mesh(format!(
                "triangle {k}: vertex {} at ({}, {}) lies outside the domain of {}",
                tri[i],
                p[0],
                p[1],
                exact.describe()
            )));
        }
    }
    let u = [
        u_vertices[tri[0] as usize],
        u_vertices[tri[1] as usize],
        u_vertices[tri[2] as usize],
    ];
    // Signed area; ∇λ_i = (y_j - y_k, x_k - x_j) / (2A) for (i, j, k) cyclic.
    let area2 =
        (c[1][0] - c[0][0]) * (c[2][1] - c[0][1]) - (c[2][0] - c[0][0]) * (c[1][1] - c[0][1]);
    let mut grad = [0.0; 2];
    for (i, ui) in u.iter().enumerate() {
        let (j, l) = ((i + 1) % 3, (i + 2) % 3);
        grad[0] += ui * (c[j][1] - c[l][1]) / area2;
        grad[1] += ui * (c[l][0] - c[j][0]) / area2;
    }
    let area = 0.5 * area2.abs();
    let (mut l2, mut h1) = (0.0, 0.0);
    for (b, w) in DEGREE5.iter() {
        let p = map(&c, b);
        if !exact.contains(p) {
            return Err(Error::Mesh(format!(
                "triangle {k}: quadrature point ({}, {}) lies outside the domain of {}",
                p[0],
                p[1],
                exact.describe()
            )));
        }
        let uh = b[0] * u[0] + b[1] * u[1] + b[2] * u[2];
        let e = exact.value(p) - uh;
        let g = exact.gradient(p);
        let (gx, gy) = (g[0] - grad[0], g[1] - grad[1]);
        l2 += w * e * e;
        h1 += w * (gx * gx + gy * gy);
    }
    Ok([area * l2, area * h1])
}

/// `[meas(gap), ∫_gap u², ∫_gap |∇u|²]` for the disc `(c, r)`: the circular segments
/// between the boundary chords of `mesh` and the circle (see the module documentation).
fn disk_gap(mesh: &Mesh, exact: &dyn ExactSolution, c: [f64; 2], r: f64) -> Result<[f64; 3]> {
    let (gx, gw) = gauss_legendre(GAP_POINTS);
    let mut out = [0.0; 3];
    let mut turn = 0.0;
    for [i, j] in mesh.boundary_edges() {
        let (pa, pb) = (mesh.points[i as usize], mesh.points[j as usize]);
        let va = [pa[0] - c[0], pa[1] - c[1]];
        let vb = [pb[0] - c[0], pb[1] - c[1]];
        let cross = va[0] * vb[1] - va[1] * vb[0];
        let dot = va[0] * vb[0] + va[1] * vb[1];
        let dtheta = cross.atan2(dot);
        if !(dtheta > 0.0 && dtheta < PI) || va == [0.0, 0.0] || vb == [0.0, 0.0] {
            return Err(Error::Mesh(format!(
                "boundary edge ({i}, {j}) does not turn counter-clockwise about the centre \
                 ({}, {}) of the disc by less than π (it turns by {dtheta}): Ω_n must be one \
                 polygon around the centre, without holes, to measure the gap to the disc",
                c[0], c[1]
            )));
        }
        turn += dtheta;
        // Outward unit normal of the chord (the domain lies to the left of a → b).
        let (ex, ey) = (pb[0] - pa[0], pb[1] - pa[1]);
        let len = ex.hypot(ey);
        let n = [ey / len, -ex / len];
        let d = n[0] * va[0] + n[1] * va[1];
        let theta_a = va[1].atan2(va[0]);
        // The chord's radius 1/cos has poles a quarter turn from the normal: split wide
        // sectors so that the Gauss rule in θ stays at machine precision.
        let pieces = (dtheta / MAX_SECTOR).ceil().max(1.0);
        let half = 0.5 * dtheta / pieces;
        for piece in 0..pieces as usize {
            let mid = theta_a + (2 * piece + 1) as f64 * half;
            for (xi, wi) in gx.iter().zip(&gw) {
                let th = mid + half * xi;
                let (s, co) = th.sin_cos();
                let rho_c = d / (n[0] * co + n[1] * s);
                if rho_c >= r {
                    continue;
                }
                let hr = 0.5 * (r - rho_c);
                let mr = 0.5 * (r + rho_c);
                for (xj, wj) in gx.iter().zip(&gw) {
                    let rho = mr + hr * xj;
                    let p = [c[0] + rho * co, c[1] + rho * s];
                    let w = wi * half * wj * hr * rho;
                    let u = exact.value(p);
                    let g = exact.gradient(p);
                    out[0] += w;
                    out[1] += w * u * u;
                    out[2] += w * (g[0] * g[0] + g[1] * g[1]);
                }
            }
        }
    }
    if (turn - 2.0 * PI).abs() > 1e-9 {
        return Err(Error::Mesh(format!(
            "the boundary edges turn by {turn} about the centre ({}, {}) of the disc instead \
             of 2π: Ω_n does not surround the centre once, so its gap to the disc is unknown",
            c[0], c[1]
        )));
    }
    Ok(out)
}

/// Observed convergence rates `log(e_{k-1}/e_k) / log(l_{k-1}/l_k)` of a sequence of errors
/// `errors[k]` on meshes of size `l_n[k]` (docs/theory.md#manufactured-solutions: about 1
/// in H¹, 2 in L²).
///
/// The result has one entry per pair `(l_n[k], errors[k])` (the shorter length of the two
/// slices); entry 0 is `None`, and so is any entry where an error or a size is not finite
/// and positive or two successive sizes are equal.
pub fn rates(l_n: &[f64], errors: &[f64]) -> Vec<Option<f64>> {
    let n = l_n.len().min(errors.len());
    let ok = |v: f64| v.is_finite() && v > 0.0;
    (0..n)
        .map(|k| {
            if k == 0 {
                return None;
            }
            let (l0, l1, e0, e1) = (l_n[k - 1], l_n[k], errors[k - 1], errors[k]);
            if !(ok(l0) && ok(l1) && ok(e0) && ok(e1)) || l0 == l1 {
                return None;
            }
            Some((e0 / e1).ln() / (l0 / l1).ln())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::verify::exact::{DiskSolution, Manufactured};
    use std::collections::BTreeMap;

    /// A polynomial on the unit square (test only): `u = cx2 x² + cy2 y² + cx x + cy y + c0`.
    struct Poly([f64; 5]);

    impl ExactSolution for Poly {
        fn value(&self, p: [f64; 2]) -> f64 {
            let [a, b, c, d, e] = self.0;
            a * p[0] * p[0] + b * p[1] * p[1] + c * p[0] + d * p[1] + e
        }
        fn gradient(&self, p: [f64; 2]) -> [f64; 2] {
            let [a, b, c, d, _] = self.0;
            [2.0 * a * p[0] + c, 2.0 * b * p[1] + d]
        }
        fn laplacian(&self, _: [f64; 2]) -> f64 {
            2.0 * (self.0[0] + self.0[1])
        }
        fn contains(&self, p: [f64; 2]) -> bool {
            let t = 1e-12;
            (-t..=1.0 + t).contains(&p[0]) && (-t..=1.0 + t).contains(&p[1])
        }
        fn describe(&self) -> String {
            format!("polynomial {:?} on the unit square", self.0)
        }
    }

    /// The unit square in n × n cells, each cut by its diagonal from (x0, y0) to
    /// (x0 + h, y0 + h).
    fn square(n: usize) -> Mesh {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push([i as f64 / n as f64, j as f64 / n as f64]);
            }
        }
        let v = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                t.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                t.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        Mesh::new(p, t, vec![], BTreeMap::new()).unwrap()
    }

    /// A disc mesh of `m` concentric rings (ring `k` has `6k` vertices at radius
    /// `R k/m`, the outer ones scaled by `outer`), rings joined by merging by angle.
    fn disc(c: [f64; 2], r: f64, m: usize, outer: f64) -> Mesh {
        let mut p = vec![c];
        let mut rings: Vec<Vec<u32>> = vec![vec![0]];
        let mut angles: Vec<Vec<f64>> = vec![vec![0.0]];
        for k in 1..=m {
            let (mut ids, mut ang) = (Vec::new(), Vec::new());
            let rho = r * k as f64 / m as f64 * if k == m { outer } else { 1.0 };
            for i in 0..6 * k {
                let th = 2.0 * PI * (i as f64 + 0.5 * (k % 2) as f64) / (6 * k) as f64;
                ids.push(p.len() as u32);
                ang.push(th);
                p.push([c[0] + rho * th.cos(), c[1] + rho * th.sin()]);
            }
            rings.push(ids);
            angles.push(ang);
        }
        let mut t = Vec::new();
        for i in 0..6 {
            t.push([0, rings[1][i], rings[1][(i + 1) % 6]]);
        }
        for k in 2..=m {
            let (a, b) = (&rings[k - 1], &rings[k]);
            let (aa, ba) = (&angles[k - 1], &angles[k]);
            let (na, nb) = (a.len(), b.len());
            // Unwrapped angle of the i-th vertex of a ring (continuing past 2π).
            let ang = |v: &Vec<f64>, i: usize| v[i % v.len()] + 2.0 * PI * (i / v.len()) as f64;
            let (mut i, mut j) = (0, 0);
            // Start the outer ring at its first vertex after the inner ring's first one.
            let off = (0..nb).find(|&j| ba[j] >= aa[0]).unwrap_or(0);
            while i < na || j < nb {
                let next_a = ang(aa, i + 1);
                let next_b = ang(ba, j + off + 1);
                if j < nb && (i >= na || next_b <= next_a) {
                    t.push([a[i % na], b[(j + off) % nb], b[(j + off + 1) % nb]]);
                    j += 1;
                } else {
                    t.push([a[i % na], b[(j + off) % nb], a[(i + 1) % na]]);
                    i += 1;
                }
            }
        }
        Mesh::new(p, t, vec![], BTreeMap::new()).unwrap()
    }

    #[test]
    fn interpolant_of_a_quadratic_has_the_known_error() {
        // On a cell [x0, x0+h] × [y0, y0+h] cut by its diagonal, the P1 interpolant of x² is
        // the 1-D chord, so e = s(h - s) + σ(h - σ) for u = x² + y² (s = x - x0, σ = y - y0):
        // ‖e‖² = 11 h⁴/90 and |e|²_H¹ = 2 h²/3 on the unit square.
        let u = Poly([1.0, 1.0, 0.3, -0.7, 0.2]);
        for n in [1, 3, 8] {
            let mesh = square(n);
            let uh: Vec<f64> = mesh.points.iter().map(|&p| u.value(p)).collect();
            let e = error_norms(&mesh, &uh, &u).unwrap();
            let h = 1.0 / n as f64;
            let l2 = (11.0 / 90.0f64).sqrt() * h * h;
            let h1 = (2.0 / 3.0f64).sqrt() * h;
            assert!((e.l2 / l2 - 1.0).abs() < 1e-13, "n = {n}: {} {l2}", e.l2);
            assert!(
                (e.h1_semi / h1 - 1.0).abs() < 1e-13,
                "n = {n}: {} {h1}",
                e.h1_semi
            );
            assert!(e.max_nodal < 1e-15);
            assert_eq!((e.gap_area, e.gap_l2, e.gap_h1_semi), (0.0, 0.0, 0.0));
        }
        // x² alone: ‖e‖ = h²/√30, |e|_H¹ = h/√3.
        let u = Poly([1.0, 0.0, 0.0, 0.0, 0.0]);
        let mesh = square(5);
        let uh: Vec<f64> = mesh.points.iter().map(|&p| u.value(p)).collect();
        let e = error_norms(&mesh, &uh, &u).unwrap();
        assert!((e.l2 / (0.04 / 30f64.sqrt()) - 1.0).abs() < 1e-13);
        assert!((e.h1_semi / (0.2 / 3f64.sqrt()) - 1.0).abs() < 1e-13);
    }

    #[test]
    fn linear_functions_are_reproduced_and_nodal_errors_seen() {
        let u = Poly([0.0, 0.0, 2.5, -1.5, 0.75]);
        let mesh = square(6);
        let mut uh: Vec<f64> = mesh.points.iter().map(|&p| u.value(p)).collect();
        let e = error_norms(&mesh, &uh, &u).unwrap();
        assert!(
            e.h1_semi < 1e-13 && e.l2 < 1e-14 && e.max_nodal < 1e-15,
            "{e:?}"
        );
        uh[17] += 1e-3;
        let e = error_norms(&mesh, &uh, &u).unwrap();
        assert!((e.max_nodal - 1e-3).abs() < 1e-15);
        // One perturbed hat function: ‖δ g‖² = δ² (patch area)/6, |δ g|²_H¹ = 4 δ² (Laplacian
        // stencil diagonal for this mesh: 4).
        let patch = 6.0 * 0.5 / 36.0;
        assert!(
            (e.l2 / (1e-3 * (patch / 6.0f64).sqrt()) - 1.0).abs() < 1e-10,
            "{e:?}"
        );
        assert!((e.h1_semi / (1e-3 * 2.0) - 1.0).abs() < 1e-10, "{e:?}");
    }

    #[test]
    fn gap_to_the_disc_is_integrated_exactly() {
        // u = f (R² - r²)/(4t) with U = 0: the totals are the norms of u on the whole disc,
        // ∫ u² = (f/4t)² π R⁶/3 and ∫ |∇u|² = (f/2t)² π R⁴/2, whatever the mesh.
        let (c, r, t, f) = ([0.4, -0.2], 1.7, 2.0, 3.0);
        let u = DiskSolution::new(c, r, t, f, Some(0.0), 0.0).unwrap();
        let l2 = (f / (4.0 * t)) * (PI * r.powi(6) / 3.0).sqrt();
        let h1 = (f / (2.0 * t)) * (PI * r.powi(4) / 2.0).sqrt();
        for (m, outer) in [(1, 1.0), (2, 1.0), (5, 1.0), (3, 0.97)] {
            let mesh = disc(c, r, m, outer);
            let e = error_norms(&mesh, &vec![0.0; mesh.n_vertices()], &u).unwrap();
            assert!((e.l2 / l2 - 1.0).abs() < 1e-13, "m = {m}: {} {l2}", e.l2);
            assert!(
                (e.h1_semi / h1 - 1.0).abs() < 1e-13,
                "m = {m}: {} {h1}",
                e.h1_semi
            );
            assert!((e.gap_area + mesh.total_area() - PI * r * r).abs() < 1e-13);
            if outer == 1.0 {
                // Inscribed regular 6m-gon: gap = π R² - (6m/2) R² sin(2π/6m).
                let n = 6.0 * m as f64;
                let gap = PI * r * r - 0.5 * n * r * r * (2.0 * PI / n).sin();
                assert!((e.gap_area / gap - 1.0).abs() < 1e-12);
            }
            assert!(e.gap_l2 > 0.0 && e.gap_h1_semi > 0.0);
        }
    }

    #[test]
    fn interpolation_converges_at_the_expected_rates_on_a_disc() {
        let u = Manufactured::disk([0.1, 0.2], 1.0, 1.0).unwrap();
        let (mut l, mut l2, mut h1) = (vec![], vec![], vec![]);
        for m in [4, 8, 16, 32] {
            let mesh = disc([0.1, 0.2], 1.0, m, 1.0);
            let uh: Vec<f64> = mesh.points.iter().map(|&p| u.value(p)).collect();
            let e = error_norms(&mesh, &uh, &u).unwrap();
            l.push(mesh.quality().l_n);
            l2.push(e.l2);
            h1.push(e.h1_semi);
            assert!(e.gap_l2 < e.l2 && e.gap_h1_semi < e.h1_semi);
        }
        let (r2, r1) = (rates(&l, &l2), rates(&l, &h1));
        for k in 2..4 {
            let (a, b) = (r2[k].unwrap(), r1[k].unwrap());
            assert!(
                (a - 2.0).abs() < 0.15 && (b - 1.0).abs() < 0.1,
                "{r2:?} {r1:?}"
            );
        }
    }

    #[test]
    fn meshes_that_do_not_fit_the_domain_are_errors() {
        let u = Manufactured::disk([0.5, 0.5], 0.5, 1.0).unwrap();
        let mesh = square(2);
        let e = error_norms(&mesh, &[0.0; 9], &u).unwrap_err().to_string();
        assert!(e.contains("triangle 0") && e.contains("outside"), "{e}");
        // A half disc: its straight edge passes through the centre.
        let c = [0.5, 0.5];
        let mut p = vec![c];
        for i in 0..=6 {
            let th = PI * i as f64 / 6.0;
            p.push([c[0] + 0.5 * th.cos(), c[1] + 0.5 * th.sin()]);
        }
        let t = (0..6).map(|i| [0, i + 1, i + 2]).collect();
        let half = Mesh::new(p, t, vec![], BTreeMap::new()).unwrap();
        let e = error_norms(&half, &[0.0; 8], &u).unwrap_err().to_string();
        assert!(e.contains("boundary edge"), "{e}");
        // A wrong number of values, a NaN.
        assert!(error_norms(&half, &[0.0; 3], &u).is_err());
        let mut v = vec![0.0; 8];
        v[2] = f64::NAN;
        assert!(error_norms(&half, &v, &u)
            .unwrap_err()
            .to_string()
            .contains("U_2"));
    }

    #[test]
    fn rates_of_a_synthetic_sequence() {
        let l = [0.4, 0.2, 0.1, 0.05, 0.05];
        let e: Vec<f64> = l.iter().map(|h: &f64| 3.0 * h.powf(1.5)).collect();
        let r = rates(&l, &e);
        assert_eq!(r.len(), 5);
        assert_eq!((r[0], r[4]), (None, None));
        for x in &r[1..4] {
            assert!((x.unwrap() - 1.5).abs() < 1e-13);
        }
        assert_eq!(rates(&[1.0, 0.5], &[1.0, 0.0]), vec![None, None]);
        assert_eq!(rates(&[1.0, 0.5, 0.25], &[1.0, 0.25]).len(), 2);
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let (x, w) = gauss_legendre(GAP_POINTS);
        for k in 0..2 * GAP_POINTS {
            let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
            let exact = if k % 2 == 1 {
                0.0
            } else {
                2.0 / (k as f64 + 1.0)
            };
            assert!((q - exact).abs() < 2e-15, "k = {k}: {q}");
        }
    }
}
