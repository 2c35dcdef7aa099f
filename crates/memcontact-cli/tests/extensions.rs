//! End to end, beyond the paper's frame: the closed forms of PETSc SNES ex9, MFEM ex36 and
//! a manufactured solution with boundary heights, a free edge and two bodies converge at
//! P1's rates through `memcontact convergence`; the example cases solve and their files
//! hold the body below's fields after the paper's columns; bad boundary data and
//! overlapping rigid bodies are refused by `check` and `solve` alike.

use std::path::Path;

mod common;
use common::{examples, run, text};

/// The header and rows of a CSV file.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let s = std::fs::read_to_string(path).unwrap();
    let mut lines = s.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

fn column(header: &[String], rows: &[Vec<String>], name: &str) -> Vec<f64> {
    let k = header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"));
    rows.iter()
        .map(|r| r[k].parse().unwrap_or(f64::NAN))
        .collect()
}

#[test]
fn closed_forms_converge_at_the_p1_rates() {
    let dir = tempfile::tempdir().unwrap();
    for (case, levels) in [
        ("petsc-ex9.toml", "3"),
        ("petsc-ex9-lower.toml", "3"),
        ("mfem-ex36.toml", "3"),
        ("manufactured-free-edge.toml", "3"),
    ] {
        let out = dir.path().join(case);
        let o = run(&[
            "convergence",
            examples().join(case).to_str().unwrap(),
            "--levels",
            levels,
            "-q",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{case}: {}", text(&o));
        let (header, rows) = read_csv(&out.join("convergence.csv"));
        let (l2, h1) = (
            column(&header, &rows, "l2_rate"),
            column(&header, &rows, "h1_rate"),
        );
        let last = rows.len() - 1;
        assert!(
            h1[last] >= 0.9 && l2[last] >= 1.8,
            "{case}: L² {l2:?}, H¹ {h1:?}"
        );
        let errors = column(&header, &rows, "h1_error");
        assert!(errors[last] < 0.2 * errors[0], "{case}: {errors:?}");
    }
}

#[test]
fn examples_solve_and_write_the_body_below_after_the_paper_columns() {
    let dir = tempfile::tempdir().unwrap();
    for case in ["roof-frame.toml", "geomembrane.toml", "plinth.toml"] {
        let out = dir.path().join(case);
        let o = run(&[
            "solve",
            examples().join(case).to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
            "--set",
            "output.plot=false",
        ]);
        assert!(o.status.success(), "{case}: {}", text(&o));
        let (header, rows) = read_csv(&out.join("nodes.csv"));
        let paper = [
            "x",
            "y",
            "u",
            "phi",
            "penetration",
            "pressure",
            "contact_force",
            "state",
        ];
        assert_eq!(&header[..8], &paper, "{case}");
        assert_eq!(
            &header[8..],
            [
                "phi_low",
                "penetration_low",
                "pressure_low",
                "contact_force_low",
                "state_low"
            ],
            "{case}"
        );
        // The lower state and penetration follow from u and φ_low as written.
        let (u, phi_low) = (
            column(&header, &rows, "u"),
            column(&header, &rows, "phi_low"),
        );
        let (pen, state) = (
            column(&header, &rows, "penetration_low"),
            column(&header, &rows, "state_low"),
        );
        let mut in_contact = 0;
        for i in 0..u.len() {
            if state[i] == 1.0 {
                assert!(u[i] < phi_low[i] && (pen[i] - (phi_low[i] - u[i])).abs() < 1e-12);
                in_contact += 1;
            } else if state[i] == 0.0 {
                assert_eq!(u[i], phi_low[i]);
                in_contact += 1;
            } else {
                assert_eq!(pen[i], 0.0);
            }
        }
        assert!(in_contact > 0, "{case}: the body below acts");
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        for key in [
            "contact_low_vertices",
            "total_contact_force_low",
            "contact_area_low",
            "squeezed_vertices",
            "lower_foundation",
        ] {
            assert!(summary.get(key).is_some(), "{case}: no {key}");
        }
        assert_eq!(summary["contact_low_vertices"], in_contact);
        assert!(summary["accepted"].as_bool().unwrap());
    }
    // The frame's heights are on the fixed boundary of the roof.
    let (header, rows) = read_csv(&dir.path().join("roof-frame.toml/nodes.csv"));
    let (x, y, u) = (
        column(&header, &rows, "x"),
        column(&header, &rows, "y"),
        column(&header, &rows, "u"),
    );
    for i in 0..x.len() {
        if y[i] == 0.0 && x[i] > 0.0 && x[i] < 12.0 {
            assert_eq!(u[i], 2.0);
        }
        if x[i] == 0.0 && y[i] > 0.0 && y[i] < 8.0 {
            assert!((u[i] - (2.0 + 0.075 * y[i])).abs() < 1e-14);
        }
    }
}

#[test]
fn bad_extension_data_is_refused_by_check_and_solve() {
    let dir = tempfile::tempdir().unwrap();
    let base = "[mesh]\ngenerator = \"rectangle\"\nnx = 8\n[membrane]\ntension = 1\n\
                load = 1\n[obstacle]\nshape = 0.1\nstiffness = 100\n";
    let cases = [
        (
            "lid",
            format!("{base}[boundary]\nfree = [\"lid\"]\n"),
            "no boundary region named 'lid'",
        ),
        (
            "nan",
            format!("{base}[boundary]\nheight = nan\n"),
            "boundary.height",
        ),
        (
            "loose",
            format!(
                "{}[boundary]\nfree = [\"left\", \"right\", \"top\", \"bottom\"]\n",
                base.replace("stiffness = 100", "stiffness = 0")
            ),
            "the membrane is not held",
        ),
        (
            "overlap",
            format!(
                "{}[lower]\nshape = \"0.3*sin(pi*x)*sin(pi*y) - 0.05\"\nstiffness = \"rigid\"\n",
                base.replace("stiffness = 100", "stiffness = \"rigid\"")
            ),
            "both bodies are rigid and overlap",
        ),
    ];
    for (name, body, needle) in cases {
        let case = dir.path().join(format!("{name}.toml"));
        std::fs::write(&case, body).unwrap();
        let out = dir.path().join(format!("out-{name}"));
        let c = run(&["check", case.to_str().unwrap()]);
        let s = run(&[
            "solve",
            case.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
        ]);
        assert!(
            !c.status.success() && !s.status.success(),
            "{name} accepted"
        );
        assert!(
            text(&c).contains(needle) && text(&s).contains(needle),
            "{name}: {}",
            text(&c)
        );
        assert!(!out.exists());
    }
}
