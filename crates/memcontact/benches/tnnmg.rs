//! `cargo bench -p memcontact --bench tnnmg [-- N1 N2 ...] [-- --lumped|--consistent]`:
//! the standard benchmark table of issue 4 (see `memcontact::bench`). Sizes default to
//! 128 … 2048 cells per side. Environment: `MEMCONTACT_PHASES=1` prints the phases,
//! `MEMCONTACT_NESTED_TOL`, `MEMCONTACT_CYCLES`, `MEMCONTACT_SMOOTHING`,
//! `MEMCONTACT_NO_NESTED` override the TNNMG options.

use memcontact::bench::{run_bench, BenchRow};
use memcontact::model::Foundation;
use memcontact::solve::multigrid::Options;

/// `-- --micro N`: times the kernels of one V-cycle on the N × N benchmark mesh.
fn micro(n: usize) {
    use memcontact::solve::multigrid::{Levels, Multigrid};
    use std::time::Instant;
    let h = memcontact::bench::mesh(n).unwrap();
    let m = memcontact::bench::model(h.finest(), Foundation::Lumped).unwrap();
    let levels = Levels::new(&h, &m.dofs, m.s.pattern.clone()).unwrap();
    let mut mg = Multigrid::new(&levels, levels.len() - 1);
    mg.update(&m.s, None).unwrap();
    let mut x = vec![0.0; m.n()];
    let mut y = vec![0.0; m.n()];
    let reps = 10;
    let t0 = Instant::now();
    for _ in 0..reps {
        m.s.mul_into(&x, &mut y);
    }
    println!("matvec      {:.2} ms", t0.elapsed().as_secs_f64() * 1e3 / reps as f64);
    let t0 = Instant::now();
    for _ in 0..reps {
        mg.v_cycle(&m.s, &mut x, &m.d);
    }
    println!("V(1,1)      {:.2} ms", t0.elapsed().as_secs_f64() * 1e3 / reps as f64);
    let t0 = Instant::now();
    for _ in 0..reps {
        mg.update(&m.s, None).unwrap();
    }
    println!("galerkin    {:.2} ms", t0.elapsed().as_secs_f64() * 1e3 / reps as f64);
    let t0 = Instant::now();
    for _ in 0..reps {
        memcontact::solve::local::sweep_forward(&m, &mut x);
    }
    println!("nonsmooth   {:.2} ms", t0.elapsed().as_secs_f64() * 1e3 / reps as f64);
    let t0 = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(m.certificate(&x));
    }
    println!("certificate {:.2} ms", t0.elapsed().as_secs_f64() * 1e3 / reps as f64);
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
