//! P1 finite elements: element geometry, local matrices and the global assembly of the
//! paper's S, L and D (docs/theory.md#matrices) over the interior vertices.
//!
//! Assembly is row-wise: every unknown gathers the contributions of the triangles around
//! it. Rows are independent, so they are built in parallel and the result does not depend
//! on the number of threads.

use crate::error::{Error, Result};
use crate::field::Coefficient;
pub use crate::mesh::VertexTriangles;
use crate::mesh::{corner, DofMap, Mesh, Point};
use crate::quadrature::{map, DEGREE5};
use crate::sparse::{row_chunks, Csr, Pattern};
use rayon::prelude::*;
use std::sync::Arc;

/// Geometry of one P1 triangle: area and the (constant) gradients of the barycentric
/// coordinates λ₀, λ₁, λ₂.
#[derive(Debug, Clone, Copy)]
pub struct Element {
    /// Corner coordinates.
    pub corners: [Point; 3],
    /// Area (positive: meshes are counter-clockwise).
    pub area: f64,
    /// ∇λ_k.
    pub grad: [[f64; 2]; 3],
}

impl Element {
    /// The element of triangle `k` of `mesh`.
    pub fn of(mesh: &Mesh, k: usize) -> Element {
        Element::new(mesh.corners(k))
    }

    /// The element with the given corners.
    pub fn new(c: [Point; 3]) -> Element {
        let two_a =
            (c[1][0] - c[0][0]) * (c[2][1] - c[0][1]) - (c[2][0] - c[0][0]) * (c[1][1] - c[0][1]);
        let mut grad = [[0.0; 2]; 3];
        for (k, g) in grad.iter_mut().enumerate() {
            let (a, b) = (c[(k + 1) % 3], c[(k + 2) % 3]);
            // ∇λ_k is the inward normal of the opposite edge divided by twice the area.
            *g = [(a[1] - b[1]) / two_a, (b[0] - a[0]) / two_a];
        }
        Element {
            corners: c,
            area: 0.5 * two_a,
            grad,
        }
    }

    /// `∫_T ∇λ_a · ∇λ_b`.
    #[inline]
    pub fn stiffness(&self, a: usize, b: usize) -> f64 {
        self.area * (self.grad[a][0] * self.grad[b][0] + self.grad[a][1] * self.grad[b][1])
    }

    /// `∫_T c λ_a λ_b` (exact for constant c on the region, degree-5 quadrature otherwise):
    /// entry (a, b) of [`Element::weighted_mass_matrix`].
    #[cfg(any(test, feature = "bench"))]
    #[inline]
    pub fn weighted_mass(&self, c: &dyn Coefficient, region: u32, a: usize, b: usize) -> f64 {
        self.weighted_mass_matrix(c, region)[sym_index(a, b)]
    }

    /// The element matrix `∫_T c λ_a λ_b`: the entries (a, b) with a ≤ b, in the order of
    /// [`sym_index`] (the matrix is exactly symmetric). Exact for c constant on the region
    /// (`|T| c / 6` on the diagonal, `|T| c / 12` off it), else degree-5 quadrature with c
    /// evaluated once per point for the whole matrix.
    pub fn weighted_mass_matrix(&self, c: &dyn Coefficient, region: u32) -> [f64; 6] {
        let values = match c.on_region(region) {
            Some(v) => {
                let (d, o) = (mass_fraction(0, 0), mass_fraction(0, 1));
                return [d, o, o, d, o, d].map(|f| v * self.area * f);
            }
            None => self.quadrature_values(c, region),
        };
        let entry = |a: usize, b: usize| {
            self.area
                * DEGREE5
                    .iter()
                    .zip(&values)
                    .map(|((l, w), cv)| w * cv * l[a] * l[b])
                    .sum::<f64>()
        };
        [
            entry(0, 0),
            entry(0, 1),
            entry(0, 2),
            entry(1, 1),
            entry(1, 2),
            entry(2, 2),
        ]
    }

    /// `∫_T c λ_a` for a = 0, 1, 2: `|T| c / 3` for c constant on the region, else
    /// degree-5 quadrature with c evaluated once per point for the three corners.
    #[inline]
    pub fn weighted_load_row(&self, c: &dyn Coefficient, region: u32) -> [f64; 3] {
        match c.on_region(region) {
            Some(v) => [v * self.area / 3.0; 3],
            None => {
                let values = self.quadrature_values(c, region);
                [0, 1, 2].map(|a| {
                    self.area
                        * DEGREE5
                            .iter()
                            .zip(&values)
                            .map(|((l, w), cv)| w * cv * l[a])
                            .sum::<f64>()
                })
            }
        }
    }

    /// `∫_T c λ_a`: corner a of [`Element::weighted_load_row`].
    #[cfg(any(test, feature = "bench"))]
    #[inline]
    pub fn weighted_load(&self, c: &dyn Coefficient, region: u32, a: usize) -> f64 {
        self.weighted_load_row(c, region)[a]
    }

    /// c at the points of the degree-5 rule ([`DEGREE5`]) on this triangle.
    #[inline]
    fn quadrature_values(&self, c: &dyn Coefficient, region: u32) -> [f64; 7] {
        let points = DEGREE5.map(|(l, _)| map(&self.corners, &l));
        let mut values = [0.0; 7];
        c.at_points(&points, region, &mut values);
        values
    }
}

/// `∫_T λ_a λ_b / |T|`: 1/6 on the diagonal, 1/12 off it (the P1 mass matrix).
#[inline]
fn mass_fraction(a: usize, b: usize) -> f64 {
    if a == b {
        1.0 / 6.0
    } else {
        1.0 / 12.0
    }
}

/// The position of entry (a, b) of a symmetric 3 × 3 element matrix stored as its upper
/// triangle by rows: (0,0), (0,1), (0,2), (1,1), (1,2), (2,2).
#[inline]
pub fn sym_index(a: usize, b: usize) -> usize {
    const INDEX: [[usize; 3]; 3] = [[0, 1, 2], [1, 3, 4], [2, 4, 5]];
    INDEX[a][b]
}

/// Collects into `buf` the unknowns sharing a triangle with vertex `v`, sorted and unique.
/// Up to [`SMALL_ROW`] candidates the row is gathered from the fan and ranked without
/// branches (a scattered mesh's rows defeat a comparison sort's branch prediction),
/// beyond that sorted.
fn row_columns(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    boundary: &[bool],
    v: usize,
    buf: &mut Vec<u32>,
) {
    buf.clear();
    let fan = adj.of(v);
    if 1 + 2 * fan.len() > SMALL_ROW {
        for &k in fan {
            buf.extend(
                mesh.triangles[k as usize]
                    .iter()
                    .filter_map(|&w| dofs.of(w as usize)),
            );
        }
        buf.sort_unstable();
        buf.dedup();
        return;
    }
    // The vertex and the vertices after it in its triangles are distinct (every directed
    // edge is used once); on the boundary, the vertices before it add those not among
    // them. Unknowns, or u32::MAX for a boundary vertex (ranked last, dropped).
    let unknown = |w: u32| dofs.of(w as usize).unwrap_or(u32::MAX);
    let (mut next, mut prev) = ([u32::MAX; SMALL_ROW], [u32::MAX; SMALL_ROW]);
    for (q, &k) in fan.iter().enumerate() {
        let t = mesh.triangles[k as usize];
        let a = corner(t, v as u32);
        next[q] = t[(a + 1) % 3];
        prev[q] = t[(a + 2) % 3];
    }
    let mut cand = [u32::MAX; SMALL_ROW];
    cand[0] = unknown(v as u32);
    let mut m = 1;
    for &w in &next[..fan.len()] {
        cand[m] = unknown(w);
        m += 1;
    }
    // Round an interior vertex the fan closes: those before it are those after it.
    let open = if boundary[v] { fan.len() } else { 0 };
    for &w in &prev[..open] {
        let known: usize = next[..fan.len()].iter().map(|&x| (x == w) as usize).sum();
        cand[m] = unknown(w);
        m += (known == 0) as usize;
    }
    let mut sorted = [u32::MAX; SMALL_ROW];
    for &x in &cand[..m] {
        let rank: usize = cand[..m].iter().map(|&y| (y < x) as usize).sum();
        sorted[rank] = x;
    }
    let unknowns: usize = cand[..m].iter().map(|&x| (x != u32::MAX) as usize).sum();
    buf.extend_from_slice(&sorted[..unknowns]);
}

/// Candidates of a row that [`row_columns`] handles in fixed-size buffers (a vertex and
/// the two others of up to 15 triangles).
const SMALL_ROW: usize = 32;

/// Rows per parallel task of assembly (fixed, so results do not depend on the thread count).
const ROW_BLOCK: usize = 2048;

/// The rows `first..first + ROW_BLOCK` (fewer in the last block) of every block.
fn block_rows(n: usize, block: usize) -> std::ops::Range<usize> {
    block * ROW_BLOCK..((block + 1) * ROW_BLOCK).min(n)
}

/// The sparsity pattern over unknowns: `(i, j)` is stored when vertices `a_i`, `a_j` share
/// a triangle. S and the consistent L live on it. One parallel pass over blocks of rows,
/// whose columns are then concatenated. `boundary`: the mesh's boundary vertices
/// ([`Mesh::boundary_vertices`]).
pub fn unknowns_pattern(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    boundary: &[bool],
) -> Result<Pattern> {
    let n = dofs.len();
    let blocks: Vec<(Vec<u32>, Vec<u32>)> = (0..n.div_ceil(ROW_BLOCK))
        .into_par_iter()
        .map(|b| {
            let rows = block_rows(n, b);
            let mut lengths = Vec::with_capacity(rows.len());
            let mut cols = Vec::with_capacity(rows.len() * 8);
            let mut buf = Vec::with_capacity(32);
            for i in rows {
                row_columns(mesh, dofs, adj, boundary, dofs.vertex[i] as usize, &mut buf);
                lengths.push(buf.len() as u32);
                cols.extend_from_slice(&buf);
            }
            (lengths, cols)
        })
        .collect();
    let nnz: usize = blocks.iter().map(|(_, c)| c.len()).sum();
    if nnz > crate::sparse::MAX_ENTRIES {
        return Err(Error::Mesh(format!(
            "the mesh's matrices would hold {nnz} entries, more than the {} a run supports",
            crate::sparse::MAX_ENTRIES
        )));
    }
    Ok(Pattern::from_blocks(&blocks))
}

/// The position of column `j` in the sorted, distinct columns `cols` of a row that holds
/// it: the number of columns before it (counted without branches, which on a scattered
/// mesh's rows of about seven entries beats a search).
#[inline]
fn position(cols: &[u32], j: u32) -> usize {
    let p = cols.iter().map(|&c| (c < j) as usize).sum();
    debug_assert_eq!(cols.get(p), Some(&j), "the pattern covers the patch");
    p
}

/// Assembles the stiffness matrix `S_ij = t ∫ ∇g_i·∇g_j` and, when `h` is given, the
/// consistent foundation matrix `L_ij = ∫ h g_i g_j` on `pattern`, in one pass over the
/// rows (docs/theory.md#matrices). Entry `(i, j)` sums the element integrals of the
/// triangles around `a_i` (`∫_T ∇λ_a·∇λ_b` from the edges opposite corners a and b, one
/// division per triangle). Blocks of rows are assembled in parallel; the result does not
/// depend on the thread count.
pub fn assemble_stiffness_and_mass(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    pattern: &Arc<Pattern>,
    t: f64,
    h: Option<&dyn Coefficient>,
) -> (Csr, Option<Csr>) {
    let (s, l) = assemble_rows(mesh, dofs, adj, pattern, Some(t), h);
    (s.expect("the stiffness matrix was asked for"), l)
}

/// The consistent foundation matrix `L_ij = ∫ h g_i g_j` alone on `pattern`, by the
/// element integrals of [`assemble_stiffness_and_mass`]; the triangles of regions where h
/// is 0 are not visited (a region's derivative coefficient is 0 outside it).
pub fn assemble_mass(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    pattern: &Arc<Pattern>,
    h: &dyn Coefficient,
) -> Csr {
    assemble_rows(mesh, dofs, adj, pattern, None, Some(h))
        .1
        .expect("the mass matrix was asked for")
}

/// `xᵀ L x` for the consistent foundation matrix `L_ij = ∫ h g_i g_j` of `h` over the
/// unknowns (x indexed by unknowns), by its element matrices, without assembling L: the
/// triangles of regions where h is 0 are skipped. Sums in fixed blocks of triangles, so
/// that the result does not depend on the thread count.
pub fn mass_quad_form(mesh: &Mesh, dofs: &DofMap, h: &dyn Coefficient, x: &[f64]) -> f64 {
    const BLOCK: usize = 8192;
    let nt = mesh.n_triangles();
    let blocks: Vec<f64> = (0..nt.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            let mut sum = 0.0;
            for k in b * BLOCK..((b + 1) * BLOCK).min(nt) {
                let region = mesh.regions[k];
                if h.on_region(region) == Some(0.0) {
                    continue;
                }
                let xs =
                    mesh.triangles[k].map(|w| dofs.of(w as usize).map_or(0.0, |i| x[i as usize]));
                if xs == [0.0; 3] {
                    continue;
                }
                let m = Element::of(mesh, k).weighted_mass_matrix(h, region);
                for a in 0..3 {
                    for c in 0..3 {
                        sum += m[sym_index(a, c)] * xs[a] * xs[c];
                    }
                }
            }
            sum
        })
        .collect();
    blocks.iter().sum()
}

/// [`assemble_stiffness_and_mass`], S assembled when `t` is given and L when `h` is.
fn assemble_rows(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    pattern: &Arc<Pattern>,
    t: Option<f64>,
    h: Option<&dyn Coefficient>,
) -> (Option<Csr>, Option<Csr>) {
    let n = pattern.n();
    // Where h varies on a triangle's region: its element matrix, computed once (every
    // corner's row reads it), with h evaluated once per quadrature point.
    let masses: Vec<[f64; 6]> = match h {
        Some(h) if mesh.regions.par_iter().any(|&r| h.on_region(r).is_none()) => (0..mesh
            .n_triangles())
            .into_par_iter()
            .with_min_len(1024)
            .map(|k| {
                let region = mesh.regions[k];
                match h.on_region(region) {
                    Some(_) => [0.0; 6],
                    None => Element::of(mesh, k).weighted_mass_matrix(h, region),
                }
            })
            .collect(),
        _ => Vec::new(),
    };
    let mut s = t.map(|_| Csr::zeros(pattern.clone()));
    let mut l = h.map(|_| Csr::zeros(pattern.clone()));
    let (s_blocks, l_blocks) = (
        optional_row_chunks(pattern, s.as_mut(), n),
        optional_row_chunks(pattern, l.as_mut(), n),
    );
    s_blocks.into_par_iter().zip(l_blocks).enumerate().for_each(
        |(b, (mut s_block, mut l_block))| {
            let rows = block_rows(n, b);
            let base = pattern.ptr(rows.start);
            for i in rows {
                let range = pattern.ptr(i) - base..pattern.ptr(i + 1) - base;
                let cols = &pattern.col[pattern.ptr(i)..pattern.ptr(i + 1)];
                let v = dofs.vertex[i];
                for &k in adj.of(v as usize) {
                    let region = mesh.regions[k as usize];
                    let h_const = h.and_then(|h| h.on_region(region));
                    if s_block.is_none() && h_const == Some(0.0) {
                        continue;
                    }
                    let tri = mesh.triangles[k as usize];
                    let a = corner(tri, v);
                    let c = tri.map(|w| mesh.points[w as usize]);
                    let e = [0, 1, 2].map(|q| {
                        let (p, r) = (c[(q + 1) % 3], c[(q + 2) % 3]);
                        [r[0] - p[0], r[1] - p[1]]
                    });
                    // Twice the area; ∇λ_k is e_k turned a quarter and divided by it, and
                    // ∫_T ∇λ_a·∇λ_b = |T| (e_a·e_b) / (2|T|)² (the gradients are formed
                    // first, so that an S that overflows shows as infinite).
                    let two_area = e[2][0] * (-e[1][1]) + e[2][1] * e[1][0];
                    let inv = 1.0 / two_area;
                    let e = e.map(|q| [q[0] * inv, q[1] * inv]);
                    let scale = t.unwrap_or(0.0) * 0.5 * two_area;
                    for (b, &w) in tri.iter().enumerate() {
                        let Some(j) = dofs.of(w as usize) else {
                            continue;
                        };
                        let pos = position(cols, j);
                        if let Some(sb) = s_block.as_deref_mut() {
                            sb[range.start + pos] +=
                                scale * (e[a][0] * e[b][0] + e[a][1] * e[b][1]);
                        }
                        if let Some(lb) = l_block.as_deref_mut() {
                            lb[range.start + pos] += match h_const {
                                Some(hc) => hc * 0.5 * two_area * mass_fraction(a, b),
                                None => masses[k as usize][sym_index(a, b)],
                            };
                        }
                    }
                }
            }
        },
    );
    (s, l)
}

/// The blocks of [`ROW_BLOCK`] rows of `m`'s values, or as many `None` when there is no
/// matrix.
fn optional_row_chunks<'a>(
    pattern: &Pattern,
    m: Option<&'a mut Csr>,
    n: usize,
) -> Vec<Option<&'a mut [f64]>> {
    match m {
        Some(m) => row_chunks(pattern, &mut m.val, ROW_BLOCK)
            .into_iter()
            .map(|(_, block)| Some(block))
            .collect(),
        None => (0..n.div_ceil(ROW_BLOCK)).map(|_| None).collect(),
    }
}

/// `∫_T c λ_a` for the corners a = 0, 1, 2 of triangle `k`: `|T| c / 3` where c is constant
/// on the triangle's region (from the triangle's entry of `areas` ([`Mesh::areas`])), else
/// by quadrature with c evaluated once per point for the three corners.
#[inline]
fn element_loads(mesh: &Mesh, areas: &[f64], k: usize, c: &dyn Coefficient) -> [f64; 3] {
    let region = mesh.regions[k];
    match c.on_region(region) {
        Some(v) => [v * areas[k] / 3.0; 3],
        None => Element::of(mesh, k).weighted_load_row(c, region),
    }
}

/// The load-type vector `∫ c g_i` over unknowns (the paper's D for c = f, the lumped
/// foundation diagonal for c = h): element areas (`areas`, [`Mesh::areas`]) only where c
/// is constant on a region. The element integrals are computed once per triangle (c
/// evaluated once per quadrature point), then summed around each vertex.
pub fn assemble_load(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    areas: &[f64],
    c: &dyn Coefficient,
) -> Vec<f64> {
    sum_around_vertices(mesh, dofs, adj, &element_rows(mesh, areas, c))
}

/// [`element_loads`] of every triangle.
fn element_rows(mesh: &Mesh, areas: &[f64], c: &dyn Coefficient) -> Vec<[f64; 3]> {
    (0..mesh.n_triangles())
        .into_par_iter()
        .with_min_len(1024)
        .map(|k| element_loads(mesh, areas, k, c))
        .collect()
}

/// Per unknown, the sum of its corner's entry of `rows` over the triangles around it.
fn sum_around_vertices(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    rows: &[[f64; 3]],
) -> Vec<f64> {
    dofs.vertex
        .par_iter()
        .with_min_len(1024)
        .map(|&v| {
            adj.of(v as usize)
                .iter()
                .map(|&k| rows[k as usize][corner(mesh.triangles[k as usize], v)])
                .sum()
        })
        .collect()
}

/// `∫_Ω c` over the whole mesh (the total load for c = f), by the same element integrals
/// as [`assemble_load`] (`areas` is [`Mesh::areas`]).
pub fn integrate(mesh: &Mesh, areas: &[f64], c: &dyn Coefficient) -> f64 {
    integrate_with(mesh, areas, c, |k| element_loads(mesh, areas, k, c))
}

/// [`integrate`] with the element integrals of triangle k (where c varies on its region)
/// from `row(k)`.
fn integrate_with(
    mesh: &Mesh,
    areas: &[f64],
    c: &dyn Coefficient,
    row: impl Fn(usize) -> [f64; 3] + Sync + Send,
) -> f64 {
    let element = |k: usize| match c.on_region(mesh.regions[k]) {
        Some(v) => v * areas[k],
        None => row(k).into_iter().sum::<f64>(),
    };
    // Summed in fixed blocks: the same for any number of threads.
    crate::sparse::sum_blocks(mesh.n_triangles(), |r| r.map(element).sum::<f64>())
}

/// The one value of `c` on all the region tags `tags`, when it has one (assembly then
/// scales the nodal areas instead of integrating element by element).
pub fn uniform_value(c: &dyn Coefficient, tags: &[u32]) -> Option<f64> {
    let (&first, rest) = tags.split_first()?;
    let v = c.on_region(first)?;
    rest.iter()
        .all(|&t| c.on_region(t).is_some_and(|w| w.to_bits() == v.to_bits()))
        .then_some(v)
}

/// The load-type integrals of one mesh ([`assemble_load`], [`integrate`]), with a fast
/// path for a coefficient with one value c everywhere: `∫ c g_i = c ∫ g_i`, c times the
/// nodal areas (found once, on first use, and shared by every such coefficient: the load
/// f and the lumped foundation's h), and `∫_Ω c = c |Ω_n|`.
pub struct Loads<'a> {
    mesh: &'a Mesh,
    dofs: &'a DofMap,
    adj: &'a VertexTriangles,
    areas: &'a [f64],
    tags: Vec<u32>,
    nodal: std::sync::OnceLock<Vec<f64>>,
}

impl<'a> Loads<'a> {
    /// The integrals over `mesh` with the unknowns `dofs`, its vertex → triangles map
    /// `adj` and its triangle areas `areas` ([`Mesh::areas`]).
    pub fn new(
        mesh: &'a Mesh,
        dofs: &'a DofMap,
        adj: &'a VertexTriangles,
        areas: &'a [f64],
    ) -> Loads<'a> {
        Loads {
            mesh,
            dofs,
            adj,
            areas,
            tags: mesh.region_tags(),
            nodal: std::sync::OnceLock::new(),
        }
    }

    /// The one value of `c` on every region of the mesh, when it has one.
    pub fn uniform(&self, c: &dyn Coefficient) -> Option<f64> {
        uniform_value(c, &self.tags)
    }

    /// `∫ g_i` over the unknowns: the sum of `|T| / 3` over the triangles around vertex i.
    pub fn nodal_areas(&self) -> &[f64] {
        self.nodal.get_or_init(|| {
            self.dofs
                .vertex
                .par_iter()
                .with_min_len(1024)
                .map(|&v| {
                    self.adj
                        .of(v as usize)
                        .iter()
                        .map(|&k| self.areas[k as usize] / 3.0)
                        .sum()
                })
                .collect()
        })
    }

    /// `∫ c g_i` over the unknowns ([`assemble_load`]).
    pub fn vector(&self, c: &dyn Coefficient) -> Vec<f64> {
        match self.uniform(c) {
            Some(v) => self
                .nodal_areas()
                .par_iter()
                .with_min_len(4096)
                .map(|a| v * a)
                .collect(),
            None => assemble_load(self.mesh, self.dofs, self.adj, self.areas, c),
        }
    }

    /// [`Loads::vector`] and [`Loads::integral`] of one coefficient, from the same element
    /// integrals (computed once where c varies).
    pub fn vector_and_integral(&self, c: &dyn Coefficient) -> (Vec<f64>, f64) {
        if self.uniform(c).is_some() {
            return (self.vector(c), self.integral(c));
        }
        let rows = element_rows(self.mesh, self.areas, c);
        let vector = sum_around_vertices(self.mesh, self.dofs, self.adj, &rows);
        let integral = integrate_with(self.mesh, self.areas, c, |k| rows[k]);
        (vector, integral)
    }

    /// `∫_Ω c` over the whole mesh ([`integrate`]).
    pub fn integral(&self, c: &dyn Coefficient) -> f64 {
        match self.uniform(c) {
            Some(v) => {
                let a = self.areas;
                v * crate::sparse::sum_blocks(a.len(), |r| a[r].iter().sum::<f64>())
            }
            None => integrate(self.mesh, self.areas, c),
        }
    }
}

/// Fills a vector over unknowns: entry `i` sums `local(element, region, a)` over the
/// triangles around `a_i` (`a` the local index of `a_i`).
#[cfg(any(test, feature = "bench"))]
pub fn assemble_vector(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    local: &(dyn Fn(&Element, u32, usize) -> f64 + Sync),
) -> Vec<f64> {
    dofs.vertex
        .par_iter()
        .with_min_len(1024)
        .map(|&v| {
            let v = v as usize;
            adj.of(v)
                .iter()
                .map(|&k| {
                    let t = mesh.triangles[k as usize];
                    let a = corner(t, v as u32);
                    local(&Element::of(mesh, k as usize), mesh.regions[k as usize], a)
                })
                .sum()
        })
        .collect()
}

/// The lifting of boundary data (docs/theory.md#boundary-data): `(S_fix G)_i = t Σ_j ∫
/// ∇g_i·∇g_j G_j` over the fixed vertices j (those without an unknown), for every unknown
/// i. `g` holds G over all vertices (its values at unknowns are not used).
pub fn assemble_lift(
    mesh: &Mesh,
    dofs: &DofMap,
    adj: &VertexTriangles,
    t: f64,
    g: &[f64],
) -> Vec<f64> {
    dofs.vertex
        .par_iter()
        .with_min_len(1024)
        .map(|&v| {
            let v = v as usize;
            let mut sum = 0.0;
            for &k in adj.of(v) {
                let tri = mesh.triangles[k as usize];
                if tri.iter().all(|&w| !dofs.is_fixed(w as usize)) {
                    continue;
                }
                let e = Element::of(mesh, k as usize);
                let a = corner(tri, v as u32);
                for (b, &w) in tri.iter().enumerate() {
                    if dofs.is_fixed(w as usize) {
                        sum += t * e.stiffness(a, b) * g[w as usize];
                    }
                }
            }
            sum
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::FnCoefficient;
    use std::collections::BTreeMap;

    /// The unit square cut into a 2×2 grid of squares, each split into two triangles:
    /// one interior vertex at the centre.
    fn grid() -> Mesh {
        let mut p = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                p.push([i as f64 * 0.5, j as f64 * 0.5]);
            }
        }
        let mut t = Vec::new();
        for j in 0..2u32 {
            for i in 0..2u32 {
                let a = j * 3 + i;
                t.push([a, a + 1, a + 4]);
                t.push([a, a + 4, a + 3]);
            }
        }
        Mesh::new(p, t, vec![], BTreeMap::new()).unwrap()
    }

    #[test]
    fn rows_are_the_sorted_unknowns_of_the_patch() {
        use crate::mesh::generate;
        let sq = |a: f64, b: f64| vec![[a, a], [b, a], [b, b], [a, b]];
        let holed = generate::polygon(&generate::PolygonSpec {
            outer: sq(0.0, 1.0),
            holes: vec![sq(0.3, 0.5)],
            regions: Vec::new(),
            size: 0.04,
            min_angle: 25.0,
        })
        .unwrap();
        // A fan of 24 triangles round an interior centre (beyond the small buffers).
        let mut p = vec![[0.0, 0.0]];
        p.extend((0..24).map(|i| {
            let a = std::f64::consts::TAU * i as f64 / 24.0;
            [a.cos(), a.sin()]
        }));
        p.extend((0..24).map(|i| {
            let a = std::f64::consts::TAU * (i as f64 + 0.5) / 24.0;
            [2.0 * a.cos(), 2.0 * a.sin()]
        }));
        let mut t: Vec<[u32; 3]> = (0..24).map(|i| [0, 1 + i, 1 + (i + 1) % 24]).collect();
        t.extend((0..24).map(|i| [1 + i, 25 + i, 1 + (i + 1) % 24]));
        let wheel = Mesh::new(p, t, vec![], BTreeMap::new()).unwrap();
        let meshes = [
            grid(),
            generate::disk([0.0, 0.0], 1.0, 0.05).unwrap(),
            holed,
            wheel,
        ];
        for (m, free_edges) in meshes.iter().flat_map(|m| [(m, false), (m, true)]) {
            let adj = VertexTriangles::new(m);
            let boundary = m.boundary_vertices();
            // With free edges, the boundary vertices left of x = 0.3 are unknowns too.
            let fixed: Vec<bool> = (0..m.n_vertices())
                .map(|v| boundary[v] && !(free_edges && m.points[v][0] < 0.3))
                .collect();
            let dofs = DofMap::from_fixed(&fixed);
            let pattern = unknowns_pattern(m, &dofs, &adj, &boundary).unwrap();
            for (i, &v) in dofs.vertex.iter().enumerate() {
                let mut expected: Vec<u32> = adj
                    .of(v as usize)
                    .iter()
                    .flat_map(|&k| m.triangles[k as usize])
                    .filter_map(|w| dofs.of(w as usize))
                    .collect();
                expected.sort_unstable();
                expected.dedup();
                let row = &pattern.col[pattern.ptr(i)..pattern.ptr(i + 1)];
                assert_eq!(row, expected.as_slice(), "row {i}");
            }
        }
    }

    #[test]
    fn uniform_coefficients_scale_the_nodal_areas() {
        /// A region table: one value on region 2, another elsewhere.
        struct ByRegion(f64, f64);
        impl Coefficient for ByRegion {
            fn at(&self, _: Point, region: u32) -> f64 {
                if region == 2 {
                    self.1
                } else {
                    self.0
                }
            }
            fn on_region(&self, region: u32) -> Option<f64> {
                Some(self.at([0.0, 0.0], region))
            }
        }
        let mut m = crate::mesh::generate::disk([0.0, 0.0], 1.0, 0.05).unwrap();
        // Two regions: the triangles left of x = 0 are region 2.
        m.regions = (0..m.n_triangles())
            .map(|k| if m.corners(k)[0][0] < 0.0 { 2 } else { 0 })
            .collect();
        let adj = VertexTriangles::new(&m);
        let dofs = DofMap::new(&m);
        let areas = m.areas();
        let loads = Loads::new(&m, &dofs, &adj, &areas);
        let area: f64 = (0..m.n_triangles())
            .map(|k| crate::mesh::signed_area(&m.points, &m.triangles[k]))
            .sum();
        // One value everywhere, given as a number or as a table: c times the nodal areas.
        let same = ByRegion(2.5, 2.5);
        for c in [&2.5 as &dyn Coefficient, &same] {
            assert_eq!(loads.uniform(c), Some(2.5));
            let fast = loads.vector(c);
            let general = assemble_load(&m, &dofs, &adj, &areas, c);
            for (x, y) in fast.iter().zip(&general) {
                assert!((x - y).abs() <= 1e-15 * y.abs(), "{x} against {y}");
            }
            assert!((loads.integral(c) - 2.5 * area).abs() <= 1e-12 * area);
            let (a1, a2) = (loads.integral(c), integrate(&m, &areas, c));
            assert!((a1 - a2).abs() <= 1e-12 * area, "{a1} {a2} {area}");
        }
        // Two values, or a function of the point: element by element, as before.
        let two = ByRegion(1.0, 3.0);
        let x2 = FnCoefficient(|p: Point| p[0] * p[0]);
        for c in [&two as &dyn Coefficient, &x2] {
            assert_eq!(loads.uniform(c), None);
            assert_eq!(loads.vector(c), assemble_load(&m, &dofs, &adj, &areas, c));
            assert_eq!(loads.integral(c), integrate(&m, &areas, c));
        }
        // D and the total from one set of element integrals: the same numbers as apart.
        for c in [&2.5 as &dyn Coefficient, &same, &two, &x2] {
            assert_eq!(
                loads.vector_and_integral(c),
                (loads.vector(c), loads.integral(c))
            );
        }
        // The total of x² against the degree-5 rule applied to whole triangles (no split
        // into corners): equal to rounding.
        let direct: f64 = (0..m.n_triangles())
            .map(|k| {
                let e = Element::of(&m, k);
                e.area
                    * DEGREE5
                        .iter()
                        .map(|(l, w)| w * map(&e.corners, l)[0].powi(2))
                        .sum::<f64>()
            })
            .sum();
        assert!((loads.integral(&x2) - direct).abs() <= 1e-13 * direct);
        // ∫ x² over the unit disc is π/4 (to the order of the polygon's gap, h²).
        assert!((loads.integral(&x2) - std::f64::consts::FRAC_PI_4).abs() < 1e-2);
        // ∫ over region 2 (the left half disc) counts 3, over the rest 1: 2π in all.
        assert!((loads.integral(&two) - 2.0 * std::f64::consts::PI).abs() < 2e-2);
        assert_eq!(uniform_value(&2.5, &[]), None);
    }

    #[test]
    fn element_mass_matrix_integrates_a_linear_weight_exactly() {
        // c = Σ_k c_k λ_k (linear): ∫_T λ_a λ_b λ_k is |T|/10, |T|/30 or |T|/60 as a, b, k
        // are all equal, two equal or all different.
        let e = Element::new([[0.2, 0.1], [1.3, 0.4], [0.5, 1.7]]);
        let c = FnCoefficient(|p: Point| 1.0 + 2.0 * p[0] - 0.5 * p[1]);
        let ck = e.corners.map(|p| 1.0 + 2.0 * p[0] - 0.5 * p[1]);
        let m = e.weighted_mass_matrix(&c, 0);
        for a in 0..3 {
            for b in 0..3 {
                let exact: f64 = (0..3)
                    .map(|k| {
                        let same = (a == b) as usize + (b == k) as usize + (a == k) as usize;
                        let w = match same {
                            3 => 1.0 / 10.0,
                            1 => 1.0 / 30.0,
                            _ => 1.0 / 60.0,
                        };
                        ck[k] * w * e.area
                    })
                    .sum();
                let got = m[sym_index(a, b)];
                assert!(
                    (got - exact).abs() <= 1e-14 * exact.abs(),
                    "({a},{b}): {got} {exact}"
                );
                assert!((got - e.weighted_mass(&c, 0, a, b)).abs() <= 1e-15 * exact.abs());
                assert_eq!(sym_index(a, b), sym_index(b, a));
            }
        }
    }

    #[test]
    fn element_gradients_reproduce_linear_functions() {
        let e = Element::new([[0.2, 0.1], [1.3, 0.4], [0.5, 1.7]]);
        // u = 2x - 3y + 1 has nodal values u(c_k); Σ u_k ∇λ_k must be (2, -3).
        let u: Vec<f64> = e
            .corners
            .iter()
            .map(|c| 2.0 * c[0] - 3.0 * c[1] + 1.0)
            .collect();
        let g = [0, 1].map(|d| (0..3).map(|k| u[k] * e.grad[k][d]).sum::<f64>());
        assert!((g[0] - 2.0).abs() < 1e-13 && (g[1] + 3.0).abs() < 1e-13);
        // Rows of the local stiffness sum to zero (constants are in the kernel).
        for a in 0..3 {
            let s: f64 = (0..3).map(|b| e.stiffness(a, b)).sum();
            assert!(s.abs() < 1e-14);
        }
    }

    #[test]
    fn quadrature_and_closed_form_agree_for_constant_data() {
        let e = Element::new([[0.2, 0.1], [1.3, 0.4], [0.5, 1.7]]);
        let f = FnCoefficient(|_| 2.5);
        for a in 0..3 {
            assert!((e.weighted_load(&f, 0, a) - e.weighted_load(&2.5, 0, a)).abs() < 1e-14);
            for b in 0..3 {
                let q = e.weighted_mass(&f, 0, a, b);
                let c = e.weighted_mass(&2.5, 0, a, b);
                assert!((q - c).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn mass_quad_form_is_the_assembled_matrix_quadratic_form() {
        // 0 on the triangles left of x = 0 (skipped), varying on the others.
        struct RightOnly;
        impl Coefficient for RightOnly {
            fn at(&self, p: Point, region: u32) -> f64 {
                if region == 2 {
                    0.0
                } else {
                    1.0 + p[0] * p[0] + 0.5 * p[1]
                }
            }
            fn on_region(&self, region: u32) -> Option<f64> {
                (region == 2).then_some(0.0)
            }
        }
        let mut m = crate::mesh::generate::disk([0.0, 0.0], 1.0, 0.1).unwrap();
        m.regions = (0..m.n_triangles())
            .map(|k| if m.corners(k)[0][0] < 0.0 { 2 } else { 0 })
            .collect();
        let adj = VertexTriangles::new(&m);
        let dofs = DofMap::new(&m);
        let pat = Arc::new(unknowns_pattern(&m, &dofs, &adj, &m.boundary_vertices()).unwrap());
        let x: Vec<f64> = (0..dofs.len())
            .map(|i| (0.37 * i as f64).sin() + 0.2)
            .collect();
        for c in [&RightOnly as &dyn Coefficient, &3.5] {
            let l = assemble_mass(&m, &dofs, &adj, &pat, c);
            let (_, with_s) = assemble_stiffness_and_mass(&m, &dofs, &adj, &pat, 1.0, Some(c));
            assert_eq!(l.val, with_s.unwrap().val, "L alone is L assembled with S");
            let (a, b) = (l.quad_form(&x), mass_quad_form(&m, &dofs, c, &x));
            assert!(a > 0.0 && (a - b).abs() <= 1e-13 * a, "{a} against {b}");
        }
    }

    #[test]
    fn assembled_centre_row_is_the_five_point_stencil() {
        let m = grid();
        let dofs = DofMap::new(&m);
        let adj = VertexTriangles::new(&m);
        let pat = Arc::new(unknowns_pattern(&m, &dofs, &adj, &m.boundary_vertices()).unwrap());
        let (s, l) = assemble_stiffness_and_mass(&m, &dofs, &adj, &pat, 1.0, Some(&2.0));
        // ∫ h g² over the patch = h × 6 × (area/6) with area 1/8 per triangle.
        assert!((l.unwrap().get(0, 0) - 2.0 * 6.0 * (1.0 / 8.0) / 6.0).abs() < 1e-15);
        // P1 on right triangles gives the 5-point stencil: diagonal 4.
        assert_eq!(s.n(), 1);
        assert!((s.get(0, 0) - 4.0).abs() < 1e-14);
        // ∫ g = area of the patch / 3 = (6 triangles × 1/8) / 3.
        let d = assemble_vector(&m, &dofs, &adj, &|e, r, a| e.weighted_load(&1.0, r, a));
        assert!((d[0] - 0.25).abs() < 1e-15);
    }
}
