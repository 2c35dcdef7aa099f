//! TNNMG on algebraic (aggregation) hierarchies, on unstructured meshes without refinement
//! levels: a Gmsh mesh with two regions and a hole, the disc and polygon generators.
//! Checked against the active-set method (an independent formulation, Problem 2f with
//! sparse Cholesky), with monotone energy, bounded iteration counts under refinement and
//! results independent of the number of threads.

use super::levels::*;
use super::smoother::*;
use super::tnnmg::*;
use crate::field::Coefficient;
use crate::mesh::generate::{disk, polygon, PolygonSpec};
use crate::mesh::{Mesh, Point};
use crate::model::Model;
use crate::model::{BodyStiffness, Foundation, ProblemData, Sampling};
use crate::solve::{active_set, Silent};
use crate::solve::{Method, Settings};
use crate::sparse::norm_inf;

/// A coefficient given per region and point.
struct ByRegion<F: Fn(Point, u32) -> f64 + Sync>(F);

impl<F: Fn(Point, u32) -> f64 + Sync> Coefficient for ByRegion<F> {
    fn at(&self, p: Point, region: u32) -> f64 {
        (self.0)(p, region)
    }
    fn on_region(&self, _: u32) -> Option<f64> {
        None
    }
}

/// The Gmsh fixture: a 2 × 1 site with a hole, regions "foam" (tag 1) and "soil" (tag 2).
fn site() -> Mesh {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/site.msh");
    crate::io::gmsh::read_msh(&path).unwrap().0
}

/// The data of the tests: f = 20, φ = 0.3 + 0.05 sin 2πx cos 2πy, h by region (foam 100,
/// soil 1000) or constant, or rigid (`h = None`).
fn model(mesh: &Mesh, h: Option<&dyn Coefficient>, foundation: Foundation) -> Model {
    use std::f64::consts::PI;
    let phi =
        ByRegion(|p: Point, _| 0.3 + 0.05 * (2.0 * PI * p[0]).sin() * (2.0 * PI * p[1]).cos());
    Model::assemble(
        mesh,
        &ProblemData {
            tension: 1.0,
            load: &20.0,
            shape: &phi,
            stiffness: match h {
                Some(h) => BodyStiffness::Elastic(h),
                None => BodyStiffness::Rigid,
            },
            foundation,
            sampling: Sampling::Nodal,
        },
    )
    .unwrap()
}

fn settings() -> Settings {
    Settings {
        method: Method::Multigrid,
        tolerance: 1e-11,
        ..Settings::default()
    }
}

/// TnnmgOptions that coarsen small test meshes over several levels.
fn options() -> TnnmgOptions {
    TnnmgOptions {
        coarsest: 40,
        ..TnnmgOptions::default()
    }
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let num = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    num / norm_inf(b).max(1e-300)
}

/// Algebraic TNNMG, with and without nested iteration on the aggregation levels (and with
/// nested iteration passing over the level below the finest), against the active-set
/// method, with its energy history monotone.
fn agrees_with_active_set(model: &Model, what: &str) {
    let reference = active_set::solve(model, &settings(), None, &mut Silent).unwrap();
    for (nested, pass_over) in [(true, false), (true, true), (false, false)] {
        let what = format!("{what}, nested {nested}, passing over {pass_over}");
        let options = TnnmgOptions {
            nested,
            nested_pass_over_algebraic: if pass_over { 0 } else { usize::MAX },
            ..options()
        };
        let rep = agrees_with(model, &options, &reference.u, &what);
        let levels = Levels::algebraic(&setup_matrix(model), options.coarsest).len();
        let solved = if nested { levels } else { 1 };
        assert_eq!(rep.levels.len(), solved, "{what}: levels reported");
        assert!(levels >= 3, "{what}: {levels} levels");
        // Only the level below the finest is passed over, and only when asked.
        for (k, level) in rep.levels.iter().enumerate() {
            let skipped = nested && pass_over && k + 2 == levels;
            assert_eq!(
                level.iterations == 0,
                skipped,
                "{what}: level {k}: {level:?}"
            );
        }
    }
}

/// Algebraic TNNMG with `options` against `reference`, with its energy history monotone.
fn agrees_with(
    model: &Model,
    options: &TnnmgOptions,
    reference: &[f64],
    what: &str,
) -> TnnmgReport {
    agrees_on(model, Coarsening::Algebraic, options, reference, what).1
}

/// TNNMG on `coarsening` with `options` against `reference` (its levels of the kind
/// asked, KKT ≤ 1e-11, relative difference < 1e-8), with its energy history monotone.
fn agrees_on(
    model: &Model,
    coarsening: Coarsening,
    options: &TnnmgOptions,
    reference: &[f64],
    what: &str,
) -> (crate::solve::Solution, TnnmgReport) {
    let (sol, rep) =
        solve_with(model, coarsening, &settings(), options, None, &mut Silent).unwrap();
    let kind = match coarsening {
        Coarsening::Algebraic => Kind::Algebraic,
        _ => Kind::Geometric,
    };
    assert_eq!(sol.coarsening, Some(kind), "{what}");
    assert!(
        sol.certificate.kkt() <= 1e-11,
        "{what}: {:?}",
        sol.certificate
    );
    let d = rel_diff(&sol.u, reference);
    assert!(d < 1e-8, "{what}: differs from active set by {d:e}");
    for w in sol.history.windows(2) {
        assert!(
            w[1].energy <= w[0].energy + 1e-13 * w[0].energy.abs(),
            "{what}: J rises {} -> {}",
            w[0].energy,
            w[1].energy
        );
    }
    (sol, rep)
}

#[test]
fn hierarchy_of_the_gmsh_site_has_several_levels() {
    let mesh = site();
    let m = model(&mesh, Some(&1000.0), Foundation::Consistent);
    let levels = Levels::algebraic(&setup_matrix(&m), options().coarsest);
    assert_eq!(levels.kind, Kind::Algebraic);
    assert!(levels.len() >= 3, "{:?}", levels.sizes);
    assert_eq!(levels.n(levels.len() - 1), m.n());
    assert!(levels.sizes.windows(2).all(|w| w[0] < w[1]));
    // The operator patterns are those of PᵀAP for the composed aggregations, as the
    // symbolic product from the finest pattern gives them.
    let direct = super::transfer::galerkin_patterns(&levels.transfers, m.s.pattern.clone());
    for (p, q) in levels.patterns.iter().zip(&direct) {
        assert_eq!((&p.row_ptr, &p.col), (&q.row_ptr, &q.col));
    }
}

#[test]
fn algebraic_tnnmg_agrees_with_the_active_set_method() {
    let mesh = site();
    // h by region: foam (1) soft, soil (2) stiff.
    let regions = ByRegion(|_, r| if r == 1 { 100.0 } else { 1000.0 });
    let varying = ByRegion(|p: Point, _| 200.0 + 300.0 * p[0]);
    for foundation in [Foundation::Consistent, Foundation::Lumped] {
        for (h, name) in [
            (&1000.0 as &dyn Coefficient, "constant"),
            (&regions as &dyn Coefficient, "region table"),
            (&varying as &dyn Coefficient, "expression"),
        ] {
            let m = model(&mesh, Some(h), foundation);
            agrees_with_active_set(&m, &format!("site, {name}, {foundation:?}"));
        }
    }
    let rigid = model(&mesh, None, Foundation::Consistent);
    agrees_with_active_set(&rigid, "site, rigid");
    // The generators without refinement: the disc and a polygon with a hole and regions.
    let d = disk([0.0, 0.0], 1.0, 0.08).unwrap();
    agrees_with_active_set(&model(&d, Some(&300.0), Foundation::Consistent), "disc");
    agrees_with_active_set(&model(&d, None, Foundation::Lumped), "disc, rigid");
    let p = polygon(&l_shape(0.08)).unwrap();
    let m = model(&p, Some(&regions), Foundation::Lumped);
    agrees_with_active_set(&m, "polygon");
}

/// An L-shaped polygon with a square hole and a region "foam" (tag 1).
fn l_shape(size: f64) -> PolygonSpec {
    PolygonSpec {
        outer: vec![
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ],
        holes: vec![vec![[0.3, 0.3], [0.6, 0.3], [0.6, 0.6], [0.3, 0.6]]],
        regions: vec![(
            "foam".into(),
            vec![[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]],
        )],
        size,
        min_angle: 25.0,
    }
}

#[test]
fn iteration_counts_stay_bounded_under_refinement() {
    // Four unstructured meshes of the same polygon, each meshed anew (no hierarchy).
    let regions = ByRegion(|_, r| if r == 1 { 100.0 } else { 1000.0 });
    for foundation in [Foundation::Consistent, Foundation::Lumped] {
        let counts: Vec<usize> = [0.1, 0.05, 0.025, 0.0125]
            .iter()
            .map(|&size| {
                let mesh = polygon(&l_shape(size)).unwrap();
                let m = model(&mesh, Some(&regions), foundation);
                let (sol, _) = solve_with(
                    &m,
                    Coarsening::Algebraic,
                    &settings(),
                    &TnnmgOptions::default().with_coarsest(200),
                    None,
                    &mut Silent,
                )
                .unwrap();
                assert!(sol.certificate.kkt() <= 1e-11);
                sol.iterations
            })
            .collect();
        let (lo, hi) = (counts[0], *counts.iter().max().unwrap());
        assert!(hi <= lo + 3, "{foundation:?}: {counts:?}");
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    // Large enough for the parallel paths (blocks of the smoother, reductions).
    let mesh = disk([0.0, 0.0], 1.0, 0.008).unwrap();
    let m = model(&mesh, Some(&1000.0), Foundation::Consistent);
    assert!(m.n() > 2 * GS_BLOCK, "{}", m.n());
    let run = |threads: usize| {
        crate::parallel::on_threads(threads, || {
            solve_with(
                &m,
                Coarsening::Algebraic,
                &settings(),
                &TnnmgOptions::default(),
                None,
                &mut Silent,
            )
            .unwrap()
            .0
        })
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one.u, two.u);
    assert_eq!(one.iterations, two.iterations);
}

#[test]
fn scaled_aggregation_levels_deflect_like_the_fine_mesh() {
    // No contact (φ far below reach): every level's model is linear, its answer S_c⁻¹D_c.
    // The exact deflection peaks at f/(4t) = 5 at the centre; the plain Galerkin product
    // of piecewise constants would peak at about half of it on the first aggregation
    // level and a quarter on the second.
    let mesh = disk([0.0, 0.0], 1.0, 0.03).unwrap();
    let mut m = model(&mesh, Some(&1000.0), Foundation::Lumped);
    m.phi.iter_mut().for_each(|p| *p = 100.0);
    let levels = Levels::algebraic(&setup_matrix(&m), 100);
    let top = levels.len() - 1;
    assert!(top >= 2, "{:?}", levels.sizes);
    let peak = |m: &Model| {
        let u = active_set::solve(m, &settings(), None, &mut Silent)
            .unwrap()
            .u;
        u.iter().fold(0.0f64, |a, &x| a.max(x))
    };
    let fine = peak(&m);
    assert!((fine - 5.0).abs() < 0.05, "{fine}");
    let first = coarse_model(&m, &levels.transfers[top - 1], &levels, top - 1);
    let second = coarse_model(&first, &levels.transfers[top - 2], &levels, top - 2);
    for (coarse, which) in [(&first, "first"), (&second, "second")] {
        let ratio = peak(coarse) / fine;
        assert!((0.8..1.25).contains(&ratio), "{which} level: {ratio}");
    }
}

/// A mesh hierarchy whose coarsest mesh is large (an unstructured disc of more than
/// [`COARSEST`](super::aggregation::COARSEST) unknowns refined once, as `refine = 1` makes
/// of an imported mesh) gets aggregation levels below it instead of a factorisation of the
/// whole coarsest mesh: the mesh levels unchanged above, the patterns those of the
/// symbolic products, and TNNMG on them (the hybrid cycle) agreeing with the active-set
/// method, with and without nested iteration. A small coarsest mesh keeps its levels.
#[test]
fn large_coarsest_meshes_get_aggregation_levels_below() {
    use super::aggregation::COARSEST;
    use crate::mesh::refine::Hierarchy;
    let h = Hierarchy::refined(disk([0.0, 0.0], 1.0, 0.03).unwrap(), 1);
    let m = model(h.finest(), Some(&300.0), Foundation::Lumped);
    let mesh_levels = Levels::new(&h, &m.dofs, m.s.pattern.clone()).unwrap();
    assert!(mesh_levels.sizes[0] > COARSEST, "{:?}", mesh_levels.sizes);
    let levels = mesh_levels
        .clone()
        .with_aggregation_below(|| setup_matrix(&m));
    let below = levels.aggregated;
    assert!(below >= 1, "{:?}", levels.sizes);
    assert_eq!(levels.len(), below + mesh_levels.len());
    assert_eq!(levels.sizes[below..], mesh_levels.sizes[..]);
    assert!(levels.sizes[0] <= COARSEST, "{:?}", levels.sizes);
    assert!(levels.sizes.windows(2).all(|w| w[0] < w[1]));
    let direct = super::transfer::galerkin_patterns(&levels.transfers, m.s.pattern.clone());
    for (p, q) in levels.patterns.iter().zip(&direct) {
        assert_eq!((&p.row_ptr, &p.col), (&q.row_ptr, &q.col));
    }
    let reference = active_set::solve(&m, &settings(), None, &mut Silent).unwrap();
    for nested in [true, false] {
        let what = format!("refined disc, nested {nested}");
        let options = TnnmgOptions {
            nested,
            ..TnnmgOptions::default()
        };
        let (sol, rep) = agrees_on(&m, Coarsening::Geometric(&h), &options, &reference.u, &what);
        let solved = if nested { levels.len() } else { 1 };
        assert_eq!(rep.levels.len(), solved, "{what}: levels reported");
        // From zero the hard start costs a few iterations more, as on any levels.
        let limit = if nested { 4 } else { 10 };
        assert!(
            sol.iterations <= limit,
            "{what}: {} iterations",
            sol.iterations
        );
    }
    // A coarsest mesh the factorisation takes whole keeps the mesh levels alone.
    let h = Hierarchy::refined(disk([0.0, 0.0], 1.0, 0.3).unwrap(), 2);
    let m = model(h.finest(), Some(&300.0), Foundation::Lumped);
    let levels = Levels::new(&h, &m.dofs, m.s.pattern.clone()).unwrap();
    let (len, sizes) = (levels.len(), levels.sizes.clone());
    let levels = levels.with_aggregation_below(|| setup_matrix(&m));
    assert_eq!(
        (levels.aggregated, levels.len(), levels.sizes),
        (0, len, sizes)
    );
}
