//! End to end through the binary on real case files: `[sensitivity]` (sensitivity.csv, the
//! influence maps in solution.vtu, the summary's keys, both foundations by `--set`), `[fit]`
//! (noise-free recovery, fit.json, fit.csv, fit.png, a fit that does not converge, the
//! identifiability warning), and bad input refused with the key named and nothing written.

use std::path::{Path, PathBuf};

mod common;
use common::{run, text, tmp_in};

/// The sensitivity site's mesh (two soils, a rigid plinth; a free top edge).
fn site_mesh() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../memcontact/tests/data/sens.msh")
}

/// The site case: the obstacle above (soils and a rigid plinth), an elastic body below, boundary
/// heights, the top edge free; four sensors; `extra` appended.
fn site(extra: &str) -> String {
    format!(
        r#"
[mesh]
file = "{mesh}"
[membrane]
tension = 1.3
load = "8 + 4*y - 60*exp(-((x - 1.5)^2 + (y - 0.5)^2)/0.03)"
[obstacle]
shape = "0.02 + 0.01*x"
stiffness = {{ soft = 300, stiff = 1000, plinth = "rigid" }}
[lower]
shape = -0.01
stiffness = 200
[boundary]
height = {{ left = "0.004*y", bottom = 0, right = 0.003 }}
free = ["top"]
[solver]
method = "active-set"
tolerance = 1e-12
[output]
vtu = "ascii"
plots = []
[[sensor]]
name = "A"
at = [0.3, 0.3]
[[sensor]]
name = "B"
at = [1.5, 0.5]
[[sensor]]
name = "C"
at = [1.2, 0.8]
{extra}
"#,
        mesh = site_mesh().display()
    )
}

const SENSITIVITY: &str = r#"
[sensitivity]
outputs = ["energy", "max_deflection", "total_contact_force", "total_contact_force_low",
           "contact_area", "sensors", "contact_force:soft", "contact_force:stiff"]
parameters = ["membrane.tension", "membrane.load", "obstacle.shape", "obstacle.stiffness.soft",
              "obstacle.stiffness.stiff", "lower.stiffness", "lower.shape", "boundary.height.right"]
"#;

/// Writes `text` as `case.toml` in `dir`; its path.
fn case_file(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The rows of sensitivity.csv as (output, parameter) → the row's fields.
fn read_sensitivity(dir: &Path) -> (String, Vec<Vec<String>>) {
    let s = std::fs::read_to_string(dir.join("sensitivity.csv")).unwrap();
    let mut lines = s.lines();
    let header = lines.next().unwrap().to_string();
    (
        header,
        lines
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect(),
    )
}

fn derivative(rows: &[Vec<String>], output: &str, parameter: &str) -> f64 {
    rows.iter()
        .find(|r| r[0] == output && r[1] == parameter)
        .unwrap_or_else(|| panic!("no row {output} / {parameter}"))[3]
        .parse()
        .unwrap()
}

/// A point field of an ASCII solution.vtu.
fn vtu_field(dir: &Path, name: &str) -> Vec<f64> {
    let s = std::fs::read_to_string(dir.join("solution.vtu")).unwrap();
    let tag = format!("Name=\"{name}\"");
    let at = s.find(&tag).unwrap_or_else(|| panic!("no field {name}"));
    let start = at + s[at..].find('>').unwrap() + 1;
    let end = start + s[start..].find("</DataArray>").unwrap();
    s[start..end]
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn sensitivity_files_for_both_foundations() {
    let dir = tmp_in("sensitivity", "files");
    let case = case_file(&dir, "site.toml", &site(SENSITIVITY));
    for foundation in ["consistent", "lumped"] {
        let out = dir.join(foundation);
        let o = run(&[
            "solve",
            case.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
            "--set",
            &format!("obstacle.foundation={foundation}"),
            "--set",
            &format!("lower.foundation={foundation}"),
        ]);
        assert!(o.status.success(), "{foundation}: {}", text(&o));
        assert!(
            text(&o).contains("sensitivity  10 outputs × 8 parameters"),
            "{}",
            text(&o)
        );
        let (header, rows) = read_sensitivity(&out);
        assert!(
            header.starts_with("output,parameter,value,derivative,elasticity"),
            "{header}"
        );
        assert_eq!(
            header,
            "output,parameter,value,derivative,elasticity,derivative_plus,derivative_minus,\
             biactive,parameter_kind,parameter_value"
        );
        assert_eq!(rows.len(), 10 * 8);
        // The envelope identities, through the files: dJ/d(obstacle offset) is minus the
        // obstacle's total force, dJ/dφ_low the body below's.
        let force = summary(&out)["total_contact_force"].as_f64().unwrap();
        let force_low = summary(&out)["total_contact_force_low"].as_f64().unwrap();
        let dj = derivative(&rows, "energy", "obstacle.shape");
        assert!((dj + force).abs() <= 1e-10 * force.abs(), "{dj} {force}");
        let dj = derivative(&rows, "energy", "lower.shape");
        assert!(
            (dj - force_low).abs() <= 1e-10 * force_low.abs(),
            "{dj} {force_low}"
        );
        // Kinds and elasticities: the offset has none.
        let shape = rows.iter().find(|r| r[1] == "obstacle.shape").unwrap();
        assert_eq!((shape[4].as_str(), shape[8].as_str()), ("", "offset"));
        let load = rows.iter().find(|r| r[1] == "membrane.load").unwrap();
        assert_eq!(load[8], "factor");
        // The summary's keys.
        let s = summary(&out);
        assert_eq!(s["sensitivity_biactive"].as_u64(), Some(0));
        // Nine outputs besides the energy, eight parameters: one tangent solve per parameter.
        assert_eq!(s["sensitivity_mode"].as_str(), Some("tangent"));
        assert!(s["sensitivity_max_residual"].as_f64().unwrap() < 1e-10);
        assert_eq!(
            s["sensitivity_solve_records"].as_array().unwrap().len(),
            s["sensitivity_solves"].as_u64().unwrap() as usize
        );
        // The influence maps add up to the derivative in a uniform change of h: over the
        // obstacle's elastic regions, that of both soils together; the body below's map to
        // its uniform stiffness's.
        let sum = |name: &str| vtu_field(&out, name).iter().sum::<f64>();
        for (map, output) in [("dJ_dh", "energy"), ("dsensor_B_dh", "sensor:B")] {
            let both = derivative(&rows, output, "obstacle.stiffness.soft")
                + derivative(&rows, output, "obstacle.stiffness.stiff");
            let m = sum(map);
            assert!(
                (m - both).abs() <= 1e-9 * both.abs(),
                "{foundation} {map}: {m} {both}"
            );
        }
        for (map, output) in [("dJ_dh_low", "energy"), ("dsensor_A_dh_low", "sensor:A")] {
            let d = derivative(&rows, output, "lower.stiffness");
            let m = sum(map);
            assert!(
                (m - d).abs() <= 1e-9 * d.abs().max(1e-12),
                "{foundation} {map}: {m} {d}"
            );
        }
        // The files are bound to the run in the summary.
        for f in ["sensitivity.csv", "solution.vtu"] {
            assert!(s["files"][f].is_object(), "{f}");
        }
    }
}

/// Sensors' measured values from the true parameters, a fit started 5 to 8 times away.
fn fit_case(dir: &Path, truth: &[(&str, f64)], start: &[(&str, f64)], extra: &str) -> PathBuf {
    // The true deflections at eight sensors.
    let points = [
        [0.2, 0.2],
        [0.7, 0.8],
        [0.8, 0.3],
        [0.3, 0.85],
        [1.2, 0.2],
        [1.8, 0.8],
        [1.3, 0.9],
        [1.75, 0.25],
    ];
    let sensors: String = points
        .iter()
        .enumerate()
        .map(|(i, p)| format!("[[sensor]]\nname = \"S{i}\"\nat = [{}, {}]\n", p[0], p[1]))
        .collect();
    let with = |values: &[(&str, f64)], sens: &str, more: &str| {
        let mut t = site("")
            .replace("soft = 300", &format!("soft = {}", values[0].1))
            .replace("stiff = 1000", &format!("stiff = {}", values[1].1));
        if let Some(l) = values.get(2) {
            t = t.replace("stiffness = 200", &format!("stiffness = {}", l.1));
        }
        format!("{t}{sens}{more}")
    };
    let truth_case = case_file(
        dir,
        "truth.toml",
        &with(
            truth,
            &sensors,
            "[sensitivity]\noutputs = [\"sensors\"]\nparameters = [\"membrane.tension\"]\ninfluence = false\n",
        ),
    );
    let out = dir.join("truth");
    let o = run(&[
        "solve",
        truth_case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let (_, rows) = read_sensitivity(&out);
    let mut csv = String::from("name,x,y,u\n");
    for (i, p) in points.iter().enumerate() {
        let row = rows
            .iter()
            .find(|r| r[0] == format!("sensor:S{i}"))
            .unwrap();
        csv.push_str(&format!("S{i},{},{},{}\n", p[0], p[1], row[2]));
    }
    std::fs::write(dir.join("points.csv"), csv).unwrap();
    let bounds: String = start
        .iter()
        .map(|(k, _)| format!("\"{k}\" = [10, 100000]\n"))
        .collect();
    case_file(
        dir,
        "fit.toml",
        &with(
            start,
            "",
            &format!(
                "[fit]\nmeasurements = \"points.csv\"\ntolerance = 1e-10\n{extra}\n[fit.parameters]\n{bounds}"
            ),
        ),
    )
}

#[test]
fn a_fit_recovers_the_stiffnesses() {
    let dir = tmp_in("sensitivity", "fit");
    let truth = [
        ("obstacle.stiffness.soft", 300.0),
        ("obstacle.stiffness.stiff", 1000.0),
        ("lower.stiffness", 200.0),
    ];
    let start = [
        ("obstacle.stiffness.soft", 1500.0),
        ("obstacle.stiffness.stiff", 150.0),
        ("lower.stiffness", 1200.0),
    ];
    let case = fit_case(&dir, &truth, &start, "max_iterations = 15");
    let out = dir.join("fit");
    let o = run(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
        "--set",
        "output.plots=[\"deflection\"]",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("fit.json")).unwrap()).unwrap();
    assert_eq!(fit["converged"], true, "{fit}");
    assert!(fit["iterations"].as_u64().unwrap() <= 15, "{fit}");
    for (k, v) in truth {
        let got = fit["parameters"][k].as_f64().unwrap();
        assert!((got - v).abs() <= 1e-6 * v, "{k}: {got} against {v}");
    }
    assert!(fit["warning"].is_null(), "{fit}");
    assert!(out.join("fit.png").exists() && out.join("deflection.png").exists());
    let csv = std::fs::read_to_string(out.join("fit.csv")).unwrap();
    assert!(
        csv.starts_with(
            "iteration,lower.stiffness,obstacle.stiffness.soft,obstacle.stiffness.stiff,rms,step"
        ),
        "{csv}"
    );
    assert_eq!(
        csv.lines().count(),
        fit["iterations"].as_u64().unwrap() as usize + 2
    );
    // The result set is at the fitted parameters.
    let s = summary(&out);
    assert!(s["files"]["fit.json"].is_object() && s["files"]["fit.csv"].is_object());
}

#[test]
fn a_fit_that_does_not_converge_writes_its_best_iterate_and_fails() {
    let dir = tmp_in("sensitivity", "unconverged");
    let truth = [
        ("obstacle.stiffness.soft", 300.0),
        ("obstacle.stiffness.stiff", 1000.0),
    ];
    let start = [
        ("obstacle.stiffness.soft", 3000.0),
        ("obstacle.stiffness.stiff", 100.0),
    ];
    let case = fit_case(&dir, &truth, &start, "max_iterations = 1");
    let out = dir.join("fit");
    let o = run(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(!o.status.success());
    assert!(text(&o).contains("did not converge"), "{}", text(&o));
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("fit.json")).unwrap()).unwrap();
    assert_eq!(fit["converged"], false);
    assert_eq!(fit["stop"], "max_iterations");
    assert!(fit["note"].as_str().unwrap().contains("best iterate"));
}

#[test]
fn two_sensors_that_cannot_tell_two_regions_apart_warn() {
    // The square in two halves of the same data, sensors on the line between them: every
    // sensor sees the two stiffnesses alike.
    let dir = tmp_in("sensitivity", "identifiability");
    let text_case = r#"
[mesh]
generator = "polygon"
outer = [[0, 0], [2, 0], [2, 1], [0, 1]]
regions = [{ name = "west", polygon = [[0, 0], [1, 0], [1, 1], [0, 1]] },
           { name = "east", polygon = [[1, 0], [2, 0], [2, 1], [1, 1]] }]
size = 0.1
[membrane]
tension = 1
load = 10
[obstacle]
shape = 0.02
stiffness = { west = 500, east = 500 }
foundation = "lumped"
[output]
plots = []
[[sensor]]
name = "N"
at = [1, 0.7]
measured = 0.03
sigma = 0.001
[[sensor]]
name = "S"
at = [1, 0.3]
measured = 0.03
sigma = 0.001
[fit]
parameters = { "obstacle.stiffness.west" = [10, 10000], "obstacle.stiffness.east" = [10, 10000] }
max_iterations = 5
"#;
    let case = case_file(&dir, "twins.toml", text_case);
    let out = dir.join("out");
    let o = run(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(text(&o).contains("not identifiable"), "{}", text(&o));
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("fit.json")).unwrap()).unwrap();
    assert!(
        fit["warning"]
            .as_str()
            .unwrap()
            .contains("not identifiable"),
        "{fit}"
    );
}

#[test]
fn bad_input_is_refused_with_the_key_and_nothing_written() {
    let dir = tmp_in("sensitivity", "bad");
    let fit2 = "[fit]\nparameters = { \"obstacle.stiffness.soft\" = [10, 1000], \"obstacle.stiffness.stiff\" = [10, 10000] }\n";
    let cases = [
        (
            "[sensitivity]\nparameters = [\"obstacle.stiffness.rock\"]\n",
            "sensitivity.parameters",
            "valid keys: membrane.tension",
        ),
        (
            "[sensitivity]\nparameters = [\"obstacle.stiffness.plinth\"]\n",
            "sensitivity.parameters",
            "rigid",
        ),
        (
            "[sensitivity]\noutputs = [\"sensor:Z\"]\nparameters = [\"membrane.tension\"]\n",
            "sensitivity.outputs",
            "no [[sensor]] is named",
        ),
        (
            "[sensitivity]\noutputs = [\"contact_force:rock\"]\nparameters = [\"membrane.tension\"]\n",
            "sensitivity.outputs",
            "no region",
        ),
        (
            "[[sensor]]\nname = \"far\"\nat = [5, 5]\n[sensitivity]\noutputs = [\"sensors\"]\nparameters = [\"membrane.tension\"]\n",
            "sensor.3",
            "\"far\" at (5, 5) is outside the mesh",
        ),
        (
            "[[sensor]]\nname = \"M\"\nat = [1, 0.5]\nmeasured = 0.01\nsigma = nan\n",
            "sensor.3.sigma",
            "finite number > 0",
        ),
        (
            "[[sensor]]\nname = \"M\"\nat = [1, 0.5]\nmeasured = 0.01\nsigma = -1\n",
            "sensor.3.sigma",
            "finite number > 0",
        ),
        (
            &format!("[[sensor]]\nname = \"M\"\nat = [1, 0.5]\nmeasured = 0.01\n{fit2}"),
            "fit",
            "1 measurement for 2 parameters",
        ),
        (
            "[[sensor]]\nname = \"M\"\nat = [1, 0.5]\nmeasured = 0.01\n[fit]\nparameters = { \"obstacle.stiffness.soft\" = [1000, 5000] }\n",
            "fit.parameters.obstacle.stiffness.soft",
            "exclude the start value 300",
        ),
        (
            "[[sensor]]\nname = \"M\"\nat = [1, 0.5]\nmeasured = 0.01\n[fit]\nparameters = { \"obstacle.shape\" = [0, 1] }\n",
            "fit.parameters.obstacle.shape",
            "must be a number in the case",
        ),
        (
            "[[sensor]]\nname = \"M\"\nat = [1, 0.5]\nmeasured = 0.01\n[fit]\nparameters = { \"obstacle.stiffness.soft\" = [10, 1000] }\n[sweep]\nparameter = \"load_factor\"\nvalues = [1, 2]\n",
            "fit",
            "a case with [sweep] cannot fit",
        ),
        (
            "[[sensor]]\nname = \"M\"\nat = [1, 0.5]\nmeasured = 0.01\n[fit]\nparameters = { \"obstacle.stiffness.soft\" = [10, 1000] }\n[adapt]\nsteps = 2\n",
            "fit",
            "a case with [adapt] cannot fit",
        ),
        (
            "[fit]\nparameters = { \"obstacle.stiffness.soft\" = [10, 1000] }\nmeasurements = \"missing.csv\"\n",
            "missing.csv",
            "",
        ),
        (
            "[fit]\nparameters = { \"obstacle.stiffness.soft\" = [10, 1000] }\nmeasurements = \"bad.csv\"\n",
            "fit.measurements",
            "column y",
        ),
        (
            "[fit]\nparameters = { \"obstacle.stiffness.soft\" = [10, 1000] }\nmeasurements = \"outside.csv\"\n",
            "fit.measurements",
            "outside the mesh",
        ),
    ];
    std::fs::write(dir.join("bad.csv"), "name,x,y,u\nP,1,oops,0.01\n").unwrap();
    std::fs::write(
        dir.join("outside.csv"),
        "name,x,y,u\nP,1,0.5,0.01\nQ,9,9,0.02\n",
    )
    .unwrap();
    for (k, (extra, key, what)) in cases.iter().enumerate() {
        let case = case_file(&dir, &format!("bad{k}.toml"), &site(extra));
        for command in ["solve", "check"] {
            let out = dir.join(format!("out{k}-{command}"));
            let mut args = vec![command, case.to_str().unwrap()];
            if command == "solve" {
                args.extend(["-o", out.to_str().unwrap(), "-q"]);
            }
            let o = run(&args);
            let t = text(&o);
            assert!(!o.status.success(), "{command} {extra}: {t}");
            assert!(
                t.contains(key) && t.contains(what),
                "{command} {extra}: {t}"
            );
            assert!(!t.contains("panicked"), "{t}");
            assert!(!out.exists(), "{command} {extra}: wrote {}", out.display());
        }
    }
}

#[test]
fn check_reports_the_sections_and_set_overrides_reach_them() {
    let dir = tmp_in("sensitivity", "check");
    let case = case_file(&dir, "site.toml", &site(SENSITIVITY));
    let o = run(&[
        "check",
        case.to_str().unwrap(),
        "--set",
        "sensitivity.parameters=[\"lower.stiffness\"]",
        "--set",
        "sensor.1.at=[1.6, 0.4]",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("sensitivity  8 × 1"), "{}", text(&o));
    let o = run(&[
        "check",
        case.to_str().unwrap(),
        "--set",
        "sensor.1.at=[7, 0.4]",
    ]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("sensor.1") && text(&o).contains("\"B\""),
        "{}",
        text(&o)
    );
    // The fit's dotted parameter keys through --set.
    let o = run(&[
        "check",
        case.to_str().unwrap(),
        "--set",
        "sensor.0.measured=0.02",
        "--set",
        "fit.parameters.lower.stiffness=[10, 1000]",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("fit          1 parameters (lower.stiffness)"),
        "{}",
        text(&o)
    );
}
