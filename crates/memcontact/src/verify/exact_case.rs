//! A case's `[exact]` section made an exact solution: the closed form it names, checked
//! against the case's mesh generator and data (a disc needs the disc generator and constant
//! data, a manufactured solution a finite stiffness, a benchmark its own domain and rigid
//! body), and the coefficients a manufactured case replaces its data with.

use crate::case::{BenchmarkBody, Case, ExactSpec, ManufacturedDomain, ManufacturedForm};
use crate::discretization::BoundData;
use crate::error::{Error, Result};
use crate::field::{Coefficient, Field, Stiffness};
use crate::mesh::{Mesh, VertexTriangles};
use crate::problem::MeshSource;
use crate::verify::exact::{
    BenchmarkKind, DiskSolution, ExactSolution, Manufactured, ManufacturedCosine, ObstacleBenchmark,
};

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
    pub fn manufactured(&self) -> bool {
        matches!(self, Exact::Manufactured(_) | Exact::Cosine(_))
    }
}

/// The exact solution as a coefficient: the heights of the fixed boundary of a
/// manufactured case (NaN outside its domain, which the data checks refuse).
pub struct ExactHeight<'a>(pub &'a dyn ExactSolution);

impl Coefficient for ExactHeight<'_> {
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
    pub fn with_stiffness(&self, h: Option<f64>) -> Result<DiskSolution> {
        DiskSolution::new(self.center, self.radius, self.t, self.f, h, self.phi)
    }
}

/// `Err` with the message alone (the case as a whole is at fault).
macro_rules! refuse {
    ($($arg:tt)*) => {
        return Err(Error::case(format!($($arg)*)))
    };
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
            _ => refuse!(
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
            let constant = |name: &str, f: &Field| -> Result<f64> {
                f.constant().ok_or_else(|| {
                    Error::case(format!(
                        "[exact] kind = \"disk\" needs a constant {name} (the closed form is for \
                         constant t, f, h, φ), not an expression or a table of different values"
                    ))
                })
            };
            let f = constant("membrane.load", &p.membrane.load)?;
            let phi = constant("obstacle.shape", &p.obstacle.shape)?;
            let h = match &p.obstacle.stiffness {
                Stiffness::Rigid => None,
                Stiffness::Elastic(h) => Some(constant("obstacle.stiffness", h)?),
                Stiffness::Mixed(_) => refuse!(
                    "[exact] kind = \"disk\" needs a constant obstacle.stiffness (the closed \
                     form is for constant t, f, h, φ), not a table with rigid regions"
                ),
            };
            let solution = DiskSolution::new(center, radius, t, f, h, phi)
                .map_err(|e| e.context("[exact] kind = \"disk\""))?;
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
                refuse!(
                    "[exact] kind = \"manufactured\" needs a finite obstacle.stiffness h (and a \
                     finite lower.stiffness with a body below): its load f = −tΔu + h(u − φ)⁺ \
                     has no meaning for a rigid body or rigid regions"
                );
            }
            let context = |e: Error| e.context("[exact] kind = \"manufactured\"");
            if form == ManufacturedForm::Cosine {
                let MeshSource::Rectangle { x0, y0, x1, y1, .. } = p.mesh.source else {
                    refuse!(
                        "[exact] form = \"cosine\" needs [mesh] generator = \"rectangle\" (its \
                         x0, y0, x1, y1 define the domain); this case uses {}",
                        describe_mesh(case)
                    );
                };
                if domain != ManufacturedDomain::Rectangle {
                    refuse!("[exact] form = \"cosine\" needs domain = \"rectangle\"");
                }
                let m =
                    ManufacturedCosine::rectangle(x0, y0, x1, y1, amplitude).map_err(context)?;
                return Ok(Some(Exact::Cosine(m)));
            }
            if !p.boundary.free.is_empty() {
                refuse!(
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
                    _ => refuse!(
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
            .map_err(context)?;
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
                (BenchmarkKind::PetscEx9, _) => refuse!(
                    "[exact] kind = \"{name}\" needs [mesh] generator = \"rectangle\" with \
                     x0 = y0 = -2, x1 = y1 = 2; this case uses {}",
                    describe_mesh(case)
                ),
                (BenchmarkKind::MfemEx36, MeshSource::Disk { center, radius, .. })
                    if *center == [0.0, 0.0] && *radius == 1.0 => {}
                (BenchmarkKind::MfemEx36, _) => refuse!(
                    "[exact] kind = \"{name}\" needs [mesh] generator = \"disk\" with center = \
                     [0, 0] and radius = 1; this case uses {}",
                    describe_mesh(case)
                ),
            }
            if p.membrane.load.constant() != Some(0.0) || t != 1.0 {
                refuse!(
                    "[exact] kind = \"{name}\" needs membrane.load = 0 and membrane.tension = 1"
                );
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
                refuse!("[exact] kind = \"{name}\" needs {key}.stiffness = \"rigid\"");
            }
            if below && p.obstacle.stiffness.field().and_then(|h| h.constant()) != Some(0.0) {
                refuse!(
                    "[exact] kind = \"{name}\" with body = \"lower\" needs no obstacle above: \
                     obstacle.stiffness = 0"
                );
            }
            if !below && p.lower.is_some() {
                refuse!("[exact] kind = \"{name}\" has no body below: remove [lower]");
            }
            Ok(Some(Exact::Benchmark(ObstacleBenchmark::new(kind, below))))
        }
    }
}

/// Checks that the case describes the benchmark `b` on `mesh`: the rigid body's surface at
/// every vertex and the heights on the fixed boundary agree with the closed form.
pub fn check_benchmark(
    b: &ObstacleBenchmark,
    case: &Case,
    mesh: &Mesh,
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
    let adj = VertexTriangles::new(mesh);
    let (fixed, heights) =
        crate::model::fixed_heights(mesh, &adj, &fields.extensions(&case.problem))?;
    let tol = 1e-9;
    let kind = case.exact.as_ref().map_or("", |e| e.kind());
    for (v, &p) in mesh.points.iter().enumerate() {
        let region = mesh.regions[adj.of(v)[0] as usize];
        let (given, expected) = (surface.eval(p, region), b.surface(p));
        if (given - expected).abs() > tol {
            refuse!(
                "[exact] kind = \"{kind}\": {key} is {given} at ({}, {}), the benchmark's \
                 surface is {expected} there",
                p[0],
                p[1]
            );
        }
        if fixed[v] && (heights[v] - b.value(p)).abs() > tol {
            refuse!(
                "[exact] kind = \"{kind}\": boundary.height is {} at ({}, {}), the benchmark's u \
                 is {} there (g = u on the boundary)",
                heights[v],
                p[0],
                p[1],
                b.value(p)
            );
        }
    }
    Ok(())
}

/// The case's mesh, named for messages.
fn describe_mesh(case: &Case) -> String {
    match &case.problem.mesh.source {
        MeshSource::File(f) => format!("the mesh file {}", f.display()),
        MeshSource::Given(g) => format!("a mesh given as data ({})", g.description),
        _ => format!("generator = \"{}\"", case.problem.mesh.kind()),
    }
}
