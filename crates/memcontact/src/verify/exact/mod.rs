//! Closed-form solutions of Problem 1 (docs/theory.md#problem-1,
//! docs/theory.md#verification), for verification.
//!
//! Problem 1 is `-t Δu + h (u - φ)⁺ = f` in Ω, `u = 0` on ∂Ω. Two families are provided:
//!
//! * [`DiskSolution`]: the axisymmetric solution on a disc with constant data `t`, `f`,
//!   `h`, `φ` (docs/theory.md#axisymmetric-disc), for the elastic obstacle (`0 ≤ h < ∞`)
//!   and for the rigid limit `h = ∞` (the classical obstacle problem `u ≤ φ`);
//! * [`Manufactured`]: smooth functions vanishing on ∂Ω with exact gradient and Laplacian,
//!   from which the caller builds the load `f = -t Δu + h (u - φ)⁺`
//!   (docs/theory.md#manufactured-solutions); [`manufactured_load`] does it at a point.
//!
//! Every solution knows its domain Ω ([`ExactSolution::contains`]); evaluating outside Ω is
//! the caller's error and must be checked by the caller (the error norms of
//! [`crate::verify::norms`] do).

mod benchmarks;
mod bessel;
mod disk;
mod disk_derivative;
mod manufactured;
mod solution;
#[cfg(test)]
mod tests;

pub use benchmarks::{BenchmarkKind, ObstacleBenchmark, EX9_KNEE, EX9_RADIUS};
pub use disk::{DiskRegime, DiskSolution};
pub use manufactured::{Manufactured, ManufacturedCosine};
pub use solution::{manufactured_load, ExactSolution};
