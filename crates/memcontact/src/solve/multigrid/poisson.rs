//! One linear multigrid solve `A x = b` (the Poisson yardstick of the benchmark: S from
//! zero to a relative tolerance).

use super::cycle::Multigrid;
use super::levels::Levels;
use super::smoother::residual;
use crate::error::{Error, Result};
use crate::mesh::refine::Hierarchy;
use crate::mesh::DofMap;
use crate::sparse::Csr;

/// The result of a linear multigrid solve.
#[derive(Debug, Clone)]
pub struct LinearSolve {
    /// The solution.
    pub x: Vec<f64>,
    /// V-cycles done.
    pub cycles: usize,
    /// `‖b − A x‖∞ / ‖b‖∞` at the end.
    pub relative_residual: f64,
    /// Wall-clock seconds per phase (setup, coarse operators, cycles).
    pub phases: Vec<(String, f64)>,
}

/// Solves the linear system `S x = rhs` (S on the finest level of `hierarchy`, over the
/// unknowns `dofs`) by V(1,1)-cycles from `x = 0` until `‖rhs − S x‖∞ ≤ tol · scale`: the
/// linear Poisson multigrid that the contact solver is measured against. `scale = None`
/// means `‖rhs‖∞` (the plain relative residual); the benchmark passes the model's force
/// scale, the scaling of the contact solver's KKT certificates, so that both stop at the
/// same residual (with `‖D‖∞` alone, 1e-10 is below the rounding floor of `S x` from about
/// a million unknowns on). Not reaching the tolerance (within `max_cycles`, or because the
/// residual stagnates at rounding level) is an error.
pub fn poisson_solve(
    s: &Csr,
    rhs: &[f64],
    hierarchy: &Hierarchy,
    dofs: &DofMap,
    tol: f64,
    scale: Option<f64>,
    max_cycles: usize,
) -> Result<LinearSolve> {
    let t0 = std::time::Instant::now();
    let levels = Levels::new(hierarchy, dofs, s.pattern.clone())?;
    let setup = t0.elapsed().as_secs_f64();
    let mut out = linear_solve(s, rhs, &levels, tol, scale, max_cycles)?;
    out.phases.insert(0, ("setup".into(), setup));
    Ok(out)
}

/// [`poisson_solve`] on prebuilt [`Levels`].
pub fn linear_solve(
    a: &Csr,
    rhs: &[f64],
    levels: &Levels,
    tol: f64,
    scale: Option<f64>,
    max_cycles: usize,
) -> Result<LinearSolve> {
    if rhs.len() != a.n() || a.n() != levels.n(levels.len() - 1) {
        return Err(Error::Solver {
            solver: "multigrid".into(),
            message: "right-hand side, matrix and hierarchy sizes differ".into(),
        });
    }
    let mut timer = crate::solve::PhaseTimer::default();
    let mut mg = Multigrid::new(levels, levels.len() - 1);
    timer.time("coarse operators", || mg.update(a, None))?;
    let t0 = std::time::Instant::now();
    let norm_b = scale.unwrap_or_else(|| crate::sparse::norm_inf(rhs));
    let mut x = vec![0.0; a.n()];
    let mut r = vec![0.0; a.n()];
    let mut cycles = 0;
    let mut rel = if crate::sparse::norm_inf(rhs) == 0.0 {
        0.0
    } else {
        crate::sparse::norm_inf(rhs) / norm_b
    };
    // The best residual so far and when it was reached (stagnation test).
    let mut best = (rel, 0);
    while rel > tol && cycles < max_cycles && cycles < best.1 + 4 {
        mg.v_cycle(a, &mut x, rhs);
        cycles += 1;
        residual(a, &x, rhs, &mut r);
        rel = crate::sparse::norm_inf(&r) / norm_b;
        if !rel.is_finite() {
            break;
        }
        if rel < 0.9 * best.0 {
            best = (rel, cycles);
        }
    }
    if rel.is_nan() || rel > tol {
        return Err(Error::Solver {
            solver: "multigrid".into(),
            message: format!(
                "linear multigrid stopped after {cycles} V-cycles at scaled residual {rel:.3e} \
                 (tolerance {tol:.1e})"
            ),
        });
    }
    timer.add("v-cycles", t0.elapsed().as_secs_f64());
    Ok(LinearSolve {
        x,
        cycles,
        relative_residual: rel,
        phases: timer.into_phases(),
    })
}
