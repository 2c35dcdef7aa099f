//! Multigrid checks on small structured squares: the linear V-cycle against Cholesky, TNNMG
//! against the active-set method, monotone energy, iteration counts under refinement.

use super::levels::*;
use super::smoother::*;
use super::tnnmg::*;
use super::transfer::Transfer;
use super::*;
use crate::field::FnCoefficient;
use crate::mesh::refine::Hierarchy;
use crate::mesh::refine::Refinement;
use crate::mesh::test_square as square;
use crate::mesh::{DofMap, Mesh};
use crate::model::{BodyStiffness, Foundation, ProblemData, Sampling};
use crate::model::{FoundationMatrix, Model};
use crate::solve::{active_set, Silent};
use crate::solve::{Method, Settings};
use crate::sparse::Csr;
use crate::sparse::{norm_inf, Cholesky};

/// The unit square on an `n0 2^k` grid for `k = 0..levels`, "right" diagonals, with the
/// refinement relations of uniform refinement (every square of the coarse grid into four).
pub(crate) fn square_hierarchy(n0: usize, levels: usize) -> Hierarchy {
    let meshes: Vec<Mesh> = (0..levels).map(|k| square(n0 << k)).collect();
    let refinements = (1..levels)
        .map(|k| {
            let n = n0 << k;
            let nc = n / 2;
            let (w, wc) = (n + 1, nc + 1);
            let mut parents = vec![[0u32; 2]; w * w];
            for j in 0..=n {
                for i in 0..=n {
                    let c = |a: usize, b: usize| (b * wc + a) as u32;
                    parents[j * w + i] = match (i % 2, j % 2) {
                        (0, 0) => [c(i / 2, j / 2), c(i / 2, j / 2)],
                        (1, 0) => [c(i / 2, j / 2), c(i / 2 + 1, j / 2)],
                        (0, 1) => [c(i / 2, j / 2), c(i / 2, j / 2 + 1)],
                        _ => [c(i / 2, j / 2), c(i / 2 + 1, j / 2 + 1)],
                    };
                }
            }
            Refinement { parents }
        })
        .collect();
    Hierarchy {
        levels: meshes,
        refinements,
    }
}

/// The benchmark's data (t = 1, f = 20, h = 1000, φ = 0.5 + 0.1 sin 2πx cos 2πy) on `mesh`;
/// `h = None` is the rigid obstacle.
pub(crate) fn bench_model(mesh: &Mesh, h: Option<f64>, foundation: Foundation) -> Model {
    use std::f64::consts::PI;
    let phi =
        FnCoefficient(|p: [f64; 2]| 0.5 + 0.1 * (2.0 * PI * p[0]).sin() * (2.0 * PI * p[1]).cos());
    let hv = h.unwrap_or(0.0);
    Model::assemble(
        mesh,
        &ProblemData {
            tension: 1.0,
            load: &20.0,
            shape: &phi,
            stiffness: match h {
                Some(_) => BodyStiffness::Elastic(&hv),
                None => BodyStiffness::Rigid,
            },
            foundation,
            sampling: Sampling::Nodal,
        },
    )
    .unwrap()
}

fn settings(tol: f64) -> Settings {
    Settings {
        method: Method::Multigrid,
        tolerance: tol,
        ..Settings::default()
    }
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let num = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    num / norm_inf(b).max(1e-300)
}

#[test]
fn prolongation_reproduces_linear_functions() {
    let h = square_hierarchy(4, 2);
    let coarse = DofMap::new(&h.levels[0]);
    let fine = DofMap::new(&h.levels[1]);
    let t = Transfer::new(&h.refinements[0], &coarse, &fine).unwrap();
    // A function vanishing on the boundary that is linear on every coarse triangle.
    let xc: Vec<f64> = coarse
        .vertex
        .iter()
        .map(|&v| {
            let p = h.levels[0].points[v as usize];
            (p[0] * 3.0).sin() + p[1]
        })
        .collect();
    let mut xf = vec![0.0; fine.len()];
    t.prolongate(&xc, &mut xf);
    let all_c = coarse.to_vertices(&xc, 0.0);
    let all_f = h.refinements[0].prolongate(&all_c);
    assert_eq!(fine.to_unknowns(&all_f), xf);
    // Pᵀ is the transpose of P.
    let rf: Vec<f64> = (0..fine.len()).map(|i| (i as f64).cos()).collect();
    let mut rc = vec![0.0; coarse.len()];
    t.restrict(&rf, &mut rc);
    let lhs: f64 = rc.iter().zip(&xc).map(|(a, b)| a * b).sum();
    let rhs: f64 = rf.iter().zip(&xf).map(|(a, b)| a * b).sum();
    assert!((lhs - rhs).abs() < 1e-12 * lhs.abs().max(1.0));
}

#[test]
fn galerkin_operator_is_the_coarse_stiffness() {
    // For nested P1 spaces, PᵀSP is the stiffness matrix of the coarse mesh.
    let h = square_hierarchy(4, 3);
    let fine = bench_model(h.finest(), Some(1000.0), Foundation::Consistent);
    let levels = Levels::new(&h, &fine.dofs, fine.s.pattern.clone()).unwrap();
    let mid = bench_model(&h.levels[1], Some(1000.0), Foundation::Consistent);
    let mut c = Csr::zeros(levels.patterns[1].clone());
    levels.transfers[1].galerkin_values(&fine.s, &mut c, None);
    for i in 0..mid.n() {
        for j in 0..mid.n() {
            assert!((c.get(i, j) - mid.s.get(i, j)).abs() < 1e-12, "({i}, {j})");
        }
    }
    // The same for the consistent L, and the lumped l (l_i = ∫ h g_i,
    // docs/theory.md#lumped).
    let FoundationMatrix::Consistent(lf) = &fine.l else {
        panic!()
    };
    let FoundationMatrix::Consistent(lm) = &mid.l else {
        panic!()
    };
    levels.transfers[1].galerkin_values(lf, &mut c, None);
    for i in 0..mid.n() {
        for j in 0..mid.n() {
            assert!((c.get(i, j) - lm.get(i, j)).abs() < 1e-12);
        }
    }
}

#[test]
fn poisson_v_cycles_converge_independently_of_the_mesh() {
    let mut counts = Vec::new();
    for levels in 2..=5 {
        let h = square_hierarchy(4, levels);
        let model = bench_model(h.finest(), Some(0.0), Foundation::Lumped);
        let out = poisson_solve(&model.s, &model.d, &h, &model.dofs, 1e-10, None, 50).unwrap();
        assert!(out.relative_residual <= 1e-10, "{}", out.relative_residual);
        let mut exact = model.d.clone();
        Cholesky::new(&model.s).unwrap().solve_in_place(&mut exact);
        assert!(
            rel_diff(&out.x, &exact) < 1e-8,
            "{}",
            rel_diff(&out.x, &exact)
        );
        counts.push(out.cycles);
    }
    // Below the rounding floor: an error, after a few stagnating cycles, not a hang.
    let h = square_hierarchy(4, 3);
    let model = bench_model(h.finest(), Some(0.0), Foundation::Lumped);
    let e = poisson_solve(&model.s, &model.d, &h, &model.dofs, 1e-30, None, 10_000).unwrap_err();
    assert!(e.to_string().contains("V-cycles"), "{e}");
    // The asymptotic rate of a V(1,1)-cycle is about 0.27 in the maximum norm.
    let (lo, hi) = (counts.iter().min().unwrap(), counts.iter().max().unwrap());
    assert!(hi - lo <= 4 && *hi <= 24, "{counts:?}");
}

fn agree(h: Option<f64>, foundation: Foundation) {
    let hier = square_hierarchy(4, 4); // 32 × 32
    let model = bench_model(hier.finest(), h, foundation);
    let reference = active_set::solve(&model, &settings(1e-11), None, &mut Silent).unwrap();
    let mg = crate::solve::solve(&model, Some(&hier), &settings(1e-11), &mut Silent).unwrap();
    assert_eq!(mg.method, Method::Multigrid);
    let d = rel_diff(&mg.u, &reference.u);
    assert!(d < 1e-8, "{foundation:?} {h:?}: {d}");
    assert!(mg.certificate.kkt() <= 1e-11);
    // J decreases monotonically (to rounding).
    for w in mg.history.windows(2) {
        assert!(
            w[1].energy <= w[0].energy + 1e-13 * w[0].energy.abs(),
            "{} > {}",
            w[1].energy,
            w[0].energy
        );
    }
    let states = model.states(&mg.u);
    assert!(states.contains(&1) || h.is_none());
}

#[test]
fn tnnmg_agrees_with_active_set_consistent() {
    agree(Some(1000.0), Foundation::Consistent);
}

#[test]
fn tnnmg_agrees_with_active_set_lumped() {
    agree(Some(1000.0), Foundation::Lumped);
}

#[test]
fn tnnmg_agrees_with_active_set_rigid() {
    agree(None, Foundation::Consistent);
}

#[test]
fn tnnmg_without_nested_iteration_converges_from_zero() {
    let hier = square_hierarchy(4, 4);
    for (h, f) in [
        (Some(1000.0), Foundation::Consistent),
        (Some(1000.0), Foundation::Lumped),
        (None, Foundation::Lumped),
    ] {
        let model = bench_model(hier.finest(), h, f);
        let opts = TnnmgOptions {
            nested: false,
            ..TnnmgOptions::default()
        };
        let (sol, rep) = solve_with(
            &model,
            Coarsening::Geometric(&hier),
            &settings(1e-10),
            &opts,
            None,
            &mut Silent,
        )
        .unwrap();
        assert!(sol.certificate.kkt() <= 1e-10, "{f:?} {h:?}");
        assert_eq!(rep.levels.len(), 1);
        assert!(sol.iterations < 40, "{f:?} {h:?}: {}", sol.iterations);
        for w in sol.history.windows(2) {
            assert!(w[1].energy <= w[0].energy + 1e-13 * w[0].energy.abs());
        }
    }
}

#[test]
fn iteration_counts_do_not_grow_under_refinement() {
    for (h, f) in [
        (Some(1000.0), Foundation::Consistent),
        (Some(1000.0), Foundation::Lumped),
        (None, Foundation::Lumped),
    ] {
        let mut counts = Vec::new();
        for levels in 4..=7 {
            // 16 × 16 ... 128 × 128 from a 2 × 2 coarse grid.
            let hier = square_hierarchy(2, levels);
            let model = bench_model(hier.finest(), h, f);
            let sol = solve(
                &model,
                Coarsening::Geometric(&hier),
                &settings(1e-10),
                None,
                &mut Silent,
            )
            .unwrap();
            counts.push(sol.iterations);
        }
        // The certificate is relative to the forces of the iterate (O(h²) per vertex), so
        // the first iterations after the prolongation of the coarse solution take a level
        // or two longer to settle the contact set on fine meshes; the count stays bounded.
        let (lo, hi) = (counts.iter().min().unwrap(), counts.iter().max().unwrap());
        assert!(hi - lo <= 4, "{f:?} {h:?}: {counts:?}");
    }
}

#[test]
fn a_hierarchy_of_another_mesh_is_an_error() {
    let hier = square_hierarchy(4, 3);
    let model = bench_model(hier.finest(), Some(1000.0), Foundation::Lumped);
    let error = |h: &Hierarchy| {
        let e = solve(
            &model,
            Coarsening::Geometric(h),
            &settings(1e-10),
            None,
            &mut Silent,
        );
        e.expect_err("a hierarchy that does not fit is refused")
            .to_string()
    };
    let e = error(&square_hierarchy(3, 3));
    assert!(e.contains("finest level"), "{e}");
    // A hierarchy with a broken refinement relation.
    let mut broken = hier.clone();
    broken.refinements[1].parents.pop();
    let e = error(&broken);
    assert!(e.contains("refinement"), "{e}");
    let mut broken = hier.clone();
    broken.refinements[0].parents[3] = [10_000, 0];
    let e = error(&broken);
    assert!(e.contains("parent"), "{e}");
    // A coarse vertex with no fine vertex on it.
    let mut broken = hier.clone();
    let parents = &mut broken.refinements[1].parents;
    let v = parents.iter().rposition(|p| p[0] == p[1]).unwrap();
    let c = parents[v][0];
    parents[v] = [c, if c == 0 { 1 } else { 0 }];
    let e = error(&broken);
    assert!(
        e.contains(&format!(
            "keeps no vertex on vertex {c} of the coarser level"
        )),
        "{e}"
    );
    let mut broken = hier;
    broken.refinements.pop();
    error(&broken);
}

#[test]
fn one_level_is_a_direct_truncated_newton() {
    let hier = square_hierarchy(16, 1);
    let model = bench_model(hier.finest(), Some(1000.0), Foundation::Consistent);
    let sol = solve(
        &model,
        Coarsening::Geometric(&hier),
        &settings(1e-11),
        None,
        &mut Silent,
    )
    .unwrap();
    let reference = active_set::solve(&model, &settings(1e-11), None, &mut Silent).unwrap();
    assert!(rel_diff(&sol.u, &reference.u) < 1e-8);
}

#[test]
fn block_gauss_seidel_keeps_the_rate_and_ignores_the_thread_count() {
    // 255² > GS_BLOCK unknowns: the fine level is smoothed block-parallel.
    let h = square_hierarchy(4, 7);
    let model = bench_model(h.finest(), Some(0.0), Foundation::Lumped);
    assert!(model.n() > GS_BLOCK);
    let run = |threads: usize| {
        crate::parallel::on_threads(threads, || {
            poisson_solve(&model.s, &model.d, &h, &model.dofs, 1e-10, None, 50).unwrap()
        })
    };
    let one = run(1);
    let two = run(3);
    assert_eq!(one.x, two.x);
    assert!(one.cycles <= 24, "{}", one.cycles);
}

#[test]
fn sweep_rows_are_the_seams_and_the_diagonal_offsets() {
    // A level of one smoothing block and one of several; then a pattern with an empty row
    // (an unknown no fine unknown restricts to), whose offset is 0.
    for levels in [5, 7] {
        let h = square_hierarchy(4, levels);
        let model = bench_model(h.finest(), Some(0.0), Foundation::Lumped);
        let p = &model.s.pattern;
        let rows = SweepRows::of(p);
        let n = p.n();
        let block = gs_block(n);
        let cols = |i: usize| &p.col[p.ptr(i)..p.ptr(i + 1)];
        for i in 0..n {
            let before = cols(i).iter().filter(|&&c| (c as usize) < i).count();
            assert_eq!(rows.diag[i] as usize, before, "row {i}");
            assert_eq!(rows.diag_of(i, cols(i)), before, "row {i}");
            assert_eq!(
                cols(i)[before] as usize,
                i,
                "row {i}: the diagonal is stored"
            );
        }
        let seams: Vec<u32> = (0..n)
            .filter(|&i| n > block && cols(i).iter().any(|&c| c as usize / block != i / block))
            .map(|i| i as u32)
            .collect();
        assert_eq!(rows.seams, seams);
        assert_eq!(seams.is_empty(), levels == 5);
    }
    let empty = crate::sparse::Pattern {
        row_ptr: vec![0, 1, 1, 2],
        col: vec![0, 2],
    };
    let rows = SweepRows::of(&empty);
    assert_eq!(rows.diag, vec![0, 0, 0]);
    assert!(rows.seams.is_empty());
    // Rows with more columns before the diagonal than a byte counts: the offset is found
    // in the row (a symmetric pattern: rows 0 and m − 1 coupled to all, the others to
    // those two).
    let m = 600;
    let mut row_ptr = vec![0];
    let mut col: Vec<u32> = Vec::new();
    for i in 0..m {
        let cols: Vec<u32> = if i == 0 || i == m - 1 {
            (0..m as u32).collect()
        } else {
            vec![0, i as u32, m as u32 - 1]
        };
        col.extend(&cols);
        row_ptr.push(col.len() as u32);
    }
    let star = crate::sparse::Pattern { row_ptr, col };
    let rows = SweepRows::of(&star);
    assert_eq!(rows.diag[m - 1], SweepRows::MANY);
    for i in 0..m {
        let cols = &star.col[star.ptr(i)..star.ptr(i + 1)];
        let expected = match i {
            0 => 0,
            i if i == m - 1 => i,
            _ => 1,
        };
        assert_eq!(rows.diag_of(i, cols), expected);
    }
    // Both fused sweeps on the star's graph Laplacian plus the identity (SPD), through
    // the counted offsets: the plain sweep with its residual, and with its product.
    let star = std::sync::Arc::new(star);
    let mut a = Csr::zeros(star.clone());
    for i in 0..m {
        for k in star.ptr(i)..star.ptr(i + 1) {
            let j = star.col[k] as usize;
            a.val[k] = if i == j {
                (star.ptr(i + 1) - star.ptr(i)) as f64
            } else {
                -1.0
            };
        }
    }
    let mut inv = vec![0.0; m];
    fill_inv_diag(&a, &mut inv);
    let b: Vec<f64> = (0..m).map(|i| ((i as f64) * 0.71).sin()).collect();
    let (mut x, mut r, mut snap) = (vec![1.0; m], vec![0.0; m], vec![0.0; m]);
    gauss_seidel_from_zero(&a, InvDiag::Stored(&inv), &mut x, &b, &mut r, &rows);
    let mut x_ref = vec![0.0; m];
    gauss_seidel(&a, InvDiag::Stored(&inv), &mut x_ref, &b, &mut snap, false);
    let mut r_ref = vec![0.0; m];
    residual(&a, &x_ref, &b, &mut r_ref);
    let close = |p: &[f64], q: &[f64]| p.iter().zip(q).all(|(u, v)| (u - v).abs() <= 1e-12);
    assert!(close(&x, &x_ref) && close(&r, &r_ref));
    let mut y = vec![0.0; m];
    gauss_seidel_back_with_product(
        &a,
        InvDiag::Stored(&inv),
        &mut x,
        &b,
        &mut snap,
        &mut y,
        &rows,
    );
    gauss_seidel(&a, InvDiag::Stored(&inv), &mut x_ref, &b, &mut snap, true);
    let mut y_ref = vec![0.0; m];
    a.mul_into(&x_ref, &mut y_ref);
    assert!(close(&x, &x_ref) && close(&y, &y_ref));
}

#[test]
fn fused_sweep_from_zero_is_the_sweep_and_its_residual() {
    // One level below GS_BLOCK (one sequential sweep) and one above (blocks and seams),
    // with truncated unknowns: their rows and columns zero, as in the Newton matrix.
    for levels in [5, 7] {
        let h = square_hierarchy(4, levels);
        let model = bench_model(h.finest(), Some(0.0), Foundation::Lumped);
        let n = model.n();
        let held = |i: usize| i % 7 == 3 || (i / 50) % 9 == 4;
        let mut a = model.s.clone();
        for i in 0..n {
            for k in a.pattern.ptr(i)..a.pattern.ptr(i + 1) {
                let j = a.pattern.col[k] as usize;
                if held(i) || held(j) {
                    a.val[k] = 0.0;
                }
            }
        }
        let mut inv = vec![0.0; n];
        fill_inv_diag(&a, &mut inv);
        let b: Vec<f64> = (0..n).map(|i| ((i as f64) * 0.71).sin()).collect();
        // The reference: the sweep from zero, then the residual, separately.
        let mut x_ref = vec![0.0; n];
        let mut snap = vec![0.0; n];
        gauss_seidel(&a, InvDiag::Stored(&inv), &mut x_ref, &b, &mut snap, false);
        let mut r_ref = vec![0.0; n];
        residual(&a, &x_ref, &b, &mut r_ref);
        let rows = SweepRows::of(&a.pattern);
        assert_eq!(rows.seams.is_empty(), n <= gs_block(n));
        let fused = |threads: usize| {
            // Whatever x holds on entry is ignored.
            let (mut x, mut r) = (vec![1.0; n], vec![f64::NAN; n]);
            crate::parallel::on_threads(threads, || {
                gauss_seidel_from_zero(&a, InvDiag::Stored(&inv), &mut x, &b, &mut r, &rows)
            });
            (x, r)
        };
        let (x, r) = fused(1);
        assert_eq!((x.clone(), r.clone()), fused(3), "thread count");
        let scale = norm_inf(&b);
        for i in 0..n {
            assert!((x[i] - x_ref[i]).abs() <= 1e-13 * scale, "x[{i}]");
            assert!(
                (r[i] - r_ref[i]).abs() <= 1e-13 * scale,
                "r[{i}]: {} {}",
                r[i],
                r_ref[i]
            );
            if held(i) {
                assert_eq!((x[i], r[i]), (0.0, b[i]));
            }
        }
        assert!(
            norm_inf(&r) > 1e-3 * scale,
            "the residual is not trivially 0"
        );
    }
}

#[test]
fn backward_sweep_with_product_is_the_sweep_and_its_product() {
    use super::operator::{apply, Shifted};
    // One level below GS_BLOCK (one sequential sweep) and one above (blocks and seams), on
    // the shifted Newton operator with held unknowns and on an assembled matrix.
    for levels in [5, 7] {
        let h = square_hierarchy(4, levels);
        let model = bench_model(h.finest(), Some(0.0), Foundation::Lumped);
        let n = model.n();
        let held: Vec<bool> = (0..n).map(|i| i % 7 == 3 || (i / 50) % 9 == 4).collect();
        let shift: Vec<f64> = (0..n).map(|i| 0.5 + ((i as f64) * 0.13).cos()).collect();
        let op = Shifted {
            s: &model.s,
            shift: &shift,
            held: &held,
        };
        let (b, x0) = rhs_and_start(&held);
        let rows = SweepRows::of(&model.s.pattern);
        let check = |name: &str,
                     fused: &dyn Fn(usize) -> (Vec<f64>, Vec<f64>),
                     reference: (Vec<f64>, Vec<f64>)| {
            let (x, y) = fused(1);
            assert_eq!((x.clone(), y.clone()), fused(3), "{name}: thread count");
            let (x_ref, y_ref) = reference;
            let scale = norm_inf(&y_ref);
            assert!(scale > 1e-3, "{name}: the product is not trivially 0");
            for i in 0..n {
                assert!(
                    (x[i] - x_ref[i]).abs() <= 1e-13 * norm_inf(&x_ref),
                    "{name}: x[{i}]"
                );
                assert!(
                    (y[i] - y_ref[i]).abs() <= 1e-12 * scale,
                    "{name}: y[{i}]: {} {}",
                    y[i],
                    y_ref[i]
                );
            }
        };
        // The shifted operator: held rows keep x = 0 and get y = 0.
        let mut inv = vec![0.0; n];
        fill_inv_diag(&op, &mut inv);
        let reference = {
            let (mut x, mut snap, mut y) = (x0.clone(), vec![0.0; n], vec![0.0; n]);
            gauss_seidel(&op, InvDiag::Stored(&inv), &mut x, &b, &mut snap, true);
            apply(&op, &x, &mut y);
            (x, y)
        };
        let fused = |threads: usize| {
            let (mut x, mut snap, mut y) = (x0.clone(), vec![0.0; n], vec![f64::NAN; n]);
            crate::parallel::on_threads(threads, || {
                gauss_seidel_back_with_product(
                    &op,
                    InvDiag::Stored(&inv),
                    &mut x,
                    &b,
                    &mut snap,
                    &mut y,
                    &rows,
                )
            });
            for i in (0..n).filter(|&i| held[i]) {
                assert_eq!((x[i], y[i]), (0.0, 0.0), "held row {i}");
            }
            (x, y)
        };
        check("shifted", &fused, reference);
        // An assembled matrix whose held rows and columns are zero (x is not zero there).
        let mut a = model.s.clone();
        for i in 0..n {
            for k in a.pattern.ptr(i)..a.pattern.ptr(i + 1) {
                if held[i] || held[a.pattern.col[k] as usize] {
                    a.val[k] = 0.0;
                }
            }
        }
        let x1: Vec<f64> = (0..n).map(|i| ((i as f64) * 0.3).cos()).collect();
        fill_inv_diag(&a, &mut inv);
        let reference = {
            let (mut x, mut snap) = (x1.clone(), vec![0.0; n]);
            gauss_seidel(&a, InvDiag::Stored(&inv), &mut x, &b, &mut snap, true);
            let y = a.mul(&x);
            (x, y)
        };
        let fused = |threads: usize| {
            let (mut x, mut snap, mut y) = (x1.clone(), vec![0.0; n], vec![f64::NAN; n]);
            crate::parallel::on_threads(threads, || {
                gauss_seidel_back_with_product(
                    &a,
                    InvDiag::Stored(&inv),
                    &mut x,
                    &b,
                    &mut snap,
                    &mut y,
                    &rows,
                )
            });
            (x, y)
        };
        check("assembled", &fused, reference);
    }
}

#[test]
fn forcing_is_quadratic_until_the_tolerance_is_near() {
    let tol = 1e-10;
    // Far from the answer: the square of the residual (capped at ¼).
    assert_eq!(forcing(1e-2, tol, 0.0, FINISH_FACTOR), 1e-4);
    assert_eq!(forcing(3.0, tol, 0.0, FINISH_FACTOR), 0.25);
    // The square within the finishing factor of the tolerance: straight to a quarter of it.
    assert_eq!(forcing(1e-4, tol, 0.0, FINISH_FACTOR), 0.25 * tol);
    assert_eq!(forcing(1e-12, tol, 0.0, FINISH_FACTOR), 0.25 * tol);
    // Never above the current residual's square, never below a quarter of the tolerance.
    for k in 0..40 {
        let kkt = 10f64.powf(-0.3 * k as f64);
        let f = forcing(kkt, tol, 0.0, FINISH_FACTOR);
        assert!(f <= kkt.min(0.5).powi(2).max(0.25 * tol), "{kkt}: {f}");
        assert!(f >= 0.25 * tol, "{kkt}: {f}");
    }
    // A rounding floor above the tolerance: the finish starts from the floor's neighbourhood
    // (the square at N = 4096: residual 3.6e-4 after two iterations, floor 1.4e-9).
    assert_eq!(forcing(3.6e-4, tol, 0.0, FINISH_FACTOR), 3.6e-4 * 3.6e-4);
    assert_eq!(forcing(3.6e-4, tol, 1.4e-9, FINISH_FACTOR), 0.25 * tol);
    // A floor below the tolerance changes nothing.
    assert_eq!(forcing(1e-3, tol, 1e-12, FINISH_FACTOR), 1e-6);
    // The algebraic levels' factor finishes from further away: from 5·10⁻³ (its square is
    // within 10⁶ of the tolerance), not from 5·10⁻².
    let algebraic = TnnmgOptions::default().finish_factor_algebraic;
    assert_eq!(forcing(5e-3, tol, 0.0, algebraic), 0.25 * tol);
    assert_eq!(forcing(5e-2, tol, 0.0, algebraic), 5e-2 * 5e-2);
}

/// The square on a 12 × 12 grid refined `steps` times by newest-vertex bisection of the
/// triangles near one corner (an adaptive loop's hierarchy).
fn corner_hierarchy(steps: usize) -> Hierarchy {
    use crate::adapt::bisect::{bisect, label_longest_edge};
    let mut h = Hierarchy::single(label_longest_edge(&square(12)));
    for _ in 0..steps {
        let mesh = h.finest();
        let marked: Vec<u32> = (0..mesh.n_triangles() as u32)
            .filter(|&k| {
                let c = mesh.triangles[k as usize].map(|v| mesh.points[v as usize]);
                c.iter().all(|p| p[0] + p[1] < 0.8)
            })
            .collect();
        let b = bisect(mesh, &marked).unwrap();
        h.levels.push(b.mesh);
        h.refinements.push(b.refinement);
    }
    h
}

#[test]
fn extended_levels_are_the_levels_built_whole() {
    let h = corner_hierarchy(4);
    let depth = h.depth();
    let mut below = h.clone();
    below.levels.pop();
    below.refinements.pop();
    let model = |m: &Mesh| bench_model(m, Some(1000.0), Foundation::Lumped);
    let (previous, finest) = (model(below.finest()), model(h.finest()));
    let old = Levels::new(&below, &previous.dofs, previous.s.pattern.clone()).unwrap();
    let whole = Levels::new(&h, &finest.dofs, finest.s.pattern.clone()).unwrap();
    let refinement = &h.refinements[depth - 2];
    let extend = |top: &DofMap| {
        old.clone()
            .extended(
                top,
                refinement,
                h.finest(),
                &finest.dofs,
                finest.s.pattern.clone(),
            )
            .unwrap()
    };
    let grown = extend(&previous.dofs).expect("the previous levels fit");
    assert_eq!(grown.len(), depth);
    assert_eq!(grown.sizes, whole.sizes);
    assert!(std::sync::Arc::ptr_eq(
        &grown.patterns[depth - 1],
        &finest.s.pattern
    ));
    for k in 0..depth {
        assert_eq!(grown.patterns[k], whole.patterns[k], "pattern {k}");
        let (a, b) = (&grown.sweep_rows[k], &whole.sweep_rows[k]);
        assert_eq!((&a.seams, &a.diag), (&b.seams, &b.diag), "sweep rows {k}");
    }
    for k in 0..depth - 1 {
        assert_eq!(grown.dofs[k].vertex, whole.dofs[k].vertex, "dofs {k}");
        let (a, b) = (&grown.transfers[k], &whole.transfers[k]);
        assert_eq!(
            (a.n_coarse, &a.parents),
            (b.n_coarse, &b.parents),
            "transfer {k}"
        );
        let n = a.n_fine();
        assert!((0..n).all(|v| a.weights(v) == b.weights(v)), "weights {k}");
        let x: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 1013) as f64 / 1013.0)
            .collect();
        let (mut ra, mut rb) = (vec![0.0; a.n_coarse], vec![1.0; b.n_coarse]);
        a.restrict(&x, &mut ra);
        b.restrict(&x, &mut rb);
        assert_eq!(ra, rb, "restriction {k}");
    }
    // Levels whose top is not the level the refinement starts from are not extended.
    assert!(extend(&DofMap::all(previous.dofs.n_vertices())).is_none());
    // A mesh that is not the model's.
    let e = old
        .clone()
        .extended(
            &previous.dofs,
            refinement,
            below.finest(),
            &finest.dofs,
            finest.s.pattern.clone(),
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("new finest level has"), "{e}");
}

#[test]
fn transfer_columns_read_from_the_fine_pattern_give_the_same_sums() {
    use crate::solve::newton::NewtonStates;
    let disk = crate::mesh::generate::disk([0.0, 0.0], 1.0, 0.3).unwrap();
    // Local refinement: most coarse unknowns have no child but the one on them.
    let local = corner_hierarchy(2);
    for (name, h, whole) in [
        ("square", square_hierarchy(4, 4), true),
        ("disc", Hierarchy::refined(disk, 3), true),
        ("local", local, false),
    ] {
        let model = bench_model(h.finest(), Some(1000.0), Foundation::Lumped);
        let levels = Levels::new(&h, &model.dofs, model.s.pattern.clone()).unwrap();
        // Every geometric transfer reads its columns from its fine level's pattern: whole
        // rows under uniform refinement, the children's positions under local refinement.
        for t in &levels.transfers {
            assert!(
                t.columns_from_fine_rows() && t.columns_are_whole_rows() == whole,
                "{name}"
            );
        }
        // Against the stored columns of the same prolongation: bitwise the same.
        let top = levels.len() - 1;
        let fine_rows = &levels.transfers[top - 1];
        let stored = {
            let coarse = &levels.dofs[top - 1];
            Transfer::new(&h.refinements[h.depth() - 2], coarse, &model.dofs).unwrap()
        };
        assert!(!stored.columns_from_fine_rows());
        let n = model.n();
        let x: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 1013) as f64 / 1013.0 - 0.3)
            .collect();
        let (mut a, mut b) = (vec![0.0; stored.n_coarse], vec![0.0; stored.n_coarse]);
        stored.restrict(&x, &mut a);
        fine_rows.restrict(&x, &mut b);
        assert_eq!(a, b, "{name}: restriction");
        assert_eq!(stored.injection(), fine_rows.injection(), "{name}");
        let pattern = stored.galerkin_pattern(&model.s.pattern);
        assert_eq!(
            pattern,
            *levels.patterns[top - 1],
            "{name}: Galerkin pattern"
        );
        // The truncated Newton matrix at a state with some unknowns held.
        let v: Vec<f64> = model.phi.iter().map(|p| p + 0.01).collect();
        let st = NewtonStates::of(&model, &v);
        let op = super::operator::LumpedShifted {
            s: &model.s,
            l: match &model.l {
                FoundationMatrix::Lumped(l) => l,
                _ => unreachable!(),
            },
            penetrating: &st.penetrating,
            held: &st.truncated,
        };
        let pat = std::sync::Arc::new(pattern);
        let (mut ca, mut cb) = (Csr::zeros(pat.clone()), Csr::zeros(pat.clone()));
        stored.galerkin_values(&op, &mut ca, None);
        fine_rows.galerkin_values(&op, &mut cb, None);
        assert_eq!(ca.val, cb.val, "{name}: Galerkin values");
        let dirty: Vec<bool> = (0..n).map(|i| i % 5 == 0).collect();
        let (mut da, mut db) = (vec![false; stored.n_coarse], vec![true; stored.n_coarse]);
        stored.coarse_dirty(&dirty, &mut da);
        fine_rows.coarse_dirty(&dirty, &mut db);
        assert_eq!(da, db, "{name}: dirty rows");
    }
}

#[test]
fn sweeps_divide_by_the_diagonal_they_read_as_by_the_stored_inverse() {
    use super::operator::Shifted;
    // Below and above one smoothing block, on the shifted operator with held unknowns (and
    // a shift that makes some diagonals zero or negative: their rows are left alone).
    for levels in [5, 7] {
        let h = square_hierarchy(4, levels);
        let model = bench_model(h.finest(), Some(0.0), Foundation::Lumped);
        let n = model.n();
        let held: Vec<bool> = (0..n).map(|i| i % 7 == 3).collect();
        let shift: Vec<f64> = (0..n)
            .map(|i| {
                if i % 11 == 5 {
                    -1e9
                } else {
                    ((i as f64) * 0.13).cos()
                }
            })
            .collect();
        let op = Shifted {
            s: &model.s,
            shift: &shift,
            held: &held,
        };
        let rows = SweepRows::of(&model.s.pattern);
        let mut inv = vec![0.0; n];
        fill_inv_diag(&op, &mut inv);
        assert!(inv.iter().filter(|&&d| d == 0.0).count() > n / 7);
        let (b, start) = rhs_and_start(&held);
        let ways = [InvDiag::Stored(&inv), InvDiag::Rows(&rows), InvDiag::Search];
        let runs: Vec<[Vec<f64>; 5]> = ways
            .iter()
            .map(|&d| {
                let (mut x0, mut r0) = (vec![0.0; n], vec![0.0; n]);
                gauss_seidel_from_zero(&op, d, &mut x0, &b, &mut r0, &rows);
                let (mut x1, mut snap) = (start.clone(), vec![0.0; n]);
                gauss_seidel(&op, d, &mut x1, &b, &mut snap, false);
                let mut x2 = start.clone();
                gauss_seidel(&op, d, &mut x2, &b, &mut snap, true);
                let (mut x3, mut y3) = (start.clone(), vec![0.0; n]);
                gauss_seidel_back_with_product(&op, d, &mut x3, &b, &mut snap, &mut y3, &rows);
                [x0, r0, x1, x2, x3]
            })
            .collect();
        assert_eq!(runs[0], runs[1], "{levels} levels: offsets");
        assert_eq!(runs[0], runs[2], "{levels} levels: searched");
    }
}

/// A right-hand side and a start for the smoother tests on `held.len()` unknowns: the start
/// is zero on the held unknowns, as the cycle leaves it.
fn rhs_and_start(held: &[bool]) -> (Vec<f64>, Vec<f64>) {
    let n = held.len();
    let b = (0..n).map(|i| ((i as f64) * 0.71).sin()).collect();
    let start = (0..n)
        .map(|i| {
            if held[i] {
                0.0
            } else {
                ((i as f64) * 0.3).cos()
            }
        })
        .collect();
    (b, start)
}
