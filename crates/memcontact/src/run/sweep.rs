//! Load sweeps and load combinations run. A tensionless foundation cannot be superposed: every
//! load level or combination is its own nonlinear solve. A sweep varies one parameter
//! (`[sweep]`); load cases override the base case's data (`[[load_case]]`). Steps run in
//! turn on one mesh, each warm-started from the previous answer.
//!
//! A sweep parameter enters the discrete model linearly, so a step scales the assembled
//! base model instead of assembling again: the load factor scales D, the stiffness factor
//! L, the tension S, and the obstacle offset adds to φₙ. A load case with new data
//! assembles once on the same mesh.

use crate::case::{steps, Case, StepSpec, SweepParameter};
use crate::discretization::check_case_on_mesh;
use crate::discretization::{assemble_model, Discretization, Phase};
use crate::error::{Error, Result};
use crate::mesh::refine::Hierarchy;
use crate::mesh::Mesh;
use crate::model::{FoundationMatrix, Model};
use crate::outcome::{Outcome, StepRow};
use crate::solve::Observer;
use std::time::Instant;

/// `model` with one sweep parameter set to `value` (the base model has factor 1, the
/// case's tension, and offset 0).
pub fn apply(base: &Model, parameter: SweepParameter, value: f64) -> Model {
    let mut m = base.clone();
    match parameter {
        SweepParameter::LoadFactor => scale_load(&mut m, value),
        SweepParameter::StiffnessFactor => {
            match &mut m.l {
                FoundationMatrix::Consistent(l) => l.val.iter_mut().for_each(|v| *v *= value),
                FoundationMatrix::Lumped(d) => d.iter_mut().for_each(|v| *v *= value),
                FoundationMatrix::Rigid => {}
            }
            if !m.is_rigid() {
                m.h_vertices.map(|h| h * value);
                // M is where L_ii > 0: a zero factor leaves nothing to touch.
                for i in 0..m.can_touch.len() {
                    m.can_touch[i] =
                        (m.can_touch[i] && value > 0.0 && m.l.diag(i) > 0.0) || m.rigid_at(i);
                }
            }
        }
        SweepParameter::Tension => m.set_tension(value),
        SweepParameter::ObstacleOffset => {
            m.phi.iter_mut().for_each(|p| *p += value);
            m.phi_fixed.iter_mut().for_each(|(_, p)| *p += value);
        }
    }
    m
}

/// Scales the load f (D and ∫f) by `k`.
fn scale_load(m: &mut Model, k: f64) {
    m.scale_load(k);
}

/// Names the step (its directory name and value) in an error about its data.
fn at_step(step: &StepSpec, case: &Case, e: Error) -> Error {
    let what = match &case.sweep {
        Some(s) => format!("{} = {:e}", s.parameter.name(), step.value),
        None => format!("load_factor = {:e}", step.value),
    };
    match e {
        Error::Data(m) => Error::Data(format!("{} ({what}): {m}", step.name)),
        other => other,
    }
}

/// The model of `step` of `case` on `mesh`, from the base case's model `base`: the sweep's
/// parameter applied to it, or the load case's model (assembled when the load case has
/// data of its own) with its load factor. The observer sees the assembly.
pub fn step_model(
    case: &Case,
    step: &StepSpec,
    base: &Model,
    mesh: &Mesh,
    observer: &mut dyn Observer,
) -> Result<Model> {
    if let Some(s) = &case.sweep {
        return Ok(apply(base, s.parameter, step.value));
    }
    let lc = case.load_cases.get(step.index).ok_or_else(|| {
        Error::Data(format!(
            "step {} is not one of the {} load cases",
            step.index,
            case.load_cases.len()
        ))
    })?;
    let mut m = if lc.assembles() {
        observer.phase_started("assembly");
        let t0 = Instant::now();
        let m = assemble_model(&lc.problem(&case.problem), mesh)
            .map_err(|e| lc.rename_error(step.index, e))?;
        observer.phase_finished("assembly", t0.elapsed().as_secs_f64());
        m
    } else {
        base.clone()
    };
    scale_load(&mut m, step.value);
    Ok(m)
}

/// The discretisation step `index` of `case` was solved on, rebuilt on the mesh levels
/// `hierarchy` (to write or derive a step's results again without running the sweep).
pub fn step_discretization(
    case: &Case,
    index: usize,
    hierarchy: Hierarchy,
    observer: &mut dyn Observer,
) -> Result<Discretization> {
    let all = steps(case)?;
    let step = all.get(index).ok_or_else(|| {
        Error::Data(format!(
            "step {index} is not one of the {} steps of the case",
            all.len()
        ))
    })?;
    let mut d = Discretization::assemble(&case.problem, hierarchy, observer)?;
    d.model = step_model(case, step, &d.model, d.mesh(), observer)?;
    Ok(d)
}

/// What a sweep (or a set of load cases) produced: every step of the case, the rows of the
/// steps solved, and, when a step was not accepted, that step and the error naming how its
/// solve ended (the sweep stopped there; the step's row is the last).
#[derive(Debug)]
pub struct SweepRun {
    /// All the steps of the case, solved or not.
    pub steps: Vec<StepSpec>,
    /// One row per step solved, in order.
    pub rows: Vec<StepRow>,
    /// The step the settings did not accept, with its error.
    pub stopped: Option<(StepSpec, Error)>,
}

impl SweepRun {
    /// Whether every step was solved and accepted.
    pub fn accepted(&self) -> bool {
        self.stopped.is_none() && self.rows.len() == self.steps.len()
    }
}

/// Runs the steps of a case's `[sweep]` or `[[load_case]]` entries in turn on one mesh,
/// each warm-started from the previous answer (`warm = false`: every step from the usual
/// start). The case is validated, its mesh built and every step's data checked on it
/// before the first step is solved. `on_step` receives each step's outcome and row (to
/// write or keep them) before the next runs; a step the settings do not accept ends the
/// sweep after `on_step` has seen it ([`SweepRun::stopped`]). Bad input is an `Err`.
pub fn run_sweep(
    case: &Case,
    warm: bool,
    observer: &mut dyn Observer,
    on_step: &mut dyn FnMut(&StepSpec, &Outcome, &StepRow) -> Result<()>,
) -> Result<SweepRun> {
    case.validate().map_err(crate::error::Invalid::into_error)?;
    let observer = &mut crate::solve::Cancellable::new(observer, &case.settings.cancel);
    let base = Discretization::new(&case.problem, observer)?;
    run_sweep_on(case, base, warm, observer, on_step)
}

/// [`run_sweep`] on the base case's discretisation, built by the caller.
pub fn run_sweep_on(
    case: &Case,
    base: Discretization,
    warm: bool,
    observer: &mut dyn Observer,
    on_step: &mut dyn FnMut(&StepSpec, &Outcome, &StepRow) -> Result<()>,
) -> Result<SweepRun> {
    let steps = steps(case)?;
    if steps.is_empty() {
        return Err(Error::Case {
            file: None,
            line: None,
            key: "sweep".into(),
            message: "the case has no [sweep] and no [[load_case]]".into(),
        });
    }
    check_case_on_mesh(case, base.mesh(), false)?;
    let base_model = base.model.clone();
    let base_phases = base.phases.clone();
    let mut current = base;
    let mut start: Option<Vec<f64>> = None;
    let mut rows = Vec::with_capacity(steps.len());
    for step in &steps {
        case.settings.cancel.check()?;
        observer.step_started(step.index, steps.len(), &step.name);
        let t0 = Instant::now();
        current.model = step_model(case, step, &base_model, current.mesh(), observer)?;
        current.phases = base_phases.clone();
        if case.sweep.is_none() && case.load_cases[step.index].assembles() {
            // This step assembled its own model: its assembly time replaces the base's.
            let seconds = t0.elapsed().as_secs_f64();
            current.phases.retain(|p| p.name != "assembly");
            current.phases.push(Phase {
                name: "assembly".into(),
                seconds,
            });
        }
        crate::model::check_model(current.mesh(), &current.model)
            .map_err(|e| at_step(step, case, e))?;
        let report = current
            .solve_from(
                &case.settings,
                if warm { start.as_deref() } else { None },
                observer,
            )
            .map_err(|e| at_step(step, case, e))?;
        let seconds = t0.elapsed().as_secs_f64();
        let outcome = Outcome {
            discretization: current,
            report,
        };
        let row = StepRow::of(step, &outcome, seconds);
        on_step(step, &outcome, &row)?;
        rows.push(row);
        if let Some(e) = outcome.report.error() {
            let e = match e {
                Error::Solver { solver, message } => Error::Solver {
                    solver,
                    message: format!("{} ({}): {message}", step.name, step.value),
                },
                other => other,
            };
            let stopped = Some((step.clone(), e));
            return Ok(SweepRun {
                steps: steps.clone(),
                rows,
                stopped,
            });
        }
        let Outcome {
            discretization,
            report,
        } = outcome;
        start = Some(report.u);
        current = discretization;
    }
    Ok(SweepRun {
        steps,
        rows,
        stopped: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::Silent;

    const BASE: &str = r#"
[mesh]
generator = "rectangle"
nx = 8
[membrane]
tension = 2
load = "10 + x"
[obstacle]
shape = "0.1 + 0.05*y"
stiffness = 300
"#;

    #[test]
    fn a_scaled_model_is_the_model_of_the_scaled_data() {
        let case = Case::from_toml_str(BASE, None).unwrap();
        let base = Discretization::new(&case.problem, &mut Silent).unwrap();
        let check = |parameter, value, text: String| {
            let scaled = apply(&base.model, parameter, value);
            let other = Case::from_toml_str(&text, None).unwrap();
            let direct = Discretization::new(&other.problem, &mut Silent)
                .unwrap()
                .model;
            let close = |a: &[f64], b: &[f64]| {
                a.iter()
                    .zip(b)
                    .all(|(x, y)| (x - y).abs() <= 1e-13 * (1.0 + y.abs()))
            };
            assert!(close(&scaled.d, &direct.d), "{parameter:?} D");
            assert!(close(&scaled.s.val, &direct.s.val), "{parameter:?} S");
            assert!(close(&scaled.phi, &direct.phi), "{parameter:?} φ");
            let (FoundationMatrix::Consistent(a), FoundationMatrix::Consistent(b)) =
                (&scaled.l, &direct.l)
            else {
                panic!()
            };
            assert!(close(&a.val, &b.val), "{parameter:?} L");
        };
        check(
            SweepParameter::LoadFactor,
            1.5,
            BASE.replace("\"10 + x\"", "\"1.5*(10 + x)\""),
        );
        check(
            SweepParameter::StiffnessFactor,
            0.5,
            BASE.replace("stiffness = 300", "stiffness = 150"),
        );
        check(
            SweepParameter::Tension,
            3.0,
            BASE.replace("tension = 2", "tension = 3"),
        );
        check(
            SweepParameter::ObstacleOffset,
            0.2,
            BASE.replace("\"0.1 + 0.05*y\"", "\"0.3 + 0.05*y\""),
        );
    }

    #[test]
    fn sweep_values_and_refusals() {
        let spec = |t: &str| -> Case {
            Case::from_toml_str(&format!("{BASE}[sweep]\n{t}\n"), None).unwrap()
        };
        let c = spec("parameter = \"load_factor\"\nfrom = 0.5\nto = 1.5\nsteps = 3");
        let s = steps(&c).unwrap();
        assert_eq!(s.len(), 3);
        assert_eq!(s[1].value, 1.0);
        assert_eq!(s[2].name, "step-002");
        for bad in [
            "parameter = \"tension\"\nvalues = [1, -1]",
            "parameter = \"load_factor\"\nvalues = []",
            "parameter = \"load_factor\"\nfrom = 1\nto = 2",
            "parameter = \"load_factor\"\nvalues = [1]\nsteps = 3",
            "parameter = \"gravity\"\nvalues = [1]",
            // A declared count far beyond the limit is refused before any allocation.
            "parameter = \"load_factor\"\nfrom = 0\nto = 1\nsteps = 100000000000",
        ] {
            let e = Case::from_toml_str(&format!("{BASE}[sweep]\n{bad}\n"), None).unwrap_err();
            assert!(e.to_string().contains("sweep"), "{bad}: {e}");
        }
        let e = Case::from_toml_str(&format!("{BASE}[[load_case]]\nname = \"../x\"\n"), None)
            .unwrap_err();
        assert!(e.to_string().contains("load_case.0.name"), "{e}");
    }

    #[test]
    fn load_case_errors_name_the_load_case() {
        let case = |t: &str| Case::from_toml_str(&format!("{BASE}{t}"), None);
        let e = case("[[load_case]]\nname = \"a\"\nstiffness = -2\n").unwrap_err();
        assert!(e.to_string().contains("load_case.0.stiffness"), "{e}");
        let e = case("[[load_case]]\nname = \"a\"\nload = nan\n").unwrap_err();
        assert!(e.to_string().contains("load_case.0.load"), "{e}");
        // A region the mesh lacks: found on the mesh, before any step.
        let c = case(
            "[[load_case]]\nname = \"a\"\n[[load_case]]\nname = \"b\"\n\
             shape = { clay = 0.2 }\n",
        )
        .unwrap();
        let d = Discretization::new(&c.problem, &mut Silent).unwrap();
        for assemble in [false, true] {
            let e = crate::discretization::case_checks::check_load_cases_on_mesh(
                &c,
                d.mesh(),
                assemble,
            )
            .unwrap_err()
            .to_string();
            assert!(e.contains("load_case.1.shape") && e.contains("clay"), "{e}");
        }
        let mut solved = 0;
        let e = run_sweep(&c, true, &mut Silent, &mut |_, _, _| {
            solved += 1;
            Ok(())
        })
        .unwrap_err();
        assert!(e.to_string().contains("load_case.1.shape"), "{e}");
        assert_eq!(solved, 0, "no step was solved");
    }

    #[test]
    fn a_rebuilt_step_has_the_model_it_was_solved_on() {
        for steps in [
            "[sweep]\nparameter = \"obstacle_offset\"\nvalues = [0, -0.05]\n",
            "[[load_case]]\nname = \"a\"\nload_factor = 2\n\
             [[load_case]]\nname = \"b\"\nload = \"5 + y\"\nload_factor = 0.5\n",
        ] {
            let case = Case::from_toml_str(&format!("{BASE}{steps}"), None).unwrap();
            let mut models = Vec::new();
            run_sweep(&case, true, &mut Silent, &mut |_, o, _| {
                models.push(o.discretization.model.clone());
                Ok(())
            })
            .unwrap();
            let (hierarchy, _) = crate::discretization::build_mesh(&case.problem.mesh).unwrap();
            for (k, m) in models.iter().enumerate() {
                let d = step_discretization(&case, k, hierarchy.clone(), &mut Silent).unwrap();
                assert_eq!(d.model.d, m.d, "{steps} step {k}: D");
                assert_eq!(d.model.phi, m.phi, "{steps} step {k}: φ");
                assert_eq!(d.model.s.val, m.s.val, "{steps} step {k}: S");
                assert_eq!(d.model.h_vertices, m.h_vertices, "{steps} step {k}: h");
            }
        }
    }

    #[test]
    fn warm_and_cold_sweeps_give_the_same_answers() {
        // Multigrid (the 8 × 8 rectangle has a hierarchy) and the active-set method.
        for method in ["auto", "active-set"] {
            let case = Case::from_toml_str(
                &format!(
                    "{BASE}[solver]\nmethod = \"{method}\"\n[sweep]\n\
                     parameter = \"load_factor\"\nvalues = [0.5, 1, 1.5, 2, 2.5]\n"
                ),
                None,
            )
            .unwrap();
            let mut warm_u = Vec::new();
            let warm = run_sweep(&case, true, &mut Silent, &mut |_, o, _| {
                warm_u.push(o.report.u.clone());
                Ok(())
            })
            .unwrap()
            .rows;
            let mut k = 0;
            let cold = run_sweep(&case, false, &mut Silent, &mut |s, o, _| {
                // Each step equals the base case solved with the scaled load.
                let scaled = Case::from_toml_str(
                    &BASE.replace("\"10 + x\"", &format!("\"{}*(10 + x)\"", s.value)),
                    None,
                )
                .unwrap();
                let direct = crate::run(&scaled, &mut Silent).unwrap();
                for (a, b) in o.report.u.iter().zip(&direct.report.u) {
                    assert!((a - b).abs() <= 1e-9 * b.abs().max(1e-3));
                }
                for (a, b) in o.report.u.iter().zip(&warm_u[k]) {
                    assert!((a - b).abs() <= 1e-9 * b.abs().max(1e-3));
                }
                k += 1;
                Ok(())
            })
            .unwrap()
            .rows;
            assert_eq!(warm.len(), 5);
            assert_eq!(cold.len(), 5);
            // Load up, deflection up.
            assert!(warm
                .windows(2)
                .all(|w| w[1].max_deflection > w[0].max_deflection));
            // Warm starts save iterations.
            let total = |rows: &[StepRow]| rows.iter().map(|r| r.iterations).sum::<usize>();
            assert!(
                total(&warm) < total(&cold),
                "{method}: warm {} cold {}",
                total(&warm),
                total(&cold)
            );
        }
    }
}
