//! Tests of case files: round trips, errors with file, line and key, overrides.

use super::*;
use crate::error::Error;
use crate::model::Foundation;
use crate::problem::MeshSource;
use std::path::Path;

const DISK: &str = r#"
[mesh]
generator = "disk"
radius = 1
size = 0.2

[membrane]
tension = 1
load = 8

[obstacle]
shape = "1.0"
stiffness = 100
"#;

#[test]
fn a_case_round_trips_through_toml_and_json() {
    let case = Case::from_toml_str(DISK, None).unwrap();
    assert_eq!(case.problem.membrane.tension, 1.0);
    assert_eq!(case.problem.obstacle.foundation, Foundation::Consistent);
    let text = case.to_toml_string().unwrap();
    assert_eq!(Case::from_toml_str(&text, None).unwrap(), case);
    let json = serde_json::to_string(&case).unwrap();
    assert_eq!(Case::from_json_str(&json).unwrap(), case);
}

fn err(text: &str) -> Error {
    Case::from_toml_str(text, Some(Path::new("case.toml"))).unwrap_err()
}

#[test]
fn errors_name_the_key_the_file_and_the_line() {
    let e = err(&DISK.replace("stiffness = 100", "stifness = 100"));
    let Error::Case { key, line, .. } = &e else {
        panic!("{e}")
    };
    assert_eq!(key, "obstacle.stifness");
    assert_eq!(*line, Some(13), "{e}");
    assert!(e.to_string().contains("unknown field"), "{e}");
    assert!(e.to_string().starts_with("case.toml:13:"), "{e}");

    let e = err(&DISK.replace("tension = 1", "tension = -1"));
    let Error::Case { key, line, .. } = &e else {
        panic!("{e}")
    };
    assert_eq!((key.as_str(), *line), ("membrane.tension", Some(8)), "{e}");

    let e = err(&DISK.replace("radius = 1", "radius = \"big\""));
    assert!(e.to_string().contains("radius"), "{e}");
    let e = err(&DISK.replace("generator = \"disk\"", "generator = \"hexagon\""));
    assert!(e.to_string().contains("hexagon"), "{e}");
    let e = err(&format!("{DISK}\n[exact]\nkind = \"foo\"\n"));
    assert!(e.to_string().contains("foo"), "{e}");
    let e = err(&format!("{DISK}\n[solver]\ntolerance = 0.5\n"));
    assert!(e.to_string().contains("solver.tolerance"), "{e}");
    let e = err(&format!("{DISK}\n[output]\nvtu = \"xml\"\n"));
    assert!(e.to_string().contains("output.vtu"), "{e}");
    let e = err(&DISK.replace("load = 8", "load = nan"));
    assert!(e.to_string().contains("membrane.load"), "{e}");
    let e = err(&DISK.replace("stiffness = 100", "stiffness = -3"));
    assert!(e.to_string().contains("obstacle.stiffness"), "{e}");
    // Found by fuzzing: a NaN polygon vertex passed validation (and its JSON, null,
    // did not read back).
    let polygon = DISK.replace(
        "generator = \"disk\"\nradius = 1\nsize = 0.2",
        "generator = \"polygon\"\nouter = [[0, 0], [2, 0], [2, 2], [0, 2]]\n\
         holes = [[[nan, 1.0], [1.2, 0.8], [1.2, 1.2]]]\nsize = 0.2",
    );
    let e = err(&polygon);
    assert!(e.to_string().contains("mesh.holes[0]"), "{e}");
    assert!(e.to_string().contains("finite"), "{e}");
    let e = err(&polygon
        .replace("[[[nan, 1.0]", "[[[1.0, 1.0]")
        .replace("[0, 2]]", "[0, inf]]"));
    assert!(e.to_string().contains("mesh.outer"), "{e}");
    // A key inside an array of tables points at its own line.
    let e = err(&format!(
        "{DISK}\n[[load_case]]\nname = \"a\"\n\n[[load_case]]\nname = \"b\"\n\
         stiffness = -4\n"
    ));
    let Error::Case { key, line, .. } = &e else {
        panic!("{e}")
    };
    assert_eq!(key, "load_case.1.stiffness");
    assert_eq!(*line, Some(20), "{e}");
}

#[test]
fn overrides_keep_the_other_lines() {
    let text = apply_overrides(
        DISK,
        &["mesh.size=0.1".into(), "obstacle.foundation=lumped".into()],
    )
    .unwrap();
    let case = Case::from_toml_str(&text, None).unwrap();
    assert_eq!(case.problem.obstacle.foundation, Foundation::Lumped);
    assert!(matches!(
        case.problem.mesh.source,
        MeshSource::Disk { size, .. } if size == 0.1
    ));
    // An error after an override still points at the original line.
    let text = apply_overrides(DISK, &["membrane.tension=-2".into()]).unwrap();
    let e = Case::from_toml_str(&text, None).unwrap_err();
    assert!(matches!(e, Error::Case { line: Some(8), .. }), "{e}");
    assert!(apply_overrides(DISK, &["nokey".into()]).is_err());
    assert!(apply_overrides(DISK, &["mesh..x=1".into()]).is_err());
}

#[test]
fn a_fragment_is_checked_on_top_of_the_fewest_keys_that_complete_it() {
    // Valid fragments: a section alone, keys of a generator without its name, an array of
    // tables.
    for text in [
        "[obstacle]\nfoundation = \"lumped\"\n",
        "[mesh]\nnx = 64\nny = 32\n",
        "[mesh]\nradius = 2.0\nsize = 0.5\n",
        "[mesh]\nouter = [[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]]\n",
        "[[load_case]]\nname = \"dead\"\n\n[[load_case]]\nname = \"snow\"\nload_factor = 1.35\n",
        "[adapt]\ntheta = 0.6\n",
        "[lower]\nshape = -0.1\nstiffness = \"rigid\"\n",
    ] {
        let case = Case::from_fragment_str(text, None).unwrap_or_else(|e| panic!("{text}: {e}"));
        assert_eq!(case.problem.membrane.tension, 1.0, "{text}");
    }
    // Invalid fragments keep their errors, named by key.
    for (text, key) in [
        (
            "[obstacle]\nfoundation = \"lumpy\"\n",
            "obstacle.foundation",
        ),
        ("[adapt]\ntheta = 1.5\n", "adapt.theta"),
        ("[solver]\ntolerance = 0.5\n", "solver.tolerance"),
        ("[mesh]\nnx = 4\nradius = 1.0\n", "mesh"),
        ("[membrane]\ntension = -1.0\n", "membrane.tension"),
        ("[units]\nlength = \"m\"\nmass = \"kg\"\n", "units"),
    ] {
        let e = Case::from_fragment_str(text, None).unwrap_err().to_string();
        assert!(e.contains(key), "{text}: {e}");
    }
    assert!(Case::from_fragment_str("[obstacle\n", None)
        .unwrap_err()
        .to_string()
        .contains("malformed TOML"));
}
