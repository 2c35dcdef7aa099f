//! The keys, types and meanings of `summary.json` are a contract: this snapshot pins them
//! on three example cases (an imported mesh with two soils, consistent and lumped, and the
//! rigid square). Times vary
//! from run to run and certificates are only meaningful up to the tolerance, so they are
//! normalised; every other number is kept to 6 significant digits (the solution is
//! deterministic, but the last digits may move with the summation order of a solver).

use serde_json::Value;

mod common;
use common::{examples, run, text};

/// Keys whose values are times (seconds).
fn is_time(key: &str) -> bool {
    key.starts_with("time_") || key.ends_with("_s")
}

/// Keys whose values are residuals compared with the tolerance.
fn is_residual(key: &str) -> bool {
    matches!(
        key,
        "kkt_residual" | "residual_2e" | "residual_2f" | "residual"
    )
}

fn round(x: f64) -> Value {
    if x == 0.0 || !x.is_finite() {
        return serde_json::json!(x);
    }
    let s = format!("{x:.5e}");
    Value::String(s)
}

/// Normalises a summary for the snapshot (see the module doc).
fn normalise(key: &str, v: &Value, tolerance: f64) -> Value {
    match v {
        Value::Object(m) => Value::Object(
            m.iter()
                .map(|(k, v)| {
                    let nv = if k == "files" {
                        // The names of the files are pinned; sizes and hashes vary.
                        Value::Object(
                            v.as_object()
                                .unwrap()
                                .keys()
                                .map(|f| (f.clone(), Value::String("[file record]".into())))
                                .collect(),
                        )
                    } else if k == "run_id" || k == "input_hash" {
                        let id = v.as_str().unwrap();
                        assert!(id.len() >= 16 && id.chars().all(|c| c.is_ascii_hexdigit()));
                        Value::String("[hex id]".into())
                    } else if k == "solver_phases_s" {
                        // Each method names its own phases; all are times.
                        let phases = v.as_object().unwrap();
                        assert!(phases.values().all(|t| t.as_f64().unwrap() >= 0.0));
                        Value::String("[phase times]".into())
                    } else {
                        normalise(k, v, tolerance)
                    };
                    (k.clone(), nv)
                })
                .collect(),
        ),
        Value::Array(a) if key == "history" => {
            // One record per iteration: its keys are pinned, the values are not (how a
            // solver gets to the answer may improve).
            Value::Array(
                a.iter()
                    .take(1)
                    .map(|r| {
                        Value::Object(
                            r.as_object()
                                .unwrap()
                                .keys()
                                .map(|k| (k.clone(), Value::String("[value]".into())))
                                .collect(),
                        )
                    })
                    .collect(),
            )
        }
        Value::Array(a) => Value::Array(a.iter().map(|x| normalise(key, x, tolerance)).collect()),
        Value::Number(n) if is_time(key) => {
            assert!(n.as_f64().unwrap() >= 0.0, "{key} = {n}");
            Value::String("[time]".into())
        }
        Value::Number(n) if is_residual(key) => {
            let r = n.as_f64().unwrap();
            assert!(r <= tolerance, "{key} = {r} above the tolerance");
            Value::String("[≤ tolerance]".into())
        }
        Value::Number(n) if key == "rounding_floor" => {
            let f = n.as_f64().unwrap();
            assert!(f > 0.0 && f < tolerance, "{key} = {f}");
            Value::String("[below the tolerance]".into())
        }
        Value::Number(n) if key == "force_scale" || key == "iterations" => {
            assert!(n.as_f64().unwrap() > 0.0);
            Value::String("[positive]".into())
        }
        Value::Number(n) if n.is_f64() => round(n.as_f64().unwrap()),
        Value::String(_) if key == "case" || key == "title" => Value::String("[case path]".into()),
        other => other.clone(),
    }
}

fn snapshot_of(case: &str, sets: &[&str]) -> Value {
    let out = tempfile::tempdir().unwrap();
    let case = examples().join(case);
    let mut args = vec![
        "solve",
        case.to_str().unwrap(),
        "-o",
        out.path().to_str().unwrap(),
        "-q",
    ];
    for s in sets {
        args.push("--set");
        args.push(s);
    }
    let o = run(&args);
    assert!(o.status.success(), "{}", text(&o));
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("summary.json")).unwrap())
            .unwrap();
    let tol = s["tolerance"].as_f64().unwrap();
    normalise("", &s, tol)
}

#[test]
fn summary_of_the_gmsh_disk() {
    insta::assert_json_snapshot!(snapshot_of(
        "gmsh-disk.toml",
        &["solver.method=\"active-set\""]
    ));
}

#[test]
fn summary_of_the_lumped_gmsh_disk() {
    insta::assert_json_snapshot!(snapshot_of(
        "gmsh-disk.toml",
        &[
            "obstacle.foundation=\"lumped\"",
            "solver.method=\"active-set\""
        ]
    ));
}

#[test]
fn summary_of_the_rigid_square() {
    insta::assert_json_snapshot!(snapshot_of(
        "rigid-square.toml",
        &["solver.method=\"active-set\""]
    ));
}
