//! The operator of a linear multigrid's top level, as its kernels read it: an assembled
//! matrix, or the truncated Newton matrix of TNNMG for lumped and rigid foundations
//! (Problem 2b), `E_F (S + diag(s)) E_F` with F the free unknowns, read from S itself.
//! That matrix differs from S only on the diagonal and in the held rows and columns, so
//! one vector replaces a second copy of S's values (a sixth of the solver's memory on
//! the benchmark square).

use crate::sparse::par_rows;
use crate::sparse::Csr;

/// A symmetric operator read row by row: the stored matrix's rows, a shift added to the
/// diagonal, and held unknowns whose rows and columns are zero.
///
/// The kernels take vectors that are zero on held unknowns (the multigrid cycle and FCG
/// keep them so), so that a held column contributes nothing without being looked at.
pub trait TopOperator: Sync {
    /// `true` for an assembled matrix (no shift, nothing held): the extra work of the
    /// kernels compiles away.
    const PLAIN: bool;
    /// The stored matrix: the operator itself when [`TopOperator::PLAIN`], else the one
    /// whose off-diagonal entries it shares.
    fn matrix(&self) -> &Csr;
    /// Added to the diagonal entry of free row `i`.
    fn shift(&self, i: usize) -> f64;
    /// Row and column `i` are zero.
    fn held(&self, i: usize) -> bool;
}

impl TopOperator for Csr {
    const PLAIN: bool = true;
    #[inline(always)]
    fn matrix(&self) -> &Csr {
        self
    }
    #[inline(always)]
    fn shift(&self, _: usize) -> f64 {
        0.0
    }
    #[inline(always)]
    fn held(&self, _: usize) -> bool {
        false
    }
}

/// `E_F (S + diag(shift)) E_F`, F the unknowns not `held`: the truncated Newton matrix of
/// a lumped or rigid foundation without a copy of S.
#[derive(Debug, Clone, Copy)]
pub struct Shifted<'a> {
    /// S (the stiffness matrix).
    pub s: &'a Csr,
    /// The diagonal added to S (the penetrated bodies' lumped l).
    pub shift: &'a [f64],
    /// The truncated unknowns.
    pub held: &'a [bool],
}

impl TopOperator for Shifted<'_> {
    const PLAIN: bool = false;
    #[inline(always)]
    fn matrix(&self) -> &Csr {
        self.s
    }
    #[inline(always)]
    fn shift(&self, i: usize) -> f64 {
        self.shift[i]
    }
    #[inline(always)]
    fn held(&self, i: usize) -> bool {
        self.held[i]
    }
}

/// [`Shifted`] for the paper's model with a lumped foundation, its shift read from the
/// model's lumped `l` and the penetrating flags instead of a stored vector:
/// `shift_i = l_i` on penetrating unknowns, 0 elsewhere (a penetrating unknown is never
/// held). The same values as the stored shift, without its vector (8 bytes per unknown).
#[derive(Debug, Clone, Copy)]
pub struct LumpedShifted<'a> {
    /// S (the stiffness matrix).
    pub s: &'a Csr,
    /// The lumped foundation's diagonal.
    pub l: &'a [f64],
    /// The penetrating unknowns (`V_i > φ_i` on M).
    pub penetrating: &'a [bool],
    /// The truncated unknowns.
    pub held: &'a [bool],
}

impl TopOperator for LumpedShifted<'_> {
    const PLAIN: bool = false;
    #[inline(always)]
    fn matrix(&self) -> &Csr {
        self.s
    }
    #[inline(always)]
    fn shift(&self, i: usize) -> f64 {
        if self.penetrating[i] {
            self.l[i]
        } else {
            0.0
        }
    }
    #[inline(always)]
    fn held(&self, i: usize) -> bool {
        self.held[i]
    }
}

/// The operator's entry `(i, j)` whose stored value is `v`.
#[inline(always)]
pub(crate) fn entry<A: TopOperator>(a: &A, i: usize, j: usize, v: f64) -> f64 {
    if A::PLAIN {
        v
    } else if a.held(i) || a.held(j) {
        0.0
    } else if i == j {
        v + a.shift(i)
    } else {
        v
    }
}

/// `y = A x` for `x` zero on the held unknowns (parallel for large operators; every row
/// is summed in the same order whatever the thread count).
pub fn apply<A: TopOperator>(a: &A, x: &[f64], y: &mut [f64]) {
    let m = a.matrix();
    par_rows(y, |i, yi| {
        *yi = if !A::PLAIN && a.held(i) {
            0.0
        } else {
            let ax = m.row_dot(i, x);
            if A::PLAIN {
                ax
            } else {
                ax + a.shift(i) * x[i]
            }
        };
    });
}

/// Sets the held entries of `x` to zero (nothing for an assembled matrix).
pub fn zero_held<A: TopOperator>(a: &A, x: &mut [f64]) {
    if !A::PLAIN {
        par_rows(x, |i, v| {
            if a.held(i) {
                *v = 0.0;
            }
        });
    }
}

/// The operator's values on the stored matrix's pattern, into `out`.
pub fn values_into<A: TopOperator>(a: &A, out: &mut [f64]) {
    let m = a.matrix();
    let pat = &m.pattern;
    for i in 0..pat.n() {
        let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
        for ((o, &j), &v) in out[s..e].iter_mut().zip(&pat.col[s..e]).zip(&m.val[s..e]) {
            *o = entry(a, i, j as usize, v);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::Pattern;
    use std::sync::Arc;

    /// The 1D Laplacian on `n` unknowns.
    fn laplacian(n: usize) -> Csr {
        let mut row_ptr = vec![0];
        let mut col = Vec::new();
        let mut val = Vec::new();
        for i in 0..n {
            for j in i.saturating_sub(1)..(i + 2).min(n) {
                col.push(j as u32);
                val.push(if i == j { 2.0 } else { -1.0 });
            }
            row_ptr.push(col.len() as u32);
        }
        Csr {
            pattern: Arc::new(Pattern { row_ptr, col }),
            val,
        }
    }

    /// The shifted operator is the assembled truncated matrix, entry by entry and in its
    /// product.
    #[test]
    fn shifted_operator_is_the_truncated_matrix() {
        let n = 40;
        let s = laplacian(n);
        let shift: Vec<f64> = (0..n).map(|i| (i % 3) as f64 * 0.5).collect();
        let held: Vec<bool> = (0..n).map(|i| i % 7 == 2).collect();
        let op = Shifted {
            s: &s,
            shift: &shift,
            held: &held,
        };
        let mut vals = vec![0.0; s.val.len()];
        values_into(&op, &mut vals);
        let a = Csr {
            pattern: s.pattern.clone(),
            val: vals,
        };
        for i in 0..n {
            for j in 0..n {
                let expect = if held[i] || held[j] {
                    0.0
                } else {
                    s.get(i, j) + if i == j { shift[i] } else { 0.0 }
                };
                assert_eq!(a.get(i, j), expect, "({i}, {j})");
            }
        }
        let mut x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        zero_held(&op, &mut x);
        assert!(x.iter().zip(&held).all(|(&v, &h)| !h || v == 0.0));
        let mut y = vec![0.0; n];
        apply(&op, &x, &mut y);
        let y_ref = a.mul(&x);
        for (p, q) in y.iter().zip(&y_ref) {
            assert!((p - q).abs() <= 1e-15 * q.abs().max(1.0));
        }
    }
}
