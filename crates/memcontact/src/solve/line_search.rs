//! Exact line search on J. Along a line `V + α δ`, J is convex and piecewise quadratic in
//! α, with breakpoints where some `V_i + α δ_i = φ_i`; its derivative is monotone and
//! piecewise linear. A bracketed Newton iteration on the derivative finds the exact
//! minimiser: once the predicted root lies in the same piece as the current point, it is
//! exact. Coordinates whose breakpoint is the chosen α are snapped exactly onto φ_i.

use crate::model::{FoundationMatrix, Model};
use rayon::prelude::*;

/// Below this many unknowns the reductions run serially.
const PAR: usize = 20_000;

/// The data of one line: `g0 = δᵀ(SV − D)` and `s2 = δᵀ S δ` (computed by the caller).
pub struct Line<'a> {
    /// The start V.
    pub v: &'a [f64],
    /// The direction δ.
    pub dir: &'a [f64],
    /// `δᵀ (S V − D)`.
    pub g0: f64,
    /// `δᵀ S δ`.
    pub s2: f64,
}

/// Derivative of the foundation term `Ψ(α) = ½ p(α)ᵀ L p(α)` at α, and its slope on the
/// piece to the right (`right = true`) or left of α.
fn foundation_derivative(model: &Model, line: &Line, alpha: f64, right: bool) -> (f64, f64) {
    let (v, d) = (line.v, line.dir);
    let active = |j: usize| -> bool {
        if !model.can_touch[j] {
            return false;
        }
        let x = v[j] + alpha * d[j] - model.phi[j];
        // On a breakpoint, the side decides: to the right, active iff moving up.
        x > 0.0 || (x == 0.0 && ((right && d[j] > 0.0) || (!right && d[j] < 0.0)))
    };
    let row = |i: usize| -> (f64, f64) {
        if d[i] == 0.0 || !active(i) {
            return (0.0, 0.0);
        }
        match &model.l {
            FoundationMatrix::Consistent(l) => {
                let (cols, vals) = l.row(i);
                let (mut lp, mut ld) = (0.0, 0.0);
                for (&j, &lv) in cols.iter().zip(vals) {
                    let j = j as usize;
                    if active(j) {
                        lp += lv * (v[j] + alpha * d[j] - model.phi[j]).max(0.0);
                        ld += lv * d[j];
                    }
                }
                (d[i] * lp, d[i] * ld)
            }
            FoundationMatrix::Lumped(l) => {
                let p = (v[i] + alpha * d[i] - model.phi[i]).max(0.0);
                (d[i] * l[i] * p, d[i] * l[i] * d[i])
            }
            FoundationMatrix::Rigid => (0.0, 0.0),
        }
    };
    let n = v.len();
    if n >= PAR {
        (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .map(row)
            .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
    } else {
        (0..n)
            .map(row)
            .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
    }
}

/// Is there a breakpoint strictly between `a` and `b`?
fn breakpoint_between(model: &Model, line: &Line, a: f64, b: f64) -> bool {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    line.v
        .iter()
        .zip(line.dir)
        .zip(&model.phi)
        .zip(&model.can_touch)
        .any(|(((&vi, &di), &fi), &c)| {
            if !c || di == 0.0 {
                return false;
            }
            let t = (fi - vi) / di;
            t > lo && t < hi
        })
}

/// The exact minimiser α ≥ 0 of `J(V + α δ)`; `None` if δ is not a descent direction.
/// For the rigid obstacle the step is also limited to stay feasible (`V ≤ φ` on M).
pub fn exact_step(model: &Model, line: &Line) -> Option<f64> {
    if line.s2.is_nan() || line.s2 <= 0.0 || !line.g0.is_finite() {
        return None;
    }
    if model.is_rigid() {
        if line.g0 >= 0.0 {
            return None;
        }
        let mut amax = f64::INFINITY;
        for i in 0..line.v.len() {
            if model.can_touch[i] && line.dir[i] > 0.0 {
                amax = amax.min((model.phi[i] - line.v[i]) / line.dir[i]);
            }
        }
        return Some((-line.g0 / line.s2).min(amax.max(0.0)));
    }
    let deriv = |alpha: f64, right: bool| -> (f64, f64) {
        let (f, fs) = foundation_derivative(model, line, alpha, right);
        (line.g0 + alpha * line.s2 + f, line.s2 + fs)
    };
    let (d0, _) = deriv(0.0, true);
    if d0 >= 0.0 {
        return None;
    }
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    let mut alpha = 1.0;
    for _ in 0..200 {
        let (dl, _) = deriv(alpha, false);
        let (dr, sr) = deriv(alpha, true);
        if dl <= 0.0 && dr >= 0.0 {
            return Some(alpha); // 0 is in the subdifferential: a kink minimum.
        }
        let (d, s) = if dr < 0.0 {
            lo = alpha;
            (dr, sr)
        } else {
            hi = alpha;
            let (_, sl) = deriv(alpha, false);
            (dl, sl)
        };
        let candidate = alpha - d / s;
        if !breakpoint_between(model, line, alpha, candidate) {
            // The derivative is linear between alpha and the candidate: exact root.
            return Some(candidate.max(0.0));
        }
        alpha = if candidate > lo && candidate < hi {
            candidate
        } else if hi.is_finite() {
            0.5 * (lo + hi)
        } else {
            2.0 * lo.max(1.0)
        };
    }
    Some(if hi.is_finite() { 0.5 * (lo + hi) } else { lo })
}

/// `v ← v + α δ`, snapping onto φ_i every coordinate of M whose breakpoint is α (up to
/// rounding), so that touching vertices are exactly touching.
pub fn apply_step(model: &Model, v: &mut [f64], dir: &[f64], alpha: f64) {
    for i in 0..v.len() {
        if dir[i] == 0.0 {
            continue;
        }
        let old = v[i];
        let new = old + alpha * dir[i];
        if model.can_touch[i] {
            let fi = model.phi[i];
            let t = (fi - old) / dir[i];
            let tol = 1e-12 * alpha.abs().max(1e-300);
            let hits =
                (t - alpha).abs() <= tol || (new - fi).abs() <= 1e-15 * fi.abs().max(old.abs());
            if hits && (old - fi) * dir[i] < 0.0 {
                v[i] = fi;
                continue;
            }
            if model.is_rigid() && new > fi {
                v[i] = fi;
                continue;
            }
        }
        v[i] = new;
    }
}
