//! The README's case-file reference against the program: every key its tables list for a
//! section is accepted by `memcontact check` (with a sample value), and every key of the
//! samples is in the README, so that neither can drift from the other.

use std::collections::BTreeMap;
use std::path::Path;

mod common;
use common::{run, text, tmp_in};

/// The keys of the table under the heading that starts with `### \`[section]\``: the
/// backquoted words of each row's first cell.
fn readme_keys(section: &str) -> Vec<String> {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md"))
            .unwrap();
    let heading = format!("### `[{section}]`");
    let start = readme
        .find(&heading)
        .unwrap_or_else(|| panic!("the README has no section {heading}"));
    let body = &readme[start + heading.len()..];
    let body = &body[..body.find("\n### ").unwrap_or(body.len())];
    let mut keys = Vec::new();
    for row in body.lines().filter(|l| l.starts_with("| `")) {
        let first = row.split('|').nth(1).unwrap();
        keys.extend(first.split('`').skip(1).step_by(2).map(str::to_string));
    }
    assert!(!keys.is_empty(), "no keys under {heading}");
    keys
}

/// A sample value (TOML) for every key a section documents.
fn samples(section: &str) -> BTreeMap<&'static str, &'static str> {
    BTreeMap::from_iter(match section {
        "membrane" => vec![("tension", "2.0"), ("load", "\"1 + x\"")],
        "obstacle" => vec![
            ("shape", "0.2"),
            ("stiffness", "{ default = 100.0 }"),
            ("foundation", "\"lumped\""),
            ("sampling", "\"mollified\""),
            ("epsilon", "0.05"),
        ],
        "lower" => vec![
            ("shape", "\"-0.2 + 0.01*x\""),
            ("stiffness", "{ default = 300.0 }"),
            ("foundation", "\"consistent\""),
            ("sampling", "\"mollified\""),
            ("epsilon", "0.05"),
        ],
        "boundary" => vec![
            (
                "height",
                "{ bottom = 0.0, left = \"0.01*y\", right = 0.02, default = 0.0 }",
            ),
            ("free", "[\"top\"]"),
        ],
        "solver" => vec![
            ("method", "\"multigrid\""),
            ("tolerance", "1e-9"),
            ("max_iterations", "50"),
            ("accept_rounding_floor", "false"),
            ("hierarchy", "\"geometric\""),
        ],
        "output" => vec![
            ("vtu", "\"ascii\""),
            ("csv", "false"),
            ("plots", "[\"deflection\"]"),
            ("plot", "true"),
            ("allowable_pressure", "5.0"),
            ("profile", "[[0.0, 0.5], [1.0, 0.5]]"),
            ("keep_steps", "true"),
        ],
        "adapt" => vec![
            ("max_vertices", "5000"),
            ("steps", "4"),
            ("theta", "0.6"),
            ("free_boundary_rings", "2"),
            ("tolerance", "1e-3"),
        ],
        "units" => vec![("length", "\"m\""), ("force", "\"kN\"")],
        other => panic!("no samples for {other}"),
    })
}

#[test]
fn every_key_the_readme_lists_is_accepted_by_check_and_documented() {
    let dir = tmp_in("readme", "keys");
    let sections = [
        "membrane", "obstacle", "lower", "boundary", "solver", "output", "units", "adapt",
    ];
    let mut case = String::from("[mesh]\ngenerator = \"rectangle\"\nnx = 16\n");
    for section in sections {
        let documented = readme_keys(section);
        let samples = samples(section);
        let sampled: Vec<&str> = samples.keys().copied().collect();
        let mut listed: Vec<&str> = documented.iter().map(String::as_str).collect();
        listed.sort_unstable();
        assert_eq!(
            listed, sampled,
            "[{section}]: the README's keys and the samples"
        );
        case.push_str(&format!("[{section}]\n"));
        for (key, value) in samples {
            case.push_str(&format!("{key} = {value}\n"));
        }
    }
    let path = dir.join("all.toml");
    std::fs::write(&path, &case).unwrap();
    let o = run(&["check", path.to_str().unwrap()]);
    assert!(o.status.success(), "{case}\n{}", text(&o));
    // The check is strict: a key the README does not list is refused, naming it.
    let wrong = case.replace("free = ", "freed = ");
    std::fs::write(&path, wrong).unwrap();
    let o = run(&["check", path.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(text(&o).contains("freed"), "{}", text(&o));
}
