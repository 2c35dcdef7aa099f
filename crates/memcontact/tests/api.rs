//! The library's front door, used as a Rust program would: a case built from TOML and the
//! same case built from Rust values give the same run; `run` reports every status with the
//! iterate and its certificate; result sets are written without the command-line tool.

use memcontact::discretization::Discretization;
use memcontact::field::{Field, Stiffness};
use memcontact::model::Foundation;
use memcontact::problem::{Membrane, MeshSource, MeshSpec, Obstacle, SamplingKind};
use memcontact::solve::{Method, Silent, Status};
use memcontact::write::{write_result_set, WriteOptions};
use memcontact::{run, Case, Problem, Settings, Summary};
use std::time::Instant;

const SQUARE: &str = r#"
[mesh]
generator = "rectangle"
nx = 16

[membrane]
tension = 1.0
load = "20"

[obstacle]
shape = "0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)"
stiffness = 1000.0
"#;

/// The square case written as Rust values.
fn problem_in_rust() -> Problem {
    Problem {
        mesh: MeshSpec {
            source: MeshSource::Rectangle {
                x0: 0.0,
                y0: 0.0,
                x1: 1.0,
                y1: 1.0,
                nx: 16,
                ny: 16,
                diagonal: memcontact::mesh::generate::Diagonal::Right,
            },
            refine: 0,
        },
        membrane: Membrane {
            tension: 1.0,
            load: Field::from(20.0),
        },
        obstacle: Obstacle {
            shape: Field::parse("0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)").unwrap(),
            stiffness: Stiffness::Elastic(Field::from(1000.0)),
            foundation: Foundation::Consistent,
            sampling: SamplingKind::Nodal,
            epsilon: None,
        },
        boundary: Default::default(),
        lower: None,
    }
}

#[test]
fn toml_rust_and_json_describe_the_same_problem_and_run_alike() {
    let from_toml = Case::from_toml_str(SQUARE, None).unwrap();
    assert_eq!(from_toml.problem, problem_in_rust());
    let json = serde_json::to_string(&from_toml).unwrap();
    assert_eq!(Case::from_json_str(&json).unwrap(), from_toml);
    let a = run(&from_toml, &mut Silent).unwrap();
    let b = run(&Case::new(problem_in_rust()), &mut Silent).unwrap();
    assert_eq!(a.status(), Status::Converged);
    assert_eq!(a.report.u, b.report.u);
    assert!(a.report.certificate.kkt() <= 1e-10);
    // The certificate the report carries is the one of its iterate.
    let c = a.discretization.model.certificate(&a.report.u);
    assert_eq!(c, a.report.certificate);
    // The phases of the run are named and timed.
    for name in ["mesh", "assembly", "solve"] {
        assert!(a.report.phases.iter().any(|p| p.name == name), "{name}");
    }
}

#[test]
fn every_status_carries_the_iterate_and_its_certificate() {
    let case = Case::from_toml_str(SQUARE, None).unwrap();
    let d = Discretization::new(&case.problem, &mut Silent).unwrap();
    let check = |status: Status, settings: &Settings| {
        let r = d.solve(settings, &mut Silent).unwrap();
        assert_eq!(r.status, status, "{settings:?}");
        assert_eq!(r.u.len(), d.model.n());
        assert_eq!(r.certificate, d.model.certificate(&r.u));
        assert_eq!(r.accepted, status.is_accepted(settings));
        if !r.accepted {
            let e = r.error().unwrap().to_string();
            assert!(e.contains(&format!("{:.3e}", r.certificate.kkt())), "{e}");
        }
        r
    };
    // One iteration is not enough.
    for method in [
        Method::ActiveSet,
        Method::Multigrid,
        Method::Coordinate,
        Method::Qp,
    ] {
        let s = Settings {
            method,
            max_iterations: Some(1),
            ..Settings::default()
        };
        let r = check(Status::IterationLimit, &s);
        assert_eq!(r.iterations, 1, "{}", method.name());
        assert!(r.certificate.kkt() > s.tolerance);
    }
    // A tolerance below what double precision resolves: the solve stops at the rounding
    // floor; accepted by default, refused when asked to be strict.
    let tight = Settings {
        method: Method::ActiveSet,
        tolerance: 1e-18,
        ..Settings::default()
    };
    let r = check(Status::RoundingFloor, &tight);
    assert!(r.certificate.kkt() <= 8.0 * r.certificate.rounding_floor);
    let strict = Settings {
        accept_rounding_floor: false,
        ..tight
    };
    check(Status::RoundingFloor, &strict);
    // A foundation 10²⁰ times stiffer than the membrane: the solve cannot balance the
    // forces; whatever stopped it, the report has an iterate, its certificate, and a
    // message that explains the conditioning.
    let text = SQUARE
        .replace("tension = 1.0", "tension = 1e-8")
        .replace("load = \"20\"", "load = 1e-7")
        .replace("stiffness = 1000.0", "stiffness = 1e12");
    let stiff = Case::from_toml_str(&text, None).unwrap();
    let d2 = Discretization::new(&stiff.problem, &mut Silent).unwrap();
    let s = Settings {
        method: Method::ActiveSet,
        ..Settings::default()
    };
    let r = d2.solve(&s, &mut Silent).unwrap();
    assert!(
        matches!(
            r.status,
            Status::NumericalFailure | Status::Stalled | Status::IterationLimit
        ),
        "{:?}",
        r.status
    );
    assert_eq!(r.certificate, d2.model.certificate(&r.u));
    assert!(r.error().unwrap().to_string().contains("rigid"));
    // On the same data the interior-point method stops short of its iteration limit (no
    // more progress), far above the rounding floor: stalled, with its iterate and
    // certificate.
    let qp = Settings {
        method: Method::Qp,
        ..Settings::default()
    };
    let r = d2.solve(&qp, &mut Silent).unwrap();
    assert_eq!(r.status, Status::Stalled);
    assert!(r.iterations >= 1 && r.iterations < Method::Qp.default_max_iterations());
    assert_eq!(r.u.len(), d2.model.n());
    assert_eq!(r.certificate, d2.model.certificate(&r.u));
    assert!(r.certificate.kkt() > 1e6 * r.certificate.rounding_floor);
    assert!(!r.accepted);
    let e = r.error().unwrap().to_string();
    assert!(e.contains("stalled after"), "{e}");
    assert!(e.contains(&format!("{:.3e}", r.certificate.kkt())), "{e}");
}

#[test]
fn auto_records_its_choice() {
    let case = Case::from_toml_str(SQUARE, None).unwrap();
    let r = run(&case, &mut Silent).unwrap().report;
    assert_eq!(r.requested, Method::Auto);
    assert_eq!(r.method, Method::Multigrid);
    assert_eq!(r.choice, memcontact::solve::Choice::GeometricHierarchy);
    let free =
        Case::from_toml_str(&SQUARE.replace("stiffness = 1000.0", "stiffness = 0"), None).unwrap();
    let r = run(&free, &mut Silent).unwrap().report;
    assert_eq!(r.method, Method::Linear);
    assert_eq!(r.choice, memcontact::solve::Choice::LinearProblem);
}

#[test]
fn a_result_set_is_written_and_read_back_without_the_cli() {
    let case = Case::from_toml_str(SQUARE, None).unwrap();
    let outcome = run(&case, &mut Silent).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("result");
    let options = WriteOptions {
        label: "square".into(),
        vtu: case.output.vtu,
        force: false,
        started: Instant::now(),
        plot_options: None,
        run_id: None,
        cell_data: Vec::new(),
        adapt: None,
        unconverged: false,
    };
    let written =
        write_result_set(&out, &outcome, &case, &options, &mut |_, _| Ok(vec![])).unwrap();
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let summary: Summary = serde_json::from_str(&text).unwrap();
    assert_eq!(summary.run_id, written.run_id);
    assert_eq!(summary.status, Status::Converged);
    assert!(summary.accepted && summary.converged);
    // Every file is listed with its size and hash, and matches.
    for name in ["solution.vtu", "nodes.csv"] {
        let rec = &summary.files[name];
        assert_eq!(
            rec,
            &memcontact::write::file_record(&out.join(name)).unwrap()
        );
    }
    // nodes.csv, read independently, holds U at the interior vertices.
    let csv = std::fs::read_to_string(out.join("nodes.csv")).unwrap();
    let u: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
        .collect();
    let expect = outcome
        .discretization
        .model
        .dofs
        .to_vertices(&outcome.report.u, 0.0);
    assert_eq!(u, expect);
}

#[test]
fn a_run_to_files_solves_alike_writes_and_then_refuses_to_solve_again() {
    let disk = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/disk.toml"),
    )
    .unwrap()
    .replace("refine = 0", "refine = 2");
    let lumped = SQUARE.replace(
        "stiffness = 1000.0",
        "stiffness = 1000.0\nfoundation = \"lumped\"",
    );
    for (name, text) in [
        ("square", SQUARE),
        ("square, lumped", &lumped),
        ("disk", &disk),
    ] {
        let case = Case::from_toml_str(text, None).unwrap();
        let a = run(&case, &mut Silent).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let w = memcontact::run::run_to_files(
            &case,
            &dir.path().join("out"),
            &WriteOptions::new(name),
            &mut Silent,
        )
        .unwrap();
        let summary = w.summary.expect("written");
        assert_eq!(summary.iterations, a.report.iterations, "{name}");
        for file in [
            "solution.vtu",
            "nodes.csv",
            "summary.json",
            "deflection.png",
        ] {
            assert!(
                dir.path().join("out").join(file).is_file(),
                "{name}: {file}"
            );
        }
        let b = w.outcome;
        assert_eq!(a.report.method, Method::Multigrid, "{name}");
        assert_eq!(a.report.u, b.report.u, "{name}");
        assert_eq!(a.report.iterations, b.report.iterations, "{name}");
        assert_eq!(a.report.certificate, b.report.certificate, "{name}");
        let (fa, ta) = a.checked_fields().unwrap();
        let (fb, tb) = b.checked_fields().unwrap();
        assert_eq!(fa.u, fb.u, "{name}");
        assert_eq!(fa.contact_force, fb.contact_force, "{name}");
        assert_eq!(ta.total_contact_force, tb.total_contact_force, "{name}");
        assert_eq!(
            a.discretization.hierarchy.depth(),
            b.discretization.hierarchy.depth(),
            "{name}"
        );
        // The finest mesh, released during the solve, is back as it was.
        let (ma, mb) = (a.discretization.mesh(), b.discretization.mesh());
        assert_eq!(ma.points, mb.points, "{name}");
        assert_eq!(ma.triangles, mb.triangles, "{name}");
        assert_eq!(ma.regions, mb.regions, "{name}");
        // Its matrices are gone: a second solve is an error, not a crash.
        let e = b
            .discretization
            .solve(&case.settings, &mut Silent)
            .unwrap_err();
        assert!(e.to_string().contains("solve it again"), "{e}");
    }
}
