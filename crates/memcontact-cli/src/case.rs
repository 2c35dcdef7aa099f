//! The case file (TOML): parsing with `--set` overrides, validation into the library's
//! types, and the mesh it describes. Paths are relative to the case file.

use anyhow::{anyhow, bail, Context, Result};
use memcontact::field::{Field, Stiffness};
use memcontact::mesh::generate::{self, Diagonal, PolygonSpec, RectangleSpec};
use memcontact::mesh::refine::Hierarchy;
use memcontact::model::{Foundation, Sampling};
use memcontact::solve::{Method, Settings};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A whole case file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// `[mesh]`: a Gmsh file or a generator, and uniform refinements.
    pub mesh: MeshSection,
    /// `[membrane]`: tension and load.
    pub membrane: Membrane,
    /// `[obstacle]`: shape, stiffness, foundation variant, sampling.
    pub obstacle: Obstacle,
    /// `[solver]`: method and tolerance.
    #[serde(default)]
    pub solver: SolverSection,
    /// `[output]`: output options.
    #[serde(default)]
    pub output: OutputSection,
    /// `[exact]`: the exact solution this case has, for convergence studies.
    pub exact: Option<toml::Table>,
    /// The directory of the case file (paths are relative to it).
    #[serde(skip)]
    pub base: PathBuf,
    /// The case file itself.
    #[serde(skip)]
    pub path: PathBuf,
}

/// `[mesh]`.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MeshSection {
    /// A Gmsh MSH file (2.2 or 4.1, ASCII or binary).
    pub file: Option<PathBuf>,
    /// `rectangle`, `disk` or `polygon`.
    pub generator: Option<String>,
    /// Rectangle corner x0 (default 0).
    pub x0: Option<f64>,
    /// Rectangle corner y0 (default 0).
    pub y0: Option<f64>,
    /// Rectangle corner x1 (default 1).
    pub x1: Option<f64>,
    /// Rectangle corner y1 (default 1).
    pub y1: Option<f64>,
    /// Rectangle cells along x (default 16).
    pub nx: Option<usize>,
    /// Rectangle cells along y (default nx).
    pub ny: Option<usize>,
    /// Rectangle diagonal: right, left, alternate, crossed (default right).
    pub diagonal: Option<String>,
    /// Disc centre (default [0, 0]).
    pub center: Option<[f64; 2]>,
    /// Disc radius (default 1).
    pub radius: Option<f64>,
    /// Target element size (disc, polygon).
    pub size: Option<f64>,
    /// Polygon outer boundary.
    pub outer: Option<Vec<[f64; 2]>>,
    /// Polygon holes.
    pub holes: Option<Vec<Vec<[f64; 2]>>>,
    /// Named sub-polygons of the polygon (regions with different data).
    pub regions: Option<Vec<RegionPolygon>>,
    /// Polygon minimum angle in degrees (default 25, at most 30).
    pub min_angle: Option<f64>,
    /// Uniform refinements (each triangle into four), default 0.
    #[serde(default)]
    pub refine: usize,
}

/// A named region polygon.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionPolygon {
    /// Region name (keys of per-region tables).
    pub name: String,
    /// Its boundary.
    pub polygon: Vec<[f64; 2]>,
}

/// `[membrane]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Membrane {
    /// Tension t > 0.
    pub tension: Number,
    /// Load f (positive in +x₃).
    pub load: Field,
}

/// `[obstacle]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Obstacle {
    /// Surface φ.
    pub shape: Field,
    /// Stiffness h ≥ 0, or "rigid".
    pub stiffness: Stiffness,
    /// "consistent" (default) or "lumped".
    #[serde(default = "default_foundation")]
    pub foundation: String,
    /// "nodal" (default) or "mollified".
    #[serde(default = "default_sampling")]
    pub sampling: String,
    /// Mollifier radius for mollified sampling (default: the paper's ε_n).
    pub epsilon: Option<Number>,
}

fn default_foundation() -> String {
    "consistent".into()
}
fn default_sampling() -> String {
    "nodal".into()
}

/// `[solver]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSection {
    /// auto | linear | active-set | qp | coordinate | multigrid.
    #[serde(default = "default_method")]
    pub method: String,
    /// Scaled KKT tolerance.
    #[serde(default = "default_tolerance")]
    pub tolerance: Number,
    /// Iteration limit.
    pub max_iterations: Option<usize>,
}

fn default_method() -> String {
    "auto".into()
}
fn default_tolerance() -> Number {
    Number(1e-10)
}

impl Default for SolverSection {
    fn default() -> Self {
        SolverSection {
            method: default_method(),
            tolerance: default_tolerance(),
            max_iterations: None,
        }
    }
}

/// `[output]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// VTU encoding: "binary" (default, raw appended) or "ascii".
    #[serde(default = "default_vtu")]
    pub vtu: String,
    /// Write `deflection.png`, a colour map of u (default: on meshes of at most
    /// 200 000 triangles).
    pub plot: Option<bool>,
}

fn default_vtu() -> String {
    "binary".into()
}

impl Default for OutputSection {
    fn default() -> Self {
        OutputSection {
            vtu: default_vtu(),
            plot: None,
        }
    }
}

/// A number that TOML may write as an integer or a float.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Number(pub f64);

impl<'de> Deserialize<'de> for Number {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Number;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number")
            }
            fn visit_f64<E>(self, v: f64) -> std::result::Result<Number, E> {
                Ok(Number(v))
            }
            fn visit_i64<E>(self, v: i64) -> std::result::Result<Number, E> {
                Ok(Number(v as f64))
            }
            fn visit_u64<E>(self, v: u64) -> std::result::Result<Number, E> {
                Ok(Number(v as f64))
            }
        }
        d.deserialize_any(V)
    }
}

/// Reads a case file and applies `key=value` overrides (dotted keys, TOML values; a value
/// that is not valid TOML is taken as a string).
pub fn load(path: &Path, sets: &[String]) -> Result<Case> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read case file {}", path.display()))?;
    let mut table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| anyhow!("{}: malformed TOML: {e}", path.display()))?;
    for s in sets {
        apply_set(&mut table, s).with_context(|| format!("--set {s}"))?;
    }
    let mut case: Case = Case::deserialize(toml::Value::Table(table))
        .map_err(|e| anyhow!("{}: {}", path.display(), e.to_string().trim()))?;
    case.base = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    case.path = path.to_path_buf();
    Ok(case)
}

/// Applies one `a.b.c=value` override to the TOML table.
fn apply_set(table: &mut toml::Table, set: &str) -> Result<()> {
    let (key, value) = set
        .split_once('=')
        .ok_or_else(|| anyhow!("expected key=value, e.g. mesh.nx=64"))?;
    let value = value.trim();
    let parsed: toml::Value = match format!("v = {value}").parse::<toml::Table>() {
        Ok(mut t) => t.remove("v").expect("parsed"),
        Err(_) => toml::Value::String(value.to_string()),
    };
    let parts: Vec<&str> = key.trim().split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        bail!("malformed key \"{key}\"");
    }
    let mut t = table;
    for p in &parts[..parts.len() - 1] {
        let entry = t
            .entry(p.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        t = entry
            .as_table_mut()
            .ok_or_else(|| anyhow!("\"{p}\" in \"{key}\" is not a table"))?;
    }
    t.insert(parts[parts.len() - 1].to_string(), parsed);
    Ok(())
}

impl Case {
    /// The solver settings.
    pub fn settings(&self) -> Result<Settings> {
        let method: Method = self
            .solver
            .method
            .parse()
            .map_err(|e| anyhow!("solver.method: {e}"))?;
        let tol = self.solver.tolerance.0;
        if !(tol.is_finite() && tol > 0.0) {
            bail!("solver.tolerance must be a finite number > 0, got {tol}");
        }
        Ok(Settings {
            method,
            tolerance: tol,
            max_iterations: self.solver.max_iterations,
        })
    }

    /// The foundation variant.
    pub fn foundation(&self) -> Result<Foundation> {
        self.obstacle
            .foundation
            .parse()
            .map_err(|e| anyhow!("obstacle.foundation: {e}"))
    }

    /// The obstacle sampling.
    pub fn sampling(&self) -> Result<Sampling> {
        let eps = self.obstacle.epsilon.map(|n| n.0);
        match self.obstacle.sampling.as_str() {
            "nodal" => {
                if eps.is_some() {
                    bail!("obstacle.epsilon is only used with sampling = \"mollified\"");
                }
                Ok(Sampling::Nodal)
            }
            "mollified" => {
                if let Some(e) = eps {
                    if !(e.is_finite() && e > 0.0) {
                        bail!("obstacle.epsilon must be a finite number > 0, got {e}");
                    }
                }
                Ok(Sampling::Mollified { epsilon: eps })
            }
            s => bail!("obstacle.sampling must be \"nodal\" or \"mollified\", not \"{s}\""),
        }
    }

    /// The tension, checked.
    pub fn tension(&self) -> Result<f64> {
        let t = self.membrane.tension.0;
        if !(t.is_finite() && t > 0.0) {
            bail!("membrane.tension must be a finite number > 0, got {t}");
        }
        Ok(t)
    }

    /// Builds the mesh (and its hierarchy of levels) the case describes; warnings (from
    /// Gmsh import) are returned for the caller to print.
    pub fn build_mesh(&self) -> Result<(Hierarchy, Vec<String>)> {
        let m = &self.mesh;
        let mut warnings = Vec::new();
        fn given(name: &'static str, v: bool) -> Option<&'static str> {
            v.then_some(name)
        }
        let rect_keys = [
            given("x0", m.x0.is_some()),
            given("y0", m.y0.is_some()),
            given("x1", m.x1.is_some()),
            given("y1", m.y1.is_some()),
            given("nx", m.nx.is_some()),
            given("ny", m.ny.is_some()),
            given("diagonal", m.diagonal.is_some()),
        ];
        let disk_keys = [
            given("center", m.center.is_some()),
            given("radius", m.radius.is_some()),
        ];
        let poly_keys = [
            given("outer", m.outer.is_some()),
            given("holes", m.holes.is_some()),
            given("regions", m.regions.is_some()),
            given("min_angle", m.min_angle.is_some()),
        ];
        let size_key = [given("size", m.size.is_some())];
        let reject = |what: &str, keys: &[Option<&str>]| -> Result<()> {
            if let Some(k) = keys.iter().flatten().next() {
                bail!("mesh.{k} is not used by {what}");
            }
            Ok(())
        };
        let mut hierarchy = match (&m.file, m.generator.as_deref()) {
            (Some(_), Some(_)) => bail!("[mesh] has both `file` and `generator`: give one"),
            (None, None) => bail!("[mesh] needs `file = \"...msh\"` or `generator = \"rectangle\" | \"disk\" | \"polygon\"`"),
            (Some(file), None) => {
                for keys in [&rect_keys[..], &disk_keys[..], &poly_keys[..], &size_key[..]] {
                    reject("a mesh file", keys)?;
                }
                let path = self.base.join(file);
                let (mesh, w) = memcontact::io::gmsh::read_msh(&path)?;
                warnings.extend(w);
                Hierarchy::single(mesh)
            }
            (None, Some("rectangle")) => {
                reject("the rectangle generator", &disk_keys)?;
                reject("the rectangle generator", &poly_keys)?;
                reject("the rectangle generator", &size_key)?;
                let diagonal: Diagonal = m
                    .diagonal
                    .as_deref()
                    .unwrap_or("right")
                    .parse()
                    .map_err(|e| anyhow!("mesh.diagonal: {e}"))?;
                let nx = m.nx.unwrap_or(16);
                generate::rectangle(&RectangleSpec {
                    x0: m.x0.unwrap_or(0.0),
                    y0: m.y0.unwrap_or(0.0),
                    x1: m.x1.unwrap_or(1.0),
                    y1: m.y1.unwrap_or(1.0),
                    nx,
                    ny: m.ny.unwrap_or(nx),
                    diagonal,
                })?
            }
            (None, Some("disk")) => {
                reject("the disk generator", &rect_keys)?;
                reject("the disk generator", &poly_keys)?;
                let radius = m.radius.unwrap_or(1.0);
                let size = m.size.unwrap_or(radius / 8.0);
                Hierarchy::single(generate::disk(m.center.unwrap_or([0.0, 0.0]), radius, size)?)
            }
            (None, Some("polygon")) => {
                reject("the polygon generator", &rect_keys)?;
                reject("the polygon generator", &disk_keys)?;
                let outer = m
                    .outer
                    .clone()
                    .ok_or_else(|| anyhow!("mesh.outer is required by the polygon generator"))?;
                let size = m
                    .size
                    .ok_or_else(|| anyhow!("mesh.size is required by the polygon generator"))?;
                Hierarchy::single(generate::polygon(&PolygonSpec {
                    outer,
                    holes: m.holes.clone().unwrap_or_default(),
                    regions: m
                        .regions
                        .clone()
                        .unwrap_or_default()
                        .into_iter()
                        .map(|r| (r.name, r.polygon))
                        .collect(),
                    size,
                    min_angle: m.min_angle.unwrap_or(25.0),
                })?)
            }
            (None, Some(g)) => bail!(
                "mesh.generator \"{g}\" is unknown (choose rectangle, disk or polygon)"
            ),
        };
        if m.refine > 12 {
            bail!(
                "mesh.refine = {} is too large (each refinement multiplies the triangles by 4)",
                m.refine
            );
        }
        if m.refine > 0 {
            hierarchy.refine(m.refine);
        }
        Ok((hierarchy, warnings))
    }
}
