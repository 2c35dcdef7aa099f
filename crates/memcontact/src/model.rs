//! The discrete model of SPEC §2 (the paper's §2): the stiffness matrix S, the h-weighted
//! foundation matrix L (consistent, or its lumped variant), the load D, the sampled
//! obstacle φₙ and the set M of vertices that can touch; the energy J of Problem 2b and the
//! certificates of Problems 2e and 2f.

pub use crate::certificate::Certificate;
use crate::error::{Error, Result};
use crate::fem::assemble_lift;
use crate::fem::{assemble_stiffness_and_mass, unknowns_pattern, Loads, VertexTriangles};
use crate::field::Coefficient;
use crate::mesh::boundary::FixedBoundary;
use crate::mesh::{DofMap, Mesh};
use crate::quadrature::gauss_legendre;
use crate::sparse::{norm_inf, Csr};
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

/// The data beyond the paper's frame (SPEC §5): boundary heights and free edges, rigid
/// regions of the obstacle (mixed bodies) and a second body below. The default is the
/// paper's frame: the whole boundary fixed at 0, one body, rigid everywhere or nowhere.
#[derive(Clone, Copy, Default)]
pub struct Extensions<'a> {
    /// Which boundary regions are free and the height g on the others (`None`: the whole
    /// boundary fixed at 0).
    pub boundary: Option<BoundaryData<'a>>,
    /// Region tags where the obstacle is rigid while elastic elsewhere (mixed bodies).
    pub rigid_regions: &'a [u32],
    /// The body below the membrane.
    pub lower: Option<BodyData<'a>>,
}

/// The boundary data of SPEC §5: `u = g` on the fixed part Γ_D, free elsewhere.
#[derive(Clone, Copy)]
pub struct BoundaryData<'a> {
    /// The boundary regions left free (names, or tags as text).
    pub free: &'a [String],
    /// The height g, evaluated at a boundary vertex with the tag of a fixed boundary edge
    /// through it (the average over those edges where they differ).
    pub height: &'a dyn Coefficient,
}

/// One body's data: surface, stiffness (with rigid regions), foundation matrix, sampling.
#[derive(Clone, Copy)]
pub struct BodyData<'a> {
    /// The body's surface.
    pub shape: &'a dyn Coefficient,
    /// Its stiffness.
    pub stiffness: Stiffness<'a>,
    /// Region tags where it is rigid while elastic elsewhere.
    pub rigid_regions: &'a [u32],
    /// Consistent or lumped.
    pub foundation: Foundation,
    /// How its surface is sampled.
    pub sampling: Sampling,
}

/// A second body (SPEC §5, the body below): its foundation term
/// `J₃(V) = ½ qᵀ L_low q`, `q = (φ_low − V)⁺`, or the constraint `U ≥ φ_low` where rigid.
#[derive(Debug, Clone)]
pub struct Body {
    /// `L_low` (consistent or lumped) or, wholly rigid, no matrix.
    pub l: FoundationMatrix,
    /// The sampled surface φ_low at the unknowns.
    pub phi: Vec<f64>,
    /// Unknowns the body can touch (`L_ii > 0`, or held rigidly).
    pub can_touch: Vec<bool>,
    /// Unknowns held rigidly when the body is rigid in some regions only.
    pub rigid: Option<Vec<bool>>,
    /// Which foundation was asked for.
    pub foundation: Foundation,
    /// φ_low at every vertex.
    pub phi_vertices: Vec<f64>,
    /// h_low at every vertex (∞ where rigid).
    pub h_vertices: Vec<f64>,
    /// The mollifier radius used, when φ_low was mollified.
    pub epsilon: Option<f64>,
}

impl Body {
    /// `true` when the body holds unknown `i` rigidly.
    #[inline]
    pub fn rigid_at(&self, i: usize) -> bool {
        self.l.is_rigid() || self.rigid.as_ref().is_some_and(|r| r[i])
    }

    /// `q = (φ_low − V)⁺` on the unknowns the body can touch (zero elsewhere).
    pub fn penetration(&self, v: &[f64]) -> Vec<f64> {
        v.par_iter()
            .with_min_len(4096)
            .zip(&self.phi)
            .zip(&self.can_touch)
            .map(|((vi, fi), &c)| if c { (fi - vi).max(0.0) } else { 0.0 })
            .collect()
    }
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
    /// Unknowns the obstacle holds rigidly (`U ≤ φ`) when it is rigid in some regions only
    /// (mixed bodies, SPEC §5); `None` when it is rigid everywhere (`l` says so) or nowhere.
    pub rigid: Option<Vec<bool>>,
    /// The body below the membrane (SPEC §5).
    pub lower: Option<Body>,
    /// u where it is prescribed (the heights g on Γ_D), 0 at the other vertices; over all
    /// vertices (empty when g = 0 everywhere, and for models that only a solver uses).
    pub boundary_values: Vec<f64>,
    /// The lifting `S_fix G` over the unknowns (empty when G = 0): `d` is the assembled
    /// load minus it (SPEC §5).
    pub lift: Vec<f64>,
}

impl Model {
    /// Assembles S, L, D, φₙ and M on `mesh` (SPEC §2), validating the data: t > 0,
    /// h ≥ 0, every value finite.
    pub fn assemble(mesh: &Mesh, data: &ProblemData) -> Result<Model> {
        Model::assemble_with(mesh, data, &Extensions::default())
    }

    /// [`Model::assemble`] with the data beyond the paper's frame (SPEC §5): boundary
    /// heights and free edges (the unknowns are then the vertices not on Γ_D and `d`
    /// carries the lifting `−S_fix G`), rigid regions of the obstacle, a body below.
    /// Refused here, before any solve: a boundary region that does not exist, a height
    /// that is not finite, a membrane that nothing holds (no fixed boundary and no body
    /// that can stop it), both bodies rigid with φ_low > φ at some unknown.
    pub fn assemble_with(mesh: &Mesh, data: &ProblemData, ext: &Extensions) -> Result<Model> {
        let (adj, boundary) = mesh.patches();
        Model::assemble_on(mesh, &adj, &boundary, data, ext)
    }

    /// [`Model::assemble_with`] given the mesh's vertex → triangles adjacency and its
    /// boundary vertices (computed once per run and shared with the checks).
    pub fn assemble_on(
        mesh: &Mesh,
        adj: &VertexTriangles,
        boundary: &[bool],
        data: &ProblemData,
        ext: &Extensions,
    ) -> Result<Model> {
        let t = data.tension;
        if !t.is_finite() || t <= 0.0 {
            return Err(Error::Data(format!(
                "membrane.tension must be a finite number > 0, got {t}"
            )));
        }
        let fixed = match &ext.boundary {
            Some(b) => Some(FixedBoundary::new(mesh, adj, b.free)?),
            None => None,
        };
        let dofs = match &fixed {
            Some(f) => DofMap::from_fixed(&f.fixed),
            None => DofMap::from_fixed(boundary),
        };
        if dofs.is_empty() {
            return Err(Error::Mesh(
                "the mesh has no interior vertex: there is no unknown to solve for".into(),
            ));
        }
        // The triangle areas, shared by every load-type integral below.
        let areas = mesh.areas();
        let loads = Loads::new(mesh, &dofs, adj, &areas);
        // Data checks: every value finite, h ≥ 0. f and h at the triangle centroids (their
        // quadrature), φ and h at the vertices (their samples).
        check_centroids(mesh, &loads, "membrane.load f", data.load, false)?;
        let upper = BodyData {
            shape: data.shape,
            stiffness: data.stiffness,
            rigid_regions: ext.rigid_regions,
            foundation: data.foundation,
            sampling: data.sampling,
        };
        let pattern = Arc::new(unknowns_pattern(mesh, &dofs, adj, boundary));
        // S and the upper body's consistent L share one pass over the rows.
        let masked = Masked::new(upper);
        let consistent_h = match (masked.elastic(), data.foundation) {
            (Some(h), Foundation::Consistent) => Some(h),
            _ => None,
        };
        let (s, l_consistent) =
            assemble_stiffness_and_mass(mesh, &dofs, adj, &pattern, t, consistent_h);
        let body = assemble_body(mesh, adj, &loads, &dofs, &upper, l_consistent, NAMES_UPPER)?;
        let load = data.load;
        let (mut d, total_load) = loads.vector_and_integral(load);
        if let Some(i) = crate::sparse::first_non_finite(&d) {
            let p = mesh.points[dofs.vertex[i] as usize];
            return Err(Error::Data(format!(
                "membrane.load f is not finite near ({}, {})",
                p[0], p[1]
            )));
        }
        // Boundary heights and the lifting S_fix G.
        let (boundary_values, lift) = match (&ext.boundary, &fixed) {
            (Some(b), Some(f)) => {
                let g = boundary_heights(mesh, f, b.height)?;
                if g.iter().any(|&x| x != 0.0) {
                    let lift = assemble_lift(mesh, &dofs, adj, t, &g);
                    (g, lift)
                } else {
                    (Vec::new(), Vec::new())
                }
            }
            _ => (Vec::new(), Vec::new()),
        };
        for (di, li) in d.iter_mut().zip(&lift) {
            *di -= li;
        }
        let lower = match &ext.lower {
            Some(low) => {
                let masked = Masked::new(*low);
                let l_consistent = match (masked.elastic(), low.foundation) {
                    (Some(h), Foundation::Consistent) => {
                        Some(assemble_mass(mesh, &dofs, adj, &pattern, h))
                    }
                    _ => None,
                };
                Some(assemble_body(
                    mesh,
                    adj,
                    &loads,
                    &dofs,
                    low,
                    l_consistent,
                    NAMES_LOWER,
                )?)
            }
            None => None,
        };
        let Body {
            l,
            phi,
            can_touch,
            rigid,
            foundation,
            phi_vertices,
            h_vertices,
            epsilon,
        } = body;
        let model = Model {
            dofs,
            tension: t,
            s,
            l,
            d,
            phi,
            can_touch,
            foundation,
            phi_vertices,
            h_vertices,
            total_load,
            epsilon,
            rigid,
            lower,
            boundary_values,
            lift,
        };
        if fixed.is_some() {
            model.check_held(mesh)?;
        }
        model.check_squeeze(mesh)?;
        Ok(model)
    }

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

    /// U over all vertices: the unknowns' values, and the heights g (0 by default) on the
    /// fixed boundary.
    pub fn to_vertices(&self, u: &[f64]) -> Vec<f64> {
        if self.boundary_values.len() != self.dofs.dof.len() {
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
    /// body below, SPEC §5); `+∞` outside the constraints of rigid bodies (`V ≤ φ` where
    /// the obstacle is rigid, `V ≥ φ_low` where the body below is).
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
    /// ([`crate::certificate`]).
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

    /// The optimality certificates of a candidate U (Problems 2e and 2f, scaled by the
    /// forces of U): see [`crate::certificate`].
    pub fn certificate(&self, u: &[f64]) -> Certificate {
        crate::certificate::evaluate(self, u).certificate
    }
}

/// `½ pᵀ L p` (0 for a rigid body).
fn foundation_energy(l: &FoundationMatrix, p: &[f64]) -> f64 {
    match l {
        FoundationMatrix::Consistent(l) => 0.5 * l.quad_form(p),
        FoundationMatrix::Lumped(d) => {
            0.5 * crate::sparse::sum_blocks(p.len(), |r| {
                p[r.clone()]
                    .iter()
                    .zip(&d[r])
                    .map(|(p, d)| d * p * p)
                    .sum::<f64>()
            })
        }
        FoundationMatrix::Rigid => 0.0,
    }
}

/// The names of one body's data in messages.
#[derive(Clone, Copy)]
struct BodyNames {
    stiffness: &'static str,
    shape: &'static str,
    epsilon: &'static str,
}

const NAMES_UPPER: BodyNames = BodyNames {
    stiffness: "obstacle.stiffness h",
    shape: "obstacle.shape φ",
    epsilon: "obstacle.epsilon",
};

const NAMES_LOWER: BodyNames = BodyNames {
    stiffness: "lower.stiffness h_low",
    shape: "lower.shape φ_low",
    epsilon: "lower.epsilon",
};

/// A body's elastic stiffness with its rigid regions masked to 0 (the elastic term is
/// integrated over the elastic triangles only, SPEC §5 "Mixed bodies").
struct Masked<'a> {
    inner: Option<&'a dyn Coefficient>,
    rigid: &'a [u32],
}

impl<'a> Masked<'a> {
    fn new(body: BodyData<'a>) -> Masked<'a> {
        Masked {
            inner: match body.stiffness {
                Stiffness::Elastic(h) => Some(h),
                Stiffness::Rigid => None,
            },
            rigid: body.rigid_regions,
        }
    }

    /// The coefficient to integrate (`None`: rigid everywhere). Without rigid regions it is
    /// the body's own coefficient, so that the paper's model is assembled as before.
    fn elastic(&self) -> Option<&dyn Coefficient> {
        let inner = self.inner?;
        if self.rigid.is_empty() {
            Some(inner)
        } else {
            Some(self)
        }
    }
}

impl Coefficient for Masked<'_> {
    fn at(&self, p: crate::mesh::Point, region: u32) -> f64 {
        if self.rigid.contains(&region) {
            0.0
        } else {
            self.inner.map_or(0.0, |h| h.at(p, region))
        }
    }
    fn on_region(&self, region: u32) -> Option<f64> {
        if self.rigid.contains(&region) {
            Some(0.0)
        } else {
            self.inner.and_then(|h| h.on_region(region))
        }
    }
}

/// Assembles one body (SPEC §2 for the obstacle, §5 for the body below and for mixed
/// bodies): its foundation matrix (`l_consistent` when the caller assembled it), its
/// sampled surface, the unknowns it can touch and those it holds rigidly, with the data
/// checks (h ≥ 0 and finite, φ finite).
fn assemble_body(
    mesh: &Mesh,
    adj: &VertexTriangles,
    loads: &Loads,
    dofs: &DofMap,
    data: &BodyData,
    l_consistent: Option<Csr>,
    names: BodyNames,
) -> Result<Body> {
    let masked = Masked::new(*data);
    // Vertices whose patch meets a rigid region (every vertex for a wholly rigid body).
    let rigid_vertex: Option<Vec<bool>> = match (data.stiffness, data.rigid_regions) {
        (Stiffness::Rigid, _) => None,
        (_, []) => None,
        (_, tags) => Some(
            (0..mesh.n_vertices())
                .map(|v| {
                    adj.of(v)
                        .iter()
                        .any(|&k| tags.contains(&mesh.regions[k as usize]))
                })
                .collect(),
        ),
    };
    let wholly_rigid = matches!(data.stiffness, Stiffness::Rigid)
        || (!data.rigid_regions.is_empty()
            && mesh.regions.iter().all(|r| data.rigid_regions.contains(r)));
    let h_vertices = match masked.elastic() {
        Some(h) if !wholly_rigid => {
            check_centroids(mesh, loads, names.stiffness, h, true)?;
            // One value everywhere: it was checked, and it is every vertex's average.
            let mut hv = match loads.uniform(h) {
                Some(v) => vec_of(mesh.n_vertices(), v),
                None => {
                    let hv = vertex_average(mesh, adj, h);
                    check_vertices(mesh, names.stiffness, &hv, true)?;
                    hv
                }
            };
            if let Some(r) = &rigid_vertex {
                for (h, &rv) in hv.iter_mut().zip(r) {
                    if rv {
                        *h = f64::INFINITY;
                    }
                }
            }
            hv
        }
        _ => vec_of(mesh.n_vertices(), f64::INFINITY),
    };
    let l = match (masked.elastic(), l_consistent) {
        _ if wholly_rigid => FoundationMatrix::Rigid,
        (_, Some(l)) => FoundationMatrix::Consistent(l),
        (Some(h), None) => FoundationMatrix::Lumped(loads.vector(h)),
        (None, None) => FoundationMatrix::Rigid,
    };
    let rigid: Option<Vec<bool>> = match (&rigid_vertex, wholly_rigid) {
        (Some(r), false) => {
            let on_unknowns: Vec<bool> = dofs.vertex.iter().map(|&v| r[v as usize]).collect();
            on_unknowns.iter().any(|&x| x).then_some(on_unknowns)
        }
        _ => None,
    };
    let can_touch: Vec<bool> = (0..dofs.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| l.is_rigid() || l.diag(i) > 0.0 || rigid.as_ref().is_some_and(|r| r[i]))
        .collect();
    let (phi_vertices, epsilon) = match data.sampling {
        Sampling::Nodal => (vertex_average(mesh, adj, data.shape), None),
        Sampling::Mollified { epsilon } => {
            let eps = match epsilon {
                Some(e) if e.is_finite() && e > 0.0 => e,
                Some(e) => {
                    return Err(Error::Data(format!(
                        "{} must be a finite number > 0, got {e}",
                        names.epsilon
                    )))
                }
                None => paper_epsilon(mesh),
            };
            (mollify(mesh, adj, data.shape, eps), Some(eps))
        }
    };
    check_vertices(mesh, names.shape, &phi_vertices, false)?;
    let phi = dofs.to_unknowns(&phi_vertices);
    Ok(Body {
        l,
        phi,
        can_touch,
        rigid,
        foundation: data.foundation,
        phi_vertices,
        h_vertices,
        epsilon,
    })
}

/// The consistent mass matrix `∫ h gᵢ gⱼ` alone, on the pattern of S.
fn assemble_mass(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    pattern: &Arc<crate::sparse::Pattern>,
    h: &dyn Coefficient,
) -> Csr {
    assemble_stiffness_and_mass(mesh, dofs, adj, pattern, 0.0, Some(h))
        .1
        .expect("a mass matrix was asked for")
}

/// Which vertices are fixed and their heights g (0 elsewhere), as the assembly with `ext`
/// takes them (SPEC §5).
pub fn fixed_heights(
    mesh: &Mesh,
    adj: &VertexTriangles,
    ext: &Extensions,
) -> Result<(Vec<bool>, Vec<f64>)> {
    fixed_heights_on(mesh, adj, &mesh.boundary_vertices_with(adj), ext)
}

/// [`fixed_heights`] given the boundary vertices of the mesh.
pub fn fixed_heights_on(
    mesh: &Mesh,
    adj: &VertexTriangles,
    boundary: &[bool],
    ext: &Extensions,
) -> Result<(Vec<bool>, Vec<f64>)> {
    match &ext.boundary {
        Some(b) => {
            let fixed = FixedBoundary::new(mesh, adj, b.free)?;
            let g = boundary_heights(mesh, &fixed, b.height)?;
            Ok((fixed.fixed, g))
        }
        None => Ok((boundary.to_vec(), vec![0.0; mesh.n_vertices()])),
    }
}

/// The heights g at the fixed vertices (SPEC §5), 0 elsewhere: at a vertex, g with the tag
/// of each fixed boundary edge through it, averaged over those edges (they differ only
/// where a table gives two sides different heights). A height that is not finite is an
/// error naming the point.
fn boundary_heights(
    mesh: &Mesh,
    fixed: &FixedBoundary,
    height: &dyn Coefficient,
) -> Result<Vec<f64>> {
    let nv = mesh.n_vertices();
    let mut sum = vec![0.0; nv];
    let mut count = vec![0u32; nv];
    for &([a, b], tag) in &fixed.edges {
        for v in [a as usize, b as usize] {
            let g = height
                .on_region(tag)
                .unwrap_or_else(|| height.at(mesh.points[v], tag));
            sum[v] += g;
            count[v] += 1;
        }
    }
    let g: Vec<f64> = sum
        .iter()
        .zip(&count)
        .map(|(&s, &c)| if c == 0 { 0.0 } else { s / c as f64 })
        .collect();
    if let Some(v) = g.iter().position(|x| !x.is_finite()) {
        return Err(bad_value("boundary.height g", g[v], mesh.points[v]));
    }
    Ok(g)
}

impl Model {
    /// Refuses a membrane that nothing holds (SPEC §5): every connected group of unknowns
    /// that no fixed vertex touches must be held by the bodies: by one from each side, or
    /// by one body toward which the net load on the group pushes. Otherwise J has no
    /// minimiser (or no unique one) and S is singular on the group.
    fn check_held(&self, mesh: &Mesh) -> Result<()> {
        let n = self.n();
        // Union-find over the couplings of S.
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(p: &mut [u32], mut i: u32) -> u32 {
            while p[i as usize] != i {
                p[i as usize] = p[p[i as usize] as usize];
                i = p[i as usize];
            }
            i
        }
        let pat = &self.s.pattern;
        for i in 0..n {
            for &j in &pat.col[pat.row_ptr[i]..pat.row_ptr[i + 1]] {
                let (a, b) = (find(&mut parent, i as u32), find(&mut parent, j));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
            }
        }
        // Unknowns next to a fixed vertex: a triangle of theirs has a fixed corner.
        let adj = VertexTriangles::new(mesh);
        #[derive(Clone, Copy, Default)]
        struct Group {
            anchored: bool,
            upper: bool,
            lower: bool,
            load: f64,
            first: u32,
            size: usize,
        }
        let mut groups = vec![Group::default(); n];
        for (i, &v) in self.dofs.vertex.iter().enumerate() {
            let anchored = adj.of(v as usize).iter().any(|&k| {
                mesh.triangles[k as usize]
                    .iter()
                    .any(|&w| self.dofs.dof[w as usize].is_none())
            });
            let r = find(&mut parent, i as u32) as usize;
            let g = &mut groups[r];
            if g.size == 0 {
                g.first = i as u32;
            }
            g.size += 1;
            g.anchored |= anchored;
            g.upper |= self.can_touch[i];
            g.lower |= self.lower.as_ref().is_some_and(|b| b.can_touch[i]);
            g.load += self.d[i];
        }
        for g in groups.iter().filter(|g| g.size > 0 && !g.anchored) {
            let held = (g.upper && (g.lower || g.load > 0.0)) || (g.lower && g.load < 0.0);
            if held {
                continue;
            }
            let p = mesh.points[self.dofs.vertex[g.first as usize] as usize];
            let why = if !g.upper && !g.lower {
                "no body can touch it".to_string()
            } else if g.upper {
                format!(
                    "only the obstacle above can touch it, and the net load on it ({:e}) does \
                     not push it up against the obstacle",
                    g.load
                )
            } else {
                format!(
                    "only the body below can touch it, and the net load on it ({:e}) does \
                     not push it down onto the body",
                    g.load
                )
            };
            return Err(Error::Data(format!(
                "the membrane is not held: {} vertices (one at ({}, {})) touch no fixed \
                 boundary and {why}, so it can move without bound; fix part of the boundary \
                 (boundary.free lists the free regions) or give it a body on each side",
                g.size, p[0], p[1]
            )));
        }
        Ok(())
    }

    /// Refuses two rigid bodies that overlap at an unknown (φ_low > φ there: no admissible
    /// deflection, SPEC §5), naming the vertices.
    fn check_squeeze(&self, mesh: &Mesh) -> Result<()> {
        let Some(low) = &self.lower else {
            return Ok(());
        };
        let bad: Vec<usize> = (0..self.n())
            .filter(|&i| self.rigid_at(i) && low.rigid_at(i) && low.phi[i] > self.phi[i])
            .collect();
        if bad.is_empty() {
            return Ok(());
        }
        let shown: Vec<String> = bad
            .iter()
            .take(5)
            .map(|&i| {
                let v = self.dofs.vertex[i] as usize;
                let p = mesh.points[v];
                format!(
                    "vertex {v} at ({}, {}): φ_low = {} > φ = {}",
                    p[0], p[1], low.phi[i], self.phi[i]
                )
            })
            .collect();
        let more = if bad.len() > 5 {
            format!(" and {} more", bad.len() - 5)
        } else {
            String::new()
        };
        Err(Error::Data(format!(
            "both bodies are rigid and overlap, so no deflection fits between them \
             (φ_low ≤ u ≤ φ is empty) at {} vertices: {}{more}",
            bad.len(),
            shown.join("; ")
        )))
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
/// (once per region where it is constant, once in all where it has one value everywhere).
fn check_centroids(
    mesh: &Mesh,
    loads: &Loads,
    name: &str,
    c: &dyn Coefficient,
    non_negative: bool,
) -> Result<()> {
    let bad = |v: f64| !v.is_finite() || (non_negative && v < 0.0);
    // One value everywhere: checked once (a bad one is named at the first centroid).
    if let Some(v) = loads.uniform(c) {
        if !bad(v) {
            return Ok(());
        }
    }
    let found = (0..mesh.n_triangles())
        .into_par_iter()
        .with_min_len(4096)
        .find_map_first(|k| {
            let r = mesh.regions[k];
            // The centroid only where c is not constant on the region (or to name a bad value).
            let centroid = || {
                let cs = mesh.corners(k);
                [
                    (cs[0][0] + cs[1][0] + cs[2][0]) / 3.0,
                    (cs[0][1] + cs[1][1] + cs[2][1]) / 3.0,
                ]
            };
            let v = c.on_region(r).unwrap_or_else(|| c.at(centroid(), r));
            bad(v).then(|| (v, centroid()))
        });
    match found {
        Some((v, p)) => Err(bad_value(name, v, p)),
        None => Ok(()),
    }
}

/// `n` copies of `v`, written on all threads.
fn vec_of(n: usize, v: f64) -> Vec<f64> {
    (0..n)
        .into_par_iter()
        .with_min_len(4096)
        .map(|_| v)
        .collect()
}

/// Checks sampled vertex values: finite, and non-negative when asked.
fn check_vertices(mesh: &Mesh, name: &str, values: &[f64], non_negative: bool) -> Result<()> {
    match crate::sparse::first_where(values, |v| !v.is_finite() | (non_negative & (v < 0.0))) {
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
        let c = crate::field::FnCoefficient(|p: crate::mesh::Point| 2.0 * p[0] - p[1] + 0.5);
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
