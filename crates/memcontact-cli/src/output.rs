//! The outputs of `memcontact solve`: solution.vtu, nodes.csv, summary.json and the human
//! summary. Every file is written atomically.

use crate::case::Case;
use crate::commands::Run;
use anyhow::{bail, Result};
use memcontact::io::csv::write_columns_csv;
use memcontact::io::json::write_json;
use memcontact::io::vtu::{write_vtu, DataArray, VtuEncoding};
use memcontact::mesh::{Mesh, MeshQuality};
use memcontact::results::{derive, Totals};
use serde_json::json;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Above this many triangles `deflection.png` is written only when asked for (it draws
/// every triangle).
const PLOT_TRIANGLES: usize = 200_000;

/// The mesh report of `check` and `solve`.
pub fn mesh_report(mesh: &Mesh, q: &MeshQuality, levels: usize) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "  mesh         {} vertices, {} triangles, {} unknowns, {} level{}",
        q.vertices,
        q.triangles,
        q.unknowns,
        levels,
        if levels == 1 { "" } else { "s" }
    );
    let _ = writeln!(
        s,
        "  quality      l_n = {:.4e}, s_n = {:.3}, smallest angle {:.2}°, area {:.6}",
        q.l_n, q.s_n, q.min_angle_deg, q.area
    );
    if mesh.region_names.len() > 1 || mesh.regions.iter().any(|&r| r != mesh.regions[0]) {
        let mut tags: Vec<u32> = mesh.regions.clone();
        tags.sort_unstable();
        tags.dedup();
        let names: Vec<String> = tags.iter().map(|&t| mesh.region_name(t)).collect();
        let _ = writeln!(s, "  regions      {}", names.join(", "));
    }
    s
}

/// Writes the three output files and returns the human summary.
pub fn write_all(case: &Case, run: &Run, out: &Path, t0: Instant) -> Result<String> {
    let mesh = run.hierarchy.finest();
    let t_out = Instant::now();
    let (fields, totals) = derive(mesh, &run.model, &run.solution);
    let encoding = match case.output.vtu.as_str() {
        "binary" => VtuEncoding::Binary,
        "ascii" => VtuEncoding::Ascii,
        s => bail!("output.vtu must be \"binary\" or \"ascii\", not \"{s}\""),
    };
    let region: Vec<i32> = mesh.regions.iter().map(|&r| r as i32).collect();
    let state: Vec<i32> = fields.state.iter().map(|&s| s as i32).collect();
    write_vtu(
        &out.join("solution.vtu"),
        mesh,
        &[
            ("u", DataArray::F64(&fields.u)),
            ("phi", DataArray::F64(&fields.phi)),
            ("penetration", DataArray::F64(&fields.penetration)),
            ("pressure", DataArray::F64(&fields.pressure)),
            ("contact_force", DataArray::F64(&fields.contact_force)),
            ("state", DataArray::I32(&state)),
        ],
        &[("region", DataArray::I32(&region))],
        encoding,
    )?;
    let x: Vec<f64> = mesh.points.iter().map(|p| p[0]).collect();
    let y: Vec<f64> = mesh.points.iter().map(|p| p[1]).collect();
    write_columns_csv(
        &out.join("nodes.csv"),
        &[
            ("x", DataArray::F64(&x)),
            ("y", DataArray::F64(&y)),
            ("u", DataArray::F64(&fields.u)),
            ("phi", DataArray::F64(&fields.phi)),
            ("penetration", DataArray::F64(&fields.penetration)),
            ("pressure", DataArray::F64(&fields.pressure)),
            ("contact_force", DataArray::F64(&fields.contact_force)),
            ("state", DataArray::I32(&state)),
        ],
    )?;
    let plotted = case
        .output
        .plot
        .unwrap_or(mesh.n_triangles() <= PLOT_TRIANGLES);
    if plotted {
        crate::plot::field_plot(
            &out.join("deflection.png"),
            &mesh.points,
            &mesh.triangles,
            &fields.u,
            &format!("deflection u: {}", case.path.display()),
        )?;
    }
    let t_write = t_out.elapsed().as_secs_f64();
    let total = t0.elapsed().as_secs_f64();
    let q = mesh.quality();
    let summary = summary_json(case, run, &q, &totals, t_write, total);
    write_json(&out.join("summary.json"), &summary)?;
    let mut text = human(case, run, &q, &totals, t_write, total);
    let _ = writeln!(
        text,
        "  wrote        {}/{{solution.vtu, nodes.csv, summary.json{}}}",
        out.display(),
        if plotted { ", deflection.png" } else { "" }
    );
    Ok(text)
}

fn time_of(run: &Run, name: &str) -> f64 {
    run.timings
        .iter()
        .find(|t| t.0 == name)
        .map_or(0.0, |t| t.1)
}

fn summary_json(
    case: &Case,
    run: &Run,
    q: &MeshQuality,
    t: &Totals,
    t_write: f64,
    total: f64,
) -> serde_json::Value {
    let s = &run.solution;
    let m = &run.model;
    let phases: serde_json::Map<String, serde_json::Value> = s
        .phases
        .iter()
        .map(|(k, v)| (k.clone(), json!(v)))
        .collect();
    json!({
        "case": case.path.display().to_string(),
        "vertices": q.vertices,
        "triangles": q.triangles,
        "unknowns": q.unknowns,
        "levels": run.hierarchy.depth(),
        "l_n": q.l_n,
        "s_n": q.s_n,
        "min_angle_deg": q.min_angle_deg,
        "area": q.area,
        "solver": s.method.name(),
        "foundation": if m.is_rigid() { "rigid" } else { m.foundation.name() },
        "rigid": m.is_rigid(),
        "sampling": case.obstacle.sampling,
        "epsilon": m.epsilon,
        "tension": m.tension,
        "tolerance": case.solver.tolerance.0,
        "iterations": s.iterations,
        "energy": s.energy,
        "kkt_residual": s.certificate.kkt(),
        "residual_2e": s.certificate.residual_2e,
        "residual_2f": s.certificate.residual_2f,
        "force_scale": s.certificate.force_scale,
        "can_touch_vertices": m.can_touch.iter().filter(|&&c| c).count(),
        "contact_vertices": t.contact_vertices,
        "touching_vertices": t.touching_vertices,
        "penetrating_vertices": t.penetrating_vertices,
        "clear_vertices": t.clear_vertices,
        "contact_area": t.contact_area,
        "total_load": t.total_load,
        "total_contact_force": t.total_contact_force,
        "max_deflection": t.max_deflection,
        "min_u": t.min_u,
        "max_u": t.max_u,
        "history": s.history,
        "solver_phases_s": phases,
        "time_mesh_s": time_of(run, "mesh"),
        "time_assembly_s": time_of(run, "assembly"),
        "time_solve_s": time_of(run, "solve"),
        "time_write_s": t_write,
        "time_total_s": total,
    })
}

fn human(case: &Case, run: &Run, q: &MeshQuality, t: &Totals, t_write: f64, total: f64) -> String {
    let mesh = run.hierarchy.finest();
    let s = &run.solution;
    let m = &run.model;
    let mut o = String::new();
    let _ = writeln!(o, "memcontact: {}", case.path.display());
    o.push_str(&mesh_report(mesh, q, run.hierarchy.depth()));
    let _ = writeln!(
        o,
        "  model        t = {}, foundation {}, sampling {}{}",
        m.tension,
        if m.is_rigid() {
            "rigid"
        } else {
            m.foundation.name()
        },
        case.obstacle.sampling,
        m.epsilon
            .map(|e| format!(" (ε = {e:.4e})"))
            .unwrap_or_default()
    );
    let _ = writeln!(
        o,
        "  solver       {}: {} iterations, J(U) = {:.12e}",
        s.method.name(),
        s.iterations,
        s.energy
    );
    let _ = writeln!(
        o,
        "  certificate  KKT {:.3e} (2e {:.3e}, 2f {:.3e})",
        s.certificate.kkt(),
        s.certificate.residual_2e,
        s.certificate.residual_2f
    );
    let _ = writeln!(
        o,
        "  contact      {} vertices ({} touching, {} penetrating), area {:.6e}",
        t.contact_vertices, t.touching_vertices, t.penetrating_vertices, t.contact_area
    );
    let _ = writeln!(
        o,
        "  forces       total load {:.6e}, total contact force {:.6e}",
        t.total_load, t.total_contact_force
    );
    let _ = writeln!(
        o,
        "  deflection   max |u| = {:.6e} (u in [{:.6e}, {:.6e}])",
        t.max_deflection, t.min_u, t.max_u
    );
    let _ = writeln!(
        o,
        "  time         mesh {:.3} s, assembly {:.3} s, solve {:.3} s, write {:.3} s, total {:.3} s",
        time_of(run, "mesh"),
        time_of(run, "assembly"),
        time_of(run, "solve"),
        t_write,
        total
    );
    if !s.phases.is_empty() {
        let phases: Vec<String> = s
            .phases
            .iter()
            .map(|(k, v)| format!("{k} {v:.3} s"))
            .collect();
        let _ = writeln!(o, "  solver time  {}", phases.join(", "));
    }
    o
}
