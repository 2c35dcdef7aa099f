//! `memcontact convergence`: the case's `[exact]` section, the convergence table, its CSV
//! and log-log plot, the lumped/consistent and nodal/mollified comparisons and the
//! rigid-limit sweep. The numerics are in `memcontact::convergence`.

use crate::progress::{Progress, Verbosity};
use anyhow::{anyhow, bail, Context, Result};
use memcontact::case::{BenchmarkBody, ExactSpec, ManufacturedDomain, ManufacturedForm};
use memcontact::discretization::BoundData;
use memcontact::field::Stiffness as FieldStiffness;
use memcontact::io::csv::write_columns_csv;
use memcontact::io::result_set::ResultSet;
use memcontact::io::vtu::DataArray;
use memcontact::mesh::refine::Hierarchy;
use memcontact::model::{Foundation, ProblemData, Sampling};
use memcontact::problem::MeshSource;
use memcontact::verify::convergence::{
    self as study, LevelResult, ManufacturedLoad, Study, StudySettings, Sweep, Target,
};
use memcontact::verify::exact::{
    BenchmarkKind, DiskSolution, ExactSolution, Manufactured, ManufacturedCosine, ObstacleBenchmark,
};
use memcontact::write::{input_hash, new_run_id, write_manifest, MANIFEST};
use memcontact::Case;
use memcontact_plot as plot;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The stiffnesses of `--h-sweep` when `--h-values` is not given: 10, 10², ..., 10⁶.
const DEFAULT_SWEEP: [f64; 6] = [1e1, 1e2, 1e3, 1e4, 1e5, 1e6];

/// The largest `--levels` accepted (each level multiplies the triangles by 4).
const MAX_LEVELS: usize = 10;

/// Which variants `--compare` runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Compare {
    /// The paper's consistent foundation matrix against the lumped diagonal.
    Foundation,
    /// Nodal sampling of φ against the paper's mollified sampling.
    Sampling,
}

/// Arguments of `memcontact convergence`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The case file (TOML); its `[exact]` section names the exact solution (without one,
    /// errors are measured against the finest level's solution).
    pub case: PathBuf,
    /// Refinement levels beyond the case's mesh (K ≥ 1: K + 1 meshes are solved). With
    /// --h-sweep: the fixed mesh is the case's mesh refined K times (K ≥ 0).
    #[arg(long, value_name = "K")]
    pub levels: usize,
    /// Output directory (created if needed).
    #[arg(short, long, default_value = "out")]
    pub output: PathBuf,
    /// Override a case key, e.g. --set mesh.size=0.2 --set obstacle.foundation=lumped.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Run the study for both variants (consistent and lumped L, or nodal and mollified φ)
    /// and write convergence-<variant>.csv for each.
    #[arg(long, value_enum, conflicts_with = "h_sweep")]
    pub compare: Option<Compare>,
    /// Instead of the study: the rigid limit. On the fixed mesh, solve with the obstacle
    /// rigid and with each constant stiffness h, and write h_sweep.csv and h_sweep.png.
    #[arg(long)]
    pub h_sweep: bool,
    /// The stiffnesses of --h-sweep, comma separated (default 10,100,...,1e6).
    #[arg(
        long,
        value_delimiter = ',',
        requires = "h_sweep",
        value_name = "H,H,..."
    )]
    pub h_values: Vec<f64>,
    /// Print no progress lines.
    #[arg(short, long)]
    pub quiet: bool,
    /// Replace the output directory even if it holds files that are not a result.
    #[arg(long)]
    pub force: bool,
}

/// The exact solution a case names in `[exact]`.
pub enum Exact {
    /// `kind = "disk"`: the axisymmetric disc (Bessel functions).
    Disk(DiskCase),
    /// `kind = "manufactured"`: the load is replaced by `f = −tΔu + h(u − φ)⁺` (less the
    /// body below's reaction) and the heights of the fixed boundary by u.
    Manufactured(Manufactured),
    /// `kind = "manufactured"`, `form = "cosine"`: the same with a u whose normal
    /// derivative vanishes on every side of the rectangle.
    Cosine(ManufacturedCosine),
    /// `kind = "petsc-ex9"` or `"mfem-ex36"`: the rigid spherical obstacle benchmarks.
    Benchmark(ObstacleBenchmark),
}

impl Exact {
    /// The solution as the library's trait object.
    pub fn solution(&self) -> &dyn ExactSolution {
        match self {
            Exact::Disk(d) => &d.solution,
            Exact::Manufactured(m) => m,
            Exact::Cosine(m) => m,
            Exact::Benchmark(b) => b,
        }
    }

    /// Whether the load and the boundary heights are replaced by the manufactured ones.
    fn manufactured(&self) -> bool {
        matches!(self, Exact::Manufactured(_) | Exact::Cosine(_))
    }
}

/// The exact solution as a coefficient: the heights of the fixed boundary of a
/// manufactured case.
struct ExactHeight<'a>(&'a dyn ExactSolution);

impl memcontact::field::Coefficient for ExactHeight<'_> {
    fn at(&self, p: [f64; 2], _: u32) -> f64 {
        if self.0.contains(p) {
            self.0.value(p)
        } else {
            f64::NAN
        }
    }
    fn on_region(&self, _: u32) -> Option<f64> {
        None
    }
}

/// The disc's solution and the constants it was built from (for the rigid-limit sweep).
pub struct DiskCase {
    /// The solution with the case's h (or rigid).
    pub solution: DiskSolution,
    center: [f64; 2],
    radius: f64,
    t: f64,
    f: f64,
    phi: f64,
}

impl DiskCase {
    /// The same disc with another stiffness (`None`: rigid).
    fn with_stiffness(&self, h: Option<f64>) -> memcontact::Result<DiskSolution> {
        DiskSolution::new(self.center, self.radius, self.t, self.f, h, self.phi)
    }
}

/// Builds the exact solution the case names in `[exact]` (`None` when it has none);
/// errors for a kind that does not fit the mesh generator, or data the kind cannot take.
pub fn parse_exact(case: &Case) -> Result<Option<Exact>> {
    let Some(spec) = &case.exact else {
        return Ok(None);
    };
    let kind = spec.kind();
    let p = &case.problem;
    let disc_geometry = || -> Result<([f64; 2], f64)> {
        match p.mesh.source {
            MeshSource::Disk { center, radius, .. } => Ok((center, radius)),
            _ => bail!(
                "[exact] kind = \"{kind}\" on a disc needs [mesh] generator = \"disk\" (its \
                 centre and radius define the domain); this case uses {}",
                describe_mesh(case)
            ),
        }
    };
    let t = p.membrane.tension;
    match spec {
        ExactSpec::Disk {} => {
            let (center, radius) = disc_geometry()?;
            let constant = |name: &str, f: &memcontact::field::Field| -> Result<f64> {
                f.constant().ok_or_else(|| {
                    anyhow!(
                        "[exact] kind = \"disk\" needs a constant {name} (the closed form is for \
                         constant t, f, h, φ), not an expression or a table of different values"
                    )
                })
            };
            let f = constant("membrane.load", &p.membrane.load)?;
            let phi = constant("obstacle.shape", &p.obstacle.shape)?;
            let h = match &p.obstacle.stiffness {
                FieldStiffness::Rigid => None,
                FieldStiffness::Elastic(h) => Some(constant("obstacle.stiffness", h)?),
                FieldStiffness::Mixed(_) => bail!(
                    "[exact] kind = \"disk\" needs a constant obstacle.stiffness (the closed \
                     form is for constant t, f, h, φ), not a table with rigid regions"
                ),
            };
            let solution = DiskSolution::new(center, radius, t, f, h, phi)
                .context("[exact] kind = \"disk\"")?;
            Ok(Some(Exact::Disk(DiskCase {
                solution,
                center,
                radius,
                t,
                f,
                phi,
            })))
        }
        &ExactSpec::Manufactured {
            domain,
            amplitude,
            form,
        } => {
            if p.obstacle.stiffness.field().is_none()
                || p.lower
                    .as_ref()
                    .is_some_and(|b| b.stiffness.field().is_none())
            {
                bail!(
                    "[exact] kind = \"manufactured\" needs a finite obstacle.stiffness h (and a \
                     finite lower.stiffness with a body below): its load f = −tΔu + h(u − φ)⁺ \
                     has no meaning for a rigid body or rigid regions"
                );
            }
            if form == ManufacturedForm::Cosine {
                let MeshSource::Rectangle { x0, y0, x1, y1, .. } = p.mesh.source else {
                    bail!(
                        "[exact] form = \"cosine\" needs [mesh] generator = \"rectangle\" (its \
                         x0, y0, x1, y1 define the domain); this case uses {}",
                        describe_mesh(case)
                    );
                };
                if domain != ManufacturedDomain::Rectangle {
                    bail!("[exact] form = \"cosine\" needs domain = \"rectangle\"");
                }
                let m = ManufacturedCosine::rectangle(x0, y0, x1, y1, amplitude)
                    .context("[exact] kind = \"manufactured\"")?;
                return Ok(Some(Exact::Cosine(m)));
            }
            if !p.boundary.free.is_empty() {
                bail!(
                    "[exact] kind = \"manufactured\" with u vanishing on the boundary needs the \
                     whole boundary fixed (boundary.free = {:?}): its normal derivative does not \
                     vanish on a free side; use form = \"cosine\"",
                    p.boundary.free
                );
            }
            let m = match domain {
                ManufacturedDomain::Rectangle => match p.mesh.source {
                    MeshSource::Rectangle { x0, y0, x1, y1, .. } => {
                        Manufactured::rectangle(x0, y0, x1, y1, amplitude)
                    }
                    _ => bail!(
                        "[exact] domain = \"rectangle\" needs [mesh] generator = \
                         \"rectangle\" (its x0, y0, x1, y1 define the domain); this case \
                         uses {}",
                        describe_mesh(case)
                    ),
                },
                ManufacturedDomain::Disk => {
                    let (center, radius) = disc_geometry()?;
                    Manufactured::disk(center, radius, amplitude)
                }
            }
            .context("[exact] kind = \"manufactured\"")?;
            Ok(Some(Exact::Manufactured(m)))
        }
        ExactSpec::PetscEx9 { body } | ExactSpec::MfemEx36 { body } => {
            let kind = if matches!(spec, ExactSpec::PetscEx9 { .. }) {
                BenchmarkKind::PetscEx9
            } else {
                BenchmarkKind::MfemEx36
            };
            let name = spec.kind();
            match (kind, &p.mesh.source) {
                (BenchmarkKind::PetscEx9, MeshSource::Rectangle { x0, y0, x1, y1, .. })
                    if [*x0, *y0, *x1, *y1] == [-2.0, -2.0, 2.0, 2.0] => {}
                (BenchmarkKind::PetscEx9, _) => bail!(
                    "[exact] kind = \"{name}\" needs [mesh] generator = \"rectangle\" with \
                     x0 = y0 = -2, x1 = y1 = 2; this case uses {}",
                    describe_mesh(case)
                ),
                (BenchmarkKind::MfemEx36, MeshSource::Disk { center, radius, .. })
                    if *center == [0.0, 0.0] && *radius == 1.0 => {}
                (BenchmarkKind::MfemEx36, _) => bail!(
                    "[exact] kind = \"{name}\" needs [mesh] generator = \"disk\" with center = \
                     [0, 0] and radius = 1; this case uses {}",
                    describe_mesh(case)
                ),
            }
            if p.membrane.load.constant() != Some(0.0) || t != 1.0 {
                bail!("[exact] kind = \"{name}\" needs membrane.load = 0 and membrane.tension = 1");
            }
            let below = *body == BenchmarkBody::Lower;
            let (rigid, key) = if below {
                (
                    p.lower.as_ref().is_some_and(|b| b.stiffness.is_rigid()),
                    "lower",
                )
            } else {
                (p.obstacle.stiffness.is_rigid(), "obstacle")
            };
            if !rigid {
                bail!("[exact] kind = \"{name}\" needs {key}.stiffness = \"rigid\"");
            }
            if below && p.obstacle.stiffness.field().and_then(|h| h.constant()) != Some(0.0) {
                bail!(
                    "[exact] kind = \"{name}\" with body = \"lower\" needs no obstacle above: \
                     obstacle.stiffness = 0"
                );
            }
            if !below && p.lower.is_some() {
                bail!("[exact] kind = \"{name}\" has no body below: remove [lower]");
            }
            Ok(Some(Exact::Benchmark(ObstacleBenchmark::new(kind, below))))
        }
    }
}

/// Checks that the case describes the benchmark `b` on `mesh`: the rigid body's surface at
/// every vertex and the heights on the fixed boundary agree with the closed form.
fn check_benchmark(
    b: &ObstacleBenchmark,
    case: &Case,
    mesh: &memcontact::mesh::Mesh,
    fields: &BoundData,
) -> Result<()> {
    let (surface, key) = if b.below() {
        (
            &fields.lower.as_ref().expect("checked by parse_exact").shape,
            "lower.shape",
        )
    } else {
        (&fields.shape, "obstacle.shape")
    };
    let adj = memcontact::mesh::VertexTriangles::new(mesh);
    let (fixed, heights) =
        memcontact::model::fixed_heights(mesh, &adj, &fields.extensions(&case.problem))?;
    let tol = 1e-9;
    for (v, &p) in mesh.points.iter().enumerate() {
        let region = mesh.regions[adj.of(v)[0] as usize];
        let (given, expected) = (surface.eval(p, region), b.surface(p));
        if (given - expected).abs() > tol {
            bail!(
                "[exact] kind = \"{}\": {key} is {given} at ({}, {}), the benchmark's \
                 surface is {expected} there",
                case.exact.as_ref().map_or("", |e| e.kind()),
                p[0],
                p[1]
            );
        }
        if fixed[v] && (heights[v] - b.value(p)).abs() > tol {
            bail!(
                "[exact] kind = \"{}\": boundary.height is {} at ({}, {}), the benchmark's u \
                 is {} there (g = u on the boundary)",
                case.exact.as_ref().map_or("", |e| e.kind()),
                heights[v],
                p[0],
                p[1],
                b.value(p)
            );
        }
    }
    Ok(())
}

fn describe_mesh(case: &Case) -> String {
    match &case.problem.mesh.source {
        MeshSource::File(f) => format!("the mesh file {}", f.display()),
        _ => format!("generator = \"{}\"", case.problem.mesh.kind()),
    }
}

/// One variant of the problem (the case itself, or one side of `--compare`).
struct Variant {
    name: &'static str,
    foundation: Foundation,
    sampling: Sampling,
}

fn variants(case: &Case, compare: Option<Compare>) -> Vec<Variant> {
    let o = &case.problem.obstacle;
    match compare {
        None => vec![Variant {
            name: "",
            foundation: o.foundation,
            sampling: o.sampling(),
        }],
        Some(Compare::Foundation) => {
            let sampling = o.sampling();
            vec![
                Variant {
                    name: "consistent",
                    foundation: Foundation::Consistent,
                    sampling,
                },
                Variant {
                    name: "lumped",
                    foundation: Foundation::Lumped,
                    sampling,
                },
            ]
        }
        Some(Compare::Sampling) => vec![
            Variant {
                name: "nodal",
                foundation: o.foundation,
                sampling: Sampling::Nodal,
            },
            Variant {
                name: "mollified",
                foundation: o.foundation,
                sampling: Sampling::Mollified { epsilon: o.epsilon },
            },
        ],
    }
}

/// `memcontact convergence`.
pub fn run(args: &Args) -> Result<()> {
    if args.levels == 0 && !args.h_sweep {
        bail!("--levels must be at least 1 for a convergence study (K + 1 meshes are solved)");
    }
    let case = Case::load(&args.case, &args.sets)?;
    let label = args.case.display().to_string();
    let file_name = args
        .case
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let exact = parse_exact(&case)?;
    let settings = case.settings.clone();
    let t = case.problem.membrane.tension;
    if args.levels > MAX_LEVELS {
        bail!(
            "--levels {} is too large (at most {MAX_LEVELS}: each level multiplies the triangles by 4)",
            args.levels
        );
    }
    let (mut hierarchy, warnings) = memcontact::discretization::build_mesh(&case.problem.mesh)?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let fields = BoundData::new(&case.problem, hierarchy.finest())?;
    if let Some(Exact::Benchmark(b)) = &exact {
        check_benchmark(b, &case, hierarchy.finest(), &fields)?;
    }
    let manufactured_load;
    let load: &dyn memcontact::field::Coefficient = match &exact {
        Some(e) if e.manufactured() => {
            manufactured_load = ManufacturedLoad {
                exact: e.solution(),
                tension: t,
                stiffness: fields
                    .stiffness
                    .as_ref()
                    .expect("elastic, checked by parse_exact"),
                shape: &fields.shape,
                lower: fields.lower.as_ref().map(|b| {
                    (
                        b.stiffness
                            .as_ref()
                            .expect("elastic, checked by parse_exact")
                            as &dyn memcontact::field::Coefficient,
                        &b.shape as &dyn memcontact::field::Coefficient,
                    )
                }),
            };
            &manufactured_load
        }
        _ => &fields.load,
    };
    // The data beyond the paper's frame; a manufactured u also gives the fixed boundary
    // its heights.
    let exact_height = exact.as_ref().map(|e| ExactHeight(e.solution()));
    let mut extensions = fields.extensions(&case.problem);
    if let (Some(e), Some(h)) = (&exact, &exact_height) {
        if e.manufactured() {
            extensions.boundary = Some(memcontact::model::BoundaryData {
                free: &case.problem.boundary.free,
                height: h,
            });
        }
    }
    // The problem data of one variant (foundation, sampling) of the case.
    let data_for = |v: &Variant| ProblemData {
        load,
        foundation: v.foundation,
        sampling: v.sampling,
        ..fields.data(&case.problem)
    };
    // Every file of the study is written into a staging directory and moved into place
    // together at the end: a failed level leaves the previous study untouched.
    let set = ResultSet::begin(&args.output, args.force)?;
    let mut out = String::new();
    let _ = writeln!(out, "memcontact convergence: {label}");
    match &exact {
        Some(e) => {
            let _ = writeln!(out, "  exact        {}", e.solution().describe());
        }
        None => {
            let _ = writeln!(
                out,
                "  exact        none: errors against the finest level's solution (reference)"
            );
        }
    }
    if exact.as_ref().is_some_and(Exact::manufactured) {
        let _ = writeln!(
            out,
            "  load         membrane.load replaced by the manufactured f = −tΔu + h(u − φ)⁺{}",
            if case.problem.lower.is_some() {
                " − h_low(φ_low − u)⁺"
            } else {
                ""
            }
        );
        let _ = writeln!(
            out,
            "  boundary     the fixed boundary's heights replaced by the manufactured u{}",
            if case.problem.boundary.free.is_empty() {
                String::new()
            } else {
                format!(" (free: {})", case.problem.boundary.free.join(", "))
            }
        );
    }
    if args.h_sweep {
        let base = memcontact::limits::MeshSize::of(hierarchy.finest());
        memcontact::limits::check_mesh_fits(
            base,
            args.levels,
            &format!(
                "--h-sweep --levels {} on a mesh of {:.0} triangles",
                args.levels, base.triangles
            ),
        )?;
        hierarchy.refine(args.levels);
        let hs: Vec<f64> = if args.h_values.is_empty() {
            DEFAULT_SWEEP.to_vec()
        } else {
            args.h_values.clone()
        };
        let v = &variants(&case, None)[0];
        let data = data_for(v);
        let spinner = Progress::new(Verbosity::of(args.quiet, false));
        spinner.line(&format!(
            "h sweep on {} vertices: rigid, then h = {:?}",
            hierarchy.finest().n_vertices(),
            hs
        ));
        spinner.message("solving …");
        let sweep = study::rigid_limit_sweep(&hierarchy, &data, &hs, &settings);
        spinner.finish();
        let sweep = sweep?;
        let disk = match &exact {
            Some(Exact::Disk(d)) => Some(d),
            _ => None,
        };
        out.push_str(&sweep_report(
            &file_name,
            &hierarchy,
            &sweep,
            disk,
            v,
            set.dir(),
        )?);
        write_manifest(set.dir(), "h sweep", &new_run_id(), &input_hash(&case))?;
        set.commit()?;
        let _ = writeln!(
            out,
            "  wrote        {}/{{h_sweep.csv, h_sweep.png, manifest.json}}",
            args.output.display()
        );
        print!("{out}");
        return Ok(());
    }
    let study_settings = StudySettings {
        levels: args.levels,
        solver: settings,
    };
    let mut studies: Vec<(Variant, Study)> = Vec::new();
    for v in variants(&case, args.compare) {
        let data = data_for(&v);
        let target = match (&exact, studies.first()) {
            (Some(e), _) => Target::Exact(e.solution()),
            (None, None) => Target::Finest,
            (None, Some((_, first))) => Target::Discrete(&first.finest_u),
        };
        let label = if v.name.is_empty() {
            String::new()
        } else {
            format!("[{}] ", v.name)
        };
        // A bar over the K + 1 levels on a terminal; one line per level either way.
        let total = args.levels + 1;
        let mut bar = Progress::new(Verbosity::of(args.quiet, false));
        bar.set_prefix(&label);
        bar.steps(0, total);
        bar.message("level 0 …");
        let mut progress = |r: &LevelResult| {
            bar.line(&format!(
                "  {label}level {}: {} vertices, {} {} iterations, assembly {:.2} s, solve {:.2} s",
                r.level,
                r.vertices,
                r.method.name(),
                r.iterations,
                r.assembly_seconds,
                r.solve_seconds
            ));
            bar.steps(r.level + 1, total);
            bar.message(&format!("level {} …", r.level + 1));
        };
        let s = study::run_with(
            hierarchy.clone(),
            &data,
            &extensions,
            target,
            &study_settings,
            &mut progress,
        );
        bar.finish();
        studies.push((v, s?));
    }
    let reference_note = match (&exact, args.compare) {
        (Some(_), _) => None,
        (None, None) => Some("errors against the finest level's solution".to_string()),
        (None, Some(_)) => Some(format!(
            "errors of every variant against the finest level of the {} variant",
            studies[0].0.name
        )),
    };
    let mut plot_series = Vec::new();
    let mut written = Vec::new();
    for (v, s) in &studies {
        out.push_str(&table(
            &case,
            v,
            s,
            exact.is_some(),
            reference_note.as_deref(),
        ));
        let file = if v.name.is_empty() {
            "convergence.csv".to_string()
        } else {
            format!("convergence-{}.csv", v.name)
        };
        write_csv(&set.dir().join(&file), s)?;
        written.push(file);
        let suffix = if v.name.is_empty() {
            String::new()
        } else {
            format!(" ({})", v.name)
        };
        let pts = |f: &dyn Fn(&LevelResult) -> Option<f64>| -> Vec<(f64, f64)> {
            s.levels
                .iter()
                .filter_map(|r| f(r).map(|e| (r.l_n, e)))
                .collect()
        };
        plot_series.push((
            format!("L² error{suffix}"),
            pts(&|r| r.errors.map(|e| e.l2)),
        ));
        plot_series.push((
            format!("H¹ error{suffix}"),
            pts(&|r| r.errors.map(|e| e.h1_semi)),
        ));
    }
    let title = format!("Convergence: {file_name}");
    plot::loglog_plot(
        &set.dir().join("convergence.png"),
        &title,
        "mesh size lₙ",
        if exact.is_some() {
            "error against the exact solution"
        } else {
            "error against the reference solution"
        },
        &plot_series,
        &[1.0, 2.0],
    )?;
    written.push("convergence.png".into());
    write_manifest(set.dir(), "convergence", &new_run_id(), &input_hash(&case))?;
    written.push(MANIFEST.into());
    set.commit()?;
    let _ = writeln!(
        out,
        "  wrote        {}/{{{}}}",
        args.output.display(),
        written.join(", ")
    );
    print!("{out}");
    Ok(())
}

/// A number in the table, or a dash.
fn sci(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.3e}"),
        _ => "—".into(),
    }
}

fn rate(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.2}"),
        _ => "—".into(),
    }
}

/// The human table of one study.
fn table(case: &Case, v: &Variant, s: &Study, exact: bool, reference: Option<&str>) -> String {
    let mut o = String::new();
    let sampling = match v.sampling {
        Sampling::Nodal => "nodal".to_string(),
        Sampling::Mollified { epsilon: None } => "mollified (paper's ε_n)".to_string(),
        Sampling::Mollified { epsilon: Some(e) } => format!("mollified (ε = {e})"),
    };
    let _ = writeln!(
        o,
        "\n  {}foundation {}, sampling {}, solver {} (tolerance {:.0e}){}",
        if v.name.is_empty() {
            String::new()
        } else {
            format!("[{}] ", v.name)
        },
        if case.problem.obstacle.stiffness.is_rigid() {
            "rigid"
        } else {
            v.foundation.name()
        },
        sampling,
        case.settings.method.name(),
        case.settings.tolerance,
        reference.map(|r| format!("; {r}")).unwrap_or_default()
    );
    if let Some(low) = &case.problem.lower {
        let _ = writeln!(
            o,
            "  body below: {}",
            if low.stiffness.is_rigid() {
                "rigid"
            } else {
                low.foundation.name()
            }
        );
    }
    let radius = exact && s.levels.iter().any(|r| r.contact_radius_error.is_some());
    let _ = write!(
        o,
        "  {:>5} {:>9} {:>10} {:>10} {:>5} {:>10} {:>5} {:>10} {:>5}",
        "level", "vertices", "l_n", "L² error", "rate", "H¹ error", "rate", "max nodal", "rate"
    );
    if radius {
        let _ = write!(o, " {:>10} {:>10}", "radius a_h", "|a_h − a|");
    } else if !exact {
        let _ = write!(o, " {:>10} {:>5}", "H¹ Δu_k", "rate");
    }
    let _ = writeln!(o, " {:>6} {:>10} {:>8}", "iters", "method", "solve s");
    for (k, r) in s.levels.iter().enumerate() {
        let e = r.errors;
        let _ = write!(
            o,
            "  {:>5} {:>9} {:>10.4e} {:>10} {:>5} {:>10} {:>5} {:>10} {:>5}",
            r.level,
            r.vertices,
            r.l_n,
            sci(e.map(|e| e.l2)),
            rate(s.l2_rates[k]),
            sci(e.map(|e| e.h1_semi)),
            rate(s.h1_rates[k]),
            sci(e.map(|e| e.max_nodal)),
            rate(s.max_nodal_rates[k]),
        );
        if radius {
            let _ = write!(
                o,
                " {:>10.6} {:>10}",
                r.contact.radius,
                sci(r.contact_radius_error)
            );
        } else if !exact {
            let _ = write!(
                o,
                " {:>10} {:>5}",
                sci(r.increment.map(|d| d[1])),
                rate(s.h1_increment_rates[k])
            );
        }
        let _ = writeln!(
            o,
            " {:>6} {:>10} {:>8.3}",
            r.iterations,
            r.method.name(),
            r.solve_seconds
        );
    }
    // The same note on several levels is printed once, with the levels it applies to.
    let mut notes: Vec<(&str, Vec<usize>)> = Vec::new();
    for r in &s.levels {
        if let Some(n) = &r.note {
            match notes.iter_mut().find(|(m, _)| *m == n.as_str()) {
                Some((_, levels)) => levels.push(r.level),
                None => notes.push((n, vec![r.level])),
            }
        }
    }
    for (n, levels) in notes {
        let l: Vec<String> = levels.iter().map(|l| l.to_string()).collect();
        let _ = writeln!(
            o,
            "  note: level{} {}: {n}",
            if l.len() > 1 { "s" } else { "" },
            l.join(", ")
        );
    }
    if let (Some(Some(l2)), Some(Some(h1))) = (s.l2_rates.last(), s.h1_rates.last()) {
        let _ = writeln!(
            o,
            "  last rates   L² {l2:.3}, H¹ {h1:.3} (optimal for P1: 2 and 1)"
        );
    }
    o
}

/// An owned CSV column: floats (NaN for a missing value, written as an empty field) or
/// integers.
enum Column {
    F(Vec<f64>),
    I(Vec<i32>),
}

/// Writes named columns atomically with [`write_columns_csv`].
fn write_csv_columns(path: &Path, columns: &[(&str, Column)]) -> Result<()> {
    let arrays: Vec<(&str, DataArray)> = columns
        .iter()
        .map(|(name, c)| {
            (
                *name,
                match c {
                    Column::F(v) => DataArray::F64(v),
                    Column::I(v) => DataArray::I32(v),
                },
            )
        })
        .collect();
    write_columns_csv(path, &arrays)?;
    Ok(())
}

/// Writes one study as CSV: the required columns `level, vertices, l_n, l2_error,
/// h1_error, max_nodal_error, l2_rate, h1_rate` first, then the extras (missing values
/// are empty fields).
fn write_csv(path: &Path, s: &Study) -> Result<()> {
    let rows = &s.levels;
    let f = |g: &dyn Fn(usize, &LevelResult) -> Option<f64>| -> Column {
        Column::F(
            rows.iter()
                .enumerate()
                .map(|(k, r)| g(k, r).unwrap_or(f64::NAN))
                .collect(),
        )
    };
    let i = |g: &dyn Fn(&LevelResult) -> usize| -> Column {
        Column::I(rows.iter().map(|r| g(r) as i32).collect())
    };
    let columns = [
        ("level", i(&|r| r.level)),
        ("vertices", i(&|r| r.vertices)),
        ("l_n", f(&|_, r| Some(r.l_n))),
        ("l2_error", f(&|_, r| r.errors.map(|e| e.l2))),
        ("h1_error", f(&|_, r| r.errors.map(|e| e.h1_semi))),
        ("max_nodal_error", f(&|_, r| r.errors.map(|e| e.max_nodal))),
        ("l2_rate", f(&|k, _| s.l2_rates[k])),
        ("h1_rate", f(&|k, _| s.h1_rates[k])),
        ("triangles", i(&|r| r.triangles)),
        ("unknowns", i(&|r| r.unknowns)),
        ("max_nodal_rate", f(&|k, _| s.max_nodal_rates[k])),
        ("contact_area", f(&|_, r| Some(r.contact.area))),
        ("contact_radius", f(&|_, r| Some(r.contact.radius))),
        ("contact_area_error", f(&|_, r| r.contact_area_error)),
        ("contact_radius_error", f(&|_, r| r.contact_radius_error)),
        ("gap_area", f(&|_, r| r.errors.map(|e| e.gap_area))),
        ("gap_l2", f(&|_, r| r.errors.map(|e| e.gap_l2))),
        ("gap_h1", f(&|_, r| r.errors.map(|e| e.gap_h1_semi))),
        ("l2_increment", f(&|_, r| r.increment.map(|d| d[0]))),
        ("h1_increment", f(&|_, r| r.increment.map(|d| d[1]))),
        ("l2_increment_rate", f(&|k, _| s.l2_increment_rates[k])),
        ("h1_increment_rate", f(&|k, _| s.h1_increment_rates[k])),
        ("iterations", i(&|r| r.iterations)),
        ("kkt_residual", f(&|_, r| Some(r.kkt))),
        ("assembly_s", f(&|_, r| Some(r.assembly_seconds))),
        ("solve_s", f(&|_, r| Some(r.solve_seconds))),
        ("error_s", f(&|_, r| Some(r.error_seconds))),
        ("epsilon", f(&|_, r| r.epsilon)),
    ];
    write_csv_columns(path, &columns)
}

/// Prints the h sweep and writes h_sweep.csv and h_sweep.png into `dir`.
fn sweep_report(
    file_name: &str,
    hierarchy: &Hierarchy,
    sweep: &Sweep,
    disk: Option<&DiskCase>,
    v: &Variant,
    dir: &Path,
) -> Result<String> {
    let mesh = hierarchy.finest();
    let q = mesh.quality();
    // The continuous distance at the vertices, when the disc's closed forms are known.
    let continuous: Vec<Option<f64>> = sweep
        .rows
        .iter()
        .map(|r| -> Result<Option<f64>> {
            let Some(d) = disk else { return Ok(None) };
            let rigid = d.with_stiffness(None)?;
            let elastic = d.with_stiffness(Some(r.h))?;
            Ok(Some(mesh.points.iter().fold(0.0f64, |m, &p| {
                m.max((elastic.value(p) - rigid.value(p)).abs())
            })))
        })
        .collect::<Result<_>>()
        .context("the disc's exact solutions for the sweep")?;
    let mut o = String::new();
    let _ = writeln!(
        o,
        "  rigid limit  {} vertices, l_n = {:.4e}, foundation {}; distance of u_h(h) to the \
         discrete rigid solution u_h(∞) (rigid: {} iterations, contact radius {:.6})",
        q.vertices,
        q.l_n,
        v.foundation.name(),
        sweep.rigid_iterations,
        sweep.rigid_contact.radius
    );
    let _ = write!(
        o,
        "  {:>10} {:>12} {:>12} {:>12} {:>10}",
        "h", "max nodal", "H¹ semi", "L²", "radius"
    );
    if disk.is_some() {
        let _ = write!(o, " {:>14}", "exact max |Δu|");
    }
    let _ = writeln!(o, " {:>6} {:>8}", "iters", "solve s");
    for (r, c) in sweep.rows.iter().zip(&continuous) {
        let _ = write!(
            o,
            "  {:>10.1e} {:>12.4e} {:>12.4e} {:>12.4e} {:>10.6}",
            r.h, r.max_nodal, r.h1_semi, r.l2, r.contact.radius
        );
        if disk.is_some() {
            let _ = write!(o, " {:>14}", sci(*c));
        }
        let _ = writeln!(o, " {:>6} {:>8.3}", r.iterations, r.solve_seconds);
    }
    let monotone = sweep
        .rows
        .windows(2)
        .all(|w| w[1].max_nodal < w[0].max_nodal && w[1].h1_semi < w[0].h1_semi);
    let _ = writeln!(
        o,
        "  the distance {} monotonically with h",
        if monotone {
            "decreases"
        } else {
            "does NOT decrease"
        }
    );
    let r = &sweep.rows;
    let col = |g: &dyn Fn(&memcontact::verify::convergence::SweepRow) -> f64| -> Column {
        Column::F(r.iter().map(g).collect())
    };
    write_csv_columns(
        &dir.join("h_sweep.csv"),
        &[
            ("h", col(&|r| r.h)),
            ("max_nodal_distance", col(&|r| r.max_nodal)),
            ("h1_distance", col(&|r| r.h1_semi)),
            ("l2_distance", col(&|r| r.l2)),
            ("contact_area", col(&|r| r.contact.area)),
            ("contact_radius", col(&|r| r.contact.radius)),
            (
                "exact_max_distance",
                Column::F(continuous.iter().map(|c| c.unwrap_or(f64::NAN)).collect()),
            ),
            (
                "iterations",
                Column::I(r.iter().map(|r| r.iterations as i32).collect()),
            ),
            ("solve_s", col(&|r| r.solve_seconds)),
        ],
    )?;
    let mut series = vec![
        (
            "max nodal |u_h(h) − u_h(∞)|".to_string(),
            sweep.rows.iter().map(|r| (r.h, r.max_nodal)).collect(),
        ),
        (
            "H¹ seminorm".to_string(),
            sweep.rows.iter().map(|r| (r.h, r.h1_semi)).collect(),
        ),
    ];
    if disk.is_some() {
        series.push((
            "exact max |u(h) − u(∞)|".to_string(),
            sweep
                .rows
                .iter()
                .zip(&continuous)
                .filter_map(|(r, c)| c.map(|c| (r.h, c)))
                .collect(),
        ));
    }
    plot::loglog_plot(
        &dir.join("h_sweep.png"),
        &format!("Rigid limit: {file_name}"),
        "stiffness h",
        "distance to the rigid solution",
        &series,
        &[-0.5, -1.0],
    )?;
    Ok(o)
}
