//! End-to-end tests: the `memcontact` binary on real case files, checking the files it
//! writes and the errors it reports.

use std::path::{Path, PathBuf};

mod common;
use common::{examples, run, text};

fn tmp(name: &str) -> common::Tmp {
    common::tmp_in("e2e", name)
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn solves_the_disk_example_and_writes_consistent_files() {
    let out = tmp("disk");
    let case = examples().join("disk.toml");
    let o = run(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("certificate"));
    let s = summary(&out);
    for key in [
        "vertices",
        "triangles",
        "unknowns",
        "solver",
        "foundation",
        "iterations",
        "energy",
        "kkt_residual",
        "contact_area",
        "total_load",
        "total_contact_force",
        "max_deflection",
        "time_total_s",
    ] {
        assert!(s.get(key).is_some(), "summary.json lacks {key}");
    }
    assert!(s["kkt_residual"].as_f64().unwrap() <= 1e-9);
    assert_eq!(s["foundation"], "consistent");
    let png = std::fs::read(out.join("deflection.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // Load = f × area of Ω_n (the disc's inscribed polygon, within 2% of π).
    let load = s["total_load"].as_f64().unwrap();
    assert!((load / 8.0 - std::f64::consts::PI).abs() < 0.02 * std::f64::consts::PI);
    // The obstacle carries part of the load: 0 < Σ X₁ < ∫ f.
    let force = s["total_contact_force"].as_f64().unwrap();
    assert!(force > 0.0 && force < load);

    let csv = std::fs::read_to_string(out.join("nodes.csv")).unwrap();
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert!(header.starts_with("x,y,u,phi,penetration,pressure,contact_force,state"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
        .collect();
    assert_eq!(rows.len() as u64, s["vertices"].as_u64().unwrap());
    // Boundary vertices (on the unit circle) have u = 0; penetration = (u - φ)⁺;
    // pressure = h × penetration; states match the sign of u - φ.
    for r in &rows {
        let (x, y, u, phi, pen, p, _x1, st) = (r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7]);
        if (x * x + y * y).sqrt() > 1.0 - 1e-9 {
            assert_eq!(u, 0.0);
        }
        assert!((pen - (u - phi).max(0.0)).abs() <= 1e-15);
        assert!((p - 100.0 * pen).abs() <= 1e-12);
        if st == 1.0 {
            assert!(u > phi);
        }
    }
    assert!(rows.iter().any(|r| r[7] == 1.0) && rows.iter().any(|r| r[7] == -1.0));
    let vtu = std::fs::read_to_string(out.join("solution.vtu"))
        .or_else(|_| {
            std::fs::read(out.join("solution.vtu"))
                .map(|b| String::from_utf8_lossy(&b).into_owned())
        })
        .unwrap();
    for name in [
        "\"u\"",
        "\"phi\"",
        "\"penetration\"",
        "\"pressure\"",
        "\"contact_force\"",
        "\"state\"",
        "\"region\"",
    ] {
        assert!(vtu.contains(name), "solution.vtu lacks {name}");
    }
}

#[test]
fn set_overrides_keys_and_lumped_differs_from_consistent() {
    let case = examples().join("bench-square.toml");
    let mut energies = Vec::new();
    for f in ["consistent", "lumped"] {
        let out = tmp(&format!("bench-{f}"));
        let o = run(&[
            "solve",
            case.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
            "--set",
            "mesh.nx=16",
            "--set",
            "mesh.ny=16",
            "--set",
            &format!("obstacle.foundation={f}"),
        ]);
        assert!(o.status.success(), "{}", text(&o));
        let s = summary(&out);
        assert_eq!(s["vertices"].as_u64().unwrap(), 17 * 17);
        assert_eq!(s["foundation"], f);
        energies.push(s["energy"].as_f64().unwrap());
    }
    assert!((energies[0] - energies[1]).abs() > 1e-6 * energies[0].abs());
}

#[test]
fn csv_false_writes_no_node_table_and_the_same_solution() {
    let case = examples().join("bench-square.toml");
    let solve = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "solve",
            case.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
            "--set",
            "mesh.nx=24",
            "--set",
            "mesh.ny=24",
            "--set",
            "output.plot=false",
        ];
        args.extend_from_slice(extra);
        let o = run(&args);
        assert!(o.status.success(), "{}", text(&o));
    };
    let (with, without) = (tmp("csv-true"), tmp("csv-false"));
    solve(&with, &[]);
    solve(&without, &["--set", "output.csv=false"]);
    assert!(with.join("nodes.csv").exists());
    assert!(!without.join("nodes.csv").exists());
    let (a, b) = (summary(&with), summary(&without));
    assert!(a["files"].get("nodes.csv").is_some());
    assert!(b["files"].get("nodes.csv").is_none(), "{}", b["files"]);
    assert!(b["files"].get("solution.vtu").is_some());
    // The solve is the same: the same energy, certificate and contact set.
    for key in ["energy", "kkt_residual", "iterations", "contact_area"] {
        assert_eq!(a[key], b[key], "{key}");
    }
}

#[test]
fn check_reports_the_mesh() {
    let case = examples().join("roof.toml");
    let o = run(&["check", case.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let t = text(&o);
    assert!(t.contains("valid") && t.contains("vertices") && t.contains("l_n"));
    assert!(t.contains("block"), "{t}");
}

#[test]
fn example_lists_and_writes() {
    let o = run(&["example"]);
    assert!(o.status.success());
    for n in ["disk", "roof", "bench-square", "rigid-square", "gmsh-disk"] {
        assert!(text(&o).contains(n));
    }
    let d = tmp("example");
    let o = run(&["example", "gmsh-disk", "--dir", d.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(d.join("gmsh-disk.toml").exists() && d.join("disk.msh").exists());
    // The written example runs where it was written (paths are relative to the case).
    let out = d.join("out");
    let o = run(&[
        "solve",
        d.join("gmsh-disk.toml").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(out.join("summary.json").exists());
    let o = run(&["example", "nope"]);
    assert!(!o.status.success());
}

/// Writes a case with `body` and returns its path.
fn case_file(dir: &Path, body: &str) -> PathBuf {
    let p = dir.join("case.toml");
    std::fs::write(&p, body).unwrap();
    p
}

const GOOD: &str = r#"
[mesh]
generator = "rectangle"
nx = 8
[membrane]
tension = 1.0
load = "8"
[obstacle]
shape = "0.1"
stiffness = 100.0
"#;

/// Runs `solve` on a case and asserts it fails with `needle` in the message and writes
/// nothing.
fn fails_with(name: &str, body: &str, needle: &str) {
    let d = tmp(name);
    let p = case_file(&d, body);
    let out = d.join("out");
    let o = run(&[
        "solve",
        p.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(!o.status.success(), "{name}: expected a failure");
    let t = text(&o);
    assert!(
        t.contains(needle),
        "{name}: message lacks \"{needle}\": {t}"
    );
    assert!(!t.contains("panicked"), "{name}: {t}");
    assert!(!out.join("summary.json").exists() && !out.join("nodes.csv").exists());
}

#[test]
fn good_case_solves() {
    let d = tmp("good");
    let p = case_file(&d, GOOD);
    let o = run(&[
        "solve",
        p.to_str().unwrap(),
        "-o",
        d.join("out").to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn bad_inputs_are_clear_errors() {
    fails_with("toml", "[mesh\ngenerator = 1", "malformed TOML");
    fails_with(
        "unknown-key",
        &GOOD.replace("nx = 8", "nx = 8\nnz = 3"),
        "nz",
    );
    fails_with(
        "tension",
        &GOOD.replace("tension = 1.0", "tension = -2.0"),
        "tension",
    );
    fails_with(
        "zero-tension",
        &GOOD.replace("tension = 1.0", "tension = 0"),
        "tension",
    );
    fails_with(
        "negative-h",
        &GOOD.replace("stiffness = 100.0", "stiffness = -5.0"),
        "negative",
    );
    fails_with(
        "nan",
        &GOOD.replace("load = \"8\"", "load = \"sqrt(x - 2)\""),
        "NaN",
    );
    fails_with(
        "inf",
        &GOOD.replace("load = \"8\"", "load = \"1/(x-x)\""),
        "load",
    );
    fails_with(
        "parse",
        &GOOD.replace("load = \"8\"", "load = \"8 * (x\""),
        "load",
    );
    fails_with(
        "variable",
        &GOOD.replace("load = \"8\"", "load = \"8 * z\""),
        "z",
    );
    fails_with(
        "method",
        &format!("{GOOD}[solver]\nmethod = \"magic\""),
        "magic",
    );
    fails_with(
        "mesh-file",
        &GOOD.replace(
            "generator = \"rectangle\"\nnx = 8",
            "file = \"missing.msh\"",
        ),
        "missing.msh",
    );
    let d = tmp("broken-msh");
    std::fs::write(
        d.join("broken.msh"),
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n",
    )
    .unwrap();
    let body = GOOD.replace("generator = \"rectangle\"\nnx = 8", "file = \"broken.msh\"");
    let p = case_file(&d, &body);
    let o = run(&[
        "solve",
        p.to_str().unwrap(),
        "-o",
        d.join("out").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(text(&o).contains("broken.msh"), "{}", text(&o));
    fails_with(
        "non-convergence",
        &format!("{GOOD}[solver]\nmethod = \"coordinate\"\nmax_iterations = 2"),
        "coordinate",
    );
}

#[test]
fn every_example_case_solves_with_a_certificate() {
    let mut n = 0;
    for entry in std::fs::read_dir(examples()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        n += 1;
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        let out = tmp(&format!("all-{name}"));
        let mut args = vec![
            "solve",
            path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
        ];
        if name == "bench-square" {
            args.extend(["--set", "mesh.nx=64", "--set", "mesh.ny=64"]);
        }
        let o = run(&args);
        assert!(o.status.success(), "{name}: {}", text(&o));
        let s = summary(&out);
        assert!(s["kkt_residual"].as_f64().unwrap() <= 1e-9, "{name}");
        // Equilibrium: the obstacle never carries more than the load (in the paper's
        // frame: with boundary heights or a body below, the frame and the body below
        // carry their share, and an obstacle that displaces the unloaded membrane, as in
        // the obstacle benchmarks, carries its own force; then only the signs of the
        // bodies' forces are known).
        let (load, force) = (
            s["total_load"].as_f64().unwrap(),
            s["total_contact_force"].as_f64().unwrap(),
        );
        let beyond =
            s.get("fixed_vertices").is_some() || s.get("lower_foundation").is_some() || load == 0.0;
        if beyond {
            let low = s
                .get("total_contact_force_low")
                .map_or(0.0, |f| f.as_f64().unwrap());
            assert!(force >= -1e-12 && low >= -1e-12, "{name}: {force}, {low}");
        } else {
            assert!(
                force >= -1e-12 && force <= load * (1.0 + 1e-12),
                "{name}: {force} vs {load}"
            );
        }
    }
    assert!(n >= 5);
}

#[test]
fn ambiguous_gmsh_region_names_are_warned_about_and_refused() {
    // Four triangles around a centre vertex: physical surfaces 2 ("clay"), 5 (named "2",
    // which is also surface 2's tag) and 6 (named "default").
    let d = tmp("region-names");
    let msh = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n2 2 \"clay\"\n\
               2 5 \"2\"\n2 6 \"default\"\n$EndPhysicalNames\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n\
               3 1 1 0\n4 0 1 0\n5 0.5 0.5 0\n$EndNodes\n$Elements\n4\n1 2 2 2 2 1 2 5\n\
               2 2 2 2 2 2 3 5\n3 2 2 5 5 3 4 5\n4 2 2 6 6 4 1 5\n$EndElements\n";
    std::fs::write(d.join("square.msh"), msh).unwrap();
    let case = |stiffness: &str| {
        case_file(
            &d,
            &format!(
                "[mesh]\nfile = \"square.msh\"\n[membrane]\ntension = 1\nload = 8\n\
                 [obstacle]\nshape = 0.01\nstiffness = {stiffness}\n[output]\nplot = false\n"
            ),
        )
    };
    let p = case("{ clay = 10, \"5\" = 20, \"6\" = 30 }");
    let o = run(&["check", p.to_str().unwrap()]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("warning: physical surface 5 is named \"2\"") && t.contains("ambiguous"),
        "{t}"
    );
    assert!(
        t.contains("warning: physical surface 6 is named \"default\""),
        "{t}"
    );
    let out = d.join("out");
    let solve = |p: &Path| {
        run(&[
            "solve",
            p.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ])
    };
    let o = solve(&p);
    assert!(o.status.success(), "{}", text(&o));
    // The key "2" could be surface 2 (by tag) or surface 5 (by name): refused.
    let o = solve(&case("{ \"2\" = 10, default = 1 }"));
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("'2' is ambiguous") && t.contains("clay"), "{t}");
}

#[test]
fn a_case_benchmark_prints_the_solver_phases_when_asked() {
    let case = examples().join("gmsh-disk.toml");
    let phases_of = |args: &[&str]| -> Vec<(String, f64)> {
        let mut all = vec!["bench", "--case", case.to_str().unwrap()];
        all.extend_from_slice(args);
        let o = run(&all);
        assert!(o.status.success(), "{}", text(&o));
        let out = String::from_utf8_lossy(&o.stdout).into_owned();
        out.lines()
            .filter_map(|l| l.trim().strip_prefix("solver phases, seconds: "))
            .flat_map(|l| l.split(", ").map(str::to_string).collect::<Vec<_>>())
            .map(|p| {
                let (name, s) = p.rsplit_once(' ').unwrap();
                (name.to_string(), s.parse::<f64>().unwrap())
            })
            .collect()
    };
    assert!(phases_of(&[]).is_empty(), "no phases without --phases");
    let phases = phases_of(&["--phases"]);
    let names: Vec<&str> = phases.iter().map(|(n, _)| n.as_str()).collect();
    // The imported disk is solved by the active-set method: its factorisation is a phase.
    assert!(names.contains(&"factorisation"), "{names:?}");
    assert!(names.contains(&"certificate"), "{names:?}");
    assert!(phases.iter().all(|(_, s)| s.is_finite() && *s >= 0.0));
}

/// A refined mesh whose coarsest level is large (a disc of about 6 500 vertices refined
/// once, as `refine = 1` makes of an imported mesh): `auto` runs multigrid on the mesh
/// levels, with aggregation levels below the coarsest mesh, says so in `summary.json`, and
/// its answer is the active-set method's (an independent formulation, Problem 2f with
/// sparse Cholesky) in every vertex of `nodes.csv`.
#[test]
fn a_refined_mesh_with_a_large_coarsest_level_is_solved_on_its_levels() {
    let case = examples().join("disk.toml");
    let solve = |name: &str, extra: &[&str]| {
        let out = tmp(name);
        let mut args = vec![
            "solve",
            case.to_str().unwrap(),
            "--set",
            "mesh.size=0.03",
            "--set",
            "mesh.refine=1",
            "-o",
            out.to_str().unwrap(),
            "-q",
        ];
        args.extend_from_slice(extra);
        let o = run(&args);
        assert!(o.status.success(), "{}", text(&o));
        let u: Vec<f64> = std::fs::read_to_string(out.join("nodes.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
            .collect();
        (summary(&out), u)
    };
    let (s, u) = solve("refined-levels", &[]);
    assert_eq!(s["solver"], "multigrid");
    assert_eq!(s["hierarchy"], "geometric");
    assert_eq!(s["solver_choice"], "geometric_hierarchy");
    assert!(
        s["unknowns"].as_u64().unwrap() > 20_000,
        "{}",
        s["unknowns"]
    );
    assert!(
        s["iterations"].as_u64().unwrap() <= 4,
        "{}",
        s["iterations"]
    );
    let (r, reference) = solve("refined-active-set", &["--set", "solver.method=active-set"]);
    assert_eq!(r["solver"], "active-set");
    assert_eq!(u.len(), reference.len());
    let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = u
        .iter()
        .zip(&reference)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(diff <= 1e-8 * scale, "differs from active set by {diff:e}");
}
