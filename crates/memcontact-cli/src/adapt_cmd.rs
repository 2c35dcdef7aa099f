//! `memcontact solve` on a case with `[adapt]`: the adaptive loop of the library, a line
//! per step, and its result set (the final step's files, `adapt.csv`, `mesh.png`, and with
//! `[output] keep_steps` every step's files in `step-NNN/`).

use crate::progress::Progress;
use crate::report;
use crate::report::print_warnings;
use crate::solve_flags::SolveFlags;
use anyhow::{bail, Result};
use memcontact::adapt::AdaptRow;
use memcontact::adapt::{AdaptHistory, AdaptSet};
use memcontact::outcome::Outcome;
use memcontact::solve::{IterationRecord, Observer};
use memcontact::write::WriteOptions;
use memcontact::write::{adapt_pictures, pictures, plot_options};
use memcontact::Case;
use std::cell::RefCell;
use std::time::Instant;

/// The progress display shared by the loop (as its observer) and the lines of its steps.
struct Shared<'a>(&'a RefCell<Progress>);

impl Observer for Shared<'_> {
    fn iteration(&mut self, record: &IterationRecord) {
        self.0.borrow_mut().iteration(record)
    }
    fn phase_started(&mut self, name: &str) {
        self.0.borrow_mut().phase_started(name)
    }
    fn phase_finished(&mut self, name: &str, seconds: f64) {
        self.0.borrow_mut().phase_finished(name, seconds)
    }
    fn step_started(&mut self, index: usize, total: usize, name: &str) {
        self.0.borrow_mut().step_started(index, total, name)
    }
}

/// The line of a step.
fn step_line(r: &AdaptRow) -> String {
    format!(
        "  step {:>3}: {:>9} vertices, estimator {:.4e}, J = {:.10e}, {} iterations, KKT \
         {:.2e}, {:.2} s",
        r.step, r.vertices, r.estimator, r.energy, r.iterations, r.kkt_residual, r.seconds
    )
}

/// Runs the adaptive loop of `case` and writes its result set into `flags.out`.
pub fn adapt(
    label: &str,
    case: &Case,
    flags: &SolveFlags,
    progress: Progress,
    started: Instant,
) -> Result<()> {
    let progress = RefCell::new(progress);
    let plots = plot_options(case, label);
    let options = WriteOptions {
        label: label.to_string(),
        vtu: case.output.vtu,
        force: flags.force,
        started,
        plot_options: serde_json::to_value(&plots).ok(),
        run_id: None,
        cell_data: Vec::new(),
        adapt: None,
        unconverged: false,
    };
    // The result set begins with the first step solved: bad input found before leaves
    // nothing behind.
    let mut set: Option<AdaptSet> = None;
    let keep = case.output.keep_steps;
    let mut on_step = |row: &AdaptRow, outcome: &Outcome, eta2: &[f64]| {
        if row.step == 0 {
            print_warnings(&outcome.discretization);
        }
        progress.borrow().line(&step_line(row));
        let s = match &mut set {
            Some(s) => s,
            None => set.insert(AdaptSet::begin(flags.out, flags.force)?),
        };
        if keep && (outcome.report.accepted || flags.write_unconverged) {
            let step_plots = memcontact::write::PlotOptions {
                title: Some(format!("{label} [step {}]", row.step)),
                ..plots.clone()
            };
            let mesh = outcome.mesh();
            let step_options = WriteOptions {
                label: format!("{label} [step-{:03}]", row.step),
                plot_options: serde_json::to_value(&step_plots).ok(),
                ..options.clone()
            };
            s.write_step(
                case,
                row,
                outcome,
                eta2,
                &step_options,
                &mut pictures(&mesh, &step_plots),
            )?;
        }
        Ok(())
    };
    let run = memcontact::run::run_adapt(case, &mut Shared(&progress), &mut on_step)?;
    progress.into_inner().finish();
    let outcome = &run.outcome;
    if !outcome.report.accepted && !flags.write_unconverged {
        bail!(
            "{}; no result files were written (pass --write-unconverged to keep the iterate, \
             marked as not accepted in summary.json)",
            run.error
                .as_ref()
                .map(|e| e.to_string())
                .unwrap_or_default()
        );
    }
    let set = set.expect("step 0 began the set");
    let start_vertices = run.rows.first().map_or(0, |r| r.vertices);
    let mesh = outcome.mesh();
    let history = AdaptHistory {
        rows: &run.rows,
        indicators: &run.indicators,
        totals: &run.totals(),
    };
    let summary = set.finish(
        case,
        outcome,
        history,
        &options,
        &mut adapt_pictures(&mesh, &plots),
    )?;
    print!(
        "{}",
        report::human(label, outcome, Some((&summary, flags.out)))
    );
    println!(
        "  adaptive     {} steps, {} → {} vertices, estimator {:.4e} → {:.4e}, stopped: {}, \
         {:.3} s; wrote {}/adapt.csv{}",
        run.rows.len(),
        start_vertices,
        run.rows.last().map_or(0, |r| r.vertices),
        run.rows.first().map_or(f64::NAN, |r| r.estimator),
        run.rows.last().map_or(f64::NAN, |r| r.estimator),
        run.stop.name(),
        run.seconds,
        flags.out.display(),
        if run.interpolated.is_empty() {
            String::new()
        } else {
            format!(
                " (data given per vertex interpolated onto new vertices: {})",
                run.interpolated.join(", ")
            )
        }
    );
    if let Some(e) = &run.error {
        if !outcome.report.accepted {
            bail!(
                "{e}; the files in {} hold the unconverged iterate (summary.json: \
                 \"accepted\": false)",
                flags.out.display()
            );
        }
        eprintln!("warning: the adaptive loop stopped: {e}");
    }
    Ok(())
}
