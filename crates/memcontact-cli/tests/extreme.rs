//! Extreme data through the command-line tool, with every method: each class either exits
//! 0 with an accepted certificate and an answer an independent fact confirms (the free
//! membrane, the obstacle's bound, a non-zero deflection where a load acts), or exits 1
//! with a message naming the condition and writes nothing. Also: the rounding-floor note,
//! `--threads`, the refusals of resources, and `convergence` failing with a level.

mod common;

use common::{bin, text, tmp_in, Tmp};
use std::path::{Path, PathBuf};
use std::process::Output;

/// Every method a case file can name.
const METHODS: [&str; 6] = [
    "auto",
    "linear",
    "active-set",
    "qp",
    "coordinate",
    "multigrid",
];

/// A case: `[mesh]` lines, `[membrane]` lines, `[obstacle]` lines, no pictures.
fn case(dir: &Path, name: &str, mesh: &str, membrane: &str, obstacle: &str) -> PathBuf {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(
        &path,
        format!(
            "[mesh]\n{mesh}\n[membrane]\n{membrane}\n[obstacle]\n{obstacle}\n[output]\nplot = false\n"
        ),
    )
    .unwrap();
    path
}

/// `memcontact solve CASE -o OUT --set solver.method=METHOD [extra]`.
fn solve(case: &Path, out: &Path, method: &str, extra: &[&str]) -> Output {
    bin()
        .args(["solve", "-q", "-o"])
        .arg(out)
        .arg(case)
        .args(["--set", &format!("solver.method={method}")])
        .args(extra)
        .output()
        .unwrap()
}

/// The summary of a result directory.
fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The outcome of one method on one class.
enum Expect {
    /// Exit 0, accepted, and the summary passes the check.
    Answer(fn(&serde_json::Value) -> bool),
    /// Exit 0 with such an answer, or exit 1 with a message holding all the needles.
    AnswerOrRefusal(fn(&serde_json::Value) -> bool, &'static [&'static str]),
    /// Exit 1 with a message holding all the needles.
    Refusal(&'static [&'static str]),
}

/// Runs `method` on `case` and checks the expectation; the exit code and the files agree.
fn check(what: &str, case: &Path, out: &Tmp, method: &str, expect: &Expect) {
    let dir = out.join(format!("{what}-{method}"));
    let o = solve(case, &dir, method, &[]);
    let t = text(&o);
    let answer = |check: &fn(&serde_json::Value) -> bool| {
        let s = summary(&dir);
        assert_eq!(s["accepted"], true, "{what} {method}: {t}");
        let kkt = s["kkt_residual"].as_f64().unwrap();
        let bound = s["tolerance"]
            .as_f64()
            .unwrap()
            .max(8.0 * s["rounding_floor"].as_f64().unwrap());
        assert!(kkt <= bound, "{what} {method}: KKT {kkt:e} above {bound:e}");
        assert!(check(&s), "{what} {method}: {s}");
    };
    let refusal = |needles: &[&str]| {
        assert_eq!(o.status.code(), Some(1), "{what} {method}: {t}");
        for n in needles {
            assert!(t.contains(n), "{what} {method}: no '{n}' in {t}");
        }
        assert!(t.contains("error:"), "{what} {method}: {t}");
        assert!(!dir.exists(), "{what} {method}: files written on a refusal");
    };
    match expect {
        Expect::Answer(c) => {
            assert!(o.status.success(), "{what} {method}: {t}");
            answer(c);
        }
        Expect::AnswerOrRefusal(c, needles) => {
            if o.status.success() {
                answer(c);
            } else {
                refusal(needles);
            }
        }
        Expect::Refusal(needles) => refusal(needles),
    }
}

fn max_u(s: &serde_json::Value) -> f64 {
    s["max_u"].as_f64().unwrap()
}

fn min_u(s: &serde_json::Value) -> f64 {
    s["min_u"].as_f64().unwrap()
}

/// `linear` needs a problem without contact (`multigrid` runs on the mesh's refinement
/// levels, or on algebraic levels where it has none).
fn expectation(method: &str, contact: bool, e: Expect) -> Expect {
    match method {
        "linear" if contact => Expect::Refusal(&["linear", "contact"]),
        _ => e,
    }
}

const SQUARE: &str = "generator = \"rectangle\"\nnx = 16";

/// The largest deflection of the free membrane (h = 0) under f/t = 10 on `SQUARE`, from the
/// linear solve S U = D (an independent formulation): 0.734457665789197.
const FREE_10: f64 = 0.734_457_665_789_197;

#[test]
fn every_class_of_extreme_data_gives_a_certified_answer_or_a_named_refusal() {
    let dir = tmp_in("extreme", "cases");
    let out = tmp_in("extreme", "out");
    // (name, mesh, membrane, obstacle, can touch, has a hierarchy, expectation)
    type Check = fn(&serde_json::Value) -> bool;
    let rigid_msg: &'static [&'static str] = &["double precision"];
    let classes: Vec<(&str, &str, &str, &str, bool, bool, Expect)> = vec![
        // The free membrane of f = 20 on the unit square reaches 1.469; never u = 0.
        (
            "far-obstacle",
            SQUARE,
            "tension = 1\nload = 20",
            "shape = 1e9\nstiffness = 100",
            true,
            true,
            Expect::Answer((|s| (max_u(s) - 2.0 * FREE_10).abs() < 1e-8) as Check),
        ),
        // Near-rigid soils: the rigid bound (u ≤ φ up to f/h) or a refusal that says why.
        (
            "near-rigid",
            SQUARE,
            "tension = 1\nload = 8",
            "shape = 0.1\nstiffness = 1e15",
            true,
            true,
            Expect::AnswerOrRefusal(|s| max_u(s) > 0.09 && max_u(s) < 0.1 + 1e-6, rigid_msg),
        ),
        // A small load on a stiff soil: a small but non-zero deflection.
        (
            "small-load-stiff-soil",
            SQUARE,
            "tension = 1\nload = 1e-4",
            "shape = 0\nstiffness = 1e7",
            true,
            true,
            Expect::Answer(|s| max_u(s) > 0.0 && max_u(s) < 1e-4),
        ),
        // A stiff half beside a free one: the free half deflects.
        (
            "stiff-beside-free",
            SQUARE,
            "tension = 1\nload = 10",
            "shape = 0.05\nstiffness = \"if(x < 0.5, 1e7, 0)\"",
            true,
            true,
            Expect::Answer(|s| max_u(s) > 0.1),
        ),
        // h from 1e-12 to 1e12 and t from 1e-8 to 1e8 (f/t = 10 throughout).
        (
            "soft-soil",
            SQUARE,
            "tension = 1\nload = 10",
            "shape = 0.1\nstiffness = 1e-12",
            true,
            true,
            Expect::Answer(|s| (max_u(s) - FREE_10).abs() < 1e-6),
        ),
        (
            "stiff-soil",
            SQUARE,
            "tension = 1\nload = 10",
            "shape = 0.1\nstiffness = 1e12",
            true,
            true,
            Expect::AnswerOrRefusal(|s| max_u(s) < 0.1 + 1e-6, rigid_msg),
        ),
        (
            "slack-membrane",
            SQUARE,
            "tension = 1e-8\nload = 1e-7",
            "shape = 0.1\nstiffness = 1e-4",
            true,
            true,
            Expect::AnswerOrRefusal(|s| max_u(s) < 0.8, rigid_msg),
        ),
        (
            "taut-membrane",
            SQUARE,
            "tension = 1e8\nload = 1e9",
            "shape = 0.1\nstiffness = 1e4",
            true,
            true,
            // The body (h = 1e4) pushes back a little: below the free membrane, barely.
            Expect::Answer(|s| max_u(s) <= FREE_10 && max_u(s) > FREE_10 - 1e-4),
        ),
        // f = 0 with a body above: u = 0 exactly.
        (
            "no-load",
            SQUARE,
            "tension = 1\nload = 0",
            "shape = 0.2\nstiffness = 100",
            true,
            true,
            Expect::Answer(|s| max_u(s) == 0.0 && min_u(s) == 0.0),
        ),
        // f = 0 and h = 0: the linear problem, u = 0.
        (
            "no-load-no-body",
            SQUARE,
            "tension = 1\nload = 0",
            "shape = 0.2\nstiffness = 0",
            false,
            true,
            Expect::Answer(|s| max_u(s) == 0.0),
        ),
        // A body far below pushes the membrane down.
        (
            "far-below",
            SQUARE,
            "tension = 1\nload = 0",
            "shape = -1e6\nstiffness = 1",
            true,
            true,
            Expect::Answer(|s| min_u(s) < -1.0 && max_u(s) <= 0.0),
        ),
        // φ is the free solution of the disc, u = 2(1 − r²): within the discretisation.
        (
            "shape-is-free-solution",
            "generator = \"disk\"\nsize = 0.2",
            "tension = 1\nload = 8",
            "shape = \"2*(1 - r^2)\"\nstiffness = 1000",
            true,
            false,
            Expect::Answer(|s| (max_u(s) - 2.0).abs() < 0.1),
        ),
        // Cells of 3.56 × 0.0625: angles of 1°.
        (
            "slivers",
            "generator = \"rectangle\"\nx1 = 57\nnx = 16",
            "tension = 1\nload = 0.01",
            "shape = 0.5\nstiffness = 100",
            true,
            true,
            Expect::Answer(|s| s["min_angle_deg"].as_f64().unwrap() < 1.01 && max_u(s) > 0.0),
        ),
        // One interior vertex.
        (
            "one-unknown",
            "generator = \"rectangle\"\nnx = 2",
            "tension = 1\nload = 12",
            "shape = 0.1\nstiffness = 50",
            true,
            false,
            Expect::Answer(|s| s["unknowns"] == 1 && max_u(s) > 0.1),
        ),
        // Overflow: refused before solving, naming the data.
        (
            "overflowing-tension",
            SQUARE,
            "tension = 1e308\nload = 1",
            "shape = 0.1\nstiffness = 1",
            true,
            true,
            Expect::Refusal(&["overflow", "tension"]),
        ),
        (
            "overflowing-load",
            SQUARE,
            "tension = 1\nload = -1e300",
            "shape = 0.1\nstiffness = 1",
            true,
            true,
            Expect::Refusal(&["overflow", "load"]),
        ),
    ];
    for (name, mesh, membrane, obstacle, contact, _hierarchy, expect) in &classes {
        let path = case(&dir, name, mesh, membrane, obstacle);
        for method in METHODS {
            let e = match expect {
                // Refusals of the data come before any method is chosen.
                Expect::Refusal(n) => Expect::Refusal(n),
                Expect::Answer(c) => expectation(method, *contact, Expect::Answer(*c)),
                Expect::AnswerOrRefusal(c, n) => {
                    expectation(method, *contact, Expect::AnswerOrRefusal(*c, n))
                }
            };
            check(name, &path, &out, method, &e);
        }
    }
}

#[test]
fn tolerances_that_certify_nothing_and_the_rounding_floor() {
    let dir = tmp_in("extreme", "floor");
    let path = case(
        &dir,
        "square",
        "generator = \"rectangle\"\nnx = 32",
        "tension = 1\nload = 8",
        "shape = 0.1\nstiffness = 100",
    );
    for tol in ["1.0", "0.01"] {
        let out = dir.join(format!("tol-{tol}"));
        let o = solve(
            &path,
            &out,
            "auto",
            &["--set", &format!("solver.tolerance={tol}")],
        );
        assert_eq!(o.status.code(), Some(1));
        assert!(text(&o).contains("solver.tolerance") && text(&o).contains("cannot certify"));
        assert!(!out.exists());
    }
    // A tolerance below the rounding floor: accepted at the floor (the default), with a
    // note on what to set; refused when the case does not accept the floor.
    for method in ["auto", "active-set", "multigrid"] {
        let out = dir.join(format!("floor-{method}"));
        let o = solve(&path, &out, method, &["--set", "solver.tolerance=1e-17"]);
        let t = text(&o);
        assert!(o.status.success(), "{method}: {t}");
        assert!(
            t.contains("rounding floor") && t.contains("tolerance = "),
            "{t}"
        );
        let s = summary(&out);
        assert_eq!(s["status"], "rounding_floor");
        assert_eq!(s["accepted"], true);
        let (kkt, floor) = (
            s["kkt_residual"].as_f64().unwrap(),
            s["rounding_floor"].as_f64().unwrap(),
        );
        assert!(kkt > 1e-17 && kkt <= 8.0 * floor, "{kkt:e} {floor:e}");
        let out = dir.join(format!("strict-{method}"));
        let o = solve(
            &path,
            &out,
            method,
            &[
                "--set",
                "solver.tolerance=1e-17",
                "--set",
                "solver.accept_rounding_floor=false",
            ],
        );
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{method}: {t}");
        assert!(
            t.contains("rounding floor") && t.contains("To accept it"),
            "{t}"
        );
        assert!(!out.exists());
    }
}

#[test]
fn threads_give_identical_results() {
    let dir = tmp_in("extreme", "threads");
    let path = case(
        &dir,
        "square",
        "generator = \"rectangle\"\nnx = 64",
        "tension = 1\nload = \"8 + 4*sin(3*x)\"",
        "shape = \"0.05 + 0.1*y\"\nstiffness = 300",
    );
    for method in ["multigrid", "active-set", "coordinate"] {
        let mut results = Vec::new();
        for threads in ["1", "2"] {
            let out = dir.join(format!("{method}-{threads}"));
            let o = bin()
                .args(["--threads", threads, "solve", "-q", "-o"])
                .arg(&out)
                .arg(&path)
                .args(["--set", &format!("solver.method={method}")])
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", text(&o));
            let s = summary(&out);
            results.push((
                std::fs::read(out.join("nodes.csv")).unwrap(),
                s["energy"].as_f64().unwrap().to_bits(),
                s["iterations"].clone(),
            ));
        }
        assert!(results[0] == results[1], "{method}: 1 and 2 threads differ");
    }
    let o = bin()
        .args(["--threads", "0", "check"])
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("--threads"));
}

#[test]
fn resources_beyond_the_machine_are_refused_before_allocation() {
    let dir = tmp_in("extreme", "resources");
    let path = case(
        &dir,
        "square",
        "generator = \"rectangle\"\nnx = 8\nrefine = 12",
        "tension = 1\nload = 8",
        "shape = 0.1\nstiffness = 100",
    );
    for command in ["solve", "check"] {
        let out = dir.join("out");
        let mut c = bin();
        c.arg(command).arg(&path);
        if command == "solve" {
            c.arg("-o").arg(&out);
        }
        let o = c.output().unwrap();
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{command}: {t}");
        assert!(
            t.contains("mesh.refine = 12") && t.contains("GB of memory"),
            "{t}"
        );
        assert!(!out.exists());
    }
    // A memory limit set by the user is honoured.
    let small = case(
        &dir,
        "small",
        "generator = \"rectangle\"\nnx = 8\nrefine = 4",
        "tension = 1\nload = 8",
        "shape = 0.1\nstiffness = 100",
    );
    let o = bin()
        .env("MEMCONTACT_MEMORY_LIMIT", "1M")
        .arg("check")
        .arg(&small)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("MEMCONTACT_MEMORY_LIMIT=1M"),
        "{}",
        text(&o)
    );
    assert!(bin()
        .arg("check")
        .arg(&small)
        .output()
        .unwrap()
        .status
        .success());
    // The estimate follows the kind of run (bytes per vertex: 320 for one solve with a
    // lumped foundation, 540 with the consistent one): 66 049 vertices fit in 30 MB
    // lumped (21 MB), not consistent (36 MB); solve agrees with check.
    let lean = case(
        &dir,
        "lean",
        "generator = \"rectangle\"\nnx = 256",
        "tension = 1\nload = 8",
        "shape = 0.1\nstiffness = 100\nfoundation = \"lumped\"",
    );
    for (foundation, fits) in [("lumped", true), ("consistent", false)] {
        for command in ["check", "solve"] {
            let mut c = bin();
            c.env("MEMCONTACT_MEMORY_LIMIT", "30M")
                .arg(command)
                .arg(&lean)
                .args(["--set", &format!("obstacle.foundation={foundation}")]);
            if command == "solve" {
                c.arg("-q").arg("-o").arg(dir.join("lean-out"));
            }
            let o = c.output().unwrap();
            let t = text(&o);
            assert_eq!(o.status.success(), fits, "{foundation} {command}: {t}");
            if !fits {
                assert!(t.contains("MB of memory") && t.contains("30.00 MB"), "{t}");
            }
            let _ = std::fs::remove_dir_all(dir.join("lean-out"));
        }
    }
    // A direct solver's factorisation is checked too, by check as by solve.
    let square = case(
        &dir,
        "square64",
        "generator = \"rectangle\"\nnx = 64",
        "tension = 1\nload = 8",
        "shape = 0.1\nstiffness = 100",
    );
    for command in ["check", "solve"] {
        let mut c = bin();
        c.env("MEMCONTACT_MEMORY_LIMIT", "8M")
            .arg(command)
            .arg(&square)
            .args(["--set", "solver.method=qp"]);
        if command == "solve" {
            c.arg("-o").arg(dir.join("qp"));
        }
        let o = c.output().unwrap();
        let t = text(&o);
        assert_eq!(o.status.code(), Some(1), "{command}: {t}");
        assert!(
            t.contains("solver qp: its factorisation") && t.contains("8.00 MB"),
            "{t}"
        );
        assert!(!dir.join("qp").exists());
    }
    let o = bin()
        .env("MEMCONTACT_MEMORY_LIMIT", "8M")
        .arg("check")
        .arg(&square)
        .args(["--set", "solver.method=active-set"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("memory       about"), "{}", text(&o));
    // The convergence study of a disc to 9 levels.
    let disc = case(
        &dir,
        "disc",
        "generator = \"disk\"",
        "tension = 1\nload = 8",
        "shape = 0.1\nstiffness = 100",
    );
    let o = bin()
        .env("MEMCONTACT_MEMORY_LIMIT", "8G")
        .args(["convergence", "--levels", "9", "-o"])
        .arg(dir.join("conv"))
        .arg(&disc)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("9 levels") && text(&o).contains("memory"),
        "{}",
        text(&o)
    );
    // A FIFO and a device are refused at once as mesh files.
    #[cfg(unix)]
    {
        let fifo = dir.join("pipe.msh");
        assert!(std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success());
        for file in [fifo.to_str().unwrap(), "/dev/zero"] {
            let p = case(
                &dir,
                "special",
                &format!("file = \"{file}\""),
                "tension = 1\nload = 8",
                "shape = 0.1\nstiffness = 100",
            );
            let o = bin().arg("check").arg(&p).output().unwrap();
            assert_eq!(o.status.code(), Some(1));
            assert!(text(&o).contains("not a regular file"), "{}", text(&o));
        }
        let o = bin().args(["check", "/dev/zero"]).output().unwrap();
        assert!(text(&o).contains("not a regular file"), "{}", text(&o));
    }
}

#[test]
fn convergence_exits_non_zero_when_a_level_fails() {
    let dir = tmp_in("extreme", "convergence");
    let path = case(
        &dir,
        "square",
        "generator = \"rectangle\"\nnx = 4",
        "tension = 1\nload = 8",
        "shape = 0.1\nstiffness = 100",
    );
    // Two coordinate sweeps cannot reach 1e-10 on the finer levels.
    let out = dir.join("out");
    let o = bin()
        .args(["convergence", "--levels", "2", "-q", "-o"])
        .arg(&out)
        .arg(&path)
        .args([
            "--set",
            "solver.method=coordinate",
            "--set",
            "solver.max_iterations=2",
        ])
        .output()
        .unwrap();
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("level") && t.contains("iteration limit"), "{t}");
    assert!(!out.exists(), "a failed study wrote files");
    // A load singular on the boundary is refused by the study as by solve.
    let singular = case(
        &dir,
        "singular",
        "generator = \"rectangle\"\nnx = 4",
        "tension = 1\nload = \"1/x\"",
        "shape = 0.1\nstiffness = 100",
    );
    let o = bin()
        .args(["convergence", "--levels", "1", "-q", "-o"])
        .arg(&out)
        .arg(&singular)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o).contains("boundary"), "{}", text(&o));
    // The same case without the failure: a study, exit 0.
    let o = bin()
        .args(["convergence", "--levels", "2", "-q", "-o"])
        .arg(&out)
        .arg(&path)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn a_sweep_step_that_overflows_is_refused_naming_the_step() {
    let dir = tmp_in("extreme", "sweep");
    let path = dir.join("sweep.toml");
    std::fs::write(
        &path,
        "[mesh]\ngenerator = \"rectangle\"\nnx = 8\n[membrane]\ntension = 1\nload = 8\n\
         [obstacle]\nshape = 0.1\nstiffness = 100\n[output]\nplot = false\n\
         [sweep]\nparameter = \"load_factor\"\nvalues = [1, 1e305]\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = bin()
        .args(["solve", "-q", "-o"])
        .arg(&out)
        .arg(&path)
        .output()
        .unwrap();
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(
        t.contains("step-001") && t.contains("load_factor = 1e305"),
        "{t}"
    );
    assert!(t.contains("overflow"), "{t}");
    assert!(!out.exists());
}
