//! Marking for adaptive refinement (SPEC §6): Dörfler's bulk criterion on error
//! indicators, the triangles across the discrete free boundary, and unions of marked
//! sets. Marked sets are sorted triangle indices without repeats, the input of
//! [`super::bisect::bisect`]. Nothing here knows the solver: indicators and contact flags
//! are plain slices.

use super::Mesh;
use crate::sparse::first_where;
use crate::{Error, Result};
use rayon::prelude::*;

/// Dörfler (bulk) marking: the smallest set `M` of triangles with
/// `Σ_{T∈M} η_T² ≥ θ Σ_T η_T²`, given the squared indicators `eta2` (η_T², one per
/// triangle) and `theta` in (0, 1]. The set holds the largest indicators; among equal ones
/// the lower index is taken first, so the result is the same on every run. Triangles with
/// η_T = 0 are never marked, and `theta = 1` marks exactly the triangles with η_T > 0
/// (not left to the rounding of the sums). Returns sorted indices.
///
/// Cost O(n) expected: the threshold is found by repeated partial selection
/// (`select_nth_unstable_by`) on halving candidate ranges, no full sort.
///
/// Errors: `theta` outside (0, 1], an indicator that is negative or not finite, a total
/// that overflows.
pub fn dorfler(eta2: &[f64], theta: f64) -> Result<Vec<u32>> {
    if !(theta > 0.0 && theta <= 1.0) {
        return Err(Error::Data(format!(
            "Dörfler marking: θ must be in (0, 1], got {theta}"
        )));
    }
    if let Some(i) = first_where(eta2, |x| !(x.is_finite() && x >= 0.0)) {
        return Err(Error::Data(format!(
            "Dörfler marking: indicator η² of triangle {i} is {}, not a finite value ≥ 0",
            eta2[i]
        )));
    }
    if eta2.len() > u32::MAX as usize {
        return Err(Error::Data(format!(
            "Dörfler marking: {} indicators, more than triangle indices hold",
            eta2.len()
        )));
    }
    // The candidates: positive indicators with their triangles.
    let mut items: Vec<(f64, u32)> = eta2
        .par_iter()
        .enumerate()
        .with_min_len(8192)
        .filter(|(_, &x)| x > 0.0)
        .map(|(k, &x)| (x, k as u32))
        .collect();
    if theta == 1.0 || items.len() <= 1 {
        return Ok(items.into_iter().map(|(_, k)| k).collect());
    }
    let total = sum(&items);
    if !total.is_finite() {
        return Err(Error::Data(format!(
            "Dörfler marking: the sum of the indicators overflows ({total})"
        )));
    }
    // Larger first, lower index first among equals: a total order, so the set is unique.
    let before = |x: &(f64, u32), y: &(f64, u32)| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1));
    // The answer is the top `k` for the smallest k with top-k sum ≥ θ·total. Invariant:
    // items[..start] are the top `start`, which fall short by `needed` > 0; the answer's
    // k is in (start, end]; items[start..end] are the candidates.
    let (mut start, mut end) = (0, items.len());
    let mut needed = theta * total;
    while end - start > 1 {
        let half = (end - start) / 2;
        let range = &mut items[start..end];
        range.select_nth_unstable_by(half, before);
        let s = sum(&range[..half]);
        if s >= needed {
            end = start + half;
        } else {
            needed -= s;
            start += half;
        }
    }
    let mut marked: Vec<u32> = items[..end].iter().map(|&(_, k)| k).collect();
    marked.par_sort_unstable();
    Ok(marked)
}

/// The sum of the values of `items` (blocks in parallel for long slices).
fn sum(items: &[(f64, u32)]) -> f64 {
    if items.len() < 1 << 15 {
        items.iter().map(|x| x.0).sum()
    } else {
        items.par_chunks(1 << 13).map(|c| c.iter().map(|x| x.0).sum::<f64>()).sum()
    }
}

/// Free-boundary marking (SPEC §6, "The free boundary"): the triangles that have both a
/// vertex in contact and one not (`contact[v]`, one flag per vertex), which hold the
/// discrete free boundary, plus `rings` rings of neighbours around them (a ring adds every
/// triangle that shares a vertex with the set; `rings = 0` gives the crossing triangles
/// alone). Energy estimators see the free boundary poorly; refining here locates it at the
/// local mesh size. Returns sorted indices; O(rings · triangles).
///
/// Errors: `contact` not of the mesh's vertex count.
pub fn free_boundary(mesh: &Mesh, contact: &[bool], rings: usize) -> Result<Vec<u32>> {
    if contact.len() != mesh.n_vertices() {
        return Err(Error::Data(format!(
            "free-boundary marking: {} contact flags for {} vertices",
            contact.len(),
            mesh.n_vertices()
        )));
    }
    let tri = &mesh.triangles;
    let mut set: Vec<bool> = tri
        .par_iter()
        .with_min_len(8192)
        .map(|t| {
            let c = t.map(|v| contact[v as usize]);
            (c[0] | c[1] | c[2]) & !(c[0] & c[1] & c[2])
        })
        .collect();
    for _ in 0..rings {
        let mut near = vec![false; mesh.n_vertices()];
        for (t, _) in tri.iter().zip(&set).filter(|(_, &s)| s) {
            for &v in t {
                near[v as usize] = true;
            }
        }
        set = tri
            .par_iter()
            .with_min_len(8192)
            .map(|t| near[t[0] as usize] | near[t[1] as usize] | near[t[2] as usize])
            .collect();
    }
    Ok(set
        .iter()
        .enumerate()
        .filter(|(_, &s)| s)
        .map(|(k, _)| k as u32)
        .collect())
}

/// The union of marked sets (any order, repeats allowed): sorted indices without repeats,
/// e.g. the Dörfler set and the free-boundary set of one step.
pub fn union(sets: &[&[u32]]) -> Vec<u32> {
    let mut all: Vec<u32> = sets.concat();
    all.par_sort_unstable();
    all.dedup();
    all
}
