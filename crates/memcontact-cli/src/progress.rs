//! Progress on the terminal: a spinner with the current phase and, while solving, the
//! iteration and its certificate; a bar with its position where the number of steps is
//! known (sweep steps, refinement levels). Hidden when stderr is not a terminal or with
//! --quiet; with --verbose, one line per phase and iteration instead. The library reports progress through
//! its `Observer`; only this module draws.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use memcontact::solve::{IterationRecord, Observer};
use std::io::IsTerminal;
use std::time::Duration;

/// How much the terminal shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verbosity {
    /// Nothing but the summary and errors.
    Quiet,
    /// A progress spinner when stderr is a terminal.
    Normal,
    /// One line per phase and per iteration.
    Verbose,
}

impl Verbosity {
    /// From the `--quiet` and `--verbose` flags (quiet wins).
    pub fn of(quiet: bool, verbose: bool) -> Verbosity {
        if quiet {
            Verbosity::Quiet
        } else if verbose {
            Verbosity::Verbose
        } else {
            Verbosity::Normal
        }
    }
}

/// The CLI's observer of a run.
pub struct Progress {
    verbosity: Verbosity,
    bar: Option<ProgressBar>,
    /// Prefix of the messages (a sweep step, say).
    prefix: String,
}

/// The spinner: phase, iteration and certificate, no known end.
const SPINNER: &str = "{spinner} {elapsed:>4} {prefix}{wide_msg}";
/// The bar, where the number of steps is known (sweep steps, refinement levels).
const BAR: &str = "{spinner} {elapsed:>4} [{bar:20}] {pos}/{len} {prefix}{wide_msg}";

impl Progress {
    /// A progress display for `verbosity`.
    pub fn new(verbosity: Verbosity) -> Progress {
        let bar = (verbosity == Verbosity::Normal && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
            bar.set_style(style(SPINNER));
            bar.enable_steady_tick(Duration::from_millis(120));
            bar
        });
        Progress {
            verbosity,
            bar,
            prefix: String::new(),
        }
    }

    /// Sets the prefix of the messages (e.g. `step-003: `).
    pub fn set_prefix(&mut self, prefix: &str) {
        self.prefix = prefix.to_string();
        if let Some(b) = &self.bar {
            b.set_prefix(prefix.to_string());
        }
    }

    /// Turns the spinner into a bar of `total` steps, `done` of them done.
    pub fn steps(&mut self, done: usize, total: usize) {
        if let Some(b) = &self.bar {
            if b.length() != Some(total as u64) {
                b.set_length(total as u64);
                b.set_style(style(BAR));
            }
            b.set_position(done as u64);
        }
    }

    /// Sets the message after the prefix.
    pub fn message(&self, message: &str) {
        if let Some(b) = &self.bar {
            b.set_message(message.to_string());
        }
    }

    /// Prints a line above the bar (or on stderr when there is none), unless quiet.
    pub fn line(&self, line: &str) {
        match (&self.bar, self.verbosity) {
            (Some(b), _) => b.println(line),
            (None, Verbosity::Quiet) => {}
            (None, _) => eprintln!("{line}"),
        }
    }

    /// Removes the spinner.
    pub fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

/// An indicatif style from a template known to be valid.
fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template)
        .unwrap_or_else(|_| ProgressStyle::default_spinner())
        .progress_chars("=> ")
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.finish();
    }
}

impl Observer for Progress {
    fn iteration(&mut self, r: &IterationRecord) {
        match self.verbosity {
            Verbosity::Verbose => eprintln!(
                "  {}iteration {:>5}  J = {:+.12e}  KKT = {:.3e} (2e {:.3e}, 2f {:.3e})  \
                 clear {} touching {} penetrating {}",
                self.prefix,
                r.iteration,
                r.energy,
                r.residual,
                r.residual_2e,
                r.residual_2f,
                r.states.clear,
                r.states.touching,
                r.states.penetrating
            ),
            _ => {
                if let Some(b) = &self.bar {
                    b.set_message(format!(
                        "solve: iteration {}, KKT {:.2e}",
                        r.iteration, r.residual
                    ));
                }
            }
        }
    }

    fn phase_started(&mut self, name: &str) {
        if let Some(b) = &self.bar {
            b.set_message(format!("{name} …"));
        }
        if self.verbosity == Verbosity::Verbose {
            eprintln!("  {}{name} …", self.prefix);
            #[cfg(feature = "alloc-trace")]
            crate::alloc_trace::report(&format!("{name} started"));
        }
    }

    fn step_started(&mut self, index: usize, total: usize, name: &str) {
        self.steps(index, total);
        self.set_prefix(&format!("{name}: "));
        if self.verbosity == Verbosity::Verbose {
            eprintln!("step {}/{total}: {name}", index + 1);
        }
    }

    fn phase_finished(&mut self, name: &str, seconds: f64) {
        if self.verbosity == Verbosity::Verbose {
            eprintln!("  {}{name} done in {seconds:.3} s", self.prefix);
            #[cfg(feature = "alloc-trace")]
            crate::alloc_trace::report(&format!("{name} finished"));
        }
    }
}
