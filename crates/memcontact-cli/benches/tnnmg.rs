//! `cargo bench -p memcontact-cli --bench tnnmg [-- N1 N2 ...] [-- --lumped|--consistent]`:
//! the standard benchmark table of `memcontact bench` (see `memcontact_cli::bench::standard`). Sizes default to
//! 128 … 2048 cells per side. Environment: `MEMCONTACT_PHASES=1` prints the phases,
//! `MEMCONTACT_NESTED_TOL`, `MEMCONTACT_CYCLES`, `MEMCONTACT_SMOOTHING`,
//! `MEMCONTACT_NO_NESTED` override the TNNMG options.

use memcontact_cli::bench::standard::{run_bench, BenchRow};

/// The allocator of the `memcontact` binary, so that the kernels are timed as it runs them.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;
use memcontact::bench::TnnmgOptions;
use memcontact::model::Foundation;

/// `-- --micro N`: times the kernels of one TNNMG iteration on the N × N benchmark mesh
/// and its geometric levels (with `--mesh FILE` instead of N: on a Gmsh mesh renumbered as
/// a solve would, and its algebraic levels).
fn micro(args: &[String]) {
    use memcontact::bench::{kernel_timings, Coarsening};
    let h = match args.iter().position(|a| a == "--mesh") {
        Some(k) => {
            let user = memcontact::io::gmsh::read_msh(std::path::Path::new(&args[k + 1]))
                .unwrap()
                .0;
            memcontact::mesh::refine::Hierarchy::single(user)
                .reordered()
                .0
        }
        None => {
            let n = args.iter().find_map(|a| a.parse().ok()).unwrap_or(1024);
            memcontact_cli::bench::standard::mesh(n).unwrap()
        }
    };
    let coarsening = if h.levels.len() > 1 {
        Coarsening::Geometric(&h)
    } else {
        Coarsening::Algebraic
    };
    for f in [Foundation::Lumped, Foundation::Consistent] {
        let m = memcontact_cli::bench::standard::model(h.finest(), f).unwrap();
        let cpu = || memcontact_cli::bench::proc::cpu_seconds().unwrap_or(f64::NAN);
        let t = kernel_timings(&m, coarsening, 10, &cpu).unwrap();
        println!("{}:                      wall ms   cpu ms", f.name());
        for (name, ms, cpu) in t {
            println!("  {name:<24} {ms:8.2} {cpu:8.2}");
        }
    }
}

/// `-- --assembly N`: times the passes of assembly on the N × N benchmark mesh (and, with
/// `--mesh FILE` instead of N, on a Gmsh mesh renumbered as a solve would).
fn assembly(args: &[String]) {
    use memcontact::bench::{
        assemble_stiffness_and_mass, assemble_vector, unknowns_pattern, DofMap, VertexTriangles,
    };
    let mesh = match args.iter().position(|a| a == "--mesh") {
        Some(k) => {
            let path = std::path::Path::new(&args[k + 1]);
            let user = memcontact::io::gmsh::read_msh(path).unwrap().0;
            let (h, _) = memcontact::mesh::refine::Hierarchy::single(user).reordered();
            h.finest().clone()
        }
        None => {
            let n = args
                .iter()
                .find_map(|a| a.parse().ok())
                .unwrap_or(1024usize);
            memcontact_cli::bench::standard::mesh(n)
                .unwrap()
                .finest()
                .clone()
        }
    };
    let reps = 5;
    let time = |name: &str, f: &mut dyn FnMut()| {
        let c0 = memcontact_cli::bench::proc::cpu_seconds().unwrap_or(f64::NAN);
        let t0 = std::time::Instant::now();
        for _ in 0..reps {
            f();
        }
        let wall = t0.elapsed().as_secs_f64() * 1e3 / reps as f64;
        let cpu = (memcontact_cli::bench::proc::cpu_seconds().unwrap_or(f64::NAN) - c0) * 1e3
            / reps as f64;
        println!("  {name:<28} {wall:8.1} {cpu:8.1}");
    };
    println!(
        "{} vertices (edge span {:.2}):   wall ms   cpu ms",
        mesh.n_vertices(),
        memcontact::bench::edge_span(&mesh)
    );
    let adj = VertexTriangles::new(&mesh);
    let boundary = mesh.boundary_vertices_with(&adj);
    time("vertex triangles", &mut || {
        std::hint::black_box(VertexTriangles::new(&mesh));
    });
    let dofs = DofMap::with_adjacency(&mesh, &adj);
    time("dof map (boundary)", &mut || {
        std::hint::black_box(DofMap::with_adjacency(&mesh, &adj));
    });
    let pattern =
        std::sync::Arc::new(unknowns_pattern(&mesh, &dofs, &adj, &boundary).expect("a pattern"));
    time("pattern", &mut || {
        std::hint::black_box(unknowns_pattern(&mesh, &dofs, &adj, &boundary).ok());
    });
    time("S and consistent L", &mut || {
        std::hint::black_box(assemble_stiffness_and_mass(
            &mesh,
            &dofs,
            &adj,
            &pattern,
            1.0,
            Some(&1000.0),
        ));
    });
    time("S", &mut || {
        std::hint::black_box(assemble_stiffness_and_mass(
            &mesh, &dofs, &adj, &pattern, 1.0, None,
        ));
    });
    time("load vector", &mut || {
        std::hint::black_box(assemble_vector(&mesh, &dofs, &adj, &|e, r, a| {
            e.weighted_load(&20.0, r, a)
        }));
    });
    for f in [Foundation::Lumped, Foundation::Consistent] {
        time(&format!("model ({})", f.name()), &mut || {
            std::hint::black_box(memcontact_cli::bench::standard::model(&mesh, f).unwrap());
        });
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--assembly") {
        assembly(&args);
        return;
    }
    if args.iter().any(|a| a == "--micro") {
        micro(&args);
        return;
    }
    let mut sizes: Vec<usize> = args.iter().filter_map(|a| a.parse().ok()).collect();
    if sizes.is_empty() {
        sizes = vec![128, 256, 512, 1024, 2048];
    }
    let foundations: Vec<Foundation> = if args.iter().any(|a| a == "--lumped") {
        vec![Foundation::Lumped]
    } else if args.iter().any(|a| a == "--consistent") {
        vec![Foundation::Consistent]
    } else {
        vec![Foundation::Lumped, Foundation::Consistent]
    };
    println!("{}", memcontact_cli::bench::square_header());
    let phases = std::env::var_os("MEMCONTACT_PHASES").is_some();
    let mut print = |r: &BenchRow| println!("{}", memcontact_cli::bench::square_row(r, phases));
    let mut options = TnnmgOptions::default();
    if let Some(t) = std::env::var("MEMCONTACT_NESTED_TOL")
        .ok()
        .and_then(|t| t.parse().ok())
    {
        options.nested_tolerance = t;
    }
    if let Some(c) = std::env::var("MEMCONTACT_CYCLES")
        .ok()
        .and_then(|t| t.parse().ok())
    {
        options.cycles = c;
    }
    if let Some(c) = std::env::var("MEMCONTACT_SMOOTHING")
        .ok()
        .and_then(|t| t.parse().ok())
    {
        options.smoothing = (c, c);
    }
    if std::env::var_os("MEMCONTACT_NO_NESTED").is_some() {
        options.nested = false;
    }
    if let Err(e) = run_bench(&sizes, &foundations, &options, &mut print) {
        eprintln!("benchmark failed: {e}");
        std::process::exit(1);
    }
}
