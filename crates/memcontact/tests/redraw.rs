//! Redrawing from a result directory (`solution.vtu` + `summary.json`, as `memcontact
//! solve` writes them) gives byte-identical pictures to the ones drawn at solve time.

#[path = "pictures_common/mod.rs"]
mod common;

use memcontact::io::vtu::{write_vtu, DataArray, VtuEncoding};
use memcontact::mesh::Mesh;
use memcontact::write::{draw_all, load_result as load, ResultData};
use memcontact_plot::{PlotKind, PlotOptions, Units};
use std::path::Path;

/// Writes a result directory the way the CLI does (plus `covered` and `plot_options`
/// when asked).
fn write_result(
    dir: &Path,
    d: &ResultData,
    opts: Option<&PlotOptions>,
    covered: bool,
    enc: VtuEncoding,
) {
    let mesh = Mesh {
        points: d.points.clone(),
        triangles: d.triangles.clone(),
        ..Default::default()
    };
    let state: Vec<i32> = d.state.iter().map(|&s| s as i32).collect();
    let cov: Vec<i32> = d.covered.iter().map(|&c| c as i32).collect();
    let pen: Vec<f64> =
        d.u.iter()
            .zip(&d.phi)
            .map(|(u, p)| (u - p).max(0.0))
            .collect();
    let mut point_data = vec![
        ("u", DataArray::F64(&d.u)),
        ("phi", DataArray::F64(&d.phi)),
        ("penetration", DataArray::F64(&pen)),
        ("pressure", DataArray::F64(&d.pressure)),
        ("state", DataArray::I32(&state)),
    ];
    if covered {
        point_data.push(("covered", DataArray::I32(&cov)));
    }
    let region = vec![0i32; d.triangles.len()];
    write_vtu(
        &dir.join("solution.vtu"),
        &mesh,
        &point_data,
        &[("region", DataArray::I32(&region))],
        enc,
    )
    .unwrap();
    let mut summary = serde_json::json!({ "case": "examples/roof.toml", "iterations": 12 });
    if let Some(o) = opts {
        summary["plot_options"] = serde_json::to_value(o).unwrap();
    }
    std::fs::write(
        dir.join("summary.json"),
        serde_json::to_vec(&summary).unwrap(),
    )
    .unwrap();
}

#[test]
fn redrawn_pictures_are_byte_identical() {
    let solved = common::roof();
    let d = &solved.data;
    let opts = PlotOptions {
        title: Some("examples/roof.toml".into()),
        allowable_pressure: Some(1.8),
        profile: Some([[0.5, 4.0], [11.5, 3.0]]),
        units: Units {
            length: Some("m".into()),
            force: Some("kN".into()),
        },
        ..PlotOptions::default()
    };
    for enc in [VtuEncoding::Binary, VtuEncoding::Ascii] {
        let solved_dir = tempfile::tempdir().unwrap();
        write_result(solved_dir.path(), d, Some(&opts), true, enc);
        let at_solve = draw_all(solved_dir.path(), &d.view(), &opts).unwrap();
        let loaded = load(solved_dir.path()).unwrap();
        assert!(loaded.notes.is_empty(), "{:?}", loaded.notes);
        assert_eq!(loaded.options, opts);
        let again = tempfile::tempdir().unwrap();
        let redrawn = draw_all(again.path(), &loaded.data.view(), &loaded.options).unwrap();
        assert_eq!(at_solve.len(), 4);
        for (a, b) in at_solve.iter().zip(&redrawn) {
            assert_eq!(a.file_name(), b.file_name());
            let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
            assert!(
                x == y,
                "{:?} ({enc:?}): the redrawn picture differs",
                a.file_name()
            );
        }
    }
}

#[test]
fn missing_optional_fields_are_assumed_and_said() {
    let solved = common::half_covered();
    let d = &solved.data;
    let dir = tempfile::tempdir().unwrap();
    write_result(dir.path(), d, None, false, VtuEncoding::Binary);
    let loaded = load(dir.path()).unwrap();
    assert_eq!(loaded.notes.len(), 2, "{:?}", loaded.notes);
    assert!(loaded.notes[0].contains("covered"));
    assert!(loaded.notes[1].contains("plot_options"));
    // Without `covered`, the body is taken to cover every vertex (φ is finite here).
    assert!(loaded.data.covered.iter().all(|&c| c));
    assert_eq!(loaded.options.plots, PlotKind::ALL.to_vec());
    assert_eq!(loaded.options.title.as_deref(), Some("examples/roof.toml"));
    assert_eq!(loaded.data.u, d.u);
    assert_eq!(loaded.data.state, d.state);
    // A broken plot_options is an error naming the key.
    let summary = serde_json::json!({ "case": "x", "plot_options": { "plots": ["contour"] } });
    std::fs::write(
        dir.path().join("summary.json"),
        serde_json::to_vec(&summary).unwrap(),
    )
    .unwrap();
    let e = load(dir.path()).unwrap_err().to_string();
    assert!(
        e.contains("summary.json") && e.contains("plot_options"),
        "{e}"
    );
    // No solution.vtu: an error naming it.
    let e = load(&dir.path().join("nowhere")).unwrap_err().to_string();
    assert!(e.contains("solution.vtu"), "{e}");
}

#[test]
fn bad_options_are_named() {
    let solved = common::disk();
    let d = solved.data.view();
    let dir = tempfile::tempdir().unwrap();
    let bad = [
        (
            PlotOptions {
                allowable_pressure: Some(-1.0),
                ..Default::default()
            },
            "allowable_pressure",
        ),
        (
            PlotOptions {
                profile: Some([[0.0, 0.0], [0.0, 0.0]]),
                ..Default::default()
            },
            "profile",
        ),
        (
            PlotOptions {
                profile: Some([[5.0, 5.0], [6.0, 5.0]]),
                ..Default::default()
            },
            "does not cross",
        ),
        (
            PlotOptions {
                plots: vec![PlotKind::Pressure, PlotKind::Pressure],
                ..Default::default()
            },
            "twice",
        ),
    ];
    for (o, want) in bad {
        let e = draw_all(dir.path(), &d, &o).unwrap_err().to_string();
        assert!(e.contains(want), "{e}");
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no file left behind"
    );
    let e = "contours".parse::<PlotKind>().unwrap_err().to_string();
    assert!(
        e.contains("deflection, pressure, liftoff or profile"),
        "{e}"
    );
    // Fields of the wrong length.
    let short = &d.u[1..];
    let e = draw_all(
        dir.path(),
        &memcontact_plot::PlotData { u: short, ..d },
        &PlotOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("`u`"), "{e}");
    // Only the asked pictures are drawn; none with an empty list.
    let o = PlotOptions {
        plots: vec![PlotKind::Profile],
        ..Default::default()
    };
    let files = draw_all(dir.path(), &d, &o).unwrap();
    assert_eq!(files, vec![dir.path().join("profile.png")]);
    let o = PlotOptions {
        plots: vec![],
        ..Default::default()
    };
    assert!(draw_all(dir.path(), &d, &o).unwrap().is_empty());
}

#[test]
fn options_round_trip_through_json_with_defaults() {
    let o: PlotOptions =
        serde_json::from_str(r#"{"allowable_pressure": 150, "units": {"length": "m"}}"#).unwrap();
    assert_eq!(o.plots, PlotKind::ALL.to_vec());
    assert_eq!(o.allowable_pressure, Some(150.0));
    assert_eq!(o.units.length.as_deref(), Some("m"));
    let back: PlotOptions = serde_json::from_value(serde_json::to_value(&o).unwrap()).unwrap();
    assert_eq!(back, o);
    assert!(serde_json::from_str::<PlotOptions>(r#"{"plot": []}"#).is_err());
}

/// With a body below: the result set the library writes (its `solution.vtu` holds the body
/// below's fields `phi_low`, `state_low`, `pressure_low`, `covered_low`) redraws to the same
/// bytes, whatever the VTU encoding.
#[test]
fn two_body_pictures_redraw_byte_identical() {
    use memcontact::case::VtuFormat;
    use memcontact::write::{plot_options, WriteOptions};
    let case =
        memcontact::Case::from_toml_str(common::LINER, Some(&common::examples().join("case.toml")))
            .unwrap();
    let outcome = memcontact::run::run(&case, &mut memcontact::solve::Silent).unwrap();
    let plots = PlotOptions {
        profile: Some([[0.0, 14.0], [20.0, 14.0]]),
        ..plot_options(&case, "liner")
    };
    for vtu in [VtuFormat::Binary, VtuFormat::Ascii, VtuFormat::Compressed] {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("solved");
        let options = WriteOptions {
            vtu,
            ..WriteOptions::new("liner")
        };
        memcontact::write::write_result(&target, &outcome, &case, &options, &plots).unwrap();
        let loaded = load(&target).unwrap();
        assert!(loaded.notes.is_empty(), "{:?}", loaded.notes);
        assert_eq!(loaded.options, plots);
        let lower = loaded.data.lower.as_ref().expect("the body below is read");
        assert!(lower.state.iter().any(|&s| s >= 0));
        let again = dir.path().join("again");
        std::fs::create_dir(&again).unwrap();
        let redrawn = draw_all(&again, &loaded.data.view(), &loaded.options).unwrap();
        assert_eq!(redrawn.len(), 4);
        for b in &redrawn {
            let name = b.file_name().unwrap();
            let (x, y) = (
                std::fs::read(target.join(name)).unwrap(),
                std::fs::read(b).unwrap(),
            );
            assert!(x == y, "{name:?} ({vtu:?}): the redrawn picture differs");
        }
    }
}
