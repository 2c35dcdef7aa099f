//! What `memcontact solve` shows: the human summary on the terminal. The result files are
//! the library's (`memcontact::write`), with their pictures.

use memcontact::mesh::{Mesh, MeshQuality};
use memcontact::{Discretization, Outcome, Summary};
use std::fmt::Write as _;
use std::path::Path;

/// Prints the mesh reader's warnings.
pub fn print_warnings(d: &Discretization) {
    for w in &d.warnings {
        eprintln!("warning: {w}");
    }
}

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

/// The boundary regions line of `check`: every boundary region with its edges and length,
/// and whether it is held (u = g) or free (the names in `free`).
pub fn boundary_report(mesh: &Mesh, free: &[String]) -> String {
    let adj = memcontact::mesh::VertexTriangles::new(mesh);
    let tagged = mesh.tagged_boundary(&adj);
    let present = tagged.present();
    let free_tags: Vec<u32> = free
        .iter()
        .flat_map(|k| mesh.boundary.resolve(k, &present))
        .collect();
    let regions: Vec<String> = mesh
        .boundary_regions_summary(&tagged)
        .iter()
        .map(|r| {
            format!(
                "{} ({} edge{}, length {:.6}, {})",
                r.name,
                r.edges,
                if r.edges == 1 { "" } else { "s" },
                r.length,
                if free_tags.contains(&r.tag) {
                    "free"
                } else {
                    "held"
                }
            )
        })
        .collect();
    format!("  boundary     {}\n", regions.join(", "))
}

/// What to do when a solve stopped at the rounding floor above the tolerance.
pub fn floor_note(outcome: &Outcome) -> Option<String> {
    let r = &outcome.report;
    if r.status != memcontact::Status::RoundingFloor {
        return None;
    }
    let kkt = r.certificate.kkt();
    // The tolerance to set: the residual reached, rounded up to two digits.
    let e = kkt.log10().floor();
    let suggested = (kkt / 10f64.powf(e) * 10.0).ceil() / 10.0 * 10f64.powf(e);
    Some(format!(
        "note: the residual {kkt:.2e} is at the rounding floor of double precision for \
         these data and this mesh (≈ {:.1e}), above the tolerance {:.1e}: no solver can \
         certify more. {} set [solver] tolerance = {suggested:.1e} to state the accuracy \
         this answer has{}.",
        r.certificate.rounding_floor,
        r.tolerance,
        if r.accepted {
            "The answer is accepted as it is (solver.accept_rounding_floor = true);"
        } else {
            "To accept it,"
        },
        if r.certificate.rounding_floor > 1e-6 {
            ", or make the data better conditioned (a stiffness this large is close to \
             rigid: stiffness = \"rigid\")"
        } else {
            ""
        }
    ))
}

/// The human summary of a run; with `written`, the summary.json values and where the files
/// went.
pub fn human(label: &str, outcome: &Outcome, written: Option<(&Summary, &Path)>) -> String {
    let d = &outcome.discretization;
    let r = &outcome.report;
    let m = &d.model;
    let mesh = d.mesh();
    let q = &d.quality;
    let t = outcome.totals();
    let mut o = String::new();
    let _ = writeln!(o, "memcontact: {label}");
    o.push_str(&mesh_report(mesh, q, d.hierarchy.depth()));
    let _ = writeln!(
        o,
        "  model        t = {}, foundation {}, sampling {}{}",
        m.tension,
        if m.is_rigid() {
            "rigid"
        } else {
            m.foundation.name()
        },
        if m.epsilon.is_some() {
            "mollified"
        } else {
            "nodal"
        },
        m.epsilon
            .map(|e| format!(" (ε = {e:.4e})"))
            .unwrap_or_default()
    );
    if let Some(rigid) = &m.rigid {
        let _ = writeln!(
            o,
            "  rigid part   {} unknowns held rigidly (u ≤ φ) by rigid regions",
            rigid.iter().filter(|&&x| x).count()
        );
    }
    if let Some(low) = &m.lower {
        let _ = writeln!(
            o,
            "  body below   foundation {}{}, {} unknowns it can touch",
            if low.l.is_rigid() {
                "rigid"
            } else {
                low.foundation.name()
            },
            match &low.rigid {
                Some(r) => format!(
                    " ({} unknowns held rigidly)",
                    r.iter().filter(|&&x| x).count()
                ),
                None => String::new(),
            },
            low.can_touch.iter().filter(|&&c| c).count()
        );
    }
    let fixed = m.dofs.per_vertex().filter(|d| d.is_none()).count();
    // The unknowns beyond the interior vertices: those on free edges.
    let free = m.n().saturating_sub(q.unknowns);
    if free > 0 || !m.boundary_values.is_empty() {
        let heights = m
            .boundary_values
            .iter()
            .enumerate()
            .filter(|(v, _)| m.dofs.is_fixed(*v))
            .map(|(_, &g)| g);
        let (lo, hi) = heights.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), g| {
            (a.min(g), b.max(g))
        });
        let range = if lo.is_finite() {
            format!(", heights g in [{lo:.6e}, {hi:.6e}]")
        } else {
            ", heights g = 0".to_string()
        };
        let _ = writeln!(
            o,
            "  boundary     {fixed} fixed vertices{range}, {free} vertices on free edges"
        );
    }
    let why = match (&r.fallback, r.requested) {
        (Some(f), _) => format!(
            " (auto: {} {} at KKT {:.1e}, fell back)",
            f.from.name(),
            f.status.name().replace('_', " "),
            f.residual
        ),
        (None, memcontact::Method::Auto) => format!(" (auto: {})", r.choice.reason()),
        _ => String::new(),
    };
    let _ = writeln!(
        o,
        "  solver       {}{}{why}: {} iterations, J(U) = {:.12e}, {}",
        r.method.name(),
        match r.coarsening {
            Some(memcontact::solve::HierarchyKind::Geometric) => " on the mesh levels",
            Some(memcontact::solve::HierarchyKind::Algebraic) => " on algebraic levels",
            None => "",
        },
        r.iterations,
        r.energy,
        r.status.name().replace('_', " ")
    );
    let _ = writeln!(
        o,
        "  certificate  KKT {:.3e} (2e {:.3e}, 2f {:.3e}), tolerance {:.1e}",
        r.certificate.kkt(),
        r.certificate.residual_2e,
        r.certificate.residual_2f,
        r.tolerance
    );
    let _ = writeln!(
        o,
        "  contact      {} vertices ({} touching, {} penetrating), area {:.6e}",
        t.contact_vertices, t.touching_vertices, t.penetrating_vertices, t.contact_area
    );
    if let Some(l) = &t.lower {
        let _ = writeln!(
            o,
            "  below        {} vertices on the body below ({} touching, {} sunk in), area \
             {:.6e}; {} squeezed between both",
            l.contact_low_vertices,
            l.touching_low_vertices,
            l.penetrating_low_vertices,
            l.contact_area_low,
            l.squeezed_vertices
        );
    }
    let _ = writeln!(
        o,
        "  forces       total load {:.6e}, total contact force {:.6e}{}",
        t.total_load,
        t.total_contact_force,
        t.lower
            .map(|l| format!(
                ", body below's force {:.6e} (upward)",
                l.total_contact_force_low
            ))
            .unwrap_or_default()
    );
    let _ = writeln!(
        o,
        "  deflection   max |u| = {:.6e} (u in [{:.6e}, {:.6e}])",
        t.max_deflection, t.min_u, t.max_u
    );
    let mut times = format!(
        "mesh {:.3} s, assembly {:.3} s, solve {:.3} s",
        r.seconds("mesh"),
        r.seconds("assembly"),
        r.seconds("solve")
    );
    if let Some((s, _)) = written {
        let _ = write!(
            times,
            ", write {:.3} s, total {:.3} s",
            s.time_write_s, s.time_total_s
        );
    }
    let _ = writeln!(o, "  time         {times}");
    if !r.solver_phases.is_empty() {
        let phases: Vec<String> = r
            .solver_phases
            .iter()
            .map(|p| format!("{} {:.3} s", p.name, p.seconds))
            .collect();
        let _ = writeln!(o, "  solver time  {}", phases.join(", "));
    }
    if let Some((s, dir)) = written {
        let mut names: Vec<&str> = s.files.keys().map(String::as_str).collect();
        names.push("summary.json");
        let _ = writeln!(
            o,
            "  wrote        {}/{{{}}}",
            dir.display(),
            names.join(", ")
        );
    }
    o
}
