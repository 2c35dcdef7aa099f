//! Problem 2b by truncated nonsmooth Newton multigrid (TNNMG; C. Gräser and R. Kornhuber,
//! "Multigrid methods for obstacle problems", J. Comput. Math. 27 (2009), and C. Gräser,
//! U. Sack, O. Sander, "Truncated nonsmooth Newton multigrid methods for convex
//! minimization problems", 2009).
//!
//! One iteration, from an iterate V:
//! 1. **nonsmooth Gauss-Seidel** pre-smoothing: ν₁ sweeps of exact one-variable
//!    minimisation of J ([`super::relax`]). Alone, this is a globally convergent method
//!    (docs/theory.md#coordinatewise-optimality: coordinatewise optimality is global
//!    optimality, even with the consistent L), and it puts vertices exactly on φ_i where
//!    their local minimum is the kink;
//! 2. the **truncated Newton system** of the smooth piece of J selected by the vertex
//!    states at the smoothed iterate ([`crate::solve::newton::NewtonStates`]): `(S + E_P L E_P) δ = −∇J` with the
//!    touching vertices (`V_i = φ_i`) truncated (their rows and columns zero, δ_i = 0),
//!    solved *approximately* by one linear multigrid V-cycle ([`cycle`]) on the truncated
//!    hierarchy: Galerkin coarse operators `PᵀAP` of the truncated matrix, recomputed every
//!    iteration in the rows whose states changed;
//! 3. an **exact line search** on J along δ ([`super::line_search`]), which keeps J
//!    monotone and snaps vertices onto φ where the minimiser is a kink (for the rigid
//!    obstacle, δ is first projected so that `V + δ ≤ φ`);
//! 4. the certificates of 2e and 2f; stop at `settings.tolerance`.
//!
//! J decreases monotonically, the method converges from any start (the smoother alone
//! does), every iteration costs O(n), and the number of iterations stays bounded under
//! refinement. **Nested iteration**: the problem is first solved on the coarser levels,
//! with the Galerkin restriction of the model (`S_c = PᵀSP`, `L_c = PᵀLP` or `l_c = Pᵀl`,
//! `D_c = PᵀD`: exactly the coarse discretisation for nested meshes; φ injected at the
//! coarse vertices), and each solution prolongated as the start of the next level. On
//! algebraic levels the aggregates play the coarse vertices (φ taken at one vertex of
//! each) and `S_c` is scaled for the energy that piecewise constants overstate
//! ([`aggregation::stiffness_scale`]); the coarse answers are only starts, so the finest
//! level, where the model itself is solved and certified, is unchanged by either choice.

pub mod aggregation;
pub mod cycle;
#[cfg(feature = "kernel-timings")]
mod kernels;
pub mod levels;
pub mod operator;
// The linear multigrid solve, the yardstick of the benchmark.
#[cfg(any(test, feature = "bench"))]
pub mod poisson;
pub mod smoother;
pub mod tnnmg;
pub mod transfer;

#[cfg(test)]
mod algebraic_tests;
#[cfg(test)]
pub(crate) mod tests;

#[cfg(feature = "kernel-timings")]
pub use kernels::kernel_timings;
pub use levels::{Kind, Levels};
#[cfg(any(test, feature = "bench"))]
pub use poisson::poisson_solve;
pub use tnnmg::{solve, Coarsening};
#[cfg(feature = "bench")]
pub use tnnmg::{solve_with, TnnmgOptions};
