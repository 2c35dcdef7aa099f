//! The standard benchmark, so that results can be compared with other codes:
//! Ω = (0,1)², u = 0 on ∂Ω, t = 1, f = 20, h = 1000,
//! φ(x, y) = 0.5 + 0.1 sin(2πx) cos(2πy), a structured N × N mesh with every square cut
//! along the diagonal from `(x_i, y_j)` to `(x_{i+1}, y_{j+1})` (the rectangle generator
//! builds the multigrid hierarchy itself), nodal φ, tolerance 1e-10 on the scaled KKT
//! residual, solved by TNNMG ([`memcontact::bench::solve_with`]).
//!
//! Every row also times one linear Poisson solve `S x = D` on the same mesh by the same
//! multigrid V-cycle (from zero, to the same relative tolerance), as the yardstick.
//! `memcontact bench` prints the rows.

use super::proc::{peak_memory, reset_peak_memory};
use memcontact::bench::{self as multigrid, BodyStiffness, Model, ProblemData, TnnmgOptions};
use memcontact::error::Result;
use memcontact::field::FnCoefficient;
use memcontact::mesh::generate::{rectangle, Diagonal, RectangleSpec};
use memcontact::model::{Foundation, Sampling};
use memcontact::solve::{Method, Settings, Silent};
use std::f64::consts::PI;
use std::time::Instant;

/// The benchmark's tolerance on the scaled KKT residual (and on the Poisson solve's
/// relative residual).
pub const TOLERANCE: f64 = 1e-10;

/// One line of the benchmark table.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BenchRow {
    /// Cells per side N.
    pub n: usize,
    /// Unknowns (interior vertices), (N − 1)².
    pub unknowns: usize,
    /// Consistent or lumped L.
    pub foundation: Foundation,
    /// TNNMG iterations on the finest level.
    pub iterations: usize,
    /// TNNMG iterations per level, coarsest first (nested iteration).
    pub level_iterations: Vec<usize>,
    /// Seconds to generate the mesh and its hierarchy.
    pub time_mesh: f64,
    /// Seconds to assemble the model (S, L, D, φₙ).
    pub time_assembly: f64,
    /// Seconds in the TNNMG solve (setup, nested iteration, iterations, certificate).
    pub time_solve: f64,
    /// Peak resident memory of the process during this row, in bytes (`VmHWM`; `None`
    /// where `/proc/self/status` is unavailable).
    pub peak_memory: Option<u64>,
    /// The final scaled KKT residual (max of the 2e and 2f certificates).
    pub certificate: f64,
    /// J(U).
    pub energy: f64,
    /// Seconds of one linear Poisson multigrid solve `S x = D` on the same mesh.
    pub time_poisson: f64,
    /// V-cycles of that solve.
    pub poisson_cycles: usize,
    /// Rayon threads used.
    pub threads: usize,
    /// Seconds per phase of the TNNMG solve.
    pub phases: Vec<(String, f64)>,
    /// Seconds per phase of the Poisson solve.
    pub poisson_phases: Vec<(String, f64)>,
}

/// Seconds, V-cycles and phases of one Poisson yardstick solve.
type PoissonRun = (f64, usize, Vec<(String, f64)>);

/// The benchmark's obstacle φ(x, y) = 0.5 + 0.1 sin(2πx) cos(2πy).
pub fn obstacle(p: [f64; 2]) -> f64 {
    0.5 + 0.1 * (2.0 * PI * p[0]).sin() * (2.0 * PI * p[1]).cos()
}

/// The benchmark's mesh: the unit square, `n × n` cells, "right" diagonals, with the
/// hierarchy the rectangle generator builds.
pub fn mesh(n: usize) -> Result<memcontact::mesh::refine::Hierarchy> {
    let cells = n as f64 * n as f64;
    memcontact::limits::check_mesh_fits(
        memcontact::limits::MeshSize::simply_connected((n as f64 + 1.0).powi(2), 2.0 * cells),
        0,
        &format!("the benchmark's {n} × {n} square"),
    )?;
    rectangle(&RectangleSpec {
        x0: 0.0,
        y0: 0.0,
        x1: 1.0,
        y1: 1.0,
        nx: n,
        ny: n,
        diagonal: Diagonal::Right,
    })
}

/// The benchmark's model on `mesh` (t = 1, f = 20, h = 1000, nodal φ).
pub fn model(mesh: &memcontact::mesh::Mesh, foundation: Foundation) -> Result<Model> {
    let phi = FnCoefficient(obstacle);
    Model::assemble(
        mesh,
        &ProblemData {
            tension: 1.0,
            load: &20.0,
            shape: &phi,
            stiffness: BodyStiffness::Elastic(&1000.0),
            foundation,
            sampling: Sampling::Nodal,
        },
    )
}

/// Runs the benchmark for every size in `sizes` (cells per side; powers of two give the
/// deepest hierarchies) and every foundation, with the TNNMG `options` (the defaults are
/// the standard), calling `observer` with each row as soon as
/// it is measured, and returns the table. Sizes should be given in increasing order: the
/// peak memory is reset before each row where the kernel allows it.
pub fn run_bench(
    sizes: &[usize],
    foundations: &[Foundation],
    options: &TnnmgOptions,
    observer: &mut dyn FnMut(&BenchRow),
) -> Result<Vec<BenchRow>> {
    let mut rows = Vec::new();
    let settings = Settings {
        method: Method::Multigrid,
        tolerance: TOLERANCE,
        ..Settings::default()
    };
    for &n in sizes {
        // (seconds, V-cycles, phases) of the Poisson solve, once per size.
        let mut poisson: Option<PoissonRun> = None;
        for &foundation in foundations {
            reset_peak_memory();
            let t0 = Instant::now();
            let hierarchy = mesh(n)?;
            let time_mesh = t0.elapsed().as_secs_f64();
            let t0 = Instant::now();
            let model = model(hierarchy.finest(), foundation)?;
            let time_assembly = t0.elapsed().as_secs_f64();
            let t0 = Instant::now();
            let (solution, report) = multigrid::solve_with(
                &model,
                multigrid::Coarsening::Geometric(&hierarchy),
                &settings,
                options,
                None,
                &mut Silent,
            )?;
            let time_solve = t0.elapsed().as_secs_f64();
            let (time_poisson, poisson_cycles, poisson_phases) = match &poisson {
                Some(p) => p.clone(),
                None => {
                    let t0 = Instant::now();
                    let out = multigrid::poisson_solve(
                        &model.s,
                        &model.d,
                        &hierarchy,
                        &model.dofs,
                        TOLERANCE,
                        Some(model.force_scale()),
                        200,
                    )?;
                    let p = (t0.elapsed().as_secs_f64(), out.cycles, out.phases);
                    poisson = Some(p.clone());
                    p
                }
            };
            let row = BenchRow {
                n,
                unknowns: model.n(),
                foundation,
                iterations: solution.iterations,
                level_iterations: report.levels.iter().map(|l| l.iterations).collect(),
                time_mesh,
                time_assembly,
                time_solve,
                peak_memory: peak_memory(),
                certificate: solution.certificate.kkt(),
                energy: solution.energy,
                time_poisson,
                poisson_cycles,
                threads: rayon::current_num_threads(),
                phases: solution.phases,
                poisson_phases,
            };
            observer(&row);
            rows.push(row);
        }
    }
    Ok(rows)
}

#[cfg(test)]
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_benchmark_rows_are_complete() {
        let mut seen = 0;
        let rows = run_bench(
            &[16, 32],
            &[Foundation::Lumped, Foundation::Consistent],
            &TnnmgOptions::default(),
            &mut |_| seen += 1,
        )
        .unwrap();
        assert_eq!(seen, 4);
        assert_eq!(rows.len(), 4);
        for r in &rows {
            assert_eq!(r.unknowns, (r.n - 1) * (r.n - 1));
            assert!(r.certificate <= TOLERANCE);
            assert!(r.iterations > 0 && r.poisson_cycles > 0);
            assert_eq!(r.level_iterations.last(), Some(&r.iterations));
        }
        // The same Poisson yardstick for both foundations of one size.
        assert_eq!(rows[0].poisson_cycles, rows[1].poisson_cycles);
    }
}
