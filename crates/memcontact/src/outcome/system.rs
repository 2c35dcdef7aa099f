//! [`System`]: the assembled discrete problem of an outcome (docs/theory.md#discrete-model:
//! S, L, D, φₙ and the unknowns; docs/theory.md#second-body: the body below) over its
//! unknowns, in the user's vertex numbering, for callers that check or post-process the
//! answer themselves (the Python module's `Result.matrices()`).

use super::solved::Outcome;
use crate::model::FoundationMatrix;
use crate::sparse::Csr;

/// A sparse matrix over the unknowns in compressed rows: row `i` holds the columns
/// `col[row_ptr[i]..row_ptr[i + 1]]` (increasing) and their values `val[..]`.
#[derive(Debug, Clone, PartialEq)]
pub struct SparseRows {
    /// Row starts (one more than the rows).
    pub row_ptr: Vec<usize>,
    /// Column indices, increasing within each row.
    pub col: Vec<u32>,
    /// One value per entry.
    pub val: Vec<f64>,
}

/// The foundation term of a body over the unknowns.
#[derive(Debug, Clone, PartialEq)]
pub struct SystemBody {
    /// L (consistent, or the lumped diagonal stored as a diagonal matrix); `None` for a
    /// body that is rigid everywhere (no matrix: the constraint on `rigid`).
    pub l: Option<SparseRows>,
    /// `true` for the lumped foundation.
    pub lumped: bool,
    /// The sampled surface at the unknowns.
    pub phi: Vec<f64>,
    /// M: the unknowns the body can touch.
    pub can_touch: Vec<bool>,
    /// The unknowns the body holds rigidly (`U ≤ φ` for the obstacle, `U ≥ φ_low` for the
    /// body below): all of M for a rigid body, those next to its rigid regions for a mixed
    /// one, none for an elastic one.
    pub rigid: Vec<bool>,
}

/// The discrete problem of an outcome over its `m` unknowns (docs/theory.md#discrete-model,
/// docs/theory.md#extensions), numbered in the order of the user's vertices: unknown `k` is
/// the user's vertex `unknowns[k]` (increasing), whatever the renumbering for locality the
/// solver worked in. U minimises `J(V) = ½ VᵀSV − VᵀD + ½ pᵀLp (+ ½ qᵀ L_low q)`.
#[derive(Debug, Clone, PartialEq)]
pub struct System {
    /// The user's vertex of each unknown, increasing.
    pub unknowns: Vec<u32>,
    /// `S_ij = t ∫ ∇g_i·∇g_j`.
    pub s: SparseRows,
    /// `D`: the load `∫ f g_i` minus the lifting `S_fix G` of the boundary heights.
    pub d: Vec<f64>,
    /// The obstacle above: L, φ, M and its rigid unknowns.
    pub obstacle: SystemBody,
    /// The body below (docs/theory.md#second-body), when there is one.
    pub lower: Option<SystemBody>,
}

/// `a` renumbered: row and column `k` of the result are row and column `old[k]` of `a`
/// (`new[old[k]] = k`), columns sorted.
fn permuted(a: &Csr, old: Option<(&[u32], &[u32])>) -> SparseRows {
    let p = &a.pattern;
    let n = p.n();
    let Some((old, new)) = old else {
        return SparseRows {
            row_ptr: p.row_ptr.iter().map(|&x| x as usize).collect(),
            col: p.col.clone(),
            val: a.val.clone(),
        };
    };
    let mut row_ptr = Vec::with_capacity(n + 1);
    row_ptr.push(0);
    let mut col = Vec::with_capacity(p.nnz());
    let mut val = Vec::with_capacity(p.nnz());
    let mut row: Vec<(u32, f64)> = Vec::new();
    for &i in old {
        let i = i as usize;
        row.clear();
        row.extend((p.ptr(i)..p.ptr(i + 1)).map(|e| (new[p.col[e] as usize], a.val[e])));
        row.sort_unstable_by_key(|&(c, _)| c);
        col.extend(row.iter().map(|&(c, _)| c));
        val.extend(row.iter().map(|&(_, v)| v));
        row_ptr.push(col.len());
    }
    SparseRows { row_ptr, col, val }
}

/// `v` renumbered: entry `k` of the result is entry `old[k]` of `v`.
fn gathered<T: Copy>(v: &[T], old: Option<&[u32]>) -> Vec<T> {
    match old {
        Some(old) => old.iter().map(|&i| v[i as usize]).collect(),
        None => v.to_vec(),
    }
}

fn body(
    l: &FoundationMatrix,
    phi: &[f64],
    can_touch: &[bool],
    rigid: impl Fn(usize) -> bool,
    perm: Option<(&[u32], &[u32])>,
) -> SystemBody {
    let old = perm.map(|p| p.0);
    let n = phi.len();
    SystemBody {
        l: match l {
            FoundationMatrix::Consistent(l) => Some(permuted(l, perm)),
            FoundationMatrix::Lumped(d) => Some(SparseRows {
                row_ptr: (0..=n).collect(),
                col: (0..n as u32).collect(),
                val: gathered(d, old),
            }),
            FoundationMatrix::Rigid => None,
        },
        lumped: matches!(l, FoundationMatrix::Lumped(_)),
        phi: gathered(phi, old),
        can_touch: gathered(can_touch, old),
        rigid: gathered(
            &(0..n).map(|i| can_touch[i] && rigid(i)).collect::<Vec<_>>(),
            old,
        ),
    }
}

impl Outcome {
    /// The assembled discrete problem over the unknowns in the user's numbering
    /// ([`System`]). The model must still hold S (not a discretisation whose solver data
    /// were released after its one solve).
    pub fn system(&self) -> crate::error::Result<System> {
        let model = &self.discretization.model;
        let mesh = self.discretization.mesh();
        if model.s.pattern.n() != model.n() {
            return Err(crate::error::Error::Data(
                "the outcome's matrices were released after its solve".into(),
            ));
        }
        // The user's vertex of each unknown (the solver's unknowns follow its vertices).
        let user_vertex: Vec<u32> = match &mesh.numbering {
            Some(r) => model
                .dofs
                .vertex
                .iter()
                .map(|&v| r.vertices.old_of_new[v as usize])
                .collect(),
            None => model.dofs.vertex.clone(),
        };
        let sorted = user_vertex.windows(2).all(|w| w[0] < w[1]);
        let (old, new): (Vec<u32>, Vec<u32>) = if sorted {
            (Vec::new(), Vec::new())
        } else {
            let mut old: Vec<u32> = (0..user_vertex.len() as u32).collect();
            old.sort_unstable_by_key(|&i| user_vertex[i as usize]);
            let mut new = vec![0u32; old.len()];
            for (k, &i) in old.iter().enumerate() {
                new[i as usize] = k as u32;
            }
            (old, new)
        };
        let perm = (!sorted).then_some((old.as_slice(), new.as_slice()));
        let old = perm.map(|p| p.0);
        Ok(System {
            unknowns: gathered(&user_vertex, old),
            s: permuted(&model.s, perm),
            d: gathered(&model.d, old),
            obstacle: body(
                &model.l,
                &model.phi,
                &model.can_touch,
                |i| model.rigid_at(i),
                perm,
            ),
            lower: model
                .lower
                .as_ref()
                .map(|b| body(&b.l, &b.phi, &b.can_touch, |i| b.rigid_at(i), perm)),
        })
    }
}
