//! `memcontact plot DIR`: redraws the pictures of a result directory from its
//! `solution.vtu` and `summary.json`, with the plot options stored when the case was solved.

use anyhow::{Context, Result};
use memcontact_plot::{draw_all, result, PlotKind};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `memcontact plot`.
#[derive(clap::Args)]
pub struct Args {
    /// The result directory (written by `memcontact solve`).
    pub dir: PathBuf,
    /// The pictures to draw, comma-separated: deflection, pressure, liftoff, profile
    /// (default: those chosen in the case's [output] section).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub plots: Option<Vec<String>>,
}

/// Runs `memcontact plot`.
pub fn run(args: &Args) -> Result<()> {
    let t0 = Instant::now();
    let loaded = result::load(&args.dir)
        .with_context(|| format!("cannot read the results in {}", args.dir.display()))?;
    for note in &loaded.notes {
        eprintln!("note: {note}");
    }
    let mut options = loaded.options;
    if let Some(list) = &args.plots {
        options.plots = list
            .iter()
            .filter(|s| !s.trim().is_empty())
            .map(|s| s.parse::<PlotKind>())
            .collect::<Result<_, _>>()?;
    }
    if options.plots.is_empty() {
        println!("no pictures to draw (the case's [output] plots is empty)");
        return Ok(());
    }
    let files = draw_all(&args.dir, &loaded.data.view(), &options)?;
    let names: Vec<String> = files
        .iter()
        .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    println!(
        "wrote {}/{{{}}} in {:.2} s",
        args.dir.display(),
        names.join(", "),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
