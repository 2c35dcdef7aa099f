//! The discrete model of SPEC §2 (the paper's §2): the stiffness matrix S, the h-weighted
//! foundation matrix L (consistent, or its lumped variant), the load D, the sampled
//! obstacle φₙ and the set M of vertices that can touch; the energy J of Problem 2b and the
//! certificates of Problems 2e and 2f.

pub use crate::certificate::Certificate;
use crate::fem::{
    assemble_stiffness_and_mass, assemble_vector, unknowns_pattern, Coefficient, Element,
    VertexTriangles,
};
use crate::mesh::{DofMap, Mesh};
use crate::quadrature::gauss_legendre;
use crate::sparse::{norm_inf, Csr};
use crate::{Error, Result};
use rayon::prelude::*;
use std::sync::Arc;

/// Which foundation matrix represents the elastic obstacle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Foundation {
    /// The paper's consistent matrix `L_ij = ∫ h g_i g_j` (J₂ is not differentiable).
    Consistent,
    /// The diagonal `l_i = ∫ h g_i` (SPEC §3): J is C¹ with a semismooth gradient.
    Lumped,
}

impl std::str::FromStr for Foundation {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "consistent" => Ok(Foundation::Consistent),
            "lumped" => Ok(Foundation::Lumped),
            _ => Err(Error::Data(format!(
                "foundation must be \"consistent\" or \"lumped\", not \"{s}\""
            ))),
        }
    }
}

impl Foundation {
    /// The name used in case files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            Foundation::Consistent => "consistent",
            Foundation::Lumped => "lumped",
        }
    }
}

/// How the obstacle φ is sampled at the vertices (SPEC §2, "Obstacle sampling").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sampling {
    /// `φ_i = φ(a_i)`: the usual practice for continuous φ.
    Nodal,
    /// The paper's `φ_n = r_n (J_ε * φ)`; `epsilon: None` takes the paper's
    /// `ε_n = max{l_n^¼, meas(Ω∖Ω_n)^¼, meas(Ω'_n)^¼}`.
    Mollified {
        /// The mollifier radius, or `None` for the paper's ε_n.
        epsilon: Option<f64>,
    },
}

/// The obstacle's stiffness.
#[derive(Clone, Copy)]
pub enum Stiffness<'a> {
    /// A Winkler foundation of stiffness h ≥ 0.
    Elastic(&'a dyn Coefficient),
    /// The rigid obstacle (h = ∞): the classical constraint u ≤ φ.
    Rigid,
}

/// The problem data of Problem 1: tension, load, obstacle.
#[derive(Clone, Copy)]
pub struct ProblemData<'a> {
    /// Tension t > 0.
    pub tension: f64,
    /// Load f.
    pub load: &'a dyn Coefficient,
    /// Obstacle surface φ.
    pub shape: &'a dyn Coefficient,
    /// Obstacle stiffness h.
    pub stiffness: Stiffness<'a>,
    /// Consistent or lumped L.
    pub foundation: Foundation,
    /// How φ is sampled.
    pub sampling: Sampling,
}

/// The foundation term of J: `J₂(V) = ½ pᵀ L p` with `p = (V − φ)⁺`.
#[derive(Debug, Clone)]
pub enum FoundationMatrix {
    /// The consistent L, on the pattern of S.
    Consistent(Csr),
    /// The lumped diagonal l.
    Lumped(Vec<f64>),
    /// The rigid obstacle: no L, the constraint `U ≤ φ` on M.
    Rigid,
}

impl FoundationMatrix {
    /// `(L p)_i`.
    #[inline]
    pub fn row_dot(&self, i: usize, p: &[f64]) -> f64 {
        match self {
            FoundationMatrix::Consistent(l) => l.row_dot(i, p),
            FoundationMatrix::Lumped(d) => d[i] * p[i],
            FoundationMatrix::Rigid => 0.0,
        }
    }

    /// `y = L p`.
    pub fn mul_into(&self, p: &[f64], y: &mut [f64]) {
        match self {
            FoundationMatrix::Consistent(l) => l.mul_into(p, y),
            FoundationMatrix::Lumped(d) => {
                for ((yi, di), pi) in y.iter_mut().zip(d).zip(p) {
                    *yi = di * pi;
                }
            }
            FoundationMatrix::Rigid => y.iter_mut().for_each(|v| *v = 0.0),
        }
    }

    /// `L_ii`.
    #[inline]
    pub fn diag(&self, i: usize) -> f64 {
        match self {
            FoundationMatrix::Consistent(l) => l.get(i, i),
            FoundationMatrix::Lumped(d) => d[i],
            FoundationMatrix::Rigid => 0.0,
        }
    }

    /// `true` for the rigid obstacle.
    pub fn is_rigid(&self) -> bool {
        matches!(self, FoundationMatrix::Rigid)
    }
}

/// The assembled discrete model (SPEC §2).
#[derive(Debug, Clone)]
pub struct Model {
    /// Unknowns ↔ vertices.
    pub dofs: DofMap,
    /// Tension t.
    pub tension: f64,
    /// `S_ij = t ∫ ∇g_i·∇g_j` over the unknowns.
    pub s: Csr,
    /// L (consistent or lumped) or the rigid constraint.
    pub l: FoundationMatrix,
    /// `D_i = ∫ f g_i`.
    pub d: Vec<f64>,
    /// Sampled obstacle φ_i at the unknowns.
    pub phi: Vec<f64>,
    /// `M`: unknowns whose patch meets {h > 0} (`L_ii > 0`), all unknowns when rigid.
    pub can_touch: Vec<bool>,
    /// Which foundation was asked for (for reports).
    pub foundation: Foundation,
    /// φ sampled at every vertex (boundary included; for outputs).
    pub phi_vertices: Vec<f64>,
    /// h at every vertex (average over the triangles around it; ∞ when rigid).
    pub h_vertices: Vec<f64>,
    /// `∫_{Ω_n} f`.
    pub total_load: f64,
    /// The mollifier radius used, when φ was mollified.
    pub epsilon: Option<f64>,
}

impl Model {
    /// Assembles S, L, D, φₙ and M on `mesh` (SPEC §2), validating the data: t > 0,
    /// h ≥ 0, every value finite.
    pub fn assemble(mesh: &Mesh, data: &ProblemData) -> Result<Model> {
        let t = data.tension;
        if !t.is_finite() || t <= 0.0 {
            return Err(Error::Data(format!(
                "membrane.tension must be a finite number > 0, got {t}"
            )));
        }
        let adj = VertexTriangles::new(mesh);
        let dofs = DofMap::with_adjacency(mesh, &adj);
        if dofs.is_empty() {
            return Err(Error::Mesh(
                "the mesh has no interior vertex: there is no unknown to solve for".into(),
            ));
        }
        // Data checks: every value finite, h ≥ 0. f and h at the triangle centroids (their
        // quadrature), φ and h at the vertices (their samples).
        check_centroids(mesh, "membrane.load f", data.load, false)?;
        let h_vertices = match data.stiffness {
            Stiffness::Rigid => vec![f64::INFINITY; mesh.n_vertices()],
            Stiffness::Elastic(h) => {
                check_centroids(mesh, "obstacle.stiffness h", h, true)?;
                let hv = vertex_average(mesh, &adj, h);
                check_vertices(mesh, "obstacle.stiffness h", &hv, true)?;
                hv
            }
        };
        let pattern = Arc::new(unknowns_pattern(mesh, &dofs, &adj));
        let consistent_h = match (data.stiffness, data.foundation) {
            (Stiffness::Elastic(h), Foundation::Consistent) => Some(h),
            _ => None,
        };
        let (s, l_consistent) =
            assemble_stiffness_and_mass(mesh, &dofs, &adj, &pattern, t, consistent_h);
        let l = match (data.stiffness, l_consistent) {
            (Stiffness::Rigid, _) => FoundationMatrix::Rigid,
            (_, Some(l)) => FoundationMatrix::Consistent(l),
            (Stiffness::Elastic(h), None) => {
                FoundationMatrix::Lumped(assemble_vector(mesh, &dofs, &adj, &|e, r, a| {
                    e.weighted_load(h, r, a)
                }))
            }
        };
        let load = data.load;
        let d = assemble_vector(mesh, &dofs, &adj, &|e, r, a| e.weighted_load(load, r, a));
        if let Some(i) = d.iter().position(|v| !v.is_finite()) {
            let p = mesh.points[dofs.vertex[i] as usize];
            return Err(Error::Data(format!(
                "membrane.load f is not finite near ({}, {})",
                p[0], p[1]
            )));
        }
        let total_load: f64 = (0..mesh.n_triangles())
            .into_par_iter()
            .with_min_len(4096)
            .map(|k| {
                let e = Element::of(mesh, k);
                let r = mesh.regions[k];
                (0..3).map(|a| e.weighted_load(load, r, a)).sum::<f64>()
            })
            .sum();
        let can_touch: Vec<bool> = (0..dofs.len())
            .map(|i| l.is_rigid() || l.diag(i) > 0.0)
            .collect();
        let (phi_vertices, epsilon) = match data.sampling {
            Sampling::Nodal => (vertex_average(mesh, &adj, data.shape), None),
            Sampling::Mollified { epsilon } => {
                let eps = match epsilon {
                    Some(e) if e.is_finite() && e > 0.0 => e,
                    Some(e) => {
                        return Err(Error::Data(format!(
                            "obstacle.epsilon must be a finite number > 0, got {e}"
                        )))
                    }
                    None => paper_epsilon(mesh),
                };
                (mollify(mesh, &adj, data.shape, eps), Some(eps))
            }
        };
        check_vertices(mesh, "obstacle.shape φ", &phi_vertices, false)?;
        let phi = dofs.to_unknowns(&phi_vertices);
        Ok(Model {
            dofs,
            tension: t,
            s,
            l,
            d,
            phi,
            can_touch,
            foundation: data.foundation,
            phi_vertices,
            h_vertices,
            total_load,
            epsilon,
        })
    }

    /// Number of unknowns m.
    pub fn n(&self) -> usize {
        self.d.len()
    }

    /// `true` for the rigid obstacle.
    pub fn is_rigid(&self) -> bool {
        self.l.is_rigid()
    }

    /// `true` when L = 0 (h = 0 on Ω_n): Problem 2b is the linear system S U = D.
    pub fn is_linear(&self) -> bool {
        !self.is_rigid() && !self.can_touch.iter().any(|&c| c)
    }

    /// The penetration `p = (V − φ)⁺` (zero outside M).
    pub fn penetration(&self, v: &[f64]) -> Vec<f64> {
        v.iter()
            .zip(&self.phi)
            .zip(&self.can_touch)
            .map(|((vi, fi), &c)| if c { (vi - fi).max(0.0) } else { 0.0 })
            .collect()
    }

    /// The energy of Problem 2b, `J(V) = ½ VᵀSV − VᵀD + ½ pᵀ L p`; for the rigid
    /// obstacle `+∞` outside `{V ≤ φ on M}`.
    pub fn energy(&self, v: &[f64]) -> f64 {
        let j1 = 0.5 * self.s.quad_form(v) - crate::sparse::dot(v, &self.d);
        match &self.l {
            FoundationMatrix::Rigid => {
                let feasible = v
                    .iter()
                    .zip(&self.phi)
                    .zip(&self.can_touch)
                    .all(|((vi, fi), &c)| !c || vi <= fi);
                if feasible {
                    j1
                } else {
                    f64::INFINITY
                }
            }
            FoundationMatrix::Consistent(l) => j1 + 0.5 * l.quad_form(&self.penetration(v)),
            FoundationMatrix::Lumped(d) => {
                let p = self.penetration(v);
                j1 + 0.5 * p.iter().zip(d).map(|(p, d)| d * p * p).sum::<f64>()
            }
        }
    }

    /// `r = S V − D`.
    pub fn residual(&self, v: &[f64]) -> Vec<f64> {
        let mut r = self.s.mul(v);
        for (ri, di) in r.iter_mut().zip(&self.d) {
            *ri -= di;
        }
        r
    }

    /// The vertex states: −1 clear (`U < φ`, or the vertex cannot touch), 0 touching
    /// (`U = φ`), 1 penetrating (`U > φ`).
    pub fn states(&self, u: &[f64]) -> Vec<i8> {
        u.iter()
            .zip(&self.phi)
            .zip(&self.can_touch)
            .map(|((ui, fi), &c)| {
                if !c || ui < fi {
                    -1
                } else if ui == fi {
                    0
                } else {
                    1
                }
            })
            .collect()
    }

    /// A force scale of the data, `max(‖D‖∞, ‖Sφ‖∞, ‖L|φ|‖∞)`: the size of the forces the
    /// problem can involve, for scaling a formulation (the QP). Certificates are scaled by
    /// the forces of the iterate instead ([`crate::certificate`]).
    pub fn force_scale(&self) -> f64 {
        let sphi = norm_inf(&self.s.mul(&self.phi));
        let abs_phi: Vec<f64> = self.phi.iter().map(|p| p.abs()).collect();
        let mut lphi = vec![0.0; self.n()];
        self.l.mul_into(&abs_phi, &mut lphi);
        norm_inf(&self.d)
            .max(sphi)
            .max(norm_inf(&lphi))
            .max(f64::MIN_POSITIVE)
    }

    /// The optimality certificates of a candidate U (Problems 2e and 2f, scaled by the
    /// forces of U): see [`crate::certificate`].
    pub fn certificate(&self, u: &[f64]) -> Certificate {
        crate::certificate::evaluate(self, u).certificate
    }
}

/// The error for a bad value `v` of `name` at `p`.
fn bad_value(name: &str, v: f64, p: [f64; 2]) -> Error {
    let what = if v.is_nan() {
        "is NaN".to_string()
    } else if !v.is_finite() {
        format!("is infinite ({v})")
    } else {
        format!("is negative ({v})")
    };
    Error::Data(format!("{name} {what} at ({}, {})", p[0], p[1]))
}

/// Checks a coefficient at every triangle centroid: finite, and non-negative when asked
/// (once per region where it is constant).
fn check_centroids(mesh: &Mesh, name: &str, c: &dyn Coefficient, non_negative: bool) -> Result<()> {
    let bad = |v: f64| !v.is_finite() || (non_negative && v < 0.0);
    let found = (0..mesh.n_triangles())
        .into_par_iter()
        .with_min_len(4096)
        .find_map_first(|k| {
            let r = mesh.regions[k];
            let cs = mesh.corners(k);
            let p = [
                (cs[0][0] + cs[1][0] + cs[2][0]) / 3.0,
                (cs[0][1] + cs[1][1] + cs[2][1]) / 3.0,
            ];
            let v = c.on_region(r).unwrap_or_else(|| c.at(p, r));
            bad(v).then_some((v, p))
        });
    match found {
        Some((v, p)) => Err(bad_value(name, v, p)),
        None => Ok(()),
    }
}

/// Checks sampled vertex values: finite, and non-negative when asked.
fn check_vertices(mesh: &Mesh, name: &str, values: &[f64], non_negative: bool) -> Result<()> {
    match values
        .iter()
        .position(|&v| !v.is_finite() || (non_negative && v < 0.0))
    {
        Some(i) => Err(bad_value(name, values[i], mesh.points[i])),
        None => Ok(()),
    }
}

/// A coefficient at every vertex: the average over the triangles around it of its value
/// there with that triangle's region (so region tables are averaged on interfaces).
fn vertex_average(mesh: &Mesh, adj: &VertexTriangles, c: &dyn Coefficient) -> Vec<f64> {
    (0..mesh.n_vertices())
        .into_par_iter()
        .with_min_len(1024)
        .map(|v| {
            let tris = adj.of(v);
            let first = mesh.regions[tris[0] as usize];
            if tris.iter().all(|&k| mesh.regions[k as usize] == first) {
                return c.at(mesh.points[v], first);
            }
            tris.iter()
                .map(|&k| c.at(mesh.points[v], mesh.regions[k as usize]))
                .sum::<f64>()
                / tris.len() as f64
        })
        .collect()
}

/// The paper's mollifier radius `ε_n = max{l_n^¼, meas(Ω∖Ω_n)^¼, meas(Ω'_n)^¼}`, with
/// Ω'_n the triangles having a vertex on ∂Ω_n and Ω∖Ω_n the gap to a curved boundary.
pub fn paper_epsilon(mesh: &Mesh) -> f64 {
    let q = mesh.quality();
    let boundary = mesh.boundary_vertices();
    let boundary_layer: f64 = (0..mesh.n_triangles())
        .filter(|&k| mesh.triangles[k].iter().any(|&v| boundary[v as usize]))
        .map(|k| mesh.area(k))
        .sum();
    let gap = mesh
        .curve
        .map(|c| (std::f64::consts::PI * c.radius * c.radius - q.area).max(0.0))
        .unwrap_or(0.0);
    q.l_n
        .powf(0.25)
        .max(gap.powf(0.25))
        .max(boundary_layer.powf(0.25))
}

/// `(J_ε * φ)(a_v)` at every vertex, with the standard mollifier
/// `J(x) ∝ exp(−1 / (1 − |x|²/ε²))` on the disc of radius ε. φ is evaluated as a function
/// on the plane (with the vertex's region for region tables); a polar Gauss rule
/// (16 radii × 32 angles), normalised with the same rule, keeps constants exact.
fn mollify(mesh: &Mesh, adj: &VertexTriangles, phi: &dyn Coefficient, eps: f64) -> Vec<f64> {
    const NR: usize = 16;
    const NT: usize = 32;
    let (gx, gw) = gauss_legendre(NR);
    // Radial nodes on (0, 1) with the Jacobian r and the mollifier profile.
    let radial: Vec<(f64, f64)> = gx
        .iter()
        .zip(&gw)
        .map(|(&x, &w)| {
            let s = 0.5 * (x + 1.0);
            let prof = (-1.0 / (1.0 - s * s)).exp();
            (s, 0.5 * w * s * prof)
        })
        .collect();
    let norm: f64 = radial.iter().map(|r| r.1).sum::<f64>() * NT as f64;
    (0..mesh.n_vertices())
        .into_par_iter()
        .with_min_len(256)
        .map(|v| {
            let a = mesh.points[v];
            let region = mesh.regions[adj.of(v)[0] as usize];
            let mut acc = 0.0;
            for &(s, w) in &radial {
                for k in 0..NT {
                    let th = 2.0 * std::f64::consts::PI * (k as f64 + 0.5) / NT as f64;
                    let p = [a[0] + eps * s * th.cos(), a[1] + eps * s * th.sin()];
                    acc += w * phi.at(p, region);
                }
            }
            acc / norm
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::tests::square;

    fn data<'a>(h: &'a f64, foundation: Foundation) -> ProblemData<'a> {
        ProblemData {
            tension: 2.0,
            load: &3.0,
            shape: &0.1,
            stiffness: Stiffness::Elastic(h),
            foundation,
            sampling: Sampling::Nodal,
        }
    }

    #[test]
    fn matrices_have_the_expected_sums() {
        let m = square(8);
        let h = 5.0;
        let model = Model::assemble(&m, &data(&h, Foundation::Consistent)).unwrap();
        // Σ_ij L_ij over interior × interior = ∫ h (Σ_i g_i)² ≤ h |Ω|; and L ≥ 0 entrywise.
        let FoundationMatrix::Consistent(l) = &model.l else {
            panic!()
        };
        assert!(l.val.iter().all(|&v| v >= 0.0));
        let ones = vec![1.0; model.n()];
        let total = l.quad_form(&ones);
        assert!(total > 0.0 && total < h);
        // S annihilates constants in the interior rows far from the boundary and is SPD.
        assert!(model.s.quad_form(&ones) > 0.0);
        // Σ D_i = ∫ f Σ g_i = f (|Ω| − boundary layer /3 ...) < f |Ω|.
        let sd: f64 = model.d.iter().sum();
        assert!(sd < 3.0 && sd > 0.0);
        assert!((model.total_load - 3.0).abs() < 1e-13);
        // Lumped l_i = ∫ h g_i = row sums of the full mass matrix = h × patch area / 3.
        let lumped = Model::assemble(&m, &data(&h, Foundation::Lumped)).unwrap();
        let FoundationMatrix::Lumped(d) = &lumped.l else {
            panic!()
        };
        for &v in d {
            assert!((v - h * 6.0 / (2.0 * 64.0) / 3.0).abs() < 1e-14);
        }
    }

    #[test]
    fn bad_data_is_reported() {
        let m = square(4);
        let h = -1.0;
        let e = Model::assemble(&m, &data(&h, Foundation::Consistent)).unwrap_err();
        assert!(e.to_string().contains("negative"), "{e}");
        let h = f64::NAN;
        let e = Model::assemble(&m, &data(&h, Foundation::Consistent)).unwrap_err();
        assert!(e.to_string().contains("NaN"), "{e}");
        let h = 1.0;
        let mut d = data(&h, Foundation::Consistent);
        d.tension = 0.0;
        let e = Model::assemble(&m, &d).unwrap_err();
        assert!(e.to_string().contains("tension"), "{e}");
    }

    #[test]
    fn mollification_keeps_constants_and_linear_functions() {
        let m = square(4);
        let adj = VertexTriangles::new(&m);
        let c = crate::fem::FnCoefficient(|p: crate::mesh::Point| 2.0 * p[0] - p[1] + 0.5);
        let v = mollify(&m, &adj, &c, 0.3);
        for (k, p) in m.points.iter().enumerate() {
            assert!((v[k] - (2.0 * p[0] - p[1] + 0.5)).abs() < 1e-13);
        }
        let (x, w) = gauss_legendre(8);
        let s: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(14)).sum();
        assert!((s - 2.0 / 15.0).abs() < 1e-14);
        assert!(paper_epsilon(&m) >= 0.25f64.sqrt().sqrt() * 2f64.sqrt().sqrt() - 1e-12);
    }
}
