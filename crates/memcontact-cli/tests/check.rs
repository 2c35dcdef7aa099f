//! `memcontact check` refuses every case `memcontact solve` refuses, with the same message,
//! and without solving or writing anything.

use std::path::Path;

mod common;
use common::{run, text};

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

/// The first line of the error a command printed.
fn error_line(o: &std::process::Output) -> String {
    text(o)
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_default()
        .to_string()
}

fn both_refuse(dir: &Path, name: &str, body: &str, needle: &str) {
    let case = dir.join(format!("{name}.toml"));
    std::fs::write(&case, body).unwrap();
    let out = dir.join(format!("out-{name}"));
    let c = run(&["check", case.to_str().unwrap()]);
    let s = run(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert!(!c.status.success(), "{name}: check accepted it");
    assert!(!s.status.success(), "{name}: solve accepted it");
    assert_eq!(error_line(&c), error_line(&s), "{name}");
    assert!(
        error_line(&c).contains(needle),
        "{name}: \"{needle}\" not in {}",
        error_line(&c)
    );
    assert!(!out.exists(), "{name}: solve wrote {}", out.display());
}

#[test]
fn check_refuses_what_solve_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let with = |extra: &str| format!("{GOOD}{extra}");
    let cases: Vec<(&str, String, &str)> = vec![
        ("malformed", "[mesh\n".into(), "malformed TOML"),
        (
            "unknown-section",
            with("[solvr]\nmethod = \"qp\"\n"),
            "solvr",
        ),
        (
            "unknown-mesh-key",
            GOOD.replace("nx = 8", "nx = 8\nnz = 2"),
            "nz",
        ),
        (
            "unknown-output-key",
            with("[output]\nformat = \"vtk\"\n"),
            "format",
        ),
        ("bad-vtu", with("[output]\nvtu = \"xml\"\n"), "output.vtu"),
        (
            "bad-plots",
            with("[output]\nplots = [\"contours\"]\n"),
            "output.plots",
        ),
        (
            "bad-allowable",
            with("[output]\nallowable_pressure = -1\n"),
            "allowable_pressure",
        ),
        (
            "bad-profile",
            with("[output]\nprofile = [[0, 0], [0, 0]]\n"),
            "output.profile",
        ),
        ("bad-units", with("[units]\ntime = \"s\"\n"), "time"),
        (
            "tension",
            GOOD.replace("tension = 1.0", "tension = -1"),
            "membrane.tension",
        ),
        (
            "nan-load",
            GOOD.replace("load = \"8\"", "load = nan"),
            "membrane.load",
        ),
        (
            "negative-h",
            GOOD.replace("stiffness = 100.0", "stiffness = -1"),
            "stiffness",
        ),
        ("method", with("[solver]\nmethod = \"magic\"\n"), "magic"),
        (
            "tolerance",
            with("[solver]\ntolerance = 0.5\n"),
            "solver.tolerance",
        ),
        (
            "iterations",
            with("[solver]\nmax_iterations = 0\n"),
            "max_iterations",
        ),
        ("exact-kind", with("[exact]\nkind = \"foo\"\n"), "foo"),
        (
            "generator",
            GOOD.replace("\"rectangle\"", "\"hexagon\""),
            "hexagon",
        ),
        (
            "refine",
            GOOD.replace("nx = 8", "nx = 8\nrefine = 40"),
            "mesh.refine",
        ),
        (
            "epsilon",
            GOOD.replace("stiffness = 100.0", "stiffness = 1\nepsilon = 0.1"),
            "epsilon",
        ),
        (
            "region",
            GOOD.replace("stiffness = 100.0", "stiffness = { clay = 5 }"),
            "clay",
        ),
        (
            "expression",
            GOOD.replace("load = \"8\"", "load = \"sqrt(x - 2)\""),
            "NaN",
        ),
        (
            "boundary-load",
            GOOD.replace("load = \"8\"", "load = \"1/x\""),
            "boundary",
        ),
        (
            "rigid-below",
            GOOD.replace("shape = \"0.1\"", "shape = \"-0.1\"")
                .replace("stiffness = 100.0", "stiffness = \"rigid\""),
            "below",
        ),
        (
            "profile-off-mesh",
            with("[output]\nprofile = [[100, 100], [200, 200]]\n"),
            "output.profile",
        ),
        (
            "sweep-parameter",
            with("[sweep]\nparameter = \"gravity\"\nvalues = [1, 2]\n"),
            "gravity",
        ),
        (
            "sweep-values",
            with("[sweep]\nparameter = \"tension\"\nvalues = [1, -2]\n"),
            "sweep.values",
        ),
        (
            "sweep-and-load-cases",
            with(
                "[sweep]\nparameter = \"load_factor\"\nvalues = [1]\n\
                 [[load_case]]\nname = \"a\"\n",
            ),
            "not both",
        ),
        (
            "load-case-name",
            with("[[load_case]]\nname = \"../up\"\n"),
            "load_case.0.name",
        ),
        (
            "load-case-key",
            with("[[load_case]]\nname = \"a\"\ntension = 2\n"),
            "tension",
        ),
        (
            "load-case-negative-h",
            with("[[load_case]]\nname = \"a\"\nstiffness = -1\n"),
            "load_case.0.stiffness",
        ),
        // Errors only the mesh reveals, in a load case: refused before any step is solved
        // (the first load case is good), naming the load case's key.
        (
            "load-case-region",
            with(
                "[[load_case]]\nname = \"dead\"\n\
                 [[load_case]]\nname = \"wet\"\nstiffness = { clay = 5.0 }\n",
            ),
            "load_case.1.stiffness",
        ),
        (
            "load-case-expression",
            with(
                "[[load_case]]\nname = \"dead\"\n\
                 [[load_case]]\nname = \"snow\"\nload = \"sqrt(x - 2)\"\n",
            ),
            "load_case.1.load",
        ),
        // NaN inside the domain only: found by assembling (check assembles every load
        // case; solve assembles the step, after solving the first).
        (
            "load-case-interior-nan",
            with(
                "[[load_case]]\nname = \"dead\"\n\
                 [[load_case]]\nname = \"snow\"\n\
                 load = \"if(abs(x - 0.5) + abs(y - 0.5) < 0.2, sqrt(-1), 1)\"\n",
            ),
            "load_case.1.load f is NaN",
        ),
        (
            "missing-mesh",
            GOOD.replace(
                "generator = \"rectangle\"\nnx = 8",
                "file = \"nowhere.msh\"",
            ),
            "nowhere.msh",
        ),
    ];
    for (name, body, needle) in &cases {
        both_refuse(d, name, body, needle);
    }
}
