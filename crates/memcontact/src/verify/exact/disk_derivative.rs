//! The disc's derivatives in the stiffness h (docs/theory.md#sensitivity-checks), from its
//! closed form ([`DiskSolution`], contact disc `0 < a < R`), for the sensitivities'
//! convergence tests.
//!
//! * **Energy** (envelope theorem: the minimum's derivative is the partial derivative at
//!   the minimiser): `dΠ/dh = ½ ∫ ((u − φ)⁺)² = π (f/h)² ∫₀ᵃ (1 − I₀(kr)/I₀(ka))² r dr`.
//! * **Centre deflection**: `u(0) = φ + (f/h)(1 − 1/I₀(ka))` with `k = √(h/t)` and the
//!   contact radius a(h) the root of
//!   `H(a, k) = R² − a² − ψ + 2a² ln(a/R) ρ(ka) = 0`, `ρ = I₂/I₀`, `ψ = 4tφ/f` (ψ does not
//!   depend on h). Differentiating the matching condition,
//!   `da/dh = −H_k (dk/dh) / H_a`, `dk/dh = k/(2h)`, with
//!   `H_k = 2a³ ln(a/R) ρ'(ka)`,
//!   `H_a = −2a + 4a ln(a/R) ρ + 2aρ + 2a² k ln(a/R) ρ'(ka)`,
//!   `ρ' = (I₂' I₀ − I₂ I₁)/I₀²`, `I₂' = I₁ − 2I₂/x`; then with `x = ka`,
//!   `du(0)/dh = −(f/h²)(1 − 1/I₀(x)) + (f/h) I₁(x)/I₀(x)² (a dk/dh + k da/dh)`.

use super::bessel::ratios;
use super::disk::{DiskRegime, DiskSolution};
use crate::error::{Error, Result};
use spec_math::cephes64::{i0, i1};
use std::f64::consts::PI;

impl DiskSolution {
    /// `dΠ/dh` and `du(0)/dh` of the contact-disc regime (an error for the others).
    pub fn h_derivatives(&self) -> Result<(f64, f64)> {
        if self.regime != DiskRegime::ContactDisc {
            return Err(Error::Data(format!(
                "the disc's h-derivatives are derived for a contact disc 0 < a < R, not {:?}",
                self.regime
            )));
        }
        let (t, f, h, r_big, a, k) = (self.t, self.f, self.h, self.radius, self.a, self.k);
        // dΠ/dh by Gauss-Legendre on (0, a): the integrand is smooth.
        let (x, w) = crate::quadrature::gauss_legendre(64);
        let integral: f64 = x
            .iter()
            .zip(&w)
            .map(|(&xi, &wi)| {
                let r = 0.5 * a * (xi + 1.0);
                let g = 1.0 - ratios(k, a, r).g0;
                0.5 * a * wi * g * g * r
            })
            .sum();
        let d_energy = PI * (f / h).powi(2) * integral;
        // du(0)/dh from the matching condition.
        let xk = k * a;
        let (b0, b1) = (i0(xk), i1(xk));
        let b2 = b0 - 2.0 * b1 / xk;
        let rho = b2 / b0;
        let d_b2 = b1 - 2.0 * b2 / xk;
        let d_rho = (d_b2 * b0 - b2 * b1) / (b0 * b0);
        let ln = (a / r_big).ln();
        let h_k = 2.0 * a * a * a * ln * d_rho;
        let h_a = -2.0 * a + 4.0 * a * ln * rho + 2.0 * a * rho + 2.0 * a * a * k * ln * d_rho;
        let dk = k / (2.0 * h);
        let da = -h_k * dk / h_a;
        let dx = a * dk + k * da;
        let _ = t;
        let d_center = -(f / (h * h)) * (1.0 - 1.0 / b0) + (f / h) * b1 / (b0 * b0) * dx;
        Ok((d_energy, d_center))
    }
}
