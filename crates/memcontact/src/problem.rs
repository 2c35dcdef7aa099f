//! The problem description: what a case file (TOML), a Rust program or a Python dict says,
//! as owned serde values. Everything deserialises into the same [`Case`]; unknown keys and
//! bad values are refused here, before any work, with the key (and, for a file, the file
//! and line).
//!
//! A [`Case`] is a [`Problem`] (mesh, membrane, obstacle: the data of the paper's Problem 1
//! and its discretisation), the solver [`Settings`], the [`OutputOptions`] and, for
//! convergence studies, the [`ExactSpec`] of a closed-form solution.

use crate::field::{Field, Stiffness};
use crate::mesh::generate::{self, Diagonal, PolygonSpec, RectangleSpec};
use crate::mesh::refine::Hierarchy;
use crate::model::{Foundation, Sampling};
use crate::resources::{check_mesh_fits, MeshSize};
use crate::solve::Settings;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub use crate::resources::CASE_FILE_CAP;

/// The largest number of uniform refinements accepted (each multiplies the triangles by
/// four); the size of the refined mesh is checked separately against the memory available
/// ([`crate::resources::check_mesh_fits`], before refining).
pub const MAX_REFINE: usize = 12;

/// A whole case: the problem, how to solve it, what to write, and (optionally) its exact
/// solution. The TOML case file has the sections `[mesh]`, `[membrane]`, `[obstacle]`,
/// `[solver]`, `[output]` and `[exact]`, and, beyond the paper's frame, `[boundary]` (heights
/// and free edges) and `[lower]` (a body below).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "CaseFile", into = "CaseFile")]
pub struct Case {
    /// The mesh and the data of the paper's Problem 1.
    pub problem: Problem,
    /// `[solver]`.
    pub settings: Settings,
    /// `[output]`.
    pub output: OutputOptions,
    /// `[exact]`: the closed-form solution this case has, for convergence studies.
    pub exact: Option<ExactSpec>,
    /// `[units]`: the names of the case's units, for labels.
    pub units: Units,
    /// `[sweep]`: one parameter varied over a list of values.
    pub sweep: Option<crate::sweep::SweepSpec>,
    /// `[[load_case]]`: named combinations overriding the case's data.
    pub load_cases: Vec<crate::sweep::LoadCase>,
}

/// `[units]`: the names of the length and force units the case's numbers are in (the
/// solver does not convert; pictures label their axes and colour bars with them).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Units {
    /// Length (mesh coordinates, u, φ), e.g. `"m"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length: Option<String>,
    /// Force, e.g. `"kN"` (t in force/length, f and pressures in force/length²).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<String>,
}

/// The serde shape of [`Case`]: one field per section.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CaseFile {
    mesh: MeshSpec,
    membrane: Membrane,
    obstacle: Obstacle,
    #[serde(default, skip_serializing_if = "Boundary::is_default")]
    boundary: Boundary,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lower: Option<Obstacle>,
    #[serde(default)]
    solver: Settings,
    #[serde(default)]
    output: OutputOptions,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    exact: Option<ExactSpec>,
    #[serde(default)]
    units: Units,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sweep: Option<crate::sweep::SweepSpec>,
    #[serde(default, rename = "load_case", skip_serializing_if = "Vec::is_empty")]
    load_cases: Vec<crate::sweep::LoadCase>,
}

impl From<CaseFile> for Case {
    fn from(c: CaseFile) -> Case {
        Case {
            problem: Problem {
                mesh: c.mesh,
                membrane: c.membrane,
                obstacle: c.obstacle,
                boundary: c.boundary,
                lower: c.lower,
            },
            settings: c.solver,
            output: c.output,
            exact: c.exact,
            units: c.units,
            sweep: c.sweep,
            load_cases: c.load_cases,
        }
    }
}

impl From<Case> for CaseFile {
    fn from(c: Case) -> CaseFile {
        CaseFile {
            mesh: c.problem.mesh,
            membrane: c.problem.membrane,
            obstacle: c.problem.obstacle,
            boundary: c.problem.boundary,
            lower: c.problem.lower,
            solver: c.settings,
            output: c.output,
            exact: c.exact,
            units: c.units,
            sweep: c.sweep,
            load_cases: c.load_cases,
        }
    }
}

/// The problem: a mesh and the data t, f, φ, h of the paper's Problem 1, with the
/// discretisation choices of its §2 (consistent or lumped L, nodal or mollified φ).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Problem {
    /// `[mesh]`: where the triangulation comes from.
    pub mesh: MeshSpec,
    /// `[membrane]`: tension and load.
    pub membrane: Membrane,
    /// `[obstacle]`: the elastic (or rigid) body.
    pub obstacle: Obstacle,
    /// `[boundary]`: the heights on the fixed boundary and the free boundary regions
    /// (default: the whole boundary fixed at 0, as in the paper).
    #[serde(default, skip_serializing_if = "Boundary::is_default")]
    pub boundary: Boundary,
    /// `[lower]`: a second body below the membrane (its surface, stiffness, foundation and
    /// sampling, with the keys of `[obstacle]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower: Option<Obstacle>,
}

/// `[boundary]`: `u = g` on the fixed part of the boundary, the natural condition
/// (no force across the edge) on the free part.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Boundary {
    /// The height g (length): a number, an expression of x and y, a table per boundary
    /// region (Gmsh physical curves; the generators' sides `left`, `right`, `bottom`,
    /// `top`, `outer`, `hole1`, ...), or one value per vertex.
    #[serde(default = "zero_height", skip_serializing_if = "is_zero")]
    pub height: Field,
    /// The boundary regions that are not fixed (names, or tags as text).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub free: Vec<String>,
}

fn zero_height() -> Field {
    Field::Constant(0.0)
}

fn is_zero(f: &Field) -> bool {
    matches!(f, Field::Constant(v) if *v == 0.0)
}

impl Default for Boundary {
    fn default() -> Boundary {
        Boundary {
            height: zero_height(),
            free: Vec::new(),
        }
    }
}

impl Boundary {
    /// The paper's frame: everything fixed at height 0.
    pub fn is_default(&self) -> bool {
        is_zero(&self.height) && self.free.is_empty()
    }
}

/// `[membrane]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Membrane {
    /// The tension t > 0 (force/length).
    pub tension: f64,
    /// The load f (force/area, positive in +x₃): a number, an expression or a region table.
    pub load: Field,
}

/// `[obstacle]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    /// The body's surface φ (length).
    pub shape: Field,
    /// The stiffness h ≥ 0 (force/length³), or rigid.
    pub stiffness: Stiffness,
    /// The consistent matrix of the paper or its lumped diagonal.
    #[serde(default = "consistent")]
    pub foundation: Foundation,
    /// Nodal values of φ, or the paper's mollified sampling.
    #[serde(default)]
    pub sampling: SamplingKind,
    /// The mollifier radius ε for mollified sampling (default: the paper's ε_n).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon: Option<f64>,
}

fn consistent() -> Foundation {
    Foundation::Consistent
}

/// How φ is sampled at the vertices (the name of a [`Sampling`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SamplingKind {
    /// `φ_i = φ(a_i)`.
    #[default]
    Nodal,
    /// The paper's `φ_n = r_n(J_ε * φ)`.
    Mollified,
}

impl SamplingKind {
    /// The name used in case files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            SamplingKind::Nodal => "nodal",
            SamplingKind::Mollified => "mollified",
        }
    }
}

impl Obstacle {
    /// The sampling with its mollifier radius.
    pub fn sampling(&self) -> Sampling {
        match self.sampling {
            SamplingKind::Nodal => Sampling::Nodal,
            SamplingKind::Mollified => Sampling::Mollified {
                epsilon: self.epsilon,
            },
        }
    }
}

/// `[mesh]`: a Gmsh file or a generator, and uniform refinements. In the case file the
/// generator is named by `generator = "rectangle" | "disk" | "polygon"` with its keys beside
/// it, or `file = "mesh.msh"` gives a file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "MeshTable", into = "MeshTable")]
pub struct MeshSpec {
    /// Where the triangles come from.
    pub source: MeshSource,
    /// Uniform refinements (each triangle into four); the levels are kept for multigrid.
    pub refine: usize,
}

/// The mesh source of a [`MeshSpec`].
#[derive(Debug, Clone, PartialEq)]
pub enum MeshSource {
    /// A Gmsh MSH file (2.2 or 4.1, ASCII or binary). A relative path is relative to the
    /// case file when the case was read from one.
    File(PathBuf),
    /// A structured mesh of a rectangle.
    Rectangle {
        /// Corners `[x0, y0]`, `[x1, y1]`.
        x0: f64,
        /// See `x0`.
        y0: f64,
        /// See `x0`.
        x1: f64,
        /// See `x0`.
        y1: f64,
        /// Cells along x.
        nx: usize,
        /// Cells along y.
        ny: usize,
        /// How each cell is cut into triangles.
        diagonal: Diagonal,
    },
    /// An unstructured mesh of a disc, boundary vertices on the circle.
    Disk {
        /// Centre.
        center: [f64; 2],
        /// Radius.
        radius: f64,
        /// Target element size.
        size: f64,
    },
    /// A constrained Delaunay mesh of a polygon with holes and named sub-regions.
    Polygon {
        /// The outer boundary.
        outer: Vec<[f64; 2]>,
        /// Holes.
        holes: Vec<Vec<[f64; 2]>>,
        /// Named sub-polygons (the keys of region tables).
        regions: Vec<RegionPolygon>,
        /// Target element size.
        size: f64,
        /// Smallest angle in degrees, in (0, 30].
        min_angle: f64,
    },
}

/// A named region polygon of the polygon generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionPolygon {
    /// The region's name (a key of region tables).
    pub name: String,
    /// Its boundary.
    pub polygon: Vec<[f64; 2]>,
}

/// The flat serde shape of `[mesh]`.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshTable {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    file: Option<PathBuf>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    generator: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    x0: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    y0: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    x1: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    y1: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    nx: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    ny: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    diagonal: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    center: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    radius: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    size: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    outer: Option<Vec<[f64; 2]>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    holes: Option<Vec<Vec<[f64; 2]>>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    regions: Option<Vec<RegionPolygon>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    min_angle: Option<f64>,
    #[serde(default)]
    refine: usize,
}

impl TryFrom<MeshTable> for MeshSpec {
    type Error = String;

    fn try_from(m: MeshTable) -> std::result::Result<MeshSpec, String> {
        let given = |name: &'static str, v: bool| v.then_some(name);
        let rect = [
            given("x0", m.x0.is_some()),
            given("y0", m.y0.is_some()),
            given("x1", m.x1.is_some()),
            given("y1", m.y1.is_some()),
            given("nx", m.nx.is_some()),
            given("ny", m.ny.is_some()),
            given("diagonal", m.diagonal.is_some()),
        ];
        let disk = [
            given("center", m.center.is_some()),
            given("radius", m.radius.is_some()),
        ];
        let poly = [
            given("outer", m.outer.is_some()),
            given("holes", m.holes.is_some()),
            given("regions", m.regions.is_some()),
            given("min_angle", m.min_angle.is_some()),
        ];
        let size = [given("size", m.size.is_some())];
        let reject = |what: &str, groups: &[&[Option<&str>]]| -> std::result::Result<(), String> {
            match groups.iter().flat_map(|g| g.iter().flatten()).next() {
                Some(k) => Err(format!("`{k}` is not used by {what}")),
                None => Ok(()),
            }
        };
        let source = match (m.file, m.generator.as_deref()) {
            (Some(_), Some(_)) => return Err("give either `file` or `generator`, not both".into()),
            (None, None) => {
                return Err(
                    "needs `file = \"mesh.msh\"` or `generator = \"rectangle\" | \
                            \"disk\" | \"polygon\"`"
                        .into(),
                )
            }
            (Some(file), None) => {
                reject("a mesh file", &[&rect, &disk, &poly, &size])?;
                MeshSource::File(file)
            }
            (None, Some("rectangle")) => {
                reject("the rectangle generator", &[&disk, &poly, &size])?;
                let diagonal = m
                    .diagonal
                    .as_deref()
                    .unwrap_or("right")
                    .parse::<Diagonal>()
                    .map_err(|_| {
                        format!(
                            "diagonal = \"{}\" is unknown (choose right, left, alternate or \
                             crossed)",
                            m.diagonal.as_deref().unwrap_or_default()
                        )
                    })?;
                let nx = m.nx.unwrap_or(16);
                MeshSource::Rectangle {
                    x0: m.x0.unwrap_or(0.0),
                    y0: m.y0.unwrap_or(0.0),
                    x1: m.x1.unwrap_or(1.0),
                    y1: m.y1.unwrap_or(1.0),
                    nx,
                    ny: m.ny.unwrap_or(nx),
                    diagonal,
                }
            }
            (None, Some("disk")) => {
                reject("the disk generator", &[&rect, &poly])?;
                let radius = m.radius.unwrap_or(1.0);
                MeshSource::Disk {
                    center: m.center.unwrap_or([0.0, 0.0]),
                    radius,
                    size: m.size.unwrap_or(radius / 8.0),
                }
            }
            (None, Some("polygon")) => {
                reject("the polygon generator", &[&rect, &disk])?;
                MeshSource::Polygon {
                    outer: m
                        .outer
                        .ok_or("`outer` is required by the polygon generator")?,
                    holes: m.holes.unwrap_or_default(),
                    regions: m.regions.unwrap_or_default(),
                    size: m
                        .size
                        .ok_or("`size` is required by the polygon generator")?,
                    min_angle: m.min_angle.unwrap_or(25.0),
                }
            }
            (None, Some(g)) => {
                return Err(format!(
                    "generator = \"{g}\" is unknown (choose rectangle, disk or polygon)"
                ))
            }
        };
        Ok(MeshSpec {
            source,
            refine: m.refine,
        })
    }
}

impl From<MeshSpec> for MeshTable {
    fn from(s: MeshSpec) -> MeshTable {
        let mut t = MeshTable {
            refine: s.refine,
            ..MeshTable::default()
        };
        match s.source {
            MeshSource::File(p) => t.file = Some(p),
            MeshSource::Rectangle {
                x0,
                y0,
                x1,
                y1,
                nx,
                ny,
                diagonal,
            } => {
                t.generator = Some("rectangle".into());
                (t.x0, t.y0, t.x1, t.y1) = (Some(x0), Some(y0), Some(x1), Some(y1));
                (t.nx, t.ny) = (Some(nx), Some(ny));
                t.diagonal = Some(diagonal_name(diagonal).into());
            }
            MeshSource::Disk {
                center,
                radius,
                size,
            } => {
                t.generator = Some("disk".into());
                (t.center, t.radius, t.size) = (Some(center), Some(radius), Some(size));
            }
            MeshSource::Polygon {
                outer,
                holes,
                regions,
                size,
                min_angle,
            } => {
                t.generator = Some("polygon".into());
                t.outer = Some(outer);
                t.holes = Some(holes);
                t.regions = Some(regions);
                (t.size, t.min_angle) = (Some(size), Some(min_angle));
            }
        }
        t
    }
}

/// The expected counts of a Delaunay mesh of `area` with elements of `size` (equilateral
/// triangles, two per vertex).
fn delaunay_size(area: f64, size: f64) -> MeshSize {
    let triangles = (area / (size * size * 3f64.sqrt() / 4.0)).max(1.0);
    MeshSize::simply_connected(triangles / 2.0, triangles)
}

/// The case-file name of a rectangle diagonal.
fn diagonal_name(d: Diagonal) -> &'static str {
    match d {
        Diagonal::Right => "right",
        Diagonal::Left => "left",
        Diagonal::Alternate => "alternate",
        Diagonal::Crossed => "crossed",
    }
}

impl MeshSpec {
    /// A mesh read from a Gmsh file.
    pub fn file(path: impl Into<PathBuf>) -> MeshSpec {
        MeshSpec {
            source: MeshSource::File(path.into()),
            refine: 0,
        }
    }

    /// The name of the source, for reports: `file`, `rectangle`, `disk` or `polygon`.
    pub fn kind(&self) -> &'static str {
        match self.source {
            MeshSource::File(_) => "file",
            MeshSource::Rectangle { .. } => "rectangle",
            MeshSource::Disk { .. } => "disk",
            MeshSource::Polygon { .. } => "polygon",
        }
    }

    /// The counts of the base mesh before it is built, where the generator knows them:
    /// exactly for the rectangle, from the area and the element size for the disc
    /// (`None` for a file or a polygon, counted once built).
    fn expected_size(&self) -> Option<MeshSize> {
        match &self.source {
            MeshSource::File(_) => None,
            &MeshSource::Rectangle {
                nx, ny, diagonal, ..
            } => {
                let cells = nx as f64 * ny as f64;
                let (vertices, triangles) = match diagonal {
                    Diagonal::Crossed => {
                        ((nx as f64 + 1.0) * (ny as f64 + 1.0) + cells, 4.0 * cells)
                    }
                    _ => ((nx as f64 + 1.0) * (ny as f64 + 1.0), 2.0 * cells),
                };
                Some(MeshSize::simply_connected(vertices, triangles))
            }
            &MeshSource::Disk { radius, size, .. } => {
                Some(delaunay_size(std::f64::consts::PI * radius * radius, size))
            }
            // The polygon's triangles are counted once generated (at most
            // `generate::MAX_TRIANGLES`).
            MeshSource::Polygon { .. } => None,
        }
    }

    /// What [`MeshSpec::build`] would make, named for messages.
    fn describe_refinement(&self, base: &MeshSize) -> String {
        format!(
            "mesh.refine = {} on a {} mesh of {:.0} triangles",
            self.refine,
            self.kind(),
            base.triangles
        )
    }

    /// The names of the boundary regions a generator gives its mesh, in the order of their
    /// tags (`None` for a mesh file: its physical curves are known once it is read).
    pub fn boundary_region_names(&self) -> Option<Vec<String>> {
        match &self.source {
            MeshSource::File(_) => None,
            MeshSource::Rectangle { .. } => Some(
                generate::RECTANGLE_SIDES
                    .iter()
                    .map(|s| s.to_string())
                    .collect(),
            ),
            MeshSource::Disk { .. } => Some(vec!["outer".into()]),
            MeshSource::Polygon { holes, .. } => Some(
                std::iter::once("outer".to_string())
                    .chain((1..=holes.len()).map(|h| format!("hole{h}")))
                    .collect(),
            ),
        }
    }

    /// Builds the mesh and its hierarchy of levels; warnings (from a Gmsh import) are
    /// returned for the caller to show. The memory the run on the refined mesh needs is
    /// checked before the base mesh is generated (when its size is known beforehand) and
    /// again, exactly, before it is refined.
    pub fn build(&self) -> Result<(Hierarchy, Vec<String>)> {
        if let Some(base) = self.expected_size() {
            check_mesh_fits(base, self.refine, &self.describe_refinement(&base))?;
        }
        let mut warnings = Vec::new();
        let mut hierarchy = match &self.source {
            MeshSource::File(path) => {
                let (mesh, w) = crate::io::gmsh::read_msh(path)?;
                warnings.extend(w);
                Hierarchy::single(mesh)
            }
            &MeshSource::Rectangle {
                x0,
                y0,
                x1,
                y1,
                nx,
                ny,
                diagonal,
            } => generate::rectangle(&RectangleSpec {
                x0,
                y0,
                x1,
                y1,
                nx,
                ny,
                diagonal,
            })?,
            &MeshSource::Disk {
                center,
                radius,
                size,
            } => generate::disk_levels(center, radius, size)?,
            MeshSource::Polygon {
                outer,
                holes,
                regions,
                size,
                min_angle,
            } => generate::polygon_levels(&PolygonSpec {
                outer: outer.clone(),
                holes: holes.clone(),
                regions: regions
                    .iter()
                    .map(|r| (r.name.clone(), r.polygon.clone()))
                    .collect(),
                size: *size,
                min_angle: *min_angle,
            })?,
        };
        if self.refine > 0 {
            let base = MeshSize::of(hierarchy.finest());
            check_mesh_fits(base, self.refine, &self.describe_refinement(&base))?;
            hierarchy.refine(self.refine);
        }
        Ok((hierarchy, warnings))
    }

    /// Resolves a relative file path against `base` (the case file's directory).
    fn resolve(&mut self, base: &Path) {
        if let MeshSource::File(p) = &mut self.source {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        }
    }

    fn validate(&self) -> std::result::Result<(), Invalid> {
        let bad = |key: &str, message: String| Err(Invalid::new(format!("mesh.{key}"), message));
        if self.refine > MAX_REFINE {
            return bad(
                "refine",
                format!(
                    "{} refinements is too many (at most {MAX_REFINE}: each multiplies the \
                     triangles by 4)",
                    self.refine
                ),
            );
        }
        let finite_positive = |v: f64| v.is_finite() && v > 0.0;
        match &self.source {
            MeshSource::File(p) if p.as_os_str().is_empty() => bad("file", "is empty".into()),
            MeshSource::File(_) => Ok(()),
            &MeshSource::Rectangle {
                x0,
                y0,
                x1,
                y1,
                nx,
                ny,
                ..
            } => {
                for (k, v) in [("x0", x0), ("y0", y0), ("x1", x1), ("y1", y1)] {
                    if !v.is_finite() {
                        return bad(k, format!("must be a finite number, got {v}"));
                    }
                }
                if !(x1 > x0 && (x1 - x0).is_finite()) {
                    return bad("x1", format!("must be greater than x0 = {x0}, got {x1}"));
                }
                if !(y1 > y0 && (y1 - y0).is_finite()) {
                    return bad("y1", format!("must be greater than y0 = {y0}, got {y1}"));
                }
                if nx == 0 {
                    return bad("nx", "must be at least 1".into());
                }
                if ny == 0 {
                    return bad("ny", "must be at least 1".into());
                }
                Ok(())
            }
            &MeshSource::Disk {
                center,
                radius,
                size,
            } => {
                if !(center[0].is_finite() && center[1].is_finite()) {
                    return bad("center", format!("must be finite, got {center:?}"));
                }
                if !finite_positive(radius) {
                    return bad(
                        "radius",
                        format!("must be a finite number > 0, got {radius}"),
                    );
                }
                if !finite_positive(size) {
                    return bad("size", format!("must be a finite number > 0, got {size}"));
                }
                Ok(())
            }
            MeshSource::Polygon {
                outer,
                holes,
                size,
                min_angle,
                regions,
            } => {
                let rings = std::iter::once(("outer".to_string(), outer))
                    .chain(
                        holes
                            .iter()
                            .enumerate()
                            .map(|(i, h)| (format!("holes[{i}]"), h)),
                    )
                    .chain(
                        regions
                            .iter()
                            .enumerate()
                            .map(|(i, r)| (format!("regions[{i}].polygon"), &r.polygon)),
                    );
                for (key, ring) in rings {
                    if let Some((i, p)) = ring
                        .iter()
                        .enumerate()
                        .find(|(_, p)| !(p[0].is_finite() && p[1].is_finite()))
                    {
                        return bad(
                            &key,
                            format!("vertex {i} must have finite coordinates, got {p:?}"),
                        );
                    }
                }
                if outer.len() < 3 {
                    return bad(
                        "outer",
                        format!("needs at least 3 vertices, got {}", outer.len()),
                    );
                }
                if !finite_positive(*size) {
                    return bad("size", format!("must be a finite number > 0, got {size}"));
                }
                if !(*min_angle > 0.0 && *min_angle <= 30.0) {
                    return bad(
                        "min_angle",
                        format!("must be in (0, 30] degrees, got {min_angle}"),
                    );
                }
                for r in regions {
                    if r.name.trim().is_empty() || r.name == crate::field::DEFAULT_KEY {
                        return bad(
                            "regions",
                            format!(
                                "region name \"{}\" is reserved or empty: name the region",
                                r.name
                            ),
                        );
                    }
                }
                Ok(())
            }
        }
    }
}

/// `[output]`: what `solve` writes besides `solution.vtu`, `nodes.csv` and `summary.json`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputOptions {
    /// The encoding of `solution.vtu`.
    #[serde(default)]
    pub vtu: VtuFormat,
    /// `false`: no `nodes.csv` (the node table of a large mesh is gigabytes); default `true`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub csv: Option<bool>,
    /// The pictures to draw (default: all four; `[]`: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plots: Option<Vec<PictureKind>>,
    /// `false`: no pictures (the same as `plots = []`); `true`: the default pictures.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plot: Option<bool>,
    /// The allowable contact pressure (force/length²): `pressure.png` then maps
    /// pressure / allowable and outlines the area above 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub allowable_pressure: Option<f64>,
    /// The line of `profile.png`, `[[x0, y0], [x1, y1]]` (default: horizontally through
    /// the middle of the domain).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile: Option<[[f64; 2]; 2]>,
}

/// A picture `solve` can draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PictureKind {
    /// `deflection.png`: u with contours and the contact zone.
    Deflection,
    /// `pressure.png`: the contact pressure (or its ratio to the allowable).
    Pressure,
    /// `liftoff.png`: where the membrane is clear of the body it could touch.
    Liftoff,
    /// `profile.png`: u and φ along a line.
    Profile,
}

impl PictureKind {
    /// All four, in order.
    pub const ALL: [PictureKind; 4] = [
        PictureKind::Deflection,
        PictureKind::Pressure,
        PictureKind::Liftoff,
        PictureKind::Profile,
    ];

    /// The name in case files (and the file name without `.png`).
    pub fn name(self) -> &'static str {
        match self {
            PictureKind::Deflection => "deflection",
            PictureKind::Pressure => "pressure",
            PictureKind::Liftoff => "liftoff",
            PictureKind::Profile => "profile",
        }
    }
}

impl OutputOptions {
    /// Whether `nodes.csv` is written (`[output] csv`, default true).
    pub fn writes_csv(&self) -> bool {
        self.csv.unwrap_or(true)
    }

    /// The pictures to draw.
    pub fn pictures(&self) -> Vec<PictureKind> {
        match (&self.plots, self.plot) {
            (Some(p), _) => p.clone(),
            (None, Some(false)) => Vec::new(),
            (None, _) => PictureKind::ALL.to_vec(),
        }
    }

    fn validate(&self) -> std::result::Result<(), Invalid> {
        if let (Some(p), Some(false)) = (&self.plots, self.plot) {
            if !p.is_empty() {
                return Err(Invalid::new(
                    "output.plot",
                    "plot = false contradicts the pictures listed in output.plots",
                ));
            }
        }
        if let Some(p) = &self.plots {
            for (i, k) in p.iter().enumerate() {
                if p[..i].contains(k) {
                    return Err(Invalid::new(
                        "output.plots",
                        format!("\"{}\" is listed twice", k.name()),
                    ));
                }
            }
        }
        if let Some(a) = self.allowable_pressure {
            if !(a.is_finite() && a > 0.0) {
                return Err(Invalid::new(
                    "output.allowable_pressure",
                    format!("must be a finite number > 0, got {a}"),
                ));
            }
        }
        if let Some([p, q]) = self.profile {
            if !p.iter().chain(&q).all(|v| v.is_finite()) || p == q {
                return Err(Invalid::new(
                    "output.profile",
                    format!("must be two distinct finite points, got {p:?}, {q:?}"),
                ));
            }
        }
        Ok(())
    }
}

/// The encoding of `solution.vtu`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum VtuFormat {
    /// Raw appended binary (fast, compact).
    #[default]
    Binary,
    /// Text.
    Ascii,
}

/// `[exact]`: a closed-form solution of the case, for `memcontact convergence`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum ExactSpec {
    /// The axisymmetric disc (constant t, f, h, φ on a disc mesh): Bessel functions.
    Disk {},
    /// A manufactured solution: the load is replaced by `f = −tΔu + h(u − φ)⁺` (minus
    /// `h_low(φ_low − u)⁺` with a body below) and the heights of the fixed boundary by u.
    Manufactured {
        /// The domain of the manufactured u (it vanishes on its boundary).
        domain: ManufacturedDomain,
        /// The scale of u.
        amplitude: f64,
        /// Which u: one vanishing on the boundary (default), or, on a rectangle, one with
        /// zero normal derivative on every side (any side may then be free).
        #[serde(default, skip_serializing_if = "ManufacturedForm::is_default")]
        form: ManufacturedForm,
    },
    /// PETSc SNES ex9: the rigid spherical obstacle on (−2, 2)² with its boundary data.
    #[serde(rename = "petsc-ex9")]
    PetscEx9 {
        /// Which body is the obstacle: `"obstacle"` above (u ≤ φ = −ψ, the solution
        /// negated; default) or `"lower"` (u ≥ ψ, as in PETSc).
        #[serde(default, skip_serializing_if = "BenchmarkBody::is_default")]
        body: BenchmarkBody,
    },
    /// MFEM ex36: PETSc SNES ex9 scaled by ½ onto the unit disc (g = 0).
    #[serde(rename = "mfem-ex36")]
    MfemEx36 {
        /// As for `petsc-ex9`.
        #[serde(default, skip_serializing_if = "BenchmarkBody::is_default")]
        body: BenchmarkBody,
    },
}

impl ExactSpec {
    /// The name used in case files.
    pub fn kind(&self) -> &'static str {
        match self {
            ExactSpec::Disk {} => "disk",
            ExactSpec::Manufactured { .. } => "manufactured",
            ExactSpec::PetscEx9 { .. } => "petsc-ex9",
            ExactSpec::MfemEx36 { .. } => "mfem-ex36",
        }
    }
}

/// The domain of a manufactured solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ManufacturedDomain {
    /// The rectangle of `[mesh]`.
    Rectangle,
    /// The disc of `[mesh]`.
    Disk,
}

/// Which manufactured solution.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ManufacturedForm {
    /// u vanishes on the boundary (the paper's frame).
    #[default]
    Vanishing,
    /// On a rectangle, `u = A (cos(πX) cos(πY) + ½ cos(2πY))`: zero normal derivative on
    /// every side, so sides may be free, and non-zero heights on the fixed ones.
    Cosine,
}

impl ManufacturedForm {
    fn is_default(&self) -> bool {
        *self == ManufacturedForm::Vanishing
    }
}

/// The body of a rigid obstacle benchmark.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BenchmarkBody {
    /// The obstacle above (`[obstacle]`), with the problem negated.
    #[default]
    Obstacle,
    /// The body below (`[lower]`), the benchmark's own convention.
    Lower,
}

impl BenchmarkBody {
    fn is_default(&self) -> bool {
        *self == BenchmarkBody::Obstacle
    }
}

/// A value refused by validation: the key (dotted path) and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct Invalid {
    /// The dotted key, e.g. `membrane.tension`.
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl Invalid {
    /// A refusal of `key`.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Invalid {
        Invalid {
            key: key.into(),
            message: message.into(),
        }
    }

    /// The library error, without a file.
    pub fn into_error(self) -> Error {
        Error::Case {
            file: None,
            line: None,
            key: self.key,
            message: self.message,
        }
    }
}

/// Checks a field's constants (a number, or the numbers of a region table): finite, and
/// non-negative when asked. Expressions are checked where they are evaluated.
fn check_field(key: &str, f: &Field, non_negative: bool) -> std::result::Result<(), Invalid> {
    let check = |k: String, v: f64| {
        if !v.is_finite() {
            Err(Invalid::new(k, format!("must be finite, got {v}")))
        } else if non_negative && v < 0.0 {
            Err(Invalid::new(k, format!("must be ≥ 0, got {v}")))
        } else {
            Ok(())
        }
    };
    match f {
        Field::Constant(v) => check(key.to_string(), *v),
        Field::Expr(_) => Ok(()),
        Field::Nodal(values) => {
            for (i, v) in values.iter().enumerate() {
                check(format!("{key}[{i}]"), *v)?;
            }
            Ok(())
        }
        Field::Regions(t) => {
            for (name, v) in t {
                if let Field::Constant(c) = v {
                    check(format!("{key}.{name}"), *c)?;
                }
            }
            Ok(())
        }
    }
}

impl Problem {
    /// Checks every value that can be checked without the mesh: t > 0, constants finite,
    /// h ≥ 0, ε > 0 and only with mollified sampling, the mesh generator's parameters, the
    /// boundary heights and, for the generators, the names of the boundary regions.
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        self.mesh.validate()?;
        let t = self.membrane.tension;
        if !(t.is_finite() && t > 0.0) {
            return Err(Invalid::new(
                "membrane.tension",
                format!("must be a finite number > 0, got {t}"),
            ));
        }
        check_field("membrane.load", &self.membrane.load, false)?;
        self.obstacle.validate("obstacle")?;
        if let Some(low) = &self.lower {
            low.validate("lower")?;
        }
        self.boundary.validate(&self.mesh)
    }
}

impl Obstacle {
    /// Checks a body's constants (the section is `obstacle` or `lower`).
    fn validate(&self, section: &str) -> std::result::Result<(), Invalid> {
        check_field(&format!("{section}.shape"), &self.shape, false)?;
        for (key, h) in self.stiffness.elastic_fields() {
            check_field(&format!("{section}.stiffness{key}"), h, true)?;
        }
        if let (SamplingKind::Mollified, Field::Nodal(_)) = (self.sampling, &self.shape) {
            return Err(Invalid::new(
                format!("{section}.sampling"),
                "mollified sampling needs φ as a function of x and y; nodal values of φ \
                 are its samples (use sampling = \"nodal\")",
            ));
        }
        match (self.sampling, self.epsilon) {
            (SamplingKind::Nodal, Some(_)) => Err(Invalid::new(
                format!("{section}.epsilon"),
                "is only used with sampling = \"mollified\"",
            )),
            (SamplingKind::Mollified, Some(e)) if !(e.is_finite() && e > 0.0) => Err(Invalid::new(
                format!("{section}.epsilon"),
                format!("must be a finite number > 0, got {e}"),
            )),
            _ => Ok(()),
        }
    }
}

impl Boundary {
    /// Checks the heights' constants and, when the mesh generator names its boundary
    /// regions, that `free` and the keys of a height table name existing regions.
    fn validate(&self, mesh: &MeshSpec) -> std::result::Result<(), Invalid> {
        check_field("boundary.height", &self.height, false)?;
        for (i, name) in self.free.iter().enumerate() {
            if name.trim().is_empty() {
                return Err(Invalid::new("boundary.free", format!("entry {i} is empty")));
            }
            if self.free[..i].contains(name) {
                return Err(Invalid::new(
                    "boundary.free",
                    format!("\"{name}\" is listed twice"),
                ));
            }
        }
        let Some(sides) = mesh.boundary_region_names() else {
            return Ok(());
        };
        let known = |k: &str| {
            sides.iter().any(|s| s == k)
                || k.trim()
                    .parse::<usize>()
                    .is_ok_and(|t| t >= 1 && t <= sides.len())
        };
        let listing = sides.join(", ");
        for name in &self.free {
            if !known(name) {
                return Err(Invalid::new(
                    "boundary.free",
                    format!(
                        "no boundary region named '{name}' (the {} generator's boundary \
                         regions: {listing})",
                        mesh.kind()
                    ),
                ));
            }
        }
        if let Field::Regions(table) = &self.height {
            for key in table.keys() {
                if key != crate::field::DEFAULT_KEY && !known(key) {
                    return Err(Invalid::new(
                        format!("boundary.height.{key}"),
                        format!(
                            "no boundary region named '{key}' (the {} generator's boundary \
                             regions: {listing})",
                            mesh.kind()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

impl Case {
    /// Whether the case has steps to solve in turn (a `[sweep]` or `[[load_case]]`
    /// entries): then it is run by [`crate::sweep::run_sweep`], not [`crate::run`].
    pub fn is_sweep(&self) -> bool {
        self.sweep.is_some() || !self.load_cases.is_empty()
    }

    /// Checks the whole case (problem, settings, output, exact solution) without the mesh.
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        self.problem.validate()?;
        self.settings.validate()?;
        self.output.validate()?;
        crate::sweep::validate(self)?;
        if let Some(ExactSpec::Manufactured { amplitude, .. }) = &self.exact {
            if !(amplitude.is_finite() && *amplitude != 0.0) {
                return Err(Invalid::new(
                    "exact.amplitude",
                    format!("must be a finite non-zero number, got {amplitude}"),
                ));
            }
        }
        Ok(())
    }

    /// Parses a case from TOML text. `file` names the text in messages and is the base of
    /// relative mesh paths. Errors carry the key, the file and the line.
    pub fn from_toml_str(text: &str, file: Option<&Path>) -> Result<Case> {
        let located =
            |key: String, message: String, span: Option<std::ops::Range<usize>>| Error::Case {
                file: file.map(Path::to_path_buf),
                line: span.map(|s| line_of(text, s.start)),
                key,
                message,
            };
        let de = toml::Deserializer::parse(text).map_err(|e| {
            located(
                String::new(),
                format!("malformed TOML: {}", e.message().trim()),
                e.span(),
            )
        })?;
        let mut case: Case = serde_path_to_error::deserialize(de).map_err(|e| {
            let key = e.path().to_string();
            let inner = e.into_inner();
            let key = if key == "." { String::new() } else { key };
            located(key, plain_types(inner.message().trim()), inner.span())
        })?;
        if let Some(base) = file.and_then(Path::parent) {
            case.problem.mesh.resolve(base);
        }
        case.validate().map_err(|inv| {
            let span = key_span(text, &inv.key);
            located(inv.key, inv.message, span)
        })?;
        Ok(case)
    }

    /// Parses a case from JSON text (what the Python module sends).
    pub fn from_json_str(text: &str) -> Result<Case> {
        let mut de = serde_json::Deserializer::from_str(text);
        let case: Case = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let key = e.path().to_string();
            let key = if key == "." { String::new() } else { key };
            let inner = e.into_inner();
            Error::Case {
                file: None,
                line: None,
                key,
                message: plain_types(&strip_json_position(&inner.to_string())),
            }
        })?;
        case.validate().map_err(Invalid::into_error)?;
        Ok(case)
    }

    /// Reads a case file (a regular file of at most [`CASE_FILE_CAP`] bytes), applies
    /// `key=value` overrides (dotted keys, TOML values; a value that is not TOML is taken
    /// as a string) and parses it; relative paths are relative to the case file.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Case> {
        let text = read_case_text(path)?;
        let text = apply_overrides(&text, overrides).map_err(|(key, message)| Error::Case {
            file: Some(path.to_path_buf()),
            line: None,
            key,
            message,
        })?;
        Case::from_toml_str(&text, Some(path))
    }

    /// The case as TOML text (round-trips through [`Case::from_toml_str`]).
    pub fn to_toml_string(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| Error::Data(format!("cannot write the case: {e}")))
    }
}

/// Reads a case file: a regular file, at most [`CASE_FILE_CAP`] bytes, UTF-8.
fn read_case_text(path: &Path) -> Result<String> {
    let bytes = crate::resources::read_input(path, crate::resources::CASE_FILE)?;
    String::from_utf8(bytes).map_err(|e| Error::File {
        path: path.to_path_buf(),
        message: format!(
            "is not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ),
    })
}

/// Applies `key=value` overrides to TOML text, keeping the rest of the text (and so the
/// line numbers of untouched keys) as it is. Errors name the override.
pub fn apply_overrides(
    text: &str,
    overrides: &[String],
) -> std::result::Result<String, (String, String)> {
    if overrides.is_empty() {
        return Ok(text.to_string());
    }
    let mut doc: toml_edit::DocumentMut = text
        .parse()
        .map_err(|e: toml_edit::TomlError| (String::new(), e.message().to_string()))?;
    for set in overrides {
        let (key, value) = set.split_once('=').ok_or_else(|| {
            (
                set.clone(),
                "an override must be key=value, e.g. mesh.nx=64".to_string(),
            )
        })?;
        let key = key.trim();
        let parts: Vec<&str> = key.split('.').map(str::trim).collect();
        if parts.iter().any(|p| p.is_empty()) {
            return Err((key.to_string(), "malformed key".into()));
        }
        let value = value.trim();
        let parsed: toml_edit::Value = value
            .parse()
            .unwrap_or_else(|_| toml_edit::Value::from(value));
        let mut table = doc.as_table_mut();
        for p in &parts[..parts.len() - 1] {
            let entry = table
                .entry(p)
                .or_insert_with(|| toml_edit::Item::Table(toml_edit::Table::new()));
            if let Some(inline) = entry.as_inline_table_mut() {
                let t = std::mem::take(inline).into_table();
                *entry = toml_edit::Item::Table(t);
            }
            table = entry
                .as_table_mut()
                .ok_or_else(|| (key.to_string(), format!("\"{p}\" is not a table")))?;
        }
        let last = parts[parts.len() - 1];
        match table.get_mut(last) {
            Some(item) if item.is_value() => {
                let decor = item.as_value().map(|v| v.decor().clone());
                let mut v = parsed;
                if let Some(d) = decor {
                    *v.decor_mut() = d;
                }
                *item = toml_edit::Item::Value(v);
            }
            _ => {
                table.insert(last, toml_edit::Item::Value(parsed));
            }
        }
    }
    Ok(doc.to_string())
}

/// The 1-based line of byte offset `at` in `text`.
fn line_of(text: &str, at: usize) -> usize {
    text.as_bytes()[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The span of the value of dotted `key` in TOML `text` (the deepest part found).
fn key_span(text: &str, key: &str) -> Option<std::ops::Range<usize>> {
    use toml::de::DeValue;
    let doc = toml::de::DeTable::parse(text).ok()?;
    let mut table = doc.get_ref();
    let mut span = None;
    let mut parts = key.split('.').peekable();
    'parts: while let Some(part) = parts.next() {
        let (_, mut v) = table.iter().find(|(k, _)| k.get_ref().as_ref() == part)?;
        span = Some(v.span());
        loop {
            match v.get_ref() {
                DeValue::Table(t) => {
                    table = t;
                    continue 'parts;
                }
                // `name.N`: element N of an array (an array of tables: `[[name]]`).
                DeValue::Array(a) => {
                    let element = parts
                        .peek()
                        .and_then(|p| p.parse::<usize>().ok())
                        .and_then(|i| a.get(i));
                    match element {
                        Some(e) => {
                            parts.next();
                            v = e;
                            span = Some(v.span());
                        }
                        None => break 'parts,
                    }
                }
                _ => break 'parts,
            }
        }
    }
    span
}

/// serde's messages name Rust types; a user reads "a number".
fn plain_types(message: &str) -> String {
    message
        .replace("expected f64", "expected a number")
        .replace("expected usize", "expected a non-negative integer")
        .replace("expected u32", "expected a non-negative integer")
        .replace("expected a sequence", "expected an array")
        .replace("expected a borrowed string", "expected a string")
}

/// serde_json's messages end with "at line 1 column 57": meaningless for a dict.
fn strip_json_position(message: &str) -> String {
    match message.rfind(" at line ") {
        Some(i) => message[..i].to_string(),
        None => message.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DISK: &str = r#"
[mesh]
generator = "disk"
radius = 1
size = 0.2

[membrane]
tension = 1
load = 8

[obstacle]
shape = "1.0"
stiffness = 100
"#;

    #[test]
    fn a_case_round_trips_through_toml_and_json() {
        let case = Case::from_toml_str(DISK, None).unwrap();
        assert_eq!(case.problem.membrane.tension, 1.0);
        assert_eq!(case.problem.obstacle.foundation, Foundation::Consistent);
        let text = case.to_toml_string().unwrap();
        assert_eq!(Case::from_toml_str(&text, None).unwrap(), case);
        let json = serde_json::to_string(&case).unwrap();
        assert_eq!(Case::from_json_str(&json).unwrap(), case);
    }

    fn err(text: &str) -> Error {
        Case::from_toml_str(text, Some(Path::new("case.toml"))).unwrap_err()
    }

    #[test]
    fn errors_name_the_key_the_file_and_the_line() {
        let e = err(&DISK.replace("stiffness = 100", "stifness = 100"));
        let Error::Case { key, line, .. } = &e else {
            panic!("{e}")
        };
        assert_eq!(key, "obstacle.stifness");
        assert_eq!(*line, Some(13), "{e}");
        assert!(e.to_string().contains("unknown field"), "{e}");
        assert!(e.to_string().starts_with("case.toml:13:"), "{e}");

        let e = err(&DISK.replace("tension = 1", "tension = -1"));
        let Error::Case { key, line, .. } = &e else {
            panic!("{e}")
        };
        assert_eq!((key.as_str(), *line), ("membrane.tension", Some(8)), "{e}");

        let e = err(&DISK.replace("radius = 1", "radius = \"big\""));
        assert!(e.to_string().contains("radius"), "{e}");
        let e = err(&DISK.replace("generator = \"disk\"", "generator = \"hexagon\""));
        assert!(e.to_string().contains("hexagon"), "{e}");
        let e = err(&format!("{DISK}\n[exact]\nkind = \"foo\"\n"));
        assert!(e.to_string().contains("foo"), "{e}");
        let e = err(&format!("{DISK}\n[solver]\ntolerance = 0.5\n"));
        assert!(e.to_string().contains("solver.tolerance"), "{e}");
        let e = err(&format!("{DISK}\n[output]\nvtu = \"xml\"\n"));
        assert!(e.to_string().contains("output.vtu"), "{e}");
        let e = err(&DISK.replace("load = 8", "load = nan"));
        assert!(e.to_string().contains("membrane.load"), "{e}");
        let e = err(&DISK.replace("stiffness = 100", "stiffness = -3"));
        assert!(e.to_string().contains("obstacle.stiffness"), "{e}");
        // Found by fuzzing: a NaN polygon vertex passed validation (and its JSON, null,
        // did not read back).
        let polygon = DISK.replace(
            "generator = \"disk\"\nradius = 1\nsize = 0.2",
            "generator = \"polygon\"\nouter = [[0, 0], [2, 0], [2, 2], [0, 2]]\n\
             holes = [[[nan, 1.0], [1.2, 0.8], [1.2, 1.2]]]\nsize = 0.2",
        );
        let e = err(&polygon);
        assert!(e.to_string().contains("mesh.holes[0]"), "{e}");
        assert!(e.to_string().contains("finite"), "{e}");
        let e = err(&polygon
            .replace("[[[nan, 1.0]", "[[[1.0, 1.0]")
            .replace("[0, 2]]", "[0, inf]]"));
        assert!(e.to_string().contains("mesh.outer"), "{e}");
        // A key inside an array of tables points at its own line.
        let e = err(&format!(
            "{DISK}\n[[load_case]]\nname = \"a\"\n\n[[load_case]]\nname = \"b\"\n\
             stiffness = -4\n"
        ));
        let Error::Case { key, line, .. } = &e else {
            panic!("{e}")
        };
        assert_eq!(key, "load_case.1.stiffness");
        assert_eq!(*line, Some(20), "{e}");
    }

    #[test]
    fn overrides_keep_the_other_lines() {
        let text = apply_overrides(
            DISK,
            &["mesh.size=0.1".into(), "obstacle.foundation=lumped".into()],
        )
        .unwrap();
        let case = Case::from_toml_str(&text, None).unwrap();
        assert_eq!(case.problem.obstacle.foundation, Foundation::Lumped);
        assert!(matches!(
            case.problem.mesh.source,
            MeshSource::Disk { size, .. } if size == 0.1
        ));
        // An error after an override still points at the original line.
        let text = apply_overrides(DISK, &["membrane.tension=-2".into()]).unwrap();
        let e = Case::from_toml_str(&text, None).unwrap_err();
        assert!(matches!(e, Error::Case { line: Some(8), .. }), "{e}");
        assert!(apply_overrides(DISK, &["nokey".into()]).is_err());
        assert!(apply_overrides(DISK, &["mesh..x=1".into()]).is_err());
    }
}
