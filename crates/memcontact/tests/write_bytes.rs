//! The result set written with everything at once (`solution.vtu`, `nodes.csv`, the
//! pictures and the input's hash side by side) has the bytes of the same files written by
//! the individual writers one after the other: every file, `summary.json` included except
//! its two timings of the writing, which the reference takes from the file.

use memcontact::write::{
    file_record, input_hash, pictures, plot_options, write_fields, write_result, WriteOptions,
};
use memcontact::{run, Case, Silent, Summary};
use std::collections::BTreeSet;
use std::path::Path;

const RUN_ID: &str = "0123456789abcdef0123456789abcdef";

/// The names of the files in `dir`.
fn names(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

/// Writes the result set of the example `name` (with `overrides`) both ways and compares
/// every file's bytes.
fn same_bytes_both_ways(name: &str, overrides: &[&str]) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name);
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let case = Case::load(&path, &overrides).unwrap();
    let outcome = run(&case, &mut Silent).unwrap();
    let plots = plot_options(&case, name);
    assert!(!plots.plots.is_empty(), "{name}: the default pictures");
    let options = WriteOptions {
        run_id: Some(RUN_ID.into()),
        plot_options: serde_json::to_value(&plots).ok(),
        ..WriteOptions::new(name)
    };
    let tmp = tempfile::tempdir().unwrap();

    // The set as `memcontact solve` writes it: staged, everything at once, moved in place.
    let set = tmp.path().join("set");
    write_result(&set, &outcome, &case, &options, &plots).unwrap();

    // The reference: each writer in turn into a plain directory, then the summary.
    let reference = tmp.path().join("reference");
    std::fs::create_dir(&reference).unwrap();
    let (fields, totals) = outcome.checked_fields().unwrap();
    let mut records = write_fields(
        &reference,
        &outcome,
        &fields,
        case.output.vtu,
        case.output.writes_csv(),
        RUN_ID,
        &[],
    )
    .unwrap();
    let mesh = outcome.mesh();
    let drawn = pictures(&mesh, &plots)(&reference, &fields).unwrap();
    assert_eq!(drawn.len(), plots.plots.len(), "{name}");
    for picture in drawn {
        let record = file_record(&reference.join(&picture)).unwrap();
        records.push((picture, record));
    }
    let mut summary = Summary::new(name, &outcome, &outcome.discretization.quality, &totals);
    summary.run_id = RUN_ID.into();
    summary.input_hash = input_hash(&case);
    summary.plot_options = options.plot_options.clone();
    summary.files.extend(records);

    // The same files, every one with the same bytes.
    let mut expected = names(&reference);
    expected.insert("summary.json".into());
    assert_eq!(names(&set), expected, "{name}");
    for file in names(&reference) {
        let a = std::fs::read(set.join(&file)).unwrap();
        let b = std::fs::read(reference.join(&file)).unwrap();
        assert!(
            a == b,
            "{name}: {file} differs ({} / {} bytes)",
            a.len(),
            b.len()
        );
    }
    // summary.json: the reference's text with the timings of the writing the file holds.
    let text = std::fs::read_to_string(set.join("summary.json")).unwrap();
    let written: Summary = serde_json::from_str(&text).unwrap();
    summary.time_write_s = written.time_write_s;
    summary.time_total_s = written.time_total_s;
    let mut reference_text = serde_json::to_string_pretty(&summary).unwrap();
    reference_text.push('\n');
    assert_eq!(text, reference_text, "{name}: summary.json");
    // The pictures are those the picture crate draws from the fields in the user's
    // numbering, whatever order they were drawn in.
    let plain = memcontact_plot::render(&user_data(&mesh, &fields), &plots).unwrap();
    for p in plain {
        let file = p.kind.file_name();
        assert!(
            p.canvas.encode_png().unwrap() == std::fs::read(set.join(&file)).unwrap(),
            "{name}: {file} is not the picture of the user's numbering"
        );
    }
    // Every file's record is that of its bytes.
    for (file, record) in &written.files {
        assert_eq!(
            record,
            &file_record(&set.join(file)).unwrap(),
            "{name}: {file}"
        );
    }
}

/// The picture crate's view of `fields` on `mesh`, in the user's numbering.
fn user_data<'a>(
    mesh: &'a memcontact::mesh::Mesh,
    fields: &'a memcontact::outcome::fields::NodalFields,
) -> memcontact_plot::PlotData<'a> {
    memcontact_plot::PlotData {
        points: &mesh.points,
        triangles: &mesh.triangles,
        u: &fields.u,
        phi: &fields.phi,
        state: &fields.state,
        pressure: &fields.pressure,
        covered: &fields.covered,
        lower: fields.lower.as_ref().map(|l| memcontact_plot::BodyData {
            phi: &l.phi,
            state: &l.state,
            pressure: &l.pressure,
            covered: &l.covered,
        }),
        numbering: None,
    }
}

#[test]
fn a_generated_square_is_written_with_the_same_bytes_both_ways() {
    same_bytes_both_ways(
        "bench-square.toml",
        &["mesh.nx=96", "mesh.ny=96", "obstacle.foundation=lumped"],
    );
}

#[test]
fn a_body_below_and_units_are_written_with_the_same_bytes_both_ways() {
    same_bytes_both_ways("geomembrane.toml", &["mesh.nx=32", "mesh.ny=32"]);
}

#[test]
fn an_imported_mesh_is_written_with_the_same_bytes_both_ways() {
    // The input's hash reads the mesh file while the other files are written.
    same_bytes_both_ways("gmsh-disk.toml", &[]);
}

#[test]
fn a_scattered_gmsh_mesh_with_a_body_below_is_drawn_as_in_the_users_numbering() {
    // A Gmsh mesh whose numbering is scattered: solved and drawn renumbered for locality.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/liner-slope.toml");
    let case = Case::load(&path, &[]).unwrap();
    let outcome = run(&case, &mut Silent).unwrap();
    assert!(
        outcome.discretization.mesh().numbering.is_some(),
        "the mesh is renumbered"
    );
    same_bytes_both_ways("liner-slope.toml", &[]);
}
