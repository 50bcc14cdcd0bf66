//! The phase diagram as SVG (plotters): map points coloured by phase, boundary points, and for
//! shaking sweeps the landmark lines of docs/model.md 4.1 and 8 drawn over, on `E*` (log axis)
//! against `Gamma`:
//! - `A = s_crit`: `Gamma = 2 E* E_cb / (m g s_crit)` (wet scenes),
//! - `A = d`:      `Gamma = 2 E* E_cb / (m g d)` (with `m g d` in place of `E_cb` for `E_d*`),
//! - Eq. 4.15:     `Gamma_C = 1 + F_B (1 - E*) / (M m g)`, never below `1 - 1/M`, with
//!   `F_B = E_cb / s_crit` and `M` the number of layers, `N d / L_x` in 2D and
//!   `N d^2 / (L_x L_y)` in 3D (wet scenes).
//!
//! On shear sweeps whose plane has the `F_max` axis (`drive.f_max`), the chain model of
//! docs/model.md 8 (Eq. 7.9) is drawn: the solid is stable while `F_max L_x / (F_B d) <= 0.9229`, so
//! the line `F_max = 0.9229 F_B d / L_x` (`F_B = E_cb / s_crit`) evaluated on each point's own
//! scene (the other axis may change `L_x`, `E_cb`, `s_crit` or anything else).
//!
//! A sweep with an `initial.start` axis (the hot and the cold branch of an elastic diagram) is
//! drawn as one map of its branches ([`branches_svg`]): a grid point where the branches agree is
//! one dot; a bistable point (their phases differ) is a split disc, one sector per branch in its
//! phase's colour (two branches: left half the first, right half the second), outlined in black
//! and labelled with the phases in branch order (`g/f`). Each branch's boundary points keep
//! their own marker, since the boundaries of the branches are extracted separately.

use crate::boundary::{PhaseMap, PlaneAxis, Slice};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use wetgran_core::scene::Scene;

/// Colour of a phase label (unknown labels grey).
pub fn phase_color(phase: &str) -> RGBColor {
    match phase {
        "s" => RGBColor(31, 119, 180),
        "f" => RGBColor(44, 160, 44),
        "g" => RGBColor(214, 39, 40),
        "sfc" => RGBColor(148, 103, 189),
        "sgc" => RGBColor(255, 127, 14),
        "fgc" => RGBColor(140, 86, 75),
        _ => RGBColor(127, 127, 127),
    }
}

/// The theory lines of a shaking sweep, from its scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Landmarks {
    /// Energy unit of the `E*` axis: `E_cb` (wet) or `m g d` (dry).
    pub energy_unit: f64,
    pub mass: f64,
    pub gravity: f64,
    pub diameter: f64,
    /// `s_crit` and `F_B = E_cb / s_crit` of a wet scene.
    pub wet: Option<(f64, f64)>,
    /// Number of layers `M`.
    pub layers: f64,
}

impl Landmarks {
    /// Landmarks of a scene (`None` without gravity).
    pub fn of(scene: &Scene) -> Option<Landmarks> {
        if scene.gravity <= 0.0 {
            return None;
        }
        let m = scene.particles.mass;
        let g = scene.gravity;
        let d = scene.particles.diameter;
        let wet = scene.is_wet() && scene.e_cb() > 0.0;
        let size = &scene.container.size;
        let lateral: f64 = size[..size.len() - 1].iter().product();
        let layers = scene.particles.count as f64 * d.powi(scene.dimension as i32 - 1) / lateral;
        Some(Landmarks {
            energy_unit: if wet { scene.e_cb() } else { m * g * d },
            mass: m,
            gravity: g,
            diameter: d,
            wet: wet.then(|| (scene.s_crit(), scene.e_cb() / scene.s_crit())),
            layers,
        })
    }

    /// `Gamma` on the line where the drive amplitude equals `a` (docs/model.md 4.1).
    pub fn gamma_at_amplitude(&self, e_star: f64, a: f64) -> f64 {
        2.0 * e_star * self.energy_unit / (self.mass * self.gravity * a)
    }

    /// `Gamma_C` of Eq. 4.15, floored at `1 - 1/M` (wet scenes).
    pub fn gamma_c(&self, e_star: f64) -> Option<f64> {
        let (_, f_b) = self.wet?;
        let m = self.layers;
        let g = 1.0 + f_b * (1.0 - e_star) / (m * self.mass * self.gravity);
        Some(g.max(1.0 - 1.0 / m))
    }
}

/// The constant of the chain model, Eq. 7.9: solid while `F_max L_x / (F_B d) <= 0.9229`.
pub const CHAIN_MODEL_CONSTANT: f64 = 0.9229;

/// The chain model's critical force `F_max = 0.9229 F_B d / L_x` (docs/model.md 8, Eq. 7.9) with
/// `F_B = E_cb / s_crit`; `None` for dry scenes.
pub fn chain_model_f_max(scene: &Scene) -> Option<f64> {
    if !scene.is_wet() || scene.e_cb() <= 0.0 {
        return None;
    }
    let f_b = scene.e_cb() / scene.s_crit();
    Some(CHAIN_MODEL_CONSTANT * f_b * scene.particles.diameter / scene.container.size[0])
}

/// The chain-model line in the plane of a shear sweep: one vertex per point of the slice,
/// `(F_c, y)` when `F_max` is the x axis or `(x, F_c)` when it is the y axis, with `F_c` from
/// the point's scene (`scene_of` maps a point's coordinates to its scene); `None` if neither
/// plane axis is `drive.f_max` or the scenes are dry.
pub fn chain_model_line(
    map: &PhaseMap,
    slice: &Slice,
    scene_of: impl Fn(&[serde_json::Value]) -> Option<Scene>,
) -> Option<Vec<(f64, f64)>> {
    let (xa, ya) = (map.x.as_ref()?, map.y.as_ref()?);
    let f_on_x = xa.key == "drive.f_max";
    if !f_on_x && ya.key != "drive.f_max" {
        return None;
    }
    let mut line: Vec<(f64, f64)> = Vec::new();
    for p in &slice.points {
        let f_c = chain_model_f_max(&scene_of(&p.coords)?)?;
        line.push(if f_on_x { (f_c, p.y) } else { (p.x, f_c) });
    }
    let along = |q: &(f64, f64)| if f_on_x { q.1 } else { q.0 };
    line.sort_by(|a, b| along(a).total_cmp(&along(b)));
    line.dedup_by(|a, b| along(a) == along(b));
    (!line.is_empty()).then_some(line)
}

/// A `(label, points)` line, already clipped to the y range (split where it leaves it).
type Line = (String, RGBColor, Vec<Vec<(f64, f64)>>);

fn clipped(xs: &[f64], f: impl Fn(f64) -> Option<f64>, y0: f64, y1: f64) -> Vec<Vec<(f64, f64)>> {
    let mut parts = vec![Vec::new()];
    for &x in xs {
        match f(x) {
            Some(y) if y >= y0 && y <= y1 && y.is_finite() => {
                parts.last_mut().expect("non-empty").push((x, y))
            }
            _ => {
                if !parts.last().expect("non-empty").is_empty() {
                    parts.push(Vec::new());
                }
            }
        }
    }
    parts.retain(|p| p.len() > 1);
    parts
}

fn range_of(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        let (a, b) = (lo.log10(), hi.log10());
        let pad = ((b - a) * 0.06).max(0.1);
        (10f64.powf(a - pad), 10f64.powf(b + pad))
    } else {
        let pad = ((hi - lo) * 0.06).max(if hi == 0.0 { 0.1 } else { hi.abs() * 0.05 });
        (lo - pad, hi + pad)
    }
}

/// A grid position of the drawn map with the phase of each branch there.
#[derive(Debug, Clone, PartialEq)]
pub struct DrawnPoint {
    pub x: f64,
    pub y: f64,
    /// One entry per branch (slice), in branch order; `None` where that branch has no point.
    pub phases: Vec<Option<String>>,
    /// Whether every branch's label here is trusted (stationary, or kept by its trend).
    pub trusted: bool,
    /// Whether a branch's point here is not stationary but on a trend that keeps its label.
    pub label_kept: bool,
}

impl DrawnPoint {
    /// The branches with a point here disagree on the phase.
    pub fn bistable(&self) -> bool {
        let mut seen = self.phases.iter().flatten();
        let first = seen.next();
        seen.any(|p| Some(p) != first)
    }

    /// The phase of the first branch with a point here.
    pub fn phase(&self) -> &str {
        self.phases
            .iter()
            .flatten()
            .next()
            .map_or("", |p| p.as_str())
    }
}

/// The points of the branches merged by position (first appearance order: the first branch's
/// points, then positions only later branches have).
pub fn merge_branches(slices: &[&Slice]) -> Vec<DrawnPoint> {
    let mut out: Vec<DrawnPoint> = Vec::new();
    // Position -> index in `out` (a search of `out` per point made 10^5 points cost 10^10
    // comparisons); `+ 0.0` makes -0.0 and 0.0 one key, as `==` does; NaN never matches.
    let mut at: std::collections::HashMap<(u64, u64), usize> = std::collections::HashMap::new();
    for (b, slice) in slices.iter().enumerate() {
        for p in &slice.points {
            let key = ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits());
            let found = if p.x.is_nan() || p.y.is_nan() {
                None
            } else {
                at.get(&key).copied()
            };
            let k = match found {
                Some(k) => k,
                None => {
                    if !(p.x.is_nan() || p.y.is_nan()) {
                        at.insert(key, out.len());
                    }
                    out.push(DrawnPoint {
                        x: p.x,
                        y: p.y,
                        phases: vec![None; slices.len()],
                        trusted: true,
                        label_kept: false,
                    });
                    out.len() - 1
                }
            };
            out[k].phases[b] = Some(p.phase.clone());
            out[k].trusted &= p.trusted;
            out[k].label_kept |= p.label_kept;
        }
    }
    out
}

/// The name of branch `k` in the legend: its start mode in words, or `branch k + 1`.
fn branch_name(slices: &[&Slice], k: usize) -> String {
    slices[k].branch.as_ref().map_or_else(
        || format!("branch {}", k + 1),
        |b| crate::boundary::branch_words(b),
    )
}

/// Draws one slice of a phase map as SVG. `landmarks` adds the theory lines (shaking sweeps).
pub fn phase_svg(
    map: &PhaseMap,
    slice: &Slice,
    landmarks: Option<Landmarks>,
    chain_model: Option<Vec<(f64, f64)>>,
    title: &str,
) -> Result<String, String> {
    branches_svg(map, &[slice], landmarks, chain_model, title)
}

/// Draws the slices of a phase map that differ only in their start mode (the branches) as one
/// SVG map: bistable points as split discs (module doc). One slice draws as [`phase_svg`].
pub fn branches_svg(
    map: &PhaseMap,
    slices: &[&Slice],
    landmarks: Option<Landmarks>,
    chain_model: Option<Vec<(f64, f64)>>,
    title: &str,
) -> Result<String, String> {
    let (Some(xa), Some(ya)) = (&map.x, &map.y) else {
        return Err("a phase diagram needs two numeric axes".to_string());
    };
    if slices.is_empty() {
        return Err("no slice to draw".to_string());
    }
    let all = || slices.iter().flat_map(|s| s.points.iter());
    let x_range = range_of(all().map(|p| p.x), xa.log);
    let y_range = range_of(all().map(|p| p.y), ya.log);
    // Headroom above the points for the legend (upper left): 0.3 of the points' span, more when
    // the legend has more rows than that holds (about 15 px a row in a plot area of about
    // 520 px), as a map of several branches has (bistable entry, one boundary entry each).
    let merged = merge_branches(slices);
    let mut phases: Vec<&str> = merged
        .iter()
        .flat_map(|p| p.phases.iter().flatten().map(String::as_str))
        .collect();
    phases.sort();
    phases.dedup();
    let rows = phases.len()
        + 3 // the landmark lines (at most)
        + usize::from(chain_model.is_some())
        + usize::from(merged.iter().any(|p| !p.trusted))
        + usize::from(merged.iter().any(|p| p.trusted && p.label_kept))
        + usize::from(merged.iter().any(DrawnPoint::bistable))
        + 1 // uncertainty bars
        + slices.len();
    let above = ((rows * 15 + 30) as f64 / 520.0).clamp(0.23, 0.6);
    let headroom = above / (1.0 - above);
    let y_range = if ya.log {
        (
            y_range.0,
            y_range.1 * (y_range.1 / y_range.0).powf(headroom),
        )
    } else {
        (y_range.0, y_range.1 + headroom * (y_range.1 - y_range.0))
    };
    let mut lines: Vec<Line> = Vec::new();
    if let (Some(l), true) = (landmarks, map.shaking) {
        let n = 300;
        let xs: Vec<f64> = (0..=n)
            .map(|k| {
                let t = k as f64 / n as f64;
                if xa.log {
                    10f64.powf(x_range.0.log10() + t * (x_range.1.log10() - x_range.0.log10()))
                } else {
                    x_range.0 + t * (x_range.1 - x_range.0)
                }
            })
            .collect();
        let (y0, y1) = y_range;
        if let Some((s_crit, _)) = l.wet {
            lines.push((
                "A = s_crit".to_string(),
                RGBColor(0, 0, 0),
                clipped(&xs, |e| Some(l.gamma_at_amplitude(e, s_crit)), y0, y1),
            ));
        }
        lines.push((
            "A = d".to_string(),
            RGBColor(90, 90, 90),
            clipped(&xs, |e| Some(l.gamma_at_amplitude(e, l.diameter)), y0, y1),
        ));
        if l.wet.is_some() {
            lines.push((
                format!("Eq. 4.15 (M = {:.2})", l.layers),
                RGBColor(23, 190, 207),
                clipped(&xs, |e| l.gamma_c(e), y0, y1),
            ));
        }
    }
    if let Some(line) = chain_model {
        // A single value (one point along the other axis) is drawn as a short bar across.
        let line = if line.len() == 1 {
            let (x, y) = line[0];
            if map.x.as_ref().is_some_and(|a| a.key == "drive.f_max") {
                vec![(x, y_range.0), (x, y_range.1)]
            } else {
                vec![(x_range.0, y), (x_range.1, y)]
            }
        } else {
            line
        };
        lines.push((
            format!("chain model, Eq. 7.9 (F_max L_x / (F_B d) = {CHAIN_MODEL_CONSTANT})"),
            RGBColor(214, 39, 40),
            vec![line],
        ));
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 640)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let x_desc = if xa.log {
            format!("{} (log scale)", xa.label)
        } else {
            xa.label.clone()
        };
        let y_desc = if ya.log {
            format!("{} (log scale)", ya.label)
        } else {
            ya.label.clone()
        };
        let x = x_range.0..x_range.1;
        let y = y_range.0..y_range.1;
        match (xa.log, ya.log) {
            (true, true) => draw(
                &root,
                x.log_scale(),
                y.log_scale(),
                slices,
                &lines,
                title,
                &x_desc,
                &y_desc,
            ),
            (true, false) => draw(
                &root,
                x.log_scale(),
                y,
                slices,
                &lines,
                title,
                &x_desc,
                &y_desc,
            ),
            (false, true) => draw(
                &root,
                x,
                y.log_scale(),
                slices,
                &lines,
                title,
                &x_desc,
                &y_desc,
            ),
            (false, false) => draw(&root, x, y, slices, &lines, title, &x_desc, &y_desc),
        }?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

fn draw<XR, YR>(
    root: &DrawingArea<SVGBackend, Shift>,
    x: XR,
    y: YR,
    slices: &[&Slice],
    lines: &[Line],
    title: &str,
    x_desc: &str,
    y_desc: &str,
) -> Result<(), String>
where
    XR: AsRangedCoord<Value = f64>,
    YR: AsRangedCoord<Value = f64>,
    XR::CoordDescType: ValueFormatter<f64>,
    YR::CoordDescType: ValueFormatter<f64>,
{
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(x, y)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .light_line_style(WHITE)
        .draw()
        .map_err(err)?;
    for (label, color, parts) in lines {
        let color = *color;
        for (k, part) in parts.iter().enumerate() {
            let s = chart
                .draw_series(LineSeries::new(part.iter().copied(), color.stroke_width(2)))
                .map_err(err)?;
            if k == 0 {
                s.label(label.as_str()).legend(move |(px, py)| {
                    PathElement::new(vec![(px, py), (px + 18, py)], color.stroke_width(2))
                });
            }
        }
    }
    let points = merge_branches(slices);
    // Smaller dots where refinement packed points densely.
    let radius = if points.len() > 100 { 3 } else { 6 };
    let mut phases: Vec<&str> = points
        .iter()
        .flat_map(|p| p.phases.iter().flatten().map(String::as_str))
        .collect();
    phases.sort();
    phases.dedup();
    for phase in phases {
        let color = phase_color(phase);
        chart
            .draw_series(
                points
                    .iter()
                    .filter(|p| !p.bistable() && p.phase() == phase)
                    .map(|p| {
                        // Untrusted points hollow: their label may still change.
                        let style = if p.trusted {
                            color.filled()
                        } else {
                            color.stroke_width(2)
                        };
                        Circle::new((p.x, p.y), radius, style)
                    }),
            )
            .map_err(err)?
            .label(phase)
            .legend(move |(px, py)| Circle::new((px + 9, py), 5, color.filled()));
    }
    if points.iter().any(|p| !p.trusted) {
        let grey = RGBColor(90, 90, 90);
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(err)?
            .label("hollow: label may change")
            .legend(move |(px, py)| Circle::new((px + 9, py), 5, grey.stroke_width(2)));
    }
    // Not stationary, label kept by the trend (a heating gas, a cooling solid, a coarsening
    // coexistence): a white centre in the filled disc.
    let kept: Vec<&DrawnPoint> = points
        .iter()
        .filter(|p| p.trusted && p.label_kept && !p.bistable())
        .collect();
    if !kept.is_empty() {
        let centre = (radius / 2).max(1);
        chart
            .draw_series(
                kept.iter()
                    .map(|p| Circle::new((p.x, p.y), centre, WHITE.filled())),
            )
            .map_err(err)?
            .label("white centre: drifting, label kept (~)")
            .legend(move |(px, py)| {
                EmptyElement::at((px + 9, py))
                    + Circle::new((0, 0), 5, RGBColor(90, 90, 90).filled())
                    + Circle::new((0, 0), 2, WHITE.filled())
            });
    }
    let bistable: Vec<&DrawnPoint> = points.iter().filter(|p| p.bistable()).collect();
    if !bistable.is_empty() {
        // One sector per branch in its phase's colour (white where that branch has no point),
        // a black outline, and the phases in branch order beside it.
        let r = radius + 2;
        let n = slices.len();
        for p in &bistable {
            for (k, phase) in p.phases.iter().enumerate() {
                let color = phase.as_deref().map_or(WHITE, phase_color);
                let wedge = sector(k, n, r);
                let style = if p.trusted {
                    color.filled()
                } else {
                    color.stroke_width(2)
                };
                if p.trusted {
                    chart
                        .plotting_area()
                        .draw(&(EmptyElement::at((p.x, p.y)) + Polygon::new(wedge, style)))
                        .map_err(err)?;
                } else {
                    let mut closed = wedge;
                    closed.push(closed[0]);
                    chart
                        .plotting_area()
                        .draw(&(EmptyElement::at((p.x, p.y)) + PathElement::new(closed, style)))
                        .map_err(err)?;
                }
            }
            let text: Vec<&str> = p
                .phases
                .iter()
                .map(|q| q.as_deref().unwrap_or("-"))
                .collect();
            chart
                .plotting_area()
                .draw(
                    &(EmptyElement::at((p.x, p.y))
                        + Circle::new((0, 0), r, BLACK.stroke_width(1))
                        + Text::new(text.join("/"), (r + 2, -r - 10), ("sans-serif", 12))),
                )
                .map_err(err)?;
        }
        let names: Vec<String> = (0..n).map(|k| branch_name(slices, k)).collect();
        // The branches' short names for the text's order: `hot/cold`.
        let short: Vec<String> = (0..n)
            .map(|k| {
                slices[k]
                    .branch
                    .clone()
                    .unwrap_or_else(|| (k + 1).to_string())
            })
            .collect();
        let how = if n == 2 {
            format!("left {}, right {}", names[0], names[1])
        } else {
            format!("anticlockwise from the top: {}", names.join(", "))
        };
        let greys = [RGBColor(60, 60, 60), RGBColor(190, 190, 190)];
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(err)?
            .label(format!(
                "split disc: bistable ({how}; text: phases {})",
                short.join("/")
            ))
            .legend(move |(px, py)| {
                let centre = |v: Vec<(i32, i32)>| -> Vec<(i32, i32)> {
                    v.into_iter().map(|(a, b)| (a + px + 9, b + py)).collect()
                };
                EmptyElement::at((0, 0))
                    + Polygon::new(centre(sector(0, n, 6)), greys[0].filled())
                    + Polygon::new(centre(sector(1, n, 6)), greys[1].filled())
            });
    }
    // Uncertainty of each boundary point: the straddling edge's extent along each axis.
    let bars: Vec<Vec<(f64, f64)>> = slices
        .iter()
        .flat_map(|s| s.boundaries.values().flatten())
        .flat_map(|b| {
            [
                vec![(b.x_range[0], b.y), (b.x_range[1], b.y)],
                vec![(b.x, b.y_range[0]), (b.x, b.y_range[1])],
            ]
        })
        .collect();
    if !bars.is_empty() {
        let grey = RGBColor(110, 110, 110);
        chart
            .draw_series(
                bars.into_iter()
                    .map(|bar| PathElement::new(bar, grey.stroke_width(1))),
            )
            .map_err(err)?
            .label("uncertainty (straddling edge)")
            .legend(move |(px, py)| PathElement::new(vec![(px, py), (px + 18, py)], grey));
    }
    // Each branch's boundary points with their own colour (the first black).
    const BRANCH_COLOURS: [RGBColor; 3] = [
        RGBColor(0, 0, 0),
        RGBColor(170, 0, 170),
        RGBColor(0, 110, 110),
    ];
    for (k, slice) in slices.iter().enumerate() {
        let boundary: Vec<(f64, f64)> = slice
            .boundaries
            .values()
            .flatten()
            .map(|b| (b.x, b.y))
            .collect();
        if boundary.is_empty() {
            continue;
        }
        let color = BRANCH_COLOURS[k % BRANCH_COLOURS.len()];
        let label = if slices.len() > 1 {
            format!("boundary points, {}", branch_name(slices, k))
        } else {
            "boundary points".to_string()
        };
        chart
            .draw_series(
                boundary
                    .iter()
                    .map(|&(bx, by)| Cross::new((bx, by), 4, color.stroke_width(2))),
            )
            .map_err(err)?
            .label(label)
            .legend(move |(px, py)| Cross::new((px + 9, py), 4, color.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.85))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// Sector `k` of `n` of a disc of radius `r` in pixel offsets from its centre: two sectors are
/// the left and the right half; more start at the top and go anticlockwise.
fn sector(k: usize, n: usize, r: i32) -> Vec<(i32, i32)> {
    let n = n.max(1);
    let step = std::f64::consts::TAU / n as f64;
    let a0 = std::f64::consts::FRAC_PI_2 + k as f64 * step;
    let mut v = if n > 1 { vec![(0, 0)] } else { Vec::new() };
    let arc = 24 / n.min(24);
    for i in 0..=arc {
        let a = a0 + step * i as f64 / arc as f64;
        // Screen y grows downwards.
        v.push((
            (r as f64 * a.cos()).round() as i32,
            (-r as f64 * a.sin()).round() as i32,
        ));
    }
    v
}

/// The plane axis labels, for callers that describe a plot.
pub fn axis_names(map: &PhaseMap) -> Option<(&PlaneAxis, &PlaneAxis)> {
    Some((map.x.as_ref()?, map.y.as_ref()?))
}

#[cfg(test)]
mod tests {
    use super::*;

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
        use crate::boundary::MapPoint;
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
        let point = |l_x: f64, f: f64| MapPoint {
            coords: vec![serde_json::json!(l_x), serde_json::json!(f)],
            x: l_x,
            y: f,
            phase: "s".into(),
            votes: vec![Some("s".into())],
            tie: false,
            trusted: true,
            label_kept: false,
            amplitude: None,
            omega: None,
        };
        let axis = |index: usize, key: &str| PlaneAxis {
            index,
            key: key.into(),
            label: key.into(),
            log: false,
        };
        let slice = Slice {
            fixed: Vec::new(),
            branch: None,
            points: vec![
                point(24.0, 0.1),
                point(12.0, 0.1),
                point(12.0, 0.5),
                point(24.0, 0.5),
            ],
            boundaries: Default::default(),
        };
        let map = PhaseMap {
            x: Some(axis(0, "box.size[0]")),
            y: Some(axis(1, "drive.f_max")),
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
            y: Some(axis(1, "contact.restitution")),
            ..map.clone()
        };
        assert!(chain_model_line(&other, &slice, scene_of).is_none());
        // The plot draws it with its legend.
        let svg = phase_svg(&map, &slice, None, Some(line), "t").unwrap();
        assert!(svg.contains("chain model, Eq. 7.9"));
    }

    #[test]
    fn branches_merge_by_position_and_only_disagreeing_points_are_bistable() {
        use crate::boundary::MapPoint;
        let point = |x: f64, phase: &str, trusted: bool| MapPoint {
            coords: vec![serde_json::json!(x)],
            x,
            y: 1.0,
            phase: phase.into(),
            votes: vec![Some(phase.into())],
            tie: false,
            trusted,
            label_kept: false,
            amplitude: None,
            omega: None,
        };
        let slice = |branch: &str, points: Vec<MapPoint>| Slice {
            fixed: Vec::new(),
            branch: Some(branch.into()),
            points,
            boundaries: Default::default(),
        };
        // Hot: f, g, g at x = 1, 2, 3; cold: f, f at x = 1, 2 (unconverged at 2), and x = 4.
        let hot = slice(
            "hot",
            vec![
                point(1.0, "f", true),
                point(2.0, "g", true),
                point(3.0, "g", true),
            ],
        );
        let cold = slice(
            "cold",
            vec![
                point(1.0, "f", true),
                point(2.0, "f", false),
                point(4.0, "s", true),
            ],
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
}
