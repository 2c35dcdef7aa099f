//! Benchmarks and their tables.
//!
//! * The standard benchmark ([`standard`]): TNNMG on the N × N unit square
//!   against one linear Poisson multigrid solve.
//! * Any case or mesh ([`run_case`]): the whole run as `memcontact solve` does it, timed
//!   phase by phase: reading or generating the mesh, renumbering, assembly, the solver's
//!   setup (hierarchy) and iterations, and writing the result set, with the iterations,
//!   the peak memory and the certificate.

pub mod proc;
pub mod sensitivity;
pub mod standard;

use anyhow::{bail, Context, Result};
use memcontact::problem::MeshSource;
use memcontact::solve::HierarchyKind as Kind;
use memcontact::solve::{HierarchyChoice, Method, Silent};
use memcontact::write::WriteOptions;
use memcontact::Case;
use proc::{peak_memory, reset_peak_memory, stolen_seconds};
use standard::BenchRow;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The header line of the standard benchmark's table (see [`square_row`]).
pub fn square_header() -> String {
    format!(
        "{:>5} {:>10} {:>10} {:>5} {:>24} {:>7} {:>7} {:>7} {:>8} {:>9} {:>8} {:>6} {:>6}",
        "N",
        "unknowns",
        "foundation",
        "its",
        "its per level",
        "mesh",
        "asm",
        "solve",
        "mem MiB",
        "KKT",
        "poisson",
        "cycles",
        "ratio"
    )
}

/// One row of the standard benchmark's table: times in seconds, memory in MiB, `ratio` =
/// solve time over the Poisson multigrid time; with `phases`, two more lines with the time
/// per phase.
pub fn square_row(r: &BenchRow, phases: bool) -> String {
    let levels: Vec<String> = r.level_iterations.iter().map(|i| i.to_string()).collect();
    let mut s = format!(
        "{:>5} {:>10} {:>10} {:>5} {:>24} {:>7.3} {:>7.3} {:>7.3} {:>8.0} {:>9.2e} {:>8.3} {:>6} {:>6.2}",
        r.n,
        r.unknowns,
        r.foundation.name(),
        r.iterations,
        levels.join(","),
        r.time_mesh,
        r.time_assembly,
        r.time_solve,
        r.peak_memory.map_or(f64::NAN, |b| b as f64 / 1048576.0),
        r.certificate,
        r.time_poisson,
        r.poisson_cycles,
        r.time_solve / r.time_poisson
    );
    if phases {
        s.push_str(&format!("\n        tnnmg: {}", phase_list(&r.phases)));
        s.push_str(&format!(
            "\n        poisson: {}",
            phase_list(&r.poisson_phases)
        ));
    }
    s
}

fn phase_list(p: &[(String, f64)]) -> String {
    p.iter()
        .map(|(n, t)| format!("{n} {t:.3}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The data of the standard benchmark (t = 1, f = 20, h = 1000,
/// φ = 0.5 + 0.1 sin 2πx cos 2πy, nodal, tolerance 1e-10), as a case on the mesh file
/// `mesh`: what `memcontact bench --mesh FILE` solves.
pub fn standard_case_on(mesh: &Path) -> Result<Case> {
    let text = format!(
        r#"[mesh]
file = {path}
[membrane]
tension = 1.0
load = 20.0
[obstacle]
shape = "0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)"
stiffness = 1000.0
[solver]
tolerance = 1e-10
"#,
        path = toml::Value::String(mesh.display().to_string())
    );
    Ok(Case::from_toml_str(&text, None)?)
}

/// One timed run of a case.
#[derive(Debug, Clone)]
pub struct CaseRun {
    /// Vertices of the solved mesh.
    pub vertices: usize,
    /// Unknowns.
    pub unknowns: usize,
    /// Mesh levels (1 without a refinement hierarchy).
    pub levels: usize,
    /// The method that produced the answer, with its hierarchy for multigrid.
    pub method: String,
    /// Iterations of that method.
    pub iterations: usize,
    /// Seconds: mesh (read or generate), reorder, assembly, setup (the solver's hierarchy
    /// and factorisations), solve (the rest of the solver), write, total (the whole run).
    pub seconds: [f64; 7],
    /// Peak resident memory in bytes (`None` where unknown).
    pub peak_memory: Option<u64>,
    /// The final scaled KKT residual.
    pub certificate: f64,
    /// Accepted by the settings.
    pub accepted: bool,
    /// CPU seconds the host of a virtual machine took during the run (`None` where unknown).
    pub stolen: Option<f64>,
    /// With `write_parts`: the seconds of each part of writing alone, one after the other
    /// after the run (`memcontact::bench::write_parts_seconds`).
    pub write_parts: Vec<(String, f64, f64)>,
    /// The solver's phases with their seconds (as `memcontact solve` prints them).
    pub solver_phases: Vec<(String, f64)>,
}

/// The names of [`CaseRun::seconds`].
pub const CASE_PHASES: [&str; 7] = [
    "mesh", "reorder", "assembly", "setup", "solve", "write", "total",
];

/// Runs `case` as `memcontact solve` does (mesh, renumbering, assembly, solve, the result
/// set written into a scratch directory under `scratch`, removed afterwards; pictures only
/// with `pictures`), timing each phase; with `write_parts`, then each part of writing
/// alone.
pub fn run_case(case: &Case, scratch: &Path, pictures: bool, write_parts: bool) -> Result<CaseRun> {
    let mut case = case.clone();
    if !pictures {
        case.output.plots = Some(Vec::new());
        case.output.plot = None;
    }
    reset_peak_memory();
    let stolen_before = stolen_seconds();
    let started = Instant::now();
    let outcome = memcontact::run(&case, &mut Silent)?;
    let t_write = Instant::now();
    let dir = scratch.join(format!("memcontact-bench-{}", std::process::id()));
    let options = WriteOptions {
        label: "bench".into(),
        vtu: case.output.vtu,
        force: true,
        started,
        plot_options: None,
        run_id: None,
        cell_data: Vec::new(),
        adapt: None,
        unconverged: false,
    };
    let plots = memcontact::write::plot_options(&case, "bench");
    let written = memcontact::write::write_result(&dir, &outcome, &case, &options, &plots);
    let write = t_write.elapsed().as_secs_f64();
    let total = started.elapsed().as_secs_f64();
    let stolen = stolen_seconds()
        .zip(stolen_before)
        .map(|(after, before)| after - before);
    let _ = std::fs::remove_dir_all(&dir);
    written.with_context(|| format!("writing the result set into {}", dir.display()))?;
    let r = &outcome.report;
    let phase = |name: &str| r.seconds(name);
    let setup: f64 = r
        .solver_phases
        .iter()
        .filter(|p| p.name == "setup" || p.name == "factorisation")
        .map(|p| p.seconds)
        .sum();
    let method = match r.coarsening {
        Some(Kind::Geometric) => format!("{} (geometric)", r.method.name()),
        Some(Kind::Algebraic) => format!("{} (algebraic)", r.method.name()),
        None => r.method.name().to_string(),
    };
    let run = CaseRun {
        vertices: outcome.discretization.mesh().n_vertices(),
        unknowns: outcome.discretization.model.n(),
        levels: outcome.discretization.hierarchy.depth(),
        method,
        iterations: r.iterations,
        seconds: [
            phase("mesh"),
            phase("reorder"),
            phase("assembly"),
            setup,
            phase("solve") - setup,
            write,
            total,
        ],
        peak_memory: peak_memory(),
        certificate: r.certificate.kkt(),
        accepted: r.accepted,
        stolen,
        write_parts: Vec::new(),
        solver_phases: r
            .solver_phases
            .iter()
            .map(|p| (p.name.to_string(), p.seconds))
            .collect(),
    };
    let run = if write_parts {
        std::fs::create_dir_all(&dir)?;
        let parts = memcontact::bench::write_parts_seconds(&dir, &outcome, &case, &plots);
        let _ = std::fs::remove_dir_all(&dir);
        CaseRun {
            write_parts: parts.context("writing the result set part by part")?,
            ..run
        }
    } else {
        run
    };
    // The teardown is not part of any phase; the freed memory goes back to the system, so
    // that a repeated run starts as the first did and its peak memory is its own.
    drop(outcome);
    release_freed_memory();
    Ok(run)
}

/// Hands the memory the allocator keeps for reuse back to the system (mimalloc's
/// `mi_collect`, the allocator of the `memcontact` program; harmless under another).
fn release_freed_memory() {
    // SAFETY: `mi_collect` takes no pointers; it frees what mimalloc holds unused.
    unsafe { libmimalloc_sys::mi_collect(true) };
}

/// The header of the case benchmark's table (see [`case_row`]).
pub fn case_header() -> String {
    let mut s = format!(
        "{:>10} {:>10} {:>6} {:<22} {:>5}",
        "vertices", "unknowns", "levels", "method", "its"
    );
    for p in CASE_PHASES {
        s.push_str(&format!(" {p:>8}"));
    }
    s.push_str(&format!(" {:>8} {:>9}", "mem MiB", "KKT"));
    s
}

/// One row of the case benchmark's table (seconds, MiB).
pub fn case_row(r: &CaseRun) -> String {
    let mut s = format!(
        "{:>10} {:>10} {:>6} {:<22} {:>5}",
        r.vertices, r.unknowns, r.levels, r.method, r.iterations
    );
    for t in r.seconds {
        s.push_str(&format!(" {t:>8.3}"));
    }
    s.push_str(&format!(
        " {:>8.0} {:>9.2e}{}",
        r.peak_memory.map_or(f64::NAN, |b| b as f64 / 1048576.0),
        r.certificate,
        if r.accepted { "" } else { "  (not accepted)" }
    ));
    s.push_str(&stolen_note(r.stolen));
    s
}

/// The line after a row with the seconds of each part of writing alone (and the processor
/// seconds of all threads meanwhile).
pub fn write_parts_row(parts: &[(String, f64, f64)]) -> String {
    let total: f64 = parts.iter().map(|(_, s, _)| s).sum();
    let cpu: f64 = parts.iter().map(|(_, _, c)| c).sum();
    let each: Vec<String> = parts
        .iter()
        .map(|(n, s, c)| format!("{n} {s:.3} (CPU {c:.2})"))
        .collect();
    format!(
        "    writing part by part, seconds: {}; sum {total:.3} (CPU {cpu:.2})",
        each.join(", ")
    )
}

/// The line after a row with the seconds of each of the solver's phases (`--phases`).
pub fn solver_phases_row(phases: &[(String, f64)]) -> String {
    let each: Vec<String> = phases.iter().map(|(n, s)| format!("{n} {s:.3}")).collect();
    format!("    solver phases, seconds: {}", each.join(", "))
}

/// The note after a row whose run lost CPU time to the host of a virtual machine (more
/// than a clock tick or two): its times are longer than the code's by up to that much.
pub fn stolen_note(stolen: Option<f64>) -> String {
    match stolen {
        Some(s) if s >= 0.02 => format!("  (host took {s:.2} s of CPU)"),
        _ => String::new(),
    }
}

/// What `memcontact bench --case/--mesh` measures.
pub struct CaseBench {
    /// The case file, if any.
    pub case: Option<PathBuf>,
    /// A mesh file replacing the case's mesh (or carrying the standard benchmark's data).
    pub mesh: Option<PathBuf>,
    /// `--set` overrides of the case.
    pub sets: Vec<String>,
    /// `auto`, `geometric`, `algebraic` or `both` (both when the mesh has levels).
    pub hierarchy: String,
    /// Runs per configuration (the table shows each).
    pub repeat: usize,
    /// Draw the pictures too.
    pub pictures: bool,
    /// Time each part of writing alone after each run.
    pub write_parts: bool,
    /// Print the solver's phases after each row.
    pub phases: bool,
}

/// Runs the case benchmark, printing the table as rows are measured.
pub fn run_case_bench(b: &CaseBench) -> Result<()> {
    let mut case = match (&b.case, &b.mesh) {
        (Some(c), _) => Case::load(c, &b.sets)?,
        (None, Some(m)) => {
            let mut case = standard_case_on(m)?;
            if !b.sets.is_empty() {
                bail!("--set needs --case (the standard data on --mesh have no case file)");
            }
            case.settings.method = Method::Auto;
            case
        }
        (None, None) => bail!("give --case FILE and/or --mesh FILE"),
    };
    if let (Some(_), Some(m)) = (&b.case, &b.mesh) {
        case.problem.mesh.source = MeshSource::File(m.clone());
    }
    let choices: Vec<HierarchyChoice> = match b.hierarchy.as_str() {
        "auto" => vec![HierarchyChoice::Auto],
        "geometric" => vec![HierarchyChoice::Geometric],
        "algebraic" => vec![HierarchyChoice::Algebraic],
        "both" => vec![HierarchyChoice::Geometric, HierarchyChoice::Algebraic],
        h => bail!("--hierarchy must be auto, geometric, algebraic or both, not \"{h}\""),
    };
    if b.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    if choices.len() > 1 && case.settings.method == Method::Auto {
        case.settings.method = Method::Multigrid;
    }
    println!(
        "threads: {} (rayon); times in seconds, memory = peak resident set (VmHWM)",
        rayon::current_num_threads()
    );
    println!("{}", case_header());
    let scratch = std::env::temp_dir();
    for choice in choices {
        let mut c = case.clone();
        c.settings.hierarchy = choice;
        for _ in 0..b.repeat {
            let run = run_case(&c, &scratch, b.pictures, b.write_parts)?;
            println!("{}", case_row(&run));
            if b.phases {
                println!("{}", solver_phases_row(&run.solver_phases));
            }
            if !run.write_parts.is_empty() {
                println!("{}", write_parts_row(&run.write_parts));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row is noted only when the host took more than a clock tick or two, with the
    /// seconds it took; rounding noise and unknown figures add nothing.
    #[test]
    fn stolen_time_is_noted_only_when_it_counts() {
        assert_eq!(stolen_note(None), "");
        assert_eq!(stolen_note(Some(0.0)), "");
        assert_eq!(stolen_note(Some(0.01)), "");
        assert_eq!(stolen_note(Some(0.254)), "  (host took 0.25 s of CPU)");
    }
}
