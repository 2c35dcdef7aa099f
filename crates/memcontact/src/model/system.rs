//! The discrete model of the paper's §2: S, L, D, φₙ, M and the energy J of Problem 2b.

use super::body::{foundation_energy, Body, FoundationMatrix, VertexValues};
use super::data::Foundation;
use crate::mesh::DofMap;
use crate::sparse::{norm_inf, Csr};
use rayon::prelude::*;

/// The assembled discrete model (docs/theory.md#discrete-model).
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
    /// φ sampled at the vertices that carry no unknown, `(vertex, value)` (at the unknowns
    /// it is `phi`): with `phi`, φ at every vertex for the outputs
    /// ([`Model::phi_vertices`]).
    pub phi_fixed: Vec<(u32, f64)>,
    /// h at every vertex (average over the triangles around it; ∞ when rigid).
    pub h_vertices: VertexValues,
    /// `∫_{Ω_n} f`.
    pub total_load: f64,
    /// The mollifier radius used, when φ was mollified.
    pub epsilon: Option<f64>,
    /// Unknowns the obstacle holds rigidly (`U ≤ φ`) when it is rigid in some regions only
    /// (mixed bodies, docs/theory.md#mixed-bodies); `None` when it is rigid everywhere (`l`
    /// says so) or nowhere.
    pub rigid: Option<Vec<bool>>,
    /// The body below the membrane (docs/theory.md#second-body).
    pub lower: Option<Body>,
    /// u where it is prescribed (the heights g on Γ_D), 0 at the other vertices; over all
    /// vertices (empty when g = 0 everywhere, and for models that only a solver uses).
    pub boundary_values: Vec<f64>,
    /// The lifting `S_fix G` over the unknowns (empty when G = 0): `d` is the assembled
    /// load minus it (docs/theory.md#boundary-data).
    pub lift: Vec<f64>,
}

impl Model {
    /// Number of unknowns m.
    pub fn n(&self) -> usize {
        self.d.len()
    }

    /// `true` for the rigid obstacle.
    pub fn is_rigid(&self) -> bool {
        self.l.is_rigid()
    }

    /// `true` when the obstacle holds unknown `i` rigidly (`U_i ≤ φ_i`): everywhere for
    /// the rigid obstacle, on the vertices next to its rigid regions for a mixed one.
    #[inline]
    pub fn rigid_at(&self, i: usize) -> bool {
        self.l.is_rigid() || self.rigid.as_ref().is_some_and(|r| r[i])
    }

    /// `true` when the model goes beyond the paper's single body: a body below, or an
    /// obstacle rigid in some regions only. The solvers' inner loops take their general
    /// path only then.
    #[inline]
    pub fn is_extended(&self) -> bool {
        self.lower.is_some() || self.rigid.is_some()
    }

    /// `true` when no body can touch (L = 0, no rigid part, no body below that can
    /// touch): Problem 2b is the linear system S U = D.
    pub fn is_linear(&self) -> bool {
        !self.is_rigid()
            && !self.can_touch.iter().any(|&c| c)
            && self
                .lower
                .as_ref()
                .is_none_or(|b| !b.l.is_rigid() && !b.can_touch.iter().any(|&c| c))
    }

    /// φ sampled at every vertex (boundary included).
    pub fn phi_vertices(&self) -> Vec<f64> {
        super::body::with_fixed(self.dofs.to_vertices(&self.phi, 0.0), &self.phi_fixed)
    }

    /// U over all vertices: the unknowns' values, and the heights g (0 by default) on the
    /// fixed boundary.
    pub fn to_vertices(&self, u: &[f64]) -> Vec<f64> {
        if self.boundary_values.len() != self.dofs.n_vertices() {
            return self.dofs.to_vertices(u, 0.0);
        }
        let mut out = self.boundary_values.clone();
        for (i, &v) in self.dofs.vertex.iter().enumerate() {
            out[v as usize] = u[i];
        }
        out
    }

    /// The penetration `p = (V − φ)⁺` (zero outside M).
    pub fn penetration(&self, v: &[f64]) -> Vec<f64> {
        v.par_iter()
            .with_min_len(4096)
            .zip(&self.phi)
            .zip(&self.can_touch)
            .map(|((vi, fi), &c)| if c { (vi - fi).max(0.0) } else { 0.0 })
            .collect()
    }

    /// The energy of Problem 2b, `J(V) = ½ VᵀSV − VᵀD + ½ pᵀ L p` (`+ ½ qᵀ L_low q` with a
    /// body below, docs/theory.md#second-body); `+∞` outside the constraints of rigid
    /// bodies (`V ≤ φ` where the obstacle is rigid, `V ≥ φ_low` where the body below is).
    pub fn energy(&self, v: &[f64]) -> f64 {
        let j1 = 0.5 * self.s.quad_form(v) - crate::sparse::dot(v, &self.d);
        let j = match &self.l {
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
            l => j1 + foundation_energy(l, &self.penetration(v)),
        };
        if !self.is_extended() {
            return j;
        }
        let n = self.n();
        if (0..n).any(|i| self.rigid_at(i) && v[i] > self.phi[i]) {
            return f64::INFINITY;
        }
        match &self.lower {
            Some(low) => {
                if (0..n).any(|i| low.rigid_at(i) && v[i] < low.phi[i]) {
                    return f64::INFINITY;
                }
                j + foundation_energy(&low.l, &low.penetration(v))
            }
            None => j,
        }
    }

    /// `true` when some body holds some unknown rigidly (the obstacle rigid, or rigid in
    /// some regions, or a body below that is).
    pub fn has_rigid_part(&self) -> bool {
        self.is_rigid()
            || self.rigid.is_some()
            || self
                .lower
                .as_ref()
                .is_some_and(|b| b.l.is_rigid() || b.rigid.is_some())
    }

    /// Projects `v` onto the rigid bodies' constraints: `V ≤ φ` where the obstacle is
    /// rigid, `V ≥ φ_low` where the body below is.
    pub fn project(&self, v: &mut [f64]) {
        if !self.is_extended() {
            if self.is_rigid() {
                for ((vi, fi), &c) in v.iter_mut().zip(&self.phi).zip(&self.can_touch) {
                    if c {
                        *vi = vi.min(*fi);
                    }
                }
            }
            return;
        }
        for (i, vi) in v.iter_mut().enumerate() {
            if self.can_touch[i] && self.rigid_at(i) {
                *vi = vi.min(self.phi[i]);
            }
            if let Some(low) = &self.lower {
                if low.can_touch[i] && low.rigid_at(i) {
                    *vi = vi.max(low.phi[i]);
                }
            }
        }
    }

    /// Scales the load f by `k` (D and ∫f; the lifting of the boundary heights stays).
    pub fn scale_load(&mut self, k: f64) {
        if self.lift.is_empty() {
            self.d.iter_mut().for_each(|v| *v *= k);
        } else {
            for (d, l) in self.d.iter_mut().zip(&self.lift) {
                *d = k * (*d + l) - l;
            }
        }
        self.total_load *= k;
    }

    /// Sets the tension to `t` (S and the lifting `S_fix G` scale with it).
    pub fn set_tension(&mut self, t: f64) {
        let k = t / self.tension;
        self.s.val.iter_mut().for_each(|v| *v *= k);
        for (d, l) in self.d.iter_mut().zip(self.lift.iter_mut()) {
            let scaled = k * *l;
            *d += *l - scaled;
            *l = scaled;
        }
        self.tension = t;
    }

    /// `r = S V − D`.
    pub fn residual(&self, v: &[f64]) -> Vec<f64> {
        let mut r = self.s.mul(v);
        r.par_iter_mut()
            .with_min_len(4096)
            .zip(&self.d)
            .for_each(|(ri, di)| *ri -= di);
        r
    }

    /// The vertex states: −1 clear (`U < φ`, or the vertex cannot touch), 0 touching
    /// (`U = φ`), 1 penetrating (`U > φ`).
    pub fn states(&self, u: &[f64]) -> Vec<i8> {
        u.par_iter()
            .with_min_len(4096)
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

    /// The vertex states toward the body below: −1 clear (`U > φ_low`, or the vertex
    /// cannot touch it), 0 touching (`U = φ_low`), 1 penetrating (`U < φ_low`); all −1
    /// without a body below.
    pub fn lower_states(&self, u: &[f64]) -> Vec<i8> {
        match &self.lower {
            None => vec![-1; u.len()],
            Some(low) => u
                .iter()
                .zip(&low.phi)
                .zip(&low.can_touch)
                .map(|((ui, fi), &c)| {
                    if !c || ui > fi {
                        -1
                    } else if ui == fi {
                        0
                    } else {
                        1
                    }
                })
                .collect(),
        }
    }

    /// A force scale of the data, `max(‖D‖∞, ‖Sφ‖∞, ‖L|φ|‖∞)` (and the same of the body
    /// below): the size of the forces the problem can involve, for scaling a formulation
    /// (the QP). Certificates are scaled by the forces of the iterate instead
    /// (docs/theory.md#certificates).
    pub fn force_scale(&self) -> f64 {
        let body_scale = |l: &FoundationMatrix, phi: &[f64]| {
            let sphi = norm_inf(&self.s.mul(phi));
            let abs_phi: Vec<f64> = phi.iter().map(|p| p.abs()).collect();
            let mut lphi = vec![0.0; self.n()];
            l.mul_into(&abs_phi, &mut lphi);
            sphi.max(norm_inf(&lphi))
        };
        let mut scale = norm_inf(&self.d).max(body_scale(&self.l, &self.phi));
        if let Some(low) = &self.lower {
            scale = scale.max(body_scale(&low.l, &low.phi));
        }
        scale.max(f64::MIN_POSITIVE)
    }
}
