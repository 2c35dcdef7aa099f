//! A body the membrane can touch, as assembled: its foundation matrix (consistent L,
//! lumped diagonal, or rigid), sampled surface and the unknowns it can touch.

use super::data::Foundation;
use crate::mesh::DofMap;
use crate::sparse::Csr;
use rayon::prelude::*;

/// A second body (the body below, docs/theory.md#second-body): its foundation term
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
    /// φ_low at the vertices that carry no unknown, `(vertex, value)` (at the unknowns it
    /// is `phi`): with `phi`, φ_low at every vertex ([`Body::phi_vertices`]).
    pub phi_fixed: Vec<(u32, f64)>,
    /// h_low at every vertex (∞ where rigid).
    pub h_vertices: VertexValues,
    /// The mollifier radius used, when φ_low was mollified.
    pub epsilon: Option<f64>,
}

impl Body {
    /// `true` when the body holds unknown `i` rigidly.
    #[inline]
    pub fn rigid_at(&self, i: usize) -> bool {
        self.l.is_rigid() || self.rigid.as_ref().is_some_and(|r| r[i])
    }

    /// φ_low at every vertex of the mesh of `dofs` (the body's own model's unknowns).
    pub fn phi_vertices(&self, dofs: &DofMap) -> Vec<f64> {
        with_fixed(dofs.to_vertices(&self.phi, 0.0), &self.phi_fixed)
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

/// `at_vertices` with the values `fixed` put in at their vertices.
pub(crate) fn with_fixed(mut at_vertices: Vec<f64>, fixed: &[(u32, f64)]) -> Vec<f64> {
    for &(v, x) in fixed {
        at_vertices[v as usize] = x;
    }
    at_vertices
}

/// The values of the vertices that carry no unknown (`dof[v]` is `None`), in vertex order.
pub(crate) fn fixed_values(dofs: &DofMap, at_vertices: &[f64]) -> Vec<(u32, f64)> {
    dofs.per_vertex()
        .zip(at_vertices)
        .enumerate()
        .filter(|(_, (d, _))| d.is_none())
        .map(|(v, (_, &x))| (v as u32, x))
        .collect()
}

/// Values at the mesh vertices that a model keeps for its outputs only (h at the
/// vertices): one number when they are all the same (a uniform stiffness), one per vertex
/// otherwise.
#[derive(Debug, Clone, PartialEq)]
pub enum VertexValues {
    /// `value` at every one of `n` vertices.
    Uniform {
        /// The value.
        value: f64,
        /// The number of vertices.
        n: usize,
    },
    /// One value per vertex.
    Each(Vec<f64>),
}

impl VertexValues {
    /// `values`, as one number when they are all the same.
    pub fn from_values(values: Vec<f64>) -> VertexValues {
        match values.first() {
            Some(&x) if values.par_iter().all(|&y| y.to_bits() == x.to_bits()) => {
                VertexValues::Uniform {
                    value: x,
                    n: values.len(),
                }
            }
            _ => VertexValues::Each(values),
        }
    }

    /// The number of vertices.
    pub fn len(&self) -> usize {
        match self {
            VertexValues::Uniform { n, .. } => *n,
            VertexValues::Each(v) => v.len(),
        }
    }

    /// `true` for no vertex.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The value at vertex `v`.
    #[inline]
    pub fn get(&self, v: usize) -> f64 {
        match self {
            VertexValues::Uniform { value, .. } => *value,
            VertexValues::Each(x) => x[v],
        }
    }

    /// The values, one per vertex.
    pub fn to_vec(&self) -> Vec<f64> {
        match self {
            VertexValues::Uniform { value, n } => vec![*value; *n],
            VertexValues::Each(x) => x.clone(),
        }
    }

    /// Every value replaced by `f` of it.
    pub fn map(&mut self, f: impl Fn(f64) -> f64 + Sync) {
        match self {
            VertexValues::Uniform { value, .. } => *value = f(*value),
            VertexValues::Each(x) => x.par_iter_mut().for_each(|v| *v = f(*v)),
        }
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

/// `½ pᵀ L p` (0 for a rigid body).
pub(super) fn foundation_energy(l: &FoundationMatrix, p: &[f64]) -> f64 {
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
