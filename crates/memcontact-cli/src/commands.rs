//! The `solve` and `check` commands: thin shells over the library's run.

use crate::progress::{Progress, Verbosity};
use crate::report::{self, print_warnings};
pub use crate::solve_flags::SolveFlags;
use anyhow::{bail, Result};
use memcontact::write::WriteOptions;
use memcontact::write::{self, SweepWriter};
use memcontact::{Case, Outcome};
use std::path::Path;
use std::time::Instant;

/// `memcontact solve`.
pub fn solve(case_path: &Path, flags: &SolveFlags) -> Result<()> {
    let started = Instant::now();
    let mut case = Case::load(case_path, flags.sets)?;
    case.settings.cancel = crate::signals::token();
    let label = case_path.display().to_string();
    let mut progress = Progress::new(flags.verbosity);
    if case.is_sweep() {
        return sweep(&label, &case, flags, progress, started);
    }
    if case.adapt.is_some() {
        return crate::adapt_cmd::adapt(&label, &case, flags, progress, started);
    }
    if case.sensitivity.is_some() || case.fit.is_some() {
        return crate::sensitivity_cmd::solve(&label, &case, flags, progress, started);
    }
    let options = WriteOptions {
        label,
        vtu: case.output.vtu,
        force: flags.force,
        started,
        plot_options: None,
        run_id: None,
        cell_data: Vec::new(),
        adapt: None,
        unconverged: flags.write_unconverged,
    };
    // Everything that needs the mesh is checked before anything is solved.
    let written = memcontact::run::run_to_files(&case, flags.out, &options, &mut progress)?;
    progress.finish();
    let outcome = &written.outcome;
    print_warnings(&outcome.discretization);
    let accepted = outcome.report.accepted;
    let Some(summary) = &written.summary else {
        eprint!("{}", report::human(&options.label, outcome, None));
        bail!(
            "{}; no result files were written (pass --write-unconverged to keep the \
             iterate, marked as not accepted in summary.json){}",
            not_converged(outcome),
            report::floor_note(outcome)
                .map(|n| format!("\n{n}"))
                .unwrap_or_default()
        );
    };
    #[cfg(feature = "alloc-trace")]
    crate::alloc_trace::report("end of the write");
    print!(
        "{}",
        report::human(&options.label, outcome, Some((summary, flags.out)))
    );
    if let Some(note) = report::floor_note(outcome) {
        eprintln!("{note}");
    }
    if !accepted {
        bail!(
            "{}; the files in {} hold the unconverged iterate (summary.json: \"accepted\": \
             false)",
            not_converged(outcome),
            flags.out.display()
        );
    }
    // The process ends right after this: returning the (possibly gigabytes of) mesh
    // levels and matrices to the allocator page by page would only delay the exit.
    std::mem::forget(written);
    Ok(())
}

/// `memcontact solve` on a case with `[sweep]` or `[[load_case]]`: every step in turn,
/// warm-started from the previous one, written into one result set: a subdirectory per
/// step, `sweep.csv` and `sweep.png` (the force-deflection curve).
fn sweep(
    label: &str,
    case: &Case,
    flags: &SolveFlags,
    mut progress: Progress,
    started: Instant,
) -> Result<()> {
    let total = memcontact::case::steps(case)?.len();
    // The result set begins with the first step to write: bad input found before any step
    // is solved leaves nothing behind.
    let mut writer: Option<SweepWriter> = None;
    let run = memcontact::run::run_sweep(case, true, &mut progress, &mut |step, outcome, row| {
        if step.index == 0 {
            print_warnings(&outcome.discretization);
        }
        if !outcome.report.accepted && !flags.write_unconverged {
            return Ok(());
        }
        let w = match &mut writer {
            Some(w) => w,
            None => writer.insert(SweepWriter::begin(
                flags.out,
                flags.force,
                case,
                label,
                case.output.vtu,
                true,
            )?),
        };
        w.write_step(case, step, outcome, row.seconds)?;
        Ok(())
    })?;
    progress.finish();
    // A step that did not converge: nothing is written unless the unconverged step was
    // asked for.
    let failed = match run.stopped {
        None => None,
        Some((_, e)) if !flags.write_unconverged => bail!(
            "{e}; no result files were written (pass --write-unconverged to keep the steps \
             solved and the unconverged iterate, marked as not accepted in summary.json)"
        ),
        Some((step, e)) => Some((step, e)),
    };
    let writer = writer.expect("the first step was written");
    let written = writer.steps_written();
    writer.finish(&run.rows)?;
    let rows = &run.rows;
    println!(
        "memcontact: {label} ({}: {total} steps)",
        write::steps_kind(case)
    );
    println!(
        "  {:>5} {:>16} {:>12} {:>12} {:>12} {:>12} {:>6} {:>10}",
        "step", "name", "value", "max |u|", "contact area", "force", "iters", "KKT"
    );
    for r in rows {
        println!(
            "  {:>5} {:>16} {:>12.5e} {:>12.5e} {:>12.5e} {:>12.5e} {:>6} {:>10.3e}",
            r.step,
            r.name,
            r.value,
            r.max_deflection,
            r.contact_area,
            r.total_contact_force,
            r.iterations,
            r.kkt_residual
        );
    }
    let iterations: usize = rows.iter().map(|r| r.iterations).sum();
    let picture = if case.output.pictures().is_empty() {
        ""
    } else {
        ", sweep.png"
    };
    println!(
        "  total        {iterations} iterations, {:.3} s; wrote {}/{{{written} step \
         directories, sweep.csv{picture}}}",
        started.elapsed().as_secs_f64(),
        flags.out.display(),
    );
    if let Some((step, e)) = failed {
        bail!(
            "{e}; the directories of the steps that did not converge ({}) hold their \
             unconverged iterates (summary.json: \"accepted\": false)",
            step.name
        );
    }
    Ok(())
}

/// The message for a solve that did not converge.
fn not_converged(outcome: &Outcome) -> String {
    outcome
        .report
        .error()
        .map(|e| e.to_string())
        .unwrap_or_default()
}

/// `memcontact check --fragment`: a fragment of a case, checked key by key
/// ([`Case::from_fragment_str`]).
pub fn check_fragment(path: &Path, sets: &[String]) -> Result<()> {
    Case::load_fragment(path, sets)?;
    println!("fragment {}: valid", path.display());
    Ok(())
}

/// `memcontact check`.
pub fn check(case_path: &Path, sets: &[String]) -> Result<()> {
    let case = Case::load(case_path, sets)?;
    // Building the mesh, binding and assembling checks the data on the mesh (regions,
    // signs, NaN), everything `solve` checks before it solves; the load cases' data are
    // assembled on the mesh too, and the profile line checked against it.
    let checked = memcontact::run::check(&case, &mut Progress::new(Verbosity::Quiet))?;
    let d = &checked.discretization;
    print_warnings(d);
    let mesh = d.mesh();
    println!("case {}: valid", case_path.display());
    print!(
        "{}",
        report::mesh_report(mesh, &d.quality, d.hierarchy.depth())
    );
    print!(
        "{}",
        report::boundary_report(mesh, &case.problem.boundary.free)
    );
    println!(
        "  obstacle     {} vertices can touch (M), foundation {}{}",
        d.model.can_touch.iter().filter(|&&c| c).count(),
        d.model.foundation.name(),
        if d.model.is_rigid() { ", rigid" } else { "" }
    );
    if case.is_sweep() {
        let steps = memcontact::case::steps(&case)?;
        let names: Vec<&str> = steps.iter().map(|s| s.name.as_str()).collect();
        println!(
            "  steps        {} ({}): {}",
            steps.len(),
            write::steps_kind(&case),
            names.join(", ")
        );
    }
    if let Some(a) = &case.adapt {
        println!(
            "  adaptive     from this mesh, at most {} steps{}, θ = {}, free-boundary rings {}{}",
            a.steps,
            a.max_vertices
                .map(|m| format!(
                    " and {m} vertices (about {} to solve)",
                    memcontact::limits::human_bytes(memcontact::limits::run_bytes(
                        memcontact::limits::MeshSize::simply_connected(m as f64, 2.0 * m as f64)
                    ))
                ))
                .unwrap_or_default(),
            a.theta,
            a.free_boundary_rings,
            a.tolerance
                .map(|t| format!(", until the estimator is at most {t:e}"))
                .unwrap_or_default()
        );
    }
    if let Some(s) = &case.sensitivity {
        println!(
            "  sensitivity  {} × {}: outputs {}; parameters {}",
            s.outputs.len(),
            s.parameters.len(),
            s.outputs.join(", "),
            s.parameters.join(", ")
        );
    }
    if let Some(f) = &case.fit {
        let keys: Vec<&str> = f.parameters.0.keys().map(String::as_str).collect();
        println!(
            "  fit          {} parameters ({}), {}, at most {} iterations",
            keys.len(),
            keys.join(", "),
            match &f.measurements {
                Some(p) => format!("measurements from {}", p.display()),
                None => format!(
                    "{} sensors measured",
                    case.sensors.iter().filter(|s| s.measured.is_some()).count()
                ),
            },
            f.max_iterations
        );
    }
    let (method, choice) = &checked.auto;
    println!(
        "  solver       {} (auto picks {}: {})",
        case.settings.method.name(),
        method.name(),
        choice.reason()
    );
    println!(
        "  memory       about {} to solve ({} available: {})",
        memcontact::limits::human_bytes(checked.memory_needed),
        memcontact::limits::human_bytes(checked.memory_available.0 as f64),
        checked.memory_available.1
    );
    Ok(())
}
