//! What an exact solution answers: u, its gradient and Laplacian, its domain; and the load
//! that makes a function an exact solution.

use crate::error::{Error, Result};

/// A closed-form solution `u` of Problem 1 on a known domain Ω.
///
/// `value`, `gradient` and `laplacian` may only be called at points `p` with
/// `contains(p) == true`; the result elsewhere is unspecified (an analytic continuation).
pub trait ExactSolution: Send + Sync {
    /// The deflection `u(p)`.
    fn value(&self, p: [f64; 2]) -> f64;
    /// The gradient `∇u(p)`.
    fn gradient(&self, p: [f64; 2]) -> [f64; 2];
    /// The Laplacian `Δu(p)` (a.e.: on the contact circle of a [`super::DiskSolution`], where
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
