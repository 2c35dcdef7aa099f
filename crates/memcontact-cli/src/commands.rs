//! The `solve` and `check` commands: thin shells over the library's run.

use crate::output;
use crate::progress::{Progress, Verbosity};
use anyhow::{bail, Result};
use memcontact::io::result_set::ResultSet;
use memcontact::output::{
    input_hash, new_run_id, write_files, write_manifest, write_result_set, write_sweep_csv,
    WriteOptions,
};
use memcontact::{Case, Discretization, Outcome};
use std::path::Path;
use std::time::Instant;

/// Prints the mesh reader's warnings.
pub fn print_warnings(d: &Discretization) {
    for w in &d.warnings {
        eprintln!("warning: {w}");
    }
}

/// How `memcontact solve` writes its results.
pub struct SolveFlags<'a> {
    /// The output directory.
    pub out: &'a Path,
    /// `--set` overrides.
    pub sets: &'a [String],
    /// How much progress to show.
    pub verbosity: Verbosity,
    /// Replace an output directory holding other files.
    pub force: bool,
    /// Write the result files of a solve that did not converge (marked in summary.json).
    pub write_unconverged: bool,
}

/// `memcontact solve`.
pub fn solve(case_path: &Path, flags: &SolveFlags) -> Result<()> {
    let started = Instant::now();
    let case = Case::load(case_path, flags.sets)?;
    if case.sweep.is_some() || !case.load_cases.is_empty() {
        return sweep(case_path, &case, flags, started);
    }
    let mut progress = Progress::new(flags.verbosity);
    let outcome = memcontact::run(&case.problem, &case.settings, &mut progress)?;
    progress.finish();
    print_warnings(&outcome.discretization);
    let accepted = outcome.report.accepted;
    if !accepted && !flags.write_unconverged {
        eprint!(
            "{}",
            output::human(&case_path.display().to_string(), &outcome, None)
        );
        bail!(
            "{}; no result files were written (pass --write-unconverged to keep the \
             iterate, marked as not accepted in summary.json){}",
            not_converged(&outcome),
            output::floor_note(&outcome)
                .map(|n| format!("\n{n}"))
                .unwrap_or_default()
        );
    }
    let label = case_path.display().to_string();
    let plots = output::plot_options(&case, &label);
    let options = WriteOptions {
        label,
        vtu: case.output.vtu,
        force: flags.force,
        started,
        plot_options: serde_json::to_value(&plots).ok(),
        run_id: None,
    };
    let summary = {
        let mut pictures = output::pictures(&outcome, &plots);
        write_result_set(flags.out, &outcome, &case, &options, &mut pictures)?
    };
    print!(
        "{}",
        output::human(&options.label, &outcome, Some((&summary, flags.out)))
    );
    if let Some(note) = output::floor_note(&outcome) {
        eprintln!("{note}");
    }
    if !accepted {
        bail!(
            "{}; the files in {} hold the unconverged iterate (summary.json: \"accepted\": \
             false)",
            not_converged(&outcome),
            flags.out.display()
        );
    }
    // The process ends right after this: returning the (possibly gigabytes of) mesh
    // levels and matrices to the allocator page by page would only delay the exit.
    std::mem::forget(outcome);
    Ok(())
}

/// `memcontact solve` on a case with `[sweep]` or `[[load_case]]`: every step in turn,
/// warm-started from the previous one, written into one result set: a subdirectory per
/// step, `sweep.csv` and `sweep.png` (the force-deflection curve).
fn sweep(case_path: &Path, case: &Case, flags: &SolveFlags, started: Instant) -> Result<()> {
    let label = case_path.display().to_string();
    let plots = output::plot_options(case, &label);
    let set = ResultSet::begin(flags.out, flags.force)?;
    let run_id = new_run_id();
    let steps = memcontact::sweep::steps(case)?;
    let total = steps.len();
    let mut progress = Progress::new(flags.verbosity);
    let mut rows = Vec::new();
    let mut written = 0;
    let result =
        memcontact::sweep::run_sweep(case, true, &mut progress, &mut |step, outcome, row| {
            rows.push(row.clone());
            if !outcome.report.accepted && !flags.write_unconverged {
                return Ok(());
            }
            let dir = set.dir().join(&step.name);
            std::fs::create_dir(&dir).map_err(|source| memcontact::Error::Io {
                path: dir.clone(),
                source,
            })?;
            let options = WriteOptions {
                label: format!("{label} [{}]", step.name),
                vtu: case.output.vtu,
                force: false,
                started: Instant::now(),
                plot_options: serde_json::to_value(&plots).ok(),
                run_id: Some(run_id.clone()),
            };
            let mut step_plots = plots.clone();
            step_plots.title = Some(options.label.clone());
            let mut pictures = output::pictures(outcome, &step_plots);
            write_files(&dir, outcome, case, &options, &mut pictures)?;
            written += 1;
            Ok(())
        });
    progress.finish();
    let result = match result {
        Err(e) if !flags.write_unconverged => return Err(e.into()),
        other => other.map(|_| ()),
    };
    let (tag, value_name) = match &case.sweep {
        Some(s) => ("sweep", s.parameter.name().replace('_', " ")),
        None => ("load cases", "load factor".to_string()),
    };
    write_sweep_csv(&set.dir().join("sweep.csv"), &rows)?;
    let force = match &case.units.force {
        Some(f) => format!(" [{f}]"),
        None => String::new(),
    };
    let length = match &case.units.length {
        Some(l) => format!(" [{l}]"),
        None => String::new(),
    };
    memcontact_plot::line_plot(
        &set.dir().join("sweep.png"),
        &memcontact_plot::LinePlot {
            title: format!("Force-deflection ({tag}): {label}"),
            x_label: format!("max deflection{length}"),
            y_label: format!("force{force}"),
            series: vec![memcontact_plot::Series {
                name: "total contact force".into(),
                points: rows
                    .iter()
                    .map(|r| (r.max_deflection, r.total_contact_force))
                    .collect(),
            }],
        },
    )?;
    write_manifest(set.dir(), tag, &run_id, &input_hash(case))?;
    set.commit()?;
    println!("memcontact: {label} ({tag}: {total} steps, {value_name})");
    println!(
        "  {:>5} {:>16} {:>12} {:>12} {:>12} {:>12} {:>6} {:>10}",
        "step", "name", "value", "max |u|", "contact area", "force", "iters", "KKT"
    );
    for r in &rows {
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
    println!(
        "  total        {iterations} iterations, {:.3} s; wrote {}/{{{} step directories, \
         sweep.csv, sweep.png, manifest.json}}",
        started.elapsed().as_secs_f64(),
        flags.out.display(),
        written
    );
    result?;
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

/// `memcontact check`.
pub fn check(case_path: &Path, sets: &[String]) -> Result<()> {
    let case = Case::load(case_path, sets)?;
    // Building the mesh, binding and assembling checks the data on the mesh (regions,
    // signs, NaN), everything `solve` checks before it solves.
    let d = Discretization::new(&case.problem, &mut Progress::new(Verbosity::Quiet))?;
    print_warnings(&d);
    let mesh = d.mesh();
    println!("case {}: valid", case_path.display());
    print!(
        "{}",
        output::mesh_report(mesh, &mesh.quality(), d.hierarchy.depth())
    );
    println!(
        "  obstacle     {} vertices can touch (M), foundation {}{}",
        d.model.can_touch.iter().filter(|&&c| c).count(),
        d.model.foundation.name(),
        if d.model.is_rigid() { ", rigid" } else { "" }
    );
    let (method, choice) = d.auto_choice();
    println!(
        "  solver       {} (auto picks {}: {})",
        case.settings.method.name(),
        method.name(),
        choice.reason()
    );
    Ok(())
}
