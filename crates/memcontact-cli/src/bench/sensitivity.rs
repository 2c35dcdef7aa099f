//! `memcontact bench --sensitivity --mesh FILE`: the cost of sensitivities and of a fit in
//! units of one solve, on an imported mesh with the standard benchmark's data and one
//! stiffness per region (docs/theory.md#sensitivities):
//!
//! 1. one solve from cold (the unit);
//! 2. the energy's derivatives in every region's stiffness (the envelope theorem: no
//!    solve), the derivative data assembled included;
//! 3. one output's adjoint (a sensor's deflection in every region's stiffness: one linear
//!    solve, its multigrid set up included);
//! 4. a fit of the regions' stiffnesses (three on `scripts/make_strips.py`'s mesh) to the
//!    deflections of 25 sensors computed at the true values, started 5 to 6 times away
//!    (every forward solve warm-started, the Jacobian from tangent solves).

use anyhow::{bail, Result};
use memcontact::case::{Case, ParameterKey};
use memcontact::discretization::Discretization;
use memcontact::sensitivity::{Prepared, Request};
use memcontact::solve::Silent;
use std::path::Path;
use std::time::Instant;

/// A wall-clock and process-CPU stopwatch: on a shared machine the CPU seconds (all
/// threads) measure the work where the wall clock also counts the other processes.
struct Watch(Instant, f64);

impl Watch {
    fn start() -> Watch {
        Watch(
            Instant::now(),
            super::proc::cpu_seconds().unwrap_or(f64::NAN),
        )
    }
    /// (wall seconds, CPU seconds) since the start.
    fn read(&self) -> (f64, f64) {
        (
            self.0.elapsed().as_secs_f64(),
            super::proc::cpu_seconds().unwrap_or(f64::NAN) - self.1,
        )
    }
}

/// `"W s = R solves (CPU C s = Q solves)"`.
fn cost((wall, cpu): (f64, f64), (w1, c1): (f64, f64)) -> String {
    format!(
        "{wall:.3} s = {:.3} solves (CPU {cpu:.3} s = {:.3} solves)",
        wall / w1,
        cpu / c1
    )
}

/// Runs the benchmark on `mesh` with the `sets` overrides of the generated case, `repeat`
/// times.
pub fn run(mesh: &Path, sets: &[String], repeat: usize) -> Result<()> {
    let (m, _) = memcontact::io::gmsh::read_msh(mesh)?;
    let mut regions: Vec<String> = m.region_tags().iter().map(|&t| m.region_name(t)).collect();
    regions.dedup();
    if regions.is_empty() {
        bail!("{}: the mesh has no regions", mesh.display());
    }
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in &m.points {
        (x0, x1, y0, y1) = (x0.min(p[0]), x1.max(p[0]), y0.min(p[1]), y1.max(p[1]));
    }
    drop(m);
    let stiffness: Vec<(String, f64)> = regions
        .iter()
        .enumerate()
        .map(|(k, r)| (r.clone(), [400.0, 1000.0, 2500.0, 700.0, 1600.0][k % 5]))
        .collect();
    let table: Vec<String> = stiffness
        .iter()
        .map(|(r, h)| format!("\"{r}\" = {h}"))
        .collect();
    let mut sensors = String::new();
    for j in 0..5 {
        for i in 0..5 {
            let x = x0 + (x1 - x0) * (i as f64 + 0.5) / 5.0;
            let y = y0 + (y1 - y0) * (j as f64 + 0.5) / 5.0;
            sensors.push_str(&format!(
                "[[sensor]]\nname = \"S{}\"\nat = [{x}, {y}]\n",
                5 * j + i
            ));
        }
    }
    let text = format!(
        r#"[mesh]
file = {path}
[membrane]
tension = 1.0
load = 20.0
[obstacle]
shape = "0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)"
stiffness = {{ {table} }}
[solver]
tolerance = 1e-10
{sensors}"#,
        path = toml::Value::String(mesh.display().to_string()),
        table = table.join(", ")
    );
    let text = memcontact::case::apply_overrides(&text, sets)
        .map_err(|(k, m)| anyhow::anyhow!("--set {k}: {m}"))?;
    let mut case = Case::from_toml_str(&text, None)?;
    // Sensors outside a mesh with holes are left out.
    let keys: Vec<String> = stiffness
        .iter()
        .map(|(r, _)| format!("obstacle.stiffness.{r}"))
        .collect();
    println!(
        "sensitivity benchmark on {} ({} regions: {})",
        mesh.display(),
        regions.len(),
        regions.join(", ")
    );
    for round in 0..repeat.max(1) {
        let w = Watch::start();
        let d = Discretization::new(&case.problem, &mut Silent)?;
        let t_setup = w.read();
        let points: Vec<[f64; 2]> = case.sensors.iter().map(|s| s.at).collect();
        let inside = memcontact::bench::locate(d.mesh(), &points)?;
        let mut k = 0;
        case.sensors.retain(|_| {
            k += 1;
            inside[k - 1].is_some()
        });
        let w = Watch::start();
        let report = d.solve(&case.settings, &mut Silent)?;
        let t_solve = w.read();
        if !report.accepted {
            bail!("the solve was not accepted: {:?}", report.error());
        }
        // The energy in every region's stiffness.
        let w = Watch::start();
        let energy = Request {
            outputs: vec!["energy".into()],
            parameters: keys.clone(),
            influence: false,
        };
        let p = Prepared::new(&case.problem, &case.sensors, &energy, d.mesh(), &d.model)?;
        let t_prepare = w.read();
        let s = p.evaluate(
            d.mesh(),
            &d.model,
            d.levels(),
            &report.u,
            &report.certificate,
            report.energy,
        )?;
        let t_energy = w.read();
        assert!(s.solves.is_empty());
        // One output's adjoint.
        let middle = &case.sensors[case.sensors.len() / 2].name;
        let w = Watch::start();
        let adjoint = Request {
            outputs: vec![format!("sensor:{middle}")],
            parameters: keys.clone(),
            influence: false,
        };
        let p = Prepared::new(&case.problem, &case.sensors, &adjoint, d.mesh(), &d.model)?;
        let s = p.evaluate(
            d.mesh(),
            &d.model,
            d.levels(),
            &report.u,
            &report.certificate,
            report.energy,
        )?;
        let t_adjoint = w.read();
        let rec = &s.solves[0];
        // The fit, from the true deflections, started 5 to 6 times away.
        let values = Prepared::new(
            &case.problem,
            &case.sensors,
            &Request {
                outputs: vec!["sensors".into()],
                parameters: Vec::new(),
                influence: false,
            },
            d.mesh(),
            &d.model,
        )?
        .values(
            d.mesh(),
            &d.model,
            &report.u,
            &report.certificate,
            report.energy,
        );
        drop(d);
        let mut fit_case = case.clone();
        for (s, v) in fit_case.sensors.iter_mut().zip(&values) {
            s.measured = Some(*v);
        }
        let factors = [6.0, 0.2, 5.0, 0.18, 5.5];
        let mut bounds = String::new();
        for (k, key) in keys.iter().enumerate() {
            let pk = ParameterKey::parse(&fit_case.problem, key).map_err(anyhow::Error::msg)?;
            pk.apply(&mut fit_case.problem, pk.value * factors[k % 5])
                .map_err(anyhow::Error::msg)?;
            bounds.push_str(&format!("\"{key}\" = [10, 100000]\n"));
        }
        let fit_text = format!(
            "{}[fit]\nmax_iterations = 20\n[fit.parameters]\n{bounds}",
            fit_case.to_toml_string()?
        );
        let fit_case = Case::from_toml_str(&fit_text, None)?;
        let w = Watch::start();
        let run = memcontact::run::run_fit(&fit_case, &mut Silent)?;
        let t_fit = w.read();
        let f = &run.fit;
        let worst = f
            .parameters
            .iter()
            .map(|p| {
                let (_, h) = stiffness
                    .iter()
                    .find(|(r, _)| p.key == format!("obstacle.stiffness.{r}"))
                    .expect("a region's stiffness");
                ((p.value - h) / h).abs()
            })
            .fold(0.0, f64::max);
        println!(
            "round {round}: {} vertices, {} unknowns; mesh and assembly {:.3} s; one solve {:.3} s, CPU {:.3} s ({} iterations) = 1 solve",
            run.outcome.discretization.mesh().n_vertices(),
            run.outcome.discretization.model.n(),
            t_setup.0,
            t_solve.0,
            t_solve.1,
            report.iterations
        );
        println!(
            "  energy in {} region stiffnesses: {} (derivative data {:.3} s; no linear solve)",
            keys.len(),
            cost(t_energy, t_solve),
            t_prepare.0
        );
        println!(
            "  one output's adjoint (sensor {middle} in {} stiffnesses): {} ({}: {} steps, residual {:.1e}, {:.3} s)",
            keys.len(),
            cost(t_adjoint, t_solve),
            rec.solver,
            rec.iterations,
            rec.residual,
            rec.seconds
        );
        let inner = (t_fit.0 - t_setup.0, t_fit.1 - t_setup.1);
        println!(
            "  fit of {} stiffnesses from {} sensors: {}; without its mesh and assembly {}; forward solves {:.3} s, Jacobians {:.3} s; {} iterations, {} forward solves, worst relative error {worst:.1e}, converged {}",
            keys.len(),
            values.len(),
            cost(t_fit, t_solve),
            cost(inner, t_solve),
            f.seconds_solves,
            f.seconds_derivatives,
            f.iterations,
            f.solves,
            f.converged
        );
        for (k, s) in f.forward_solves.iter().enumerate() {
            println!(
                "    forward solve {k:>2}: {:>2} iterations, {:.3} s = {:.2} solves at {:?}",
                s.iterations,
                s.seconds,
                s.seconds / t_solve.0,
                s.parameters
            );
        }
        for h in &f.history {
            println!(
                "    iteration {:>2}: rms {:.3e}, step {:.2e}, damping {:.2e}, after {} solves",
                h.iteration, h.rms, h.step, h.damping, h.solves
            );
        }
    }
    Ok(())
}
