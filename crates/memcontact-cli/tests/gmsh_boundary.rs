//! End to end, Gmsh physical curves as boundary regions: a structured rectangle written by
//! Gmsh in the four MSH flavours (`crates/memcontact/tests/data/rect.geo`, the triangles of
//! the rectangle generator) solves with free edges and heights per curve exactly like the
//! generator's mesh, refined or not; the vertex where a free edge meets a held one is held;
//! a physical curve inside the mesh is reported; a name the mesh lacks is refused with the
//! regions it has; the liner example (a Gmsh mesh with a free crest) solves.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

mod common;
use common::{examples, run, text, tmp_in};

const FLAVOURS: [&str; 4] = ["v22_ascii", "v22_binary", "v41_ascii", "v41_binary"];

fn fixture(flavour: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../memcontact/tests/data")
        .join(format!("rect_{flavour}.msh"))
}

/// The problem of the tests on the rectangle (0, 2) × (0, 1): stiffer soil on the upper
/// half (a region of the Gmsh mesh, an expression on the generator's), a body below,
/// heights per side, the top side free.
fn case_text(mesh: &str, stiffness: &str) -> String {
    format!(
        "{mesh}\n[membrane]\ntension = 1.0\nload = \"2 - 4*x*y\"\n\
         [obstacle]\nshape = 0.05\nstiffness = {stiffness}\n\
         [lower]\nshape = \"-0.02 - 0.01*x\"\nstiffness = 150.0\n\
         [boundary]\nheight = {{ bottom = \"0.01*x\", left = \"0.02*y\", right = \"0.02 + 0.01*y\" }}\n\
         free = [\"top\"]\n[solver]\ntolerance = 1e-12\n"
    )
}

fn gmsh_case(flavour: &str, refine: usize) -> String {
    case_text(
        &format!(
            "[mesh]\nfile = \"{}\"\nrefine = {refine}",
            fixture(flavour).display()
        ),
        "{ lower = 100.0, upper = 300.0 }",
    )
}

fn generator_case(refine: usize) -> String {
    let n = 16 << refine;
    case_text(
        &format!(
            "[mesh]\ngenerator = \"rectangle\"\nx1 = 2.0\nnx = {n}\nny = {}",
            n / 2
        ),
        "\"if(y < 0.5, 100, 300)\"",
    )
}

/// Solves `body` (a case file's text) into `dir/name`; the `nodes.csv` rows by their
/// coordinates (rounded to 1e-9) and the run's text.
fn solve(dir: &Path, name: &str, body: &str) -> (HashMap<(i64, i64), f64>, String) {
    let case = dir.join(format!("{name}.toml"));
    std::fs::write(&case, body).unwrap();
    let out = dir.join(name);
    let o = run(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
        "--set",
        "output.plot=false",
    ]);
    assert!(o.status.success(), "{name}: {}", text(&o));
    let csv = std::fs::read_to_string(out.join("nodes.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&header[..3], ["x", "y", "u"]);
    let key = |s: &str| (s.parse::<f64>().unwrap() * 1e9).round() as i64;
    let u = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            ((key(f[0]), key(f[1])), f[2].parse().unwrap())
        })
        .collect();
    (u, text(&o))
}

fn max_difference(a: &HashMap<(i64, i64), f64>, b: &HashMap<(i64, i64), f64>) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .map(|(k, u)| (u - b.get(k).expect("the same vertices")).abs())
        .fold(0.0, f64::max)
}

#[test]
fn every_msh_flavour_solves_like_the_generator_mesh_with_curves_as_boundary_regions() {
    let dir = tmp_in("gmsh-boundary", "flavours");
    for refine in [0, 2] {
        let (reference, _) = solve(&dir, &format!("gen-{refine}"), &generator_case(refine));
        // The free top side moves: the problem is not the all-fixed one.
        let top_mid = reference[&(1_000_000_000, 1_000_000_000)];
        assert!(top_mid.abs() > 1e-3, "{top_mid}");
        for flavour in FLAVOURS {
            let (u, out) = solve(
                &dir,
                &format!("{flavour}-{refine}"),
                &gmsh_case(flavour, refine),
            );
            let d = max_difference(&u, &reference);
            assert!(d <= 1e-9, "{flavour}, refine {refine}: {d:e}");
            // The seam inside the mesh is reported, not an error.
            assert!(
                out.contains("physical curve \"seam\" (tag 15): 16 line elements lie inside"),
                "{out}"
            );
        }
        // Multigrid on algebraic levels (aggregates of the Gmsh mesh) agrees too.
        let body = gmsh_case("v41_binary", refine).replace(
            "[solver]\n",
            "[solver]\nmethod = \"multigrid\"\nhierarchy = \"algebraic\"\n",
        );
        let (u, _) = solve(&dir, &format!("algebraic-{refine}"), &body);
        let d = max_difference(&u, &reference);
        assert!(d <= 1e-9, "algebraic levels, refine {refine}: {d:e}");
    }
}

#[test]
fn a_vertex_where_a_free_edge_meets_a_held_one_is_held() {
    let dir = tmp_in("gmsh-boundary", "corner");
    for flavour in ["v41_binary", "v22_ascii"] {
        let (u, _) = solve(&dir, flavour, &gmsh_case(flavour, 0));
        let at = |x: f64, y: f64| u[&((x * 1e9).round() as i64, (y * 1e9).round() as i64)];
        // The top's ends lie on the held left and right sides: held at their heights.
        assert_eq!(at(0.0, 1.0), 0.02);
        assert_eq!(at(2.0, 1.0), 0.03);
        // The top's inner vertices are unknowns, lifted off the frame's plane u = 0.
        for i in 1..16 {
            let x = i as f64 * 0.125;
            assert!(at(x, 1.0).abs() > 1e-4, "x = {x}: {}", at(x, 1.0));
        }
    }
    // Two free sides meeting: their common corner is free too (no held edge reaches it).
    let body = gmsh_case("v41_ascii", 0).replace("free = [\"top\"]", "free = [\"top\", \"right\"]");
    let (u, _) = solve(&dir, "two-free", &body);
    let corner = u[&(2_000_000_000, 1_000_000_000)];
    assert!((corner - 0.03).abs() > 1e-4, "{corner}");
}

#[test]
fn a_name_the_mesh_lacks_is_refused_with_the_regions_and_their_kinds() {
    let dir = tmp_in("gmsh-boundary", "names");
    for (key, body, extra) in [
        (
            "crest",
            gmsh_case("v41_ascii", 0).replace("free = [\"top\"]", "free = [\"crest\"]"),
            "",
        ),
        (
            "seam",
            gmsh_case("v22_binary", 0).replace("bottom = ", "seam = 0.0, bottom = "),
            "",
        ),
        (
            "upper",
            gmsh_case("v22_ascii", 0).replace("free = [\"top\"]", "free = [\"upper\"]"),
            "; 'upper' is a region of triangles",
        ),
    ] {
        let case = dir.join(format!("{key}.toml"));
        std::fs::write(&case, body).unwrap();
        let field = if key == "seam" {
            "boundary.height"
        } else {
            "boundary.free"
        };
        let needle = format!(
            "{field}: no boundary region named '{key}' in the mesh (boundary regions, curves: \
             bottom, right, top, left; regions of triangles, surfaces: lower, upper){extra}"
        );
        let out = dir.join(format!("out-{key}"));
        let c = run(&["check", case.to_str().unwrap()]);
        let s = run(&["solve", case.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        for o in [&c, &s] {
            assert!(!o.status.success(), "{key} accepted");
            assert!(text(o).contains(&needle), "{key}: {}", text(o));
        }
        assert!(!out.exists());
    }
}

#[test]
fn check_lists_the_boundary_regions_with_edges_lengths_and_kinds() {
    let dir = tmp_in("gmsh-boundary", "check");
    let case = dir.join("c.toml");
    std::fs::write(&case, gmsh_case("v41_binary", 0)).unwrap();
    let o = run(&["check", case.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains(
            "  boundary     bottom (16 edges, length 2.000000, held), right (8 edges, length \
             1.000000, held), top (16 edges, length 2.000000, free), left (8 edges, length \
             1.000000, held)"
        ),
        "{}",
        text(&o)
    );
    // A mesh without physical curves: one region, `default`, which `free` can name.
    let bare = dir.join("bare.msh");
    let msh = std::fs::read_to_string(fixture("v22_ascii")).unwrap();
    std::fs::write(&bare, without_lines(&msh)).unwrap();
    let body = gmsh_case("v22_ascii", 0)
        .replace(
            &fixture("v22_ascii").display().to_string(),
            bare.to_str().unwrap(),
        )
        .replace(
            "height = { bottom = \"0.01*x\", left = \"0.02*y\", right = \"0.02 + 0.01*y\" }",
            "height = 0.0",
        )
        .replace("free = [\"top\"]", "free = []");
    std::fs::write(&case, &body).unwrap();
    let o = run(&["check", case.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("  boundary     default (48 edges, length 6.000000, held)"),
        "{}",
        text(&o)
    );
    std::fs::write(&case, body.replace("free = []", "free = [\"default\"]")).unwrap();
    let o = run(&["check", case.to_str().unwrap()]);
    // The whole boundary free, with an elastic soil under it: well posed, and listed so.
    assert!(
        text(&o).contains("  boundary     default (48 edges, length 6.000000, free)"),
        "{}",
        text(&o)
    );
}

/// An MSH 2.2 ASCII file without its line elements (the triangles alone).
fn without_lines(msh: &str) -> String {
    let mut out = Vec::new();
    let mut lines = msh.lines();
    while let Some(l) = lines.next() {
        out.push(l.to_string());
        if l == "$Elements" {
            let _count = lines.next();
            let elements: Vec<&str> = lines
                .by_ref()
                .take_while(|l| *l != "$EndElements")
                .filter(|l| l.split_whitespace().nth(1) == Some("2"))
                .collect();
            out.push(elements.len().to_string());
            out.extend(elements.iter().map(|s| s.to_string()));
            out.push("$EndElements".into());
        }
    }
    out.join("\n") + "\n"
}

#[test]
fn the_liner_example_solves_with_its_crest_free() {
    let dir = tmp_in("gmsh-boundary", "liner");
    let out = dir.join("out");
    let o = run(&[
        "solve",
        examples().join("liner-slope.toml").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-q",
        "--set",
        "output.plot=false",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(!text(&o).contains("warning"), "{}", text(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["accepted"].as_bool().unwrap());
    // 2 × 30 crest edges free: 2 × 31 vertices, less the ends held by a flank or the
    // anchored stretch.
    assert_eq!(summary["free_boundary_vertices"], 58);
    let csv = std::fs::read_to_string(out.join("nodes.csv")).unwrap();
    let mut lines = csv.lines();
    lines.next();
    let (mut free_crest, mut held) = (0, 0);
    for l in lines {
        let f: Vec<f64> = l.split(',').map(|s| s.parse().unwrap()).collect();
        let (x, y, u) = (f[0], f[1], f[2]);
        if y == 20.0 && x > 15.0 && x < 25.0 {
            assert_eq!(u, 20.0 / 3.0, "the anchored crest at x = {x}");
            held += 1;
        } else if y == 20.0 && x > 0.0 && x < 40.0 && x != 15.0 && x != 25.0 {
            // The free crest settles below the frame onto the subsoil.
            assert!(u < 20.0 / 3.0 - 1e-6, "the free crest at x = {x}: u = {u}");
            free_crest += 1;
        } else if y == 0.0 {
            assert_eq!(u, 0.0);
        }
    }
    assert_eq!((held, free_crest), (19, 58));
}
