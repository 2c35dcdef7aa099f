//! `cargo bench -p memcontact --bench tnnmg [-- N1 N2 ...] [-- --lumped|--consistent]`:
//! the standard benchmark table of issue 4 (see `memcontact::bench`). Sizes default to
//! 128 … 2048 cells per side. Environment: `MEMCONTACT_PHASES=1` prints the phases,
//! `MEMCONTACT_NESTED_TOL`, `MEMCONTACT_CYCLES`, `MEMCONTACT_SMOOTHING`,
//! `MEMCONTACT_NO_NESTED` override the TNNMG options.

use memcontact::bench::{run_bench, BenchRow};
use memcontact::model::Foundation;
use memcontact::solve::multigrid::Options;

/// `-- --micro N`: times the kernels of one TNNMG iteration on the N × N benchmark mesh.
fn micro(n: usize) {
    let h = memcontact::bench::mesh(n).unwrap();
    for f in [Foundation::Lumped, Foundation::Consistent] {
        let m = memcontact::bench::model(h.finest(), f).unwrap();
        let t = memcontact::solve::multigrid::kernel_timings(&m, &h, 10).unwrap();
        println!("{}:                      wall ms   cpu ms", f.name());
        for (name, ms, cpu) in t {
            println!("  {name:<24} {ms:8.2} {cpu:8.2}");
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Some(k) = args.iter().position(|a| a == "--micro") {
        let n = args.get(k + 1).and_then(|a| a.parse().ok()).unwrap_or(1024);
        micro(n);
        return;
    }
    let mut sizes: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    if sizes.is_empty() {
        sizes = vec![128, 256, 512, 1024, 2048];
    }
    let foundations: Vec<Foundation> = if args.iter().any(|a| a == "--lumped") {
        vec![Foundation::Lumped]
    } else if args.iter().any(|a| a == "--consistent") {
        vec![Foundation::Consistent]
    } else {
        vec![Foundation::Lumped, Foundation::Consistent]
    };
    println!(
        "{:>5} {:>9} {:>10} {:>5} {:>22} {:>7} {:>7} {:>7} {:>8} {:>9} {:>7} {:>4}",
        "N",
        "unknowns",
        "foundation",
        "its",
        "per level",
        "mesh s",
        "asm s",
        "solve s",
        "peak MB",
        "KKT",
        "poisson",
        "cyc"
    );
    let mut print = |r: &BenchRow| {
        let levels: Vec<String> = r.level_iterations.iter().map(|i| i.to_string()).collect();
        println!(
            "{:>5} {:>9} {:>10} {:>5} {:>22} {:>7.3} {:>7.3} {:>7.3} {:>8.0} {:>9.2e} {:>7.3} {:>4}",
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
            r.poisson_cycles
        );
        if std::env::var_os("MEMCONTACT_PHASES").is_some() {
            let f = |p: &[(String, f64)]| {
                p.iter()
                    .map(|(n, t)| format!("{n} {t:.3}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            println!("      tnnmg: {}", f(&r.phases));
            println!("      poisson: {}", f(&r.poisson_phases));
        }
    };
    let mut options = Options::default();
    if let Some(t) = std::env::var("MEMCONTACT_NESTED_TOL")
        .ok()
        .and_then(|t| t.parse().ok())
    {
        options.nested_tolerance = t;
    }
    if let Some(c) = std::env::var("MEMCONTACT_CYCLES")
        .ok()
        .and_then(|t| t.parse().ok())
    {
        options.cycles = c;
    }
    if let Some(c) = std::env::var("MEMCONTACT_SMOOTHING")
        .ok()
        .and_then(|t| t.parse().ok())
    {
        options.smoothing = (c, c);
    }
    if std::env::var_os("MEMCONTACT_NO_NESTED").is_some() {
        options.nested = false;
    }
    if let Err(e) = run_bench(&sizes, &foundations, &options, &mut print) {
        eprintln!("benchmark failed: {e}");
        std::process::exit(1);
    }
}
