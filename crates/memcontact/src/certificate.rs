//! The optimality certificate of a candidate U: the residuals of the paper's Kuhn-Tucker
//! system 2e and complementarity problem 2f, scaled by the forces the iterate itself
//! carries, with the energy J(U) of Problem 2b and an estimate of the rounding floor,
//! all in one pass over the matrices (no allocation; fixed blocks, so the result does not
//! depend on the number of threads).
//!
//! With `r = SU − D`, `p = (U − φ)⁺` (on M) and `(Lp)ᵢ` (neighbours' penetrations
//! included), vertex i is optimal when zero lies between the left and right derivatives of
//! J along coordinate i:
//!
//! * `U_i < φ_i` (clear, or off M): `r_i = 0`;
//! * `U_i > φ_i` (penetrating): `r_i + (Lp)_i = 0`;
//! * `U_i = φ_i` (touching): `−(Lp)_i ≤ r_i ≤ 0`;
//! * rigid obstacle: `r_i ≤ 0` where `U_i = φ_i`, and `U_i ≤ φ_i` (a violation counts as the
//!   force `S_ii (U_i − φ_i)` that would be needed to push the vertex back).
//!
//! These are the componentwise conditions of 2f; with `X₁ = D − SU`, `U₂ = p`,
//! `X₂ = L̃U₂ − X₁` they are those of 2e (`X ≥ 0`, `X̂₁ = 0` off M, both complementarities).
//! The largest violation, a force, is divided by the **force scale of the iterate**
//! `max(‖D‖∞, ‖SU‖∞, ‖Lp‖∞)`: the load and the elastic and foundation forces actually
//! present, never forces the iterate does not exert, so that no iterate passes unless it
//! balances the forces it carries.
//!
//! The **rounding floor** is what double precision can resolve: each residual component
//! is a sum whose terms have the size `Σⱼ|S_ij||U_j| + |D_i| + Σⱼ L_ij (|U_j| + |φ_j|)`;
//! rounding leaves an error of a few ulps of that. A residual at the floor is as good as
//! the data allow in this arithmetic.

use crate::model::{FoundationMatrix, Model};
use rayon::prelude::*;

/// Rows per block of the deterministic reductions.
const BLOCK: usize = 4096;

/// Rows from which the pass runs in parallel.
const PAR_ROWS: usize = 32 * 1024;

/// The floor is this many ulps of the largest sum a residual is computed from: the
/// rounding of U itself (half an ulp of each U_j, multiplied by |S_ij|) and of the sums.
const FLOOR_ULPS: f64 = 2.0;

/// A residual within this factor of the rounding floor is at the floor: iterating further
/// only moves the rounding errors around.
pub const AT_FLOOR: f64 = 2.0;

/// A solve whose residual stops decreasing within this factor of the rounding floor has
/// reached what the arithmetic allows (the floor is an estimate, not a bound).
pub const NEAR_FLOOR: f64 = 8.0;

/// Above this rounding floor the certificate can no longer certify an answer worth
/// having: the data's scales are beyond what double precision resolves.
pub const FLOOR_LIMIT: f64 = 1e-6;

/// Iterations without a 10 % decrease of the best residual after which a solve near the
/// rounding floor is considered stuck there.
const FLOOR_PATIENCE: usize = 4;

/// The scaled optimality residuals of a candidate U: zero exactly at the solution.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Certificate {
    /// Largest violation of Problem 2f's conditions, componentwise, divided by the force
    /// scale (`r ≤ 0`, `r + Lp ≥ 0`, `r + Lp = 0` where `U > φ`, `r = 0` where `U < φ`).
    pub residual_2f: f64,
    /// Largest violation of the Kuhn-Tucker system 2e with `X₁ = D − SU`, `U₂ = p`,
    /// `X₂ = L̃U₂ − X₁`: `X ≥ 0`, `X̂₁ = 0` off M, and both complementarities.
    pub residual_2e: f64,
    /// The force scale of the iterate, `max(‖D‖∞, ‖SU‖∞, ‖Lp‖∞)`.
    pub force_scale: f64,
    /// The rounding floor of these residuals at this iterate (see the module doc).
    #[serde(default)]
    pub rounding_floor: f64,
}

impl Certificate {
    /// `max(residual_2f, residual_2e)`.
    pub fn kkt(&self) -> f64 {
        self.residual_2f.max(self.residual_2e)
    }

    /// The residual is within [`AT_FLOOR`] times the rounding floor.
    pub fn at_floor(&self) -> bool {
        self.kkt() <= AT_FLOOR * self.rounding_floor
    }

    /// Within [`NEAR_FLOOR`] times the rounding floor.
    pub fn near_floor(&self) -> bool {
        self.kkt() <= NEAR_FLOOR * self.rounding_floor
    }

    /// A solver can stop: the residual meets `tolerance`, or it is at the rounding floor
    /// (where more iterations cannot lower it).
    pub fn settled(&self, tolerance: f64) -> bool {
        self.kkt() <= tolerance || self.at_floor()
    }
}

/// Watches the residuals of an iteration for a stop near the rounding floor: the best
/// residual has not decreased by 10 % for a few iterations while it is near the floor.
#[derive(Debug, Clone)]
pub struct FloorWatch {
    best: f64,
    since: usize,
}

impl Default for FloorWatch {
    fn default() -> Self {
        FloorWatch {
            best: f64::INFINITY,
            since: 0,
        }
    }
}

impl FloorWatch {
    /// Records the certificate of the latest iterate; `true` when the iteration is stuck
    /// near the rounding floor.
    pub fn stuck(&mut self, c: &Certificate) -> bool {
        if c.kkt() < 0.9 * self.best {
            self.best = c.kkt();
            self.since = 0;
        } else {
            self.since += 1;
        }
        self.since >= FLOOR_PATIENCE && c.near_floor()
    }
}

/// How many unknowns are in each vertex state at an iterate: clear (`U_i < φ_i`, or off
/// M), touching (`U_i = φ_i` on M) and penetrating (`U_i > φ_i` on M).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct StateCounts {
    /// `U_i < φ_i`, or the vertex cannot touch.
    pub clear: usize,
    /// `U_i = φ_i` on M.
    pub touching: usize,
    /// `U_i > φ_i` on M.
    pub penetrating: usize,
}

/// A certificate with the energy and the state counts at the same iterate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluation {
    /// The residuals.
    pub certificate: Certificate,
    /// J(U); `+∞` for a rigid obstacle violated.
    pub energy: f64,
    /// The vertex states.
    pub states: StateCounts,
}

/// Per-block accumulators.
#[derive(Clone, Copy, Default)]
struct Acc {
    /// Largest violation of 2f (force).
    f2: f64,
    /// Largest violation of 2e (force).
    e2: f64,
    /// ‖D‖∞, ‖SU‖∞, ‖Lp‖∞.
    scale: f64,
    /// Largest size of the sums a residual is made of.
    size: f64,
    /// Σ Uᵢ (rᵢ − Dᵢ) = UᵀSU − 2UᵀD.
    quad: f64,
    /// pᵀLp.
    foundation: f64,
    /// Some vertex violates the rigid constraint.
    infeasible: bool,
    /// Touching and penetrating unknowns.
    touching: usize,
    penetrating: usize,
}

impl Acc {
    fn merge(mut self, o: Acc) -> Acc {
        self.f2 = self.f2.max(o.f2);
        self.e2 = self.e2.max(o.e2);
        self.scale = self.scale.max(o.scale);
        self.size = self.size.max(o.size);
        self.quad += o.quad;
        self.foundation += o.foundation;
        self.infeasible |= o.infeasible;
        self.touching += o.touching;
        self.penetrating += o.penetrating;
        self
    }
}

/// The certificate and energy of `v` (see the module doc).
pub fn evaluate(model: &Model, v: &[f64]) -> Evaluation {
    match &model.l {
        FoundationMatrix::Consistent(l) => evaluate_with(model, v, |_, s, e| {
            let (mut lp, mut size) = (0.0, 0.0);
            for (&j, &lv) in l.pattern.col[s..e].iter().zip(&l.val[s..e]) {
                let j = j as usize;
                if lv != 0.0 && model.can_touch[j] {
                    let pj = v[j] - model.phi[j];
                    if pj > 0.0 {
                        lp += lv * pj;
                        size += lv * (v[j].abs() + model.phi[j].abs());
                    }
                }
            }
            (lp, size)
        }),
        FoundationMatrix::Lumped(d) => evaluate_with(model, v, |i, _, _| {
            let pi = v[i] - model.phi[i];
            if model.can_touch[i] && pi > 0.0 {
                (d[i] * pi, d[i] * (v[i].abs() + model.phi[i].abs()))
            } else {
                (0.0, 0.0)
            }
        }),
        FoundationMatrix::Rigid => evaluate_with(model, v, |_, _, _| (0.0, 0.0)),
    }
}

/// [`evaluate`] with `lp(i, row start, row end) = ((Lp)_i, Σⱼ L_ij(|U_j| + |φ_j|))` over
/// the penetrating j (S and a consistent L share their pattern).
fn evaluate_with(
    model: &Model,
    v: &[f64],
    lp_of: impl Fn(usize, usize, usize) -> (f64, f64) + Sync,
) -> Evaluation {
    let n = model.n();
    let rigid = model.is_rigid();
    let pat = &model.s.pattern;
    let sval = &model.s.val;
    let block = |b: usize| -> Acc {
        let mut acc = Acc::default();
        let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(n));
        for i in lo..hi {
            let (s, e) = (pat.row_ptr[i], pat.row_ptr[i + 1]);
            let (mut su, mut size, mut sii) = (0.0, model.d[i].abs(), 0.0);
            for (&j, &a) in pat.col[s..e].iter().zip(&sval[s..e]) {
                let j = j as usize;
                su += a * v[j];
                size += a.abs() * v[j].abs();
                if j == i {
                    sii = a;
                }
            }
            let r = su - model.d[i];
            let (vi, fi) = (v[i], model.phi[i]);
            acc.scale = acc.scale.max(model.d[i].abs()).max(su.abs());
            acc.quad += vi * (r - model.d[i]);
            let (violation_2f, violation_2e) = if model.can_touch[i] {
                let (lp, lsize) = lp_of(i, s, e);
                size += lsize;
                acc.scale = acc.scale.max(lp.abs());
                let p = (vi - fi).max(0.0);
                acc.foundation += p * lp;
                if vi == fi {
                    acc.touching += 1;
                } else if vi > fi {
                    acc.penetrating += 1;
                }
                // Left and right derivatives of J along coordinate i.
                let (left, right) = if vi < fi {
                    (r, r)
                } else if vi > fi {
                    if rigid {
                        acc.infeasible = true;
                        (r, r)
                    } else {
                        (r + lp, r + lp)
                    }
                } else if rigid {
                    (r, f64::INFINITY)
                } else {
                    (r, r + lp)
                };
                let mut f2 = left.max(-right).max(0.0);
                if rigid && vi > fi {
                    f2 = f2.max(sii * (vi - fi));
                }
                // 2e: X₁ = −r ≥ 0, X₂ = Lp − X₁ ≥ 0 (elastic), X₁ = 0 where U < φ,
                // X₂ = 0 where p > 0.
                let (x1, x2) = (-r, lp + r);
                let mut e2 = (-x1).max(0.0);
                if !rigid {
                    e2 = e2.max(-x2);
                    if p > 0.0 {
                        e2 = e2.max(x2.abs());
                    }
                }
                if vi < fi {
                    e2 = e2.max(x1.abs());
                }
                if rigid && vi > fi {
                    e2 = e2.max(sii * (vi - fi));
                }
                (f2, e2)
            } else {
                // Off M, L vanishes: r = 0 (2f), and X̂₁ = 0 there (2e).
                (r.abs(), r.abs())
            };
            // NaN anywhere makes the certificate fail.
            acc.f2 = if violation_2f.is_nan() {
                f64::INFINITY
            } else {
                acc.f2.max(violation_2f)
            };
            acc.e2 = if violation_2e.is_nan() {
                f64::INFINITY
            } else {
                acc.e2.max(violation_2e)
            };
            acc.size = acc.size.max(size);
        }
        acc
    };
    let nb = n.div_ceil(BLOCK);
    let tot = if n >= PAR_ROWS {
        (0..nb)
            .into_par_iter()
            .map(block)
            .collect::<Vec<_>>()
            .into_iter()
            .fold(Acc::default(), Acc::merge)
    } else {
        (0..nb).map(block).fold(Acc::default(), Acc::merge)
    };
    let scale = tot.scale.max(f64::MIN_POSITIVE);
    let finite = |x: f64| if x.is_finite() { x } else { f64::INFINITY };
    let energy = if tot.infeasible {
        f64::INFINITY
    } else {
        0.5 * tot.quad + 0.5 * tot.foundation
    };
    Evaluation {
        certificate: Certificate {
            residual_2f: finite(tot.f2 / scale),
            residual_2e: finite(tot.e2 / scale),
            force_scale: scale,
            rounding_floor: finite(FLOOR_ULPS * f64::EPSILON * tot.size / scale),
        },
        energy,
        states: StateCounts {
            clear: n - tot.touching - tot.penetrating,
            touching: tot.touching,
            penetrating: tot.penetrating,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Foundation, ProblemData, Sampling, Stiffness};
    use crate::solve::tests::square;

    fn model(h: Option<f64>, f: f64, phi: f64, foundation: Foundation) -> Model {
        let mesh = square(8);
        let h = h.unwrap_or(0.0);
        let data = ProblemData {
            tension: 1.0,
            load: &f,
            shape: &phi,
            stiffness: if h > 0.0 {
                Stiffness::Elastic(&h)
            } else {
                Stiffness::Rigid
            },
            foundation,
            sampling: Sampling::Nodal,
        };
        Model::assemble(&mesh, &data).unwrap()
    }

    #[test]
    fn zero_never_passes_when_the_load_is_unbalanced() {
        // A far obstacle: L|φ| is huge, but U = 0 carries no foundation force; the load is
        // unbalanced, so the certificate says so.
        for (h, phi) in [(100.0, 1e9), (1e11, 1.0), (1e7, 0.0)] {
            for foundation in [Foundation::Consistent, Foundation::Lumped] {
                let m = model(Some(h), 20.0, phi, foundation);
                let c = evaluate(&m, &vec![0.0; m.n()]).certificate;
                assert!(c.kkt() >= 0.5, "h {h} φ {phi}: {c:?}");
            }
        }
        let m = model(None, 20.0, 1e9, Foundation::Consistent);
        assert!(evaluate(&m, &vec![0.0; m.n()]).certificate.kkt() >= 0.5);
    }

    #[test]
    fn energy_and_certificate_agree_with_the_model() {
        let m = model(Some(50.0), 10.0, 0.02, Foundation::Consistent);
        let v: Vec<f64> = (0..m.n())
            .map(|i| 0.05 * ((i as f64) * 0.7).sin())
            .collect();
        let e = evaluate(&m, &v);
        assert!((e.energy - m.energy(&v)).abs() <= 1e-13 * m.energy(&v).abs().max(1.0));
        // The scale is the largest force present.
        let r = m.residual(&v);
        let su: Vec<f64> = r.iter().zip(&m.d).map(|(r, d)| r + d).collect();
        let s = crate::sparse::norm_inf(&su).max(crate::sparse::norm_inf(&m.d));
        assert!(e.certificate.force_scale >= s);
        assert!(e.certificate.rounding_floor > 0.0 && e.certificate.rounding_floor < 1e-12);
    }

    #[test]
    fn rigid_infeasibility_is_a_force() {
        let m = model(None, 20.0, 0.01, Foundation::Consistent);
        let mut v = vec![0.0; m.n()];
        v[m.n() / 2] = 0.011;
        let e = evaluate(&m, &v);
        assert!(e.energy.is_infinite());
        assert!(e.certificate.kkt() > 1e-3, "{:?}", e.certificate);
    }
}
