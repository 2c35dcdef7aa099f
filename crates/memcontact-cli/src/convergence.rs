//! `memcontact convergence`: arguments, progress and the tables of a convergence study
//! (or of the rigid-limit sweep); the study itself is `memcontact::verify::study`, its
//! files `memcontact::write::write_study` with the pictures of `memcontact::write::study_pictures`.

use crate::progress::{Progress, Verbosity};
use anyhow::Result;
use memcontact::mesh::refine::Hierarchy;
use memcontact::model::Sampling;
use memcontact::verify::convergence::{RigidLimit, Study};
use memcontact::verify::study::{run_study, StudyOptions, StudyResult, Variant};
use memcontact::Case;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Which variants `--compare` runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Compare {
    /// The paper's consistent foundation matrix against the lumped diagonal.
    Foundation,
    /// Nodal sampling of φ against the paper's mollified sampling.
    Sampling,
}

impl From<Compare> for memcontact::verify::study::Compare {
    fn from(c: Compare) -> Self {
        match c {
            Compare::Foundation => memcontact::verify::study::Compare::Foundation,
            Compare::Sampling => memcontact::verify::study::Compare::Sampling,
        }
    }
}

/// Arguments of `memcontact convergence`.
// The doc comments below are the command's help text (plain text: `<variant>` is a
// placeholder, not an HTML tag).
#[allow(rustdoc::invalid_html_tags)]
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The case file (TOML); its `[exact]` section names the exact solution (without one,
    /// errors are measured against the finest level's solution).
    pub case: PathBuf,
    /// Refinement levels beyond the case's mesh (K ≥ 1: K + 1 meshes are solved). With
    /// --h-sweep: the fixed mesh is the case's mesh refined K times (K ≥ 0).
    #[arg(long, value_name = "K")]
    pub levels: usize,
    /// Output directory (created if needed).
    #[arg(short, long, default_value = "out")]
    pub output: PathBuf,
    /// Override a case key, e.g. --set mesh.size=0.2 --set obstacle.foundation=lumped.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Run the study for both variants (consistent and lumped L, or nodal and mollified φ)
    /// and write convergence-<variant>.csv for each.
    #[arg(long, value_enum, conflicts_with = "h_sweep")]
    pub compare: Option<Compare>,
    /// Instead of the study: the rigid limit. On the fixed mesh, solve with the obstacle
    /// rigid and with each constant stiffness h, and write h_sweep.csv and h_sweep.png.
    #[arg(long)]
    pub h_sweep: bool,
    /// The stiffnesses of --h-sweep, comma separated (default 10,100,...,1e6).
    #[arg(
        long,
        value_delimiter = ',',
        requires = "h_sweep",
        value_name = "H,H,..."
    )]
    pub h_values: Vec<f64>,
    /// Print no progress lines.
    #[arg(short, long)]
    pub quiet: bool,
    /// Replace the output directory even if it holds files that are not a result.
    #[arg(long)]
    pub force: bool,
}

/// `memcontact convergence`.
pub fn run(args: &Args) -> Result<()> {
    let mut case = Case::load(&args.case, &args.sets)?;
    case.settings.cancel = crate::signals::token();
    let label = args.case.display().to_string();
    let file_name = args
        .case
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let options = StudyOptions {
        levels: args.levels,
        compare: args.compare.map(Into::into),
        h_sweep: args.h_sweep.then(|| args.h_values.clone()),
    };
    // A bar over the K + 1 levels of each variant on a terminal; one line per level either
    // way.
    let total = args.levels + 1;
    let bar = std::cell::RefCell::new(Progress::new(Verbosity::of(args.quiet, false)));
    let mut current = None;
    let outcome = run_study(
        &case,
        &options,
        &mut |v, r| {
            let prefix = if v.name.is_empty() {
                String::new()
            } else {
                format!("[{}] ", v.name)
            };
            let mut bar = bar.borrow_mut();
            if current != Some(v.name) {
                current = Some(v.name);
                bar.set_prefix(&prefix);
            }
            bar.line(&format!(
                "  {prefix}level {}: {} vertices, {} {} iterations, assembly {:.2} s, solve {:.2} s",
                r.level,
                r.vertices,
                r.method.name(),
                r.iterations,
                r.assembly_seconds,
                r.solve_seconds
            ));
            bar.steps(r.level + 1, total);
            bar.message(&format!("level {} …", r.level + 1));
        },
        &mut |vertices, hs| {
            let bar = bar.borrow_mut();
            bar.line(&format!(
                "h sweep on {vertices} vertices: rigid, then h = {hs:?}"
            ));
            bar.message("solving …");
        },
    );
    bar.into_inner().finish();
    let outcome = outcome?;
    for w in &outcome.warnings {
        eprintln!("warning: {w}");
    }
    let written =
        memcontact::write::write_study(&args.output, args.force, &case, &outcome, &mut |dir| {
            memcontact::write::study_pictures(dir, &outcome, &file_name)
        })?;
    let mut out = String::new();
    let _ = writeln!(out, "memcontact convergence: {label}");
    match &outcome.exact {
        Some(e) => {
            let _ = writeln!(out, "  exact        {}", e.solution().describe());
        }
        None => {
            let _ = writeln!(
                out,
                "  exact        none: errors against the finest level's solution (reference)"
            );
        }
    }
    if outcome.exact.as_ref().is_some_and(|e| e.manufactured()) {
        let _ = writeln!(
            out,
            "  load         membrane.load replaced by the manufactured f = −tΔu + h(u − φ)⁺{}",
            if case.problem.lower.is_some() {
                " − h_low(φ_low − u)⁺"
            } else {
                ""
            }
        );
        let _ = writeln!(
            out,
            "  boundary     the fixed boundary's heights replaced by the manufactured u{}",
            if case.problem.boundary.free.is_empty() {
                String::new()
            } else {
                format!(" (free: {})", case.problem.boundary.free.join(", "))
            }
        );
    }
    match &outcome.result {
        StudyResult::RigidLimit {
            variant,
            hierarchy,
            sweep,
            exact_distance,
        } => {
            out.push_str(&sweep_report(hierarchy, sweep, exact_distance, variant));
        }
        StudyResult::Convergence(studies) => {
            let reference = outcome.reference_note();
            for (v, s) in studies {
                out.push_str(&table(
                    &case,
                    v,
                    s,
                    outcome.exact.is_some(),
                    reference.as_deref(),
                ));
            }
        }
    }
    let _ = writeln!(
        out,
        "  wrote        {}/{{{}}}",
        args.output.display(),
        written.join(", ")
    );
    print!("{out}");
    Ok(())
}

/// A number in the table, or a dash.
fn sci(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.3e}"),
        _ => "—".into(),
    }
}

fn rate(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.2}"),
        _ => "—".into(),
    }
}

/// The human table of one study.
/// The human table of one study.
fn table(case: &Case, v: &Variant, s: &Study, exact: bool, reference: Option<&str>) -> String {
    let mut o = String::new();
    let sampling = match v.sampling {
        Sampling::Nodal => "nodal".to_string(),
        Sampling::Mollified { epsilon: None } => "mollified (paper's ε_n)".to_string(),
        Sampling::Mollified { epsilon: Some(e) } => format!("mollified (ε = {e})"),
    };
    let _ = writeln!(
        o,
        "\n  {}foundation {}, sampling {}, solver {} (tolerance {:.0e}){}",
        if v.name.is_empty() {
            String::new()
        } else {
            format!("[{}] ", v.name)
        },
        if case.problem.obstacle.stiffness.is_rigid() {
            "rigid"
        } else {
            v.foundation.name()
        },
        sampling,
        case.settings.method.name(),
        case.settings.tolerance,
        reference.map(|r| format!("; {r}")).unwrap_or_default()
    );
    if let Some(low) = &case.problem.lower {
        let _ = writeln!(
            o,
            "  body below: {}",
            if low.stiffness.is_rigid() {
                "rigid"
            } else {
                low.foundation.name()
            }
        );
    }
    let radius = exact && s.levels.iter().any(|r| r.contact_radius_error.is_some());
    let _ = write!(
        o,
        "  {:>5} {:>9} {:>10} {:>10} {:>5} {:>10} {:>5} {:>10} {:>5}",
        "level", "vertices", "l_n", "L² error", "rate", "H¹ error", "rate", "max nodal", "rate"
    );
    if radius {
        let _ = write!(o, " {:>10} {:>10}", "radius a_h", "|a_h − a|");
    } else if !exact {
        let _ = write!(o, " {:>10} {:>5}", "H¹ Δu_k", "rate");
    }
    let _ = writeln!(o, " {:>6} {:>10} {:>8}", "iters", "method", "solve s");
    for (k, r) in s.levels.iter().enumerate() {
        let e = r.errors;
        let _ = write!(
            o,
            "  {:>5} {:>9} {:>10.4e} {:>10} {:>5} {:>10} {:>5} {:>10} {:>5}",
            r.level,
            r.vertices,
            r.l_n,
            sci(e.map(|e| e.l2)),
            rate(s.l2_rates[k]),
            sci(e.map(|e| e.h1_semi)),
            rate(s.h1_rates[k]),
            sci(e.map(|e| e.max_nodal)),
            rate(s.max_nodal_rates[k]),
        );
        if radius {
            let _ = write!(
                o,
                " {:>10.6} {:>10}",
                r.contact.radius,
                sci(r.contact_radius_error)
            );
        } else if !exact {
            let _ = write!(
                o,
                " {:>10} {:>5}",
                sci(r.increment.map(|d| d[1])),
                rate(s.h1_increment_rates[k])
            );
        }
        let _ = writeln!(
            o,
            " {:>6} {:>10} {:>8.3}",
            r.iterations,
            r.method.name(),
            r.solve_seconds
        );
    }
    // The same note on several levels is printed once, with the levels it applies to.
    let mut notes: Vec<(&str, Vec<usize>)> = Vec::new();
    for r in &s.levels {
        if let Some(n) = &r.note {
            match notes.iter_mut().find(|(m, _)| *m == n.as_str()) {
                Some((_, levels)) => levels.push(r.level),
                None => notes.push((n, vec![r.level])),
            }
        }
    }
    for (n, levels) in notes {
        let l: Vec<String> = levels.iter().map(|l| l.to_string()).collect();
        let _ = writeln!(
            o,
            "  note: level{} {}: {n}",
            if l.len() > 1 { "s" } else { "" },
            l.join(", ")
        );
    }
    if let (Some(Some(l2)), Some(Some(h1))) = (s.l2_rates.last(), s.h1_rates.last()) {
        let _ = writeln!(
            o,
            "  last rates   L² {l2:.3}, H¹ {h1:.3} (optimal for P1: 2 and 1)"
        );
    }
    o
}

/// The table of the rigid-limit sweep.
fn sweep_report(
    hierarchy: &Hierarchy,
    sweep: &RigidLimit,
    continuous: &[Option<f64>],
    v: &Variant,
) -> String {
    let mesh = hierarchy.finest();
    let q = mesh.quality();
    let disk = continuous.iter().any(Option::is_some);
    let mut o = String::new();
    let _ = writeln!(
        o,
        "  rigid limit  {} vertices, l_n = {:.4e}, foundation {}; distance of u_h(h) to the \
         discrete rigid solution u_h(∞) (rigid: {} iterations, contact radius {:.6})",
        q.vertices,
        q.l_n,
        v.foundation.name(),
        sweep.rigid_iterations,
        sweep.rigid_contact.radius
    );
    let _ = write!(
        o,
        "  {:>10} {:>12} {:>12} {:>12} {:>10}",
        "h", "max nodal", "H¹ semi", "L²", "radius"
    );
    if disk {
        let _ = write!(o, " {:>14}", "exact max |Δu|");
    }
    let _ = writeln!(o, " {:>6} {:>8}", "iters", "solve s");
    for (r, c) in sweep.rows.iter().zip(continuous) {
        let _ = write!(
            o,
            "  {:>10.1e} {:>12.4e} {:>12.4e} {:>12.4e} {:>10.6}",
            r.h, r.max_nodal, r.h1_semi, r.l2, r.contact.radius
        );
        if disk {
            let _ = write!(o, " {:>14}", sci(*c));
        }
        let _ = writeln!(o, " {:>6} {:>8.3}", r.iterations, r.solve_seconds);
    }
    let monotone = sweep
        .rows
        .windows(2)
        .all(|w| w[1].max_nodal < w[0].max_nodal && w[1].h1_semi < w[0].h1_semi);
    let _ = writeln!(
        o,
        "  the distance {} monotonically with h",
        if monotone {
            "decreases"
        } else {
            "does NOT decrease"
        }
    );
    o
}
