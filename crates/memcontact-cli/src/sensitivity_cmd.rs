//! `memcontact solve` of a case with `[sensitivity]` or `[fit]`: the library's run, then
//! the result set with its extra files (`sensitivity.csv`, the influence maps in
//! `solution.vtu`, `fit.json`, `fit.csv`, `fit.png`) and a table on the terminal.

use crate::progress::Progress;
use crate::report::{self, print_warnings};
use crate::solve_flags::SolveFlags;
use anyhow::{bail, Result};
use memcontact::sensitivity::Sensitivities;
use memcontact::write::{self, WriteOptions};
use memcontact::{Case, Outcome};
use std::time::Instant;

/// Solves a case with `[sensitivity]` and/or `[fit]` and writes its result set.
pub fn solve(
    label: &str,
    case: &Case,
    flags: &SolveFlags,
    mut progress: Progress,
    started: Instant,
) -> Result<()> {
    if case.fit.is_some() {
        return fit(label, case, flags, progress, started);
    }
    let run = memcontact::run::run_sensitivity(case, &mut progress)?;
    progress.finish();
    print_warnings(&run.outcome.discretization);
    let outcome = run.outcome;
    if !outcome.report.accepted && !flags.write_unconverged {
        eprint!("{}", report::human(label, &outcome, None));
        bail!(
            "{}; no result files were written and no derivatives computed (pass \
             --write-unconverged to keep the iterate, marked as not accepted in summary.json)",
            not_converged(&outcome)
        );
    }
    let s = run.sensitivities;
    let summary = write(label, case, &outcome, flags, started, s.as_ref(), None)?;
    print!(
        "{}",
        report::human(label, &outcome, Some((&summary, flags.out)))
    );
    if let Some(s) = &s {
        print!("{}", table(s));
    }
    if !outcome.report.accepted {
        bail!(
            "{}; the files in {} hold the unconverged iterate, without derivatives \
             (summary.json: \"accepted\": false)",
            not_converged(&outcome),
            flags.out.display()
        );
    }
    Ok(())
}

/// `solve` with `[fit]`: the fit, then the result set at the fitted (or best) parameters.
fn fit(
    label: &str,
    case: &Case,
    flags: &SolveFlags,
    mut progress: Progress,
    started: Instant,
) -> Result<()> {
    let run = memcontact::run::run_fit(case, &mut progress)?;
    progress.finish();
    print_warnings(&run.outcome.discretization);
    let summary = write(
        label,
        &run.fitted_case,
        &run.outcome,
        flags,
        started,
        run.sensitivities.as_ref(),
        Some(&run.fit),
    )?;
    print!(
        "{}",
        report::human(label, &run.outcome, Some((&summary, flags.out)))
    );
    let f = &run.fit;
    println!(
        "  fit          {} iterations, {} solves, rms {:.4e}, stop: {}{}",
        f.iterations,
        f.solves,
        f.rms,
        f.stop.name(),
        if f.converged { "" } else { " (not converged)" }
    );
    println!(
        "  {:>32} {:>14} {:>14} {:>12}",
        "parameter", "start", "fitted", "std error"
    );
    for p in &f.parameters {
        println!(
            "  {:>32} {:>14.6e} {:>14.6e} {:>12.3e}",
            p.key, p.start, p.value, p.std_error
        );
    }
    println!(
        "  singular values of the scaled Jacobian: {}; condition number {:.3e}",
        f.statistics
            .singular_values
            .iter()
            .map(|v| format!("{v:.3e}"))
            .collect::<Vec<_>>()
            .join(", "),
        f.statistics.condition_number
    );
    if let Some(w) = &f.statistics.warning {
        eprintln!("warning: {w}");
    }
    if let Some(s) = &run.sensitivities {
        print!("{}", table(s));
    }
    if !f.converged {
        bail!(
            "the fit did not converge (stop: {}, rms {:.3e} after {} iterations); the files in \
             {} hold its best iterate (fit.json: \"converged\": false)",
            f.stop.name(),
            f.rms,
            f.iterations,
            flags.out.display()
        );
    }
    Ok(())
}

/// Writes the result set of `outcome` with the sensitivity's and the fit's files
/// ([`memcontact::write::write_sensitivity_result`]).
fn write(
    label: &str,
    case: &Case,
    outcome: &Outcome,
    flags: &SolveFlags,
    started: Instant,
    s: Option<&Sensitivities>,
    fit: Option<&memcontact::fit::FitResult>,
) -> Result<memcontact::Summary> {
    let plots = write::plot_options(case, label);
    let options = WriteOptions {
        vtu: case.output.vtu,
        force: flags.force,
        started,
        unconverged: flags.write_unconverged,
        ..WriteOptions::new(label)
    };
    Ok(write::write_sensitivity_result(
        flags.out, outcome, case, &options, &plots, s, fit,
    )?)
}

/// The derivatives as a terminal table (the first rows; sensitivity.csv has them all).
fn table(s: &Sensitivities) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "  sensitivity  {} outputs × {} parameters ({}), {} solves, {} biactive vertices",
        s.outputs.len(),
        s.parameters.len(),
        s.mode.name(),
        s.solves.len(),
        s.biactive()
    );
    let _ = writeln!(
        out,
        "  {:>26} {:>32} {:>14} {:>14} {:>12}",
        "output", "parameter", "value", "derivative", "elasticity"
    );
    const SHOWN: usize = 40;
    let np = s.parameters.len();
    let total = s.outputs.len() * np;
    for k in 0..total.min(SHOWN) {
        let (o, p) = (k / np, k % np);
        let e = s.elasticity(o, p);
        let _ = writeln!(
            out,
            "  {:>26} {:>32} {:>14.6e} {:>14.6e} {:>12}{}",
            s.outputs[o],
            s.parameters[p].key,
            s.values[o],
            s.derivative[k],
            if e.is_nan() {
                String::new()
            } else {
                format!("{e:.4e}")
            },
            if s.nonsmooth[k] {
                format!(
                    "  one-sided: +{:.6e} / −{:.6e}",
                    s.derivative_plus[k], s.derivative_minus[k]
                )
            } else {
                String::new()
            }
        );
    }
    if total > SHOWN {
        let _ = writeln!(out, "  ... {} more rows in sensitivity.csv", total - SHOWN);
    }
    out
}

/// The message for a solve that did not converge.
fn not_converged(outcome: &Outcome) -> String {
    outcome
        .report
        .error()
        .map(|e| e.to_string())
        .unwrap_or_default()
}
