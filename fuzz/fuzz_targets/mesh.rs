//! The mesh checks on arbitrary points and triangles (`Mesh::new`), and what follows for a
//! mesh they accept: its quality, a uniform refinement, the assembly of a model and a few
//! iterations of a solver. Nothing may panic on a mesh `Mesh::new` accepted.
//!
//! Input: byte 0 picks the coordinates (small integers, so that duplicates, collinear
//! points and slivers are common, or raw doubles); bytes 1-2 the number of points; then
//! the points; then triangles as three little-endian u16 vertex numbers and a region byte.
#![no_main]

use libfuzzer_sys::fuzz_target;
use memcontact::field::Field;
use memcontact::mesh::refine::Hierarchy;
use memcontact::mesh::Mesh;
use memcontact::model::{Foundation, Model, ProblemData, Sampling, BodyStiffness};
use memcontact::solve::{self, Method, Settings, Silent};
use std::collections::BTreeMap;

fuzz_target!(|data: &[u8]| {
    if data.len() < 3 {
        return;
    }
    let raw_doubles = data[0] & 1 == 1;
    let n = (u16::from_le_bytes([data[1], data[2]]) % 512) as usize;
    let mut rest = &data[3..];
    let mut points = Vec::with_capacity(n);
    for _ in 0..n {
        if raw_doubles {
            if rest.len() < 16 {
                return;
            }
            let x = f64::from_le_bytes(rest[..8].try_into().unwrap());
            let y = f64::from_le_bytes(rest[8..16].try_into().unwrap());
            points.push([x, y]);
            rest = &rest[16..];
        } else {
            if rest.len() < 2 {
                return;
            }
            points.push([rest[0] as i8 as f64 / 8.0, rest[1] as i8 as f64 / 8.0]);
            rest = &rest[2..];
        }
    }
    let mut triangles = Vec::new();
    let mut regions = Vec::new();
    for t in rest.chunks_exact(7).take(1024) {
        let v = |k: usize| u16::from_le_bytes([t[2 * k], t[2 * k + 1]]) as u32;
        triangles.push([v(0), v(1), v(2)]);
        regions.push((t[6] % 4) as u32);
    }
    let mut names = BTreeMap::new();
    names.insert(1, "one".to_string());
    let Ok(mesh) = Mesh::new(points, triangles, regions, names) else {
        return;
    };
    let q = mesh.quality();
    assert!(q.area > 0.0 && q.triangles == mesh.n_triangles());
    let hierarchy = Hierarchy::refined(mesh, 1);
    let mesh = hierarchy.finest();
    let bind = |name: &str, v: f64| Field::from_number(v).bind_to_mesh(name, mesh).unwrap();
    let load = bind("membrane.load", 3.0);
    let shape = bind("obstacle.shape", 0.01);
    let h = bind("obstacle.stiffness", 50.0);
    let data = ProblemData {
        tension: 1.0,
        load: &load,
        shape: &shape,
        stiffness: BodyStiffness::Elastic(&h),
        foundation: Foundation::Consistent,
        sampling: Sampling::Nodal,
    };
    // No interior vertex, or data out of range: a refusal, not a panic.
    let Ok(model) = Model::assemble(mesh, &data) else {
        return;
    };
    let settings = Settings {
        method: Method::ActiveSet,
        max_iterations: Some(20),
        ..Settings::default()
    };
    if let Ok(a) = solve::attempt(&model, Some(&hierarchy), &settings, &mut Silent) {
        let _ = a.solution.certificate.kkt();
    }
});
