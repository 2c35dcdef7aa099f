//! End-to-end: `memcontact solve` on a case with `[adapt]` (the roof with a
//! re-entrant corner): `adapt.csv` with its exact header, the final step's result set on
//! the final mesh with the estimator per triangle, `mesh.png`, the adaptive totals in
//! `summary.json`, `[output] keep_steps`, and bad input refused naming the key with
//! nothing written.

mod common;

use common::{examples, run, text, tmp_in};
use std::path::Path;

/// The columns of `adapt.csv`, in order.
const HEADER: &str =
    "step,vertices,unknowns,estimator,energy,contact_area,iterations,kkt_residual,seconds";

fn example() -> String {
    examples()
        .join("roof-corner.toml")
        .to_str()
        .unwrap()
        .to_string()
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// `adapt.csv` as rows of named cells.
fn adapt_rows(dir: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let text = std::fs::read_to_string(dir.join("adapt.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    assert_eq!(header.join(","), HEADER);
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), header.len(), "{l}");
            header
                .iter()
                .cloned()
                .zip(cells.iter().map(|c| c.to_string()))
                .collect()
        })
        .collect()
}

fn num(row: &std::collections::HashMap<String, String>, key: &str) -> f64 {
    row[key].parse().unwrap()
}

/// The number of data rows of a `nodes.csv` (one per vertex).
fn node_rows(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("nodes.csv"))
        .unwrap()
        .lines()
        .count()
        - 1
}

#[test]
fn the_roof_corner_example_writes_its_history_and_the_final_mesh() {
    let out = tmp_in("adapt", "example");
    let o = run(&["solve", &example(), "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("step   0:"),
        "a line per step: {}",
        text(&o)
    );
    let rows = adapt_rows(&out);
    assert!(rows.len() >= 5, "{} steps", rows.len());
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(num(r, "step") as usize, k);
        assert!(num(r, "kkt_residual") <= 1e-10, "step {k}: certified");
        if k >= 2 {
            assert!(
                num(r, "iterations") <= 10.0,
                "step {k}: {}",
                r["iterations"]
            );
        }
    }
    for w in rows.windows(2) {
        assert!(num(&w[1], "vertices") > num(&w[0], "vertices"));
        assert!(num(&w[1], "estimator") < num(&w[0], "estimator"));
        // Nested spaces, frame at height 0, foam surface linear: J never rises.
        assert!(num(&w[1], "energy") <= num(&w[0], "energy") + 1e-9);
    }
    let last = rows.last().unwrap();
    let vertices = num(last, "vertices") as usize;
    assert!(vertices <= 30_000);
    // The final set is the last step's, on its mesh.
    assert_eq!(node_rows(&out), vertices);
    let s = summary(&out);
    assert_eq!(s["vertices"].as_u64().unwrap() as usize, vertices);
    assert_eq!(s["adapt_steps"].as_u64().unwrap() as usize, rows.len());
    assert_eq!(s["adapt_stop"], "max_vertices");
    assert_eq!(s["energy"].as_f64().unwrap(), num(last, "energy"));
    assert_eq!(
        s["adapt_estimator"].as_f64().unwrap(),
        num(last, "estimator")
    );
    assert_eq!(s["adapt_start_vertices"].as_u64().unwrap(), 171);
    let vtu = std::fs::read_to_string(out.join("solution.vtu")).unwrap_or_default();
    let vtu = if vtu.is_empty() {
        String::from_utf8_lossy(&std::fs::read(out.join("solution.vtu")).unwrap()).into_owned()
    } else {
        vtu
    };
    assert!(vtu.contains("Name=\"estimator\""), "estimator per triangle");
    let png = std::fs::read(out.join("mesh.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // Only the final set: no step directories without keep_steps.
    assert!(!out.join("step-000").exists());
}

#[test]
fn keep_steps_writes_every_step() {
    let out = tmp_in("adapt", "keep");
    let o = run(&[
        "solve",
        &example(),
        "-o",
        out.to_str().unwrap(),
        "-q",
        "--set",
        "adapt.max_vertices=1500",
        "--set",
        "output.keep_steps=true",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let rows = adapt_rows(&out);
    for (k, r) in rows.iter().enumerate() {
        let dir = out.join(format!("step-{k:03}"));
        assert_eq!(node_rows(&dir), num(r, "vertices") as usize, "step {k}");
        let s = summary(&dir);
        assert_eq!(s["energy"].as_f64().unwrap(), num(r, "energy"));
        assert!(dir.join("solution.vtu").exists());
    }
    assert!(!out.join(format!("step-{:03}", rows.len())).exists());
}

#[test]
fn bad_adapt_settings_are_refused_naming_the_key_and_nothing_is_written() {
    let dir = tmp_in("adapt", "bad");
    let out = dir.join("out");
    for (set, key) in [
        ("adapt.theta=0", "adapt.theta"),
        ("adapt.theta=1.5", "adapt.theta"),
        ("adapt.steps=0", "adapt.steps"),
        ("adapt.max_vertices=100", "adapt.max_vertices"),
        ("adapt.tolerance=-1", "adapt.tolerance"),
        ("adapt.free_boundary_rings=-1", "adapt.free_boundary_rings"),
        ("adapt.refine=2", "refine"),
    ] {
        let o = run(&[
            "solve",
            &example(),
            "-o",
            out.to_str().unwrap(),
            "-q",
            "--set",
            set,
        ]);
        assert!(!o.status.success(), "{set} accepted");
        assert!(text(&o).contains(key), "{set}: {}", text(&o));
        assert!(!text(&o).contains("panicked"), "{set}: {}", text(&o));
        assert!(!out.exists(), "{set}: something was written");
        // `check` finds the same, and says nothing is valid.
        let o = run(&["check", &example(), "--set", set]);
        assert!(!o.status.success(), "check accepted {set}");
        assert!(
            text(&o).contains(key) && !text(&o).contains(": valid"),
            "{set}: {}",
            text(&o)
        );
    }
    // A mesh of more vertices than memory or 32-bit indices allow is refused up front.
    let o = run(&[
        "check",
        &example(),
        "--set",
        "adapt.max_vertices=100000000000",
    ]);
    assert!(!o.status.success());
    assert!(text(&o).contains("adapt.max_vertices"), "{}", text(&o));
    let o = run(&["check", &example()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("adaptive     from this mesh, at most 20 steps and 30000 vertices"),
        "{}",
        text(&o)
    );
    // [adapt] with the steps of a sweep or load cases: refused with the reason.
    let base = std::fs::read_to_string(example()).unwrap();
    for (name, extra) in [
        (
            "sweep",
            "[sweep]\nparameter = \"load_factor\"\nvalues = [0.5, 1.0]\n",
        ),
        (
            "load-cases",
            "[[load_case]]\nname = \"a\"\nload = -1.0\n\n[[load_case]]\nname = \"b\"\nload = -2.0\n",
        ),
    ] {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, format!("{base}\n{extra}")).unwrap();
        let o = run(&[
            "solve",
            path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
        ]);
        assert!(!o.status.success(), "{name} accepted");
        assert!(text(&o).contains("[adapt]"), "{name}: {}", text(&o));
        assert!(!out.exists());
    }
}

#[test]
fn a_gmsh_mesh_with_boundary_regions_adapts_and_keeps_them() {
    // The liner on a slope: a Gmsh mesh whose physical curves carry heights (held) and a
    // free crest, two cover soils above (regions) and the subsoil below.
    let dir = tmp_in("adapt", "gmsh");
    let base = std::fs::read_to_string(examples().join("liner-slope.toml")).unwrap();
    let case = dir.join("liner.toml");
    std::fs::copy(
        examples().join("liner-slope.msh"),
        dir.join("liner-slope.msh"),
    )
    .unwrap();
    std::fs::write(&case, format!("{base}\n[adapt]\nmax_vertices = 8000\n")).unwrap();
    let (plain, adapted) = (dir.join("plain"), dir.join("adapted"));
    let o = run(&[
        "solve",
        examples().join("liner-slope.toml").to_str().unwrap(),
        "-o",
        plain.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let o = run(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        adapted.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let rows = adapt_rows(&adapted);
    assert!(rows.len() >= 3);
    assert!(rows.iter().all(|r| num(r, "kkt_residual") <= 1e-10));
    let (p, a) = (summary(&plain), summary(&adapted));
    // Step 0 is the plain solve (to rounding: the loop orders each triangle's vertices
    // from its longest edge, which changes the order of the sums).
    let (j0, j) = (num(&rows[0], "energy"), p["energy"].as_f64().unwrap());
    assert!((j0 - j).abs() <= 1e-12 * j.abs(), "{j0} vs {j}");
    // Refined edges of the held and the free boundary stay held and free.
    for key in ["fixed_vertices", "free_boundary_vertices"] {
        assert!(
            a[key].as_u64().unwrap() > p[key].as_u64().unwrap(),
            "{key}: {} → {}",
            p[key],
            a[key]
        );
    }
    let (area, area0) = (a["area"].as_f64().unwrap(), p["area"].as_f64().unwrap());
    assert!(
        (area - area0).abs() < 1e-12 * area0,
        "the domain is the same: {area} vs {area0}"
    );
}

#[test]
fn the_lumped_foundation_adapts_too() {
    let out = tmp_in("adapt", "lumped");
    let o = run(&[
        "solve",
        &example(),
        "-o",
        out.to_str().unwrap(),
        "-q",
        "--set",
        "obstacle.foundation=lumped",
        "--set",
        "adapt.max_vertices=5000",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let rows = adapt_rows(&out);
    assert!(rows.len() >= 5);
    assert!(rows.iter().all(|r| num(r, "kkt_residual") <= 1e-10));
    let (first, last) = (&rows[0], rows.last().unwrap());
    assert!(num(last, "estimator") < num(first, "estimator") / 3.0);
    assert_eq!(summary(&out)["foundation"], "lumped");
}
