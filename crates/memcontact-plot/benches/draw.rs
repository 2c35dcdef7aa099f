//! Drawing the four pictures of a 1 M-vertex result: the unit square with N × N cells
//! (N = 1024 by default, `MEMCONTACT_PLOT_N` to change), synthetic fields shaped like a
//! solution (a membrane pushed onto a sloping Winkler foundation that covers most of it).
//!
//! `cargo bench -p memcontact-plot --bench draw` prints the time of the shared layout
//! (transform + rasterisation + boundary), of each picture, of PNG encoding, and of all
//! four drawn and encoded end to end (as a result set draws them; the library writes the
//! files).

use memcontact_plot::{render, render_kind, MapLayout, PlotData, PlotKind, PlotOptions, Units};
use rayon::prelude::*;
use std::time::Instant;

/// The unit square cut into n × n cells, each into two triangles along its right diagonal.
fn square(n: usize) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
    let h = 1.0 / n as f64;
    let points = (0..=n)
        .flat_map(|j| (0..=n).map(move |i| [i as f64 * h, j as f64 * h]))
        .collect();
    let v = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let triangles = (0..n)
        .flat_map(|j| {
            (0..n).flat_map(move |i| {
                [
                    [v(i, j), v(i + 1, j), v(i + 1, j + 1)],
                    [v(i, j), v(i + 1, j + 1), v(i, j + 1)],
                ]
            })
        })
        .collect();
    (points, triangles)
}

/// All four pictures drawn and encoded as PNG, in parallel.
fn draw_all(data: &PlotData, options: &PlotOptions) -> Vec<Vec<u8>> {
    render(data, options)
        .expect("draw")
        .par_iter()
        .map(|p| p.canvas.encode_png().expect("png"))
        .collect()
}

fn main() {
    let n: usize = std::env::var("MEMCONTACT_PLOT_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1024);
    let (points, triangles) = square(n);
    let pts = &points;
    let u: Vec<f64> = pts
        .iter()
        .map(|p| 8.0 * p[0] * (1.0 - p[0]) * p[1] * (1.0 - p[1]) * (1.0 + 0.3 * p[0]))
        .collect();
    let phi: Vec<f64> = pts
        .iter()
        .map(|p| 0.35 + 0.1 * p[0] * p[1] + 0.02 * (9.0 * p[0]).sin())
        .collect();
    let covered: Vec<bool> = pts.iter().map(|p| p[0] < 0.92).collect();
    let state: Vec<i8> = u
        .iter()
        .zip(&phi)
        .zip(&covered)
        .map(|((u, f), &c)| {
            if !c || u < f {
                -1
            } else if u == f {
                0
            } else {
                1
            }
        })
        .collect();
    let pressure: Vec<f64> = u
        .iter()
        .zip(&phi)
        .zip(&covered)
        .map(|((u, f), &c)| if c { 300.0 * (u - f).max(0.0) } else { 0.0 })
        .collect();
    let data = PlotData {
        points: pts,
        triangles: &triangles,
        u: &u,
        phi: &phi,
        state: &state,
        pressure: &pressure,
        covered: &covered,
        lower: None,
        numbering: None,
    };
    let options = PlotOptions {
        title: Some(format!("synthetic square N = {n}")),
        allowable_pressure: Some(12.0),
        units: Units {
            length: Some("m".into()),
            force: Some("kN".into()),
        },
        ..PlotOptions::default()
    };
    println!(
        "{} vertices, {} triangles, {} threads",
        pts.len(),
        triangles.len(),
        rayon::current_num_threads()
    );
    // Warm-up (fonts, colour tables, page faults).
    draw_all(&data, &options);
    let reps = 3;
    let best = |f: &mut dyn FnMut()| {
        (0..reps)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let layout = MapLayout::new(&data);
    {
        use memcontact_plot::raster;
        let pv = layout.vertex_pixels().to_vec();
        let frame = layout.frame;
        println!(
            "{:<28} {:>8.3} s",
            "  rasterise",
            best(&mut || {
                std::hint::black_box(raster::rasterise(&pv, data.triangles, frame, None));
            })
        );
        println!(
            "{:<28} {:>8.3} s",
            "  boundary edges",
            best(&mut || {
                std::hint::black_box(raster::boundary_edges(pts.len(), data.triangles));
            })
        );
        println!(
            "{:<28} {:>8.3} s",
            "  one level line of u",
            best(&mut || {
                std::hint::black_box(raster::level_segments(&pv, data.triangles, &u, 0.3, None));
            })
        );
    }
    println!(
        "{:<28} {:>8.3} s",
        "layout (raster + boundary)",
        best(&mut || {
            std::hint::black_box(MapLayout::new(&data));
        })
    );
    let mut total = 0.0;
    for kind in PlotKind::ALL {
        let t = best(&mut || {
            std::hint::black_box(render_kind(kind, &layout, &data, &options).expect("render"));
        });
        let pic = render_kind(kind, &layout, &data, &options).expect("render");
        let e = best(&mut || {
            std::hint::black_box(pic.canvas.encode_png().expect("png"));
        });
        let size = pic.canvas.encode_png().expect("png").len();
        println!(
            "{:<28} {:>8.3} s   PNG {:.3} s, {:.0} kB",
            format!("{}.png", kind.name()),
            t,
            e,
            size as f64 / 1e3
        );
        total += t + e;
    }
    println!("{:<28} {:>8.3} s", "sum (sequential)", total);
    let t = best(&mut || {
        std::hint::black_box(draw_all(&data, &options));
    });
    println!("{:<28} {:>8.3} s", "all four, PNG bytes", t);
    let t = best(&mut || {
        let c = memcontact_plot::field_plot(pts, &triangles, &u, "u").expect("field plot");
        std::hint::black_box(c.encode_png().expect("png"));
    });
    println!("{:<28} {:>8.3} s", "field_plot (u only, PNG)", t);
    let c0 = cpu_seconds();
    let t0 = Instant::now();
    let pngs = draw_all(&data, &options);
    println!(
        "{:<28} {:>8.3} s wall, {:.3} s CPU",
        "all four once more",
        t0.elapsed().as_secs_f64(),
        cpu_seconds() - c0
    );
    if let Ok(keep) = std::env::var("MEMCONTACT_KEEP_PLOTS") {
        for (kind, png) in options.plots.iter().zip(pngs) {
            let to = std::path::Path::new(&keep).join(format!("bench-{}", kind.file_name()));
            std::fs::write(to, png).expect("write");
        }
    }
}

/// User + system CPU seconds of this process (Linux `/proc/self/stat`; 0 elsewhere).
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = after.split_whitespace().collect();
    let tick = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    // fields 14 and 15 of the file (utime, stime) are 12 and 13 after the name
    (tick(11) + tick(12)) / 100.0
}
