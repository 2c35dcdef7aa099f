//! The documentation's case-file reference against the program: every key the key table
//! of a section's page (`docs/case-file/*.md`) lists is accepted by `memcontact check` (with
//! a sample value), and every key of the samples is in that table, so that neither can
//! drift from the other. A key the program accepts must have a sample here (the check is
//! strict: a key not accepted is refused, naming it), and so a row in the docs.

use std::path::{Path, PathBuf};

mod common;
use common::{run, text, tmp_in};

/// Every section of a case file, its page under `docs/case-file/`, and how its heading
/// names it.
const SECTIONS: [(&str, &str, &str); 15] = [
    ("mesh", "mesh.md", "`[mesh]`"),
    ("membrane", "membrane.md", "`[membrane]`"),
    ("obstacle", "obstacle.md", "`[obstacle]`"),
    ("lower", "lower.md", "`[lower]`"),
    ("boundary", "boundary.md", "`[boundary]`"),
    ("solver", "solver.md", "`[solver]`"),
    ("output", "output.md", "`[output]`"),
    ("units", "units.md", "`[units]`"),
    ("sweep", "sweep.md", "`[sweep]`"),
    ("load_case", "load-case.md", "`[[load_case]]`"),
    ("adapt", "adapt.md", "`[adapt]`"),
    ("sensor", "sensor.md", "`[[sensor]]`"),
    ("sensitivity", "sensitivity.md", "`[sensitivity]`"),
    ("fit", "fit.md", "`[fit]`"),
    ("exact", "exact.md", "`[exact]`"),
];

fn docs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/case-file")
}

/// The keys of a section page's key table: the backquoted words of the first cell of each
/// row that starts with "| `". The page's title must name the section.
fn documented_keys(page: &str, title: &str) -> Vec<String> {
    let path = docs().join(page);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let heading = text.lines().next().unwrap_or("");
    assert!(
        heading.starts_with("# ") && heading.contains(title),
        "{page}: the page's heading should name {title}, got {heading:?}"
    );
    let mut keys = Vec::new();
    for row in text.lines().filter(|l| l.starts_with("| `")) {
        let first = row.split('|').nth(1).unwrap();
        keys.extend(first.split('`').skip(1).step_by(2).map(str::to_string));
    }
    assert!(!keys.is_empty(), "{page}: no key table");
    keys
}

/// Sample values (TOML) for every key a section accepts, in groups that can stand in one
/// case together (a rectangle's keys and a disc's cannot, nor `values` and `steps`).
fn samples(section: &str) -> Vec<Vec<(&'static str, &'static str)>> {
    match section {
        "mesh" => vec![
            vec![
                ("generator", "\"rectangle\""),
                ("x0", "-1.0"),
                ("y0", "-1.0"),
                ("x1", "1.0"),
                ("y1", "1.0"),
                ("nx", "8"),
                ("ny", "8"),
                ("diagonal", "\"alternate\""),
                ("refine", "1"),
            ],
            vec![
                ("generator", "\"disk\""),
                ("center", "[0.5, 0.5]"),
                ("radius", "0.5"),
                ("size", "0.1"),
            ],
            vec![
                ("generator", "\"polygon\""),
                ("outer", "[[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]"),
                ("holes", "[[[1.2, 0.4], [1.6, 0.4], [1.6, 0.6], [1.2, 0.6]]]"),
                (
                    "regions",
                    "[{ name = \"block\", polygon = [[0.2, 0.2], [0.8, 0.2], [0.8, 0.8], [0.2, 0.8]] }]",
                ),
                ("size", "0.1"),
                ("min_angle", "28.0"),
            ],
            vec![("file", "\"disk.msh\"")],
            // Written by the program for a mesh given as data: a known key, whose case
            // cannot be solved from the file alone (checked below).
            vec![("given", "\"620 vertices, 1160 triangles, 1 level, xxh3 0\"")],
        ],
        "membrane" => vec![vec![("tension", "2.0"), ("load", "\"1 + x\"")]],
        "obstacle" => vec![vec![
            ("shape", "0.2"),
            ("stiffness", "{ default = 100.0 }"),
            ("foundation", "\"lumped\""),
            ("sampling", "\"mollified\""),
            ("epsilon", "0.05"),
        ]],
        "lower" => vec![vec![
            ("shape", "\"-0.2 + 0.01*x\""),
            ("stiffness", "{ default = 300.0 }"),
            ("foundation", "\"consistent\""),
            ("sampling", "\"mollified\""),
            ("epsilon", "0.05"),
        ]],
        "boundary" => vec![vec![
            (
                "height",
                "{ bottom = 0.0, left = \"0.01*y\", right = 0.02, default = 0.0 }",
            ),
            ("free", "[\"top\"]"),
        ]],
        "solver" => vec![vec![
            ("method", "\"multigrid\""),
            ("tolerance", "1e-9"),
            ("max_iterations", "50"),
            ("accept_rounding_floor", "false"),
            ("hierarchy", "\"algebraic\""),
        ]],
        "output" => vec![vec![
            ("vtu", "\"ascii\""),
            ("csv", "false"),
            ("plots", "[\"deflection\"]"),
            ("plot", "true"),
            ("allowable_pressure", "5.0"),
            ("profile", "[[0.0, 0.5], [1.0, 0.5]]"),
            ("keep_steps", "true"),
        ]],
        "units" => vec![vec![("length", "\"m\""), ("force", "\"kN\"")]],
        "sweep" => vec![
            vec![
                ("parameter", "\"load_factor\""),
                ("values", "[0.5, 1.0]"),
            ],
            vec![
                ("parameter", "\"tension\""),
                ("from", "1.0"),
                ("to", "2.0"),
                ("steps", "3"),
            ],
        ],
        "load_case" => vec![vec![
            ("name", "\"snow\""),
            ("load", "\"1.2 + 0.8*step(y - 0.5)\""),
            ("load_factor", "1.35"),
            ("shape", "0.3"),
            ("stiffness", "\"rigid\""),
        ]],
        "adapt" => vec![vec![
            ("max_vertices", "5000"),
            ("steps", "4"),
            ("theta", "0.6"),
            ("free_boundary_rings", "2"),
            ("tolerance", "1e-3"),
        ]],
        "sensor" => vec![vec![
            ("name", "\"P1\""),
            ("at", "[0.5, 0.5]"),
            ("measured", "0.25"),
            ("sigma", "0.01"),
        ]],
        "sensitivity" => vec![vec![
            ("outputs", "[\"energy\", \"max_deflection\", \"total_contact_force\"]"),
            ("parameters", "[\"membrane.tension\", \"obstacle.stiffness\"]"),
            ("influence", "false"),
        ]],
        "fit" => vec![vec![
            ("parameters", "{ \"obstacle.stiffness\" = [10.0, 1000.0] }"),
            ("measurements", "\"points.csv\""),
            ("max_iterations", "10"),
            ("tolerance", "1e-6"),
            ("prior", "0.01"),
        ]],
        "exact" => vec![
            vec![
                ("kind", "\"manufactured\""),
                ("domain", "\"rectangle\""),
                ("amplitude", "0.1"),
                ("form", "\"cosine\""),
            ],
            vec![("kind", "\"petsc-ex9\""), ("body", "\"lower\"")],
        ],
        other => panic!("no samples for {other}"),
    }
}

/// A case of the base sections with `section` holding `keys`.
fn case_with(section: &str, keys: &[(&str, &str)]) -> String {
    let mut case = String::new();
    let body: String = keys.iter().map(|(k, v)| format!("{k} = {v}\n")).collect();
    if section == "mesh" {
        case.push_str(&format!("[mesh]\n{body}"));
    } else {
        case.push_str("[mesh]\ngenerator = \"rectangle\"\nnx = 16\n");
    }
    case.push_str("[membrane]\ntension = 1.0\nload = 1.0\n");
    case.push_str("[obstacle]\nshape = 0.2\nstiffness = 100.0\n");
    match section {
        "mesh" | "membrane" | "obstacle" => {
            // The base sections' own keys replace the base's values.
            if section != "mesh" {
                let start = case.find(&format!("[{section}]")).unwrap();
                let end = case[start + 1..]
                    .find('[')
                    .map_or(case.len(), |e| start + 1 + e);
                case.replace_range(start..end, &format!("[{section}]\n{body}"));
            }
        }
        "load_case" | "sensor" => case.push_str(&format!("[[{section}]]\n{body}")),
        _ => case.push_str(&format!("[{section}]\n{body}")),
    }
    case
}

#[test]
fn every_key_the_docs_list_is_accepted_by_check_and_documented() {
    let dir = tmp_in("docs_keys", "keys");
    // Relative mesh files (the `file` sample) resolve beside the case.
    std::fs::copy(common::examples().join("disk.msh"), dir.join("disk.msh")).unwrap();
    // And the measurements of the `[fit]` sample.
    std::fs::write(
        dir.join("points.csv"),
        "name,x,y,u\nA,0.3,0.3,0.2\nB,0.5,0.5,0.3\nC,0.7,0.6,0.2\n",
    )
    .unwrap();
    for (section, page, title) in SECTIONS {
        let mut documented = documented_keys(page, title);
        documented.sort_unstable();
        documented.dedup();
        let groups = samples(section);
        let mut sampled: Vec<&str> = groups.iter().flatten().map(|(k, _)| *k).collect();
        sampled.sort_unstable();
        sampled.dedup();
        assert_eq!(
            documented, sampled,
            "[{section}]: the keys of docs/case-file/{page} and the samples"
        );
        for (g, keys) in groups.iter().enumerate() {
            let case = case_with(section, keys);
            let path = dir.join(format!("{section}-{g}.toml"));
            std::fs::write(&path, &case).unwrap();
            let o = run(&["check", path.to_str().unwrap()]);
            if keys.iter().any(|(k, _)| *k == "given") {
                // Known to the parser, refused because the mesh itself is not in the file.
                assert!(!o.status.success(), "{case}");
                assert!(text(&o).contains("mesh.given"), "{case}\n{}", text(&o));
                assert!(!text(&o).contains("unknown field"), "{case}\n{}", text(&o));
            } else {
                assert!(o.status.success(), "{case}\n{}", text(&o));
            }
        }
    }
}

#[test]
fn a_key_the_docs_do_not_list_is_refused_naming_it() {
    let dir = tmp_in("docs_keys", "unknown");
    let case = case_with("boundary", &[("freed", "[\"top\"]")]);
    let path = dir.join("wrong.toml");
    std::fs::write(&path, &case).unwrap();
    let o = run(&["check", path.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(text(&o).contains("freed"), "{}", text(&o));
}

/// The pages of the documentation list the sections and keys of the program's own key
/// list (`memcontact::case::keys`), and `solve --help` and `check --help` print them all:
/// the help, the docs and the parser cannot drift apart.
#[test]
fn the_help_prints_every_section_and_key_the_docs_list() {
    let listed = memcontact::case::keys::SECTIONS;
    assert_eq!(
        listed.iter().map(|s| s.name).collect::<Vec<_>>(),
        SECTIONS.iter().map(|s| s.0).collect::<Vec<_>>(),
        "the docs' pages and the key list name the same sections, in the same order"
    );
    for command in ["solve", "check"] {
        let o = run(&[command, "--help"]);
        assert!(o.status.success());
        let help = text(&o);
        for ((name, page, title), section) in SECTIONS.iter().zip(listed) {
            assert!(
                help.contains(&section.heading()),
                "{command} --help lacks {name}"
            );
            let mut documented = documented_keys(page, title);
            documented.sort();
            documented.dedup();
            let mut keys: Vec<String> = section.keys.iter().map(|k| k.name.to_string()).collect();
            keys.sort();
            assert_eq!(
                documented, keys,
                "docs/case-file/{page} against the key list"
            );
            let block = &help[help.find(&section.heading()).unwrap()..];
            for k in section.keys {
                assert!(
                    block.contains(k.name),
                    "{command} --help: {name}.{}",
                    k.name
                );
            }
        }
    }
}
