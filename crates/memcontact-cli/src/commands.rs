//! The `solve` and `check` commands, and the case → mesh → model → solution pipeline they
//! share with the other commands.

use crate::case::{self, Case};
use crate::output;
use anyhow::{Context, Result};
use memcontact::field::{BoundField, Stiffness as FieldStiffness};
use memcontact::mesh::refine::Hierarchy;
use memcontact::mesh::Mesh;
use memcontact::model::{Model, ProblemData, Stiffness};
use memcontact::solve::{self, IterationRecord, Observer, Solution};
use std::path::Path;
use std::time::Instant;

/// Everything a solved case produced.
pub struct Run {
    /// The mesh levels; the finest is the solved mesh.
    pub hierarchy: Hierarchy,
    /// The assembled model.
    pub model: Model,
    /// The solution.
    pub solution: Solution,
    /// Wall-clock seconds: mesh, assembly, solve.
    pub timings: Vec<(String, f64)>,
}

/// Prints one line per iteration on stderr.
struct Progress {
    quiet: bool,
}

impl Observer for Progress {
    fn iteration(&mut self, r: &IterationRecord) {
        if !self.quiet {
            eprintln!(
                "  iteration {:>5}  J = {:+.12e}  KKT = {:.3e}",
                r.iteration, r.energy, r.residual
            );
        }
    }
}

/// The case's data bound to the mesh's regions.
pub struct BoundData {
    load: BoundField,
    shape: BoundField,
    stiffness: Option<BoundField>,
}

impl BoundData {
    /// Binds f, φ and h to the regions of `mesh`.
    pub fn new(case: &Case, mesh: &Mesh) -> Result<BoundData> {
        let mut tags: Vec<u32> = mesh.regions.clone();
        tags.sort_unstable();
        tags.dedup();
        let names = &mesh.region_names;
        Ok(BoundData {
            load: case.membrane.load.bind("membrane.load", names, &tags)?,
            shape: case.obstacle.shape.bind("obstacle.shape", names, &tags)?,
            stiffness: match &case.obstacle.stiffness {
                FieldStiffness::Rigid => None,
                FieldStiffness::Elastic(h) => Some(h.bind("obstacle.stiffness", names, &tags)?),
            },
        })
    }

    /// The library's view of the data.
    pub fn problem<'a>(&'a self, case: &Case) -> Result<ProblemData<'a>> {
        Ok(ProblemData {
            tension: case.tension()?,
            load: &self.load,
            shape: &self.shape,
            stiffness: match &self.stiffness {
                Some(h) => Stiffness::Elastic(h),
                None => Stiffness::Rigid,
            },
            foundation: case.foundation()?,
            sampling: case.sampling()?,
        })
    }
}

/// Assembles the model of `case` on the finest level of `hierarchy`.
pub fn assemble(case: &Case, hierarchy: &Hierarchy) -> Result<Model> {
    let mesh = hierarchy.finest();
    let data = BoundData::new(case, mesh)?;
    Ok(Model::assemble(mesh, &data.problem(case)?)?)
}

/// Runs the pipeline: mesh, assembly, solve.
pub fn run(case: &Case, quiet: bool) -> Result<Run> {
    let settings = case.settings()?;
    let t0 = Instant::now();
    let (hierarchy, warnings) = case.build_mesh()?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let t_mesh = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let model = assemble(case, &hierarchy)?;
    let t_assembly = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let h = (hierarchy.depth() > 1).then_some(&hierarchy);
    let solution = solve::solve(&model, h, &settings, &mut Progress { quiet })?;
    let t_solve = t2.elapsed().as_secs_f64();
    Ok(Run {
        hierarchy,
        model,
        solution,
        timings: vec![
            ("mesh".into(), t_mesh),
            ("assembly".into(), t_assembly),
            ("solve".into(), t_solve),
        ],
    })
}

/// `memcontact solve`.
pub fn solve(case_path: &Path, out: &Path, sets: &[String], quiet: bool) -> Result<()> {
    let t0 = Instant::now();
    let case = case::load(case_path, sets)?;
    let run = run(&case, quiet)?;
    std::fs::create_dir_all(out)
        .with_context(|| format!("cannot create the output directory {}", out.display()))?;
    let report = output::write_all(&case, &run, out, t0)?;
    print!("{report}");
    // The process ends right after this: returning the (possibly gigabytes of) mesh
    // levels and matrices to the allocator page by page would only delay the exit.
    std::mem::forget(run);
    Ok(())
}

/// `memcontact check`.
pub fn check(case_path: &Path, sets: &[String]) -> Result<()> {
    let case = case::load(case_path, sets)?;
    case.settings()?;
    case.tension()?;
    case.foundation()?;
    case.sampling()?;
    let (hierarchy, warnings) = case.build_mesh()?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let mesh = hierarchy.finest();
    // Binding and assembling checks the data on the mesh (regions, signs, NaN).
    let model = assemble(&case, &hierarchy)?;
    println!("case {}: valid", case_path.display());
    print!(
        "{}",
        output::mesh_report(mesh, &mesh.quality(), hierarchy.depth())
    );
    println!(
        "  obstacle     {} vertices can touch (M), foundation {}{}",
        model.can_touch.iter().filter(|&&c| c).count(),
        model.foundation.name(),
        if model.is_rigid() { ", rigid" } else { "" }
    );
    println!(
        "  solver       {} (auto picks {})",
        case.solver.method,
        solve::auto_method(&model, (hierarchy.depth() > 1).then_some(&hierarchy)).name()
    );
    Ok(())
}
