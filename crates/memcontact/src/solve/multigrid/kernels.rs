//! Timings of the kernels of one TNNMG iteration, for the benchmark's micro mode (behind
//! the `kernel-timings` feature).

use super::aggregation;
use super::cycle::{FcgWork, Multigrid};
use super::levels::Levels;
use super::smoother::*;
use super::tnnmg::{coarse_model, mesh_levels_of, setup_matrix, Coarsening};
use crate::error::Result;
use crate::model::Model;
use crate::solve::line_search::{apply_step, exact_step, line_data, line_data_at};
use crate::solve::newton::{mark_dirty, newton_system, NewtonStates};
use crate::solve::relax::sweep_forward;
use crate::sparse::Csr;
use std::time::Instant;

/// Wall-clock and CPU (all threads) milliseconds per call of the kernels of one TNNMG
/// iteration on `model` with the levels of `coarsening` (for the benchmark's `--micro`
/// mode; `reps` calls each, at a point with every vertex state). `cpu_seconds` is the
/// caller's clock of the process's CPU time (NaN where it has none).
#[doc(hidden)]
pub fn kernel_timings(
    model: &Model,
    coarsening: Coarsening,
    reps: usize,
    cpu_seconds: &dyn Fn() -> f64,
) -> Result<Vec<(&'static str, f64, f64)>> {
    let mut out = Vec::new();
    let mut time = |name: &'static str, f: &mut dyn FnMut()| {
        let c0 = cpu_seconds();
        let t0 = Instant::now();
        for _ in 0..reps {
            f();
        }
        let wall = t0.elapsed().as_secs_f64() * 1e3 / reps as f64;
        let cpu = (cpu_seconds() - c0) * 1e3 / reps as f64;
        out.push((name, wall, cpu));
    };
    let mut levels = None;
    time("levels setup", &mut || {
        levels = match coarsening {
            Coarsening::Geometric(h) => mesh_levels_of(model, h).ok(),
            Coarsening::Built(l) => Some(l.clone()),
            Coarsening::Algebraic => Some(Levels::algebraic(
                &setup_matrix(model),
                aggregation::COARSEST,
            )),
        }
    });
    let levels = levels.filter(|l| l.len() > 1).ok_or_else(|| {
        crate::error::Error::Mesh("the hierarchy does not fit or has one level".into())
    })?;
    let top = levels.len() - 1;
    time("coarse models", &mut || {
        std::hint::black_box(coarse_model(
            model,
            &levels.transfers[top - 1],
            &levels,
            top - 1,
        ));
    });
    let n = model.n();
    let mut v: Vec<f64> = (0..n)
        .map(|i| model.phi[i] + 0.01 * ((i as f64) * 0.37).sin())
        .collect();
    time("certificate", &mut || {
        std::hint::black_box(crate::certificate::evaluate(model, &v));
    });
    time("nonsmooth sweep", &mut || {
        sweep_forward(model, &mut v);
    });
    let mut st = NewtonStates::of(model, &v);
    time("states", &mut || st = NewtonStates::of(model, &v));
    let mut a = Csr::zeros(model.s.pattern.clone());
    let (mut g, mut r) = (vec![0.0; n], vec![0.0; n]);
    time("newton system", &mut || {
        newton_system(model, &v, &st, &mut a, None, &mut g, &mut r)
    });
    let (mut changed, mut dirty) = (vec![false; n], vec![false; n]);
    let prev = st.clone();
    time("mark dirty", &mut || {
        mark_dirty(&model.s.pattern, &prev, &st, &mut changed, &mut dirty);
    });
    let mut mg = Multigrid::new(&levels, top);
    time("coarse operators (all)", &mut || {
        mg.update(&a, None).unwrap_or(())
    });
    let mut delta = vec![0.0; n];
    let rhs: Vec<f64> = g.iter().map(|x| -x).collect();
    time("cycle", &mut || mg.cycle(&a, &mut delta, &rhs));
    let mut work = FcgWork::default();
    let mut b = rhs.clone();
    time("flexible CG, 3 steps", &mut || {
        b.copy_from_slice(&rhs);
        mg.fcg(&a, &mut delta, &mut b, 0.0, 3, &st.truncated, &mut work);
    });
    // The top level's sweeps divide by the diagonal they read (no stored inverse).
    let rows = SweepRows::of(&a.pattern);
    time("sweep rows (setup)", &mut || {
        std::hint::black_box(SweepRows::of(&a.pattern));
    });
    let inv = InvDiag::Rows(&rows);
    let mut snap = vec![0.0; n];
    time("gauss-seidel sweep", &mut || {
        gauss_seidel(&a, inv, &mut delta, &rhs, &mut snap, false)
    });
    let mut res = vec![0.0; n];
    time("sweep from zero + residual", &mut || {
        gauss_seidel_from_zero(&a, inv, &mut delta, &rhs, &mut res, &rows)
    });
    let mut prod = vec![0.0; n];
    time("backward sweep + product", &mut || {
        gauss_seidel_back_with_product(&a, inv, &mut delta, &rhs, &mut snap, &mut prod, &rows)
    });
    time("residual", &mut || residual(&a, &delta, &rhs, &mut res));
    time("matrix-vector product", &mut || {
        a.mul_into(&delta, &mut res)
    });
    for (i, d) in delta.iter_mut().enumerate() {
        if st.truncated[i] {
            *d = 0.0;
        }
    }
    let mut gs = (0.0, 0.0);
    time("line data", &mut || gs = line_data(model, &delta, &r));
    time("line data, r on the way", &mut || {
        gs = line_data_at(model, &delta, &v)
    });
    let mut alpha = None;
    time("exact step", &mut || {
        alpha = exact_step(model, &v, &delta, gs.0, gs.1)
    });
    let mut w = v.clone();
    time("apply step", &mut || {
        w.copy_from_slice(&v);
        apply_step(model, &mut w, &delta, alpha.unwrap_or(0.0));
    });
    Ok(out)
}
