//! Pictures of data renumbered for locality with the user's numbering attached are the
//! pictures of the data in the user's numbering.

use crate::{render, BodyData, PlotData, PlotOptions, UserNumbering};

/// A structured grid of the unit square numbered in a scattered order (as a mesh
/// generator's), with fields shaped like a solution: the obstacle touched in the middle,
/// the body below on the left, a part that no body covers.
struct Scattered {
    points: Vec<[f64; 2]>,
    triangles: Vec<[u32; 3]>,
    u: Vec<f64>,
    phi: Vec<f64>,
    state: Vec<i8>,
    pressure: Vec<f64>,
    covered: Vec<bool>,
    phi_low: Vec<f64>,
    state_low: Vec<i8>,
    pressure_low: Vec<f64>,
    covered_low: Vec<bool>,
}

/// A fixed pseudo-random key (for a scattered order without a random-number crate).
fn scramble(i: usize) -> u64 {
    (i as u64 ^ 0x9e37_79b9_7f4a_7c15).wrapping_mul(0xbf58_476d_1ce4_e5b9) >> 7
}

/// `0..n` sorted by `key` (ties by index).
fn order_by(n: usize, key: impl Fn(usize) -> u64) -> Vec<u32> {
    let mut o: Vec<u32> = (0..n as u32).collect();
    o.sort_by_key(|&i| (key(i as usize), i));
    o
}

fn scattered(m: usize) -> Scattered {
    let n = (m + 1) * (m + 1);
    // Grid vertex g at user number user_of_grid[g].
    let grid_of_user = order_by(n, scramble);
    let mut user_of_grid = vec![0u32; n];
    for (u, &g) in grid_of_user.iter().enumerate() {
        user_of_grid[g as usize] = u as u32;
    }
    let h = 1.0 / m as f64;
    let points: Vec<[f64; 2]> = grid_of_user
        .iter()
        .map(|&g| {
            let g = g as usize;
            [(g % (m + 1)) as f64 * h, (g / (m + 1)) as f64 * h]
        })
        .collect();
    let v = |i: usize, j: usize| user_of_grid[j * (m + 1) + i];
    let mut cells = Vec::new();
    for j in 0..m {
        for i in 0..m {
            cells.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            cells.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    let tri_order = order_by(cells.len(), |k| scramble(k + 77));
    let triangles: Vec<[u32; 3]> = tri_order.iter().map(|&k| cells[k as usize]).collect();
    let u: Vec<f64> = points
        .iter()
        .map(|p| 0.8 * (3.0 * p[0]).sin() * (3.0 * p[1]).sin() - 0.3 * p[0])
        .collect();
    let phi: Vec<f64> = points.iter().map(|p| 0.4 + 0.05 * p[1]).collect();
    let phi_low: Vec<f64> = points.iter().map(|p| -0.02 + 0.1 * p[0]).collect();
    let state_of = |d: f64| {
        if d > 1e-3 {
            1
        } else if d > -1e-3 {
            0
        } else {
            -1
        }
    };
    let covered: Vec<bool> = points.iter().map(|p| p[0] < 0.93).collect();
    let covered_low: Vec<bool> = points.iter().map(|p| p[1] > 0.05).collect();
    let state: Vec<i8> = (0..n)
        .map(|i| {
            if covered[i] {
                state_of(u[i] - phi[i])
            } else {
                -1
            }
        })
        .collect();
    let state_low: Vec<i8> = (0..n)
        .map(|i| {
            if covered_low[i] {
                state_of(phi_low[i] - u[i])
            } else {
                -1
            }
        })
        .collect();
    let pressure = (0..n).map(|i| 50.0 * (u[i] - phi[i]).max(0.0)).collect();
    let pressure_low = (0..n)
        .map(|i| 30.0 * (phi_low[i] - u[i]).max(0.0))
        .collect();
    Scattered {
        points,
        triangles,
        u,
        phi,
        state,
        pressure,
        covered,
        phi_low,
        state_low,
        pressure_low,
        covered_low,
    }
}

/// The data of `s` (with the body below when `two`), optionally renumbered.
fn view<'a>(s: &'a Scattered, two: bool) -> PlotData<'a> {
    PlotData {
        points: &s.points,
        triangles: &s.triangles,
        u: &s.u,
        phi: &s.phi,
        state: &s.state,
        pressure: &s.pressure,
        covered: &s.covered,
        lower: two.then_some(BodyData {
            phi: &s.phi_low,
            state: &s.state_low,
            pressure: &s.pressure_low,
            covered: &s.covered_low,
        }),
        numbering: None,
    }
}

/// `s` renumbered: vertices by their position (row by row), triangles by their lowest new
/// vertex; with the user's number of each.
fn renumbered(s: &Scattered) -> (Scattered, Vec<u32>, Vec<u32>) {
    let n = s.points.len();
    let key = |i: usize| {
        let p = s.points[i];
        ((p[1] * 1e6) as u64) << 32 | (p[0] * 1e6) as u64
    };
    let old_of_new = order_by(n, key);
    let mut new_of_old = vec![0u32; n];
    for (new, &old) in old_of_new.iter().enumerate() {
        new_of_old[old as usize] = new as u32;
    }
    let mapped: Vec<[u32; 3]> = s
        .triangles
        .iter()
        .map(|t| t.map(|v| new_of_old[v as usize]))
        .collect();
    let tri_old_of_new = order_by(mapped.len(), |k| *mapped[k].iter().min().unwrap() as u64);
    let gather = |k: &[u32]| -> Vec<[u32; 3]> { k.iter().map(|&t| mapped[t as usize]).collect() };
    fn to_new<T: Copy>(old_of_new: &[u32], x: &[T]) -> Vec<T> {
        old_of_new.iter().map(|&o| x[o as usize]).collect()
    }
    let o = &old_of_new;
    let r = Scattered {
        points: to_new(o, &s.points),
        triangles: gather(&tri_old_of_new),
        u: to_new(o, &s.u),
        phi: to_new(o, &s.phi),
        state: to_new(o, &s.state),
        pressure: to_new(o, &s.pressure),
        covered: to_new(o, &s.covered),
        phi_low: to_new(o, &s.phi_low),
        state_low: to_new(o, &s.state_low),
        pressure_low: to_new(o, &s.pressure_low),
        covered_low: to_new(o, &s.covered_low),
    };
    (r, old_of_new, tri_old_of_new)
}

#[test]
fn renumbered_data_draw_the_pictures_of_the_users_numbering() {
    let user = scattered(96);
    let (local, vertices, triangles) = renumbered(&user);
    let numbering = UserNumbering {
        vertices: &vertices,
        triangles: &triangles,
    };
    for two in [false, true] {
        for allowable in [None, Some(4.0)] {
            let options = PlotOptions {
                allowable_pressure: allowable,
                // Along grid lines: the profile runs on triangle edges (ties).
                profile: Some([[0.0, 0.5], [1.0, 0.5]]),
                ..PlotOptions::default()
            };
            let a = render(&view(&user, two), &options).unwrap();
            let b = render(
                &PlotData {
                    numbering: Some(numbering),
                    ..view(&local, two)
                },
                &options,
            )
            .unwrap();
            assert_eq!(a.len(), 4);
            for (p, q) in a.iter().zip(&b) {
                let what = format!("{:?}, body below {two}, allowable {allowable:?}", p.kind);
                assert_eq!(p.legend, q.legend, "{what}");
                assert_eq!(p.range, q.range, "{what}");
                assert_eq!(p.text_boxes, q.text_boxes, "{what}");
                let differ = p
                    .canvas
                    .rgb
                    .iter()
                    .zip(&q.canvas.rgb)
                    .filter(|(x, y)| x != y)
                    .count();
                assert_eq!(differ, 0, "{what}: {differ} bytes differ");
            }
        }
    }
    // Errors name the user's numbers.
    let mut bad = local.u.clone();
    let v = 17;
    bad[v] = f64::NAN;
    let e = PlotData {
        u: &bad,
        numbering: Some(numbering),
        ..view(&local, false)
    }
    .validate()
    .unwrap_err()
    .to_string();
    assert!(e.contains(&format!("vertex {}", vertices[v])), "{e}");
}
