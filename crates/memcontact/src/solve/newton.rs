//! The truncated Newton system of the smooth piece of J (Problems 2b/2f), the one home of
//! that formula for every solver: the active-set method factorises it, TNNMG solves it by a
//! multigrid cycle, the QP polish solves it with its own right-hand side.
//!
//! At an iterate V, the vertex states select a piece of J on which it is quadratic:
//! *truncated* vertices (`V_i = φ_i` on M: touching, or at the rigid obstacle) are held,
//! *penetrating* ones (`V_i > φ_i`, elastic obstacle) carry the foundation term. The
//! Hessian of the piece is `S + E_P L E_P` on the free vertices, its gradient
//! `g = SV − D + E_P L p` (`p = (V − φ)⁺`), zero on truncated vertices.
//!
//! With a body below (docs/theory.md#second-body) the vertices sunk into it (Q, elastic
//! there) add `E_Q L_low E_Q` to the Hessian and `− E_Q L_low q` (`q = (φ_low − V)⁺`) to
//! the gradient; vertices on either body's surface, or held by a rigid one, are truncated.

use crate::model::{FoundationMatrix, Model};
use crate::sparse::row_chunks;
use crate::sparse::{filled, zeroed, Csr, Pattern};
use crate::sparse::{par_rows, VECTOR_ROWS};
use rayon::prelude::*;

/// The states of the truncated Newton step at V: which vertices are held (touching, or at
/// a rigid body) and which penetrate the body above or the body below.
#[derive(Debug, Clone)]
pub struct NewtonStates {
    /// Held fixed on a kink: `V_i = φ_i` on M, or `V_i = φ_low,i` where the body below
    /// can touch.
    pub truncated: Vec<bool>,
    /// `V_i > φ_i` on M where the obstacle is elastic.
    pub penetrating: Vec<bool>,
    /// `V_i < φ_low,i` where the body below is elastic and can touch (empty without a body
    /// below).
    pub penetrating_low: Vec<bool>,
    /// Held on the body below (`V_i = φ_low,i`) rather than on φ (empty without a body
    /// below).
    pub at_lower: Vec<bool>,
}

impl NewtonStates {
    /// The states of V.
    pub fn of(model: &Model, v: &[f64]) -> NewtonStates {
        let mut st = NewtonStates::clear(model);
        st.update(model, v);
        st
    }

    /// Every vertex free and clear of both bodies.
    pub fn clear(model: &Model) -> NewtonStates {
        let n = model.n();
        let low = if model.lower.is_some() { n } else { 0 };
        NewtonStates {
            truncated: filled(n, false),
            penetrating: filled(n, false),
            penetrating_low: filled(low, false),
            at_lower: filled(low, false),
        }
    }

    /// `true` when vertex `i` penetrates the body below.
    #[inline]
    pub fn below(&self, i: usize) -> bool {
        !self.penetrating_low.is_empty() && self.penetrating_low[i]
    }

    /// Recomputes the states of V in place (no allocation).
    pub fn update(&mut self, model: &Model, v: &[f64]) {
        if !model.is_extended() {
            let rigid = model.is_rigid();
            let fill = |i: usize| -> (bool, bool) {
                if model.can_touch[i] {
                    (v[i] == model.phi[i], !rigid && v[i] > model.phi[i])
                } else {
                    (false, false)
                }
            };
            par_rows(&mut self.truncated, |i, t| *t = fill(i).0);
            par_rows(&mut self.penetrating, |i, p| *p = fill(i).1);
            return;
        }
        // Both bodies and rigid regions (docs/theory.md#extensions).
        let up_held = |i: usize| model.can_touch[i] && v[i] == model.phi[i];
        let low_held = |i: usize| {
            model
                .lower
                .as_ref()
                .is_some_and(|b| b.can_touch[i] && v[i] == b.phi[i])
        };
        par_rows(&mut self.truncated, |i, t| *t = up_held(i) || low_held(i));
        par_rows(&mut self.penetrating, |i, p| {
            *p = model.can_touch[i] && !model.rigid_at(i) && v[i] > model.phi[i]
        });
        if let Some(low) = &model.lower {
            par_rows(&mut self.penetrating_low, |i, p| {
                *p = low.can_touch[i] && !low.rigid_at(i) && v[i] < low.phi[i]
            });
            par_rows(&mut self.at_lower, |i, a| *a = low_held(i) && !up_held(i));
        }
    }
}

/// Rows per block of the parallel fill.
const CHUNK: usize = 1024;

/// The truncated Newton system at V for the states `st`: the Hessian of the piece,
/// `S + E_P L E_P`, into `a` (on the pattern of S) with the rows and columns of the
/// truncated vertices *zero* (they are decoupled; multigrid leaves zero rows alone, and
/// [`unit_diagonal_on_truncated`] makes the matrix definite for a factorisation), the
/// gradient of the piece `g = SV − D + E_P L p`, zero on truncated vertices, and
/// `r = SV − D`. One pass without allocation; only the matrix rows flagged in `rows` are
/// refilled when given (those whose states or whose neighbours' states changed, see
/// [`mark_dirty`]); `g` and `r` are always complete.
pub fn newton_system(
    model: &Model,
    v: &[f64],
    st: &NewtonStates,
    a: &mut Csr,
    rows: Option<&[bool]>,
    g: &mut [f64],
    r: &mut [f64],
) {
    newton_system_into(model, v, st, Hessian::Rows(a, rows), g, Some(r))
}

/// The truncated Newton matrix as TNNMG keeps it between iterations.
#[derive(Debug, Clone)]
pub enum NewtonMatrix {
    /// Assembled on the pattern of S (a consistent foundation couples neighbours).
    Assembled(Csr),
    /// When every body's foundation is lumped or rigid, the Hessian differs from S only on
    /// the diagonal and in the truncated rows and columns: the diagonal added to S alone,
    /// read with S as a [`Shifted`](super::multigrid::operator::Shifted) operator (one vector instead of a copy of S's values).
    Diagonal(Vec<f64>),
    /// The paper's model (no body below, no rigid regions) with a lumped foundation: the
    /// diagonal added to S is `l_i` on the penetrating unknowns, read from the model and
    /// the states ([`LumpedShifted`](super::multigrid::operator::LumpedShifted)); nothing
    /// is stored.
    Implicit,
}

impl NewtonMatrix {
    /// The form `model`'s Newton matrices take, zero.
    pub fn for_model(model: &Model) -> NewtonMatrix {
        let consistent = |l: &FoundationMatrix| matches!(l, FoundationMatrix::Consistent(_));
        if consistent(&model.l) || model.lower.as_ref().is_some_and(|b| consistent(&b.l)) {
            NewtonMatrix::Assembled(Csr::zeros(model.s.pattern.clone()))
        } else if !model.is_extended() && matches!(model.l, FoundationMatrix::Lumped(_)) {
            NewtonMatrix::Implicit
        } else {
            NewtonMatrix::Diagonal(zeroed(model.n()))
        }
    }

    /// [`newton_system`] into this matrix (a [`NewtonMatrix::Diagonal`] is always refilled
    /// whole: it is one vector).
    ///
    /// Without `r`, `SV − D` is not kept: the caller recomputes it where it needs it
    /// ([`crate::solve::line_search::line_data_at`]), one vector less.
    pub fn fill(
        &mut self,
        model: &Model,
        v: &[f64],
        st: &NewtonStates,
        rows: Option<&[bool]>,
        g: &mut [f64],
        r: Option<&mut [f64]>,
    ) {
        let target = match self {
            NewtonMatrix::Assembled(a) => Hessian::Rows(a, rows),
            NewtonMatrix::Diagonal(d) => Hessian::Diagonal(d),
            NewtonMatrix::Implicit => Hessian::None,
        };
        newton_system_into(model, v, st, target, g, r)
    }
}

/// Where [`newton_system_into`] puts the Hessian.
enum Hessian<'x> {
    /// Into a matrix on S's pattern, only the flagged rows when given.
    Rows(&'x mut Csr, Option<&'x [bool]>),
    /// The diagonal added to S (lumped and rigid foundations only), zero on truncated rows.
    Diagonal(&'x mut [f64]),
    /// Not stored (the gradient and `r` only).
    None,
}

/// [`newton_system`] into either form of the Hessian.
fn newton_system_into(
    model: &Model,
    v: &[f64],
    st: &NewtonStates,
    hessian: Hessian,
    g: &mut [f64],
    r: Option<&mut [f64]>,
) {
    if model.is_extended() {
        newton_system_with::<true>(model, v, st, hessian, g, r)
    } else {
        newton_system_with::<false>(model, v, st, hessian, g, r)
    }
}

/// [`newton_system_into`]; `EXT`: with the body below's terms `− E_Q L_low q` in the
/// gradient and `E_Q L_low E_Q` in the Hessian (`q = (φ_low − V)⁺`, Q its penetrating
/// vertices).
fn newton_system_with<const EXT: bool>(
    model: &Model,
    v: &[f64],
    st: &NewtonStates,
    hessian: Hessian,
    g: &mut [f64],
    r: Option<&mut [f64]>,
) {
    let pat = model.s.pattern.clone();
    let sval = &model.s.val;
    let lower = if EXT { model.lower.as_ref() } else { None };
    let pen = |j: usize| {
        if model.can_touch[j] {
            (v[j] - model.phi[j]).max(0.0)
        } else {
            0.0
        }
    };
    let gradient = |i: usize, gi: &mut f64, ri: &mut f64| {
        let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
        let cols = &pat.col[s..e];
        let mut sv = 0.0;
        for (&j, &sij) in cols.iter().zip(&sval[s..e]) {
            sv += sij * v[j as usize];
        }
        *ri = sv - model.d[i];
        *gi = if st.truncated[i] {
            0.0
        } else if st.penetrating[i] {
            *ri + match &model.l {
                FoundationMatrix::Consistent(l) => {
                    let mut lp = 0.0;
                    for (&j, &lij) in cols.iter().zip(&l.val[s..e]) {
                        lp += lij * pen(j as usize);
                    }
                    lp
                }
                FoundationMatrix::Lumped(d) => d[i] * pen(i),
                FoundationMatrix::Rigid => 0.0,
            }
        } else {
            *ri
        };
        if let Some(low) = lower {
            if !st.truncated[i] && st.below(i) {
                let q = |j: usize| {
                    if low.can_touch[j] {
                        (low.phi[j] - v[j]).max(0.0)
                    } else {
                        0.0
                    }
                };
                *gi -= match &low.l {
                    FoundationMatrix::Consistent(l) => {
                        let mut lq = 0.0;
                        for (&j, &lij) in cols.iter().zip(&l.val[s..e]) {
                            lq += lij * q(j as usize);
                        }
                        lq
                    }
                    FoundationMatrix::Lumped(d) => d[i] * q(i),
                    FoundationMatrix::Rigid => 0.0,
                };
            }
        }
    };
    // The diagonal added to S in row i (lumped and rigid foundations).
    let shift = |i: usize| -> f64 {
        if st.truncated[i] {
            return 0.0;
        }
        let mut d = if st.penetrating[i] {
            model.l.diag(i)
        } else {
            0.0
        };
        if let Some(low) = lower {
            if st.below(i) {
                d += low.l.diag(i);
            }
        }
        d
    };
    let matrix_row = |i: usize, arow: &mut [f64]| {
        let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
        let cols = &pat.col[s..e];
        for (k, &j) in cols.iter().enumerate() {
            let j = j as usize;
            arow[k] = if st.truncated[i] || st.truncated[j] {
                0.0
            } else if st.penetrating[i] && st.penetrating[j] {
                match &model.l {
                    FoundationMatrix::Consistent(l) => sval[s + k] + l.val[s + k],
                    FoundationMatrix::Lumped(d) if i == j => sval[s + k] + d[i],
                    _ => sval[s + k],
                }
            } else {
                sval[s + k]
            };
            if let Some(low) = lower {
                if !st.truncated[i] && !st.truncated[j] && st.below(i) && st.below(j) {
                    arow[k] += match &low.l {
                        FoundationMatrix::Consistent(l) => l.val[s + k],
                        FoundationMatrix::Lumped(d) if i == j => d[i],
                        _ => 0.0,
                    };
                }
            }
        }
    };
    // The chunks of `r`, or none of them when it is not kept.
    let n_chunks = v.len().div_ceil(CHUNK);
    let r_chunks = |r| chunks_or_none(r, n_chunks);
    let r_chunks_serial = |r| chunks_or_none_serial(r, n_chunks);
    // Row i's gradient into gi, and SV − D into the chunk's slot k when kept.
    let row_gradient = |i: usize, k: usize, gi: &mut f64, rc: &mut Option<&mut [f64]>| {
        let mut scratch = 0.0;
        let ri = match rc {
            Some(rc) => &mut rc[k],
            None => &mut scratch,
        };
        gradient(i, gi, ri);
    };
    let parallel = v.len() >= VECTOR_ROWS;
    match hessian {
        Hessian::Rows(a, rows) => {
            let blocks = row_chunks(&pat, &mut a.val, CHUNK);
            type Block<'a> = (
                (usize, &'a mut [f64]),
                (&'a mut [f64], Option<&'a mut [f64]>),
            );
            let work = |((start, vals), (gc, mut rc)): Block| {
                let mut off = 0;
                for (k, gi) in gc.iter_mut().enumerate() {
                    let i = start + k;
                    let len = pat.ptr(i + 1) - pat.ptr(i);
                    row_gradient(i, k, gi, &mut rc);
                    if rows.is_none_or(|d| d[i]) {
                        matrix_row(i, &mut vals[off..off + len]);
                    }
                    off += len;
                }
            };
            if parallel {
                blocks
                    .into_par_iter()
                    .zip(g.par_chunks_mut(CHUNK).zip(r_chunks(r)))
                    .for_each(work);
            } else {
                blocks
                    .into_iter()
                    .zip(g.chunks_mut(CHUNK).zip(r_chunks_serial(r)))
                    .for_each(work);
            }
        }
        Hessian::None => {
            type Block<'a> = (&'a mut [f64], Option<&'a mut [f64]>);
            let work = |(block, (gc, mut rc)): (usize, Block)| {
                for (k, gi) in gc.iter_mut().enumerate() {
                    row_gradient(block * CHUNK + k, k, gi, &mut rc);
                }
            };
            if parallel {
                g.par_chunks_mut(CHUNK)
                    .zip(r_chunks(r))
                    .enumerate()
                    .for_each(work);
            } else {
                g.chunks_mut(CHUNK)
                    .zip(r_chunks_serial(r))
                    .enumerate()
                    .for_each(work);
            }
        }
        Hessian::Diagonal(d) => {
            type Block<'a> = (&'a mut [f64], (&'a mut [f64], Option<&'a mut [f64]>));
            let work = |(block, (dc, (gc, mut rc))): (usize, Block)| {
                for (k, (di, gi)) in dc.iter_mut().zip(gc.iter_mut()).enumerate() {
                    let i = block * CHUNK + k;
                    row_gradient(i, k, gi, &mut rc);
                    *di = shift(i);
                }
            };
            if parallel {
                d.par_chunks_mut(CHUNK)
                    .zip(g.par_chunks_mut(CHUNK).zip(r_chunks(r)))
                    .enumerate()
                    .for_each(work);
            } else {
                d.chunks_mut(CHUNK)
                    .zip(g.chunks_mut(CHUNK).zip(r_chunks_serial(r)))
                    .enumerate()
                    .for_each(work);
            }
        }
    }
}

/// The `CHUNK`-row chunks of `r`, or `n_chunks` times `None` without it.
fn chunks_or_none(
    r: Option<&mut [f64]>,
    n_chunks: usize,
) -> impl IndexedParallelIterator<Item = Option<&mut [f64]>> {
    match r {
        Some(r) => rayon::iter::Either::Left(r.par_chunks_mut(CHUNK).map(Some)),
        None => rayon::iter::Either::Right((0..n_chunks).into_par_iter().map(|_| None)),
    }
}

/// [`chunks_or_none`], serially.
fn chunks_or_none_serial(
    r: Option<&mut [f64]>,
    n_chunks: usize,
) -> impl Iterator<Item = Option<&mut [f64]>> {
    match r {
        Some(r) => rayon::iter::Either::Left(r.chunks_mut(CHUNK).map(Some)),
        None => rayon::iter::Either::Right((0..n_chunks).map(|_| None)),
    }
}

/// Puts 1 on the diagonal of the truncated rows of a matrix filled by [`newton_system`], so
/// that it is positive definite (for a Cholesky factorisation); with `g = 0` there, the
/// truncated components of the Newton step are 0.
pub fn unit_diagonal_on_truncated(a: &mut Csr, st: &NewtonStates) {
    let pat = a.pattern.clone();
    for (i, _) in st.truncated.iter().enumerate().filter(|(_, &t)| t) {
        if let Some(k) = pat.find(i, i) {
            a.val[k] = 1.0;
        }
    }
}

/// The truncated Hessian alone, positive definite (unit diagonal on the truncated rows),
/// for callers that bring their own right-hand side (the QP polish).
pub fn truncated_hessian(model: &Model, st: &NewtonStates, a: &mut Csr) {
    let n = model.n();
    let (mut g, mut r) = (vec![0.0; n], vec![0.0; n]);
    newton_system(model, &model.phi, st, a, None, &mut g, &mut r);
    unit_diagonal_on_truncated(a, st);
}

/// Flags the rows of the truncated Hessian that differ between two state sets: a row
/// changes when its vertex or a neighbour changed state. Returns the number of dirty rows.
pub fn mark_dirty(
    pattern: &Pattern,
    old: &NewtonStates,
    new: &NewtonStates,
    changed: &mut [bool],
    dirty: &mut [bool],
) -> usize {
    par_rows(changed, |i, c| {
        *c = old.truncated[i] != new.truncated[i]
            || old.penetrating[i] != new.penetrating[i]
            || old.below(i) != new.below(i);
    });
    let changed: &[bool] = changed;
    par_rows(dirty, |i, d| {
        *d = pattern.col[pattern.ptr(i)..pattern.ptr(i + 1)]
            .iter()
            .any(|&j| changed[j as usize]);
    });
    dirty.iter().filter(|&&d| d).count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Foundation;
    use crate::solve::multigrid::tests::{bench_model, square_hierarchy};

    /// The Hessian and gradient of the piece, entry by entry from their definitions: J on
    /// the piece is `½VᵀSV − VᵀD + ½(V − φ)_Pᵀ L_PP (V − φ)_P` with the truncated
    /// coordinates fixed.
    #[test]
    #[allow(clippy::needless_range_loop)] // (i, j) index matrices and vectors alike
    fn system_is_the_hessian_and_gradient_of_the_piece() {
        let hier = square_hierarchy(4, 2);
        for (h, f) in [
            (Some(1000.0), Foundation::Consistent),
            (Some(1000.0), Foundation::Lumped),
            (None, Foundation::Lumped),
        ] {
            let model = bench_model(hier.finest(), h, f);
            let n = model.n();
            let mut v: Vec<f64> = (0..n)
                .map(|i| model.phi[i] + 0.05 * ((i as f64) * 0.7).sin())
                .collect();
            for i in (0..n).step_by(5) {
                v[i] = model.phi[i];
            }
            if h.is_none() {
                for (x, p) in v.iter_mut().zip(&model.phi) {
                    *x = x.min(*p);
                }
            }
            let st = NewtonStates::of(&model, &v);
            let mut a = Csr::zeros(model.s.pattern.clone());
            let (mut g, mut r) = (vec![0.0; n], vec![0.0; n]);
            newton_system(&model, &v, &st, &mut a, None, &mut g, &mut r);
            let lij = |i: usize, j: usize| match &model.l {
                FoundationMatrix::Consistent(l) => l.get(i, j),
                FoundationMatrix::Lumped(d) => {
                    if i == j {
                        d[i]
                    } else {
                        0.0
                    }
                }
                FoundationMatrix::Rigid => 0.0,
            };
            for i in 0..n {
                let mut ri = -model.d[i];
                let mut lp = 0.0;
                for j in 0..n {
                    ri += model.s.get(i, j) * v[j];
                    if st.penetrating[j] {
                        lp += lij(i, j) * (v[j] - model.phi[j]);
                    }
                }
                assert!((r[i] - ri).abs() < 1e-12, "r {i}");
                let gi = if st.truncated[i] {
                    0.0
                } else if st.penetrating[i] {
                    ri + lp
                } else {
                    ri
                };
                assert!((g[i] - gi).abs() < 1e-12, "g {i}");
                for j in 0..n {
                    let expect = if st.truncated[i] || st.truncated[j] {
                        0.0
                    } else if st.penetrating[i] && st.penetrating[j] {
                        model.s.get(i, j) + lij(i, j)
                    } else {
                        model.s.get(i, j)
                    };
                    assert_eq!(a.get(i, j), expect, "{f:?} ({i}, {j})");
                }
            }
            // Lumped and rigid foundations keep the diagonal added to S alone: read as an
            // operator, it is the assembled matrix entry by entry, with the same gradient.
            let mut m = NewtonMatrix::for_model(&model);
            let (mut g2, mut r2) = (vec![0.0; n], vec![0.0; n]);
            m.fill(&model, &v, &st, None, &mut g2, Some(&mut r2));
            assert_eq!((&g2, &r2), (&g, &r));
            // Without r: the same gradient.
            let mut g3 = vec![0.0; n];
            m.fill(&model, &v, &st, None, &mut g3, None);
            assert_eq!(g3, g);
            match (&m, f) {
                (NewtonMatrix::Assembled(b), Foundation::Consistent) => assert_eq!(b.val, a.val),
                (NewtonMatrix::Diagonal(d), Foundation::Lumped) => {
                    let op = crate::solve::multigrid::operator::Shifted {
                        s: &model.s,
                        shift: d,
                        held: &st.truncated,
                    };
                    let mut vals = vec![0.0; a.val.len()];
                    crate::solve::multigrid::operator::values_into(&op, &mut vals);
                    for (p, q) in vals.iter().zip(&a.val) {
                        assert!((p - q).abs() <= 1e-12 * q.abs(), "{p} against {q}");
                    }
                }
                (NewtonMatrix::Implicit, Foundation::Lumped) => {
                    let FoundationMatrix::Lumped(l) = &model.l else {
                        unreachable!()
                    };
                    let op = crate::solve::multigrid::operator::LumpedShifted {
                        s: &model.s,
                        l,
                        penetrating: &st.penetrating,
                        held: &st.truncated,
                    };
                    let mut vals = vec![0.0; a.val.len()];
                    crate::solve::multigrid::operator::values_into(&op, &mut vals);
                    for (p, q) in vals.iter().zip(&a.val) {
                        assert!((p - q).abs() <= 1e-12 * q.abs(), "{p} against {q}");
                    }
                }
                _ => panic!("{f:?}: the wrong form of the Newton matrix"),
            }
            // Only the flagged rows are refilled.
            let mut b = a.clone();
            b.val.iter_mut().for_each(|x| *x = -7.0);
            let rows: Vec<bool> = (0..n).map(|i| i % 3 == 0).collect();
            newton_system(&model, &v, &st, &mut b, Some(&rows), &mut g, &mut r);
            for i in 0..n {
                let (s, e) = (b.pattern.ptr(i), b.pattern.ptr(i + 1));
                if rows[i] {
                    assert_eq!(&b.val[s..e], &a.val[s..e]);
                } else {
                    assert!(b.val[s..e].iter().all(|&x| x == -7.0));
                }
            }
        }
    }
}
