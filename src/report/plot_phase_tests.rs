//! Tests of the phase diagram plot (`plot_phase`): landmark lines, the chain model, branches
//! and bistable points, the note of a map without boundary, ticks, log axes and the legend, the
//! regions and the boundary lines (also after refinement), the PNG rendering.

use super::*;
use crate::boundary::{MapPoint, PlaneAxis};

/// A map point at `(x, y)` with its coordinates, phase and trust.
fn point(coords: Vec<serde_json::Value>, x: f64, y: f64, phase: &str, trusted: bool) -> MapPoint {
    MapPoint {
        coords,
        x,
        y,
        phase: phase.into(),
        votes: vec![Some(phase.into())],
        tie: false,
        trusted,
        label_kept: false,
        amplitude: None,
        omega: None,
        decided_by: None,
    }
}

fn axis(index: usize, key: &str, label: &str, log: bool) -> PlaneAxis {
    PlaneAxis {
        index,
        key: key.into(),
        label: label.into(),
        log,
    }
}

fn slice(branch: Option<&str>, points: Vec<MapPoint>) -> Slice {
    Slice {
        fixed: Vec::new(),
        branch: branch.map(String::from),
        points,
        boundaries: Default::default(),
    }
}

/// One slice drawn with the plane's scales, but the y axis's where `y_log` is given.
fn draw(map: &PhaseMap, slice: &Slice, y_log: Option<bool>) -> Result<DrawnMap, String> {
    let style = MapStyle { x_log: None, y_log };
    branches_map(map, &[slice], None, None, "t", style)
}

/// One slice drawn with the plane's scales.
fn svg(map: &PhaseMap, slice: &Slice, chain: Option<Vec<(f64, f64)>>) -> String {
    branches_map(map, &[slice], None, chain, "t", MapStyle::default())
        .unwrap()
        .svg
}

#[test]
fn landmark_lines_follow_model_4_1_and_eq_4_15() {
    // Standard wet 2D system: E_cb = 0.2844, s_crit = 0.0711, F_B = 4, N = 1200, L_x = 400.
    let l = Landmarks {
        energy_unit: 0.2844,
        mass: 1.0,
        gravity: 1.0,
        diameter: 1.0,
        wet: Some((0.0711, 4.0)),
        layers: 3.0,
    };
    // On A = s_crit the amplitude from (Gamma, E*) is s_crit: A = v_w^2 / (Gamma g).
    let e = 2.5;
    let g = l.gamma_at_amplitude(e, 0.0711);
    let v_w2 = 2.0 * e * 0.2844;
    assert!((v_w2 / g - 0.0711).abs() < 1e-12);
    // Eq. 4.15 at E* = 0: 1 + F_B / (M m g); at large E* the floor 1 - 1/M.
    assert!((l.gamma_c(0.0).unwrap() - (1.0 + 4.0 / 3.0)).abs() < 1e-12);
    assert!((l.gamma_c(100.0).unwrap() - (1.0 - 1.0 / 3.0)).abs() < 1e-12);
}

#[test]
fn chain_model_matches_eq_7_9() {
    // The shear set-up of docs/model.md 1: F_B = E_cb / s_crit = 6 m g, L_x = 60 d:
    // F_max = 0.9229 * 6 / 60 = 0.09229 (the value quoted in sweeps/shear_3d.toml).
    let text = include_str!("../../tests/scenes/good/shear_3d.toml")
        .replace("size = [12.0, 12.0, 6.0]", "size = [60.0, 12.0, 6.0]");
    let scene = Scene::from_toml_str(&text, "test").unwrap();
    let f = chain_model_f_max(&scene).unwrap();
    assert!((f - 0.09229).abs() < 1e-12, "{f}");
    // Dry scenes have no bridge force and no chain model.
    let dry = Scene::from_toml_str(
        &text
            .replace("model = \"thin_thread\"", "model = \"none\"")
            .replace("s_crit = 0.0625\n", "")
            .replace("e_cb = 0.375\n", "")
            .replace("temperature_over_ecb = 40.0", "temperature = 10.0"),
        "test",
    )
    .unwrap();
    assert_eq!(chain_model_f_max(&dry), None);
}

#[test]
fn chain_model_line_follows_the_other_axis() {
    // Plane: x = L_x (box.size[0]), y = F_max; the line F_c(L_x) = 0.9229 * 6 / L_x.
    let base = include_str!("../../tests/scenes/good/shear_3d.toml");
    let scene_of = |c: &[serde_json::Value]| {
        let l_x = c[0].as_f64()?;
        let text = base.replace(
            "size = [12.0, 12.0, 6.0]",
            &format!("size = [{l_x:?}, 12.0, 6.0]"),
        );
        Scene::from_toml_str(&text, "test").ok()
    };
    let at = |l_x: f64, f: f64| point(vec![l_x.into(), f.into()], l_x, f, "s", true);
    let slice = slice(
        None,
        vec![at(24.0, 0.1), at(12.0, 0.1), at(12.0, 0.5), at(24.0, 0.5)],
    );
    let map = PhaseMap {
        x: Some(axis(0, "box.size[0]", "box.size[0]", false)),
        y: Some(axis(1, "drive.f_max", "drive.f_max", false)),
        shaking: false,
        slices: vec![slice.clone()],
    };
    let line = chain_model_line(&map, &slice, scene_of).unwrap();
    assert_eq!(line.len(), 2);
    for (&(x, y), l_x) in line.iter().zip([12.0, 24.0]) {
        assert_eq!(x, l_x);
        assert!((y - 0.9229 * 6.0 / l_x).abs() < 1e-12, "{y}");
    }
    // Without the F_max axis in the plane: no line.
    let other = PhaseMap {
        y: Some(axis(1, "contact.restitution", "contact.restitution", false)),
        ..map.clone()
    };
    assert!(chain_model_line(&other, &slice, scene_of).is_none());
    // The plot draws it with its legend.
    assert!(svg(&map, &slice, Some(line)).contains("chain model, Eq. 7.9"));
}

#[test]
fn branches_merge_by_position_and_only_disagreeing_points_are_bistable() {
    let at = |x: f64, phase: &str, trusted: bool| point(vec![x.into()], x, 1.0, phase, trusted);
    // Hot: f, g, g at x = 1, 2, 3; cold: f, f at x = 1, 2 (unconverged at 2), and x = 4.
    let hot = slice(
        Some("hot"),
        vec![at(1.0, "f", true), at(2.0, "g", true), at(3.0, "g", true)],
    );
    let cold = slice(
        Some("cold"),
        vec![at(1.0, "f", true), at(2.0, "f", false), at(4.0, "s", true)],
    );
    let merged = merge_branches(&[&hot, &cold]);
    let xs: Vec<f64> = merged.iter().map(|p| p.x).collect();
    assert_eq!(xs, vec![1.0, 2.0, 3.0, 4.0]);
    let bistable: Vec<bool> = merged.iter().map(DrawnPoint::bistable).collect();
    // Only x = 2 disagrees; a point only one branch has is not bistable.
    assert_eq!(bistable, vec![false, true, false, false]);
    assert_eq!(merged[1].phases, vec![Some("g".into()), Some("f".into())]);
    assert!(!merged[1].trusted && merged[0].trusted);
    assert_eq!(merged[3].phase(), "s");
    assert_eq!(branch_name(&[&hot, &cold], 1), "cold start");
}

/// A 3 x 3 (E*, Gamma) grid, Gamma 0.5, 2, 8: f below E* = 2, g from there; `trusted`
/// marks every point.
fn grid_map(trusted: bool) -> (PhaseMap, Slice) {
    let mut points = Vec::new();
    for g in [0.5, 2.0, 8.0] {
        for e in [0.3, 1.0, 4.0] {
            let phase = if e < 2.0 { "f" } else { "g" };
            points.push(point(vec![g.into(), e.into()], e, g, phase, trusted));
        }
    }
    let slice = slice(None, points);
    let map = PhaseMap {
        x: Some(axis(1, "drive.e_star", "E*", true)),
        y: Some(axis(0, "drive.gamma", "Gamma", false)),
        shaking: true,
        slices: vec![slice.clone()],
    };
    (map, slice)
}

#[test]
fn a_map_without_boundary_says_why_on_the_plot() {
    let (map, slice) = grid_map(false);
    let text = svg(&map, &slice, None);
    assert!(
        text.contains("No boundary: none of the 9 points is converged"),
        "{text}"
    );
    let (map, slice) = grid_map(true);
    let mut one_phase = slice.clone();
    for p in &mut one_phase.points {
        p.phase = "g".into();
    }
    assert!(svg(&map, &one_phase, None).contains("No boundary: every converged point is g"));
    // With a boundary point: no note.
    let (_, mut with) = grid_map(true);
    let b = crate::boundary::BoundaryPoint {
        pair: "f|g".into(),
        x: 2.0,
        y: 2.0,
        between: [0, 1],
        x_half: 0.3,
        y_half: 0.0,
        x_range: [1.0, 4.0],
        y_range: [2.0, 2.0],
        confidence: 1.0,
        amplitude: None,
        omega: None,
        branch: None,
    };
    with.boundaries.insert("f|g".into(), vec![b]);
    assert!(!svg(&map, &with, None).contains("No boundary"));
}

#[test]
fn the_axes_have_decade_ticks_typeset_names_and_gamma_can_be_logarithmic() {
    let (map, slice) = grid_map(true);
    let linear = svg(&map, &slice, None);
    let log = draw(&map, &slice, Some(true)).unwrap();
    let texts = |svg: &str| crate::report::figure_read::svg_texts(svg);
    // E* (0.3 .. 4, under two decades): 0.5, 1, 2 labelled; Gamma linear: steps of 2; Gamma
    // log (0.5 .. 8): 0.5, 1, 2, 5. One format per axis: no label in another notation.
    for v in ["0.5", "1", "2"] {
        assert!(
            texts(&linear).iter().any(|t| t == v),
            "linear map: no tick {v}"
        );
    }
    for v in ["2", "4", "6", "8"] {
        assert!(
            texts(&linear).iter().any(|t| t == v),
            "linear Gamma: no tick {v}"
        );
    }
    for v in ["0.5", "1", "2", "5"] {
        assert!(
            texts(&log.svg).iter().any(|t| t == v),
            "log map: no tick {v}"
        );
    }
    assert!(
        !texts(&log.svg)
            .iter()
            .any(|t| t.contains("e-") || t.contains("log scale"))
    );
    // The axis names typeset: Γ, and E with a raised star.
    assert!(
        texts(&log.svg).iter().any(|t| t == "Γ"),
        "{:?}",
        texts(&log.svg)
    );
    assert!(texts(&log.svg).iter().any(|t| t == "E*"));
    assert!(log.svg.contains("font-style=\"italic\">E</tspan>"));
    // On the log axis Gamma = 2 lies halfway between 0.5 and 8 (in pixels).
    let py = |g: f64| {
        log.points
            .iter()
            .find(|p| p.1 == g && p.0 == 1.0)
            .unwrap()
            .3
    };
    assert!((2 * py(2.0) - py(0.5) - py(8.0)).abs() <= 1);
    // The legend is below every point, in a box as wide as the figure at most: full names.
    let legend_y = {
        let k = log
            .svg
            .find(">\nfluid\n</text>")
            .expect("the legend names fluid");
        let tag = &log.svg[log.svg[..k].rfind("<text").unwrap()..k];
        tag.split("y=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .parse::<i32>()
            .unwrap()
    };
    assert!(
        log.points.iter().all(|p| p.3 + 20 < legend_y),
        "legend at y = {legend_y}"
    );
    assert!(log.svg.contains(">\ngas\n</text>"));
    assert_eq!(log.width, MAP_WIDTH);
    // A log axis of non-positive values is refused.
    let (map0, mut zero) = grid_map(true);
    zero.points[0].y = 0.0;
    assert!(draw(&map0, &zero, Some(true)).is_err());
}

/// The fill colours of an SVG's polygons, counted.
fn fills(svg: &str) -> std::collections::BTreeMap<String, usize> {
    let doc = roxmltree::Document::parse(svg).unwrap();
    let mut out = std::collections::BTreeMap::new();
    for n in doc.descendants().filter(|n| n.has_tag_name("polygon")) {
        *out.entry(n.attribute("fill").unwrap_or("").to_string())
            .or_insert(0) += 1;
    }
    out
}

/// The hex form plotters writes of a colour.
fn hex(c: RGBColor) -> String {
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

/// The boundary points of a slice as extraction finds them: the midpoint, in the plane
/// `(log10 x, y)`, of every Delaunay edge whose ends differ in phase.
fn boundaries_of(slice: &mut Slice) {
    let pos: Vec<(f64, f64)> = slice.points.iter().map(|p| (p.x.log10(), p.y)).collect();
    for (i, j) in crate::boundary::delaunay_pairs(&pos).unwrap() {
        let (p, q) = (&slice.points[i], &slice.points[j]);
        if p.phase == q.phase {
            continue;
        }
        let b = crate::boundary::BoundaryPoint {
            pair: "f|g".into(),
            x: (p.x * q.x).sqrt(),
            y: (p.y + q.y) / 2.0,
            between: [i, j],
            x_half: (q.x / p.x).log10().abs() / 2.0,
            y_half: (q.y - p.y).abs() / 2.0,
            x_range: [p.x.min(q.x), p.x.max(q.x)],
            y_range: [p.y.min(q.y), p.y.max(q.y)],
            confidence: 1.0,
            amplitude: None,
            omega: None,
            branch: None,
        };
        slice.boundaries.entry("f|g".into()).or_default().push(b);
    }
}

#[test]
fn each_phase_has_its_region_and_the_boundary_is_a_line_between_them() {
    let (map, mut slice) = grid_map(true);
    boundaries_of(&mut slice);
    let drawn = branches_map(&map, &[&slice], None, None, "t", MapStyle::default()).unwrap();
    // One shaded cell per point: 6 fluid, 3 gas.
    let f = fills(&drawn.svg);
    assert_eq!(
        f.get(&hex(tint(phase_color("f"), REGION_SHADE))),
        Some(&6),
        "{f:?}"
    );
    assert_eq!(
        f.get(&hex(tint(phase_color("g"), REGION_SHADE))),
        Some(&3),
        "{f:?}"
    );
    // The boundary: black 2 px segments on the bisector between E* = 1 and 4 (x = 2 on the log
    // axis), joined end to end into one line from the bottom of the plot to its top.
    let segments = black_segments(&drawn.svg);
    assert_eq!(segments.len(), 3, "{segments:?}");
    let px = |e: f64| drawn.points.iter().find(|p| p.0 == e).unwrap().2 as f64;
    let mid = (px(1.0) + px(4.0)) / 2.0;
    for s in &segments {
        assert!(
            (s.0.0 - mid).abs() <= 1.0 && (s.1.0 - mid).abs() <= 1.0,
            "{s:?}"
        );
    }
    assert_eq!(loose_ends(&segments), 2, "{segments:?}");
    // Its error bars: the straddling edge, 1 .. 4 in E*, with caps.
    assert!(drawn.svg.matches("stroke=\"#464646\"").count() >= 3 * 3);
    // The legend names the boundary and its bars.
    assert!(drawn.svg.contains("phase boundary"));
    assert!(drawn.svg.contains("bars: straddling edge"));
}

/// The black, 2 px wide straight segments of an SVG (the boundary lines), in pixels.
fn black_segments(svg: &str) -> Vec<crate::report::regions::Segment> {
    let doc = roxmltree::Document::parse(svg).unwrap();
    doc.descendants()
        .filter(|n| {
            // In the plot, above the legend.
            n.attribute("points")
                .and_then(|p| p.split([',', ' ']).nth(1)?.parse::<u32>().ok())
                .is_some_and(|y| y < PLOT_HEIGHT)
                && n.has_tag_name("polyline")
                && n.attribute("stroke") == Some("#000000")
                && n.attribute("stroke-width") == Some("2")
        })
        .filter_map(|n| {
            let v: Vec<(f64, f64)> = n
                .attribute("points")?
                .split_whitespace()
                .filter_map(|p| {
                    let (x, y) = p.split_once(',')?;
                    Some((x.parse().ok()?, y.parse().ok()?))
                })
                .collect();
            (v.len() == 2).then(|| (v[0], v[1]))
        })
        .collect()
}

/// The ends of segments that no other segment shares (a line has two; crosses four each).
fn loose_ends(segments: &[crate::report::regions::Segment]) -> usize {
    let ends: Vec<(f64, f64)> = segments.iter().flat_map(|s| [s.0, s.1]).collect();
    let near = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() <= 1.0 && (a.1 - b.1).abs() <= 1.0;
    ends.iter()
        .filter(|&&e| ends.iter().filter(|&&o| near(e, o)).count() == 1)
        .count()
}

#[test]
fn after_refinement_the_boundary_stays_a_line() {
    // A refined map: a 6 x 6 grid and 60 points packed near the boundary E* = 2 / Gamma (a
    // curve), fluid left of it and gas right.
    let mut points = Vec::new();
    let mut add = |e: f64, g: f64| {
        let phase = if e < 2.0 / g.sqrt() { "f" } else { "g" };
        points.push(point(vec![g.into(), e.into()], e, g, phase, true));
    };
    for i in 0..6 {
        for j in 0..6 {
            add(0.3 * 2f64.powi(i), 0.5 + 1.5 * j as f64);
        }
    }
    for k in 0..60 {
        let g = 0.6 + 7.5 * (k as f64 * 0.618).fract();
        let e = 2.0 / g.sqrt() * 2f64.powf(0.4 * ((k as f64 * 0.377).fract() - 0.5));
        add(e, g);
    }
    let mut slice = slice(None, points);
    boundaries_of(&mut slice);
    let n = slice.boundaries["f|g"].len();
    assert!(n > 40, "{n} boundary points");
    let map = PhaseMap {
        x: Some(axis(1, "drive.e_star", "E*", true)),
        y: Some(axis(0, "drive.gamma", "Gamma", false)),
        shaking: true,
        slices: vec![slice.clone()],
    };
    let drawn = branches_map(&map, &[&slice], None, None, "t", MapStyle::default()).unwrap();
    // One segment per boundary point, joined into lines: their loose ends are only where the
    // line leaves the plot (and a few where a straddling edge is not a Voronoi neighbour in
    // pixels), not four per point as crosses have.
    let segments = black_segments(&drawn.svg);
    assert!(
        segments.len() * 10 >= n * 9,
        "{} segments, {n} points",
        segments.len()
    );
    let loose = loose_ends(&segments);
    assert!(
        loose <= 6,
        "{loose} loose ends of {} segments",
        segments.len()
    );
}

#[test]
fn the_guides_are_in_the_legend_and_the_caption_explains_the_floor_of_eq_4_15() {
    let (map, mut slice) = grid_map(true);
    boundaries_of(&mut slice);
    let l = Landmarks {
        energy_unit: 0.2844,
        mass: 1.0,
        gravity: 1.0,
        diameter: 1.0,
        wet: Some((0.0711, 4.0)),
        layers: 3.0,
    };
    let drawn = branches_map(&map, &[&slice], Some(l), None, "t", MapStyle::default()).unwrap();
    let texts = crate::report::figure_read::svg_texts(&drawn.svg);
    for want in ["A = scrit", "A = d", "Eq. 4.15, ΓC (caption)"] {
        assert!(
            texts.iter().any(|t| t == want),
            "no legend entry {want}: {texts:?}"
        );
    }
    let caption = texts.join(" ");
    assert!(
        caption.contains("never falls below 1 \u{2212} 1/M = 0.67"),
        "{caption}"
    );
    assert!(caption.contains("M = 3.00 layers"), "{caption}");
    // The figure as PNG: the fluid region's shade left, the gas region's right.
    let png = crate::report::figure_read::decode_png(
        &crate::report::figure::render(&drawn.svg, crate::report::figure::FigureFormat::Png)
            .unwrap(),
    );
    assert_eq!(png.width, 3 * MAP_WIDTH);
    let at = |e: f64, g: f64| {
        let p = drawn.points.iter().find(|p| p.0 == e && p.1 == g).unwrap();
        // Beside the dot, inside the cell.
        png.at(3 * (p.2 as u32) + 24, 3 * (p.3 as u32) + 24)
    };
    let rgb = |c: RGBColor| [c.0, c.1, c.2, 255];
    assert_eq!(at(0.3, 2.0), rgb(tint(phase_color("f"), REGION_SHADE)));
    assert_eq!(at(4.0, 2.0), rgb(tint(phase_color("g"), REGION_SHADE)));
}

#[test]
fn two_sectors_are_the_left_and_the_right_half() {
    let left = sector(0, 2, 10);
    let right = sector(1, 2, 10);
    // Both start at the centre; the left one spans x <= 0, the right one x >= 0, each from
    // the top (screen y = -10) to the bottom (y = 10) or back.
    assert_eq!((left[0], right[0]), ((0, 0), (0, 0)));
    assert!(left.iter().all(|&(x, _)| x <= 0));
    assert!(right.iter().all(|&(x, _)| x >= 0));
    assert!(left.contains(&(-10, 0)) && right.contains(&(10, 0)));
    assert_eq!((left[1], *left.last().unwrap()), ((0, -10), (0, 10)));
    // One branch: a whole disc, no centre vertex.
    let whole = sector(0, 1, 10);
    assert!(
        whole
            .iter()
            .all(|&(x, y)| (x * x + y * y - 100).abs() <= 20)
    );
}
