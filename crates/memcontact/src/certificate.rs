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
//!
//! Beyond the paper (docs/theory.md#second-body, docs/theory.md#mixed-bodies) the same pass
//! takes a body below and rigid regions: with `q = (φ_low − U)⁺`, zero must lie between
//! `left = r + (Lp)·[U > φ] − (L_low q)·[U ≤ φ_low]` and `right = r + (Lp)·[U ≥ φ] − (L_low
//! q)·[U < φ_low]`, and 2e splits the net force between the two bodies ([`ContactForces`]).
//! Without a body below and rigid regions these are exactly the conditions above; the pass
//! then runs its original instantiation, at its original cost. Boundary heights enter
//! through `D` (the lifting). The largest violation, a force, is divided by the **force
//! scale of the iterate** `max(‖D‖∞, ‖SU‖∞, ‖Lp‖∞)`: the load and the elastic and
//! foundation forces actually present, never forces the iterate does not exert, so that no
//! iterate passes unless it balances the forces it carries.
//!
//! The **rounding floor** is what double precision can resolve: each residual component
//! is a sum whose terms have the size `Σⱼ|S_ij||U_j| + |D_i| + Σⱼ L_ij (|U_j| + |φ_j|)`;
//! rounding leaves an error of a few ulps of that. A residual at the floor is as good as
//! the data allow in this arithmetic.

use crate::model::{Body, FoundationMatrix, Model};
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

    /// The residual is within twice the rounding floor (`AT_FLOOR`): iterating further only
    /// moves the rounding errors around.
    pub fn at_floor(&self) -> bool {
        self.kkt() <= AT_FLOOR * self.rounding_floor
    }

    /// Within eight times the rounding floor (`NEAR_FLOOR`): a solve whose residual stops
    /// decreasing there has reached what the arithmetic allows.
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
    if model.is_extended() {
        evaluate_bodies::<true>(model, v)
    } else {
        evaluate_bodies::<false>(model, v)
    }
}

/// [`evaluate`] with the upper body's `(Lp)_i` computed by a closure per kind of L (the
/// inner loop is compiled once per kind). `EXT`: a body below or rigid regions
/// (docs/theory.md#extensions).
fn evaluate_bodies<const EXT: bool>(model: &Model, v: &[f64]) -> Evaluation {
    match &model.l {
        FoundationMatrix::Consistent(l) => evaluate_with::<EXT>(model, v, |_, s, e| {
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
        FoundationMatrix::Lumped(d) => evaluate_with::<EXT>(model, v, |i, _, _| {
            let pi = v[i] - model.phi[i];
            if model.can_touch[i] && pi > 0.0 {
                (d[i] * pi, d[i] * (v[i].abs() + model.phi[i].abs()))
            } else {
                (0.0, 0.0)
            }
        }),
        FoundationMatrix::Rigid => evaluate_with::<EXT>(model, v, |_, _, _| (0.0, 0.0)),
    }
}

/// The body below's `((L_low q)_i, Σⱼ L_low,ij (|U_j| + |φ_low,j|))` over the penetrating
/// j (`q = (φ_low − U)⁺`); its L shares the pattern of S.
#[inline]
fn lower_dot(body: &Body, v: &[f64], i: usize, s: usize, e: usize) -> (f64, f64) {
    match &body.l {
        FoundationMatrix::Consistent(l) => {
            let (mut lq, mut size) = (0.0, 0.0);
            for (&j, &lv) in l.pattern.col[s..e].iter().zip(&l.val[s..e]) {
                let j = j as usize;
                if lv != 0.0 && body.can_touch[j] {
                    let qj = body.phi[j] - v[j];
                    if qj > 0.0 {
                        lq += lv * qj;
                        size += lv * (v[j].abs() + body.phi[j].abs());
                    }
                }
            }
            (lq, size)
        }
        FoundationMatrix::Lumped(d) => {
            let qi = body.phi[i] - v[i];
            if body.can_touch[i] && qi > 0.0 {
                (d[i] * qi, d[i] * (v[i].abs() + body.phi[i].abs()))
            } else {
                (0.0, 0.0)
            }
        }
        FoundationMatrix::Rigid => (0.0, 0.0),
    }
}

/// One body at one vertex, for [`conditions`]: its surface, `(Lp)_i` (its elastic force),
/// whether it can touch the vertex and whether it holds it rigidly.
#[derive(Clone, Copy)]
struct Side {
    phi: f64,
    force: f64,
    active: bool,
    rigid: bool,
}

impl Side {
    const NONE: Side = Side {
        phi: 0.0,
        force: 0.0,
        active: false,
        rigid: false,
    };
}

/// The optimality conditions at a vertex that a body can touch
/// (docs/theory.md#second-body): the violations `(2f, 2e)` as forces. 2f: zero lies between
/// the left and right derivatives of J along the coordinate, `left = r + (Lp)·[U > φ] −
/// (L_low q)·[U ≤ φ_low]`, `right = r + (Lp)·[U ≥ φ] − (L_low q)·[U < φ_low]` (±∞ on the
/// far side of a rigid body at its surface; a rigid body violated counts the force `S_ii`
/// times the violation). 2e: the contact forces `X = X_up` (pushing down) and `X_low`
/// (pushing up) with `r + X − X_low = 0`, each ≥ 0, zero where its body is clear, and, for
/// an elastic body, at most its force `(Lp)_i` and equal to it where it penetrates. Without
/// a body below these are the paper's 2f and 2e with `X₁ = −r`, `X₂ = Lp + r`.
#[inline(always)]
fn conditions(r: f64, sii: f64, vi: f64, up: Side, low: Side) -> (f64, f64) {
    let up_el = up.active && !up.rigid;
    let low_el = low.active && !low.rigid;
    // Left and right derivatives of J along the coordinate.
    let mut left = r;
    let mut right = r;
    if up_el {
        if vi > up.phi {
            left += up.force;
        }
        if vi >= up.phi {
            right += up.force;
        }
    }
    if low_el {
        if vi <= low.phi {
            left -= low.force;
        }
        if vi < low.phi {
            right -= low.force;
        }
    }
    if up.active && up.rigid && vi == up.phi {
        right = f64::INFINITY;
    }
    if low.active && low.rigid && vi == low.phi {
        left = f64::NEG_INFINITY;
    }
    let mut f2 = left.max(-right).max(0.0);
    // A rigid body violated: the force that would push the vertex back.
    let mut infeasible = 0.0f64;
    if up.active && up.rigid && vi > up.phi {
        infeasible = sii * (vi - up.phi);
    }
    if low.active && low.rigid && vi < low.phi {
        infeasible = infeasible.max(sii * (low.phi - vi));
    }
    if infeasible > 0.0 {
        f2 = f2.max(infeasible);
    }
    // 2e: the contact forces of the two bodies.
    let pen_up = up_el && vi > up.phi;
    let pen_low = low_el && vi < low.phi;
    let (x, x_low) = split(r, vi, up, low);
    let mut e2 = (-x).max(0.0);
    if low.active {
        e2 = e2.max(-x_low);
    }
    if up_el {
        let x2 = up.force - x;
        e2 = e2.max(-x2);
        if pen_up {
            e2 = e2.max(x2.abs());
        }
    }
    if low_el {
        let y2 = low.force - x_low;
        e2 = e2.max(-y2);
        if pen_low {
            e2 = e2.max(y2.abs());
        }
    }
    e2 = e2.max((r + x - x_low).abs());
    if infeasible > 0.0 {
        e2 = e2.max(infeasible);
    }
    (f2, e2)
}

/// The contact forces of the two bodies at an iterate, over the unknowns: `up` pushing
/// down (the obstacle's, X₁ of 2e) and `low` pushing up (the body below's), with
/// `up − low = D − SU` where a body touches. Without a body below, `up = D − SU` on M
/// (the paper's X₁) and `low` is empty. With one, the net force `D − SU` is split by the
/// bodies' states: to the body in contact; where both are, the elastic force of a
/// penetrated body fixes its share, and between two bodies just touching each takes the
/// part pushing away from it.
#[derive(Debug, Clone)]
pub struct ContactForces {
    /// The obstacle's force on the membrane (positive downward).
    pub up: Vec<f64>,
    /// The body below's force (positive upward; empty without a body below).
    pub low: Vec<f64>,
}

/// The contact forces of `model` at `u` (see [`ContactForces`]).
pub fn contact_forces(model: &Model, u: &[f64]) -> ContactForces {
    let r = model.residual(u);
    let Some(low) = &model.lower else {
        let up = r
            .par_iter()
            .with_min_len(4096)
            .zip(&model.can_touch)
            .map(|(ri, &c)| if c { -ri } else { 0.0 })
            .collect();
        return ContactForces {
            up,
            low: Vec::new(),
        };
    };
    let p = model.penetration(u);
    let q = low.penetration(u);
    let mut lp = vec![0.0; model.n()];
    let mut lq = vec![0.0; model.n()];
    model.l.mul_into(&p, &mut lp);
    low.l.mul_into(&q, &mut lq);
    let mut up_f = vec![0.0; model.n()];
    let mut low_f = vec![0.0; model.n()];
    for i in 0..model.n() {
        let up = Side {
            phi: model.phi[i],
            force: lp[i],
            active: model.can_touch[i],
            rigid: model.rigid_at(i),
        };
        let down = Side {
            phi: low.phi[i],
            force: lq[i],
            active: low.can_touch[i],
            rigid: low.rigid_at(i),
        };
        let (x, x_low) = split(r[i], u[i], up, down);
        up_f[i] = x;
        low_f[i] = x_low;
    }
    ContactForces {
        up: up_f,
        low: low_f,
    }
}

/// The split of the net force `−r` between the two bodies at a vertex (see
/// [`ContactForces`]): `(X, X_low)` with `X − X_low = −r` where a body touches, zero for
/// a body clear of the vertex.
#[inline(always)]
fn split(r: f64, vi: f64, up: Side, low: Side) -> (f64, f64) {
    let clear_up = !up.active || vi < up.phi;
    let clear_low = !low.active || vi > low.phi;
    match (clear_up, clear_low) {
        (true, true) => (0.0, 0.0),
        (true, false) => (0.0, r),
        (false, true) => (-r, 0.0),
        (false, false) => {
            if up.active && !up.rigid && vi > up.phi {
                (up.force, up.force + r)
            } else if low.active && !low.rigid && vi < low.phi {
                (low.force - r, low.force)
            } else {
                ((-r).max(0.0), r.max(0.0))
            }
        }
    }
}

/// [`evaluate`] with `lp(i, row start, row end) = ((Lp)_i, Σⱼ L_ij(|U_j| + |φ_j|))` over
/// the penetrating j (S and a consistent L share their pattern).
fn evaluate_with<const EXT: bool>(
    model: &Model,
    v: &[f64],
    lp_of: impl Fn(usize, usize, usize) -> (f64, f64) + Sync,
) -> Evaluation {
    let n = model.n();
    let rigid = model.is_rigid();
    let pat = &model.s.pattern;
    let sval = &model.s.val;
    let lower = if EXT { model.lower.as_ref() } else { None };
    let block = |b: usize| -> Acc {
        let mut acc = Acc::default();
        let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(n));
        for i in lo..hi {
            let (s, e) = (pat.ptr(i), pat.ptr(i + 1));
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
            let mut up = Side {
                phi: fi,
                force: 0.0,
                active: model.can_touch[i],
                rigid: if EXT { model.rigid_at(i) } else { rigid },
            };
            let mut down = Side::NONE;
            if let Some(low) = lower {
                down = Side {
                    phi: low.phi[i],
                    force: 0.0,
                    active: low.can_touch[i],
                    rigid: low.rigid_at(i),
                };
            }
            let (violation_2f, violation_2e) = if up.active || down.active {
                if up.active {
                    let (lp, lsize) = lp_of(i, s, e);
                    size += lsize;
                    acc.scale = acc.scale.max(lp.abs());
                    acc.foundation += (vi - fi).max(0.0) * lp;
                    up.force = lp;
                }
                if down.active {
                    let low = lower.expect("a body below");
                    let (lq, qsize) = lower_dot(low, v, i, s, e);
                    size += qsize;
                    acc.scale = acc.scale.max(lq.abs());
                    acc.foundation += (down.phi - vi).max(0.0) * lq;
                    down.force = lq;
                }
                let touching = (up.active && vi == fi) || (down.active && vi == down.phi);
                let penetrating = (up.active && vi > fi) || (down.active && vi < down.phi);
                if touching {
                    acc.touching += 1;
                } else if penetrating {
                    acc.penetrating += 1;
                }
                if (up.active && up.rigid && vi > fi)
                    || (down.active && down.rigid && vi < down.phi)
                {
                    acc.infeasible = true;
                }
                conditions(r, sii, vi, up, down)
            } else {
                // Off M (and off the body below), no foundation acts: r = 0 (2f), and
                // X̂₁ = 0 there (2e).
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

impl Model {
    /// The optimality certificates of a candidate U (Problems 2e and 2f, scaled by the
    /// forces of U, with the energy and the rounding floor): see
    /// docs/theory.md#certificates.
    pub fn certificate(&self, u: &[f64]) -> Certificate {
        evaluate(self, u).certificate
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::test_square as square;
    use crate::model::{BodyStiffness, Foundation, ProblemData, Sampling};

    fn model(h: Option<f64>, f: f64, phi: f64, foundation: Foundation) -> Model {
        let mesh = square(8);
        let h = h.unwrap_or(0.0);
        let data = ProblemData {
            tension: 1.0,
            load: &f,
            shape: &phi,
            stiffness: if h > 0.0 {
                BodyStiffness::Elastic(&h)
            } else {
                BodyStiffness::Rigid
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
        let su = m.s.mul(&v);
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
