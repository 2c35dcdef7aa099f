//! Exact minimisation of J in one coordinate (SPEC §3) and the nonsmooth Gauss-Seidel sweep
//! built on it. With the other coordinates fixed, J as a function of `V_i = x` is
//!
//! `½ S_ii x² − b x + ½ L_ii p² + c p + const`, `p = (x − φ_i)⁺`,
//!
//! with `b = D_i − Σ_{j≠i} S_ij V_j` and `c = Σ_{j≠i} L_ij p_j ≥ 0`: a convex piecewise
//! quadratic with one kink at φ_i. Its minimiser is in closed form, and lands *exactly* on
//! φ_i (the touching state) when `S_ii φ_i − b ≤ 0 ≤ S_ii φ_i − b + c`.

use crate::model::{FoundationMatrix, Model};

/// The minimiser of the one-variable problem above. `lii = None` means the rigid obstacle
/// (`x ≤ φ_i`); `can_touch = false` removes the foundation term.
#[inline]
pub fn minimise_1d(sii: f64, b: f64, phi: f64, lii: Option<f64>, c: f64, can_touch: bool) -> f64 {
    let free = b / sii;
    if !can_touch {
        return free;
    }
    let Some(lii) = lii else {
        return free.min(phi);
    };
    let left = sii * phi - b;
    if left >= 0.0 {
        // The left piece's derivative is non-negative at the kink: the minimum is at or
        // left of φ_i.
        free.min(phi)
    } else if left + c <= 0.0 {
        // The right piece's derivative is non-positive at the kink: minimum at or right.
        ((b + lii * phi - c) / (sii + lii)).max(phi)
    } else {
        phi
    }
}

/// The one-variable problem of coordinate `i` at `v`: returns `(S_ii, b, L_ii, c)`.
#[inline]
pub fn local_problem(model: &Model, v: &[f64], i: usize) -> (f64, f64, Option<f64>, f64) {
    let (cols, svals) = model.s.row(i);
    let mut sii = 0.0;
    let mut sv = 0.0;
    match &model.l {
        FoundationMatrix::Consistent(l) => {
            // S and the consistent L share the pattern: one pass over the row.
            let lvals = &l.val[l.pattern.row_ptr[i]..l.pattern.row_ptr[i + 1]];
            let mut lii = 0.0;
            let mut c = 0.0;
            for ((&j, &s), &lv) in cols.iter().zip(svals).zip(lvals) {
                let j = j as usize;
                if j == i {
                    sii = s;
                    lii = lv;
                } else {
                    sv += s * v[j];
                    if lv != 0.0 && model.can_touch[j] {
                        c += lv * (v[j] - model.phi[j]).max(0.0);
                    }
                }
            }
            (sii, model.d[i] - sv, Some(lii), c)
        }
        other => {
            for (&j, &s) in cols.iter().zip(svals) {
                let j = j as usize;
                if j == i {
                    sii = s;
                } else {
                    sv += s * v[j];
                }
            }
            let lii = match other {
                FoundationMatrix::Lumped(d) => Some(d[i]),
                _ => None,
            };
            (sii, model.d[i] - sv, lii, 0.0)
        }
    }
}

/// Minimises J exactly in coordinate `i`, updating `v[i]`.
#[inline]
pub fn relax(model: &Model, v: &mut [f64], i: usize) {
    let (sii, b, lii, c) = local_problem(model, v, i);
    v[i] = minimise_1d(sii, b, model.phi[i], lii, c, model.can_touch[i]);
}

/// One forward nonsmooth Gauss-Seidel sweep: every coordinate minimised exactly, in order.
/// J never increases.
pub fn sweep_forward(model: &Model, v: &mut [f64]) {
    for i in 0..v.len() {
        relax(model, v, i);
    }
}

/// One backward sweep (the reverse order; forward + backward is a symmetric sweep).
pub fn sweep_backward(model: &Model, v: &mut [f64]) {
    for i in (0..v.len()).rev() {
        relax(model, v, i);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute-force minimiser of the 1-D function on a fine grid around the candidates.
    fn brute(sii: f64, b: f64, phi: f64, lii: f64, c: f64) -> f64 {
        let f = |x: f64| {
            let p = (x - phi).max(0.0);
            0.5 * sii * x * x - b * x + 0.5 * lii * p * p + c * p
        };
        let mut best = (f64::INFINITY, 0.0);
        let mut x = -5.0;
        while x <= 5.0 {
            let y = f(x);
            if y < best.0 {
                best = (y, x);
            }
            x += 1e-4;
        }
        best.1
    }

    #[test]
    fn closed_form_matches_brute_force() {
        let cases = [
            (2.0, 1.0, 0.0, 3.0, 0.0),  // free minimum right of the kink
            (2.0, -1.0, 0.0, 3.0, 0.0), // left of the kink
            (2.0, 1.0, 0.3, 3.0, 0.5),  // at the kink
            (1.0, 4.0, 0.5, 1.0, 0.2),  // right
            (1.0, 0.2, 0.5, 1.0, 2.0),  // left
        ];
        for (sii, b, phi, lii, c) in cases {
            let x = minimise_1d(sii, b, phi, Some(lii), c, true);
            assert!(
                (x - brute(sii, b, phi, lii, c)).abs() < 2e-4,
                "{sii} {b} {phi} {lii} {c}"
            );
        }
        // Exactly at the kink when the subdifferential contains 0.
        assert_eq!(minimise_1d(2.0, 1.0, 0.3, Some(3.0), 0.5, true), 0.3);
        // Rigid: projection onto x ≤ φ.
        assert_eq!(minimise_1d(2.0, 4.0, 1.0, None, 0.0, true), 1.0);
        assert_eq!(minimise_1d(2.0, 1.0, 1.0, None, 0.0, true), 0.5);
        // Cannot touch: plain quadratic.
        assert_eq!(minimise_1d(2.0, 4.0, 1.0, Some(1.0), 0.0, false), 2.0);
    }
}
