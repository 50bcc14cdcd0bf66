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
//! drawn as one map of its branches ([`branches_map`]): a grid point where the branches agree is
//! one dot; a bistable point (their phases differ) is a split disc, one sector per branch in its
//! phase's colour (two branches: left half the first, right half the second), outlined in black
//! and labelled with the phases in branch order (`g/f`). Each branch's boundary points keep
//! their own marker, since the boundaries of the branches are extracted separately.

use super::chart::{Swatch, draw_legend, hand_ticks, sector, shape, wrap};
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
        // Non-negative values (Gamma, a force) keep the axis at or above zero, so that an
        // overlay does not run into negative values no point can have.
        let low = if lo >= 0.0 {
            (lo - pad).max(0.0)
        } else {
            lo - pad
        };
        (low, hi + pad)
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
    /// Whether a branch's label here rests on a fallback (`observe::criterion`).
    pub fallback: bool,
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
    // Position -> index in `out`; `+ 0.0` makes -0.0 and 0.0 one key, as `==` does; NaN
    // never matches.
    let mut at: std::collections::HashMap<(u64, u64), usize> = std::collections::HashMap::new();
    for (b, slice) in slices.iter().enumerate() {
        for p in &slice.points {
            let key = (!p.x.is_nan() && !p.y.is_nan())
                .then(|| ((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits()));
            let k = match key.and_then(|key| at.get(&key).copied()) {
                Some(k) => k,
                None => {
                    if let Some(key) = key {
                        at.insert(key, out.len());
                    }
                    out.push(DrawnPoint {
                        x: p.x,
                        y: p.y,
                        phases: vec![None; slices.len()],
                        trusted: true,
                        label_kept: false,
                        fallback: false,
                    });
                    out.len() - 1
                }
            };
            out[k].phases[b] = Some(p.phase.clone());
            out[k].trusted &= p.trusted;
            out[k].label_kept |= p.label_kept;
            out[k].fallback |= p.decided_by.as_ref().is_some_and(|d| d.fallback);
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

/// How a map is drawn: the scale of its axes where the caller chooses (`None`: the plane's, so
/// `E*` log and `Gamma` linear on a shaking map).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MapStyle {
    pub x_log: Option<bool>,
    pub y_log: Option<bool>,
}

/// A drawn map: the SVG and, for every drawn grid position, its pixel position in the SVG (what
/// an HTML image map links from).
#[derive(Debug, Clone, PartialEq)]
pub struct DrawnMap {
    pub svg: String,
    /// `(x, y, pixel x, pixel y)` of every merged grid position ([`merge_branches`] order).
    pub points: Vec<(f64, f64, i32, i32)>,
}

/// The width of the map's SVG: the plot, then the legend to its right.
pub const MAP_WIDTH: u32 = 1240;
/// The height of the map's SVG.
pub const MAP_HEIGHT: u32 = 640;
/// The width kept right of the plot for the legend.
const LEGEND_WIDTH: u32 = 330;

/// Draws the slices of a phase map that differ only in their start mode (the branches) as one
/// SVG map, bistable points as split discs (module doc), with the axes' scales of `style`;
/// `landmarks` adds the theory lines (shaking sweeps). Also gives the pixel positions of the
/// points.
pub fn branches_map(
    map: &PhaseMap,
    slices: &[&Slice],
    landmarks: Option<Landmarks>,
    chain_model: Option<Vec<(f64, f64)>>,
    title: &str,
    style: MapStyle,
) -> Result<DrawnMap, String> {
    let (Some(xa), Some(ya)) = (&map.x, &map.y) else {
        return Err("a phase diagram needs two numeric axes".to_string());
    };
    if slices.is_empty() {
        return Err("no slice to draw".to_string());
    }
    let x_log = style.x_log.unwrap_or(xa.log);
    let y_log = style.y_log.unwrap_or(ya.log);
    let all = || slices.iter().flat_map(|s| s.points.iter());
    if x_log && !all().all(|p| p.x > 0.0) {
        return Err(format!("{}: a log axis needs positive values", xa.label));
    }
    if y_log && !all().all(|p| p.y > 0.0) {
        return Err(format!("{}: a log axis needs positive values", ya.label));
    }
    let x_range = range_of(all().map(|p| p.x), x_log);
    let y_range = range_of(all().map(|p| p.y), y_log);
    let ticks = |values: Vec<f64>, range, log| super::svg::grid_ticks(&values, range, log, 14);
    let desc = |a: &PlaneAxis, log: bool| match log {
        true => format!("{} (log scale)", a.label),
        false => a.label.clone(),
    };
    let drawing = Drawing {
        title,
        x_desc: desc(xa, x_log),
        y_desc: desc(ya, y_log),
        note: no_boundary_note(slices),
        slices,
        lines: overlay_lines(map, landmarks, chain_model, (x_range, y_range), x_log),
        ticks: (
            ticks(all().map(|p| p.x).collect(), x_range, x_log),
            ticks(all().map(|p| p.y).collect(), y_range, y_log),
        ),
    };
    let mut svg = String::new();
    let points;
    {
        let root = SVGBackend::with_string(&mut svg, (MAP_WIDTH, MAP_HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (x, y) = (x_range.0..x_range.1, y_range.0..y_range.1);
        points = match (x_log, y_log) {
            (true, true) => drawing.draw(&root, x.log_scale(), y.log_scale()),
            (true, false) => drawing.draw(&root, x.log_scale(), y),
            (false, true) => drawing.draw(&root, x, y.log_scale()),
            (false, false) => drawing.draw(&root, x, y),
        }?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(DrawnMap { svg, points })
}

/// The overlay lines of a map (the landmarks of a shaking map, the chain model), clipped to the
/// plot's ranges `(x, y)`.
fn overlay_lines(
    map: &PhaseMap,
    landmarks: Option<Landmarks>,
    chain_model: Option<Vec<(f64, f64)>>,
    (x_range, y_range): ((f64, f64), (f64, f64)),
    x_log: bool,
) -> Vec<Line> {
    let mut lines: Vec<Line> = Vec::new();
    if let (Some(l), true) = (landmarks, map.shaking) {
        let n = 300;
        let xs: Vec<f64> = (0..=n)
            .map(|k| {
                let t = k as f64 / n as f64;
                if x_log {
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
    lines
}

/// What a map draws: title, axis names, the note saying why no boundary is drawn, the
/// branches' points, the overlay lines and the ticks of both axes.
struct Drawing<'a> {
    title: &'a str,
    x_desc: String,
    y_desc: String,
    note: Option<String>,
    slices: &'a [&'a Slice],
    lines: Vec<Line>,
    ticks: (Vec<f64>, Vec<f64>),
}

/// Why a map has no boundary point, in words (`None` when it has one).
pub fn no_boundary_note(slices: &[&Slice]) -> Option<String> {
    if slices
        .iter()
        .any(|s| s.boundaries.values().any(|b| !b.is_empty()))
    {
        return None;
    }
    let points: Vec<&crate::boundary::MapPoint> =
        slices.iter().flat_map(|s| s.points.iter()).collect();
    let trusted: Vec<&&crate::boundary::MapPoint> = points.iter().filter(|p| p.trusted).collect();
    let mut phases: Vec<&str> = trusted.iter().map(|p| p.phase.as_str()).collect();
    phases.sort();
    phases.dedup();
    let untrusted = points.len() - trusted.len();
    Some(if trusted.is_empty() {
        format!(
            "No boundary: none of the {} points is converged (all hollow, their labels may \
             still change); resume the sweep, or --include-unconverged",
            points.len()
        )
    } else if phases.len() == 1 {
        format!(
            "No boundary: every converged point is {}{}",
            phases[0],
            if untrusted > 0 {
                format!(" ({untrusted} unconverged point(s) left out)")
            } else {
                String::new()
            }
        )
    } else {
        "No boundary: too few converged points to join two phases by an edge".to_string()
    })
}

impl Drawing<'_> {
    fn draw<XR, YR>(
        &self,
        root: &DrawingArea<SVGBackend, Shift>,
        x: XR,
        y: YR,
    ) -> Result<Vec<(f64, f64, i32, i32)>, String>
    where
        XR: AsRangedCoord<Value = f64>,
        YR: AsRangedCoord<Value = f64>,
        XR::CoordDescType: ValueFormatter<f64>,
        YR::CoordDescType: ValueFormatter<f64>,
    {
        let err = |e: DrawingAreaErrorKind<_>| e.to_string();
        let mut chart = ChartBuilder::on(root)
            .caption(self.title, ("sans-serif", 20))
            .margin(15)
            .margin_right(15 + LEGEND_WIDTH)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(x, y)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(&self.x_desc)
            .y_desc(&self.y_desc)
            .disable_mesh()
            .x_label_formatter(&|_| String::new())
            .y_label_formatter(&|_| String::new())
            .set_all_tick_mark_size(0)
            .draw()
            .map_err(err)?;
        hand_ticks(root, chart.plotting_area(), &self.ticks.0, &self.ticks.1).map_err(err)?;
        if let Some(note) = &self.note {
            let (xr, yr) = chart.plotting_area().get_pixel_range();
            let words = wrap(note, 60);
            for (k, line) in words.iter().enumerate() {
                root.draw(&Text::new(
                    line.clone(),
                    (xr.start + 12, yr.start + 10 + 18 * k as i32),
                    ("sans-serif", 15).into_font().color(&RGBColor(170, 0, 0)),
                ))
                .map_err(err)?;
            }
        }
        let mut legend: Vec<(String, Swatch)> = Vec::new();
        for (label, color, parts) in &self.lines {
            let color = *color;
            for (k, part) in parts.iter().enumerate() {
                chart
                    .draw_series(LineSeries::new(part.iter().copied(), color.stroke_width(2)))
                    .map_err(err)?;
                if k == 0 {
                    legend.push((label.clone(), Swatch::Line(color)));
                }
            }
        }
        let points = merge_branches(self.slices);
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
                .map_err(err)?;
            legend.push((phase.to_string(), Swatch::Dot(color)));
        }
        if points.iter().any(|p| !p.trusted) {
            let grey = RGBColor(90, 90, 90);
            legend.push(("hollow: label may change".to_string(), Swatch::Ring(grey)));
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
                .map_err(err)?;
            legend.push((
                "white centre: drifting, label kept (~)".to_string(),
                Swatch::Kept,
            ));
        }
        draw_bistable(root, &mut chart, self.slices, &points, radius, &mut legend)?;
        draw_fallbacks(&mut chart, &points, radius, &mut legend)?;
        draw_boundary_points(&mut chart, self.slices, &mut legend)?;
        // The legend right of the plot, level with its top: it hides no point.
        let (xr, yr) = chart.plotting_area().get_pixel_range();
        draw_legend(root, (xr.end + 14, yr.start), &legend).map_err(err)?;
        Ok(points
            .iter()
            .map(|p| {
                let (px, py) = chart.backend_coord(&(p.x, p.y));
                (p.x, p.y, px, py)
            })
            .collect())
    }
}

/// The bistable points (those whose branches disagree): a disc split into one sector per
/// branch, the phases in branch order beside it, and their legend entries.
fn draw_bistable<X, Y>(
    root: &DrawingArea<SVGBackend, Shift>,
    chart: &mut ChartContext<'_, SVGBackend<'_>, Cartesian2d<X, Y>>,
    slices: &[&Slice],
    points: &[DrawnPoint],
    radius: i32,
    legend: &mut Vec<(String, Swatch)>,
) -> Result<(), String>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();
    let bistable: Vec<&DrawnPoint> = points.iter().filter(|p| p.bistable()).collect();
    if bistable.is_empty() {
        return Ok(());
    }
    // One sector per branch in its phase's colour (white where that branch has no point),
    // a black outline, and the phases in branch order beside it.
    let r = radius + 2;
    let n = slices.len();
    for p in &bistable {
        let at = chart.backend_coord(&(p.x, p.y));
        for (k, phase) in p.phases.iter().enumerate() {
            let color = phase.as_deref().map_or(WHITE, phase_color);
            shape(root, at, &sector(k, n, r), color, p.trusted).map_err(err)?;
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
    legend.push((format!("split disc: bistable ({how})"), Swatch::Split(n)));
    legend.push((
        format!("text by the disc: phases {}", short.join("/")),
        Swatch::None,
    ));
    Ok(())
}

/// A square outline around every point whose label rests on a fallback (the temperature for an
/// unmeasured mobility, or `gas_temperature` where no line decided), and its legend entry.
fn draw_fallbacks<X, Y>(
    chart: &mut ChartContext<'_, SVGBackend<'_>, Cartesian2d<X, Y>>,
    points: &[DrawnPoint],
    radius: i32,
    legend: &mut Vec<(String, Swatch)>,
) -> Result<(), String>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let fallback: Vec<&DrawnPoint> = points.iter().filter(|p| p.fallback).collect();
    if fallback.is_empty() {
        return Ok(());
    }
    let r = radius + 3;
    chart
        .draw_series(fallback.iter().map(|p| {
            EmptyElement::at((p.x, p.y)) + Rectangle::new([(-r, -r), (r, r)], BLACK.stroke_width(1))
        }))
        .map_err(|e| e.to_string())?;
    legend.push((
        "square: decided by a fallback (T_g/E_cb)".to_string(),
        Swatch::Square(BLACK),
    ));
    Ok(())
}

/// The boundary points of each branch, with the uncertainty bars of their straddling edges,
/// and their legend entries.
fn draw_boundary_points<X, Y>(
    chart: &mut ChartContext<'_, SVGBackend<'_>, Cartesian2d<X, Y>>,
    slices: &[&Slice],
    legend: &mut Vec<(String, Swatch)>,
) -> Result<(), String>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();
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
            .map_err(err)?;
        legend.push((
            "uncertainty (straddling edge)".to_string(),
            Swatch::Line(grey),
        ));
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
            .map_err(err)?;
        legend.push((label, Swatch::Cross(color)));
    }
    Ok(())
}

#[cfg(test)]
#[path = "plot_phase_tests.rs"]
mod tests;
