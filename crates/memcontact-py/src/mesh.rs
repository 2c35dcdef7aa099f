//! `Mesh`: a triangulation (with its refinement levels, for multigrid) seen as NumPy
//! arrays, and the generators and the Gmsh reader that make one.

use crate::convert::py_err;
use crate::views::{self, Cache};
use memcontact::mesh::generate::{self, Diagonal, PolygonSpec, RectangleSpec};
use memcontact::mesh::refine::{Hierarchy, Refinement};
use memcontact::mesh::{Circle, Mesh, Point};
use numpy::ndarray::{Array1, Array2};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

/// A triangulation and the coarser levels it was refined from (the finest level is the
/// mesh; multigrid uses the others). Immutable; shared between a mesh and the results
/// solved on it.
#[pyclass(name = "Mesh", module = "memcontact._memcontact", frozen)]
#[derive(Clone)]
pub struct PyMesh {
    pub hierarchy: Arc<Hierarchy>,
    /// The arrays handed out (read-only, made once; shared by the copies of this mesh).
    cache: Arc<Cache<{ MeshSlot::COUNT }>>,
}

/// The cached arrays of a mesh.
#[derive(Clone, Copy)]
enum MeshSlot {
    Vertices,
    Triangles,
    Regions,
    Boundary,
    BoundaryEdges,
    BoundaryTags,
}

impl MeshSlot {
    const COUNT: usize = 6;
}

impl PyMesh {
    pub fn new_from(hierarchy: Hierarchy) -> PyMesh {
        PyMesh::shared(Arc::new(hierarchy))
    }

    /// A mesh of a hierarchy shared with others (results, cases).
    pub fn shared(hierarchy: Arc<Hierarchy>) -> PyMesh {
        PyMesh {
            hierarchy,
            cache: Arc::default(),
        }
    }

    /// A cached array of this mesh.
    fn cached<'py>(
        &self,
        py: Python<'py>,
        slot: MeshSlot,
        make: impl FnOnce() -> PyResult<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.cache.get(py, slot as usize, make)
    }

    fn finest(&self) -> &Mesh {
        self.hierarchy.finest()
    }
}

/// The shape of an array, for messages.
fn shape_of(a: &Bound<'_, PyAny>) -> String {
    a.getattr("shape")
        .and_then(|s| s.str().map(|s| s.to_string()))
        .unwrap_or_else(|_| "?".into())
}

/// `obj` as a contiguous int64 array; floats are refused (a triangle is made of indices).
fn integer_array<'py>(
    np: &Bound<'py, PyModule>,
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let a = np.call_method1("asarray", (obj,))?;
    let kind: String = a.getattr("dtype")?.getattr("kind")?.extract()?;
    if !(kind == "i" || kind == "u" || (kind == "f" && a.getattr("size")?.extract::<usize>()? == 0))
    {
        return Err(PyValueError::new_err(format!(
            "{name} must hold integers (vertex indices or tags), got dtype {}",
            a.getattr("dtype")?.str()?
        )));
    }
    np.call_method1("ascontiguousarray", (a, np.getattr("int64")?))
}

/// Vertices (n, 2) as a Vec of points, checking the shape.
fn points_of(vertices: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<Point>> {
    let a = vertices.as_array();
    if a.ncols() != 2 {
        return Err(PyValueError::new_err(format!(
            "vertices must have shape (n, 2), got {:?}",
            a.shape()
        )));
    }
    Ok(a.rows().into_iter().map(|r| [r[0], r[1]]).collect())
}

/// Triangles (m, 3) of vertex indices in `0..n`.
fn triangles_of(triangles: &PyReadonlyArray2<'_, i64>, n: usize) -> PyResult<Vec<[u32; 3]>> {
    let a = triangles.as_array();
    if a.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "triangles must have shape (m, 3), got {:?}",
            a.shape()
        )));
    }
    let mut out = Vec::with_capacity(a.nrows());
    for (k, r) in a.rows().into_iter().enumerate() {
        let mut t = [0u32; 3];
        for (c, &v) in r.iter().enumerate() {
            if v < 0 || v as u64 >= n as u64 {
                return Err(PyValueError::new_err(format!(
                    "triangle {k} refers to vertex {v}, but there are {n} vertices (0 to {})",
                    n.saturating_sub(1)
                )));
            }
            t[c] = v as u32;
        }
        out.push(t);
    }
    Ok(out)
}

fn regions_of(regions: Option<PyReadonlyArray1<'_, i64>>, m: usize) -> PyResult<Vec<u32>> {
    let Some(regions) = regions else {
        return Ok(vec![0; m]);
    };
    let a = regions.as_array();
    if a.len() != m {
        return Err(PyValueError::new_err(format!(
            "regions must have one tag per triangle ({m}), got {}",
            a.len()
        )));
    }
    a.iter()
        .enumerate()
        .map(|(k, &r)| {
            u32::try_from(r).map_err(|_| {
                PyValueError::new_err(format!(
                    "regions: tag {r} of triangle {k} is not in 0..2^32"
                ))
            })
        })
        .collect()
}

fn vertices_array<'py>(py: Python<'py>, mesh: &Mesh) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = mesh.points.iter().flat_map(|p| [p[0], p[1]]).collect();
    let a = Array2::from_shape_vec((mesh.points.len(), 2), flat).expect("n x 2");
    PyArray2::from_owned_array(py, a)
}

fn triangles_array<'py>(py: Python<'py>, mesh: &Mesh) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = mesh
        .triangles
        .iter()
        .flat_map(|t| t.map(i64::from))
        .collect();
    let a = Array2::from_shape_vec((mesh.triangles.len(), 3), flat).expect("m x 3");
    PyArray2::from_owned_array(py, a)
}

fn regions_array<'py>(py: Python<'py>, mesh: &Mesh) -> Bound<'py, PyArray1<i64>> {
    PyArray1::from_owned_array(
        py,
        Array1::from_iter(mesh.regions.iter().map(|&r| i64::from(r))),
    )
}

/// Names of tags given as a dict (tag → name): tags in 0..2³², names strings.
fn tag_names(names: &Bound<'_, PyAny>, what: &str) -> PyResult<BTreeMap<u32, String>> {
    let dict = names.cast::<PyDict>().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(format!(
            "{what} must be a dict of tags to names, got a {}",
            names
                .get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_default()
        ))
    })?;
    let mut out = BTreeMap::new();
    for (k, v) in dict.iter() {
        let tag = crate::convert::count(&k, what)
            .ok()
            .and_then(|t| u32::try_from(t).ok())
            .ok_or_else(|| {
                PyValueError::new_err(format!("{what}: the tag {k} is not an integer in 0..2^32"))
            })?;
        let name: String = v.extract().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(format!(
                "{what}: the name of tag {tag} must be a string"
            ))
        })?;
        out.insert(tag, name);
    }
    Ok(out)
}

/// Builds and checks a mesh from arrays (see `Mesh.__new__`).
pub fn mesh_from_arrays(
    vertices: &PyReadonlyArray2<'_, f64>,
    triangles: &PyReadonlyArray2<'_, i64>,
    regions: Option<PyReadonlyArray1<'_, i64>>,
    region_names: Option<BTreeMap<u32, String>>,
) -> PyResult<Mesh> {
    let points = points_of(vertices)?;
    let tris = triangles_of(triangles, points.len())?;
    let regions = regions_of(regions, tris.len())?;
    Mesh::new(points, tris, regions, region_names.unwrap_or_default()).map_err(py_err)
}

#[pymethods]
impl PyMesh {
    /// Mesh(vertices, triangles, regions=None, region_names=None, boundary_edges=None,
    ///      boundary_tags=None, boundary_names=None)
    ///
    /// A mesh from NumPy arrays: `vertices` (n, 2) float64, `triangles` (m, 3) int64
    /// vertex indices, `regions` (m,) int64 region tags (default all 0) and `region_names`
    /// mapping tags to names (the keys of region tables). `boundary_edges` (k, 2) vertex
    /// pairs of boundary edges with `boundary_tags` (k,) and `boundary_names` name
    /// boundary regions (the keys of `[boundary]` tables and `free`; untagged boundary
    /// edges form the region `default`). The mesh is checked: finite coordinates, no degenerate,
    /// inverted or duplicate element, no unused vertex, a manifold boundary, tagged edges
    /// on the boundary; clockwise meshes are reoriented.
    #[new]
    #[pyo3(signature = (vertices, triangles, regions=None, region_names=None,
                        boundary_edges=None, boundary_tags=None, boundary_names=None))]
    #[allow(clippy::too_many_arguments)]
    fn py_new(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        regions: Option<&Bound<'_, PyAny>>,
        region_names: Option<&Bound<'_, PyAny>>,
        boundary_edges: Option<&Bound<'_, PyAny>>,
        boundary_tags: Option<&Bound<'_, PyAny>>,
        boundary_names: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyMesh> {
        let region_names = region_names
            .map(|n| tag_names(n, "region_names"))
            .transpose()?;
        let boundary_names = boundary_names
            .map(|n| tag_names(n, "boundary_names"))
            .transpose()?;
        let np = py.import("numpy")?;
        let float64 = np.getattr("float64")?;
        let v = np.call_method1("ascontiguousarray", (vertices, &float64))?;
        let v: PyReadonlyArray2<'_, f64> = v.extract().map_err(|_| {
            PyValueError::new_err(format!(
                "vertices must have shape (n, 2), got shape {}",
                shape_of(&v)
            ))
        })?;
        let t = integer_array(&np, triangles, "triangles")?;
        let t: PyReadonlyArray2<'_, i64> = t.extract().map_err(|_| {
            PyValueError::new_err(format!(
                "triangles must have shape (m, 3), got shape {}",
                shape_of(&t)
            ))
        })?;
        let r = match regions {
            None => None,
            Some(r) => {
                let r = integer_array(&np, r, "regions")?;
                Some(r.extract::<PyReadonlyArray1<'_, i64>>().map_err(|_| {
                    PyValueError::new_err(format!(
                        "regions must have shape (m,), got shape {}",
                        shape_of(&r)
                    ))
                })?)
            }
        };
        let mut mesh = mesh_from_arrays(&v, &t, r, region_names)?;
        if boundary_edges.is_some() || boundary_tags.is_some() || boundary_names.is_some() {
            let (Some(e), Some(tags)) = (boundary_edges, boundary_tags) else {
                return Err(PyValueError::new_err(
                    "boundary regions need both boundary_edges (k, 2) and boundary_tags (k,)",
                ));
            };
            let e = integer_array(&np, e, "boundary_edges")?;
            let e: PyReadonlyArray2<'_, i64> = e.extract().map_err(|_| {
                PyValueError::new_err(format!(
                    "boundary_edges must have shape (k, 2), got shape {}",
                    shape_of(&e)
                ))
            })?;
            let a = e.as_array();
            if a.ncols() != 2 {
                return Err(PyValueError::new_err(format!(
                    "boundary_edges must have shape (k, 2), got {:?}",
                    a.shape()
                )));
            }
            let n = mesh.n_vertices();
            let mut edges = Vec::with_capacity(a.nrows());
            for (k, r) in a.rows().into_iter().enumerate() {
                if r.iter().any(|&v| v < 0 || v as u64 >= n as u64) {
                    return Err(PyValueError::new_err(format!(
                        "boundary edge {k} refers to vertex ({}, {}), but there are {n} \
                         vertices",
                        r[0], r[1]
                    )));
                }
                edges.push([r[0] as u32, r[1] as u32]);
            }
            let tags = integer_array(&np, tags, "boundary_tags")?;
            let tags: PyReadonlyArray1<'_, i64> = tags.extract().map_err(|_| {
                PyValueError::new_err(format!(
                    "boundary_tags must have shape (k,), got shape {}",
                    shape_of(&tags)
                ))
            })?;
            let tags = regions_of(Some(tags), edges.len()).map_err(|e| {
                PyValueError::new_err(e.to_string().replace("regions", "boundary_tags"))
            })?;
            mesh = mesh
                .with_boundary_regions(edges, tags, boundary_names.unwrap_or_default())
                .map_err(py_err)?;
        }
        Ok(PyMesh::new_from(Hierarchy::single(mesh)))
    }

    /// The tagged boundary edges (vertex pairs), shape (k, 2), int64: Gmsh physical curves
    /// or the generators' sides (a new array). Boundary edges not listed form the region
    /// `default`.
    #[getter]
    fn boundary_edges<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cached(py, MeshSlot::BoundaryEdges, || {
            let b = &self.finest().boundary;
            let flat: Vec<i64> = b.edges.iter().flat_map(|e| e.map(i64::from)).collect();
            views::owned2(py, flat, 2)
        })
    }

    /// The boundary region tag of every edge of `boundary_edges`, shape (k,), int64.
    #[getter]
    fn boundary_tags<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cached(py, MeshSlot::BoundaryTags, || {
            let b = &self.finest().boundary;
            views::owned1(py, b.tags.iter().map(|&t| i64::from(t)).collect())
        })
    }

    /// The names of the boundary region tags (the keys of `[boundary]` tables and
    /// `free`), e.g. `{1: "bottom", 2: "right", 3: "top", 4: "left"}` for a rectangle.
    #[getter]
    fn boundary_names(&self) -> BTreeMap<u32, String> {
        self.finest().boundary.names.clone()
    }

    /// Vertex coordinates, shape (n, 2), float64 (a read-only view of the mesh's own
    /// coordinates).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cached(py, MeshSlot::Vertices, || {
            let points = &self.finest().points;
            // SAFETY: `[f64; 2]` is two f64 with no padding; the points live in the shared
            // hierarchy, which the owner keeps alive and nobody mutates (it is behind an
            // `Arc` that the owner shares, so never uniquely owned while the view lives).
            let flat = unsafe {
                std::slice::from_raw_parts(points.as_ptr().cast::<f64>(), 2 * points.len())
            };
            let owner = views::owner(py, self.hierarchy.clone())?;
            unsafe { views::view2(flat, 2, &owner) }
        })
    }

    /// Triangles as vertex indices, shape (m, 3), int64, counter-clockwise (read-only).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cached(py, MeshSlot::Triangles, || {
            views::read_only(triangles_array(py, self.finest()).into_any())
        })
    }

    /// The region tag of every triangle, shape (m,), int64 (read-only).
    #[getter]
    fn regions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cached(py, MeshSlot::Regions, || {
            views::read_only(regions_array(py, self.finest()).into_any())
        })
    }

    /// The names of the region tags that have one.
    #[getter]
    fn region_names(&self) -> BTreeMap<u32, String> {
        self.finest().region_names.clone()
    }

    /// Whether each vertex lies on the boundary (where u = 0), shape (n,), bool.
    #[getter]
    fn boundary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.cached(py, MeshSlot::Boundary, || {
            views::owned1(py, self.finest().boundary_vertices())
        })
    }

    /// The number of vertices.
    #[getter]
    fn n_vertices(&self) -> usize {
        self.finest().n_vertices()
    }

    /// The number of triangles.
    #[getter]
    fn n_triangles(&self) -> usize {
        self.finest().n_triangles()
    }

    /// The number of nested levels (1 for a mesh that was not refined).
    #[getter]
    fn levels(&self) -> usize {
        self.hierarchy.depth()
    }

    /// The circle a disc mesh approximates, `(cx, cy, radius)`, or None.
    #[getter]
    fn circle(&self) -> Option<(f64, f64, f64)> {
        self.finest()
            .curve
            .map(|c| (c.center[0], c.center[1], c.radius))
    }

    /// Quality figures: vertices, triangles, unknowns, l_n (largest diameter), s_n (largest
    /// diameter / inscribed diameter), min_angle_deg, area.
    fn quality<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let q = self.finest().quality();
        crate::convert::to_py(py, &q)
    }

    /// The mesh refined uniformly `times` times (each triangle into four; new boundary
    /// vertices of a disc are moved onto its circle). The levels are kept, so a solve on
    /// the refined mesh can use multigrid.
    #[pyo3(signature = (times=None), text_signature = "($self, times=1)")]
    fn refine(&self, py: Python<'_>, times: Option<&Bound<'_, PyAny>>) -> PyResult<PyMesh> {
        let times = match times {
            Some(t) => crate::convert::count(t, "refine: times")?,
            None => 1,
        };
        if times > memcontact::problem::MAX_REFINE {
            return Err(PyValueError::new_err(format!(
                "refine: {times} refinements is too many (at most {}: each multiplies the \
                 triangles by 4)",
                memcontact::problem::MAX_REFINE
            )));
        }
        let base = memcontact::limits::MeshSize::of(self.finest());
        memcontact::limits::check_mesh_fits(
            base,
            times,
            &format!(
                "refine({times}) of a mesh of {} triangles",
                self.finest().n_triangles()
            ),
        )
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let mut h = (*self.hierarchy).clone();
        crate::convert::detached(py, || h.refine(times));
        Ok(PyMesh::new_from(h))
    }

    /// Draws the mesh with matplotlib: edges, regions and named boundary regions.
    ///
    /// Parameters
    /// ----------
    /// ax : matplotlib.axes.Axes, optional
    ///     Where to draw (default: a new figure).
    /// **kwargs
    ///     `regions=False`, `boundary=False`, `title`; the rest goes to `Axes.triplot`.
    ///
    /// Returns
    /// -------
    /// matplotlib.axes.Axes
    ///
    /// Raises
    /// ------
    /// ImportError
    ///     matplotlib is not installed.
    #[pyo3(signature = (ax=None, **kwargs))]
    fn plot<'py>(
        slf: &Bound<'py, Self>,
        ax: Option<&Bound<'py, PyAny>>,
        kwargs: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(slf.py(), "mesh_plot", (slf, ax), kwargs)
    }

    /// A mesh from a `meshio.Mesh`: its 3-node triangles (unused points dropped), Gmsh
    /// physical surfaces as named regions and physical curves on the boundary as boundary
    /// regions (lines inside the mesh skipped with a warning).
    ///
    /// Parameters
    /// ----------
    /// mesh : meshio.Mesh
    /// regions : str, optional
    ///     The cell data of the region tags (default `gmsh:physical`, else `region`).
    ///
    /// Returns
    /// -------
    /// Mesh
    ///
    /// Raises
    /// ------
    /// ValueError
    ///     Other cells than triangles, lines and vertices, a mesh not plane or not valid.
    /// TypeError
    ///     Not a meshio mesh.
    #[staticmethod]
    #[pyo3(signature = (mesh, regions=None))]
    fn from_meshio<'py>(
        py: Python<'py>,
        mesh: &Bound<'py, PyAny>,
        regions: Option<&str>,
    ) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::call_helper(py, "mesh_from_meshio", (mesh, regions), None)
    }

    fn __repr__(&self) -> String {
        let m = self.finest();
        format!(
            "Mesh({} vertices, {} triangles, {} level{})",
            m.n_vertices(),
            m.n_triangles(),
            self.hierarchy.depth(),
            if self.hierarchy.depth() == 1 { "" } else { "s" }
        )
    }

    fn __len__(&self) -> usize {
        self.finest().n_vertices()
    }

    /// Pickling: the levels as arrays, rebuilt and checked on loading.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let module = py.import("memcontact._memcontact")?;
        let rebuild = module.getattr("_mesh_from_state")?;
        let state = mesh_state(py, &self.hierarchy)?;
        PyTuple::new(py, [rebuild, PyTuple::new(py, [state])?.into_any()])
    }
}

/// The pickled form of a hierarchy: `{"levels": [(vertices, triangles, regions), ...],
/// "parents": [(k, 2) uint32 arrays], "names": {...}, "circle": (cx, cy, r) or None}`.
pub fn mesh_state<'py>(py: Python<'py>, h: &Hierarchy) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    let levels = PyList::empty(py);
    for m in &h.levels {
        levels.append((
            vertices_array(py, m),
            triangles_array(py, m),
            regions_array(py, m),
        ))?;
    }
    d.set_item("levels", levels)?;
    let parents = PyList::empty(py);
    for r in &h.refinements {
        let flat: Vec<i64> = r.parents.iter().flat_map(|p| p.map(i64::from)).collect();
        let a = Array2::from_shape_vec((r.parents.len(), 2), flat).expect("k x 2");
        parents.append(PyArray2::from_owned_array(py, a))?;
    }
    d.set_item("parents", parents)?;
    d.set_item("names", h.finest().region_names.clone())?;
    // Boundary regions of every level: (edges (k, 2), tags (k,)), and their names.
    let boundary = PyList::empty(py);
    for m in &h.levels {
        let b = &m.boundary;
        let flat: Vec<i64> = b.edges.iter().flat_map(|e| e.map(i64::from)).collect();
        let edges = Array2::from_shape_vec((b.edges.len(), 2), flat).expect("k x 2");
        let tags: Vec<i64> = b.tags.iter().map(|&t| i64::from(t)).collect();
        boundary.append((
            PyArray2::from_owned_array(py, edges),
            PyArray1::from_vec(py, tags),
        ))?;
    }
    d.set_item("boundary", boundary)?;
    d.set_item("boundary_names", h.finest().boundary.names.clone())?;
    d.set_item(
        "circle",
        h.finest()
            .curve
            .map(|c| (c.center[0], c.center[1], c.radius)),
    )?;
    Ok(d.into_any())
}

/// Rebuilds a hierarchy from [`mesh_state`].
pub fn hierarchy_from_state(state: &Bound<'_, PyAny>) -> PyResult<Hierarchy> {
    let d = state.cast::<PyDict>()?;
    let get = |k: &str| -> PyResult<Bound<'_, PyAny>> {
        d.get_item(k)?
            .ok_or_else(|| PyValueError::new_err(format!("mesh state without '{k}'")))
    };
    let names: BTreeMap<u32, String> = get("names")?.extract()?;
    let circle: Option<(f64, f64, f64)> = get("circle")?.extract()?;
    // Boundary regions (absent from states written before they existed).
    let boundary_names: BTreeMap<u32, String> = match d.get_item("boundary_names")? {
        Some(v) => v.extract()?,
        None => BTreeMap::new(),
    };
    let mut boundary = Vec::new();
    if let Some(list) = d.get_item("boundary")? {
        for item in list.try_iter()? {
            let (e, t): (PyReadonlyArray2<'_, i64>, PyReadonlyArray1<'_, i64>) = item?.extract()?;
            let edges: Vec<[u32; 2]> = e
                .as_array()
                .rows()
                .into_iter()
                .map(|r| [r[0] as u32, r[1] as u32])
                .collect();
            let tags: Vec<u32> = t.as_array().iter().map(|&x| x as u32).collect();
            boundary.push(memcontact::mesh::BoundaryRegions {
                edges,
                tags,
                names: boundary_names.clone(),
            });
        }
    }
    let mut levels = Vec::new();
    for item in get("levels")?.try_iter()? {
        let (v, t, r): (
            PyReadonlyArray2<'_, f64>,
            PyReadonlyArray2<'_, i64>,
            PyReadonlyArray1<'_, i64>,
        ) = item?.extract()?;
        // The arrays come from a checked mesh: only their shapes and indices are checked
        // again (the full checks of `Mesh::new` cost more than the rest of unpickling).
        let points = points_of(&v)?;
        let triangles = triangles_of(&t, points.len())?;
        let regions = regions_of(Some(r), triangles.len())?;
        levels.push(Mesh {
            points,
            triangles,
            regions,
            region_names: names.clone(),
            curve: circle.map(|(x, y, r)| Circle {
                center: [x, y],
                radius: r,
            }),
            boundary: boundary.get(levels.len()).cloned().unwrap_or_default(),
            numbering: None,
        });
    }
    let mut refinements = Vec::new();
    for item in get("parents")?.try_iter()? {
        let a: PyReadonlyArray2<'_, i64> = item?.extract()?;
        let parents = a
            .as_array()
            .rows()
            .into_iter()
            .map(|r| [r[0] as u32, r[1] as u32])
            .collect();
        refinements.push(Refinement { parents });
    }
    if levels.is_empty() || refinements.len() + 1 != levels.len() {
        return Err(PyValueError::new_err("mesh state: inconsistent levels"));
    }
    Ok(Hierarchy {
        levels,
        refinements,
    })
}

/// Rebuilds a pickled mesh.
#[pyfunction]
pub fn _mesh_from_state(state: &Bound<'_, PyAny>) -> PyResult<PyMesh> {
    Ok(PyMesh::new_from(hierarchy_from_state(state)?))
}

/// The structured mesh of the rectangle [x0, x1] × [y0, y1] with nx × ny cells, each cut
/// into two triangles along `diagonal` ("right", "left", "alternate") or four
/// ("crossed"). With nx, ny sharing a power-of-two factor the coarser levels are kept.
#[pyfunction]
#[pyo3(signature = (x0=0.0, y0=0.0, x1=1.0, y1=1.0, nx=16, ny=None, diagonal="right"))]
#[allow(clippy::too_many_arguments)]
pub fn rectangle(
    py: Python<'_>,
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    nx: usize,
    ny: Option<usize>,
    diagonal: &str,
) -> PyResult<PyMesh> {
    let diagonal: Diagonal = diagonal.parse().map_err(py_err)?;
    let spec = RectangleSpec {
        x0,
        y0,
        x1,
        y1,
        nx,
        ny: ny.unwrap_or(nx),
        diagonal,
    };
    let h = crate::convert::detached(py, || generate::rectangle(&spec)).map_err(py_err)?;
    Ok(PyMesh::new_from(h))
}

/// An unstructured mesh of the disc of `center` and `radius` with elements of about
/// `size` (default radius/8); boundary vertices lie on the circle. A mesh of more than
/// about 150 000 triangles is a coarser Delaunay mesh refined uniformly, with its levels
/// (for multigrid).
#[pyfunction]
#[pyo3(signature = (center=(0.0, 0.0), radius=1.0, size=None))]
pub fn disk(
    py: Python<'_>,
    center: (f64, f64),
    radius: f64,
    size: Option<f64>,
) -> PyResult<PyMesh> {
    let size = size.unwrap_or(radius / 8.0);
    let h = crate::convert::detached(py, || {
        generate::disk_levels([center.0, center.1], radius, size)
    })
    .map_err(py_err)?;
    Ok(PyMesh::new_from(h))
}

/// A named region polygon, as Python gives it.
type NamedPolygon = (String, Vec<(f64, f64)>);

/// A constrained Delaunay mesh of the polygon `outer` minus `holes`, with named
/// sub-polygons `regions` (a dict name -> polygon; triangles outside all of them are the
/// region "default"), elements of about `size` and angles of at least `min_angle` degrees.
/// A mesh of more than about 150 000 triangles is a coarser Delaunay mesh refined
/// uniformly, with its levels (for multigrid).
#[pyfunction]
#[pyo3(signature = (outer, size, holes=None, regions=None, min_angle=25.0))]
pub fn polygon(
    py: Python<'_>,
    outer: Vec<(f64, f64)>,
    size: f64,
    holes: Option<Vec<Vec<(f64, f64)>>>,
    regions: Option<Vec<NamedPolygon>>,
    min_angle: f64,
) -> PyResult<PyMesh> {
    let pts = |v: Vec<(f64, f64)>| v.into_iter().map(|(x, y)| [x, y]).collect::<Vec<_>>();
    let regions = regions.unwrap_or_default();
    for (name, _) in &regions {
        if name.trim().is_empty() || name == memcontact::field::DEFAULT_KEY {
            return Err(PyValueError::new_err(format!(
                "regions: region name \"{name}\" is reserved or empty: name the region"
            )));
        }
    }
    if !(min_angle > 0.0 && min_angle <= 30.0) {
        return Err(PyValueError::new_err(format!(
            "min_angle: must be in (0, 30] degrees, got {min_angle}"
        )));
    }
    let spec = PolygonSpec {
        outer: pts(outer),
        holes: holes.unwrap_or_default().into_iter().map(pts).collect(),
        regions: regions.into_iter().map(|(n, p)| (n, pts(p))).collect(),
        size,
        min_angle,
    };
    let h = crate::convert::detached(py, || generate::polygon_levels(&spec)).map_err(py_err)?;
    Ok(PyMesh::new_from(h))
}

/// Reads a Gmsh mesh (MSH 2.2 or 4.1, ASCII or binary): the mesh and the reader's warnings.
#[pyfunction]
pub fn read_gmsh(py: Python<'_>, path: PathBuf) -> PyResult<(PyMesh, Vec<String>)> {
    let (mesh, warnings) =
        crate::convert::detached(py, || memcontact::io::gmsh::read_msh(&path)).map_err(py_err)?;
    Ok((PyMesh::new_from(Hierarchy::single(mesh)), warnings))
}
