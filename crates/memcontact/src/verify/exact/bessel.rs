//! Bessel-function ratios in scaled form (large arguments do not overflow) and a bracketed
//! root finder, for the disc's contact radius.

use spec_math::cephes64::{i0, i0e, i1e};

/// `e^{-x} I₁(x) / x`, with its limit 1/2 at 0 (x ≥ 0).
pub(super) fn i1_over_x_e(x: f64) -> f64 {
    if x < 1e-150 {
        0.5
    } else {
        i1e(x) / x
    }
}

/// `I₂(x) / I₀(x)` for x ≥ 0, without the cancellation of `1 - 2 I₁/(x I₀)` at small x
/// (the recurrence `x I₀ - 2 I₁ = x I₂`).
pub(super) fn ratio_i2_i0(x: f64) -> f64 {
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
pub(super) struct Ratios {
    pub(super) g0: f64,
    pub(super) q1: f64,
    pub(super) q2: f64,
    pub(super) w: f64,
}

pub(super) fn ratios(k: f64, a: f64, r: f64) -> Ratios {
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
pub(super) fn brent(f: impl Fn(f64) -> f64, lo: f64, hi: f64, flo: f64, fhi: f64) -> f64 {
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
