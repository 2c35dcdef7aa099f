//! The axisymmetric disc (docs/theory.md#axisymmetric-disc): elastic and rigid, every
//! contact regime.

use super::bessel::{brent, ratio_i2_i0, ratios};
use super::solution::ExactSolution;
use crate::error::{Error, Result};
use spec_math::cephes64::i0e;
use std::f64::consts::PI;

/// Which closed form a [`DiskSolution`] uses, decided from the data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DiskRegime {
    /// No reaction anywhere: `u = f (R² - r²)/(4t)` (h = 0, or the free membrane stays
    /// clear of the obstacle).
    NoContact,
    /// Elastic obstacle, contact disc `r < a` with `0 < a < R`.
    ContactDisc,
    /// Elastic obstacle, the membrane penetrates on the whole open disc (`a = R`).
    FullContact,
    /// Rigid obstacle (`h = ∞`), coincidence set `u = φ` on `r ≤ a`, `0 < a ≤ R`.
    Rigid,
}

/// The axisymmetric solution of Problem 1 on the disc `|x - c| < R` with constant `t > 0`,
/// `f`, `h ≥ 0` (or `h = ∞`, the rigid obstacle) and `φ`
/// (docs/theory.md#axisymmetric-disc).
///
/// With `r = |x - c|`, `k = √(h/t)`, `ψ = 4tφ/f` and the free deflection
/// `u₀(r) = f (R² - r²)/(4t)`, the regime is decided from the data:
///
/// * **no contact** ([`DiskRegime::NoContact`]) when `h = 0`, or `φ ≥ 0` and `f ≤ 0`, or
///   `0 < f R²/(4t) ≤ φ`: `u = u₀`;
/// * **contact disc** ([`DiskRegime::ContactDisc`]) when `h > 0` finite, `φ > 0` and
///   `f R²/(4t) > φ`: `u = φ + f/h + C I₀(kr)` for `r < a`,
///   `u = u₀(r) + B ln(r/R)` for `a ≤ r ≤ R`, with `u(a∓) = φ`, `u'(a⁻) = u'(a⁺)`, hence
///   `C = -(f/h) / I₀(ka)`, `B = f a² I₂(ka) / (2t I₀(ka))`, and `a` the unique root in
///   `(0, R)` of
///   `H(a) = R² - a² - ψ + 2 a² ln(a/R) I₂(ka)/I₀(ka) = 0`
///   (`H(0⁺) = R² - ψ > 0`, `H(R) = -ψ < 0`); see [`DiskSolution::new`];
/// * **full contact** ([`DiskRegime::FullContact`]) when `h > 0` finite and either `φ = 0 < f`
///   or `φ < 0` and `f (I₀(kR) - 1) ≥ h φ` (i.e. `u(0) ≥ φ`):
///   `u = φ + f/h - (φ + f/h) I₀(kr)/I₀(kR)`, `a = R`;
/// * **rigid** ([`DiskRegime::Rigid`], `h = ∞`) when `φ ≥ 0` and `f R²/(4t) > φ`: `u = φ` for
///   `r < a`, `u = u₀ + B ln(r/R)` outside with `B = f a²/(2t)` and `a` the root of
///   `R² - a² + 2a² ln(a/R) = ψ` (the `k → ∞` limit of `H`; `a = R`, `u ≡ 0` when `φ = 0`).
///
/// Not supported (an [`Error::Data`]): the rigid obstacle with `φ < 0` (no admissible
/// function: `u = 0 > φ` on ∂Ω), and the elastic annular-contact case `φ < 0`, `f < 0`,
/// `f (I₀(kR) - 1) < hφ`, where the membrane hangs free below the obstacle in a central disc
/// and touches it only in an annulus (its closed form needs K₀ and is not implemented).
///
/// All Bessel functions are exponentially scaled, so `k R` up to 1e300 works; for small
/// `k R` (≤ 2) power series avoid the cancellation of `1 - I₀(kr)/I₀(ka)`.
#[derive(Debug, Clone)]
pub struct DiskSolution {
    pub(super) center: [f64; 2],
    pub(super) radius: f64,
    pub(super) t: f64,
    pub(super) f: f64,
    pub(super) h: f64,
    pub(super) phi: f64,
    pub(super) regime: DiskRegime,
    pub(super) k: f64,
    pub(super) a: f64,
    pub(super) b: f64,
    pub(super) c_scaled: f64,
}

impl DiskSolution {
    /// Builds the solution for the disc `(center, radius)`, tension `t`, load `f`, foundation
    /// stiffness `h` (`None` or `Some(∞)`: rigid obstacle) and obstacle height `φ`; solves
    /// `H(a) = 0` (see [`DiskSolution`]) by Brent's method to machine precision.
    ///
    /// Errors ([`Error::Data`]): non-finite centre, `radius ≤ 0`, `t ≤ 0`, non-finite `f` or
    /// `φ`, `h < 0` or NaN, and the unsupported cases listed on [`DiskSolution`].
    pub fn new(
        center: [f64; 2],
        radius: f64,
        t: f64,
        f: f64,
        h: Option<f64>,
        phi: f64,
    ) -> Result<DiskSolution> {
        if !(center[0].is_finite() && center[1].is_finite()) {
            return Err(Error::Data(format!(
                "disc centre ({}, {}) must be finite",
                center[0], center[1]
            )));
        }
        if !(radius > 0.0 && radius.is_finite()) {
            return Err(Error::Data(format!(
                "disc radius R = {radius} must be finite and > 0"
            )));
        }
        if !(t > 0.0 && t.is_finite()) {
            return Err(Error::Data(format!(
                "tension t = {t} must be finite and > 0"
            )));
        }
        if !f.is_finite() {
            return Err(Error::Data(format!("load f = {f} must be finite")));
        }
        if !phi.is_finite() {
            return Err(Error::Data(format!("obstacle φ = {phi} must be finite")));
        }
        let h = h.unwrap_or(f64::INFINITY);
        if h.is_nan() || h < 0.0 {
            return Err(Error::Data(format!(
                "foundation stiffness h = {h} must be ≥ 0 (None for the rigid obstacle)"
            )));
        }
        let r = radius;
        let mut s = DiskSolution {
            center,
            radius,
            t,
            f,
            h,
            phi,
            regime: DiskRegime::NoContact,
            k: (h / t).sqrt(),
            a: 0.0,
            b: 0.0,
            c_scaled: 0.0,
        };
        let free_max = f * r * r / (4.0 * t); // u₀(0)
        if h.is_infinite() {
            if phi < 0.0 {
                return Err(Error::Data(format!(
                    "rigid obstacle with φ = {phi} < 0: no deflection vanishing on the \
                     boundary satisfies u ≤ φ"
                )));
            }
            if f <= 0.0 || free_max <= phi {
                return Ok(s);
            }
            // R² - a² + 2a² ln(a/R) = ψ, in s = a/R: 1 - s² + 2 s² ln s - ψ/R² = 0.
            let psi = 4.0 * t * phi / (f * r * r);
            let a = if phi == 0.0 {
                r
            } else {
                let g = |x: f64| {
                    if x == 0.0 {
                        1.0 - psi
                    } else {
                        1.0 - x * x + 2.0 * x * x * x.ln() - psi
                    }
                };
                r * brent(g, 0.0, 1.0, 1.0 - psi, -psi)
            };
            s.regime = DiskRegime::Rigid;
            s.a = a;
            s.b = f * a * a / (2.0 * t);
            return Ok(s);
        }
        if h == 0.0 || (phi >= 0.0 && (f <= 0.0 || free_max <= phi)) {
            return Ok(s);
        }
        let k = s.k;
        if phi > 0.0 {
            // f > 0 and u₀(0) > φ: a contact disc 0 < a < R.
            let psi = 4.0 * t * phi / (f * r * r);
            let g = |x: f64| {
                if x == 0.0 {
                    1.0 - psi
                } else {
                    1.0 - x * x - psi + 2.0 * x * x * x.ln() * ratio_i2_i0(k * r * x)
                }
            };
            let a = r * brent(g, 0.0, 1.0, 1.0 - psi, -psi);
            s.regime = DiskRegime::ContactDisc;
            s.a = a;
            s.b = f * a * a * ratio_i2_i0(k * a) / (2.0 * t);
            s.c_scaled = -f / h;
            return Ok(s);
        }
        // φ ≤ 0 and (φ < 0 or f > 0): the membrane penetrates near the boundary. Full
        // contact iff the full-contact formula has u(0) ≥ φ, i.e. f (I₀(kR) - 1) ≥ hφ,
        // evaluated divided by I₀(kR): f (1 - 1/I₀(kR)) ≥ hφ / I₀(kR).
        let inv_i0 = (-k * r).exp() / i0e(k * r); // 1/I₀(kR)
        let one_minus = k * k * ratios(k, r, 0.0).w; // 1 - 1/I₀(kR), accurate for small kR
        if f * one_minus >= h * phi * inv_i0 {
            s.regime = DiskRegime::FullContact;
            s.a = r;
            s.c_scaled = -(phi + f / h);
            return Ok(s);
        }
        Err(Error::Data(format!(
            "disc with φ = {phi} < 0 and f = {f} < 0 (h = {h}, t = {t}, R = {r}): the membrane \
             touches the obstacle only in an annulus near the boundary; this case has no \
             closed form here"
        )))
    }

    /// The regime decided from the data.
    pub fn regime(&self) -> DiskRegime {
        self.regime
    }

    /// The contact radius `a` (`0` without contact, `R` in full contact).
    pub fn a(&self) -> f64 {
        self.a
    }

    /// `k = √(h/t)` (`∞` for the rigid obstacle).
    pub fn k(&self) -> f64 {
        self.k
    }

    /// The coefficient `B` of `ln(r/R)` in the outer solution `u₀(r) + B ln(r/R)`
    /// (`0` without contact; irrelevant in full contact).
    pub fn b(&self) -> f64 {
        self.b
    }

    /// The coefficient `C` of `I₀(kr)` in the inner solution `φ + f/h + C I₀(kr)`:
    /// `C = -(f/h)/I₀(ka)` (contact disc) or `-(φ + f/h)/I₀(kR)` (full contact), `0`
    /// otherwise. Underflows to 0 for `k a ≳ 700`: use [`DiskSolution::c_scaled`].
    pub fn c(&self) -> f64 {
        if self.c_scaled == 0.0 {
            return 0.0;
        }
        let x = self.k * self.a;
        self.c_scaled * (-x).exp() / i0e(x)
    }

    /// `C I₀(ka)`: `-f/h` (contact disc), `-(φ + f/h)` (full contact), `0` otherwise.
    pub fn c_scaled(&self) -> f64 {
        self.c_scaled
    }

    /// The disc radius `R`.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The disc centre.
    pub fn center(&self) -> [f64; 2] {
        self.center
    }

    /// The radial profile at `r ≥ 0`: `[u(r), u'(r), u''(r)]`, from the closed forms
    /// (`d/dr I₀ = I₁`, `d/dr I₁(kr) = k (I₀(kr) - I₁(kr)/(kr))`).
    pub fn radial(&self, r: f64) -> [f64; 3] {
        let (t, f, phi) = (self.t, self.f, self.phi);
        match self.regime {
            DiskRegime::NoContact => self.outer(r),
            DiskRegime::ContactDisc | DiskRegime::Rigid if r >= self.a => self.outer(r),
            DiskRegime::Rigid => [phi, 0.0, 0.0],
            DiskRegime::ContactDisc => {
                let q = ratios(self.k, self.a, r);
                [phi + f / t * q.w, -f / t * q.q1, -f / t * q.q2]
            }
            DiskRegime::FullContact => {
                let q = ratios(self.k, self.radius, r);
                let m = (f + self.h * phi) / t;
                [phi + f / t * q.w - phi * q.g0, -m * q.q1, -m * q.q2]
            }
        }
    }

    /// The outer closed form `u₀(r) + B ln(r/R)` with its first two derivatives.
    pub(super) fn outer(&self, r: f64) -> [f64; 3] {
        let (t, f, big_r, b) = (self.t, self.f, self.radius, self.b);
        let free = f * (big_r - r) * (big_r + r) / (4.0 * t);
        if b == 0.0 {
            return [free, -f * r / (2.0 * t), -f / (2.0 * t)];
        }
        [
            free + b * (r / big_r).ln(),
            -f * r / (2.0 * t) + b / r,
            -f / (2.0 * t) - b / (r * r),
        ]
    }

    /// The Laplacian as a function of r: `-f/t` where the obstacle does not react,
    /// `(h (u - φ) - f)/t` in the contact region, `0` on the rigid coincidence set.
    pub(super) fn radial_laplacian(&self, r: f64) -> f64 {
        let (t, f) = (self.t, self.f);
        match self.regime {
            DiskRegime::NoContact => -f / t,
            DiskRegime::ContactDisc | DiskRegime::Rigid if r >= self.a => -f / t,
            DiskRegime::Rigid => 0.0,
            DiskRegime::ContactDisc => -f / t * ratios(self.k, self.a, r).g0,
            DiskRegime::FullContact => {
                -(f + self.h * self.phi) / t * ratios(self.k, self.radius, r).g0
            }
        }
    }

    pub(super) fn polar(&self, p: [f64; 2]) -> (f64, [f64; 2]) {
        let (dx, dy) = (p[0] - self.center[0], p[1] - self.center[1]);
        (dx.hypot(dy), [dx, dy])
    }
}

impl ExactSolution for DiskSolution {
    fn value(&self, p: [f64; 2]) -> f64 {
        self.radial(self.polar(p).0)[0]
    }

    fn gradient(&self, p: [f64; 2]) -> [f64; 2] {
        let (r, d) = self.polar(p);
        if r == 0.0 {
            return [0.0, 0.0];
        }
        let du = self.radial(r)[1];
        [du * d[0] / r, du * d[1] / r]
    }

    fn laplacian(&self, p: [f64; 2]) -> f64 {
        self.radial_laplacian(self.polar(p).0)
    }

    fn contact_radius(&self) -> Option<f64> {
        Some(self.a)
    }

    fn contact_area(&self) -> Option<f64> {
        Some(PI * self.a * self.a)
    }

    fn contains(&self, p: [f64; 2]) -> bool {
        self.polar(p).0 <= self.radius * (1.0 + 1e-10)
    }

    fn disk(&self) -> Option<([f64; 2], f64)> {
        Some((self.center, self.radius))
    }

    fn describe(&self) -> String {
        let h = if self.h.is_infinite() {
            "∞ (rigid)".to_string()
        } else {
            format!("{}", self.h)
        };
        format!(
            "axisymmetric disc (centre ({}, {}), R = {}), t = {}, f = {}, h = {}, φ = {}: \
             {:?}, contact radius a = {}",
            self.center[0],
            self.center[1],
            self.radius,
            self.t,
            self.f,
            h,
            self.phi,
            self.regime,
            self.a
        )
    }
}
