//! End-to-end tests of `memcontact convergence`: the binary on small cases, checking the
//! table, the CSV and PNG it writes, the exit code, and the errors for bad `[exact]` input.
//! (The rates themselves are tested on the library function, in
//! `memcontact::verify::convergence`.)

use std::path::{Path, PathBuf};

mod common;
use common::{examples, run, text};

fn tmp(name: &str) -> common::Tmp {
    common::tmp_in("conv", name)
}

/// The header and the rows of a CSV file (empty fields become NaN).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let s = std::fs::read_to_string(path).unwrap();
    let mut lines = s.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| {
                    if v.is_empty() {
                        f64::NAN
                    } else {
                        v.parse().unwrap()
                    }
                })
                .collect()
        })
        .collect();
    (header, rows)
}

fn column(header: &[String], rows: &[Vec<f64>], name: &str) -> Vec<f64> {
    let k = header.iter().position(|h| h == name).unwrap();
    rows.iter().map(|r| r[k]).collect()
}

fn assert_png(path: &Path) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(
        &bytes[..8],
        b"\x89PNG\r\n\x1a\n",
        "{} is not a PNG",
        path.display()
    );
}

#[test]
fn disc_study_writes_the_table_csv_and_png() {
    let out = tmp("disc");
    let case = examples().join("disk.toml");
    let o = run(&[
        "convergence",
        case.to_str().unwrap(),
        "--levels",
        "2",
        "-o",
        out.to_str().unwrap(),
        "--set",
        "mesh.size=0.25",
        "--set",
        "solver.method=active-set",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let t = text(&o);
    assert!(t.contains("ContactDisc") && t.contains("L² error") && t.contains("|a_h − a|"));
    let (header, rows) = read_csv(&out.join("convergence.csv"));
    let required = [
        "level",
        "vertices",
        "l_n",
        "l2_error",
        "h1_error",
        "max_nodal_error",
        "l2_rate",
        "h1_rate",
    ];
    assert_eq!(&header[..8], &required, "{header:?}");
    assert!(header.contains(&"contact_radius_error".to_string()));
    assert_eq!(rows.len(), 3);
    assert!(rows.iter().all(|r| r.len() == header.len()));
    assert_eq!(column(&header, &rows, "level"), [0.0, 1.0, 2.0]);
    // The first level has no rate; the others are about 2 (L²) and 1 (H¹).
    let (l2, h1) = (
        column(&header, &rows, "l2_rate"),
        column(&header, &rows, "h1_rate"),
    );
    assert!(l2[0].is_nan() && h1[0].is_nan());
    assert!(l2[2] > 1.6 && h1[2] > 0.85, "{l2:?} {h1:?}");
    // Meshes are refined uniformly: the size halves.
    let l_n = column(&header, &rows, "l_n");
    assert!((l_n[1] / l_n[0] - 0.5).abs() < 0.05, "{l_n:?}");
    assert_png(&out.join("convergence.png"));
    // Nothing but the two outputs and the manifest that binds them to the run (atomic
    // writes leave no temporary file).
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["convergence.csv", "convergence.png", "manifest.json"]
    );
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(manifest["kind"], "convergence");
    assert_eq!(manifest["run_id"].as_str().unwrap().len(), 32);
    for name in ["convergence.csv", "convergence.png"] {
        let bytes = std::fs::read(out.join(name)).unwrap();
        assert_eq!(
            manifest["files"][name]["bytes"],
            bytes.len() as u64,
            "{name}"
        );
    }
}

#[test]
fn manufactured_compare_and_reference_and_sweep() {
    // --compare foundation on the manufactured square: one CSV per variant.
    let out = tmp("msq");
    let case = examples().join("manufactured-square.toml");
    let o = run(&[
        "convergence",
        case.to_str().unwrap(),
        "--levels",
        "2",
        "-q",
        "-o",
        out.to_str().unwrap(),
        "--set",
        "mesh.nx=4",
        "--set",
        "mesh.ny=4",
        "--set",
        "solver.method=active-set",
        "--compare",
        "foundation",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("replaced by the manufactured f"));
    for v in ["consistent", "lumped"] {
        let (header, rows) = read_csv(&out.join(format!("convergence-{v}.csv")));
        assert_eq!(rows.len(), 3);
        let h1 = column(&header, &rows, "h1_rate");
        assert!(h1[2] > 0.9, "{v}: {h1:?}");
    }
    assert_png(&out.join("convergence.png"));

    // No [exact]: errors against the finest level, whose own error is empty.
    let out = tmp("step");
    let case = examples().join("disk-step.toml");
    let o = run(&[
        "convergence",
        case.to_str().unwrap(),
        "--levels",
        "2",
        "-q",
        "-o",
        out.to_str().unwrap(),
        "--set",
        "mesh.size=0.3",
        "--set",
        "solver.method=active-set",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("reference"));
    let (header, rows) = read_csv(&out.join("convergence.csv"));
    let l2 = column(&header, &rows, "l2_error");
    assert!(l2[0] > l2[1] && l2[1] > 0.0 && l2[2].is_nan(), "{l2:?}");
    assert!(column(&header, &rows, "h1_increment")[1] > 0.0);

    // The rigid-limit sweep: distances decrease with h.
    let out = tmp("sweep");
    let case = examples().join("disk.toml");
    let o = run(&[
        "convergence",
        case.to_str().unwrap(),
        "--levels",
        "0",
        "--h-sweep",
        "--h-values",
        "10,1000,100000",
        "-q",
        "-o",
        out.to_str().unwrap(),
        "--set",
        "mesh.size=0.2",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("decreases monotonically"));
    let (header, rows) = read_csv(&out.join("h_sweep.csv"));
    assert_eq!(column(&header, &rows, "h"), [10.0, 1000.0, 100000.0]);
    for name in ["max_nodal_distance", "h1_distance"] {
        let d = column(&header, &rows, name);
        assert!(d[0] > d[1] && d[1] > d[2] && d[2] > 0.0, "{name}: {d:?}");
    }
    assert_png(&out.join("h_sweep.png"));
}

/// Writes a case with `body` and returns its path.
fn case_file(dir: &Path, body: &str) -> PathBuf {
    let p = dir.join("case.toml");
    std::fs::write(&p, body).unwrap();
    p
}

const DISC: &str = r#"
[mesh]
generator = "disk"
size = 0.4
[membrane]
tension = 1.0
load = "8"
[obstacle]
shape = "1.0"
stiffness = 100.0
"#;

const SQUARE: &str = r#"
[mesh]
generator = "rectangle"
nx = 4
[membrane]
tension = 1.0
load = "8"
[obstacle]
shape = "0.5"
stiffness = 100.0
"#;

#[test]
fn bad_exact_sections_are_errors() {
    let dir = tmp("bad");
    let out = dir.join("out");
    let cases: &[(&str, &str, &str)] = &[
        (DISC, "[exact]\nkind = \"bessel\"", "unknown"),
        (DISC, "[exact]\ndomain = \"disk\"", "missing field `kind`"),
        (DISC, "[exact]\nkind = \"disk\"\namplitude = 1", "amplitude"),
        (SQUARE, "[exact]\nkind = \"disk\"", "generator = \"disk\""),
        (
            &DISC.replace("load = \"8\"", "load = \"8 + x\""),
            "[exact]\nkind = \"disk\"",
            "constant membrane.load",
        ),
        (
            &DISC.replace("stiffness = 100.0", "stiffness = \"100*(1+y*y)\""),
            "[exact]\nkind = \"disk\"",
            "constant obstacle.stiffness",
        ),
        (
            SQUARE,
            "[exact]\nkind = \"manufactured\"\ndomain = \"rectangle\"",
            "amplitude",
        ),
        (
            SQUARE,
            "[exact]\nkind = \"manufactured\"\namplitude = 1",
            "domain",
        ),
        (
            SQUARE,
            "[exact]\nkind = \"manufactured\"\ndomain = \"disk\"\namplitude = 1",
            "generator = \"disk\"",
        ),
        (
            SQUARE,
            "[exact]\nkind = \"manufactured\"\ndomain = \"square\"\namplitude = 1",
            "unknown",
        ),
        (
            &SQUARE.replace("stiffness = 100.0", "stiffness = \"rigid\""),
            "[exact]\nkind = \"manufactured\"\ndomain = \"rectangle\"\namplitude = 1",
            "finite obstacle.stiffness",
        ),
        (
            SQUARE,
            "[exact]\nkind = \"manufactured\"\ndomain = \"rectangle\"\namplitude = \"big\"",
            "number",
        ),
        // The annular-contact regime has no closed form.
        (
            &DISC
                .replace("load = \"8\"", "load = \"-10\"")
                .replace("shape = \"1.0\"", "shape = \"-0.01\""),
            "[exact]\nkind = \"disk\"",
            "annulus",
        ),
    ];
    for (base, exact, expect) in cases {
        let case = case_file(&dir, &format!("{base}\n{exact}\n"));
        let o = run(&[
            "convergence",
            case.to_str().unwrap(),
            "--levels",
            "1",
            "-q",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(!o.status.success(), "{exact}: should fail\n{}", text(&o));
        assert_eq!(o.status.code(), Some(1));
        assert!(
            text(&o).contains(expect),
            "{exact}: expected \"{expect}\" in\n{}",
            text(&o)
        );
    }
    // --levels 0 without --h-sweep, and a missing --levels.
    let case = case_file(&dir, &format!("{DISC}\n[exact]\nkind = \"disk\"\n"));
    let o = run(&["convergence", case.to_str().unwrap(), "--levels", "0"]);
    assert!(
        !o.status.success() && text(&o).contains("at least 1"),
        "{}",
        text(&o)
    );
    let o = run(&["convergence", case.to_str().unwrap()]);
    assert!(
        !o.status.success() && text(&o).contains("--levels"),
        "{}",
        text(&o)
    );
    // Nothing was written by the failing runs.
    assert!(!out.join("convergence.csv").exists());
}
