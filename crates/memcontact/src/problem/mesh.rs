//! `[mesh]`: a Gmsh file or a generator, and uniform refinements.

use crate::error::Invalid;
use crate::mesh::generate::{self, Diagonal};
use crate::mesh::refine::Hierarchy;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The largest number of uniform refinements accepted (each multiplies the triangles by
/// four); the size of the refined mesh is checked separately against the memory available
/// ([`crate::limits::check_mesh_fits`], before refining).
pub const MAX_REFINE: usize = 12;

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
    /// A mesh given as data (arrays from a program, a mesh refined or adapted before),
    /// shown in a case file by its description.
    Given(GivenMesh),
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

/// A mesh given as data: its levels (shared, not copied, by the cases that hold it) and the
/// description a case file shows in their place (`given = "…"`: counts and a hash of the
/// vertices and triangles).
#[derive(Debug, Clone)]
pub struct GivenMesh {
    /// The mesh levels, coarsest first; `None` for a case read back from its text, which
    /// holds the description alone (the mesh must be given again to solve it).
    pub hierarchy: Option<Arc<Hierarchy>>,
    /// `"V vertices, T triangles, L levels, xxh3 HASH"`.
    pub description: String,
}

impl GivenMesh {
    /// The mesh levels `hierarchy`, described by their finest level's counts and a hash of
    /// every level's vertices and triangles.
    pub fn new(hierarchy: Hierarchy) -> GivenMesh {
        GivenMesh::shared(Arc::new(hierarchy))
    }

    /// [`GivenMesh::new`] of mesh levels shared with the caller (not copied).
    pub fn shared(hierarchy: Arc<Hierarchy>) -> GivenMesh {
        let mut h = xxhash_rust::xxh3::Xxh3::new();
        for m in &hierarchy.levels {
            for p in &m.points {
                h.update(&p[0].to_le_bytes());
                h.update(&p[1].to_le_bytes());
            }
            for t in &m.triangles {
                for v in t {
                    h.update(&v.to_le_bytes());
                }
            }
            for r in &m.regions {
                h.update(&r.to_le_bytes());
            }
        }
        let f = hierarchy.finest();
        GivenMesh {
            description: format!(
                "{} vertices, {} triangles, {} level{}, xxh3 {:016x}",
                f.n_vertices(),
                f.n_triangles(),
                hierarchy.depth(),
                if hierarchy.depth() == 1 { "" } else { "s" },
                h.digest()
            ),
            hierarchy: Some(hierarchy),
        }
    }
}

impl PartialEq for GivenMesh {
    fn eq(&self, other: &GivenMesh) -> bool {
        self.description == other.description
    }
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
    given: Option<String>,
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
        if let Some(description) = m.given {
            if m.file.is_some() || m.generator.is_some() {
                return Err("a mesh given as data takes no `file` and no `generator`".into());
            }
            reject("a mesh given as data", &[&rect, &disk, &poly, &size])?;
            return Ok(MeshSpec {
                source: MeshSource::Given(GivenMesh {
                    hierarchy: None,
                    description,
                }),
                refine: m.refine,
            });
        }
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
            MeshSource::Given(g) => t.given = Some(g.description),
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
    /// A mesh given as data ([`GivenMesh::new`]), refined no further.
    pub fn given(hierarchy: Hierarchy) -> MeshSpec {
        MeshSpec {
            source: MeshSource::Given(GivenMesh::new(hierarchy)),
            refine: 0,
        }
    }

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
            MeshSource::Given(_) => "given",
            MeshSource::Rectangle { .. } => "rectangle",
            MeshSource::Disk { .. } => "disk",
            MeshSource::Polygon { .. } => "polygon",
        }
    }

    /// The names of the boundary regions a generator gives its mesh, in the order of their
    /// tags (`None` for a mesh file: its physical curves are known once it is read).
    pub fn boundary_region_names(&self) -> Option<Vec<String>> {
        match &self.source {
            MeshSource::File(_) | MeshSource::Given(_) => None,
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

    /// Resolves a relative file path against `base` (the case file's directory).
    pub(crate) fn resolve(&mut self, base: &Path) {
        if let MeshSource::File(p) = &mut self.source {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        }
    }

    pub(crate) fn validate(&self) -> std::result::Result<(), Invalid> {
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
            MeshSource::File(_) | MeshSource::Given(_) => Ok(()),
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
