//! Exact minimisation of J in one coordinate (docs/theory.md#coordinatewise-optimality) and
//! the nonsmooth Gauss-Seidel sweep built on it. With the other coordinates fixed, J as a
//! function of `V_i = x` is
//!
//! `½ S_ii x² − b x + ½ L_ii p² + c p + const`, `p = (x − φ_i)⁺`,
//!
//! with `b = D_i − Σ_{j≠i} S_ij V_j` and `c = Σ_{j≠i} L_ij p_j ≥ 0`: a convex piecewise
//! quadratic with one kink at φ_i. Its minimiser is in closed form, and lands *exactly* on
//! φ_i (the touching state) when `S_ii φ_i − b ≤ 0 ≤ S_ii φ_i − b + c`.
//!
//! With a body below (docs/theory.md#second-body) the term `½ L_low,ii q² + c_low q`, `q =
//! (φ_low,i − x)⁺`, adds a second kink at φ_low,i; where a body is rigid at vertex i its
//! term is the constraint `x ≤ φ_i` (or `x ≥ φ_low,i`) instead. [`minimise_two_kinks`] is
//! the closed form of that case; without a body below and without rigid regions the sweep
//! uses [`minimise_1d`], so the paper's model runs exactly as before.

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

/// The one-variable problem of coordinate `i`: returns `(S_ii, b, L_ii, c)`. `v` holds the
/// coordinates `base..base + v.len()` of the iterate, which must include every neighbour
/// of `i` (`base = 0` for the whole iterate).
#[inline]
pub fn local_problem(
    model: &Model,
    v: &[f64],
    base: usize,
    i: usize,
) -> (f64, f64, Option<f64>, f64) {
    let (cols, svals) = model.s.row(i);
    let mut sii = 0.0;
    let mut sv = 0.0;
    match &model.l {
        FoundationMatrix::Consistent(l) => {
            // S and the consistent L share the pattern: one pass over the row.
            let lvals = &l.val[l.pattern.ptr(i)..l.pattern.ptr(i + 1)];
            let mut lii = 0.0;
            let mut c = 0.0;
            for ((&j, &s), &lv) in cols.iter().zip(svals).zip(lvals) {
                let j = j as usize;
                if j == i {
                    sii = s;
                    lii = lv;
                } else {
                    let vj = v[j - base];
                    sv += s * vj;
                    if lv != 0.0 && model.can_touch[j] {
                        c += lv * (vj - model.phi[j]).max(0.0);
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
                    sv += s * v[j - base];
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

/// Minimises J exactly in coordinate `i`, updating it in `v` (which holds the coordinates
/// `base..`, as for [`local_problem`]); returns whether its value changed.
#[inline]
pub fn relax(model: &Model, v: &mut [f64], base: usize, i: usize) -> bool {
    let (sii, b, lii, c) = local_problem(model, v, base, i);
    let new = minimise_1d(sii, b, model.phi[i], lii, c, model.can_touch[i]);
    let old = std::mem::replace(&mut v[i - base], new);
    new != old
}

/// One body's part of the one-variable problem at a vertex: the kink `phi`, `L_ii`, the
/// neighbours' coupling `c = Σ_{j≠i} L_ij p_j`, whether the body can touch the vertex and
/// whether it holds it rigidly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kink {
    /// The body's surface at the vertex.
    pub phi: f64,
    /// `L_ii` of the body's elastic part.
    pub lii: f64,
    /// `Σ_{j≠i} L_ij p_j` (p the body's penetrations), ≥ 0.
    pub c: f64,
    /// The body can touch the vertex.
    pub active: bool,
    /// The body holds the vertex rigidly (a constraint instead of the elastic term).
    pub rigid: bool,
}

impl Kink {
    /// No body.
    pub const NONE: Kink = Kink {
        phi: 0.0,
        lii: 0.0,
        c: 0.0,
        active: false,
        rigid: false,
    };

    /// The body's elastic term is present.
    #[inline]
    fn elastic(self) -> bool {
        self.active && !self.rigid
    }
}

/// The minimiser of `½ s x² − b x + [x > φ](½ l p² + c p) + [x < φ_low](½ l_low q² + c_low q)`
/// with `p = x − φ`, `q = φ_low − x` (the elastic terms of the body above and below), then
/// clamped to `x ≤ φ` where the body above is rigid and `x ≥ φ_low` where the body below is
/// (a convex function's minimiser on an interval is its free minimiser projected there).
///
/// The derivative is piecewise linear and increasing with upward jumps `c` at φ and
/// `c_low` at φ_low: the kinks are visited in increasing order; the minimiser is a kink
/// when zero lies between the derivatives on its two sides, else the root of the piece
/// where the derivative changes sign.
#[inline]
pub fn minimise_two_kinks(s: f64, b: f64, up: Kink, low: Kink) -> f64 {
    let (ue, le) = (up.elastic(), low.elastic());
    // The derivative on a piece, as `A x + B`, from which terms are on.
    let piece = |up_on: bool, low_on: bool| -> (f64, f64) {
        let mut a = s;
        let mut c = -b;
        if up_on {
            a += up.lii;
            c += up.c - up.lii * up.phi;
        }
        if low_on {
            a += low.lii;
            c -= low.lii * low.phi + low.c;
        }
        (a, c)
    };
    // Kinks in increasing order (at most two).
    let mut kinks = [f64::INFINITY; 2];
    let mut nk = 0;
    if ue {
        kinks[nk] = up.phi;
        nk += 1;
    }
    if le {
        kinks[nk] = low.phi;
        nk += 1;
    }
    if nk == 2 && kinks[1] < kinks[0] {
        kinks.swap(0, 1);
    }
    let mut x = f64::NAN;
    let mut prev = f64::NEG_INFINITY;
    for &k in &kinks[..nk] {
        // The piece left of k, from the previous kink: the upper term is on when φ lies at
        // or below its left end, the lower term when φ_low lies at or above its right end.
        let left = piece(ue && up.phi <= prev, le && low.phi >= k);
        let dl = left.0 * k + left.1;
        if dl > 0.0 {
            x = -left.1 / left.0;
            break;
        }
        let right = piece(ue && up.phi <= k, le && low.phi > k);
        if right.0 * k + right.1 >= 0.0 {
            x = k;
            break;
        }
        prev = k;
    }
    if x.is_nan() {
        // Right of every kink only the upper term can be on (the lower one is off right of
        // its kink); without kinks neither is.
        let last = piece(ue, false);
        x = -last.1 / last.0;
    }
    if up.active && up.rigid {
        x = x.min(up.phi);
    }
    if low.active && low.rigid {
        x = x.max(low.phi);
    }
    x
}

/// The one-variable problem of coordinate `i` with both bodies
/// (docs/theory.md#second-body): returns `(S_ii, b, upper, lower)`; `v` and `base` as for
/// [`local_problem`]. S and consistent foundation matrices share the pattern.
#[inline]
pub fn local_problem_two(
    model: &Model,
    v: &[f64],
    base: usize,
    i: usize,
) -> (f64, f64, Kink, Kink) {
    let (cols, svals) = model.s.row(i);
    let (start, end) = (model.s.pattern.ptr(i), model.s.pattern.ptr(i + 1));
    let mut sii = 0.0;
    let mut sv = 0.0;
    for (&j, &s) in cols.iter().zip(svals) {
        let j = j as usize;
        if j == i {
            sii = s;
        } else {
            sv += s * v[j - base];
        }
    }
    // One body's `(L_ii, c)`; `sign` = 1 above (p = V − φ), −1 below (q = φ_low − V).
    let body = |l: &FoundationMatrix, phi: &[f64], can_touch: &[bool], sign: f64| -> (f64, f64) {
        match l {
            FoundationMatrix::Consistent(l) => {
                let mut lii = 0.0;
                let mut c = 0.0;
                for (&j, &lv) in cols.iter().zip(&l.val[start..end]) {
                    let j = j as usize;
                    if j == i {
                        lii = lv;
                    } else if lv != 0.0 && can_touch[j] {
                        c += lv * (sign * (v[j - base] - phi[j])).max(0.0);
                    }
                }
                (lii, c)
            }
            FoundationMatrix::Lumped(d) => (d[i], 0.0),
            FoundationMatrix::Rigid => (0.0, 0.0),
        }
    };
    let (lii, c) = body(&model.l, &model.phi, &model.can_touch, 1.0);
    let up = Kink {
        phi: model.phi[i],
        lii,
        c,
        active: model.can_touch[i],
        rigid: model.rigid_at(i),
    };
    let low = match &model.lower {
        Some(low) => {
            let (lii, c) = body(&low.l, &low.phi, &low.can_touch, -1.0);
            Kink {
                phi: low.phi[i],
                lii,
                c,
                active: low.can_touch[i],
                rigid: low.rigid_at(i),
            }
        }
        None => Kink::NONE,
    };
    (sii, model.d[i] - sv, up, low)
}

/// [`relax`] with both bodies and rigid regions (docs/theory.md#second-body,
/// docs/theory.md#mixed-bodies).
#[inline]
pub fn relax_two(model: &Model, v: &mut [f64], base: usize, i: usize) -> bool {
    let (sii, b, up, low) = local_problem_two(model, v, base, i);
    let new = minimise_two_kinks(sii, b, up, low);
    let old = std::mem::replace(&mut v[i - base], new);
    new != old
}

/// Below this many unknowns the nonsmooth sweep runs serially in the natural order.
const PARALLEL_SWEEP: usize = 1 << 15;

/// Rows per block of the parallel sweep for `n` unknowns: about sixteen blocks, so that
/// both cores stay busy and the rows on block seams are a few per cent. It depends on `n`
/// alone, so the sweep's order (and result) does not depend on the number of threads.
fn sweep_block(n: usize) -> usize {
    (n / 16).clamp(1 << 14, 1 << 17)
}

/// One forward nonsmooth Gauss-Seidel sweep: every coordinate minimised exactly, once.
/// J never increases. Returns whether any coordinate changed.
///
/// Large problems are swept by blocks of consecutive rows: first, in parallel, the rows
/// of every block whose neighbours all lie in the same block (in increasing order within
/// the block; two such rows of different blocks never read each other), then the rows on
/// the seams between blocks, serially in increasing order. Every update is an exact
/// coordinate minimisation with the current values of all neighbours, so this is the
/// Gauss-Seidel sweep of a fixed reordering of the coordinates: the same descent and
/// convergence, the same result for any number of threads.
pub fn sweep_forward(model: &Model, v: &mut [f64]) -> bool {
    if model.is_extended() {
        sweep(model, v, relax_two)
    } else {
        sweep(model, v, relax)
    }
}

fn sweep(
    model: &Model,
    v: &mut [f64],
    relax: impl Fn(&Model, &mut [f64], usize, usize) -> bool + Sync,
) -> bool {
    use rayon::prelude::*;
    let n = v.len();
    if n < PARALLEL_SWEEP {
        let mut changed = false;
        for i in 0..n {
            changed |= relax(model, v, 0, i);
        }
        return changed;
    }
    let pat = &model.s.pattern;
    let block = sweep_block(n);
    // Inside the blocks, in parallel; the seam rows are collected per block.
    let parts: Vec<(bool, Vec<u32>)> = v
        .par_chunks_mut(block)
        .enumerate()
        .map(|(b, xs)| {
            let (lo, hi) = (b * block, b * block + xs.len());
            let mut changed = false;
            let mut seams = Vec::new();
            for i in lo..hi {
                // Columns are sorted: the row is inside when its first and last are.
                let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
                let inside = e > s && pat.col[s] as usize >= lo && (pat.col[e - 1] as usize) < hi;
                if inside {
                    changed |= relax(model, xs, lo, i);
                } else {
                    seams.push(i as u32);
                }
            }
            (changed, seams)
        })
        .collect();
    let mut changed = false;
    for (c, seams) in parts {
        changed |= c;
        for i in seams {
            changed |= relax(model, v, 0, i as usize);
        }
    }
    changed
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

    /// The parallel sweep is exactly the Gauss-Seidel sweep of its documented order (the
    /// rows inside the blocks, then the seam rows), done serially here: bit for bit, on one
    /// thread and on several, and it lowers J. Paper model (consistent, lumped, rigid) and
    /// the extended path (some vertices held rigidly).
    #[test]
    fn parallel_sweep_is_gauss_seidel_in_a_fixed_order() {
        use crate::model::Foundation;
        use crate::solve::multigrid::tests::{bench_model, square_hierarchy};
        let mesh = square_hierarchy(200, 1).levels.pop().unwrap();
        let lumped = bench_model(&mesh, Some(1000.0), Foundation::Lumped);
        let mut partly_rigid = lumped.clone();
        partly_rigid.rigid = Some((0..lumped.n()).map(|i| i % 7 == 0).collect());
        let models = [
            bench_model(&mesh, Some(1000.0), Foundation::Consistent),
            lumped,
            bench_model(&mesh, None, Foundation::Consistent),
            partly_rigid,
        ];
        for model in &models {
            let n = model.n();
            assert!(n >= PARALLEL_SWEEP);
            let (pat, block) = (&model.s.pattern, sweep_block(n));
            assert!(n / block >= 2, "the test must cross block seams");
            let inside = |i: usize| {
                let lo = i / block * block;
                let hi = (lo + block).min(n);
                let cols = &pat.col[pat.ptr(i)..pat.ptr(i + 1)];
                cols[0] as usize >= lo && (cols[cols.len() - 1] as usize) < hi
            };
            let order: Vec<usize> = (0..n)
                .filter(|&i| inside(i))
                .chain((0..n).filter(|&i| !inside(i)))
                .collect();
            assert!(order.len() == n && order.iter().any(|&i| !inside(i)));
            let mut start = vec![0.0; n];
            model.project(&mut start);
            let mut reference = start.clone();
            let mut par = start.clone();
            let mut energy = model.energy(&start);
            for _ in 0..3 {
                for &i in &order {
                    if model.is_extended() {
                        relax_two(model, &mut reference, 0, i);
                    } else {
                        relax(model, &mut reference, 0, i);
                    }
                }
                assert!(sweep_forward(model, &mut par));
                assert_eq!(par, reference);
                let e = model.energy(&par);
                assert!(e < energy, "J rose from {energy} to {e}");
                energy = e;
            }
            let mut serial = start.clone();
            crate::parallel::on_threads(1, || {
                for _ in 0..3 {
                    sweep_forward(model, &mut serial);
                }
            });
            assert_eq!(serial, par);
        }
    }

    /// The 1-D function with both bodies, for brute force.
    fn energy_two(s: f64, b: f64, up: Kink, low: Kink, x: f64) -> f64 {
        if (up.active && up.rigid && x > up.phi) || (low.active && low.rigid && x < low.phi) {
            return f64::INFINITY;
        }
        let mut f = 0.5 * s * x * x - b * x;
        if up.elastic() {
            let p = (x - up.phi).max(0.0);
            f += 0.5 * up.lii * p * p + up.c * p;
        }
        if low.elastic() {
            let q = (low.phi - x).max(0.0);
            f += 0.5 * low.lii * q * q + low.c * q;
        }
        f
    }

    #[test]
    fn two_kinks_match_brute_force_and_reduce_to_one() {
        let kink = |phi, lii, c, rigid| Kink {
            phi,
            lii,
            c,
            active: true,
            rigid,
        };
        // Both orders of the kinks, both rigid flags, every position of the minimum.
        let mut cases = Vec::new();
        for &b in &[-6.0, -2.0, -0.3, 0.0, 0.4, 1.1, 3.0, 7.0] {
            for &(fu, fl) in &[(0.5, -0.5), (-0.2, 0.3), (0.1, 0.1), (1.0, 0.0)] {
                for &(ru, rl) in &[(false, false), (true, false), (false, true), (true, true)] {
                    if ru && rl && fl > fu {
                        continue; // an empty admissible set: refused at assembly
                    }
                    for &(cu, cl) in &[(0.0, 0.0), (0.7, 0.2), (3.0, 4.0)] {
                        cases.push((2.0, b, kink(fu, 1.5, cu, ru), kink(fl, 0.8, cl, rl)));
                    }
                }
            }
        }
        for (s, b, up, low) in cases {
            let x = minimise_two_kinks(s, b, up, low);
            let fx = energy_two(s, b, up, low, x);
            assert!(fx.is_finite(), "{up:?} {low:?} b {b}: infeasible {x}");
            // No point of a fine grid is lower, nor a point next to x.
            let mut t = -6.0;
            while t <= 6.0 {
                assert!(
                    fx <= energy_two(s, b, up, low, t) + 1e-12,
                    "{up:?} {low:?} b {b}"
                );
                t += 1e-3;
            }
            for d in [1e-7, -1e-7] {
                assert!(fx <= energy_two(s, b, up, low, x + d) + 1e-13);
            }
        }
        // Without a body below it is the one-kink minimiser.
        for (sii, b, phi, lii, c) in [(2.0, 1.0, 0.0, 3.0, 0.0), (2.0, 1.0, 0.3, 3.0, 0.5)] {
            let one = minimise_1d(sii, b, phi, Some(lii), c, true);
            let two = minimise_two_kinks(sii, b, kink(phi, lii, c, false), Kink::NONE);
            assert!((one - two).abs() < 1e-15);
        }
        // At a kink the minimiser is the kink exactly (touching is a state).
        let x = minimise_two_kinks(2.0, -1.2, Kink::NONE, kink(-0.5, 1.0, 0.5, false));
        assert_eq!(x, -0.5);
    }
}
