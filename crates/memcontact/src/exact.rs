//! Closed-form solutions of Problem 1 (SPEC §1 and §4), for verification.
//!
//! Problem 1 is `-t Δu + h (u - φ)⁺ = f` in Ω, `u = 0` on ∂Ω. Two families are provided:
//!
//! * [`DiskSolution`]: the axisymmetric solution on a disc with constant data `t`, `f`, `h`,
//!   `φ` (SPEC §4, "Axisymmetric disc"), for the elastic obstacle (`0 ≤ h < ∞`) and for the
//!   rigid limit `h = ∞` (the classical obstacle problem `u ≤ φ`);
//! * [`Manufactured`]: smooth functions vanishing on ∂Ω with exact gradient and Laplacian,
//!   from which the caller builds the load `f = -t Δu + h (u - φ)⁺` (SPEC §4,
//!   "Manufactured solutions"); [`manufactured_load`] does it at a point.
//!
//! Every solution knows its domain Ω ([`ExactSolution::contains`]); evaluating outside Ω is
//! the caller's error and must be checked by the caller (the error norms of
//! [`crate::errors`] do).

use crate::error::{Error, Result};
use spec_math::cephes64::{i0, i0e, i1e};
use std::f64::consts::PI;

/// A closed-form solution `u` of Problem 1 on a known domain Ω.
///
/// `value`, `gradient` and `laplacian` may only be called at points `p` with
/// `contains(p) == true`; the result elsewhere is unspecified (an analytic continuation).
pub trait ExactSolution: Send + Sync {
    /// The deflection `u(p)`.
    fn value(&self, p: [f64; 2]) -> f64;
    /// The gradient `∇u(p)`.
    fn gradient(&self, p: [f64; 2]) -> [f64; 2];
    /// The Laplacian `Δu(p)` (a.e.: on the contact circle of a [`DiskSolution`], where
    /// `Δu` jumps, either one-sided value).
    fn laplacian(&self, p: [f64; 2]) -> f64;
    /// The radius of the contact disc (the set where the obstacle reacts), when the
    /// solution knows it.
    fn contact_radius(&self) -> Option<f64> {
        None
    }
    /// The area of the contact set, when the solution knows it.
    fn contact_area(&self) -> Option<f64> {
        None
    }
    /// Whether `p` lies in the closure of Ω (with a relative tolerance of about 1e-10 of
    /// the domain's size, so that mesh vertices placed on a curved boundary count).
    fn contains(&self, p: [f64; 2]) -> bool;
    /// The domain when it is a disc: `(centre, radius)`. `None` for other domains.
    fn disk(&self) -> Option<([f64; 2], f64)> {
        None
    }
    /// A one-line human description (kind of solution, parameters, regime).
    fn describe(&self) -> String;
}

/// The load of a manufactured solution at a point: `f(p) = -t Δu(p) + h (u(p) - φ)⁺`
/// (Problem 1 read from left to right), exact (no finite differences).
///
/// Errors: `t ≤ 0`, `h < 0` or a non-finite datum, or `p` outside Ω.
pub fn manufactured_load(
    sol: &dyn ExactSolution,
    p: [f64; 2],
    t: f64,
    h: f64,
    phi: f64,
) -> Result<f64> {
    if !(t > 0.0 && t.is_finite()) {
        return Err(Error::Data(format!(
            "tension t = {t} must be finite and > 0"
        )));
    }
    if !(h >= 0.0 && h.is_finite()) {
        return Err(Error::Data(format!(
            "foundation stiffness h = {h} must be finite and ≥ 0"
        )));
    }
    if !phi.is_finite() {
        return Err(Error::Data(format!("obstacle φ = {phi} must be finite")));
    }
    if !sol.contains(p) {
        return Err(Error::Data(format!(
            "point ({}, {}) lies outside the domain of {}",
            p[0],
            p[1],
            sol.describe()
        )));
    }
    let u = sol.value(p);
    Ok(-t * sol.laplacian(p) + h * (u - phi).max(0.0))
}

// ---------------------------------------------------------------------------------------
// Bessel helpers. All work with exponentially scaled functions so that arguments up to
// k·R ~ 1e300 neither overflow nor lose accuracy.

/// `e^{-x} I₁(x) / x`, with its limit 1/2 at 0 (x ≥ 0).
fn i1_over_x_e(x: f64) -> f64 {
    if x < 1e-150 {
        0.5
    } else {
        i1e(x) / x
    }
}

/// `I₂(x) / I₀(x)` for x ≥ 0, without the cancellation of `1 - 2 I₁/(x I₀)` at small x
/// (the recurrence `x I₀ - 2 I₁ = x I₂`).
fn ratio_i2_i0(x: f64) -> f64 {
    if x.is_infinite() {
        return 1.0;
    }
    if x <= 2.0 {
        // I₂(x) = Σ_{m≥0} (x/2)^{2m+2} / (m! (m+2)!)
        let q = 0.25 * x * x;
        let mut term = 0.5 * q;
        let mut sum = 0.0;
        for m in 0..40 {
            sum += term;
            if term <= 1e-18 * sum {
                break;
            }
            let m = m as f64;
            term *= q / ((m + 1.0) * (m + 3.0));
        }
        sum / i0(x)
    } else {
        1.0 - 2.0 * i1_over_x_e(x) / i0e(x)
    }
}

/// Ratios of Bessel functions at radius `r` against a reference radius `a`
/// (the contact radius, or R):
/// `g0 = I₀(kr)/I₀(ka)`, `q1 = I₁(kr) / (k I₀(ka))`, `q2 = (I₀(kr) - I₁(kr)/(kr)) / I₀(ka)`,
/// and `w = (1 - g0) / k²`, all evaluated without overflow and, for `w`, without the
/// cancellation of `1 - g0` when `k a` is small (power series of `I₀(ka) - I₀(kr)`).
#[derive(Debug, Clone, Copy)]
struct Ratios {
    g0: f64,
    q1: f64,
    q2: f64,
    w: f64,
}

fn ratios(k: f64, a: f64, r: f64) -> Ratios {
    let (x, y) = (k * a, k * r);
    let scale = (k * (r - a)).exp() / i0e(x);
    let g0 = i0e(y) * scale;
    let q1 = r * i1_over_x_e(y) * scale;
    let q2 = (i0e(y) - i1_over_x_e(y)) * scale;
    let w = if x <= 2.0 {
        // (I₀(ka) - I₀(kr)) / k² = Σ_{m≥1} (k²/4)^{m-1} (a^{2m} - r^{2m}) / (4 (m!)²),
        // with a^{2m} - r^{2m} = (a² - r²) s_m, s_1 = 1, s_{m+1} = a² s_m + r^{2m}.
        let q = 0.25 * k * k;
        let (a2, r2) = (a * a, r * r);
        let mut s = 1.0f64;
        let mut r2m = r2;
        let mut coef = 1.0f64;
        let mut sum = 0.0f64;
        for m in 1..60 {
            let term = coef * s;
            sum += term;
            if term.abs() <= 1e-18 * sum.abs() {
                break;
            }
            s = a2 * s + r2m;
            r2m *= r2;
            let m1 = (m + 1) as f64;
            coef *= q / (m1 * m1);
        }
        (a - r) * (a + r) * sum / (4.0 * i0(x))
    } else {
        (1.0 - g0) / (k * k)
    };
    Ratios { g0, q1, q2, w }
}

/// Brent's bracketing root finder (zeroin): `f(lo)` and `f(hi)` have opposite signs; returns
/// a root to about four units in the last place.
fn brent(f: impl Fn(f64) -> f64, lo: f64, hi: f64, flo: f64, fhi: f64) -> f64 {
    let (mut a, mut b, mut fa, mut fb) = (lo, hi, flo, fhi);
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    for _ in 0..1000 {
        if (fb > 0.0 && fc > 0.0) || (fb < 0.0 && fc < 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol = 2.0 * f64::EPSILON * b.abs() + 1e-300;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol || fb == 0.0 {
            return b;
        }
        if e.abs() >= tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qa = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qa * (qa - r) - (b - a) * (r - 1.0));
                q = (qa - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * xm * q - (tol * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol { d } else { tol.copysign(xm) };
        fb = f(b);
    }
    b
}

// ---------------------------------------------------------------------------------------

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
/// `f`, `h ≥ 0` (or `h = ∞`, the rigid obstacle) and `φ` (SPEC §4).
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
    center: [f64; 2],
    radius: f64,
    t: f64,
    f: f64,
    h: f64,
    phi: f64,
    regime: DiskRegime,
    k: f64,
    a: f64,
    b: f64,
    c_scaled: f64,
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
    fn outer(&self, r: f64) -> [f64; 3] {
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
    fn radial_laplacian(&self, r: f64) -> f64 {
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

    fn polar(&self, p: [f64; 2]) -> (f64, [f64; 2]) {
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

// ---------------------------------------------------------------------------------------

#[derive(Debug, Clone, Copy)]
enum Shape {
    Rectangle { x0: f64, y0: f64, x1: f64, y1: f64 },
    Disk { center: [f64; 2], radius: f64 },
}

/// Manufactured solutions (SPEC §4): smooth functions vanishing on ∂Ω, with exact gradient
/// and Laplacian. The caller sets `f = -t Δu + h (u - φ)⁺` (see [`manufactured_load`]).
#[derive(Debug, Clone, Copy)]
pub struct Manufactured {
    shape: Shape,
    amplitude: f64,
}

impl Manufactured {
    /// On the rectangle `[x0, x1] × [y0, y1]`:
    /// `u = A sin(π (x - x0)/(x1 - x0)) sin(π (y - y0)/(y1 - y0))`,
    /// `Δu = -π² (1/(x1-x0)² + 1/(y1-y0)²) u`.
    ///
    /// Errors: non-finite data, `x1 ≤ x0` or `y1 ≤ y0`.
    pub fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64, amplitude: f64) -> Result<Manufactured> {
        if ![x0, y0, x1, y1, amplitude].iter().all(|v| v.is_finite()) {
            return Err(Error::Data(format!(
                "manufactured rectangle [{x0}, {x1}] × [{y0}, {y1}], amplitude {amplitude}: \
                 data must be finite"
            )));
        }
        if x1 <= x0 || y1 <= y0 {
            return Err(Error::Data(format!(
                "manufactured rectangle [{x0}, {x1}] × [{y0}, {y1}] is empty"
            )));
        }
        Ok(Manufactured {
            shape: Shape::Rectangle { x0, y0, x1, y1 },
            amplitude,
        })
    }

    /// On the disc `|x - c| < R`, with `X = (x - cx)/R`, `Y = (y - cy)/R`:
    /// `u = A (1 - X² - Y²)(1 + X/2)` (not radial), `Δu = -4A (1 + X)/R²`.
    ///
    /// Errors: non-finite data or `radius ≤ 0`.
    pub fn disk(center: [f64; 2], radius: f64, amplitude: f64) -> Result<Manufactured> {
        if ![center[0], center[1], radius, amplitude]
            .iter()
            .all(|v| v.is_finite())
            || radius <= 0.0
        {
            return Err(Error::Data(format!(
                "manufactured disc centre ({}, {}), radius {radius}, amplitude {amplitude}: \
                 data must be finite and the radius > 0",
                center[0], center[1]
            )));
        }
        Ok(Manufactured {
            shape: Shape::Disk { center, radius },
            amplitude,
        })
    }
}

impl ExactSolution for Manufactured {
    fn value(&self, p: [f64; 2]) -> f64 {
        let a = self.amplitude;
        match self.shape {
            Shape::Rectangle { x0, y0, x1, y1 } => {
                let (sx, sy) = (
                    (PI * (p[0] - x0) / (x1 - x0)).sin(),
                    (PI * (p[1] - y0) / (y1 - y0)).sin(),
                );
                a * sx * sy
            }
            Shape::Disk { center, radius } => {
                let (x, y) = ((p[0] - center[0]) / radius, (p[1] - center[1]) / radius);
                a * (1.0 - x * x - y * y) * (1.0 + 0.5 * x)
            }
        }
    }

    fn gradient(&self, p: [f64; 2]) -> [f64; 2] {
        let a = self.amplitude;
        match self.shape {
            Shape::Rectangle { x0, y0, x1, y1 } => {
                let (lx, ly) = (x1 - x0, y1 - y0);
                let (ax, ay) = (PI * (p[0] - x0) / lx, PI * (p[1] - y0) / ly);
                [
                    a * PI / lx * ax.cos() * ay.sin(),
                    a * PI / ly * ax.sin() * ay.cos(),
                ]
            }
            Shape::Disk { center, radius } => {
                let (x, y) = ((p[0] - center[0]) / radius, (p[1] - center[1]) / radius);
                [
                    a * (0.5 - 2.0 * x - 0.5 * (3.0 * x * x + y * y)) / radius,
                    a * (-2.0 * y - x * y) / radius,
                ]
            }
        }
    }

    fn laplacian(&self, p: [f64; 2]) -> f64 {
        let a = self.amplitude;
        match self.shape {
            Shape::Rectangle { x0, y0, x1, y1 } => {
                let (lx, ly) = (x1 - x0, y1 - y0);
                -PI * PI * (1.0 / (lx * lx) + 1.0 / (ly * ly)) * self.value(p)
            }
            Shape::Disk { center, radius } => {
                let x = (p[0] - center[0]) / radius;
                -4.0 * a * (1.0 + x) / (radius * radius)
            }
        }
    }

    fn contains(&self, p: [f64; 2]) -> bool {
        match self.shape {
            Shape::Rectangle { x0, y0, x1, y1 } => {
                let tol = 1e-10 * (x1 - x0).max(y1 - y0);
                p[0] >= x0 - tol && p[0] <= x1 + tol && p[1] >= y0 - tol && p[1] <= y1 + tol
            }
            Shape::Disk { center, radius } => {
                (p[0] - center[0]).hypot(p[1] - center[1]) <= radius * (1.0 + 1e-10)
            }
        }
    }

    fn disk(&self) -> Option<([f64; 2], f64)> {
        match self.shape {
            Shape::Disk { center, radius } => Some((center, radius)),
            Shape::Rectangle { .. } => None,
        }
    }

    fn describe(&self) -> String {
        match self.shape {
            Shape::Rectangle { x0, y0, x1, y1 } => format!(
                "manufactured A sin sin on [{x0}, {x1}] × [{y0}, {y1}], A = {}",
                self.amplitude
            ),
            Shape::Disk { center, radius } => format!(
                "manufactured A (1 - r²/R²)(1 + (x - cx)/(2R)) on the disc (centre ({}, {}), \
                 R = {radius}), A = {}",
                center[0], center[1], self.amplitude
            ),
        }
    }
}

// ---------------------------------------------------------------------------------------

/// PETSc SNES ex9's contact radius `a` (SPEC §5): where `√(1 − a²)` meets `−A ln a + B`
/// with matching slopes.
pub const EX9_RADIUS: f64 = 0.697965148223374;

/// The radius where PETSc SNES ex9's obstacle turns from the sphere to its tangent line.
pub const EX9_KNEE: f64 = 0.9;

/// The classical radial obstacle benchmarks (SPEC §5): a rigid spherical cap with a
/// conical skirt, `f = 0`, t = 1, the membrane lying on the cap for `r ≤ a` and harmonic
/// beyond.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BenchmarkKind {
    /// PETSc SNES ex9: Ω = (−2, 2)², `ψ = √(1 − r²)` for `r ≤ 0.9` and its tangent line
    /// beyond, `u = ψ` for `r ≤ a`, `u = −A ln r + B` beyond, `A = a²/√(1 − a²)`,
    /// `B = A ln 2`, `g = u` on ∂Ω.
    PetscEx9,
    /// MFEM ex36: the same problem scaled by ½ onto the unit disc (`g = 0` on the circle).
    MfemEx36,
}

/// A radial obstacle benchmark ([`BenchmarkKind`]) in either sign convention: the body
/// below as in the benchmark (`u ≥ ψ`, `sign = 1`), or this project's obstacle above
/// (`u ≤ φ = −ψ`, the solution `−u`, `sign = −1`).
#[derive(Debug, Clone, Copy)]
pub struct ObstacleBenchmark {
    kind: BenchmarkKind,
    /// 1 for ex9, ½ for ex36: `u(r) = s u₉(r / s)`.
    scale: f64,
    sign: f64,
}

impl ObstacleBenchmark {
    /// The benchmark `kind`; `below = true` for the body below (the benchmark's own
    /// convention), `false` for the obstacle above (the solution and obstacle negated).
    pub fn new(kind: BenchmarkKind, below: bool) -> ObstacleBenchmark {
        ObstacleBenchmark {
            kind,
            scale: match kind {
                BenchmarkKind::PetscEx9 => 1.0,
                BenchmarkKind::MfemEx36 => 0.5,
            },
            sign: if below { 1.0 } else { -1.0 },
        }
    }

    /// `A = a²/√(1 − a²)` of ex9.
    fn big_a() -> f64 {
        EX9_RADIUS * EX9_RADIUS / (1.0 - EX9_RADIUS * EX9_RADIUS).sqrt()
    }

    /// ex9's radial profile at ρ: `[u, u', Δu]`.
    fn profile(rho: f64) -> [f64; 3] {
        let a = EX9_RADIUS;
        if rho <= a {
            let w = 1.0 - rho * rho;
            [
                w.sqrt(),
                -rho / w.sqrt(),
                -(2.0 - rho * rho) / (w * w.sqrt()),
            ]
        } else {
            let big_a = Self::big_a();
            [big_a * (2.0 / rho).ln(), -big_a / rho, 0.0]
        }
    }

    /// ex9's obstacle ψ at ρ: the sphere, then its tangent line beyond 0.9.
    pub fn ex9_obstacle(rho: f64) -> f64 {
        let k = EX9_KNEE;
        if rho <= k {
            (1.0 - rho * rho).sqrt()
        } else {
            let c = (1.0 - k * k).sqrt();
            c - k / c * (rho - k)
        }
    }

    /// The body's surface at `p` in this convention: `ψ` below, `φ = −ψ` above.
    pub fn surface(&self, p: [f64; 2]) -> f64 {
        let s = self.scale;
        self.sign * s * Self::ex9_obstacle(p[0].hypot(p[1]) / s)
    }

    /// `true` for the convention of the body below.
    pub fn below(&self) -> bool {
        self.sign > 0.0
    }

    /// Which benchmark.
    pub fn kind(&self) -> BenchmarkKind {
        self.kind
    }
}

impl ExactSolution for ObstacleBenchmark {
    fn value(&self, p: [f64; 2]) -> f64 {
        let s = self.scale;
        self.sign * s * Self::profile(p[0].hypot(p[1]) / s)[0]
    }

    fn gradient(&self, p: [f64; 2]) -> [f64; 2] {
        let r = p[0].hypot(p[1]);
        if r == 0.0 {
            return [0.0, 0.0];
        }
        let du = self.sign * Self::profile(r / self.scale)[1];
        [du * p[0] / r, du * p[1] / r]
    }

    fn laplacian(&self, p: [f64; 2]) -> f64 {
        self.sign * Self::profile(p[0].hypot(p[1]) / self.scale)[2] / self.scale
    }

    fn contact_radius(&self) -> Option<f64> {
        Some(self.scale * EX9_RADIUS)
    }

    fn contact_area(&self) -> Option<f64> {
        let a = self.scale * EX9_RADIUS;
        Some(PI * a * a)
    }

    fn contains(&self, p: [f64; 2]) -> bool {
        match self.kind {
            BenchmarkKind::PetscEx9 => {
                let tol = 2.0 + 4e-10;
                p[0].abs() <= tol && p[1].abs() <= tol
            }
            BenchmarkKind::MfemEx36 => p[0].hypot(p[1]) <= 1.0 + 1e-10,
        }
    }

    fn disk(&self) -> Option<([f64; 2], f64)> {
        match self.kind {
            BenchmarkKind::PetscEx9 => None,
            BenchmarkKind::MfemEx36 => Some(([0.0, 0.0], 1.0)),
        }
    }

    fn describe(&self) -> String {
        let (name, domain) = match self.kind {
            BenchmarkKind::PetscEx9 => ("PETSc SNES ex9", "(−2, 2)², g = u on the boundary"),
            BenchmarkKind::MfemEx36 => ("MFEM ex36", "the unit disc, g = 0"),
        };
        let convention = if self.below() {
            "rigid body below, u ≥ ψ"
        } else {
            "rigid obstacle above, u ≤ φ = −ψ (the solution negated)"
        };
        format!(
            "{name}: f = 0, t = 1 on {domain}; {convention}; contact radius a = {}",
            self.scale * EX9_RADIUS
        )
    }
}

/// A manufactured solution with zero normal derivative on every side of a rectangle, so
/// that any side may be free (the natural condition holds there) and the others fixed at
/// `g = u`: `u = A (cos(πX) cos(πY) + ½ cos(2πY))` with `X = (x − x0)/(x1 − x0)`,
/// `Y = (y − y0)/(y1 − y0)`; `u` ranges over `[−¾A, 3/2 A]`.
#[derive(Debug, Clone, Copy)]
pub struct ManufacturedCosine {
    x0: f64,
    y0: f64,
    lx: f64,
    ly: f64,
    amplitude: f64,
}

impl ManufacturedCosine {
    /// On the rectangle `[x0, x1] × [y0, y1]`. Errors: non-finite data, an empty rectangle.
    pub fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64, amplitude: f64) -> Result<Self> {
        Manufactured::rectangle(x0, y0, x1, y1, amplitude)?;
        Ok(ManufacturedCosine {
            x0,
            y0,
            lx: x1 - x0,
            ly: y1 - y0,
            amplitude,
        })
    }
}

impl ExactSolution for ManufacturedCosine {
    fn value(&self, p: [f64; 2]) -> f64 {
        let (ax, ay) = (
            PI * (p[0] - self.x0) / self.lx,
            PI * (p[1] - self.y0) / self.ly,
        );
        self.amplitude * (ax.cos() * ay.cos() + 0.5 * (2.0 * ay).cos())
    }

    fn gradient(&self, p: [f64; 2]) -> [f64; 2] {
        let (ax, ay) = (
            PI * (p[0] - self.x0) / self.lx,
            PI * (p[1] - self.y0) / self.ly,
        );
        let a = self.amplitude;
        [
            -a * PI / self.lx * ax.sin() * ay.cos(),
            -a * PI / self.ly * (ax.cos() * ay.sin() + (2.0 * ay).sin()),
        ]
    }

    fn laplacian(&self, p: [f64; 2]) -> f64 {
        let (ax, ay) = (
            PI * (p[0] - self.x0) / self.lx,
            PI * (p[1] - self.y0) / self.ly,
        );
        let (kx, ky) = (PI / self.lx, PI / self.ly);
        -self.amplitude
            * ((kx * kx + ky * ky) * ax.cos() * ay.cos() + 2.0 * ky * ky * (2.0 * ay).cos())
    }

    fn contains(&self, p: [f64; 2]) -> bool {
        let tol = 1e-10 * self.lx.max(self.ly);
        p[0] >= self.x0 - tol
            && p[0] <= self.x0 + self.lx + tol
            && p[1] >= self.y0 - tol
            && p[1] <= self.y0 + self.ly + tol
    }

    fn describe(&self) -> String {
        format!(
            "manufactured A (cos(πX) cos(πY) + ½ cos(2πY)) on [{}, {}] × [{}, {}] (zero normal \
             derivative on every side), A = {}",
            self.x0,
            self.x0 + self.lx,
            self.y0,
            self.y0 + self.ly,
            self.amplitude
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(t: f64, f: f64, h: Option<f64>, phi: f64) -> DiskSolution {
        DiskSolution::new([0.0, 0.0], 1.0, t, f, h, phi).unwrap()
    }

    /// Sixth-order central difference of the closed-form u' (test only): an independent u''.
    fn fd_second(s: &DiskSolution, r: f64, d: f64) -> f64 {
        let du = |x: f64| s.radial(x)[1];
        (45.0 * (du(r + d) - du(r - d)) - 9.0 * (du(r + 2.0 * d) - du(r - 2.0 * d))
            + (du(r + 3.0 * d) - du(r - 3.0 * d)))
            / (60.0 * d)
    }

    /// Sixth-order central difference of a function of one variable (test only).
    fn fd1(g: impl Fn(f64) -> f64, x: f64, d: f64) -> f64 {
        (45.0 * (g(x + d) - g(x - d)) - 9.0 * (g(x + 2.0 * d) - g(x - 2.0 * d))
            + (g(x + 3.0 * d) - g(x - 3.0 * d)))
            / (60.0 * d)
    }

    /// The ODE residual `-t (u'' + u'/r) + h (u - φ)⁺ - f` relative to the size of its terms,
    /// with u'' from the closed form and, away from r = a, from finite differences of u'.
    fn check_ode(s: &DiskSolution, tol: f64) {
        let (t, f, h, phi, big_r) = (s.t, s.f, s.h, s.phi, s.radius);
        let n = 200;
        for i in 1..n {
            let r = big_r * i as f64 / n as f64;
            let [u, du, d2u] = s.radial(r);
            let pen = (u - phi).max(0.0);
            let react = if h.is_infinite() { 0.0 } else { h * pen };
            let res = -t * (d2u + du / r) + react - f;
            let scale = f.abs() + react.abs() + t * (d2u.abs() + (du / r).abs());
            if s.regime == DiskRegime::Rigid && r < s.a {
                // Coincidence set: u = φ, and the obstacle takes the load.
                assert_eq!([u, du, d2u], [phi, 0.0, 0.0]);
                continue;
            }
            // h (u - φ) computed from u carries the rounding h·ε·|u| of u itself.
            let rounding = if h.is_infinite() {
                0.0
            } else {
                4.0 * f64::EPSILON * h * u.abs()
            };
            assert!(
                res.abs() <= tol * scale + rounding,
                "r = {r}: residual {res:e}, scale {scale:e}"
            );
            // Laplacian of the trait = u'' + u'/r.
            let lap = s.laplacian([r, 0.0]);
            assert!((lap - (d2u + du / r)).abs() <= tol * scale / t, "r = {r}");
            // An independent u'' where the stencil stays on one side of the contact circle.
            // Step: r/1000 where u varies on the scale r (outside the contact disc: B ln r), and
            // min(R, 1/k)/1000 inside it; no check when that is below R/10⁶.
            let inner = r < s.a && s.regime != DiskRegime::NoContact;
            let d = if inner && s.k.is_finite() {
                1e-3 * big_r.min(1.0 / s.k)
            } else {
                1e-3 * r
            };
            if d >= 1e-6 * big_r && (r - s.a).abs() > 4.0 * d && r + 4.0 * d < big_r {
                let fd = fd_second(s, r, d);
                assert!(
                    (fd - d2u).abs() <= 1e-7 * (d2u.abs() + (du / r).abs() + (f / t).abs()),
                    "r = {r}: u'' {d2u:e}, finite differences {fd:e}"
                );
            }
        }
        // The centre: Δu = 2 u''(0), u'(0) = 0.
        let [u0, du0, d2u0] = s.radial(0.0);
        assert_eq!(du0, 0.0);
        let react = if h.is_infinite() {
            0.0
        } else {
            h * (u0 - phi).max(0.0)
        };
        let res0 = -2.0 * t * d2u0 + react - f;
        if !(s.regime == DiskRegime::Rigid && s.a > 0.0) {
            assert!(
                res0.abs() <= tol * (f.abs() + react.abs()) + 4.0 * f64::EPSILON * h * u0.abs(),
                "centre: {res0:e}"
            );
        }
        // The boundary condition u(R) = 0 (relative to the largest deflection).
        let umax = s.radial(0.0)[0]
            .abs()
            .max(phi.abs())
            .max((f / t).abs() * big_r * big_r);
        assert!(
            s.radial(big_r)[0].abs() <= 1e-13 * umax,
            "u(R) = {}",
            s.radial(big_r)[0]
        );
    }

    /// `u(a⁻) = u(a⁺) = φ` and `u'(a⁻) = u'(a⁺)` from the inner and outer closed forms.
    fn check_matching(s: &DiskSolution) {
        let (t, f, phi) = (s.t, s.f, s.phi);
        let q = ratios(s.k, s.a, s.a);
        let inner = [phi + f / t * q.w, -f / t * q.q1];
        let outer = s.outer(s.a);
        let scale_u = phi.abs() + f.abs() / t * s.radius * s.radius;
        let scale_du = (f / t).abs() * s.radius;
        assert!((inner[0] - phi).abs() <= 1e-14 * scale_u, "{inner:?} {phi}");
        assert!((outer[0] - phi).abs() <= 1e-12 * scale_u, "{outer:?} {phi}");
        assert!(
            (inner[1] - outer[1]).abs() <= 1e-12 * scale_du,
            "{inner:?} {outer:?}"
        );
        // B from the value condition agrees with B from the derivative condition.
        let b_value =
            (phi - f * (s.radius.powi(2) - s.a.powi(2)) / (4.0 * t)) / (s.a / s.radius).ln();
        // (The value form cancels when a ≪ R; its error is ε·scale_u/|ln(a/R)|.)
        let ln = (s.a / s.radius).ln().abs();
        assert!(
            (b_value - s.b).abs() <= 1e-11 * s.b.abs() + 1e-14 * scale_u / ln,
            "{b_value} {}",
            s.b
        );
        // The inner solution penetrates and the outer one stays clear.
        // (Strictly, unless the penetration ~ f/h is below the rounding of φ.)
        let inside = s.radial(0.5 * s.a)[0];
        assert!(inside > phi || (inside == phi && f / s.h < 1e-15 * phi.abs()));
        assert!(s.radial(0.5 * (s.a + s.radius))[0] < phi);
    }

    #[test]
    fn contact_disc_solves_the_ode_and_matches_at_a() {
        let cases = [
            (1.0, 4.0, 100.0, 0.5), // k = 10
            (1.0, 4.0, 1e-3, 0.5),  // small k: the series branch everywhere
            (1.0, 4.0, 3.0, 0.5),   // k a crosses the series threshold 2 inside the disc
            (2.0, 1.0, 50.0, 0.1),  // t ≠ 1
            (1.0, 4.0, 1e6, 0.999), // a tiny contact disc
            (1.0, 1.0, 1e4, 1e-6),  // a close to R
        ];
        for (t, f, h, phi) in cases {
            let s = disc(t, f, Some(h), phi);
            assert_eq!(s.regime(), DiskRegime::ContactDisc, "{}", s.describe());
            assert!(s.a() > 0.0 && s.a() < 1.0);
            check_matching(&s);
            check_ode(&s, 1e-10);
            assert_eq!(s.c_scaled(), -f / h);
            let c = s.c();
            let i0a = i0(s.k() * s.a());
            assert!((c * i0a + f / h).abs() <= 1e-14 * f / h);
        }
    }

    #[test]
    fn shifted_disc_with_gradient_against_finite_differences() {
        let s = DiskSolution::new([0.3, -1.0], 2.5, 2.0, 1.0, Some(50.0), 0.3).unwrap();
        assert_eq!(s.regime(), DiskRegime::ContactDisc);
        check_matching(&s);
        assert!(s.contains([0.3 + 2.5, -1.0]) && !s.contains([0.3 + 2.5001, -1.0]));
        assert!(s.value([0.3, 1.5]).abs() < 1e-14);
        for &(x, y) in &[
            (0.5, -0.7),
            (1.1, 0.2),
            (-1.5, -1.8),
            (0.31, -1.02),
            (2.0, -1.5),
        ] {
            let p = [x, y];
            let g = s.gradient(p);
            let d = 1e-3;
            let gx = fd1(|x| s.value([x, p[1]]), p[0], d);
            let gy = fd1(|y| s.value([p[0], y]), p[1], d);
            let scale = g[0].hypot(g[1]) + 1e-3;
            assert!((gx - g[0]).abs() <= 1e-9 * scale, "{p:?}: {gx} vs {}", g[0]);
            assert!((gy - g[1]).abs() <= 1e-9 * scale, "{p:?}: {gy} vs {}", g[1]);
        }
        assert_eq!(s.gradient([0.3, -1.0]), [0.0, 0.0]);
    }

    #[test]
    fn series_and_direct_branches_agree() {
        for &(k, a, r) in &[(1.0, 1.99, 0.3), (1.0, 1.99, 1.9), (4.0, 0.4999, 0.1)] {
            let q = ratios(k, a, r);
            let direct = (1.0 - i0(k * r) / i0(k * a)) / (k * k);
            assert!((q.w - direct).abs() <= 1e-13 * direct, "{} {direct}", q.w);
        }
        // I₂/I₀ both ways around x = 2, against 1 - 2 I₁/(x I₀) where it is well conditioned.
        for &x in &[1.999_999, 2.0, 2.000_001] {
            let direct = 1.0 - 2.0 * spec_math::cephes64::i1(x) / (x * i0(x));
            assert!((ratio_i2_i0(x) - direct).abs() <= 1e-14, "{x}");
        }
        // Small x: I₂/I₀ ≈ x²/8.
        assert!((ratio_i2_i0(1e-6) / 1.25e-13 - 1.0).abs() < 1e-11);
    }

    #[test]
    fn rigid_limit_is_approached_as_h_grows() {
        let (t, f, phi) = (1.0, 4.0, 0.5);
        let rigid = disc(t, f, None, phi);
        assert_eq!(rigid.regime(), DiskRegime::Rigid);
        check_matching_rigid(&rigid);
        check_ode(&rigid, 1e-10);
        let same = disc(t, f, Some(f64::INFINITY), phi);
        assert_eq!(same.a(), rigid.a());
        let mut prev_da = f64::INFINITY;
        let mut prev_du = f64::INFINITY;
        for j in 1..=8 {
            let h = 10f64.powi(j);
            let s = disc(t, f, Some(h), phi);
            let da = s.a() - rigid.a();
            // The softer obstacle is penetrated further: a_h > a_rigid, decreasing in h.
            assert!(da > 0.0 && da < prev_da, "h = {h}: a - a_rigid = {da}");
            // First-order asymptotics: a_h - a_rigid = 1/k + O(1/k²).
            if j >= 4 {
                assert!(
                    (da * s.k() - 1.0).abs() < 3.0 / (s.k() * rigid.a()),
                    "h = {h}: {}",
                    da * s.k()
                );
            }
            let du = (0..=100)
                .map(|i| {
                    let r = i as f64 / 100.0;
                    (s.radial(r)[0] - rigid.radial(r)[0]).abs()
                })
                .fold(0.0, f64::max);
            assert!(du < prev_du, "h = {h}: {du}");
            prev_da = da;
            prev_du = du;
            check_ode(&s, 1e-10);
        }
        assert!(prev_da < 2e-4 && prev_du < 1e-7, "{prev_da} {prev_du}");
    }

    fn check_matching_rigid(s: &DiskSolution) {
        let o = s.outer(s.a);
        assert!((o[0] - s.phi).abs() <= 1e-14 * s.f * s.radius.powi(2));
        assert!(o[1].abs() <= 1e-14 * s.f * s.radius);
    }

    #[test]
    fn large_k_is_finite_and_accurate() {
        for &h in &[1e8, 1e12, 1e30] {
            let s = disc(1.0, 4.0, Some(h), 0.5);
            assert_eq!(s.regime(), DiskRegime::ContactDisc);
            for i in 0..=1000 {
                let r = i as f64 / 1000.0;
                let v = s.radial(r);
                assert!(v.iter().all(|x| x.is_finite()), "h = {h}, r = {r}: {v:?}");
            }
            check_matching(&s);
            check_ode(&s, 1e-10);
            assert!(s.c().is_finite() && s.c() <= 0.0);
            let full = disc(1.0, 4.0, Some(h), -0.5);
            assert_eq!(full.regime(), DiskRegime::FullContact);
            check_ode(&full, 1e-10);
            assert!((0..=100).all(|i| full.radial(i as f64 / 100.0)[0].is_finite()));
        }
    }

    #[test]
    fn full_contact_branch() {
        // (t, f, h, φ): φ < 0 ≤ f, φ = 0 < f, and φ < 0, f < 0 with u(0) ≥ φ.
        for (t, f, h, phi) in [
            (1.0, 1.0, 10.0, -0.1),
            (1.0, 1.0, 10.0, 0.0),
            (1.0, 0.0, 10.0, -0.2),
            (1.0, -0.5, 10.0, -1.0),
            (2.0, 3.0, 1e-4, -0.01),
            (0.5, 1.0, 2.0, -0.3),
        ] {
            let s = disc(t, f, Some(h), phi);
            assert_eq!(s.regime(), DiskRegime::FullContact, "{}", s.describe());
            assert_eq!(s.a(), 1.0);
            check_ode(&s, 1e-10);
            // Penetration everywhere in the open disc.
            for i in 0..100 {
                let r = i as f64 / 100.0;
                assert!(s.radial(r)[0] > phi, "{} r = {r}", s.describe());
            }
            assert_eq!(s.contact_area(), Some(PI));
        }
        // The boundary case u(0) = φ: f (I₀(kR) - 1) = hφ, just inside the full-contact range.
        let (t, h, phi) = (1.0, 4.0, -0.25);
        let f = h * phi / (i0(2.0) - 1.0) * (1.0 - 1e-12);
        let s = disc(t, f, Some(h), phi);
        assert_eq!(s.regime(), DiskRegime::FullContact);
        assert!((s.radial(0.0)[0] - phi).abs() < 1e-11);
    }

    #[test]
    fn contact_disc_tends_to_full_contact_as_phi_tends_to_zero() {
        let full = disc(1.0, 1.0, Some(10.0), 0.0);
        let near = disc(1.0, 1.0, Some(10.0), 1e-13);
        assert_eq!(near.regime(), DiskRegime::ContactDisc);
        assert!(1.0 - near.a() < 1e-6, "{}", near.a());
        for i in 0..=20 {
            let r = i as f64 / 20.0;
            assert!((near.radial(r)[0] - full.radial(r)[0]).abs() < 1e-11);
        }
    }

    #[test]
    fn no_contact_branch() {
        for (f, h, phi) in [
            (4.0, Some(10.0), 1.0), // u₀(0) = φ: touches at the centre only
            (4.0, Some(10.0), 2.0),
            (4.0, Some(0.0), 0.5), // h = 0: plain Poisson
            (4.0, Some(0.0), -0.5),
            (-1.0, Some(10.0), 0.0), // pulled away from the obstacle
            (-1.0, None, 0.3),
            (4.0, None, 1.5),
        ] {
            let s = disc(1.0, f, h, phi);
            assert_eq!(s.regime(), DiskRegime::NoContact, "{}", s.describe());
            assert_eq!(s.contact_radius(), Some(0.0));
            for i in 0..=10 {
                let r = i as f64 / 10.0;
                assert_eq!(s.radial(r)[0], f * (1.0 - r) * (1.0 + r) / 4.0);
            }
            assert_eq!(s.laplacian([0.2, 0.1]), -f);
        }
        // Rigid obstacle at φ = 0 pushed upwards: u ≡ 0, everything in contact.
        let s = disc(1.0, 1.0, None, 0.0);
        assert_eq!((s.regime(), s.a()), (DiskRegime::Rigid, 1.0));
        assert_eq!(s.value([0.3, 0.2]), 0.0);
    }

    #[test]
    fn small_contact_disc_near_the_threshold() {
        // u₀(0) slightly above φ: a tiny contact disc, radius ~ √(R² - ψ) for small h.
        let (t, f) = (1.0, 4.0);
        let phi = 1.0 - 1e-6;
        let s = disc(t, f, Some(1e-6), phi);
        assert_eq!(s.regime(), DiskRegime::ContactDisc);
        let expected = (1.0 - 4.0 * t * phi / f).sqrt();
        assert!(
            (s.a() / expected - 1.0).abs() < 1e-6,
            "{} {expected}",
            s.a()
        );
        check_matching(&s);
        check_ode(&s, 1e-10);
    }

    #[test]
    fn invalid_data_are_errors() {
        let e = |r: Result<DiskSolution>| r.unwrap_err().to_string();
        assert!(
            e(DiskSolution::new([0.0, 0.0], 1.0, 0.0, 1.0, Some(1.0), 0.1)).contains("tension")
        );
        assert!(e(DiskSolution::new(
            [0.0, 0.0],
            1.0,
            f64::NAN,
            1.0,
            Some(1.0),
            0.1
        ))
        .contains("tension"));
        assert!(e(DiskSolution::new(
            [0.0, 0.0],
            -1.0,
            1.0,
            1.0,
            Some(1.0),
            0.1
        ))
        .contains("radius"));
        assert!(e(DiskSolution::new(
            [f64::NAN, 0.0],
            1.0,
            1.0,
            1.0,
            Some(1.0),
            0.1
        ))
        .contains("centre"));
        assert!(e(DiskSolution::new(
            [0.0, 0.0],
            1.0,
            1.0,
            1.0,
            Some(-1.0),
            0.1
        ))
        .contains("stiffness"));
        assert!(e(DiskSolution::new(
            [0.0, 0.0],
            1.0,
            1.0,
            1.0,
            Some(f64::NAN),
            0.1
        ))
        .contains("stiffness"));
        assert!(e(DiskSolution::new(
            [0.0, 0.0],
            1.0,
            1.0,
            f64::INFINITY,
            Some(1.0),
            0.1
        ))
        .contains("load"));
        assert!(e(DiskSolution::new(
            [0.0, 0.0],
            1.0,
            1.0,
            1.0,
            Some(1.0),
            f64::NAN
        ))
        .contains("obstacle"));
        assert!(e(DiskSolution::new([0.0, 0.0], 1.0, 1.0, 1.0, None, -0.1)).contains("rigid"));
        // Annular contact: pulled down in the middle, obstacle below the rim.
        assert!(e(DiskSolution::new(
            [0.0, 0.0],
            1.0,
            1.0,
            -10.0,
            Some(10.0),
            -0.01
        ))
        .contains("annulus"));
    }

    #[test]
    fn manufactured_derivatives_against_finite_differences() {
        let sols = [
            Manufactured::rectangle(-1.0, 0.5, 2.0, 1.5, 0.7).unwrap(),
            Manufactured::disk([0.2, -0.4], 1.3, -2.0).unwrap(),
        ];
        let pts = [[0.1, 0.8], [1.2, 1.1], [-0.5, 0.6], [0.6, 0.7]];
        for s in &sols {
            for &p0 in &pts {
                let p = if s.disk().is_some() {
                    [p0[0] * 0.8, p0[1] - 1.0]
                } else {
                    p0
                };
                assert!(s.contains(p), "{p:?}");
                let d = 1e-3;
                let g = s.gradient(p);
                let gx = fd1(|x| s.value([x, p[1]]), p[0], d);
                let gy = fd1(|y| s.value([p[0], y]), p[1], d);
                assert!(
                    (gx - g[0]).abs() < 1e-10 && (gy - g[1]).abs() < 1e-10,
                    "{p:?}"
                );
                let lx = fd1(|x| s.gradient([x, p[1]])[0], p[0], d);
                let ly = fd1(|y| s.gradient([p[0], y])[1], p[1], d);
                let lap = s.laplacian(p);
                assert!(
                    (lx + ly - lap).abs() < 1e-9 * (1.0 + lap.abs()),
                    "{p:?}: {} {lap}",
                    lx + ly
                );
                // The load helper is Problem 1 read from left to right.
                let (t, h, phi) = (1.5, 20.0, 0.05);
                let load = manufactured_load(s, p, t, h, phi).unwrap();
                assert_eq!(load, -t * lap + h * (s.value(p) - phi).max(0.0));
            }
        }
        // Zero on the boundary.
        let r = &sols[0];
        for i in 0..=10 {
            let x = -1.0 + 3.0 * i as f64 / 10.0;
            assert!(r.value([x, 0.5]).abs() < 1e-15 && r.value([x, 1.5]).abs() < 1e-15);
        }
        let d = &sols[1];
        for i in 0..16 {
            let th = 2.0 * PI * i as f64 / 16.0;
            let p = [0.2 + 1.3 * th.cos(), -0.4 + 1.3 * th.sin()];
            assert!(d.contains(p) && d.value(p).abs() < 1e-14);
        }
        assert_eq!(d.disk(), Some(([0.2, -0.4], 1.3)));
        assert!(!d.contains([1.6, -0.4]));
        assert!(manufactured_load(d, [1.6, -0.4], 1.0, 0.0, 0.0).is_err());
        assert!(manufactured_load(d, [0.0, 0.0], 0.0, 0.0, 0.0).is_err());
        assert!(Manufactured::rectangle(1.0, 0.0, 0.0, 1.0, 1.0).is_err());
        assert!(Manufactured::disk([0.0, 0.0], 0.0, 1.0).is_err());
    }

    #[test]
    fn brent_finds_roots_to_machine_precision() {
        let g = |x: f64| x * x - 2.0;
        let r = brent(g, 0.0, 2.0, -2.0, 2.0);
        assert!((r - 2f64.sqrt()).abs() <= 4.0 * f64::EPSILON);
        let g = |x: f64| (x - 1e-9).powi(3);
        let r = brent(g, 0.0, 1.0, g(0.0), g(1.0));
        assert!((r - 1e-9).abs() <= 1e-12, "{r}");
    }

    #[test]
    fn obstacle_benchmarks_are_continuous_c1_and_harmonic_outside() {
        let a = EX9_RADIUS;
        for kind in [BenchmarkKind::PetscEx9, BenchmarkKind::MfemEx36] {
            for below in [true, false] {
                let b = ObstacleBenchmark::new(kind, below);
                let s = b.scale;
                let r = s * a;
                // Value and slope match at the contact radius.
                let (lo, hi) = ([r * (1.0 - 1e-12), 0.0], [r * (1.0 + 1e-12), 0.0]);
                assert!((b.value(lo) - b.value(hi)).abs() < 1e-10);
                assert!((b.gradient(lo)[0] - b.gradient(hi)[0]).abs() < 1e-9);
                // u = ψ on the contact disc, u above ψ (below φ) beyond.
                for k in 0..=40 {
                    let rho = 1.9 * s * k as f64 / 40.0;
                    let p = [rho * 0.6, rho * 0.8];
                    let gap = b.sign * (b.value(p) - b.surface(p));
                    if rho <= r {
                        assert!(gap.abs() < 1e-14, "{kind:?} r {rho}");
                    } else {
                        assert!(gap > 0.0, "{kind:?} r {rho}: {gap}");
                    }
                }
                // The outer part is harmonic: a finite-difference Laplacian vanishes.
                let p = [0.8 * s, 0.5 * s];
                let d = 1e-4 * s;
                let fd = (b.value([p[0] + d, p[1]])
                    + b.value([p[0] - d, p[1]])
                    + b.value([p[0], p[1] + d])
                    + b.value([p[0], p[1] - d])
                    - 4.0 * b.value(p))
                    / (d * d);
                assert!(fd.abs() < 1e-5, "{fd}");
                assert_eq!(b.laplacian(p), 0.0);
            }
        }
        // MFEM ex36 is ex9 scaled by ½: u = ln r × A₃₆ outside, A₃₆ = −0.340129705945858.
        let m = ObstacleBenchmark::new(BenchmarkKind::MfemEx36, true);
        let p: [f64; 2] = [0.5, 0.3];
        let r = p[0].hypot(p[1]);
        assert!((m.value(p) - (-0.340129705945858) * r.ln()).abs() < 1e-13);
        assert!(m.value([1.0, 0.0]).abs() < 1e-15);
        // ex9's boundary values: u = A ln(2/r), zero at the midpoints of the sides.
        let e = ObstacleBenchmark::new(BenchmarkKind::PetscEx9, true);
        assert!(e.value([2.0, 0.0]).abs() < 1e-15);
        assert!(e.value([2.0, 2.0]) < 0.0);
    }

    #[test]
    fn the_cosine_manufactured_solution_has_its_derivatives() {
        let m = ManufacturedCosine::rectangle(0.0, 0.0, 2.0, 1.0, 0.3).unwrap();
        let d = 1e-5;
        for p in [[0.3, 0.2], [1.1, 0.7], [1.9, 0.45]] {
            let g = m.gradient(p);
            let fx = (m.value([p[0] + d, p[1]]) - m.value([p[0] - d, p[1]])) / (2.0 * d);
            let fy = (m.value([p[0], p[1] + d]) - m.value([p[0], p[1] - d])) / (2.0 * d);
            assert!((g[0] - fx).abs() < 1e-8 && (g[1] - fy).abs() < 1e-8);
            let lap = (m.value([p[0] + d, p[1]])
                + m.value([p[0] - d, p[1]])
                + m.value([p[0], p[1] + d])
                + m.value([p[0], p[1] - d])
                - 4.0 * m.value(p))
                / (d * d);
            assert!(
                (m.laplacian(p) - lap).abs() < 1e-4,
                "{} {lap}",
                m.laplacian(p)
            );
        }
        // The normal derivative vanishes on every side.
        for t in [0.1, 0.5, 0.9] {
            assert!(m.gradient([0.0, t])[0].abs() < 1e-14);
            assert!(m.gradient([2.0, t])[0].abs() < 1e-14);
            assert!(m.gradient([2.0 * t, 0.0])[1].abs() < 1e-14);
            assert!(m.gradient([2.0 * t, 1.0])[1].abs() < 1e-14);
        }
    }
}
