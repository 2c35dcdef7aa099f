//! The levels of a linear multigrid: the unknowns of every level of a mesh hierarchy (or of
//! an aggregation hierarchy), the transfers between them and the Galerkin patterns of the
//! coarse operators, computed once.

use super::smoother::SweepRows;
use super::transfer::Transfer;
use crate::error::{Error, Result};
use crate::mesh::refine::{Hierarchy, Refinement};
use crate::mesh::{DofMap, Mesh};
use crate::sparse::{Csr, Pattern};
use std::sync::Arc;

/// Where the coarse levels of a multigrid come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// Nested meshes of uniform refinement (the exact P1 prolongation).
    Geometric,
    /// Aggregation of the matrix's unknowns (double pairwise aggregation, as in AGMG).
    Algebraic,
}

/// The static structure of a multigrid hierarchy over unknowns: per level its size and
/// operator pattern (and, for a geometric hierarchy, its dof map), and the prolongations.
/// Built once per hierarchy.
#[derive(Debug, Clone)]
pub struct Levels {
    /// Geometric or algebraic.
    pub kind: Kind,
    /// Unknowns of every level, coarsest first.
    pub sizes: Vec<usize>,
    /// Geometric hierarchies: the unknowns of every level's mesh but the finest (the
    /// model's own), coarsest first (levels without unknowns are left out). Empty for an
    /// algebraic hierarchy.
    pub dofs: Vec<DofMap>,
    /// Operator patterns, coarsest first; the finest is the pattern of S.
    pub patterns: Vec<Arc<Pattern>>,
    /// `transfers[k]` prolongates level `k` to level `k + 1`.
    pub transfers: Vec<Transfer>,
    /// What the smoother reads from every level's pattern, coarsest first.
    pub(crate) sweep_rows: Vec<SweepRows>,
    /// The number of aggregation transfers at the bottom of the hierarchy: levels
    /// `0..=aggregated` are solved by the K-cycle ([`super::cycle::Multigrid::k_cycle`]),
    /// the levels above by the V-cycle. All of them on an algebraic hierarchy, none on the
    /// levels of a mesh hierarchy whose coarsest mesh is small; on one whose coarsest mesh
    /// is large (an imported mesh refined uniformly), the aggregation levels below it
    /// ([`Levels::with_aggregation_below`]).
    pub aggregated: usize,
}

impl Levels {
    /// Checks that `hierarchy` ends with the mesh of the unknowns `finest` (whose operator
    /// pattern is `pattern`) and builds the transfers and Galerkin patterns. A hierarchy
    /// that does not fit is an error.
    pub fn new(hierarchy: &Hierarchy, finest: &DofMap, pattern: Arc<Pattern>) -> Result<Levels> {
        let counts = hierarchy.vertex_counts();
        Levels::from_relations(
            &hierarchy.refinements,
            &counts,
            hierarchy.levels.last(),
            finest,
            pattern,
        )
    }

    /// [`Levels::new`] from what it reads of a hierarchy: the refinement relations, the
    /// vertex count of every level (coarsest first) and the finest mesh (`None` for a
    /// hierarchy without levels, an error). The coarser meshes themselves are not needed.
    pub fn from_relations(
        refinements: &[Refinement],
        vertex_counts: &[usize],
        last: Option<&Mesh>,
        finest: &DofMap,
        pattern: Arc<Pattern>,
    ) -> Result<Levels> {
        let nl = vertex_counts.len();
        let last = match last {
            Some(m) if nl > 0 && refinements.len() + 1 == nl => m,
            _ => {
                return Err(Error::Mesh(format!(
                    "a hierarchy of {nl} levels needs {} refinement relations, it has {}",
                    nl.saturating_sub(1),
                    refinements.len()
                )))
            }
        };
        if last.n_vertices() != finest.n_vertices() || pattern.n() != finest.len() {
            return Err(Error::Mesh(format!(
                "the finest level of the hierarchy has {} vertices, but the model was \
                 assembled on a mesh of {} vertices: the hierarchy must end with the model's \
                 mesh",
                last.n_vertices(),
                finest.n_vertices()
            )));
        }
        check_pattern(last, finest, &pattern)?;
        // The unknowns of the coarser levels, from the finer ones: a coarse vertex is
        // interior exactly when the fine vertex sitting on it is (nested meshes). The
        // finest level's unknowns are the model's own: no copy is kept.
        let mut dofs: Vec<DofMap> = Vec::with_capacity(nl - 1);
        for k in (0..nl - 1).rev() {
            let coarse = coarse_dofs(
                &refinements[k],
                vertex_counts[k],
                dofs.last().unwrap_or(finest),
            )?;
            dofs.push(coarse);
        }
        dofs.reverse();
        let level = |k: usize| dofs.get(k).unwrap_or(finest);
        // Levels without unknowns cannot carry a correction: start above them.
        let first = (0..nl).position(|k| !level(k).is_empty()).unwrap_or(nl - 1);
        let mut transfers = Vec::with_capacity(nl - 1 - first);
        for (k, refinement) in refinements.iter().enumerate().skip(first) {
            transfers.push(Transfer::new(refinement, level(k), level(k + 1))?);
        }
        let sizes = (first..nl).map(|k| level(k).len()).collect();
        let dofs: Vec<DofMap> = dofs.into_iter().skip(first).collect();
        // Coarsest last: each transfer reads its columns from the pattern of its fine
        // level, known once the finer levels' Galerkin patterns are.
        let mut patterns = vec![pattern];
        for t in transfers.iter_mut().rev() {
            let fine = patterns.last().expect("the finest pattern");
            *t = std::mem::replace(t, Transfer::aggregation(&[], 0)).with_columns_from(fine);
            let coarse = t.galerkin_pattern(fine);
            patterns.push(Arc::new(coarse));
        }
        patterns.reverse();
        Ok(Levels {
            kind: Kind::Geometric,
            aggregated: 0,
            sizes,
            dofs,
            sweep_rows: patterns.iter().map(|p| SweepRows::of(p)).collect(),
            patterns,
            transfers,
        })
    }

    /// These mesh levels with a finer level on top, the next step of an adaptive loop:
    /// `refinement` leads from the current top level, whose unknowns were `top` (the
    /// previous model's), to the mesh `last` with unknowns `finest` and operator pattern
    /// `pattern`. Only the new level's transfer, Galerkin pattern and sweep data are
    /// computed; the levels below are kept, the same as [`Levels::from_relations`] would
    /// build them again. `None` when they would not be the same (levels with aggregation
    /// below, or a top level whose unknowns or pattern differ from the ones the refinement
    /// implies): the caller then builds all levels.
    pub(crate) fn extended(
        mut self,
        top: &DofMap,
        refinement: &Refinement,
        last: &Mesh,
        finest: &DofMap,
        pattern: Arc<Pattern>,
    ) -> Result<Option<Levels>> {
        if self.kind != Kind::Geometric || self.aggregated > 0 {
            return Ok(None);
        }
        if last.n_vertices() != finest.n_vertices() || pattern.n() != finest.len() {
            return Err(Error::Mesh(format!(
                "the new finest level has {} vertices, but the model was assembled on a mesh \
                 of {} vertices",
                last.n_vertices(),
                finest.n_vertices()
            )));
        }
        check_pattern(last, finest, &pattern)?;
        let below = self.patterns.len() - 1;
        let coarse = coarse_dofs(refinement, top.n_vertices(), finest)?;
        if coarse.vertex != top.vertex || coarse.len() != self.sizes[below] {
            return Ok(None);
        }
        let transfer = Transfer::new(refinement, &coarse, finest)?.with_columns_from(&pattern);
        if transfer.galerkin_pattern(&pattern) != *self.patterns[below] {
            return Ok(None);
        }
        self.sizes.push(finest.len());
        self.dofs.push(coarse);
        self.transfers.push(transfer);
        self.sweep_rows.push(SweepRows::of(&pattern));
        self.patterns.push(pattern);
        Ok(Some(self))
    }

    /// An algebraic hierarchy for the operator `a` (the finest level; its pattern is the
    /// finest pattern) by double pairwise aggregation, down to about `coarsest` unknowns.
    pub fn algebraic(a: &Csr, coarsest: usize) -> Levels {
        let (transfers, sizes, patterns) = super::aggregation::hierarchy(a, coarsest);
        Levels {
            kind: Kind::Algebraic,
            aggregated: sizes.len() - 1,
            sizes,
            dofs: Vec::new(),
            sweep_rows: patterns.iter().map(|p| SweepRows::of(p)).collect(),
            patterns,
            transfers,
        }
    }

    /// These mesh levels with aggregation levels below the coarsest mesh when it has more
    /// than [`super::aggregation::COARSEST`] unknowns (an imported mesh refined uniformly),
    /// so that the coarsest level is not factorised whole: its Galerkin operator, from
    /// the finest level's operator `a()` (on the finest pattern, formed only then) through
    /// the mesh levels, is aggregated as an algebraic hierarchy is. Otherwise unchanged.
    pub fn with_aggregation_below(self, a: impl FnOnce() -> Csr) -> Levels {
        use super::aggregation::{hierarchy, COARSEST};
        if self.kind != Kind::Geometric || self.aggregated > 0 || self.sizes[0] <= COARSEST {
            return self;
        }
        // The operator of every mesh level, finest to coarsest; the coarsest is kept.
        let a = a();
        let mut coarse: Option<Csr> = None;
        for (k, t) in self.transfers.iter().enumerate().rev() {
            let mut c = Csr::zeros(self.patterns[k].clone());
            t.galerkin_values(coarse.as_ref().unwrap_or(&a), &mut c, None);
            coarse = Some(c);
        }
        let Some(bottom) = coarse else { return self };
        let (below, sizes, patterns) = hierarchy(&bottom, COARSEST);
        if below.is_empty() {
            return self;
        }
        let m = below.len();
        // The aggregation levels' list without its finest (the coarsest mesh level, which
        // the mesh levels have), then the mesh levels'.
        fn join<T>(mut low: Vec<T>, high: Vec<T>) -> Vec<T> {
            low.pop();
            low.extend(high);
            low
        }
        let sweep_below = patterns[..m].iter().map(|p| SweepRows::of(p)).collect();
        Levels {
            kind: Kind::Geometric,
            aggregated: m,
            sizes: join(sizes, self.sizes),
            dofs: self.dofs,
            patterns: join(patterns, self.patterns),
            transfers: [below, self.transfers].concat(),
            sweep_rows: [sweep_below, self.sweep_rows].concat(),
        }
    }

    /// The unknowns of mesh level `k` (not an aggregation level, nor the finest).
    pub fn dofs_of(&self, k: usize) -> &DofMap {
        &self.dofs[k - self.aggregated]
    }

    /// Number of levels.
    pub fn len(&self) -> usize {
        self.sizes.len()
    }

    /// `true` when there is no level (never, after [`Levels::new`]).
    pub fn is_empty(&self) -> bool {
        self.sizes.is_empty()
    }

    /// Number of unknowns of level `k`.
    pub fn n(&self, k: usize) -> usize {
        self.sizes[k]
    }
}

/// The unknowns of a coarse level of `n_vertices` vertices, given those of the level
/// refined from it: coarse vertex `c` is interior iff the fine vertex on it (parents
/// `[c, c]`) is. A coarse vertex without such a fine vertex is an error.
fn coarse_dofs(refinement: &Refinement, n_vertices: usize, fine: &DofMap) -> Result<DofMap> {
    if refinement.parents.len() != fine.n_vertices() {
        return Err(Error::Mesh(format!(
            "the refinement relation names parents for {} vertices, but the finer level has \
             {} vertices",
            refinement.parents.len(),
            fine.n_vertices()
        )));
    }
    use rayon::prelude::*;
    use std::sync::atomic::{AtomicU8, Ordering::Relaxed};
    // Per coarse vertex: 0 while no fine vertex sits on it, then FIXED or INTERIOR. A
    // refinement puts one fine vertex on each coarse one; should a broken one put two, the
    // larger state is kept, whatever the order the threads write in.
    const FIXED: u8 = 1;
    const INTERIOR: u8 = 2;
    let state: Vec<AtomicU8> = (0..n_vertices)
        .into_par_iter()
        .with_min_len(4096)
        .map(|_| AtomicU8::new(0))
        .collect();
    let bad = refinement
        .parents
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .map(|(v, &[a, b])| {
            if a as usize >= n_vertices || b as usize >= n_vertices {
                return Some((v, a, b));
            }
            if a == b {
                let on = if !fine.is_fixed(v) { INTERIOR } else { FIXED };
                state[a as usize].fetch_max(on, Relaxed);
            }
            None
        })
        .find_first(Option::is_some)
        .flatten();
    if let Some((v, a, b)) = bad {
        return Err(Error::Mesh(format!(
            "vertex {v} of the finer level has parent vertices ({a}, {b}), but the coarser \
             level has only {n_vertices} vertices"
        )));
    }
    let state: Vec<u8> = state.into_par_iter().map(AtomicU8::into_inner).collect();
    if let Some(c) = crate::sparse::first_where(&state, |x| x == 0) {
        return Err(Error::Mesh(format!(
            "the refinement relation keeps no vertex on vertex {c} of the coarser level"
        )));
    }
    let fixed: Vec<bool> = state.par_iter().map(|&x| x == FIXED).collect();
    Ok(DofMap::from_fixed(&fixed))
}

/// Checks that the operator pattern couples the unknowns along the edges of the triangles
/// of `mesh` (every triangle of small meshes, every 16th of large ones): a cheap test that
/// the model was assembled on this mesh.
fn check_pattern(mesh: &Mesh, dofs: &DofMap, pattern: &Pattern) -> Result<()> {
    use rayon::prelude::*;
    let step = if mesh.n_triangles() > 100_000 { 16 } else { 1 };
    let bad = mesh
        .triangles
        .par_iter()
        .enumerate()
        .with_min_len(4096)
        .filter(|(k, _)| k % step == 0)
        .find_any(|(_, t)| {
            t.iter().any(|&a| {
                t.iter()
                    .any(|&b| match (dofs.of(a as usize), dofs.of(b as usize)) {
                        (Some(i), Some(j)) => pattern.find(i as usize, j as usize).is_none(),
                        _ => false,
                    })
            })
        });
    match bad {
        Some((k, _)) => Err(Error::Mesh(format!(
            "triangle {k} of the finest level of the hierarchy couples unknowns that the \
             model's matrices do not: the hierarchy must end with the mesh the model was \
             assembled on"
        ))),
        None => Ok(()),
    }
}
