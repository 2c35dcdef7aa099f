//! The four pictures of real solved cases: sizes, contents, text layout, and the contact
//! zone drawn where the state field says contact; redrawing from a result directory gives
//! the same bytes.

#[path = "pictures_common/mod.rs"]
mod common;

use common::Solved;
use memcontact::write::draw_all;
use memcontact_plot::canvas::{decode_png, Rgb};
use memcontact_plot::{
    hatch_color, render, MapLayout, Picture, PlotData, PlotKind, PlotOptions, Units, CONTACT,
    LOWER_CONTACT, LOWER_OUTLINE, LOWER_PRESSURE_OUTLINE, MAP_HEIGHT, MAP_WIDTH, NOT_COVERED,
    OUTLINE, PRESSURE_OUTLINE, PROFILE_HEIGHT, PROFILE_WIDTH,
};
use std::collections::HashSet;

fn options(s: &Solved) -> PlotOptions {
    PlotOptions {
        title: Some(format!("examples/{}.toml", s.name)),
        units: if s.name == "roof" {
            Units {
                length: Some("m".into()),
                force: Some("kN".into()),
            }
        } else {
            Units::default()
        },
        allowable_pressure: (s.name == "roof").then_some(1.8),
        ..PlotOptions::default()
    }
}

/// Distinct colours inside `r`.
fn distinct(p: &Picture, r: memcontact_plot::PixelRect) -> usize {
    let mut set = HashSet::new();
    for y in r.y0..r.y1 {
        for x in r.x0..r.x1 {
            set.insert(p.canvas.get(x as u32, y as u32));
        }
    }
    set.len()
}

/// The vertex class the contact zone is drawn for: 1 contact, 0 clear.
fn class(d: &PlotData, v: u32) -> u8 {
    (d.state[v as usize] >= 0) as u8
}

/// Checks the generic properties of every picture.
fn check_common(s: &Solved, pics: &[Picture]) {
    let d = s.data.view();
    assert_eq!(pics.len(), 4, "{}", s.name);
    for p in pics {
        let (w, h) = match p.kind {
            PlotKind::Profile => (PROFILE_WIDTH, PROFILE_HEIGHT),
            _ => (MAP_WIDTH, MAP_HEIGHT),
        };
        assert_eq!(
            (p.canvas.width, p.canvas.height),
            (w, h),
            "{} {:?}",
            s.name,
            p.kind
        );
        // Texts lie on the canvas and never overlap.
        for (i, a) in p.text_boxes.iter().enumerate() {
            assert!(
                a.x0 >= 0 && a.y0 >= 0 && a.x1 <= w as i32 && a.y1 <= h as i32,
                "{} {:?}: text box {a:?} leaves the canvas",
                s.name,
                p.kind
            );
            for b in &p.text_boxes[..i] {
                assert!(
                    !a.overlaps(b),
                    "{} {:?}: texts {a:?} and {b:?} overlap",
                    s.name,
                    p.kind
                );
            }
        }
        assert!(
            p.text_boxes.len() > 10,
            "{} {:?}: axes, title, legend",
            s.name,
            p.kind
        );
        // Not blank: many colours where the data is drawn.
        let area = match (&p.map, &p.axes) {
            (Some((_, frame)), _) => *frame,
            (_, Some(ax)) => ax.rect,
            _ => panic!("no drawing area"),
        };
        let n = distinct(p, area);
        let want = if p.kind == PlotKind::Liftoff || p.kind == PlotKind::Profile {
            20
        } else {
            100
        };
        assert!(n > want, "{} {:?}: {n} distinct colours", s.name, p.kind);
    }
    // The colour bar of u spans the data range of u.
    let lo = d.u.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = d.u.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(pics[0].range, Some((lo, hi)), "{}", s.name);
    // The pressure bar spans the pressure (or ratio) range.
    let a = options(s).allowable_pressure.unwrap_or(1.0);
    let plo = d
        .pressure
        .iter()
        .map(|p| p / a)
        .fold(f64::INFINITY, f64::min);
    let phi = d
        .pressure
        .iter()
        .map(|p| p / a)
        .fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(pics[1].range, Some((plo, phi)), "{}", s.name);
}

/// The deflection map: hatching exactly on the contact zone, in the right direction, and
/// the outline only where contact and clear vertices meet.
fn check_deflection(s: &Solved, p: &Picture, layout: &MapLayout) {
    let d = s.data.view();
    let (_, frame) = p.map.unwrap();
    let (mut lattice_in, mut hit_in, mut stray) = (0usize, 0usize, 0usize);
    let mut mixed_px = HashSet::new();
    let mut outline_px = Vec::new();
    for y in frame.y0..frame.y1 {
        for x in frame.x0..frame.x1 {
            let c = p.canvas.get(x as u32, y as u32);
            if c == OUTLINE {
                outline_px.push((x, y));
            }
            let Some(t) = layout.triangle_at(x, y) else {
                continue;
            };
            let tri = d.triangles[t as usize];
            let cls: Vec<u8> = tri.iter().map(|&v| class(&d, v)).collect();
            if cls.iter().any(|&k| k != cls[0]) {
                mixed_px.insert((x, y));
                continue;
            }
            let hatch = c == [255, 255, 255] || c == [0, 0, 0];
            if cls[0] == 0 {
                // Clear triangles: no hatching at all.
                assert!(
                    !hatch,
                    "{}: hatch colour at ({x}, {y}) in a clear triangle",
                    s.name
                );
                continue;
            }
            let states: Vec<i8> = tri.iter().map(|&v| d.state[v as usize]).collect();
            if states.iter().any(|&k| k != states[0]) {
                continue; // touching and penetrating mixed: either pattern
            }
            let slash = states[0] == 1;
            match hatch_color(x, y, slash) {
                Some(want) => {
                    lattice_in += 1;
                    hit_in += (c == want) as usize;
                }
                None => stray += hatch as usize,
            }
        }
    }
    if d.state.iter().any(|&k| k >= 0) {
        assert!(
            lattice_in > 50,
            "{}: {lattice_in} hatch pixels in the contact zone",
            s.name
        );
        // Contour lines, labels and markers may cover some of them.
        assert!(
            hit_in as f64 >= 0.75 * lattice_in as f64,
            "{}: {hit_in} of {lattice_in} hatch pixels",
            s.name
        );
    }
    assert!(
        stray <= lattice_in / 50,
        "{}: {stray} hatch-coloured pixels off the pattern",
        s.name
    );
    // The outline passes only through triangles with contact and clear vertices (within
    // its width).
    let near =
        |x: i32, y: i32| (-3..=3).any(|dy| (-3..=3).any(|dx| mixed_px.contains(&(x + dx, y + dy))));
    let far: Vec<_> = outline_px.iter().filter(|&&(x, y)| !near(x, y)).collect();
    assert!(
        far.is_empty(),
        "{}: outline pixels away from the contact edge: {:?}",
        s.name,
        &far[..far.len().min(5)]
    );
    if d.state.iter().any(|&k| k >= 0) && d.state.iter().any(|&k| k < 0) {
        assert!(outline_px.len() > 20, "{}: the outline is drawn", s.name);
    }
}

/// The lift-off map: contact colour exactly over contact triangles, grey where the body
/// cannot touch, blues elsewhere.
fn check_liftoff(s: &Solved, p: &Picture, layout: &MapLayout) {
    let d = s.data.view();
    let (_, frame) = p.map.unwrap();
    let (mut n_contact, mut ok_contact, mut n_nc, mut ok_nc) = (0, 0, 0, 0);
    for y in frame.y0..frame.y1 {
        for x in frame.x0..frame.x1 {
            let Some(t) = layout.triangle_at(x, y) else {
                continue;
            };
            let c: Rgb = p.canvas.get(x as u32, y as u32);
            let tri = d.triangles[t as usize];
            let cov = tri.iter().filter(|&&v| d.covered[v as usize]).count();
            let con = tri.iter().filter(|&&v| d.state[v as usize] >= 0).count();
            if cov == 0 {
                n_nc += 1;
                ok_nc += (c == NOT_COVERED) as usize;
                assert_ne!(
                    c, CONTACT,
                    "{}: contact colour where the body cannot touch",
                    s.name
                );
            } else if cov == 3 && con == 3 {
                n_contact += 1;
                ok_contact += (c == CONTACT) as usize;
            } else if cov == 3 && con == 0 {
                assert_ne!(
                    c, CONTACT,
                    "{}: contact colour over lift-off at ({x}, {y})",
                    s.name
                );
                assert_ne!(
                    c, NOT_COVERED,
                    "{}: grey over lift-off at ({x}, {y})",
                    s.name
                );
            }
        }
    }
    assert!(
        ok_contact as f64 >= 0.85 * n_contact as f64,
        "{}: {ok_contact}/{n_contact}",
        s.name
    );
    if n_nc >= 500 {
        assert!(
            ok_nc as f64 >= 0.85 * n_nc as f64,
            "{}: {ok_nc}/{n_nc}",
            s.name
        );
    }
}

/// The profile: shaded columns exactly over the contact stretches.
fn check_profile(s: &Solved, p: &Picture) {
    let d = s.data.view();
    let ax = p.axes.unwrap();
    let stretches = memcontact_plot::profile::contact_along(&d, &options(s));
    let shade = memcontact_plot::profile::CONTACT_SHADE;
    let col_shaded = |x: i32| {
        let n = (ax.rect.y0..ax.rect.y1)
            .filter(|&y| p.canvas.get(x as u32, y as u32) == shade)
            .count();
        n as f64 / ax.rect.height() as f64
    };
    for &(a, b) in &stretches {
        let (xa, xb) = (ax.px(a), ax.px(b));
        if xb - xa > 6.0 {
            let m = ((xa + xb) / 2.0) as i32;
            let f = (m - 3..=m + 3).map(col_shaded).fold(0.0, f64::max);
            assert!(
                f > 0.7,
                "{}: contact stretch [{a}, {b}] shaded on {f}",
                s.name
            );
        }
    }
    // Columns well away from every stretch are not shaded.
    for x in ax.rect.x0 + 2..ax.rect.x1 - 2 {
        let s_mid = (x as f64 + 0.5 - ax.rect.x0 as f64) / ax.rect.width() as f64 * ax.x.1;
        let margin = 3.0 / ax.rect.width() as f64 * ax.x.1;
        if stretches
            .iter()
            .all(|&(a, b)| s_mid < a - margin || s_mid > b + margin)
        {
            assert_eq!(
                col_shaded(x),
                0.0,
                "{}: column {x} shaded outside contact",
                s.name
            );
        }
    }
}

fn check_case(s: Solved) {
    let d = s.data.view();
    let opts = options(&s);
    let pics = render(&d, &opts).unwrap();
    // The files are the pictures.
    let dir = tempfile::tempdir().unwrap();
    let files = draw_all(dir.path(), &d, &opts).unwrap();
    assert_eq!(files.len(), 4);
    for (f, p) in files.iter().zip(&pics) {
        common::keep(f, s.name);
        assert_eq!(f.file_name().unwrap().to_string_lossy(), p.kind.file_name());
        let back = decode_png(&std::fs::read(f).unwrap()).unwrap();
        assert!(
            back == p.canvas,
            "{}: {} differs from the rendered picture",
            s.name,
            f.display()
        );
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        4,
        "only the four PNGs"
    );
    check_common(&s, &pics);
    let layout = MapLayout::new(&d);
    check_deflection(&s, &pics[0], &layout);
    check_liftoff(&s, &pics[2], &layout);
    check_profile(&s, &pics[3]);
}

#[test]
fn disk_pictures() {
    check_case(common::disk());
}

#[test]
fn disk_step_pictures() {
    check_case(common::disk_step());
}

#[test]
fn rigid_square_pictures() {
    check_case(common::rigid_square());
}

#[test]
fn roof_pictures() {
    check_case(common::roof());
}

#[test]
fn gmsh_disk_pictures() {
    check_case(common::gmsh_disk());
}

#[test]
fn half_covered_pictures() {
    check_case(common::half_covered());
}

#[test]
fn disk_rigid_pictures() {
    check_case(common::disk_rigid());
}

#[test]
fn manufactured_square_pictures() {
    let s = common::manufactured_square();
    let d = s.data.view();
    // Coarse: the markers are drawn, and the pixel under each contact vertex shows its
    // state's marker colour (orange penetrating, light touching).
    let pics = render(&d, &options(&s)).unwrap();
    assert!(pics[0].markers);
    let layout = MapLayout::new(&d);
    for (v, &st) in d.state.iter().enumerate() {
        let (x, y) = layout.transform.pixel_of(d.points[v]);
        let c = pics[0].canvas.get(x as u32, y as u32);
        match st {
            1 => assert_eq!(c, [255, 120, 0], "vertex {v}"),
            0 => assert_eq!(c, [250, 250, 250], "vertex {v}"),
            _ => assert!(c != [255, 120, 0] && c != [250, 250, 250], "vertex {v}"),
        }
    }
    assert!(d.state.iter().any(|&st| st >= 0), "the case has contact");
    check_case(s);
}

/// With an allowable pressure, the pressure map shows pressure / allowable and outlines the
/// area above 1: the outline's pixels lie where the P1 ratio crosses 1 (triangles with
/// vertices above and at or below the allowable), and every such crossing along a mesh
/// edge has outline pixels next to it.
#[test]
fn allowable_pressure_outlines_the_area_above_one() {
    let s = common::roof();
    let d = s.data.view();
    let opts = PlotOptions {
        plots: vec![PlotKind::Pressure],
        ..options(&s)
    };
    let allowable = opts
        .allowable_pressure
        .expect("the roof has an allowable pressure");
    let ratio = |v: u32| d.pressure[v as usize] / allowable;
    let above = d.pressure.iter().filter(|&&p| p > allowable).count();
    assert!(
        above > 10 && above < d.pressure.len() / 2,
        "{above} vertices above the allowable: the case must have both sides"
    );
    let pics = render(&d, &opts).unwrap();
    let p = &pics[0];
    let (transform, frame) = p.map.unwrap();
    let layout = MapLayout::new(&d);
    // The colour bar spans the ratio.
    let hi = d.pressure.iter().fold(0.0f64, |m, &v| m.max(v)) / allowable;
    assert_eq!(p.range.map(|r| r.1), Some(hi));
    let in_text = |x: i32, y: i32| {
        p.text_boxes
            .iter()
            .any(|b| x >= b.x0 - 1 && x < b.x1 + 1 && y >= b.y0 - 1 && y < b.y1 + 1)
    };
    let mut line = HashSet::new();
    let mut crossing = HashSet::new();
    for y in frame.y0..frame.y1 {
        for x in frame.x0..frame.x1 {
            if p.canvas.get(x as u32, y as u32) == [0, 0, 0] && !in_text(x, y) {
                line.insert((x, y));
            }
            if let Some(t) = layout.triangle_at(x, y) {
                let tri = d.triangles[t as usize];
                let up = tri.iter().filter(|&&v| ratio(v) > 1.0).count();
                if up > 0 && up < 3 {
                    crossing.insert((x, y));
                }
            }
        }
    }
    assert!(line.len() > 100, "{} outline pixels", line.len());
    let near = |set: &HashSet<(i32, i32)>, x: i32, y: i32, r: i32| {
        (-r..=r).any(|dy| (-r..=r).any(|dx| set.contains(&(x + dx, y + dy))))
    };
    let far: Vec<_> = line
        .iter()
        .filter(|&&(x, y)| !near(&crossing, x, y, 3))
        .collect();
    assert!(
        far.is_empty(),
        "outline pixels away from where the ratio crosses 1: {:?}",
        &far[..far.len().min(5)]
    );
    // Where the ratio crosses 1 along a mesh edge, the outline passes.
    let (mut edges, mut outlined) = (0, 0);
    for tri in d.triangles {
        for k in 0..3 {
            let (v, w) = (tri[k], tri[(k + 1) % 3]);
            let (rv, rw) = (ratio(v), ratio(w));
            if (rv > 1.0) == (rw > 1.0) {
                continue;
            }
            let t = (1.0 - rv) / (rw - rv);
            let (a, b) = (d.points[v as usize], d.points[w as usize]);
            let q = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            let (x, y) = transform.pixel_of(q);
            if in_text(x, y) {
                continue;
            }
            edges += 1;
            outlined += near(&line, x, y, 2) as usize;
        }
    }
    assert!(edges > 20, "{edges} edges cross the allowable");
    assert!(
        outlined as f64 >= 0.95 * edges as f64,
        "{outlined} of {edges} crossings outlined"
    );
}

/// The picture options of the two-body liner: its units, and a profile line across the
/// gas bubble (contact with the obstacle) and the stone (squeezed between the bodies).
fn liner_options(s: &Solved) -> PlotOptions {
    PlotOptions {
        units: Units {
            length: Some("m".into()),
            force: Some("kN".into()),
        },
        profile: Some([[0.0, 14.0], [20.0, 14.0]]),
        ..options(s)
    }
}

/// Pixels of `color` in the frame of map `p` lie only in triangles with a vertex where
/// `mine` holds, and fill at least 85 % of the pixels of the triangles whose vertices all
/// have `mine` and none `other` (outlines drawn over the fill take the rest). Returns the
/// pixels of `color` in the triangles whose vertices all have both.
fn check_fill(
    name: &str,
    p: &Picture,
    layout: &MapLayout,
    d: &PlotData,
    color: Rgb,
    mine: &dyn Fn(usize) -> bool,
    other: &dyn Fn(usize) -> bool,
) -> usize {
    let (_, frame) = p.map.unwrap();
    let (mut inside, mut hit, mut both) = (0usize, 0usize, 0usize);
    for y in frame.y0..frame.y1 {
        for x in frame.x0..frame.x1 {
            let Some(t) = layout.triangle_at(x, y) else {
                continue;
            };
            let c = p.canvas.get(x as u32, y as u32);
            let tri = d.triangles[t as usize].map(|v| v as usize);
            let k = tri.iter().filter(|&&v| mine(v)).count();
            let o = tri.iter().filter(|&&v| other(v)).count();
            assert!(
                c != color || k > 0,
                "{name}: its colour at ({x}, {y}), in a triangle without a vertex in contact"
            );
            if k == 3 && o == 0 {
                inside += 1;
                hit += (c == color) as usize;
            }
            if k == 3 && o == 3 {
                both += (c == color) as usize;
            }
        }
    }
    assert!(inside > 500, "{name}: {inside} pixels of contact alone");
    assert!(
        hit as f64 >= 0.85 * inside as f64,
        "{name}: {hit} of {inside} pixels in its colour"
    );
    both
}

/// Pixels of `color` (an outline) lie within 3 pixels of a triangle whose vertices are
/// partly in the set `inside`; there are more than 20 of them.
fn check_outline(
    name: &str,
    p: &Picture,
    layout: &MapLayout,
    d: &PlotData,
    color: Rgb,
    inside: &dyn Fn(usize) -> bool,
) {
    let (_, frame) = p.map.unwrap();
    let mut mixed = HashSet::new();
    let mut line = Vec::new();
    for y in frame.y0..frame.y1 {
        for x in frame.x0..frame.x1 {
            if p.canvas.get(x as u32, y as u32) == color {
                line.push((x, y));
            }
            if let Some(t) = layout.triangle_at(x, y) {
                let k = d.triangles[t as usize]
                    .iter()
                    .filter(|&&v| inside(v as usize))
                    .count();
                if k > 0 && k < 3 {
                    mixed.insert((x, y));
                }
            }
        }
    }
    let near =
        |x: i32, y: i32| (-3..=3).any(|dy| (-3..=3).any(|dx| mixed.contains(&(x + dx, y + dy))));
    let far: Vec<_> = line.iter().filter(|&&(x, y)| !near(x, y)).collect();
    assert!(
        far.is_empty(),
        "{name}: outline pixels away from its contact edge: {:?}",
        &far[..far.len().min(5)]
    );
    assert!(line.len() > 20, "{name}: {} outline pixels", line.len());
}

/// A membrane between two bodies (a small geomembrane liner, with a stone in the subsoil
/// that squeezes it into the cover): every picture draws each body's contact in its own
/// colour, where and only where the membrane touches that body, and names both bodies;
/// the files are the pictures.
#[test]
fn liner_pictures_tell_the_two_bodies_apart() {
    let s = common::liner();
    let d = s.data.view();
    let low = d.lower.expect("the liner lies on a body below");
    let n = d.points.len();
    let up = |i: usize| d.state[i] >= 0;
    let down = |i: usize| low.state[i] >= 0;
    // The case has every kind of vertex.
    assert!(
        (0..n).any(|i| up(i) && !down(i)),
        "contact with the obstacle alone"
    );
    assert!(
        (0..n).any(|i| down(i) && !up(i)),
        "contact with the body below alone"
    );
    assert!((0..n).any(|i| up(i) && down(i)), "squeezed between both");
    assert!((0..n).any(|i| !up(i) && !down(i)), "clear of both");
    let opts = liner_options(&s);
    let pics = render(&d, &opts).unwrap();
    assert_eq!(pics.len(), 4);
    let dir = tempfile::tempdir().unwrap();
    let files = draw_all(dir.path(), &d, &opts).unwrap();
    for (f, p) in files.iter().zip(&pics) {
        common::keep(f, s.name);
        let back = decode_png(&std::fs::read(f).unwrap()).unwrap();
        assert!(back == p.canvas, "{} differs from the picture", f.display());
    }
    // Texts on the canvas, none over another.
    for p in &pics {
        let (w, h) = (p.canvas.width as i32, p.canvas.height as i32);
        for (i, a) in p.text_boxes.iter().enumerate() {
            assert!(
                a.x0 >= 0 && a.y0 >= 0 && a.x1 <= w && a.y1 <= h,
                "{:?}: text box {a:?} leaves the canvas",
                p.kind
            );
            for b in &p.text_boxes[..i] {
                assert!(
                    !a.overlaps(b),
                    "{:?}: texts {a:?} and {b:?} overlap",
                    p.kind
                );
            }
        }
    }
    // The legends name both bodies.
    let legend = |k: usize| pics[k].legend.join(" | ");
    for (k, want) in [
        (
            0,
            &["contact with the obstacle", "contact with the body below"][..],
        ),
        (
            1,
            &["contact with the obstacle", "contact with the body below"][..],
        ),
        (
            2,
            &[
                "obstacle: contact",
                "body below: contact",
                "both: squeezed",
                "obstacle: gap",
                "body below: gap",
            ][..],
        ),
        (
            3,
            &[
                "obstacle φ",
                "body below φ_low",
                "contact with the obstacle",
                "contact with the body below",
            ][..],
        ),
    ] {
        for w in want {
            assert!(
                legend(k).contains(w),
                "{:?}: {w:?} in {}",
                pics[k].kind,
                legend(k)
            );
        }
    }
    let layout = MapLayout::new(&d);

    // Deflection: each body's outline along its own contact edge; hatching over the
    // contact with either body, none over triangles clear of both.
    check_outline("deflection, obstacle", &pics[0], &layout, &d, OUTLINE, &up);
    check_outline(
        "deflection, body below",
        &pics[0],
        &layout,
        &d,
        LOWER_OUTLINE,
        &down,
    );
    let (_, frame) = pics[0].map.unwrap();
    let (mut lattice, mut hit) = (0usize, 0usize);
    for y in frame.y0..frame.y1 {
        for x in frame.x0..frame.x1 {
            let Some(t) = layout.triangle_at(x, y) else {
                continue;
            };
            let c = pics[0].canvas.get(x as u32, y as u32);
            let tri = d.triangles[t as usize].map(|v| v as usize);
            let touching = tri.iter().filter(|&&v| up(v) || down(v)).count();
            let hatch = c == [255, 255, 255] || c == [0, 0, 0];
            if touching == 0 {
                assert!(!hatch, "deflection: hatching at ({x}, {y}) clear of both");
            } else if touching == 3 && tri.iter().all(|&v| !up(v) && low.state[v] == 1) {
                // Sunk into the body below only: the penetrating pattern.
                if let Some(want) = hatch_color(x, y, true) {
                    lattice += 1;
                    hit += (c == want) as usize;
                }
            }
        }
    }
    assert!(
        lattice > 50 && hit as f64 >= 0.75 * lattice as f64,
        "{hit}/{lattice}"
    );

    // Pressure: each body's outline along its own contact edge.
    check_outline(
        "pressure, obstacle",
        &pics[1],
        &layout,
        &d,
        PRESSURE_OUTLINE,
        &up,
    );
    check_outline(
        "pressure, body below",
        &pics[1],
        &layout,
        &d,
        LOWER_PRESSURE_OUTLINE,
        &down,
    );

    // Lift-off: each body's contact colour where, and only where, it touches; both, in
    // stripes, where the membrane is squeezed; elsewhere neither.
    let squeezed_up = check_fill(
        "lift-off, obstacle",
        &pics[2],
        &layout,
        &d,
        CONTACT,
        &up,
        &down,
    );
    let squeezed_low = check_fill(
        "lift-off, body below",
        &pics[2],
        &layout,
        &d,
        LOWER_CONTACT,
        &down,
        &up,
    );
    assert!(
        squeezed_up > 20 && squeezed_low > 20,
        "stripes of both where squeezed: {squeezed_up}, {squeezed_low}"
    );
    // Clear of both: a gap colour (not grey: both bodies cover everything).
    let (_, frame) = pics[2].map.unwrap();
    for y in frame.y0..frame.y1 {
        for x in frame.x0..frame.x1 {
            if let Some(t) = layout.triangle_at(x, y) {
                let tri = d.triangles[t as usize].map(|v| v as usize);
                if tri.iter().all(|&v| !up(v) && !down(v)) {
                    let c = pics[2].canvas.get(x as u32, y as u32);
                    assert!(
                        c != NOT_COVERED && c != CONTACT && c != LOWER_CONTACT,
                        "lift-off: {c:?} at ({x}, {y}), clear of both"
                    );
                }
            }
        }
    }
    // The gaps' range: both gaps shown, from the contact edges (about 0) up.
    let (glo, ghi) = pics[2].range.expect("a gap is shown");
    assert!((0.0..1e-2).contains(&glo) && ghi > 0.05, "{glo} {ghi}");

    // Profile: each body's contact stretches in its own shade.
    let ax = pics[3].axes.unwrap();
    let p = &pics[3];
    let column = |x: i32, shade: Rgb| {
        (ax.rect.y0..ax.rect.y1)
            .filter(|&y| p.canvas.get(x as u32, y as u32) == shade)
            .count() as f64
            / ax.rect.height() as f64
    };
    let upper = memcontact_plot::profile::contact_along(&d, &opts);
    let lower = memcontact_plot::profile::lower_contact_along(&d, &opts);
    assert!(
        !upper.is_empty() && !lower.is_empty(),
        "{upper:?} {lower:?}"
    );
    for (stretches, shade, min) in [
        (&upper, memcontact_plot::profile::CONTACT_SHADE, 0.35),
        (&lower, memcontact_plot::profile::LOWER_SHADE, 0.35),
    ] {
        for &(a, b) in stretches {
            let (xa, xb) = (ax.px(a), ax.px(b));
            if xb - xa > 6.0 {
                let m = ((xa + xb) / 2.0) as i32;
                let f = (m - 3..=m + 3)
                    .map(|x| column(x, shade))
                    .fold(0.0, f64::max);
                assert!(f > min, "stretch [{a}, {b}] shaded on {f}");
            }
        }
        for x in ax.rect.x0 + 2..ax.rect.x1 - 2 {
            let s_mid = (x as f64 + 0.5 - ax.rect.x0 as f64) / ax.rect.width() as f64 * ax.x.1;
            let margin = 3.0 / ax.rect.width() as f64 * ax.x.1;
            if stretches
                .iter()
                .all(|&(a, b)| s_mid < a - margin || s_mid > b + margin)
            {
                assert_eq!(column(x, shade), 0.0, "column {x} shaded outside contact");
            }
        }
    }
}
