//! `memcontact`: the command-line tool. Parses arguments, reads the case, runs the library,
//! prints a summary and writes the outputs. All the numerics live in the library.

mod adapt_cmd;
#[cfg(feature = "alloc-trace")]
mod alloc_trace;
mod bench_cmd;
mod commands;
mod convergence;
mod examples;
mod plot_cmd;
mod progress;
mod report;
mod sensitivity_cmd;
mod signals;
mod solve_flags;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// mimalloc keeps freed memory for reuse: the solver's large work vectors are not handed
/// back to the kernel and faulted in again page by page on every allocation.
#[cfg(not(feature = "alloc-trace"))]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// With the `alloc-trace` feature (a profiling aid, off by default): mimalloc with a count
/// of live bytes and a table of the large allocations alive at the peak.
#[cfg(feature = "alloc-trace")]
#[global_allocator]
static ALLOCATOR: alloc_trace::Tracing<mimalloc::MiMalloc> =
    alloc_trace::Tracing(mimalloc::MiMalloc);

/// Contact between a stretched membrane and an elastic (Winkler) obstacle: the discrete
/// model of Maceri & Maceri (1986), solved exactly and certified.
///
/// Units are whatever consistent system the case uses: lengths in the mesh's unit,
/// tension t in force/length, load f and pressures in force/area, stiffness h in
/// force/length³.
#[derive(Parser)]
#[command(name = "memcontact", version, about, long_about)]
struct Cli {
    /// Worker threads for the parallel parts (default: one per core).
    #[arg(long, global = true, value_name = "N")]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

// The doc comments below are the command's help text (plain text: `[sweep]` is a case-file
// section, not an intra-doc link).
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(Subcommand)]
enum Command {
    /// Solve a case and write solution.vtu, nodes.csv, the pictures and summary.json.
    ///
    /// The files are written as one set: the output directory is replaced as a whole when
    /// all are complete, so it never mixes two runs. A solve that does not reach the
    /// tolerance writes nothing and exits with status 1 (see --write-unconverged). A case
    /// with [sweep] or [[load_case]] entries solves every step in turn, each from the
    /// previous answer, into a directory per step, with sweep.csv and sweep.png.
    #[command(after_long_help = memcontact::case::keys::reference())]
    Solve {
        /// The case file (TOML).
        case: PathBuf,
        /// Output directory (created if needed; a previous result there is replaced).
        #[arg(short, long, default_value = "out")]
        output: PathBuf,
        /// Override a case key, e.g. --set mesh.nx=128 --set obstacle.foundation=lumped.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Show no progress.
        #[arg(short, long)]
        quiet: bool,
        /// Print every phase and iteration (energy J, the KKT residual and those of 2e
        /// and 2f, the vertex state counts).
        #[arg(short, long, conflicts_with = "quiet")]
        verbose: bool,
        /// Replace the output directory even if it holds files that are not a result.
        #[arg(long)]
        force: bool,
        /// Write the files of a solve that did not converge (summary.json says
        /// "accepted": false; in a sweep, the steps before it too); the exit status is
        /// still 1.
        #[arg(long)]
        write_unconverged: bool,
    },
    /// Validate a case and report its mesh, without solving.
    #[command(after_long_help = memcontact::case::keys::reference())]
    Check {
        /// The case file (TOML).
        case: PathBuf,
        /// Override a case key.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// The file is a fragment of a case (some sections or keys, as the documentation
        /// shows them): check its keys and values on top of the fewest keys that complete
        /// it, without a mesh.
        #[arg(long)]
        fragment: bool,
    },
    /// Measure the convergence of the discrete solution under uniform refinement: errors
    /// against the case's [exact] solution, rates, convergence.csv and convergence.png
    /// (or, with --h-sweep, the distance to the rigid limit).
    Convergence(convergence::Args),
    /// Benchmarks (release build recommended). Without --case or --mesh: the standard
    /// benchmark, TNNMG on the N × N unit square against one linear Poisson multigrid
    /// solve (unknowns, iterations in total and per level, mesh / assembly / solve
    /// seconds, peak memory, the final KKT certificate). With --case and/or --mesh: the
    /// whole run of that case as `solve` does it, phase by phase (reading or generating
    /// the mesh, renumbering, assembly, the solver's setup and iterations, writing the
    /// result set to a scratch directory), with iterations, peak memory and certificate.
    Bench {
        /// Cells per side of the standard benchmark, comma-separated.
        #[arg(long, value_delimiter = ',', default_values_t = [128usize, 256, 512, 1024, 2048])]
        sizes: Vec<usize>,
        /// Standard benchmark: lumped, consistent or both.
        #[arg(long, default_value = "both")]
        foundation: String,
        /// Also print the time per solver phase (the standard benchmark's per size, a case's
        /// after each row).
        #[arg(long)]
        phases: bool,
        /// Benchmark this case file.
        #[arg(long, value_name = "FILE")]
        case: Option<PathBuf>,
        /// Benchmark on this Gmsh mesh (the case's data, or without --case the standard
        /// benchmark's data: t = 1, f = 20, h = 1000, φ = 0.5 + 0.1 sin 2πx cos 2πy).
        #[arg(long, value_name = "FILE")]
        mesh: Option<PathBuf>,
        /// Override a key of the --case file.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Multigrid levels: auto, geometric, algebraic, or both (each in turn, to compare
        /// them on a mesh with refinement levels).
        #[arg(long, default_value = "auto")]
        hierarchy: String,
        /// Runs of each configuration (one row each).
        #[arg(long, default_value_t = 1)]
        repeat: usize,
        /// Also draw the pictures when writing.
        #[arg(long)]
        pictures: bool,
        /// After each run, write its files again one part at a time (solution.vtu,
        /// nodes.csv, the input's hash, with --pictures each picture) and print the
        /// seconds of each part alone: where the time of writing goes.
        #[arg(long)]
        write_parts: bool,
        /// With --mesh: the cost of sensitivities in units of one solve (the energy in
        /// every region's stiffness, one output's adjoint, a fit of the regions'
        /// stiffnesses) on the standard data with a stiffness per region.
        #[arg(long, requires = "mesh")]
        sensitivity: bool,
    },
    /// Redraw the pictures of a result directory (deflection.png, pressure.png,
    /// liftoff.png, profile.png) from its solution.vtu and summary.json, without solving
    /// (identical files); on a sweep's directory, every step's.
    Plot(plot_cmd::Args),
    /// List the example cases, or write one (and any mesh it needs) to a directory.
    Example {
        /// The example to write; omit to list them.
        name: Option<String>,
        /// Directory to write into (created if needed).
        #[arg(short, long, default_value = "examples")]
        dir: PathBuf,
        /// Overwrite existing files.
        #[arg(long)]
        force: bool,
    },
}

/// Transparent huge pages off for this process (Linux). A run touches all its memory once,
/// fresh from the kernel; a fresh 2 MiB page costs the kernel (and a virtual machine's
/// host) far more than 512 small ones. Measured on a 2-core virtual machine, whole runs:
/// the square at N = 1024 in 1.2 s instead of 1.5-1.7 s, at N = 2048 in 4.7-4.9 s instead
/// of 5.9-6.0 s, the same at N = 4096; the compute itself is 2-4 % slower without them.
fn small_pages_only() {
    #[cfg(target_os = "linux")]
    // SAFETY: PR_SET_THP_DISABLE takes plain integers and touches no memory of ours.
    unsafe {
        libc::prctl(libc::PR_SET_THP_DISABLE, 1, 0, 0, 0);
    }
}

fn main() -> ExitCode {
    small_pages_only();
    #[cfg(feature = "alloc-trace")]
    alloc_trace::enable();
    let cli = Cli::parse();
    if let Some(n) = cli.threads {
        if memcontact::parallel::set_threads(n).is_err() {
            eprintln!("error: --threads must be at least 1, got {n}");
            return ExitCode::FAILURE;
        }
    }
    signals::install();
    // The whole command runs on a worker thread of the pool (see memcontact::on_workers).
    let result = memcontact::on_workers(|| match cli.command {
        Command::Solve {
            case,
            output,
            sets,
            quiet,
            verbose,
            force,
            write_unconverged,
        } => commands::solve(
            &case,
            &commands::SolveFlags {
                out: &output,
                sets: &sets,
                verbosity: progress::Verbosity::of(quiet, verbose),
                force,
                write_unconverged,
            },
        ),
        Command::Check {
            case,
            sets,
            fragment,
        } => {
            if fragment {
                commands::check_fragment(&case, &sets)
            } else {
                commands::check(&case, &sets)
            }
        }
        Command::Convergence(args) => convergence::run(&args),
        Command::Plot(args) => plot_cmd::run(&args),
        Command::Example { name, dir, force } => examples::run(name.as_deref(), &dir, force),
        Command::Bench {
            sizes,
            foundation,
            phases,
            case,
            mesh,
            sets,
            hierarchy,
            repeat,
            pictures,
            write_parts,
            sensitivity,
        } => {
            if let (true, Some(m)) = (sensitivity, &mesh) {
                memcontact_cli::bench::sensitivity::run(m, &sets, repeat)
            } else if case.is_some() || mesh.is_some() {
                memcontact_cli::bench::run_case_bench(&memcontact_cli::bench::CaseBench {
                    case,
                    mesh,
                    sets,
                    hierarchy,
                    repeat,
                    pictures,
                    write_parts,
                    phases,
                })
            } else {
                bench_cmd::run(&sizes, &foundation, phases)
            }
        }
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e)
            if e.chain().any(|c| {
                matches!(
                    c.downcast_ref::<memcontact::Error>(),
                    Some(memcontact::Error::Cancelled)
                )
            }) =>
        {
            eprintln!("interrupted: nothing was written (an earlier result stays as it was)");
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {e}");
            for cause in e.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::FAILURE
        }
    }
}
