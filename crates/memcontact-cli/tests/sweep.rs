//! End-to-end: `[sweep]` and `[[load_case]]` runs (a directory per step, `sweep.csv`,
//! `sweep.png`), each step equal to the case solved directly with that step's data;
//! `memcontact plot` redraws a step's pictures byte for byte; `--write-unconverged`
//! writes a marked iterate, and nothing is written without it.

mod common;

use common::{examples, run, text};
use std::path::Path;

/// The columns of `sweep.csv`, in order.
const HEADER: &str = "step,name,value,max_deflection,contact_area,liftoff_area,\
                      total_contact_force,max_pressure,energy,iterations,kkt_residual,seconds";

/// The roof example on a coarse mesh, with `extra` appended.
fn roof_with(dir: &Path, name: &str, extra: &str) -> std::path::PathBuf {
    let text = std::fs::read_to_string(examples().join("roof.toml"))
        .unwrap()
        .replace("size = 0.25", "size = 0.5");
    let path = dir.join(name);
    std::fs::write(&path, format!("{text}\n{extra}")).unwrap();
    path
}

/// A CSV file as its header and rows of cells.
fn read_csv(path: &Path) -> (String, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

/// Column `name` of a `nodes.csv`.
fn nodes_column(path: &Path, name: &str) -> Vec<f64> {
    let (header, rows) = read_csv(path);
    let k = header.split(',').position(|h| h == name).unwrap();
    rows.iter().map(|r| r[k].parse().unwrap()).collect()
}

/// `summary.json` of a result directory.
fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// `a` and `b` agree to `tol` relative to the largest |b|.
fn close(a: &[f64], b: &[f64], tol: f64) -> bool {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol * scale)
}

/// Solves `case` with `--set` overrides into `out`; panics unless it succeeds.
fn solve(case: &Path, out: &Path, sets: &[&str]) {
    let mut args = vec![
        "solve",
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ];
    for s in sets {
        args.extend(["--set", s]);
    }
    let o = run(&args);
    assert!(o.status.success(), "{}", text(&o));
}

/// The roof's load expression.
const ROOF_LOAD: &str = "1.2 + 0.3*exp(-((x-3)^2 + (y-4)^2)/4)";

#[test]
fn a_load_factor_sweep_writes_a_directory_per_step_and_sweep_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let case = roof_with(
        d,
        "roof-sweep.toml",
        "[sweep]\nparameter = \"load_factor\"\nfrom = 0.5\nto = 2.0\nsteps = 4\n",
    );
    let out = d.join("out");
    solve(&case, &out, &[]);
    let (header, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(header, HEADER);
    assert_eq!(rows.len(), 4);
    let png = std::fs::read(out.join("sweep.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let mut previous = f64::NEG_INFINITY;
    for (k, row) in rows.iter().enumerate() {
        let name = format!("step-{k:03}");
        assert_eq!(row[0], k.to_string());
        assert_eq!(row[1], name);
        let value: f64 = row[2].parse().unwrap();
        assert!((value - (0.5 + 0.5 * k as f64)).abs() < 1e-12, "{value}");
        let step = out.join(&name);
        for f in [
            "solution.vtu",
            "nodes.csv",
            "summary.json",
            "deflection.png",
            "pressure.png",
            "liftoff.png",
            "profile.png",
        ] {
            assert!(step.join(f).is_file(), "{name}/{f}");
        }
        // The row's max deflection is the step's, read back from its nodes.csv.
        let u = nodes_column(&step.join("nodes.csv"), "u");
        let max_u = u.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let max_deflection: f64 = row[3].parse().unwrap();
        assert_eq!(max_deflection, max_u, "{name}");
        // Load up, deflection up (a larger load pushes the membrane further everywhere).
        assert!(
            max_deflection > previous,
            "{name}: {max_deflection} ≤ {previous}"
        );
        previous = max_deflection;
        let s = summary(&step);
        assert_eq!(s["case"], format!("{} [{name}]", case.display()));
        assert_eq!(s["accepted"], true);
        assert_eq!(s["plot_options"]["title"], s["case"]);
    }
    // The last step is the case solved directly with twice the load.
    let direct = d.join("direct");
    solve(
        &roof_with(d, "roof.toml", ""),
        &direct,
        &[&format!("membrane.load=\"2*({ROOF_LOAD})\"")],
    );
    let u_sweep = nodes_column(&out.join("step-003/nodes.csv"), "u");
    let u_direct = nodes_column(&direct.join("nodes.csv"), "u");
    assert!(close(&u_sweep, &u_direct, 1e-8));

    // `memcontact plot` redraws each step's pictures byte for byte, and the hashes in its
    // summary.json still describe them; on the sweep's directory, every step's.
    let step = out.join("step-003");
    let before: Vec<Vec<u8>> = ["deflection", "pressure", "liftoff", "profile"]
        .iter()
        .map(|n| std::fs::read(step.join(format!("{n}.png"))).unwrap())
        .collect();
    for target in [&step, &out] {
        for n in ["deflection", "pressure", "liftoff", "profile"] {
            std::fs::remove_file(step.join(format!("{n}.png"))).unwrap();
        }
        let o = run(&["plot", target.to_str().unwrap()]);
        assert!(o.status.success(), "{}", text(&o));
        let files = &summary(&step)["files"];
        for (n, old) in ["deflection", "pressure", "liftoff", "profile"]
            .iter()
            .zip(&before)
        {
            let name = format!("{n}.png");
            let path = step.join(&name);
            assert!(
                std::fs::read(&path).unwrap() == *old,
                "{name} redrawn differs"
            );
            let record = memcontact::write::file_record(&path).unwrap();
            assert_eq!(files[&name]["xxh3"], record.xxh3, "{name}");
            assert_eq!(files[&name]["bytes"], record.bytes, "{name}");
        }
    }
}

#[test]
fn load_cases_write_a_directory_per_case_each_equal_to_a_direct_solve() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let cases = "\
[[load_case]]
name = \"dead\"

[[load_case]]
name = \"gust x1.5\"
load_factor = 1.5

[[load_case]]
name = \"uniform\"
load = 2.0

[[load_case]]
name = \"soft foam\"
stiffness = { block = 300.0, default = 100.0 }
";
    let case = roof_with(d, "roof-cases.toml", cases);
    let out = d.join("out");
    solve(&case, &out, &[]);
    let (header, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(header, HEADER);
    let names: Vec<&str> = rows.iter().map(|r| r[1].as_str()).collect();
    assert_eq!(names, ["dead", "gust x1.5", "uniform", "soft foam"]);
    let values: Vec<f64> = rows.iter().map(|r| r[2].parse().unwrap()).collect();
    assert_eq!(values, [1.0, 1.5, 1.0, 1.0]);
    assert!(out.join("sweep.png").is_file());
    // Each load case is the base case with its data, solved directly.
    let base = roof_with(d, "roof.toml", "");
    for (name, sets) in [
        ("dead", vec![]),
        (
            "gust x1.5",
            vec![format!("membrane.load=\"1.5*({ROOF_LOAD})\"")],
        ),
        ("uniform", vec!["membrane.load=2.0".to_string()]),
        (
            "soft foam",
            vec!["obstacle.stiffness={ block = 300.0, default = 100.0 }".to_string()],
        ),
    ] {
        let direct = d.join(format!("direct-{name}"));
        let sets: Vec<&str> = sets.iter().map(String::as_str).collect();
        solve(&base, &direct, &sets);
        for column in ["u", "pressure", "contact_force"] {
            let a = nodes_column(&out.join(name).join("nodes.csv"), column);
            let b = nodes_column(&direct.join("nodes.csv"), column);
            assert!(close(&a, &b, 1e-8), "{name}: {column}");
        }
        let s = summary(&out.join(name));
        assert_eq!(s["case"], format!("{} [{name}]", case.display()));
    }
}

#[test]
fn write_unconverged_keeps_a_marked_iterate() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // One iteration of the active-set method cannot reach the tolerance.
    let case = roof_with(d, "roof-short.toml", "");
    let sets = ["solver.method=\"active-set\"", "solver.max_iterations=1"];
    let args = |out: &Path, extra: Option<&str>| {
        let mut a: Vec<String> = vec![
            "solve".into(),
            case.to_str().unwrap().into(),
            "-o".into(),
            out.to_str().unwrap().into(),
            "-q".into(),
        ];
        for s in sets {
            a.extend(["--set".into(), s.into()]);
        }
        a.extend(extra.map(String::from));
        a
    };
    let go = |a: Vec<String>| run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let out = d.join("plain");
    let o = go(args(&out, None));
    assert!(!o.status.success());
    assert!(
        text(&o).contains("no result files were written"),
        "{}",
        text(&o)
    );
    assert!(text(&o).contains("--write-unconverged"), "{}", text(&o));
    assert!(!out.exists());

    let out = d.join("kept");
    let o = go(args(&out, Some("--write-unconverged")));
    assert!(!o.status.success(), "the exit status still says it failed");
    assert!(text(&o).contains("unconverged iterate"), "{}", text(&o));
    let s = summary(&out);
    assert_eq!(s["accepted"], false);
    assert_eq!(s["converged"], false);
    assert_eq!(s["status"], "iteration_limit");
    assert_eq!(s["iterations"], 1);
    assert!(s["kkt_residual"].as_f64().unwrap() > s["tolerance"].as_f64().unwrap());
    for f in ["solution.vtu", "nodes.csv", "deflection.png"] {
        assert!(out.join(f).is_file(), "{f}");
    }

    // In a sweep, the step that does not converge ends it: with the flag, the steps
    // before it and its marked iterate are written, with sweep.csv.
    let sweep = roof_with(
        d,
        "roof-short-sweep.toml",
        "[sweep]\nparameter = \"load_factor\"\nvalues = [0.1, 0.2, 2.0, 3.0]\n",
    );
    let run_sweep = |out: &Path, flag: bool| {
        let mut a = vec![
            "solve",
            sweep.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
            "--set",
            sets[0],
            "--set",
            sets[1],
        ];
        if flag {
            a.push("--write-unconverged");
        }
        run(&a)
    };
    let out = d.join("sweep-plain");
    let o = run_sweep(&out, false);
    assert!(!o.status.success());
    assert!(text(&o).contains("step-002"), "{}", text(&o));
    assert!(!out.exists());
    let out = d.join("sweep-kept");
    let o = run_sweep(&out, true);
    assert!(!o.status.success());
    let (_, rows) = read_csv(&out.join("sweep.csv"));
    assert_eq!(rows.len(), 3, "steps 0, 1 and the one that failed");
    assert_eq!(summary(&out.join("step-001"))["accepted"], true);
    assert_eq!(summary(&out.join("step-002"))["accepted"], false);
    assert!(!out.join("step-003").exists());
}
