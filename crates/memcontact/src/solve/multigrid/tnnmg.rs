//! The TNNMG iteration on a hierarchy of levels: nested iteration, smoothing, the
//! truncated Newton correction by the cycle, the exact line search and the certificate.

use super::aggregation;
use super::cycle::{FcgWork, Multigrid};
use super::levels::{Kind, Levels};
use super::transfer::Transfer;
use crate::certificate::Certificate;
use crate::error::Result;
use crate::mesh::refine::Hierarchy;
use crate::model::{FoundationMatrix, Model};
use crate::solve::active_set::start_from;
use crate::solve::line_search::{apply_step, exact_step, line_data_at};
use crate::solve::newton::{mark_dirty, NewtonMatrix, NewtonStates};
use crate::solve::relax::sweep_forward;
use crate::solve::{IterationRecord, Method, Observer, PhaseTimer, Settings, Solution};
use crate::sparse::{filled, par_rows, zeroed, Csr};
use std::sync::Arc;
use std::time::Instant;

pub(crate) const MAX_ITERATIONS: usize = 300;

/// Iterations without any change of the iterate after which the solver gives up.
pub(super) const STALL_LIMIT: usize = 3;

/// Tunable parameters of TNNMG (the defaults are what the benchmark uses).
#[derive(Debug, Clone)]
pub struct TnnmgOptions {
    /// ν₁: nonsmooth Gauss-Seidel sweeps before each Newton correction.
    pub presmoothing: usize,
    /// Multigrid cycles per Newton correction while the vertex states change (flexible CG
    /// steps preconditioned by the cycle when `krylov_steps > 0`). Three rather than two:
    /// an imported Gmsh mesh of 10⁶ vertices on algebraic levels takes 5 iterations instead
    /// of 6 (lumped; solve 1.54–1.61 s against 1.61–1.67 s in alternating runs), the square
    /// at N = 2048 lumped 1.93–1.97 s of solve against 2.02–2.08 s with the same 3
    /// iterations; consistent foundations take as long (four cycles were faster still with
    /// a lumped foundation, 3 % slower with a consistent one).
    pub cycles: usize,
    /// Once the vertex states (nearly) repeat from one iteration to the next, up to this
    /// many flexible CG steps preconditioned by the cycle per Newton correction. The
    /// correction is inexact Newton: its linear residual is driven below the square of the
    /// current scaled KKT residual, or a quarter of the tolerance once that square comes
    /// near it (the inexact Newton forcing term). 0: `cycles` plain cycles, always.
    pub krylov_steps: usize,
    /// (pre, post) Gauss-Seidel steps per level inside a V-cycle.
    pub smoothing: (usize, usize),
    /// Solve the coarser levels (geometric or algebraic) first and start from the
    /// prolongated solution.
    pub nested: bool,
    /// Scaled KKT residual to which the coarser levels are solved in nested iteration
    /// (never below `settings.tolerance`). A start only needs the accuracy the prolongation
    /// keeps: the finest level's first residual is about 1e-2 on the benchmark square
    /// whether the coarser level was solved to 1e-4 or to 1e-6, and the finest level takes
    /// as many iterations from a start solved to 1e-2 as from one solved to 1e-4 (N = 256
    /// to 2048, lumped and consistent, and the multigrid examples), while the coarse
    /// levels are spared their third iteration.
    pub nested_tolerance: f64,
    /// [`TnnmgOptions::nested_tolerance`] on algebraic levels. Their piecewise-constant
    /// prolongation keeps less of a coarse solution's accuracy than linear interpolation
    /// does: on imported Gmsh meshes of 10⁵ and 10⁶ vertices the finest level takes the
    /// same Krylov steps from coarse levels solved to 1e-1 as from 1e-2, and the coarse
    /// levels are spared a third of their time.
    pub nested_tolerance_algebraic: f64,
    /// Algebraic hierarchies: coarsen down to about this many unknowns (the coarsest level
    /// is factorised).
    pub coarsest: usize,
    /// Algebraic hierarchies: nested iteration passes over the level just below the finest
    /// (prolongates through it without solving there) when that level has more than this
    /// many unknowns. The finest level's first iterate is then as good from the level two
    /// below: the piecewise-constant prolongation keeps no more of the finer coarse
    /// solution's accuracy. On imported Gmsh sites of 1.1 M and 2.9 M vertices the finest
    /// level takes as many iterations or one fewer, and the run saves the tenth of a second
    /// (at 10⁶) that level cost; with 10⁵ to 2.4·10⁵ vertices (a level below of 25 000 to
    /// 60 000 unknowns) the finest level would take one iteration more, hence the bound.
    pub nested_pass_over_algebraic: usize,
    /// The finishing factor on algebraic levels (geometric levels use 10³): once the
    /// vertex states repeat, the Newton correction goes straight to the tolerance when the
    /// square of the scaled KKT residual is within this factor of it (with the tolerance 1e-10 of the benchmark:
    /// from a residual of 10⁻² down, against 3·10⁻⁴ with 10³). On imported
    /// Gmsh meshes the iteration reaches 10⁻³ to 10⁻² with its states settled, and with
    /// 10³ took one quadratic step to 10⁻⁶–10⁻⁷ and another to finish; with
    /// this factor it finishes at once, one iteration fewer for as many cycles: 6 → 5
    /// (consistent) and 5 → 4 (lumped) iterations at 1.2·10⁶ vertices, 6 → 5 and 4 → 4 on
    /// a graded mesh with a hole (2.1·10⁵), unchanged at 1.3·10⁵. 10⁷ finished one more
    /// case but spent a whole finishing solve (14 cycles) on states not yet settled on the
    /// graded mesh, 14 % more processor time there.
    pub finish_factor_algebraic: f64,
}

impl Default for TnnmgOptions {
    fn default() -> Self {
        TnnmgOptions {
            presmoothing: 1,
            cycles: 3,
            krylov_steps: 30,
            smoothing: (1, 1),
            nested: true,
            nested_tolerance: 1e-2,
            nested_tolerance_algebraic: 1e-1,
            coarsest: aggregation::COARSEST,
            nested_pass_over_algebraic: 100_000,
            finish_factor_algebraic: 1e6,
        }
    }
}

impl TnnmgOptions {
    /// These options with algebraic hierarchies coarsened down to about `coarsest`
    /// unknowns.
    #[cfg(any(test, feature = "bench"))]
    pub fn with_coarsest(self, coarsest: usize) -> TnnmgOptions {
        TnnmgOptions { coarsest, ..self }
    }
}

/// What happened on one level of a TNNMG solve.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LevelReport {
    /// Unknowns of the level.
    pub unknowns: usize,
    /// TNNMG iterations done there (0 on a level nested iteration passes over).
    pub iterations: usize,
    /// The scaled KKT residual reached there (NaN on a level passed over).
    pub residual: f64,
    /// Wall-clock seconds spent there.
    pub seconds: f64,
}

/// The per-level record of a TNNMG solve, coarsest first (the last entry is the model's
/// level; only it exists without nested iteration).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct TnnmgReport {
    /// One entry per level from the first solved on (a level nested iteration passes over
    /// has 0 iterations).
    pub levels: Vec<LevelReport>,
}

/// The coarse levels TNNMG runs on.
#[derive(Debug, Clone, Copy)]
pub enum Coarsening<'a> {
    /// Nested meshes of uniform refinement; the last must be the mesh the model was
    /// assembled on (anything else is an error).
    Geometric(&'a Hierarchy),
    /// Geometric levels built beforehand (`Levels::new`) for the model's unknowns and
    /// matrix pattern.
    Built(&'a Levels),
    /// An aggregation hierarchy built from the model's matrices (double pairwise
    /// aggregation, as in AGMG).
    Algebraic,
}

impl Coarsening<'_> {
    /// Geometric or algebraic.
    #[cfg(feature = "bench")]
    pub fn kind(&self) -> Kind {
        match self {
            Coarsening::Geometric(_) => Kind::Geometric,
            Coarsening::Built(l) => l.kind,
            Coarsening::Algebraic => Kind::Algebraic,
        }
    }
}

/// Solves Problem 2b by TNNMG with the default [`TnnmgOptions`] on the given coarse levels.
/// With a `start` (a warm start, e.g. the answer of a neighbouring load step) the
/// iteration begins there on the finest level, without nested iteration.
pub fn solve(
    model: &Model,
    coarsening: Coarsening,
    settings: &Settings,
    start: Option<&[f64]>,
    observer: &mut dyn Observer,
) -> Result<Solution> {
    solve_with(
        model,
        coarsening,
        settings,
        &TnnmgOptions::default(),
        start,
        observer,
    )
    .map(|r| r.0)
}

/// The matrix an algebraic hierarchy is built from: S plus the diagonals of the bodies'
/// foundations (where the membrane penetrates a body, the Newton matrices add its L to S).
/// S's values are copied, then its diagonal shifted, on all threads (a copy the size of
/// the problem).
pub(crate) fn setup_matrix(model: &Model) -> Csr {
    use rayon::prelude::*;
    const ROWS: usize = 4096;
    let s = &model.s;
    let pat = &s.pattern;
    let mut val = Vec::with_capacity(s.val.len());
    val.par_extend(s.val.par_iter().with_min_len(ROWS).copied());
    crate::sparse::row_chunks(pat, &mut val, ROWS)
        .into_par_iter()
        .for_each(|(first, block)| {
            let base = pat.ptr(first);
            for i in first..(first + ROWS).min(pat.n()) {
                let Some(k) = pat.find(i, i) else { continue };
                let v = &mut block[k - base];
                if model.can_touch[i] {
                    *v += model.l.diag(i);
                }
                if let Some(low) = model.lower.as_ref().filter(|low| low.can_touch[i]) {
                    *v += low.l.diag(i);
                }
            }
        });
    Csr {
        pattern: pat.clone(),
        val,
    }
}

/// The multigrid levels of `model` on the mesh hierarchy of the refinement relations
/// `refinements` (vertex counts coarsest first, the finest mesh `last`; see
/// [`Levels::from_relations`]), with aggregation levels below a coarsest mesh too large to
/// factorise ([`Levels::with_aggregation_below`], from [`setup_matrix`]). Every solve of a
/// model on mesh levels builds them here.
pub(crate) fn mesh_levels(
    model: &Model,
    refinements: &[crate::mesh::refine::Refinement],
    vertex_counts: &[usize],
    last: Option<&crate::mesh::Mesh>,
) -> Result<Levels> {
    Ok(Levels::from_relations(
        refinements,
        vertex_counts,
        last,
        &model.dofs,
        model.s.pattern.clone(),
    )?
    .with_aggregation_below(|| setup_matrix(model)))
}

/// [`mesh_levels`] of `model` on the whole hierarchy `h`.
pub(crate) fn mesh_levels_of(model: &Model, h: &Hierarchy) -> Result<Levels> {
    let counts = h.vertex_counts();
    mesh_levels(model, &h.refinements, &counts, h.levels.last())
}

/// Solves Problem 2b by TNNMG ([`crate::Method::Multigrid`]) with explicit options, also
/// returning the per-level report (one entry per level solved: all of them with nested
/// iteration). With a `start` the iteration begins there on the finest level, without
/// nested iteration.
pub fn solve_with(
    model: &Model,
    coarsening: Coarsening,
    settings: &Settings,
    options: &TnnmgOptions,
    start: Option<&[f64]>,
    observer: &mut dyn Observer,
) -> Result<(Solution, TnnmgReport)> {
    let mut timer = PhaseTimer::default();
    let built;
    let levels: &Levels = match coarsening {
        Coarsening::Built(l) => {
            if !Arc::ptr_eq(&l.patterns[l.len() - 1], &model.s.pattern) {
                return Err(crate::error::Error::Mesh(
                    "the multigrid levels were built for another matrix than the model's".into(),
                ));
            }
            l
        }
        Coarsening::Geometric(h) => {
            built = timer.time("setup", || mesh_levels_of(model, h))?;
            &built
        }
        Coarsening::Algebraic => {
            built = timer.time("setup", || {
                Levels::algebraic(&setup_matrix(model), options.coarsest)
            });
            &built
        }
    };
    let top = levels.len() - 1;
    let max = settings.max_iterations.unwrap_or(MAX_ITERATIONS);
    let mut report = TnnmgReport::default();
    let mut history = Vec::new();

    // Nested iteration: the Galerkin models of the coarser levels, coarsest first.
    let first = if options.nested && start.is_none() {
        0
    } else {
        top
    };
    let mut models: Vec<Model> = Vec::new();
    if first < top {
        timer.time("setup", || {
            let mut m = coarse_model(model, &levels.transfers[top - 1], levels, top - 1);
            for k in (first..top - 1).rev() {
                let next = coarse_model(&m, &levels.transfers[k], levels, k);
                models.push(m);
                m = next;
            }
            models.push(m);
            models.reverse();
        });
    }
    let mut final_certificate = None;
    let mut v = if first < top {
        start_from(&models[0], None)
    } else {
        start_from(model, start)
    };
    // Each coarse model is dropped as soon as its level is solved: the finest level's
    // iteration, the largest user of memory, runs without them.
    let mut models = models.into_iter();
    for k in first..=top {
        let coarse = if k < top { models.next() } else { None };
        let m = coarse.as_ref().unwrap_or(model);
        if k > first {
            let mut next = zeroed(m.n());
            levels.transfers[k - 1].prolongate(&v, &mut next);
            m.project(&mut next);
            v = next;
        }
        if k > first && passed_over(levels, k, options) {
            report.levels.push(LevelReport {
                unknowns: m.n(),
                iterations: 0,
                residual: f64::NAN,
                seconds: 0.0,
            });
            continue;
        }
        let t0 = Instant::now();
        let tol = if k == top {
            settings.tolerance
        } else {
            let nested = if k < levels.aggregated {
                options.nested_tolerance_algebraic
            } else {
                options.nested_tolerance
            };
            nested.max(settings.tolerance)
        };
        let mut silent = crate::solve::Silent;
        let mut coarse_timer = PhaseTimer::default();
        let obs: &mut dyn Observer = if k == top { observer } else { &mut silent };
        let level_timer = if k == top {
            &mut timer
        } else {
            &mut coarse_timer
        };
        let out = level_solve(LevelSolve {
            model: m,
            levels,
            top: k,
            v: &mut v,
            tolerance: tol,
            max_iterations: max,
            options,
            observer: obs,
            history: if k == top { Some(&mut history) } else { None },
            timer: level_timer,
            confirm: k == top,
            check_start: k == first,
            cancel: &settings.cancel,
        })?;
        let seconds = t0.elapsed().as_secs_f64();
        final_certificate = out.2;
        if k < top {
            timer.add("nested iteration", seconds);
        }
        report.levels.push(LevelReport {
            unknowns: m.n(),
            iterations: out.0,
            residual: out.1,
            seconds,
        });
    }
    let certificate = match final_certificate {
        Some(c) => c,
        None => timer.time("certificate", || model.certificate(&v)),
    };
    let iterations = report.levels.last().map_or(0, |l| l.iterations);
    Ok((
        Solution {
            energy: model.energy(&v),
            u: v,
            method: Method::Multigrid,
            iterations,
            certificate,
            multipliers: None,
            history,
            phases: timer.into_phases(),
            coarsening: Some(levels.kind),
        },
        report,
    ))
}

/// Whether nested iteration passes over level `k` of `levels` (see
/// [`TnnmgOptions::nested_pass_over_algebraic`]): the level just below the finest of a large
/// algebraic hierarchy.
fn passed_over(levels: &Levels, k: usize, options: &TnnmgOptions) -> bool {
    levels.kind == Kind::Algebraic
        && k + 2 == levels.len()
        && levels.n(k) > options.nested_pass_over_algebraic
}

/// The Galerkin restriction of `fine` to level `k` of `levels` (`t` prolongates level `k`
/// to the fine one): the coarse discretisation of the same problem for nested meshes; on
/// aggregates, the piecewise-constant restriction with the stiffness scaled.
pub(super) fn coarse_model(fine: &Model, t: &Transfer, levels: &Levels, k: usize) -> Model {
    let pattern = levels.patterns[k].clone();
    let galerkin = |a: &Csr| {
        let mut c = Csr::zeros(pattern.clone());
        t.galerkin_values(a, &mut c, None);
        c
    };
    let restrict = |x: &[f64]| {
        let mut y = zeroed(t.n_coarse);
        t.restrict(x, &mut y);
        y
    };
    let mut s = galerkin(&fine.s);
    if k < levels.aggregated {
        let factor = aggregation::stiffness_scale(t.n_fine(), t.n_coarse);
        par_rows(&mut s.val, |_, x| *x *= factor);
    }
    let inject = t.injection();
    // One body's Galerkin restriction: L_c = PᵀLP (or l_c = Pᵀl), φ and the rigid flags
    // injected at the coarse vertices (on aggregates: at the first vertex of weight 1).
    let body = |l: &FoundationMatrix, phi: &[f64], rigid: Option<&Vec<bool>>| {
        let l = match l {
            FoundationMatrix::Consistent(l) => FoundationMatrix::Consistent(galerkin(l)),
            FoundationMatrix::Lumped(d) => FoundationMatrix::Lumped(restrict(d)),
            FoundationMatrix::Rigid => FoundationMatrix::Rigid,
        };
        let phi: Vec<f64> = inject.iter().map(|&v| phi[v as usize]).collect();
        let rigid: Option<Vec<bool>> =
            rigid.map(|r| inject.iter().map(|&v| r[v as usize]).collect());
        let can_touch: Vec<bool> = (0..t.n_coarse)
            .map(|i| l.is_rigid() || l.diag(i) > 0.0 || rigid.as_ref().is_some_and(|r| r[i]))
            .collect();
        (l, phi, can_touch, rigid)
    };
    let (l, phi, can_touch, rigid) = body(&fine.l, &fine.phi, fine.rigid.as_ref());
    let lower = fine.lower.as_ref().map(|low| {
        let (l, phi, can_touch, rigid) = body(&low.l, &low.phi, low.rigid.as_ref());
        crate::model::Body {
            l,
            phi,
            can_touch,
            rigid,
            foundation: low.foundation,
            phi_fixed: Vec::new(),
            h_vertices: crate::model::VertexValues::Each(Vec::new()),
            epsilon: low.epsilon,
        }
    });
    let dofs = if k < levels.aggregated {
        crate::mesh::DofMap::all(t.n_coarse)
    } else {
        levels.dofs_of(k).clone()
    };
    Model {
        d: restrict(&fine.d),
        tension: fine.tension,
        s,
        l,
        phi,
        can_touch,
        foundation: fine.foundation,
        // Only the solver uses this model: vertex fields are not needed beyond φ.
        h_vertices: crate::model::VertexValues::Each(Vec::new()),
        phi_fixed: Vec::new(),
        total_load: fine.total_load,
        epsilon: fine.epsilon,
        dofs,
        rigid,
        lower,
        boundary_values: Vec::new(),
        lift: Vec::new(),
    }
}

/// Within this factor of the tolerance, the square of the scaled KKT residual (what the next
/// Newton iteration would reach) sends the Newton correction straight to the tolerance, on
/// geometric levels (on algebraic ones: [`TnnmgOptions::finish_factor_algebraic`]).
pub(super) const FINISH_FACTOR: f64 = 1e3;

/// The inexact Newton forcing term, in scaled KKT units, once the vertex states repeat: the
/// linear residual is driven below the square of the current KKT residual (quadratic
/// convergence without oversolving), and below a quarter of the tolerance once that square
/// is within the factor `finish` of it ([`FINISH_FACTOR`] on geometric levels). On the
/// answer's piece of J the Newton step is then the answer, and the iteration that would
/// only have finished the linear solve is saved; off it, the extra accuracy costs a few
/// Krylov steps (at most a factor 4·`finish` more reduction).
///
/// The finish is decided against the residual the iteration can reach: the tolerance, or
/// the rounding floor when that lies above it (`floor`, already times
/// [`crate::certificate::AT_FLOOR`]). Below the floor the tolerance cannot be met and the
/// iteration stops at the floor, so a quadratic step taken first would only delay the
/// finish by one iteration.
pub(super) fn forcing(kkt: f64, tolerance: f64, floor: f64, finish: f64) -> f64 {
    let quadratic = kkt.min(0.5).powi(2);
    if quadratic <= finish * tolerance.max(floor) {
        0.25 * tolerance
    } else {
        quadratic
    }
}

/// Evaluates `$body` with `$op` bound to the Newton matrix `$a` ([`NewtonMatrix`]) of
/// `$model` at the states `$st`, as a multigrid top-level operator of its own type (the
/// kernels are compiled for each form).
macro_rules! with_operator {
    ($a:expr, $model:expr, $st:expr, |$op:ident| $body:expr) => {
        match &$a {
            NewtonMatrix::Assembled(m) => {
                let $op = m;
                $body
            }
            NewtonMatrix::Diagonal(d) => {
                let $op = &super::operator::Shifted {
                    s: &$model.s,
                    shift: d,
                    held: &$st.truncated,
                };
                $body
            }
            NewtonMatrix::Implicit => {
                let FoundationMatrix::Lumped(l) = &$model.l else {
                    unreachable!("an implicit Newton matrix has a lumped foundation")
                };
                let $op = &super::operator::LumpedShifted {
                    s: &$model.s,
                    l,
                    penetrating: &$st.penetrating,
                    held: &$st.truncated,
                };
                $body
            }
        }
    };
}

/// Everything one level's TNNMG iteration needs.
pub(super) struct LevelSolve<'a, 'b> {
    model: &'a Model,
    levels: &'a Levels,
    top: usize,
    v: &'a mut Vec<f64>,
    tolerance: f64,
    max_iterations: usize,
    options: &'a TnnmgOptions,
    observer: &'b mut dyn Observer,
    history: Option<&'b mut Vec<IterationRecord>>,
    timer: &'b mut PhaseTimer,
    /// Confirm convergence with [`Model::certificate`] (the finest level).
    confirm: bool,
    /// Whether `v` may already meet the tolerance. A start prolongated from the level below
    /// is not checked (its residual is that of the coarser mesh, far above any tolerance):
    /// the first iteration begins at once, without a certificate pass.
    check_start: bool,
    /// Stops the iteration when cancelled.
    cancel: &'a crate::parallel::Cancel,
}

/// TNNMG on one level; returns the iterations, the scaled KKT residual reached and, when
/// convergence was confirmed, the model's certificate at the final iterate.
pub(super) fn level_solve(ls: LevelSolve) -> Result<(usize, f64, Option<Certificate>)> {
    let LevelSolve {
        model,
        levels,
        top,
        v,
        tolerance,
        max_iterations,
        options,
        observer,
        mut history,
        timer,
        confirm,
        check_start,
        cancel,
    } = ls;
    let n = model.n();
    let pattern = model.s.pattern.clone();
    let mut a = NewtonMatrix::for_model(model);
    let mut mg = Multigrid::new(levels, top);
    mg.cancel = cancel.clone();
    mg.smoothing = options.smoothing;
    let mut delta = zeroed(n);
    let mut g = zeroed(n);
    let mut prev: Option<NewtonStates> = None;
    let mut changed = filled(n, false);
    let mut dirty = filled(n, false);
    let mut iterations = 0;
    let mut stalled = 0;
    let mut certificate = None;
    let mut watch = crate::certificate::FloorWatch::default();
    let mut fcg = FcgWork::default();
    let mut scale = 1.0;
    let mut skip_check = !check_start && max_iterations > 0;
    let mut kkt = f64::INFINITY;
    let mut floor = 0.0;
    loop {
        cancel.check()?;
        if !std::mem::take(&mut skip_check) {
            let ev = timer.time("certificate", || crate::certificate::evaluate(model, v));
            scale = ev.certificate.force_scale;
            kkt = ev.certificate.kkt();
            floor = crate::certificate::AT_FLOOR * ev.certificate.rounding_floor;
            if iterations > 0 {
                let record = IterationRecord::new(iterations, &ev);
                observer.iteration(&record);
                if let Some(h) = history.as_deref_mut() {
                    h.push(record);
                }
            }
            // Met the tolerance, or at the rounding floor (more iterations cannot help).
            if ev.certificate.settled(tolerance) || watch.stuck(&ev.certificate) {
                if confirm {
                    certificate = Some(ev.certificate);
                }
                break;
            }
            if !kkt.is_finite() || iterations >= max_iterations || stalled >= STALL_LIMIT {
                break;
            }
        }
        iterations += 1;
        // Whether the iterate moved at all in this iteration (smoothing or step).
        let mut moved = false;
        timer.time("smoothing", || {
            for _ in 0..options.presmoothing {
                moved |= sweep_forward(model, v);
            }
        });
        // The truncated Newton system at the smoothed iterate.
        let st = NewtonStates::of(model, v);
        let dirty_rows = prev
            .as_ref()
            .map(|p| mark_dirty(&pattern, p, &st, &mut changed, &mut dirty));
        // The states are (nearly) those of the last iteration: the piece of J is likely the
        // solution's, and the Newton step on it is worth computing accurately.
        let settled = dirty_rows.is_some_and(|d| d <= n / 1000);
        let rows = dirty_rows.map(|_| dirty.as_slice());
        timer.time("newton system", || {
            a.fill(model, v, &st, rows, &mut g, None)
        });
        timer.time("coarse operators", || {
            with_operator!(a, model, st, |op| mg.update(op, rows))
        })?;
        timer.time("v-cycle", || {
            par_rows(&mut g, |_, x| *x = -*x);
            par_rows(&mut delta, |_, d| *d = 0.0);
            if options.krylov_steps > 0 {
                // Inexact Newton once the states repeat ([`forcing`]); until then, a few
                // steps only.
                let (eta, steps) = if settled {
                    let finish = match levels.kind {
                        Kind::Geometric => FINISH_FACTOR,
                        Kind::Algebraic => options.finish_factor_algebraic,
                    };
                    (forcing(kkt, tolerance, floor, finish), options.krylov_steps)
                } else {
                    (0.0, options.cycles)
                };
                with_operator!(a, model, st, |op| mg.fcg(
                    op,
                    &mut delta,
                    &mut g,
                    eta * scale,
                    steps,
                    &st.truncated,
                    &mut fcg,
                ));
            } else {
                for _ in 0..options.cycles {
                    with_operator!(a, model, st, |op| mg.cycle(op, &mut delta, &g));
                }
            }
            let extended = model.is_extended();
            let (v, truncated): (&[f64], &[bool]) = (v, &st.truncated);
            par_rows(&mut delta, |i, d| {
                if truncated[i] || !d.is_finite() {
                    *d = 0.0;
                    return;
                }
                // Project onto the defect obstacles of the rigid bodies: V + δ ≤ φ (and
                // V + δ ≥ φ_low).
                if !extended {
                    if model.is_rigid() && model.can_touch[i] {
                        *d = d.min(model.phi[i] - v[i]);
                    }
                    return;
                }
                if model.can_touch[i] && model.rigid_at(i) {
                    *d = d.min(model.phi[i] - v[i]);
                }
                if let Some(low) = &model.lower {
                    if low.can_touch[i] && low.rigid_at(i) {
                        *d = d.max(low.phi[i] - v[i]);
                    }
                }
            });
        });
        timer.time("line search", || {
            let (g0, s2) = line_data_at(model, &delta, v);
            if let Some(alpha) = exact_step(model, v, &delta, g0, s2) {
                moved |= apply_step(model, v, &delta, alpha);
            }
        });
        prev = Some(st);
        if !moved {
            stalled += 1;
        } else {
            stalled = 0;
        }
    }
    Ok((iterations, kkt, certificate))
}
