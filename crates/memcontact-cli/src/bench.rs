//! `memcontact bench`: the standard benchmark table of issue 4 (Ω = (0,1)², t = 1, f = 20,
//! h = 1000, φ = 0.5 + 0.1 sin(2πx) cos(2πy), N × N "right" mesh, nodal φ, tolerance
//! 1e-10), solved by TNNMG, with one linear Poisson multigrid solve as the yardstick.

use anyhow::{bail, Result};
use memcontact::bench::{run_bench, BenchRow};
use memcontact::model::Foundation;
use memcontact::solve::multigrid::Options;

/// Runs the benchmark for `sizes` (cells per side) and the chosen foundations, printing
/// one row per (size, foundation) as soon as it is measured.
pub fn run(sizes: &[usize], foundation: &str, phases: bool) -> Result<()> {
    let foundations: Vec<Foundation> = match foundation {
        "both" => vec![Foundation::Lumped, Foundation::Consistent],
        "lumped" => vec![Foundation::Lumped],
        "consistent" => vec![Foundation::Consistent],
        f => bail!("--foundation must be lumped, consistent or both, not \"{f}\""),
    };
    if sizes.is_empty() || sizes.iter().any(|&n| n < 2) {
        bail!("--sizes needs cells per side ≥ 2, e.g. --sizes 128,256,512,1024");
    }
    println!(
        "threads: {} (rayon); times in seconds, memory = peak resident set (VmHWM)",
        rayon::current_num_threads()
    );
    println!(
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
    );
    let mut print = |r: &BenchRow| {
        let levels: Vec<String> = r.level_iterations.iter().map(|i| i.to_string()).collect();
        println!(
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
            let f = |p: &[(String, f64)]| {
                p.iter()
                    .map(|(n, t)| format!("{n} {t:.3}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            println!("        tnnmg: {}", f(&r.phases));
            println!("        poisson: {}", f(&r.poisson_phases));
        }
    };
    run_bench(sizes, &foundations, &Options::default(), &mut print)?;
    Ok(())
}
