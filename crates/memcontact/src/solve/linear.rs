//! h ≡ 0: Problem 2b is the linear system `S U = D`, one sparse Cholesky solve (the
//! paper's "classical algorithms" case).

use super::{PhaseTimer, Settings, Solution};
use crate::error::{Error, Result};
use crate::model::Model;
use crate::sparse::Cholesky;

/// Solves `S U = D` by sparse Cholesky; a bad-input error unless L = 0.
pub fn solve(model: &Model, _settings: &Settings) -> Result<Solution> {
    if !model.is_linear() {
        return Err(Error::Data(
            "solver.method = \"linear\" needs a problem without contact, but the obstacle \
             can touch the membrane (h > 0 somewhere, or rigid): choose another method"
                .into(),
        ));
    }
    let mut timer = PhaseTimer::default();
    let chol = timer.time("factorisation", || Cholesky::new(&model.s))?;
    let mut u = model.d.clone();
    timer.time("solve", || chol.solve_in_place(&mut u));
    let certificate = timer.time("certificate", || model.certificate(&u));
    Ok(Solution {
        energy: model.energy(&u),
        u,
        method: super::Method::Linear,
        iterations: 1,
        certificate,
        multipliers: None,
        history: vec![],
        phases: timer.into_phases(),
        coarsening: None,
    })
}
