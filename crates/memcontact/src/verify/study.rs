//! The convergence study of a case (the paper's main result, `u_n → u` in H¹, measured):
//! the case's `[exact]` section made an exact solution, the manufactured data replacing the
//! case's where it says so, the h-sweep over `levels` refinements for each variant
//! (`compare`: consistent against lumped L, or nodal against mollified φ), or the
//! rigid-limit sweep. The numerics of a study are in [`super::convergence`]; the files are
//! written by [`crate::write::write_study`].

use super::convergence::{
    rigid_limit_sweep, run_with, LevelResult, ManufacturedLoad, RigidLimit, Study, StudySettings,
    Target,
};
use super::exact_case::{check_benchmark, parse_exact, Exact, ExactHeight};
use crate::case::Case;
use crate::discretization::{build_mesh, BoundData};
use crate::error::{Error, Result};
use crate::field::Coefficient;
use crate::mesh::refine::Hierarchy;
use crate::model::{BoundaryData, Foundation, ProblemData, Sampling};
use crate::verify::exact::ExactSolution;

/// The stiffnesses of the rigid-limit sweep when none are given: 10, 10², ..., 10⁶.
pub const DEFAULT_H_VALUES: [f64; 6] = [1e1, 1e2, 1e3, 1e4, 1e5, 1e6];

/// The most refinement levels a study accepts (each multiplies the triangles by 4).
pub const MAX_LEVELS: usize = 10;

/// Which variants a study compares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compare {
    /// The paper's consistent foundation matrix against the lumped diagonal.
    Foundation,
    /// Nodal sampling of φ against the paper's mollified sampling.
    Sampling,
}

/// What a study does: the refinement levels, and either the variants to compare or the
/// stiffnesses of the rigid-limit sweep.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StudyOptions {
    /// Refinement levels beyond the case's mesh (K ≥ 1: K + 1 meshes are solved). For the
    /// rigid-limit sweep: the fixed mesh is the case's mesh refined K times (K ≥ 0).
    pub levels: usize,
    /// The variants to compare (`None`: the case itself).
    pub compare: Option<Compare>,
    /// The rigid-limit sweep instead of the study, with these stiffnesses (empty:
    /// [`DEFAULT_H_VALUES`]).
    pub h_sweep: Option<Vec<f64>>,
}

/// One variant of the problem: the case itself (`name` empty), or one side of a
/// comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variant {
    /// `""`, `consistent`, `lumped`, `nodal` or `mollified`.
    pub name: &'static str,
    /// The foundation matrix.
    pub foundation: Foundation,
    /// The sampling of φ.
    pub sampling: Sampling,
}

impl Variant {
    /// The file of its study: `convergence.csv`, or `convergence-<name>.csv`.
    pub fn csv_name(&self) -> String {
        if self.name.is_empty() {
            "convergence.csv".to_string()
        } else {
            format!("convergence-{}.csv", self.name)
        }
    }
}

/// The variants of `case` that `compare` asks for.
pub fn variants(case: &Case, compare: Option<Compare>) -> Vec<Variant> {
    let o = &case.problem.obstacle;
    match compare {
        None => vec![Variant {
            name: "",
            foundation: o.foundation,
            sampling: o.sampling(),
        }],
        Some(Compare::Foundation) => {
            let sampling = o.sampling();
            vec![
                Variant {
                    name: "consistent",
                    foundation: Foundation::Consistent,
                    sampling,
                },
                Variant {
                    name: "lumped",
                    foundation: Foundation::Lumped,
                    sampling,
                },
            ]
        }
        Some(Compare::Sampling) => vec![
            Variant {
                name: "nodal",
                foundation: o.foundation,
                sampling: Sampling::Nodal,
            },
            Variant {
                name: "mollified",
                foundation: o.foundation,
                sampling: Sampling::Mollified { epsilon: o.epsilon },
            },
        ],
    }
}

/// What a study found.
pub enum StudyResult {
    /// The convergence study of each variant, in order.
    Convergence(Vec<(Variant, Study)>),
    /// The rigid-limit sweep on the fixed mesh.
    RigidLimit {
        /// The variant swept (the case's own).
        variant: Variant,
        /// The fixed mesh's levels.
        hierarchy: Hierarchy,
        /// The distances to the rigid solution.
        sweep: RigidLimit,
        /// For the disc: the same distance between the exact solutions, max over the
        /// vertices, per stiffness.
        exact_distance: Vec<Option<f64>>,
    },
}

/// A study of a case: its exact solution (when it has one), the warnings of its mesh, and
/// what it found.
pub struct StudyOutcome {
    /// The exact solution of `[exact]` (`None`: errors against the finest level's solution).
    pub exact: Option<Exact>,
    /// Warnings from reading the mesh.
    pub warnings: Vec<String>,
    /// The study, or the rigid-limit sweep.
    pub result: StudyResult,
}

impl StudyOutcome {
    /// The note on what the errors are measured against, when it is not an exact solution.
    pub fn reference_note(&self) -> Option<String> {
        let StudyResult::Convergence(studies) = &self.result else {
            return None;
        };
        match (&self.exact, studies.len()) {
            (Some(_), _) => None,
            (None, 1) => Some("errors against the finest level's solution".to_string()),
            (None, _) => Some(format!(
                "errors of every variant against the finest level of the {} variant",
                studies[0].0.name
            )),
        }
    }
}

/// Runs the convergence study of `case` (or its rigid-limit sweep) as `options` say.
/// `on_level` sees each level of each variant as soon as it is solved (the variant, the
/// level); `on_sweep_start` is told the vertices of the fixed mesh and the stiffnesses
/// before the rigid-limit sweep runs.
pub fn run_study(
    case: &Case,
    options: &StudyOptions,
    on_level: &mut dyn FnMut(&Variant, &LevelResult),
    on_sweep_start: &mut dyn FnMut(usize, &[f64]),
) -> Result<StudyOutcome> {
    let sweep = options.h_sweep.as_ref();
    if options.levels == 0 && sweep.is_none() {
        return Err(Error::case(
            "--levels must be at least 1 for a convergence study (K + 1 meshes are solved)",
        ));
    }
    case.validate().map_err(crate::error::Invalid::into_error)?;
    let exact = parse_exact(case)?;
    if options.levels > MAX_LEVELS {
        return Err(Error::case(format!(
            "--levels {} is too large (at most {MAX_LEVELS}: each level multiplies the triangles by 4)",
            options.levels
        )));
    }
    let (mut hierarchy, warnings) = build_mesh(&case.problem.mesh)?;
    let fields = BoundData::new(&case.problem, hierarchy.finest())?;
    if let Some(Exact::Benchmark(b)) = &exact {
        check_benchmark(b, case, hierarchy.finest(), &fields)?;
    }
    let t = case.problem.membrane.tension;
    let manufactured_load;
    let load: &dyn Coefficient = match &exact {
        Some(e) if e.manufactured() => {
            manufactured_load = ManufacturedLoad {
                exact: e.solution(),
                tension: t,
                stiffness: fields
                    .stiffness
                    .as_ref()
                    .expect("elastic, checked by parse_exact"),
                shape: &fields.shape,
                lower: fields.lower.as_ref().map(|b| {
                    (
                        b.stiffness
                            .as_ref()
                            .expect("elastic, checked by parse_exact")
                            as &dyn Coefficient,
                        &b.shape as &dyn Coefficient,
                    )
                }),
            };
            &manufactured_load
        }
        _ => &fields.load,
    };
    // The data beyond the paper's frame; a manufactured u also gives the fixed boundary
    // its heights.
    let exact_height = exact.as_ref().map(|e| ExactHeight(e.solution()));
    let mut extensions = fields.extensions(&case.problem);
    if let (Some(e), Some(h)) = (&exact, &exact_height) {
        if e.manufactured() {
            extensions.boundary = Some(BoundaryData {
                free: &case.problem.boundary.free,
                height: h,
            });
        }
    }
    // The problem data of one variant (foundation, sampling) of the case.
    let data_for = |v: &Variant| ProblemData {
        load,
        foundation: v.foundation,
        sampling: v.sampling,
        ..fields.data(&case.problem)
    };
    let settings = case.settings.clone();
    if let Some(hs) = sweep {
        let base = crate::limits::MeshSize::of(hierarchy.finest());
        crate::limits::check_mesh_fits(
            base,
            options.levels,
            &format!(
                "--h-sweep --levels {} on a mesh of {:.0} triangles",
                options.levels, base.triangles
            ),
        )?;
        hierarchy.refine(options.levels);
        let hs: Vec<f64> = if hs.is_empty() {
            DEFAULT_H_VALUES.to_vec()
        } else {
            hs.clone()
        };
        let variant = variants(case, None)[0];
        on_sweep_start(hierarchy.finest().n_vertices(), &hs);
        let sweep = rigid_limit_sweep(&hierarchy, &data_for(&variant), &hs, &settings)?;
        let exact_distance = exact_distances(&exact, &hierarchy, &sweep)?;
        return Ok(StudyOutcome {
            exact,
            warnings,
            result: StudyResult::RigidLimit {
                variant,
                hierarchy,
                sweep,
                exact_distance,
            },
        });
    }
    let study_settings = StudySettings {
        levels: options.levels,
        solver: settings,
    };
    let mut studies: Vec<(Variant, Study)> = Vec::new();
    for v in variants(case, options.compare) {
        let data = data_for(&v);
        let target = match (&exact, studies.first()) {
            (Some(e), _) => Target::Exact(e.solution()),
            (None, None) => Target::Finest,
            (None, Some((_, first))) => Target::Discrete(&first.finest_u),
        };
        let s = run_with(
            hierarchy.clone(),
            &data,
            &extensions,
            target,
            &study_settings,
            &mut |r| on_level(&v, r),
        )?;
        studies.push((v, s));
    }
    Ok(StudyOutcome {
        exact,
        warnings,
        result: StudyResult::Convergence(studies),
    })
}

/// For the disc, the max over the fixed mesh's vertices of the distance between the exact
/// solutions with each stiffness of the sweep and the rigid one.
fn exact_distances(
    exact: &Option<Exact>,
    hierarchy: &Hierarchy,
    sweep: &RigidLimit,
) -> Result<Vec<Option<f64>>> {
    let mesh = hierarchy.finest();
    sweep
        .rows
        .iter()
        .map(|r| -> Result<Option<f64>> {
            let Some(Exact::Disk(d)) = exact else {
                return Ok(None);
            };
            let rigid = d.with_stiffness(None)?;
            let elastic = d.with_stiffness(Some(r.h))?;
            Ok(Some(mesh.points.iter().fold(0.0f64, |m, &p| {
                m.max((elastic.value(p) - rigid.value(p)).abs())
            })))
        })
        .collect::<Result<_>>()
        .map_err(|e| e.context("the disc's exact solutions for the sweep"))
}
