//! `memcontact plot DIR`: redraws the pictures of a result directory from its
//! `solution.vtu` and `summary.json`, with the plot options stored when the case was solved
//! (so the files are the same); on a sweep's directory, those of every step.

use anyhow::{bail, Context, Result};
use memcontact::write::{draw_all, load_result, PlotKind};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `memcontact plot`.
// The doc comments below are the command's help text (plain text: `[output]` is a case-file
// section, not an intra-doc link).
#[allow(rustdoc::broken_intra_doc_links)]
#[derive(clap::Args)]
pub struct Args {
    /// The result directory (written by `memcontact solve`), or a sweep's directory (then
    /// every step's pictures are redrawn).
    pub dir: PathBuf,
    /// The pictures to draw, comma-separated: deflection, pressure, liftoff, profile
    /// (default: those chosen in the case's [output] section).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub plots: Option<Vec<String>>,
}

/// Runs `memcontact plot`: on a result directory, or on a sweep's (every step directory
/// that `sweep.csv` lists).
pub fn run(args: &Args) -> Result<()> {
    let sweep_csv = args.dir.join("sweep.csv");
    if !args.dir.join("solution.vtu").exists() && sweep_csv.exists() {
        let text = std::fs::read_to_string(&sweep_csv)
            .with_context(|| format!("cannot read {}", sweep_csv.display()))?;
        let mut any = false;
        for name in text.lines().skip(1).filter_map(|l| l.split(',').nth(1)) {
            let step = args.dir.join(name);
            if step.join("solution.vtu").exists() {
                redraw(&step, args)?;
                any = true;
            }
        }
        if !any {
            bail!(
                "{} lists no step directory with a solution.vtu",
                sweep_csv.display()
            );
        }
        return Ok(());
    }
    redraw(&args.dir, args)
}

/// Redraws the pictures of one result directory.
fn redraw(dir: &Path, args: &Args) -> Result<()> {
    let t0 = Instant::now();
    let loaded = load_result(dir)
        .with_context(|| format!("cannot read the results in {}", dir.display()))?;
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
    let files = draw_all(dir, &loaded.data.view(), &options)?;
    let names: Vec<String> = files
        .iter()
        .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    println!(
        "wrote {}/{{{}}} in {:.2} s",
        dir.display(),
        names.join(", "),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
