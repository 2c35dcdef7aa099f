//! `cargo bench -p memcontact-cli --bench tnnmg [-- N1 N2 ...] [-- --lumped|--consistent]`:
//! the standard benchmark table of `memcontact bench` (see `memcontact::bench`). Sizes default to
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
    println!("{}", memcontact_cli::bench::square_header());
    let phases = std::env::var_os("MEMCONTACT_PHASES").is_some();
    let mut print = |r: &BenchRow| println!("{}", memcontact_cli::bench::square_row(r, phases));
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
