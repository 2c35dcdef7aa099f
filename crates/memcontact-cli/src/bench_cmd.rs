//! `memcontact bench`: the standard benchmark table (Ω = (0,1)², t = 1, f = 20,
//! h = 1000, φ = 0.5 + 0.1 sin(2πx) cos(2πy), N × N "right" mesh, nodal φ, tolerance
//! 1e-10), solved by TNNMG, with one linear Poisson multigrid solve as the yardstick.

use anyhow::{bail, Result};
use memcontact::bench::TnnmgOptions;
use memcontact::model::Foundation;
use memcontact_cli::bench::proc::stolen_seconds;
use memcontact_cli::bench::standard::{run_bench, BenchRow};
use memcontact_cli::bench::{square_header, square_row, stolen_note};

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
    println!("{}", square_header());
    // The host's share of each row: what it took since the previous row was printed.
    let mut stolen_before = stolen_seconds();
    let mut print = |r: &BenchRow| {
        let now = stolen_seconds();
        let stolen = now.zip(stolen_before).map(|(a, b)| a - b);
        stolen_before = now;
        println!("{}{}", square_row(r, phases), stolen_note(stolen));
    };
    run_bench(sizes, &foundations, &TnnmgOptions::default(), &mut print)?;
    Ok(())
}
