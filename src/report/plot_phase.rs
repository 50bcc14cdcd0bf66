//! The phase diagram as SVG (plotters), a figure for a paper: each phase's **region** shaded (the
//! Voronoi cell of every sampled point, in the axes' own scales: `report::regions`), the sampled
//! points as dots in their phase's colour, the **boundaries** as lines (the interfaces between
//! cells of different phase, each through the boundary point halfway between the two samples)
//! with every boundary point's uncertainty as an error bar with caps (the straddling edge), and
//! for shaking sweeps the guides of docs/model.md 4.1 and 8 dashed, on `E*` (log axis, decade
//! ticks) against `Gamma`:
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
//! Axis names and legend are typeset (`report::typeset`: Γ, E*, ...), phases named in full
//! (`solid`, `fluid-gas coexistence`); the legend is a box of one or two columns below the plot,
//! and a caption under it gives Eq. 4.15 with its floor and the number of layers `M`.
//!
//! A sweep with an `initial.start` axis (the hot and the cold branch of an elastic diagram) is
//! drawn as one map of its branches ([`branches_map`]): a grid point where the branches agree is
//! one dot; a bistable point (their phases differ) is a split disc, one sector per branch in its
//! phase's colour (two branches: left half the first, right half the second), outlined in black
//! and labelled with the phases in branch order (`g/f`). Each branch's boundary points keep
//! their own marker, since the boundaries of the branches are extracted separately.

use super::chart::{
    AXIS_FONT, LEGEND_FONT, LEGEND_ROW, Swatch, draw_legend, font, hand_ticks, legend_size, px,
    sector, shape, wrap,
};
use super::typeset::{marked, typeset_svg};
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

/// The name of a phase label in a legend: `s` solid, `f` fluid, `g` gas and the coexistences in
/// words (any other label as it is).
pub fn phase_name(phase: &str) -> String {
    match phase {
        "s" => "solid",
        "f" => "fluid",
        "g" => "gas",
        "sfc" => "solid-fluid coexistence",
        "sgc" => "solid-gas coexistence",
        "fgc" => "fluid-gas coexistence",
        other => other,
    }
    .to_string()
}

/// `colour` mixed with white: `share` of the colour (the shade of a region).
fn tint(colour: RGBColor, share: f64) -> RGBColor {
    let mix = |c: u8| (255.0 - share * (255.0 - c as f64)).round() as u8;
    RGBColor(mix(colour.0), mix(colour.1), mix(colour.2))
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
    /// The size of the SVG in pixels (its height grows with the legend).
    pub width: u32,
    pub height: u32,
    /// `(x, y, pixel x, pixel y)` of every merged grid position ([`merge_branches`] order).
    pub points: Vec<(f64, f64, i32, i32)>,
}

/// The width of the map's SVG (the legend goes below the plot): 480 px, so its text stays
/// readable at a column width of 8.5 cm (`chart::TICK_FONT`).
pub const MAP_WIDTH: u32 = 480;
/// The height of the map's plot, title and axes (the legend and caption come below).
const PLOT_HEIGHT: u32 = 400;

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
    let drawing = Drawing {
        title,
        x_desc: marked(&xa.label),
        y_desc: marked(&ya.label),
        note: no_boundary_note(slices),
        slices,
        axes: (xa, ya),
        ranges: (x_range, y_range),
        lines: overlay_lines(map, landmarks, chain_model, (x_range, y_range), x_log),
        caption: landmarks
            .filter(|l| map.shaking && l.wet.is_some())
            .map(|l| {
                format!(
                    "Eq. 4.15: Gamma_C = 1 + F_B (1 \u{2212} E*) / (M m g), F_B = E_cb / s_crit, \
                     with M = {:.2} layers of grains; it never falls below 1 \u{2212} 1/M = {:.2} \
                     (its flat part at large E*). Shades: the phases' regions (the cells of the \
                     sampled points), paler where the label may change.",
                    l.layers,
                    1.0 - 1.0 / l.layers
                )
            }),
        ticks: (
            super::ticks::axis_ticks(x_range, x_log),
            super::ticks::axis_ticks(y_range, y_log),
        ),
    };
    let legend = drawing.legend();
    let legend_h = legend_size(&legend, MAP_WIDTH as i32 - 20).1;
    let caption_lines = drawing.caption.as_ref().map_or(0, |c| wrap(c, 74).len()) as i32;
    let height = PLOT_HEIGHT + (legend_h + 10 + caption_lines * LEGEND_ROW + 6) as u32;
    let mut svg = String::new();
    let points;
    {
        let root = SVGBackend::with_string(&mut svg, (MAP_WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (x, y) = (x_range.0..x_range.1, y_range.0..y_range.1);
        points = match (x_log, y_log) {
            (true, true) => drawing.draw(&root, x.log_scale(), y.log_scale()),
            (true, false) => drawing.draw(&root, x.log_scale(), y),
            (false, true) => drawing.draw(&root, x, y.log_scale()),
            (false, false) => drawing.draw(&root, x, y),
        }?;
        drawing
            .draw_legend(&root, &legend)
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(DrawnMap {
        svg: typeset_svg(&svg),
        width: MAP_WIDTH,
        height,
        points,
    })
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
                RGBColor(60, 60, 170),
                clipped(&xs, |e| Some(l.gamma_at_amplitude(e, s_crit)), y0, y1),
            ));
        }
        lines.push((
            "A = d".to_string(),
            RGBColor(110, 110, 110),
            clipped(&xs, |e| Some(l.gamma_at_amplitude(e, l.diameter)), y0, y1),
        ));
        if l.wet.is_some() {
            lines.push((
                "Eq. 4.15, Gamma_C (caption)".to_string(),
                RGBColor(0, 150, 170),
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
            format!("chain model, Eq. 7.9: F_max L_x / (F_B d) = {CHAIN_MODEL_CONSTANT}"),
            RGBColor(214, 39, 40),
            vec![line],
        ));
    }
    lines
}

/// What a map draws: title, axis names (marked for typesetting), the note saying why no
/// boundary is drawn, the branches' points, the overlay lines, the caption under the legend and
/// the ticks of both axes.
struct Drawing<'a> {
    title: &'a str,
    x_desc: String,
    y_desc: String,
    note: Option<String>,
    slices: &'a [&'a Slice],
    /// The plane's axes (the tessellation is in their scales, as the boundaries' extraction)
    /// and the plot's ranges on them.
    axes: (&'a PlaneAxis, &'a PlaneAxis),
    ranges: ((f64, f64), (f64, f64)),
    lines: Vec<Line>,
    caption: Option<String>,
    ticks: (Vec<super::ticks::Tick>, Vec<super::ticks::Tick>),
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

/// The colours of each branch's boundary lines (the first black).
const BRANCH_COLOURS: [RGBColor; 3] = [
    RGBColor(0, 0, 0),
    RGBColor(170, 0, 170),
    RGBColor(0, 110, 110),
];

/// The share of a phase's colour in its region's shade: trusted points, and points whose label
/// may still change (paler).
const REGION_SHADE: f64 = 0.3;
const UNTRUSTED_SHADE: f64 = 0.12;

/// The shade of a bistable point's region.
const BISTABLE_SHADE: RGBColor = RGBColor(215, 215, 215);

impl Drawing<'_> {
    /// The legend's entries, in the order drawn: phases (region and dot), the marks of trust,
    /// bistable and fallback points, boundaries and their uncertainty, the guides.
    fn legend(&self) -> Vec<(String, Swatch)> {
        let points = merge_branches(self.slices);
        let mut legend: Vec<(String, Swatch)> = Vec::new();
        let mut phases: Vec<&str> = points
            .iter()
            .flat_map(|p| p.phases.iter().flatten().map(String::as_str))
            .collect();
        phases.sort();
        phases.dedup();
        for phase in phases {
            let c = phase_color(phase);
            legend.push((phase_name(phase), Swatch::Region(tint(c, REGION_SHADE), c)));
        }
        if points.iter().any(|p| !p.trusted) {
            legend.push((
                "hollow: label may change".to_string(),
                Swatch::Ring(RGBColor(90, 90, 90)),
            ));
        }
        if points
            .iter()
            .any(|p| p.trusted && p.label_kept && !p.bistable())
        {
            legend.push(("white centre: label kept".to_string(), Swatch::Kept));
        }
        let n = self.slices.len();
        if points.iter().any(DrawnPoint::bistable) {
            let names: Vec<String> = (0..n).map(|k| branch_name(self.slices, k)).collect();
            let how = if n == 2 {
                format!("left {}, right {}", names[0], names[1])
            } else {
                format!("anticlockwise from the top: {}", names.join(", "))
            };
            legend.push((format!("split disc: bistable ({how})"), Swatch::Split(n)));
            let short: Vec<String> = (0..n)
                .map(|k| {
                    self.slices[k]
                        .branch
                        .clone()
                        .unwrap_or_else(|| (k + 1).to_string())
                })
                .collect();
            legend.push((
                format!("text by the disc: phases {}", short.join("/")),
                Swatch::None,
            ));
        }
        if points.iter().any(|p| p.fallback) {
            legend.push((
                "square: decided by a fallback".to_string(),
                Swatch::Square(BLACK),
            ));
        }
        let mut any_boundary = false;
        for (k, slice) in self.slices.iter().enumerate() {
            if slice.boundaries.values().all(Vec::is_empty) {
                continue;
            }
            any_boundary = true;
            let label = if n > 1 {
                format!("phase boundary, {}", branch_name(self.slices, k))
            } else {
                "phase boundary".to_string()
            };
            legend.push((
                marked(&label),
                Swatch::Line(BRANCH_COLOURS[k % BRANCH_COLOURS.len()]),
            ));
        }
        if any_boundary {
            legend.push((
                "bars: straddling edge".to_string(),
                Swatch::ErrorBar(RGBColor(70, 70, 70)),
            ));
        }
        for (label, colour, parts) in &self.lines {
            if !parts.is_empty() {
                legend.push((marked(label), Swatch::Dashed(*colour)));
            }
        }
        legend
    }

    /// The legend (a box of one or two columns) and the caption below the plot.
    fn draw_legend(
        &self,
        root: &DrawingArea<SVGBackend, Shift>,
        legend: &[(String, Swatch)],
    ) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
        let top = PLOT_HEIGHT as i32;
        draw_legend(root, (10, top), MAP_WIDTH as i32 - 20, legend)?;
        let below = top + legend_size(legend, MAP_WIDTH as i32 - 20).1 + 8;
        if let Some(caption) = &self.caption {
            for (k, line) in wrap(caption, 74).iter().enumerate() {
                root.draw(&Text::new(
                    marked(line),
                    (10, below + 12 + LEGEND_ROW * k as i32),
                    TextStyle::from(font(LEGEND_FONT)).pos(plotters::style::text_anchor::Pos::new(
                        plotters::style::text_anchor::HPos::Left,
                        plotters::style::text_anchor::VPos::Center,
                    )),
                ))?;
            }
        }
        Ok(())
    }

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
        let (upper, _) = root.split_vertically(PLOT_HEIGHT);
        let mut chart = ChartBuilder::on(&upper)
            .caption(self.title, font(14.0))
            .margin(10)
            .margin_right(16)
            .x_label_area_size(46)
            .y_label_area_size(58)
            .build_cartesian_2d(x, y)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(&self.x_desc)
            .y_desc(&self.y_desc)
            .axis_desc_style(("sans-serif", px(AXIS_FONT)))
            .disable_mesh()
            .x_label_formatter(&|_| String::new())
            .y_label_formatter(&|_| String::new())
            .set_all_tick_mark_size(0)
            .draw()
            .map_err(err)?;
        let points = merge_branches(self.slices);
        let at: Vec<(i32, i32)> = points
            .iter()
            .map(|p| chart.backend_coord(&(p.x, p.y)))
            .collect();
        let cells = self.draw_regions(root, &chart, &points).map_err(err)?;
        // The frame again, over the shades.
        let (xr, yr) = chart.plotting_area().get_pixel_range();
        root.draw(&Rectangle::new(
            [(xr.start, yr.start), (xr.end - 1, yr.end - 1)],
            BLACK.stroke_width(1),
        ))
        .map_err(err)?;
        hand_ticks(root, chart.plotting_area(), &self.ticks.0, &self.ticks.1).map_err(err)?;
        for (_, color, parts) in &self.lines {
            for part in parts {
                chart
                    .draw_series(DashedLineSeries::new(
                        part.iter().copied(),
                        6,
                        4,
                        color.stroke_width(2),
                    ))
                    .map_err(err)?;
            }
        }
        self.draw_boundaries(root, &chart, &points, &cells)?;
        // Smaller dots where refinement packed points densely.
        let radius = if points.len() > 100 { 2 } else { 3 };
        for (p, &c) in points.iter().zip(&at) {
            if p.bistable() {
                continue;
            }
            let color = phase_color(p.phase());
            // Untrusted points hollow: their label may still change.
            let style = if p.trusted {
                color.filled()
            } else {
                color.stroke_width(2)
            };
            root.draw(&Circle::new(c, radius, style)).map_err(err)?;
            // Not stationary, label kept by the trend (a heating gas, a cooling solid, a
            // coarsening coexistence): a white centre in the filled disc.
            if p.trusted && p.label_kept {
                root.draw(&Circle::new(c, (radius / 2).max(1), WHITE.filled()))
                    .map_err(err)?;
            }
        }
        draw_bistable(root, &mut chart, self.slices, &points, radius + 1)?;
        draw_fallbacks(&mut chart, &points, radius)?;
        if let Some(note) = &self.note {
            for (k, line) in wrap(note, 52).iter().enumerate() {
                root.draw(&Text::new(
                    line.clone(),
                    (xr.start + 8, yr.start + 8 + 16 * k as i32),
                    font(12.5).color(&RGBColor(170, 0, 0)),
                ))
                .map_err(err)?;
            }
        }
        Ok(points
            .iter()
            .zip(&at)
            .map(|(p, &(px, py))| (p.x, p.y, px, py))
            .collect())
    }

    /// The plane coordinates of an axis value pair (the scales the boundaries are extracted in).
    fn plane(&self, (x, y): (f64, f64)) -> (f64, f64) {
        (self.axes.0.scale(x), self.axes.1.scale(y))
    }

    /// The pixel position of plane coordinates.
    fn pixel<X, Y>(
        &self,
        chart: &ChartContext<'_, SVGBackend<'_>, Cartesian2d<X, Y>>,
        (u, v): (f64, f64),
    ) -> (i32, i32)
    where
        X: Ranged<ValueType = f64>,
        Y: Ranged<ValueType = f64>,
    {
        chart.backend_coord(&(self.axes.0.unscale(u), self.axes.1.unscale(v)))
    }

    /// Shades every sampled point's Voronoi cell in its phase's colour: paler where its label
    /// may change, grey where the branches disagree. The cells are those of the plane the
    /// boundaries are extracted in (`boundary`: log10 on a log axis), so each boundary point's
    /// straddling edge joins two neighbouring cells. Returns the cells, in plane coordinates.
    fn draw_regions<X, Y>(
        &self,
        root: &DrawingArea<SVGBackend, Shift>,
        chart: &ChartContext<'_, SVGBackend<'_>, Cartesian2d<X, Y>>,
        points: &[DrawnPoint],
    ) -> Result<Vec<super::regions::Polygon>, DrawingAreaErrorKind<std::io::Error>>
    where
        X: Ranged<ValueType = f64>,
        Y: Ranged<ValueType = f64>,
    {
        let ((x0, x1), (y0, y1)) = self.ranges;
        let (a, b) = (self.plane((x0, y0)), self.plane((x1, y1)));
        let rect = (a.0.min(b.0), a.1.min(b.1), a.0.max(b.0), a.1.max(b.1));
        let pos: Vec<(f64, f64)> = points.iter().map(|p| self.plane((p.x, p.y))).collect();
        let cells = super::regions::voronoi_cells(&pos, rect);
        for (p, cell) in points.iter().zip(&cells) {
            if cell.len() < 3 {
                continue;
            }
            let shade = if p.bistable() {
                BISTABLE_SHADE
            } else {
                let share = if p.trusted {
                    REGION_SHADE
                } else {
                    UNTRUSTED_SHADE
                };
                tint(phase_color(p.phase()), share)
            };
            let v: Vec<(i32, i32)> = cell.iter().map(|&c| self.pixel(chart, c)).collect();
            root.draw(&Polygon::new(v.clone(), shade.filled()))?;
            // The outline in the same shade closes the seams between neighbouring cells.
            let mut closed = v;
            closed.push(closed[0]);
            root.draw(&PathElement::new(closed, shade.stroke_width(1)))?;
        }
        Ok(cells)
    }

    /// Each branch's boundaries: the interface of the two cells of every boundary point's
    /// straddling edge as a line, the point on it, and its uncertainty (the straddling edge's
    /// extent along each axis) as error bars with caps.
    fn draw_boundaries<X, Y>(
        &self,
        root: &DrawingArea<SVGBackend, Shift>,
        chart: &ChartContext<'_, SVGBackend<'_>, Cartesian2d<X, Y>>,
        points: &[DrawnPoint],
        cells: &[super::regions::Polygon],
    ) -> Result<(), String>
    where
        X: Ranged<ValueType = f64>,
        Y: Ranged<ValueType = f64>,
    {
        let err = |e: DrawingAreaErrorKind<_>| e.to_string();
        let index: std::collections::HashMap<(u64, u64), usize> = points
            .iter()
            .enumerate()
            .map(|(k, p)| (((p.x + 0.0).to_bits(), (p.y + 0.0).to_bits()), k))
            .collect();
        let find = |x: f64, y: f64| index.get(&((x + 0.0).to_bits(), (y + 0.0).to_bits()));
        let bar = RGBColor(70, 70, 70);
        let mut marks: Vec<(i32, i32)> = Vec::new();
        for (k, slice) in self.slices.iter().enumerate() {
            let colour = BRANCH_COLOURS[k % BRANCH_COLOURS.len()];
            for b in slice.boundaries.values().flatten() {
                let ends = b.between.map(|i| slice.points.get(i));
                if let [Some(p), Some(q)] = ends
                    && let (Some(&i), Some(&j)) = (find(p.x, p.y), find(q.x, q.y))
                {
                    let f = |k: usize| self.plane((points[k].x, points[k].y));
                    if let Some((a, c)) = super::regions::interface(&cells[i], f(i), f(j)) {
                        let line = vec![self.pixel(chart, a), self.pixel(chart, c)];
                        root.draw(&PathElement::new(line, colour.stroke_width(2)))
                            .map_err(err)?;
                    }
                }
                let c = chart.backend_coord(&(b.x, b.y));
                let (x0, x1) = (
                    chart.backend_coord(&(b.x_range[0], b.y)).0,
                    chart.backend_coord(&(b.x_range[1], b.y)).0,
                );
                let (y0, y1) = (
                    chart.backend_coord(&(b.x, b.y_range[0])).1,
                    chart.backend_coord(&(b.x, b.y_range[1])).1,
                );
                for (from, to, cap) in [
                    ((x0, c.1), (x1, c.1), (0, 3)),
                    ((c.0, y0), (c.0, y1), (3, 0)),
                ] {
                    if from == to {
                        continue;
                    }
                    root.draw(&PathElement::new(vec![from, to], bar.stroke_width(1)))
                        .map_err(err)?;
                    for end in [from, to] {
                        root.draw(&PathElement::new(
                            vec![
                                (end.0 - cap.0, end.1 - cap.1),
                                (end.0 + cap.0, end.1 + cap.1),
                            ],
                            bar.stroke_width(1),
                        ))
                        .map_err(err)?;
                    }
                }
                marks.push(c);
            }
        }
        // The points last, over every bar and line: white discs outlined in black.
        for c in marks {
            root.draw(&Circle::new(c, 3, WHITE.filled())).map_err(err)?;
            root.draw(&Circle::new(c, 3, BLACK.stroke_width(1)))
                .map_err(err)?;
        }
        Ok(())
    }
}

/// The bistable points (those whose branches disagree): a disc split into one sector per
/// branch, the phases in branch order beside it.
fn draw_bistable<X, Y>(
    root: &DrawingArea<SVGBackend, Shift>,
    chart: &mut ChartContext<'_, SVGBackend<'_>, Cartesian2d<X, Y>>,
    slices: &[&Slice],
    points: &[DrawnPoint],
    radius: i32,
) -> Result<(), String>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();
    // One sector per branch in its phase's colour (white where that branch has no point),
    // a black outline, and the phases in branch order beside it.
    let r = radius + 2;
    let n = slices.len();
    for p in points.iter().filter(|p| p.bistable()) {
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
                    + Text::new(text.join("/"), (r + 2, -r - 12), font(12.0))),
            )
            .map_err(err)?;
    }
    Ok(())
}

/// A square outline around every point whose label rests on a fallback (the temperature for an
/// unmeasured mobility, or `gas_temperature` where no line decided).
fn draw_fallbacks<X, Y>(
    chart: &mut ChartContext<'_, SVGBackend<'_>, Cartesian2d<X, Y>>,
    points: &[DrawnPoint],
    radius: i32,
) -> Result<(), String>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let r = radius + 3;
    chart
        .draw_series(points.iter().filter(|p| p.fallback).map(|p| {
            EmptyElement::at((p.x, p.y)) + Rectangle::new([(-r, -r), (r, r)], BLACK.stroke_width(1))
        }))
        .map_err(|e| e.to_string())?;
    Ok(())
}

#[cfg(test)]
#[path = "plot_phase_tests.rs"]
mod tests;
