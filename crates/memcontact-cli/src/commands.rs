//! The `solve` and `check` commands: thin shells over the library's run.

use crate::output;
use anyhow::{bail, Result};
use memcontact::output::{write_result_set, WriteOptions};
use crate::progress::{Progress, Verbosity};
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
