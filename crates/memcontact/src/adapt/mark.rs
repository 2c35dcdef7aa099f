//! Marking for adaptive refinement (docs/adaptivity.md#marking): Dörfler's bulk criterion
//! on error indicators, the triangles across the discrete free boundary, and unions of
//! marked sets. Marked sets are sorted triangle indices without repeats, the input of
//! [`super::bisect::bisect`]. Nothing here knows the solver: indicators and contact flags
//! are plain slices.

use crate::mesh::Mesh;
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
        items
            .par_chunks(1 << 13)
            .map(|c| c.iter().map(|x| x.0).sum::<f64>())
            .sum()
    }
}

/// Free-boundary marking (docs/theory.md#free-boundary): the triangles that have both a
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

/// At most `count` triangles of `set` that are not in `besides` (both sorted, without
/// repeats): the largest by area, the lower index first among equal areas. The adaptive
/// loop bounds the free-boundary marks by the Dörfler set's size with it, so the free
/// boundary is refined at most as fast as the bulk and the energy error keeps its rate.
/// Returns sorted indices.
pub fn largest(mesh: &Mesh, set: &[u32], besides: &[u32], count: usize) -> Vec<u32> {
    // `set` minus `besides`, one merge of the two sorted lists.
    let mut rest = Vec::with_capacity(set.len());
    let mut others = besides.iter().peekable();
    for &k in set {
        while others.next_if(|&&o| o < k).is_some() {}
        if others.peek() != Some(&&k) {
            rest.push(k);
        }
    }
    if rest.len() > count {
        // Each area computed once; the `count` first in the order (larger area, then lower
        // index), which is a total order: the same set as a full sort's first `count`.
        let mut keyed: Vec<(std::cmp::Reverse<OrdArea>, u32)> = rest
            .iter()
            .map(|&k| (std::cmp::Reverse(OrdArea(mesh.area(k as usize))), k))
            .collect();
        if count > 0 {
            keyed.select_nth_unstable(count - 1);
        }
        rest = keyed[..count].iter().map(|&(_, k)| k).collect();
        rest.sort_unstable();
    }
    rest
}

/// An area ordered by `f64::total_cmp`, for sorting keys.
#[derive(PartialEq)]
struct OrdArea(f64);
impl Eq for OrdArea {}
impl PartialOrd for OrdArea {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for OrdArea {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// The union of marked sets (any order, repeats allowed): sorted indices without repeats,
/// e.g. the Dörfler set and the free-boundary set of one step.
pub fn union(sets: &[&[u32]]) -> Vec<u32> {
    let mut all: Vec<u32> = sets.concat();
    all.par_sort_unstable();
    all.dedup();
    all
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{rectangle, Diagonal, RectangleSpec};

    /// Deterministic pseudo-random numbers in [0, 1) (xorshift64*).
    fn uniform(seed: u64, n: usize) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s ^= s >> 12;
                s ^= s << 25;
                s ^= s >> 27;
                (s.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
            })
            .collect()
    }

    /// Checks a Dörfler set: it reaches θ of the total, it holds the largest values (every
    /// value left out is at most every value taken, the lower index first among equals),
    /// and without its smallest member it falls short.
    fn check_dorfler(eta2: &[f64], theta: f64, marked: &[u32]) {
        assert!(marked.windows(2).all(|w| w[0] < w[1]), "sorted, no repeats");
        let total: f64 = eta2.iter().sum();
        let sum: f64 = marked.iter().map(|&k| eta2[k as usize]).sum();
        assert!(
            sum >= theta * total * (1.0 - 1e-12),
            "{sum} < {theta} · {total}"
        );
        let mut taken = vec![false; eta2.len()];
        for &k in marked {
            taken[k as usize] = true;
        }
        // The smallest member under the order (value down, index up): the last one taken.
        let last = marked
            .iter()
            .copied()
            .max_by(|&a, &b| {
                eta2[b as usize]
                    .total_cmp(&eta2[a as usize])
                    .then(a.cmp(&b))
            })
            .unwrap();
        let (lv, li) = (eta2[last as usize], last);
        for (k, &x) in eta2.iter().enumerate() {
            if !taken[k] {
                assert!(
                    x < lv || (x == lv && k as u32 > li),
                    "triangle {k} ({x}) left out, {li} ({lv}) taken"
                );
            }
        }
        assert!(
            sum - lv < theta * total * (1.0 + 1e-12),
            "not minimal: {} without {last}",
            sum - lv
        );
    }

    #[test]
    fn dorfler_marks_the_smallest_set_that_reaches_theta() {
        for (seed, n) in [(1, 1), (2, 7), (3, 100), (4, 1000), (5, 200_000)] {
            // Heavy tails and exact zeros, as estimators give.
            let eta2: Vec<f64> = uniform(seed, n)
                .iter()
                .enumerate()
                .map(|(k, &u)| if k % 11 == 3 { 0.0 } else { u.powi(6) })
                .collect();
            for theta in [0.05, 0.3, 0.5, 0.9, 0.999] {
                let marked = dorfler(&eta2, theta).unwrap();
                if eta2.iter().any(|&x| x > 0.0) {
                    check_dorfler(&eta2, theta, &marked);
                } else {
                    assert!(marked.is_empty());
                }
            }
        }
        // A single large indicator is enough for θ = 0.5.
        assert_eq!(dorfler(&[1.0, 10.0, 2.0, 3.0], 0.5).unwrap(), vec![1]);
        assert_eq!(dorfler(&[1.0, 10.0, 2.0, 3.0], 0.65).unwrap(), vec![1, 3]);
    }

    #[test]
    fn dorfler_with_ties_takes_lower_indices_first() {
        let eta2 = vec![2.0; 10];
        assert_eq!(dorfler(&eta2, 0.5).unwrap(), vec![0, 1, 2, 3, 4]);
        assert_eq!(dorfler(&eta2, 0.51).unwrap(), vec![0, 1, 2, 3, 4, 5]);
        let eta2 = [1.0, 3.0, 1.0, 1.0, 3.0, 1.0];
        assert_eq!(dorfler(&eta2, 0.7).unwrap(), vec![0, 1, 4]);
        check_dorfler(&eta2, 0.7, &[0, 1, 4]);
    }

    #[test]
    fn dorfler_theta_one_marks_every_nonzero_indicator() {
        // A tiny indicator that the total's rounding cannot see is still marked.
        let eta2 = [1.0, 0.0, 1e-30, 0.5, 0.0, 2.0];
        assert_eq!(dorfler(&eta2, 1.0).unwrap(), vec![0, 2, 3, 5]);
        let eta2: Vec<f64> = uniform(9, 5000)
            .iter()
            .map(|&u| (u - 0.3).max(0.0))
            .collect();
        let marked = dorfler(&eta2, 1.0).unwrap();
        let positive: Vec<u32> = (0..5000).filter(|&k| eta2[k as usize] > 0.0).collect();
        assert_eq!(marked, positive);
        assert!(dorfler(&[0.0; 4], 0.5).unwrap().is_empty());
        assert!(dorfler(&[], 0.5).unwrap().is_empty());
    }

    #[test]
    fn dorfler_refuses_bad_data() {
        for theta in [0.0, -0.1, 1.5, f64::NAN] {
            let e = dorfler(&[1.0], theta).unwrap_err().to_string();
            assert!(e.contains("θ must be in (0, 1]"), "{e}");
        }
        let e = dorfler(&[1.0, -2.0, f64::NAN], 0.5)
            .unwrap_err()
            .to_string();
        assert!(e.contains("triangle 1 is -2"), "{e}");
        let e = dorfler(&[1.0, 2.0, f64::INFINITY], 0.5)
            .unwrap_err()
            .to_string();
        assert!(e.contains("triangle 2 is inf"), "{e}");
        let e = dorfler(&[f64::MAX, f64::MAX], 0.5).unwrap_err().to_string();
        assert!(e.contains("overflows"), "{e}");
    }

    /// The grid [-1, 1]² with `n × n` cells cut alternately.
    fn grid(n: usize) -> Mesh {
        let spec = RectangleSpec {
            x0: -1.0,
            y0: -1.0,
            x1: 1.0,
            y1: 1.0,
            nx: n,
            ny: n,
            diagonal: Diagonal::Alternate,
        };
        rectangle(&spec).unwrap().levels.pop().unwrap()
    }

    #[test]
    fn free_boundary_marks_the_triangles_across_the_contact_circle() {
        let n = 40;
        let m = grid(n);
        let h = 2.0 / n as f64;
        let r = 0.5;
        let contact: Vec<bool> = m.points.iter().map(|p| p[0].hypot(p[1]) < r).collect();
        let ring0 = free_boundary(&m, &contact, 0).unwrap();
        // By definition, checked triangle by triangle.
        let crossing: Vec<u32> = (0..m.n_triangles() as u32)
            .filter(|&k| {
                let c = m.triangles[k as usize].map(|v| contact[v as usize]);
                c.contains(&true) && c.contains(&false)
            })
            .collect();
        assert_eq!(ring0, crossing);
        // They lie along the circle: within a cell diagonal of it, and about as many as
        // the circle crosses cells (2πr / h cells, two to four triangles each).
        for &k in &ring0 {
            for p in m.corners(k as usize) {
                assert!((p[0].hypot(p[1]) - r).abs() <= h * 2f64.sqrt(), "{k}");
            }
        }
        let cells = 2.0 * std::f64::consts::PI * r / h;
        assert!(
            ring0.len() as f64 > cells && (ring0.len() as f64) < 6.0 * cells,
            "{} triangles, {cells} cells",
            ring0.len()
        );
        // One ring: the triangles sharing a vertex with a crossing triangle.
        let ring1 = free_boundary(&m, &contact, 1).unwrap();
        let mut near = vec![false; m.n_vertices()];
        for &k in &ring0 {
            for v in m.triangles[k as usize] {
                near[v as usize] = true;
            }
        }
        let expected: Vec<u32> = (0..m.n_triangles() as u32)
            .filter(|&k| m.triangles[k as usize].iter().any(|&v| near[v as usize]))
            .collect();
        assert_eq!(ring1, expected);
        assert!(ring1.len() > 2 * ring0.len());
        let ring2 = free_boundary(&m, &contact, 2).unwrap();
        assert!(union(&[&ring1, &ring2]) == ring2 && ring2.len() > ring1.len());
        for &k in &ring2 {
            for p in m.corners(k as usize) {
                assert!((p[0].hypot(p[1]) - r).abs() <= 3.0 * h * 2f64.sqrt(), "{k}");
            }
        }
        // No contact, or contact everywhere: no free boundary.
        for flag in [false, true] {
            let all = vec![flag; m.n_vertices()];
            assert!(free_boundary(&m, &all, 3).unwrap().is_empty());
        }
        let e = free_boundary(&m, &contact[1..], 0).unwrap_err().to_string();
        assert!(e.contains("contact flags for"), "{e}");
    }

    #[test]
    fn largest_takes_the_largest_areas_outside_the_other_set() {
        // Interior vertices moved in the left half (areas vary); the right half keeps
        // equal areas, so ties are broken by index.
        let mut m = grid(12);
        let jitter = uniform(7, 2 * m.n_vertices());
        for (i, p) in m.points.iter_mut().enumerate() {
            if p[0] < 0.0 && p[0] > -1.0 && p[1].abs() < 1.0 {
                p[0] += 0.04 * (jitter[2 * i] - 0.5);
                p[1] += 0.04 * (jitter[2 * i + 1] - 0.5);
            }
        }
        let n = m.n_triangles() as u32;
        let pick = uniform(11, n as usize);
        let set: Vec<u32> = (0..n).filter(|&k| pick[k as usize] < 0.6).collect();
        let besides: Vec<u32> = (0..n).filter(|&k| k % 3 == 0).collect();
        // By definition: a full sort of the rest by (larger area, lower index).
        let naive = |count: usize| {
            let mut rest: Vec<u32> = set
                .iter()
                .copied()
                .filter(|k| !besides.contains(k))
                .collect();
            rest.sort_by(|&a, &b| {
                let (aa, ab) = (m.area(a as usize), m.area(b as usize));
                ab.total_cmp(&aa).then(a.cmp(&b))
            });
            rest.truncate(count);
            rest.sort_unstable();
            rest
        };
        let rest = naive(usize::MAX);
        assert!(rest.len() > 100);
        for count in [
            0,
            1,
            7,
            rest.len() / 2,
            rest.len() - 1,
            rest.len(),
            rest.len() + 5,
        ] {
            assert_eq!(largest(&m, &set, &besides, count), naive(count), "{count}");
        }
        assert_eq!(largest(&m, &set, &[], usize::MAX), set);
        assert!(largest(&m, &[], &besides, 10).is_empty());
    }

    #[test]
    fn union_is_sorted_without_repeats() {
        assert_eq!(
            union(&[&[5, 1, 3], &[3, 2], &[], &[1, 9]]),
            vec![1, 2, 3, 5, 9]
        );
        assert!(union(&[]).is_empty());
    }

    /// Timings for the report:
    /// `cargo test --release -p memcontact --lib mark::tests::timings -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn timings() {
        let n = 1_000_000;
        let eta2: Vec<f64> = uniform(3, n).iter().map(|&u| u.powi(4)).collect();
        for theta in [0.3, 0.5] {
            let t = std::time::Instant::now();
            let marked = dorfler(&eta2, theta).unwrap();
            let dt = t.elapsed();
            let mut sorted = eta2.clone();
            let t = std::time::Instant::now();
            sorted.sort_unstable_by(|a, b| b.total_cmp(a));
            eprintln!(
                "Dörfler θ = {theta} on {n} indicators: {} marked in {dt:?} (a full sort alone: {:?})",
                marked.len(),
                t.elapsed()
            );
        }
        let m = grid(708);
        let contact: Vec<bool> = m.points.iter().map(|p| p[0].hypot(p[1]) < 0.5).collect();
        let t = std::time::Instant::now();
        let set = free_boundary(&m, &contact, 2).unwrap();
        eprintln!(
            "free boundary, 2 rings, {} triangles: {} marked in {:?}",
            m.n_triangles(),
            set.len(),
            t.elapsed()
        );
    }
}
