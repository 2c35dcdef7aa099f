//! The exact line search on J (Problem 2b), `min_α≥0 J(V + αδ)`, in few passes over the
//! data: the one line search of every solver (active set, TNNMG).
//!
//! Along the line, J is convex and piecewise quadratic, with breakpoints `t_i` where
//! `V_i + t_i δ_i = φ_i`. On a piece (a fixed set A of penetrating vertices) the
//! derivative is linear,
//!
//! `J'(α) = g₀ + α s₂ + a + α b`, `a = δ_Aᵀ L_AA w_A`, `b = δ_Aᵀ L_AA δ_A`, `w = V − φ`,
//!
//! (`g₀ = δᵀ(SV − D)`, `s₂ = δᵀSδ`), so its root on the piece is exact. One pass at a
//! point α yields the data of the pieces on both sides of α *and* the nearest breakpoints
//! on either side, so it tells at once whether the Newton root lies in the current piece
//! (it is then the exact minimiser), or whether α is a kink minimiser (`J'(α−) ≤ 0 ≤
//! J'(α+)`); otherwise a bracketed Newton step on the monotone derivative moves on.
//! [`apply_step`] takes the step and snaps the coordinates whose breakpoint it is onto φ.
//!
//! A body below (docs/theory.md#second-body) adds the same terms for `J₃ = ½ qᵀ L_low q`,
//! `q = (φ_low − V)⁺`: it is J₂ of the mirrored problem (gap `φ_low − V`, direction `−δ`),
//! so one function computes the pieces of either body. Where a body is rigid the step is
//! limited so that `V + αδ` keeps its constraint.

use crate::model::{FoundationMatrix, Model};
use crate::sparse::{par_rows, VECTOR_ROWS};
use rayon::prelude::*;

/// Rows per block of the deterministic reductions.
const BLOCK: usize = 4096;

/// `(g₀, s₂) = (δᵀ r, δᵀ S δ)`, summed in fixed blocks.
pub fn line_data(model: &Model, dir: &[f64], r: &[f64]) -> (f64, f64) {
    let s = &model.s;
    let block = |b: usize| -> [f64; 2] {
        let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(dir.len()));
        let mut acc = [0.0; 2];
        for i in lo..hi {
            if dir[i] != 0.0 {
                acc[0] += dir[i] * r[i];
                acc[1] += dir[i] * s.row_dot(i, dir);
            }
        }
        acc
    };
    let [g0, s2] = reduce(dir.len(), block, |a, b| [a[0] + b[0], a[1] + b[1]]);
    (g0, s2)
}

/// [`line_data`] with `r = SV − D` computed on the way from the iterate `v` instead of
/// read from a vector (the same values as [`crate::solve::newton::newton_system`]'s `r`,
/// summed in the same order): S's rows are read once for both products.
pub fn line_data_at(model: &Model, dir: &[f64], v: &[f64]) -> (f64, f64) {
    let s = &model.s;
    let pat = &s.pattern;
    let block = |b: usize| -> [f64; 2] {
        let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(dir.len()));
        let mut acc = [0.0; 2];
        for i in lo..hi {
            if dir[i] != 0.0 {
                let (cols, vals) = (pat.cols(i), &s.val[pat.ptr(i)..pat.ptr(i + 1)]);
                let (mut sv, mut sd) = (0.0, 0.0);
                for (&j, &sij) in cols.iter().zip(vals) {
                    sv += sij * v[j as usize];
                    sd += sij * dir[j as usize];
                }
                acc[0] += dir[i] * (sv - model.d[i]);
                acc[1] += dir[i] * sd;
            }
        }
        acc
    };
    let [g0, s2] = reduce(dir.len(), block, |a, b| [a[0] + b[0], a[1] + b[1]]);
    (g0, s2)
}

/// Runs `block` over the fixed blocks of `0..n` (in parallel for large n) and folds the
/// results in block order.
fn reduce<T: Send + Copy>(
    n: usize,
    block: impl Fn(usize) -> T + Sync + Send,
    fold: impl Fn(T, T) -> T,
) -> T {
    let nb = n.div_ceil(BLOCK).max(1);
    let parts: Vec<T> = if n >= VECTOR_ROWS {
        (0..nb).into_par_iter().map(block).collect()
    } else {
        (0..nb).map(block).collect()
    };
    let mut it = parts.into_iter();
    let first = it.next().expect("at least one block");
    it.fold(first, fold)
}

/// What one pass at α reveals: the foundation term's derivative data on the pieces left
/// and right of α, and the nearest breakpoints strictly below and above α.
#[derive(Clone, Copy)]
struct Pieces {
    /// `(a, b)` of the left piece.
    left: (f64, f64),
    /// `(a, b)` of the right piece.
    right: (f64, f64),
    /// Largest breakpoint `< α` (−∞ if none).
    below: f64,
    /// Smallest breakpoint `> α` (+∞ if none).
    above: f64,
}

fn merge(p: Pieces, q: Pieces) -> Pieces {
    Pieces {
        left: (p.left.0 + q.left.0, p.left.1 + q.left.1),
        right: (p.right.0 + q.right.0, p.right.1 + q.right.1),
        below: p.below.max(q.below),
        above: p.above.min(q.above),
    }
}

/// Penetrating on the left (bit 0) and right (bit 1) piece of α, for a body whose gap at
/// step α is `w + α d` (penetrating where positive).
#[inline]
fn side_code(w: f64, d: f64, alpha: f64) -> u8 {
    let x = w + alpha * d;
    if x > 0.0 {
        3
    } else if x < 0.0 {
        0
    } else {
        u8::from(d < 0.0) | (u8::from(d > 0.0) << 1)
    }
}

/// One body along the line: its foundation term, the unknowns whose elastic term is present
/// (`touch` and not held rigidly), and its gap `w_j + α d_j`: `w = V − φ`, `d = δ` above,
/// `w = φ_low − V`, `d = −δ` below (docs/theory.md#second-body: J₃ is J₂ of the mirrored
/// problem).
struct LineBody<'a, E, W, D> {
    l: &'a FoundationMatrix,
    elastic: E,
    w: W,
    d: D,
}

/// One pass at α over one body. For the consistent L, `codes` receives the side codes of
/// every vertex first (one light pass), so that the rows of L read them instead of
/// recomputing them for every neighbour.
fn body_pieces<E, W, D>(body: &LineBody<E, W, D>, n: usize, alpha: f64, codes: &mut [u8]) -> Pieces
where
    E: Fn(usize) -> bool + Sync,
    W: Fn(usize) -> f64 + Sync,
    D: Fn(usize) -> f64 + Sync,
{
    let (w, dir) = (&body.w, &body.d);
    let code = |j: usize| {
        if !(body.elastic)(j) {
            return 0;
        }
        side_code(w(j), dir(j), alpha)
    };
    let consistent = matches!(body.l, FoundationMatrix::Consistent(_));
    if consistent {
        par_rows(codes, |j, c| *c = code(j));
    }
    let codes: &[u8] = codes;
    let side = |j: usize| -> (bool, bool) {
        let c = if consistent { codes[j] } else { code(j) };
        (c & 1 != 0, c & 2 != 0)
    };
    let block = |b: usize| -> Pieces {
        let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(n));
        let mut acc = Pieces {
            left: (0.0, 0.0),
            right: (0.0, 0.0),
            below: f64::NEG_INFINITY,
            above: f64::INFINITY,
        };
        for i in lo..hi {
            let d = dir(i);
            if d == 0.0 || !(body.elastic)(i) {
                continue;
            }
            let t = -w(i) / d;
            if t < alpha {
                acc.below = acc.below.max(t);
            } else if t > alpha {
                acc.above = acc.above.min(t);
            }
            let (li, ri) = side(i);
            if !li && !ri {
                continue;
            }
            match body.l {
                FoundationMatrix::Lumped(l) => {
                    let (a, b) = (d * l[i] * w(i), d * l[i] * d);
                    if li {
                        acc.left.0 += a;
                        acc.left.1 += b;
                    }
                    if ri {
                        acc.right.0 += a;
                        acc.right.1 += b;
                    }
                }
                FoundationMatrix::Consistent(l) => {
                    let (cols, vals) = l.row(i);
                    let (mut al, mut bl, mut ar, mut br) = (0.0, 0.0, 0.0, 0.0);
                    for (&j, &lv) in cols.iter().zip(vals) {
                        if lv == 0.0 {
                            continue;
                        }
                        let j = j as usize;
                        let (lj, rj) = side(j);
                        if lj {
                            al += lv * w(j);
                            bl += lv * dir(j);
                        }
                        if rj {
                            ar += lv * w(j);
                            br += lv * dir(j);
                        }
                    }
                    if li {
                        acc.left.0 += d * al;
                        acc.left.1 += d * bl;
                    }
                    if ri {
                        acc.right.0 += d * ar;
                        acc.right.1 += d * br;
                    }
                }
                FoundationMatrix::Rigid => {}
            }
        }
        acc
    };
    reduce(n, block, merge)
}

/// The foundation pieces at α of every elastic body: the obstacle's, and the body below's
/// (`codes_low` its side codes).
fn pieces(
    model: &Model,
    v: &[f64],
    dir: &[f64],
    alpha: f64,
    codes: &mut [u8],
    codes_low: &mut [u8],
) -> Pieces {
    let n = v.len();
    if !model.is_extended() {
        let up = LineBody {
            l: &model.l,
            elastic: |j: usize| model.can_touch[j],
            w: |j: usize| v[j] - model.phi[j],
            d: |j: usize| dir[j],
        };
        return body_pieces(&up, n, alpha, codes);
    }
    let up = LineBody {
        l: &model.l,
        elastic: |j: usize| model.can_touch[j] && !model.rigid_at(j),
        w: |j: usize| v[j] - model.phi[j],
        d: |j: usize| dir[j],
    };
    let mut p = body_pieces(&up, n, alpha, codes);
    if let Some(low) = &model.lower {
        let down = LineBody {
            l: &low.l,
            elastic: |j: usize| low.can_touch[j] && !low.rigid_at(j),
            w: |j: usize| low.phi[j] - v[j],
            d: |j: usize| -dir[j],
        };
        p = merge(p, body_pieces(&down, n, alpha, codes_low));
    }
    p
}

/// The largest step the rigid bodies allow: `V + αδ ≤ φ` where the obstacle is rigid,
/// `≥ φ_low` where the body below is (∞ without rigid parts).
fn rigid_limit(model: &Model, v: &[f64], dir: &[f64]) -> f64 {
    let block = |b: usize| -> f64 {
        let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(v.len()));
        let mut m = f64::INFINITY;
        for i in lo..hi {
            if model.can_touch[i] && dir[i] > 0.0 && model.rigid_at(i) {
                m = m.min((model.phi[i] - v[i]) / dir[i]);
            }
            if let Some(low) = &model.lower {
                if low.can_touch[i] && dir[i] < 0.0 && low.rigid_at(i) {
                    m = m.min((low.phi[i] - v[i]) / dir[i]);
                }
            }
        }
        m
    };
    reduce(v.len(), block, f64::min)
}

/// The exact minimiser α ≥ 0 of `J(V + αδ)` given `g₀ = δᵀ(SV − D)` and `s₂ = δᵀSδ`;
/// `None` when δ is not a descent direction. Where a body is rigid the step is limited so
/// that `V + αδ` stays between them (`≤ φ`, `≥ φ_low`).
pub fn exact_step(model: &Model, v: &[f64], dir: &[f64], g0: f64, s2: f64) -> Option<f64> {
    if s2.is_nan() || s2 <= 0.0 || !g0.is_finite() {
        return None;
    }
    let no_elastic = model.is_rigid()
        && model
            .lower
            .as_ref()
            .is_none_or(|b| b.l.is_rigid() || !b.can_touch.iter().any(|&c| c));
    if no_elastic {
        // J is quadratic along the line until a rigid body stops it.
        if g0 >= 0.0 {
            return None;
        }
        let amax = rigid_limit(model, v, dir);
        return Some((-g0 / s2).min(amax.max(0.0))).filter(|a| *a > 0.0);
    }
    let amax = if model.is_extended() {
        rigid_limit(model, v, dir).max(0.0)
    } else {
        f64::INFINITY
    };
    let alpha = elastic_step(model, v, dir, g0, s2)?;
    Some(alpha.min(amax)).filter(|a| *a > 0.0)
}

/// The exact minimiser along the line of J with its elastic terms (the rigid limits are
/// applied by the caller).
fn elastic_step(model: &Model, v: &[f64], dir: &[f64], g0: f64, s2: f64) -> Option<f64> {
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    let mut alpha = 1.0f64;
    let mut codes = match model.l {
        FoundationMatrix::Consistent(_) => vec![0u8; v.len()],
        _ => Vec::new(),
    };
    let mut codes_low = match model.lower.as_ref().map(|b| &b.l) {
        Some(FoundationMatrix::Consistent(_)) => vec![0u8; v.len()],
        _ => Vec::new(),
    };
    for _ in 0..200 {
        let p = pieces(model, v, dir, alpha, &mut codes, &mut codes_low);
        let dl = g0 + alpha * s2 + p.left.0 + alpha * p.left.1;
        let dr = g0 + alpha * s2 + p.right.0 + alpha * p.right.1;
        if dl <= 0.0 && dr >= 0.0 {
            // 0 is in the subdifferential at α: a kink minimum.
            return (alpha > 0.0).then_some(alpha);
        }
        let next = if dr < 0.0 {
            lo = alpha;
            // The root of the right piece's derivative: exact if it stays in the piece.
            let c = -(g0 + p.right.0) / (s2 + p.right.1);
            if c <= p.above {
                return Some(c);
            }
            c
        } else {
            hi = alpha;
            let c = -(g0 + p.left.0) / (s2 + p.left.1);
            if c >= p.below {
                return (c > 0.0).then_some(c);
            }
            c
        };
        alpha = if next > lo && next < hi {
            next
        } else if hi.is_finite() {
            0.5 * (lo + hi)
        } else {
            2.0 * lo.max(1.0)
        };
        if alpha <= 0.0 {
            return None;
        }
    }
    Some(if hi.is_finite() { 0.5 * (lo + hi) } else { lo }).filter(|a| *a > 0.0)
}

/// `v ← v + α δ`, snapping onto its kink every coordinate whose breakpoint is α (up to
/// rounding), so that touching vertices are exactly touching (on φ, or on φ_low with a
/// body below), and keeping rigid bodies' constraints exact. Returns whether any
/// coordinate changed.
pub fn apply_step(model: &Model, v: &mut [f64], dir: &[f64], alpha: f64) -> bool {
    let extended = model.is_extended();
    // Snaps `new` onto the kink `f` crossed at this step, if it is one.
    let snaps = |old: f64, new: f64, f: f64, d: f64| -> bool {
        let t = (f - old) / d;
        let tol = 1e-12 * alpha.abs().max(1e-300);
        let hits = (t - alpha).abs() <= tol || (new - f).abs() <= 1e-15 * f.abs().max(old.abs());
        hits && (old - f) * d < 0.0
    };
    // The new value of coordinate i.
    let step = |i: usize, old: f64| -> f64 {
        let d = dir[i];
        let new = old + alpha * d;
        if model.can_touch[i] {
            let fi = model.phi[i];
            if snaps(old, new, fi, d) {
                return fi;
            }
            let rigid = if extended {
                model.rigid_at(i)
            } else {
                model.is_rigid()
            };
            if rigid && new > fi {
                return fi;
            }
        }
        if extended {
            if let Some(low) = &model.lower {
                if low.can_touch[i] {
                    let fi = low.phi[i];
                    if snaps(old, new, fi, d) || (low.rigid_at(i) && new < fi) {
                        return fi;
                    }
                }
            }
        }
        new
    };
    let chunk = |lo: usize, xs: &mut [f64]| -> bool {
        let mut changed = false;
        for (k, x) in xs.iter_mut().enumerate() {
            if dir[lo + k] != 0.0 {
                let new = step(lo + k, *x);
                changed |= new != *x;
                *x = new;
            }
        }
        changed
    };
    if v.len() < VECTOR_ROWS {
        return chunk(0, v);
    }
    v.par_chunks_mut(BLOCK)
        .enumerate()
        .map(|(b, xs)| chunk(b * BLOCK, xs))
        .reduce(|| false, |a, b| a || b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Foundation;
    use crate::solve::multigrid::tests::{bench_model, square_hierarchy};

    /// The step is the minimiser of J along the line: J at α is below J on a fine grid of
    /// steps and at α(1 ± 1e-6), evaluated from the model's energy.
    #[test]
    fn step_minimises_the_energy_along_the_line() {
        let hier = square_hierarchy(4, 2);
        for (h, f) in [
            (Some(1000.0), Foundation::Consistent),
            (Some(1000.0), Foundation::Lumped),
            (None, Foundation::Lumped),
        ] {
            let model = bench_model(hier.finest(), h, f);
            let n = model.n();
            for seed in 0..20 {
                let s = seed as f64;
                let mut v: Vec<f64> = (0..n)
                    .map(|i| model.phi[i] + 0.05 * ((i as f64) * 0.37 + s).sin())
                    .collect();
                if h.is_none() {
                    for (x, p) in v.iter_mut().zip(&model.phi) {
                        *x = x.min(*p);
                    }
                }
                let r = model.residual(&v);
                let dir: Vec<f64> = (0..n)
                    .map(|i| -r[i] * (1.0 + 0.5 * ((i as f64) * 1.3 + s).cos()) * 50.0)
                    .collect();
                let (g0, s2) = line_data(&model, &dir, &r);
                let at = |a: f64| {
                    let w: Vec<f64> = v.iter().zip(&dir).map(|(x, d)| x + a * d).collect();
                    model.energy(&w)
                };
                let j0 = at(0.0);
                match exact_step(&model, &v, &dir, g0, s2) {
                    Some(alpha) => {
                        assert!(alpha > 0.0);
                        let ja = at(alpha);
                        let tol = 1e-12 * j0.abs().max(1.0);
                        assert!(ja <= j0 + tol, "{f:?}: J rises");
                        // Beyond the rigid limit J is +∞; below it the minimum is α.
                        for k in 1..=200 {
                            let b = alpha * k as f64 / 100.0;
                            assert!(ja <= at(b) + tol, "{f:?} seed {seed}: J({b}) < J({alpha})");
                        }
                        for b in [alpha * (1.0 - 1e-6), alpha * (1.0 + 1e-6)] {
                            assert!(ja <= at(b) + tol, "{f:?}: not a local minimum");
                        }
                    }
                    None => {
                        // Not a descent direction: J does not decrease for small steps.
                        assert!(at(1e-6) >= j0 - 1e-12 * j0.abs().max(1.0), "{f:?}");
                    }
                }
            }
        }
    }
}
