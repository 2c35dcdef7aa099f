//! Real solved cases for the picture tests: the example cases of the repository, built
//! and solved with the library alone (mesh, `Model::assemble`, `solve`, `results::derive`).

#![allow(dead_code)]

use memcontact::field::{Field, DEFAULT_KEY};
use memcontact::mesh::generate::{self, Diagonal, PolygonSpec, RectangleSpec};
use memcontact::mesh::refine::Hierarchy;
use memcontact::model::{BodyStiffness, Foundation, Model, ProblemData, Sampling};
use memcontact::outcome::fields::derive;
use memcontact::solve::{self, Settings, Silent};
use memcontact_plot::result::ResultData;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A solved case.
pub struct Solved {
    /// Its name (as the examples are called).
    pub name: &'static str,
    /// The fields.
    pub data: ResultData,
    /// The contact force per nodal area etc. are in `data`; the mesh's region tags here.
    pub regions: Vec<u32>,
}

/// The obstacle's stiffness in a case.
pub enum H {
    Rigid,
    Field(Field),
}

/// Solves a case on `hierarchy`'s finest mesh.
pub fn solve_case(
    name: &'static str,
    hierarchy: Hierarchy,
    t: f64,
    f: &str,
    phi: &str,
    h: H,
) -> Solved {
    let mesh = hierarchy.finest();
    let mut tags = mesh.regions.clone();
    tags.sort_unstable();
    tags.dedup();
    let bind = |what: &str, field: &Field| field.bind(what, &mesh.region_names, &tags).unwrap();
    let load = bind("load", &Field::parse(f).unwrap());
    let shape = bind("shape", &Field::parse(phi).unwrap());
    let stiff = match &h {
        H::Rigid => None,
        H::Field(field) => Some(bind("stiffness", field)),
    };
    let data = ProblemData {
        tension: t,
        load: &load,
        shape: &shape,
        stiffness: match &stiff {
            Some(s) => BodyStiffness::Elastic(s),
            None => BodyStiffness::Rigid,
        },
        foundation: Foundation::Consistent,
        sampling: Sampling::Nodal,
    };
    let model = Model::assemble(mesh, &data).unwrap();
    let h = (hierarchy.depth() > 1).then_some(&hierarchy);
    let solution = solve::solve(&model, h, &Settings::default(), &mut Silent).unwrap();
    let (fields, _) = derive(mesh, &model, &solution);
    // The body covers the vertices where h > 0 (h = ∞ when rigid), boundary included.
    let covered = model.h_vertices.to_vec().iter().map(|&h| h > 0.0).collect();
    Solved {
        name,
        data: ResultData {
            points: mesh.points.clone(),
            triangles: mesh.triangles.clone(),
            u: fields.u,
            phi: fields.phi,
            state: fields.state,
            pressure: fields.pressure,
            covered,
        },
        regions: mesh.regions.clone(),
    }
}

/// `examples/disk.toml`: the elastic disc.
pub fn disk() -> Solved {
    let mesh = generate::disk([0.0, 0.0], 1.0, 0.1).unwrap();
    solve_case(
        "disk",
        Hierarchy::single(mesh),
        1.0,
        "8",
        "1.0",
        H::Field(Field::Constant(100.0)),
    )
}

/// `examples/disk-step.toml`: the disc on a stepped obstacle.
pub fn disk_step() -> Solved {
    let mesh = generate::disk([0.0, 0.0], 1.0, 0.1).unwrap();
    solve_case(
        "disk-step",
        Hierarchy::single(mesh),
        1.0,
        "8",
        "if(x > 0.1, 0.9, 1.1)",
        H::Field(Field::Constant(100.0)),
    )
}

/// `examples/rigid-square.toml`: the classical obstacle problem (every contact vertex
/// touches).
pub fn rigid_square() -> Solved {
    let spec = RectangleSpec {
        x0: 0.0,
        y0: 0.0,
        x1: 1.0,
        y1: 1.0,
        nx: 64,
        ny: 64,
        diagonal: Diagonal::Right,
    };
    solve_case(
        "rigid-square",
        generate::rectangle(&spec).unwrap(),
        1.0,
        "20",
        "0.3 + 0.2*x*y",
        H::Rigid,
    )
}

/// `examples/roof.toml`: a roof membrane with a skylight opening on a foam cushion with a
/// stiffer block (units m, kN).
pub fn roof() -> Solved {
    let spec = PolygonSpec {
        outer: vec![[0.0, 0.0], [12.0, 0.0], [12.0, 8.0], [0.0, 8.0]],
        holes: vec![vec![[7.0, 3.0], [9.0, 3.0], [9.0, 5.0], [7.0, 5.0]]],
        regions: vec![(
            "block".into(),
            vec![[1.5, 2.5], [5.0, 2.5], [5.0, 5.5], [1.5, 5.5]],
        )],
        size: 0.25,
        min_angle: 28.0,
    };
    let mesh = generate::polygon(&spec).unwrap();
    let h: BTreeMap<String, Field> = [
        ("block".to_string(), Field::Constant(900.0)),
        (DEFAULT_KEY.to_string(), Field::parse("250 + 20*y").unwrap()),
    ]
    .into();
    solve_case(
        "roof",
        Hierarchy::single(mesh),
        6.0,
        "1.2 + 0.3*exp(-((x-3)^2 + (y-4)^2)/4)",
        "0.45 + 0.12*sin(0.9*x)*cos(0.7*y) - 0.1*exp(-((x-9.5)^2 + (y-2)^2)) + 0.01*x",
        H::Field(Field::Regions(h)),
    )
}

/// `examples/gmsh-disk.toml`: a Gmsh disc with two soils, one of which (foam) is soft,
/// refined once.
pub fn gmsh_disk() -> Solved {
    let path = examples().join("disk.msh");
    let (mesh, _) = memcontact::io::gmsh::read_msh(&path).unwrap();
    let h: BTreeMap<String, Field> = [
        ("foam".to_string(), Field::Constant(50.0)),
        ("soil".to_string(), Field::Constant(400.0)),
    ]
    .into();
    solve_case(
        "gmsh-disk",
        Hierarchy::refined(mesh, 1),
        2.0,
        "10",
        "0.8 - 0.2*(x*x + y*y)",
        H::Field(Field::Regions(h)),
    )
}

/// A partly covered case: the body (h > 0) only under the left half of the square, so
/// that lift-off, contact and "cannot touch" all appear.
pub fn half_covered() -> Solved {
    let spec = RectangleSpec {
        x0: 0.0,
        y0: 0.0,
        x1: 2.0,
        y1: 1.0,
        nx: 48,
        ny: 24,
        diagonal: Diagonal::Alternate,
    };
    solve_case(
        "half-covered",
        generate::rectangle(&spec).unwrap(),
        1.0,
        "30",
        "0.25 + 0.15*sin(3*y)",
        H::Field(Field::parse("if(x < 1.1, 500, 0)").unwrap()),
    )
}

/// `examples/disk-rigid.toml`: the disc on a rigid flat obstacle.
pub fn disk_rigid() -> Solved {
    let mesh = generate::disk([0.0, 0.0], 1.0, 0.1).unwrap();
    solve_case(
        "disk-rigid",
        Hierarchy::single(mesh),
        1.0,
        "8",
        "1.0",
        H::Rigid,
    )
}

/// `examples/manufactured-square.toml` (the case's own load): an 8 × 8 mesh, coarse
/// enough that vertex markers are drawn.
pub fn manufactured_square() -> Solved {
    let spec = RectangleSpec {
        x0: 0.0,
        y0: 0.0,
        x1: 1.0,
        y1: 1.0,
        nx: 8,
        ny: 8,
        diagonal: Diagonal::Right,
    };
    solve_case(
        "manufactured-square",
        generate::rectangle(&spec).unwrap(),
        1.5,
        "30",
        "0.55 + 0.3*(x - 0.5)^2 + 0.1*y",
        H::Field(Field::parse("50*(1 + y)").unwrap()),
    )
}

/// The repository's `examples/` folder.
pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// Copies `file` into `$MEMCONTACT_KEEP_PLOTS/<prefix>-<file name>` when that variable is
/// set (to look at the pictures).
pub fn keep(file: &Path, prefix: &str) {
    if let Ok(dir) = std::env::var("MEMCONTACT_KEEP_PLOTS") {
        let name = format!("{prefix}-{}", file.file_name().unwrap().to_string_lossy());
        std::fs::copy(file, Path::new(&dir).join(name)).unwrap();
    }
}
