//! Tests of the generators.

use super::geometry::*;
use super::size::*;
use super::*;
use crate::mesh::refine::refine_uniform;
use crate::mesh::{Circle, Mesh, Point};
use std::f64::consts::PI;

fn revalidate(m: &Mesh) -> Mesh {
    Mesh::new(
        m.points.clone(),
        m.triangles.clone(),
        m.regions.clone(),
        m.region_names.clone(),
    )
    .unwrap()
}

fn spec(nx: usize, ny: usize, diagonal: Diagonal) -> RectangleSpec {
    RectangleSpec {
        x0: -0.3,
        y0: 0.1,
        x1: 1.7,
        y1: 0.7,
        nx,
        ny,
        diagonal,
    }
}

/// The triangles of a mesh as sorted triples of rounded corner coordinates.
fn triangle_set(m: &Mesh) -> Vec<[[i64; 2]; 3]> {
    let key = |p: Point| [(p[0] * 1e9).round() as i64, (p[1] * 1e9).round() as i64];
    let mut s: Vec<_> = (0..m.triangles.len())
        .map(|k| {
            let mut c = m.corners(k).map(key);
            c.sort();
            c
        })
        .collect();
    s.sort();
    s
}

#[test]
fn diagonal_parses() {
    assert_eq!("Right".parse::<Diagonal>().unwrap(), Diagonal::Right);
    assert_eq!("left".parse::<Diagonal>().unwrap(), Diagonal::Left);
    assert_eq!(
        "alternate".parse::<Diagonal>().unwrap(),
        Diagonal::Alternate
    );
    assert_eq!("crossed".parse::<Diagonal>().unwrap(), Diagonal::Crossed);
    let e = "diagonal".parse::<Diagonal>().unwrap_err().to_string();
    assert!(e.contains("right, left, alternate, crossed"), "{e}");
}

#[test]
fn rectangle_counts_area_and_orientation() {
    for d in [
        Diagonal::Right,
        Diagonal::Left,
        Diagonal::Alternate,
        Diagonal::Crossed,
    ] {
        let h = rectangle(&spec(5, 3, d)).unwrap();
        assert_eq!(h.depth(), 1);
        let m = revalidate(h.finest());
        assert_eq!(m.triangles, h.finest().triangles, "{d:?} must be CCW");
        let q = m.quality();
        let crossed = d == Diagonal::Crossed;
        assert_eq!(q.vertices, 6 * 4 + if crossed { 15 } else { 0 });
        assert_eq!(q.triangles, if crossed { 60 } else { 30 });
        assert!((q.area - 2.0 * 0.6).abs() < 1e-12);
        assert_eq!(m.boundary_edges().len(), 2 * (5 + 3));
        assert_eq!(q.unknowns, 4 * 2 + if crossed { 15 } else { 0 });
        // lexicographic numbering: vertex j (nx+1) + i at (x_i, y_j)
        assert_eq!(m.points[0], [-0.3, 0.1]);
        assert_eq!(m.points[5], [1.7, 0.1]);
        assert_eq!(m.points[23], [1.7, 0.7]);
    }
}

#[test]
fn diagonals_run_the_right_way() {
    let right = rectangle(&spec(1, 1, Diagonal::Right)).unwrap();
    let left = rectangle(&spec(1, 1, Diagonal::Left)).unwrap();
    let has_edge =
        |m: &Mesh, a: u32, b: u32| m.triangles.iter().any(|t| t.contains(&a) && t.contains(&b));
    assert!(has_edge(right.finest(), 0, 3) && !has_edge(right.finest(), 1, 2));
    assert!(has_edge(left.finest(), 1, 2) && !has_edge(left.finest(), 0, 3));
    // Alternate: the four cells around the centre vertex of a 2×2 grid all use it.
    let alt = rectangle(&spec(2, 2, Diagonal::Alternate)).unwrap();
    let uses = alt
        .finest()
        .triangles
        .iter()
        .filter(|t| t.contains(&4))
        .count();
    assert_eq!(uses, 8);
}

#[test]
fn rectangle_hierarchy_matches_uniform_refinement() {
    for d in [Diagonal::Right, Diagonal::Left] {
        let h = rectangle(&spec(12, 8, d)).unwrap();
        // 12 × 8 halves twice (3 × 2 keeps an interior vertex): 3×2, 6×4, 12×8.
        let sizes: Vec<usize> = h.levels.iter().map(|m| m.triangles.len()).collect();
        assert_eq!(sizes, vec![12, 48, 192]);
        assert_eq!(h.refinements.len(), 2);
        for level in 0..2 {
            let (coarse, fine) = (&h.levels[level], &h.levels[level + 1]);
            let (refined, r) = refine_uniform(coarse);
            assert_eq!(triangle_set(&refined), triangle_set(fine));
            // Parents: the same relation, vertex by vertex through coordinates.
            for (v, p) in fine.points.iter().enumerate() {
                let [a, b] = h.refinements[level].parents[v];
                let (pa, pb) = (coarse.points[a as usize], coarse.points[b as usize]);
                assert!((p[0] - 0.5 * (pa[0] + pb[0])).abs() < 1e-14);
                assert!((p[1] - 0.5 * (pa[1] + pb[1])).abs() < 1e-14);
                // and (a, b) is an edge of the coarse mesh or a == b
                if a != b {
                    assert!(coarse
                        .triangles
                        .iter()
                        .any(|t| t.contains(&a) && t.contains(&b)));
                }
            }
            assert_eq!(r.parents.len(), fine.points.len());
            // Coarse vertices sit exactly on fine grid vertices.
            for (v, &[a, b]) in h.refinements[level].parents.iter().enumerate() {
                if a == b {
                    assert_eq!(fine.points[v], coarse.points[a as usize]);
                }
            }
        }
        let lin = |p: Point| 2.0 * p[0] + 5.0 * p[1] - 1.0;
        let c: Vec<f64> = h.levels[0].points.iter().map(|&p| lin(p)).collect();
        let f = h.prolongate(1, &h.prolongate(0, &c));
        for (v, p) in h.finest().points.iter().enumerate() {
            assert!((f[v] - lin(*p)).abs() < 1e-12);
        }
    }
}

#[test]
fn hierarchy_depth_rules() {
    let depth = |nx, ny, d| rectangle(&spec(nx, ny, d)).unwrap().depth();
    assert_eq!(depth(64, 64, Diagonal::Right), 6); // 2, 4, ..., 64
    assert_eq!(depth(64, 16, Diagonal::Left), 4); // 8×2, ..., 64×16
    assert_eq!(depth(2, 2, Diagonal::Right), 1);
    assert_eq!(depth(4, 4, Diagonal::Right), 2);
    assert_eq!(depth(6, 10, Diagonal::Right), 2); // 3×5, 6×10
    assert_eq!(depth(7, 8, Diagonal::Right), 1);
    assert_eq!(depth(64, 64, Diagonal::Alternate), 1);
    assert_eq!(depth(64, 64, Diagonal::Crossed), 1);
    let h = rectangle(&spec(64, 16, Diagonal::Left)).unwrap();
    assert_eq!(h.levels[0].points.len(), 9 * 3);
}

#[test]
fn rectangle_rejects_bad_input() {
    let mut s = spec(2, 2, Diagonal::Right);
    s.x1 = s.x0;
    assert!(rectangle(&s).unwrap_err().to_string().contains("x0 < x1"));
    let mut s = spec(2, 0, Diagonal::Right);
    assert!(rectangle(&s).unwrap_err().to_string().contains("ny = 0"));
    s.ny = 2;
    s.y0 = f64::NAN;
    assert!(rectangle(&s).unwrap_err().to_string().contains("y0"));
    let s = spec(100_000, 100_000, Diagonal::Right);
    assert!(rectangle(&s).unwrap_err().to_string().contains("limit"));
}

#[test]
fn disk_is_shape_regular_and_on_the_circle() {
    let (c, r, h) = ([0.5, -1.0], 2.0, 0.2);
    let m = disk(c, r, h).unwrap();
    assert_eq!(
        m.curve,
        Some(Circle {
            center: c,
            radius: r
        })
    );
    let q = m.quality();
    assert!(q.min_angle_deg > 25.0, "{q:?}");
    assert!(q.l_n < 2.0 * h, "{q:?}");
    let boundary = m.boundary_vertices();
    let nb = boundary.iter().filter(|b| **b).count();
    let expected = 2.0 * PI * r / h;
    assert!(
        nb as f64 >= expected && (nb as f64) < 1.5 * expected,
        "{nb}"
    );
    for (v, p) in m.points.iter().enumerate() {
        let d = crate::mesh::dist(*p, c);
        if boundary[v] {
            assert!((d - r).abs() < 1e-12 * r, "boundary vertex {v} at {d}");
        } else {
            assert!(d < r);
        }
    }
    // Inscribed polygon with chords ≤ h: area error ≤ n·h³/(12 r).
    let err = PI * r * r - q.area;
    assert!(
        err > 0.0 && err < nb as f64 * h.powi(3) / (12.0 * r),
        "{err}"
    );
    // Refining keeps the boundary on the circle and the area converges.
    let (f, _) = refine_uniform(&m);
    assert!(PI * r * r - f.total_area() < err / 3.0);
}

#[test]
fn fine_disks_and_polygons_are_coarse_meshes_refined_with_their_guarantees() {
    // Small: one Delaunay mesh, as `disk` makes it.
    let small = disk_levels([0.0, 0.0], 1.0, 0.1).unwrap();
    assert_eq!(small.levels.len(), 1);
    assert_eq!(
        triangle_set(small.finest()),
        triangle_set(&disk([0.0, 0.0], 1.0, 0.1).unwrap())
    );
    // Fine: about 4× more triangles than the limit of Delaunay refinement.
    let (c, r, h) = ([0.3, -0.2], 1.0, 0.005);
    let levels = disk_levels(c, r, h).unwrap();
    assert!(levels.levels.len() >= 3, "at least two uniform refinements");
    let m = levels.finest();
    let q = revalidate(m).quality();
    let expected = estimated_triangles(PI * r * r, h);
    assert!(
        (0.6 * expected..1.4 * expected).contains(&(q.triangles as f64)),
        "{} triangles for {expected:.0} expected",
        q.triangles
    );
    // The size and angle guarantees of `disk` (snapping to the circle costs a little
    // of the 30° at the boundary), every boundary vertex on the circle.
    assert!(q.min_angle_deg > 25.0, "{q:?}");
    assert!(q.l_n < 2.0 * h, "{q:?}");
    let boundary = m.boundary_vertices();
    for (v, p) in m.points.iter().enumerate() {
        if boundary[v] {
            let d = crate::mesh::dist(*p, c);
            assert!((d - r).abs() < 1e-12, "boundary vertex {v} at {d}");
        }
    }
    assert_eq!(m.boundary.names.get(&1).map(String::as_str), Some("outer"));

    // A polygon with a hole and a region: areas exact, regions and boundary regions
    // carried to the finest level, angles at least the coarse mesh's.
    let spec = PolygonSpec {
        outer: square(0.0, 2.0),
        holes: vec![square(0.2, 0.6)],
        regions: vec![(
            "clay".into(),
            vec![[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]],
        )],
        size: 0.006,
        min_angle: 28.0,
    };
    let levels = polygon_levels(&spec).unwrap();
    assert!(levels.levels.len() >= 3);
    let m = levels.finest();
    let q = revalidate(m).quality();
    assert!((q.area - (4.0 - 0.16)).abs() < 1e-9, "{}", q.area);
    assert!(q.min_angle_deg > 27.9, "{q:?}");
    assert!(q.l_n < 2.0 * spec.size, "{q:?}");
    let clay: f64 = (0..m.triangles.len())
        .filter(|&k| m.regions[k] == 1)
        .map(|k| m.area(k))
        .sum();
    assert!((clay - 1.0).abs() < 1e-9, "{clay}");
    assert_eq!(m.region_name(1), "clay");
    let names: Vec<&str> = m.boundary.names.values().map(String::as_str).collect();
    assert_eq!(names, ["outer", "hole1"]);
    // Too fine is refused as by `polygon`.
    let e = polygon_levels(&PolygonSpec { size: 1e-5, ..spec }).unwrap_err();
    assert!(e.to_string().contains("limit"), "{e}");
}

#[test]
fn disk_rejects_bad_input() {
    assert!(disk([0.0, 0.0], -1.0, 0.1)
        .unwrap_err()
        .to_string()
        .contains("radius"));
    assert!(disk([0.0, 0.0], 1.0, 0.0)
        .unwrap_err()
        .to_string()
        .contains("size"));
    assert!(disk([0.0, 0.0], 1.0, 1e-5)
        .unwrap_err()
        .to_string()
        .contains("limit"));
    assert!(disk([f64::NAN, 0.0], 1.0, 0.1).is_err());
}

fn square(a: f64, b: f64) -> Vec<Point> {
    vec![[a, a], [b, a], [b, b], [a, b]]
}

#[test]
fn polygon_with_hole_and_regions() {
    let s = PolygonSpec {
        outer: vec![
            [0.0, 0.0],
            [4.0, 0.0],
            [4.0, 2.0],
            [2.0, 2.0],
            [2.0, 4.0],
            [0.0, 4.0],
        ],
        holes: vec![vec![[0.5, 0.5], [1.0, 0.5], [1.0, 1.0], [0.5, 1.0]]],
        regions: vec![
            // a layer along the bottom edge, sharing boundary with the outer polygon
            (
                "clay".into(),
                vec![[2.0, 0.0], [4.0, 0.0], [4.0, 1.0], [2.0, 1.0]],
            ),
            // a triangle strictly inside
            ("sand".into(), vec![[0.5, 2.5], [1.5, 2.5], [1.0, 3.5]]),
        ],
        size: 0.2,
        min_angle: 28.0,
    };
    let m = polygon(&s).unwrap();
    let q = m.quality();
    assert!((q.area - (12.0 - 0.25)).abs() < 1e-9, "{}", q.area);
    assert!(q.min_angle_deg > 20.0, "{q:?}");
    assert!(q.l_n < 2.0 * s.size, "{q:?}");
    let area_of = |tag: u32| -> f64 {
        (0..m.triangles.len())
            .filter(|&k| m.regions[k] == tag)
            .map(|k| m.area(k))
            .sum()
    };
    assert!((area_of(1) - 2.0).abs() < 1e-9);
    assert!((area_of(2) - 0.5).abs() < 1e-9);
    assert!((area_of(0) - (12.0 - 0.25 - 2.5)).abs() < 1e-9);
    assert_eq!(m.region_name(0), "default");
    assert_eq!(m.region_name(1), "clay");
    assert_eq!(m.region_name(2), "sand");
    // The hole's corners are boundary vertices; no triangle inside the hole.
    for k in 0..m.triangles.len() {
        let c = m.corners(k);
        let g = [
            (c[0][0] + c[1][0] + c[2][0]) / 3.0,
            (c[0][1] + c[1][1] + c[2][1]) / 3.0,
        ];
        assert!(!inside(g, &s.holes[0]));
    }
    // Two boundary loops of total length 18: at least 18 / size boundary edges (more
    // where refinement on both sides of the boundary split them further).
    let nb = m.boundary_edges().len();
    assert!((90..180).contains(&nb), "{nb}");
}

#[test]
fn a_long_thin_polygon_is_refused_before_its_boundary_is_subdivided() {
    // Area 1, boundary 2e9: 2e12 boundary points at size 1e-3.
    let e = polygon(&PolygonSpec {
        outer: vec![[0.0, 0.0], [1e9, 0.0], [1e9, 1e-9], [0.0, 1e-9]],
        size: 1e-3,
        min_angle: 25.0,
        ..PolygonSpec::default()
    })
    .unwrap_err();
    assert!(e.to_string().contains("boundary points"), "{e}");
}

#[test]
fn subdivided_hull_edges_make_no_flat_triangle() {
    // A quadrilateral whose subdivided edges round a point a hair outside its edge's
    // line: once a flat triangle on the convex hull (refused by the mesh checks), and
    // with an inner region an endless refinement.
    let ring = |scale: f64| -> Vec<Point> {
        [
            [0.8314008957461496, 0.4732346134033799],
            [-0.6364938189611482, 0.7629665477107125],
            [-0.5407696944244654, -0.6194612298086862],
            [0.74945108207679, -0.4166310906170837],
        ]
        .iter()
        .map(|p| [scale * p[0], scale * p[1]])
        .collect()
    };
    for regions in [vec![], vec![("core".to_string(), ring(0.5))]] {
        let m = polygon(&PolygonSpec {
            outer: ring(1.0),
            holes: vec![],
            regions,
            size: 0.28482042467643337,
            min_angle: 25.0,
        })
        .unwrap();
        assert!((m.quality().area - ring_area(&ring(1.0)).abs()).abs() < 1e-12);
    }
}

#[test]
fn polygon_without_regions_has_no_names() {
    let s = PolygonSpec {
        outer: square(0.0, 1.0),
        holes: vec![],
        regions: vec![],
        size: 0.1,
        min_angle: 30.0,
    };
    let m = polygon(&s).unwrap();
    assert!(m.region_names.is_empty());
    assert!(m.regions.iter().all(|&r| r == 0));
    assert!((m.total_area() - 1.0).abs() < 1e-12);
    assert!(m.quality().min_angle_deg > 25.0);
}

#[test]
fn polygon_rejects_bad_input() {
    let ok = PolygonSpec {
        outer: square(0.0, 1.0),
        holes: vec![],
        regions: vec![],
        size: 0.1,
        min_angle: 25.0,
    };
    let err = |s: PolygonSpec| polygon(&s).unwrap_err().to_string();
    let mut s = ok.clone();
    s.outer.truncate(2);
    assert!(err(s).contains("at least 3"));
    let mut s = ok.clone();
    s.outer = vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
    assert!(err(s).contains("self-intersecting"));
    let mut s = ok.clone();
    s.outer[2][0] = f64::INFINITY;
    assert!(err(s).contains("not finite"));
    let mut s = ok.clone();
    s.holes = vec![square(2.0, 3.0)];
    assert!(err(s).contains("outside"));
    let mut s = ok.clone();
    s.holes = vec![square(0.5, 1.5)];
    assert!(err(s).contains("crosses"));
    let mut s = ok.clone();
    s.holes = vec![square(0.2, 0.5), square(0.4, 0.7)];
    assert!(err(s).contains("overlap"));
    let mut s = ok.clone();
    s.holes = vec![square(0.2, 0.8), square(0.4, 0.6)];
    assert!(err(s).contains("overlap"));
    let mut s = ok.clone();
    s.min_angle = 35.0;
    assert!(err(s).contains("min_angle"));
    let mut s = ok.clone();
    s.min_angle = 0.0;
    assert!(err(s).contains("min_angle"));
    let mut s = ok.clone();
    s.size = -1.0;
    assert!(err(s).contains("size"));
    let mut s = ok.clone();
    s.size = 1e-5;
    assert!(err(s).contains("limit"));
    let mut s = ok.clone();
    s.regions = vec![("out".into(), square(0.5, 2.0))];
    assert!(err(s).contains("outside"));
    let mut s = ok;
    s.outer = vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
    let e = err(s);
    assert!(
        e.contains("self-intersecting") || e.contains("zero area"),
        "{e}"
    );
}

#[test]
fn convex_hull_of_l_shape() {
    let l = vec![
        [0.0, 0.0],
        [2.0, 0.0],
        [2.0, 1.0],
        [1.0, 1.0],
        [1.0, 2.0],
        [0.0, 2.0],
    ];
    let h = convex_hull(&l);
    assert_eq!(h.len(), 5);
    assert!((ring_area(&h) - 3.5).abs() < 1e-15);
}
#[test]
fn layer_ending_mid_edge_shares_the_boundary_cleanly() {
    // A 0.7-thick layer along the bottom of an L: its sides end in the middle of the
    // outer edges, whose subdivision (0.2) does not match the layer's (0.175).
    let outer = vec![
        [0.0, 0.0],
        [4.0, 0.0],
        [4.0, 2.0],
        [2.0, 2.0],
        [2.0, 4.0],
        [0.0, 4.0],
    ];
    let layer = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 0.7], [0.0, 0.7]];
    let s = PolygonSpec {
        outer,
        holes: vec![],
        regions: vec![("layer".into(), layer)],
        size: 0.2,
        min_angle: 28.0,
    };
    let m = polygon(&s).unwrap();
    let shortest = m
        .boundary_edges()
        .iter()
        .map(|&[a, b]| crate::mesh::dist(m.points[a as usize], m.points[b as usize]))
        .fold(f64::INFINITY, f64::min);
    assert!(shortest > 0.05, "{shortest}");
    assert!(m.quality().min_angle_deg > 20.0);
    let layer_area: f64 = (0..m.triangles.len())
        .filter(|&k| m.regions[k] == 1)
        .map(|k| m.area(k))
        .sum();
    assert!((layer_area - 2.8).abs() < 1e-9, "{layer_area}");
    assert!((m.total_area() - 12.0).abs() < 1e-9);
}
/// Timings for the report: `cargo test --release -p memcontact --lib timings -- --ignored --nocapture`.
#[test]
#[ignore]
fn timings() {
    for n in [1024, 4096] {
        let t = std::time::Instant::now();
        let h = rectangle(&spec(n, n, Diagonal::Right)).unwrap();
        let dt = t.elapsed();
        let tri: usize = h.levels.iter().map(|m| m.triangles.len()).sum();
        eprintln!(
            "rectangle {n}²: {dt:?}, {} levels, finest {} vertices / {} triangles, all levels {tri} triangles",
            h.depth(),
            h.finest().points.len(),
            h.finest().triangles.len()
        );
    }
    let coarse = rectangle(&spec(708, 708, Diagonal::Alternate))
        .unwrap()
        .levels
        .pop()
        .unwrap();
    let t = std::time::Instant::now();
    let (f, _) = refine_uniform(&coarse);
    eprintln!(
        "refine_uniform {} -> {} triangles: {:?}",
        coarse.triangles.len(),
        f.triangles.len(),
        t.elapsed()
    );
    let t = std::time::Instant::now();
    let d = disk([0.0, 0.0], 1.0, 0.005).unwrap();
    eprintln!(
        "disk size 0.005: {} triangles in {:?}",
        d.triangles.len(),
        t.elapsed()
    );
}
