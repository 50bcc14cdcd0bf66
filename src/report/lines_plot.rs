//! The order parameters along lines of constant Gamma as SVG (`wetgran lines`): one row per
//! Gamma, three panels per row: `T_g / E_cb`, bridges per grain and `Delta n_cb` (`T_g / m g d`
//! and `Delta n_area` for dry scenes, no bridge panel) against `E*`.
//!
//! Every finished job is a marker: its colour is its label (`plot_phase::phase_color`), its shape
//! its trend state (circle stationary, triangle up heating, triangle down cooling, square
//! coarsening, diamond undecided), filled when its label is trusted and hollow when it may
//! change; a vertical bar is its standard error (`report::lines`). Each branch of a hysteretic
//! sweep has its own line colour, joining the mean over replicas at each `E*`, and its label
//! changes are dashed vertical lines in that colour; the `T_g` panel marks the fluid-gas
//! inflection with a grey dotted line. `E*` is on a log axis; `T_g` too when it spans more than
//! a factor of 20 (a solid is orders of magnitude colder than a gas); the other two are linear
//! from zero. The panels of one column share their range, so the lines compare at a glance.

use super::lines::{GammaLine, LinePoint, Lines};
use super::plot_phase::phase_color;
use super::svg::{grid_ticks, label};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::element::DashedPathElement;
use plotters::prelude::*;

/// The colours of the branches' lines and label changes (the first black).
const BRANCH_COLOURS: [RGBColor; 3] = [
    RGBColor(40, 40, 40),
    RGBColor(170, 0, 170),
    RGBColor(0, 110, 110),
];

/// Pixel size of one panel row and of the legend above them.
const ROW_HEIGHT: u32 = 230;
const HEADER_HEIGHT: u32 = 118;
const WIDTH: u32 = 1260;

/// One quantity of the panels.
#[derive(Clone, Copy)]
enum Quantity {
    Temperature,
    Bridges,
    Contrast,
}

impl Quantity {
    fn value(self, p: &LinePoint) -> Option<(f64, Option<f64>)> {
        match self {
            Quantity::Temperature => Some((p.temperature, p.temperature_error)),
            Quantity::Bridges => p.bridges.map(|b| (b, p.bridges_error)),
            Quantity::Contrast => Some((p.contrast, p.contrast_error)),
        }
    }

    fn name(self, lines: &Lines) -> String {
        match self {
            Quantity::Temperature => format!("T_g / {}", lines.energy_unit),
            Quantity::Bridges => "bridges per grain".to_string(),
            Quantity::Contrast if lines.wet => "Delta n_cb".to_string(),
            Quantity::Contrast => "Delta n_area".to_string(),
        }
    }
}

/// The range of a column, and whether its axis is logarithmic.
fn column_range(lines: &Lines, q: Quantity, log_allowed: bool) -> ((f64, f64), bool) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let mut min_positive = f64::INFINITY;
    for p in lines.lines.iter().flat_map(|l| &l.points) {
        if let Some((v, e)) = q.value(p).filter(|(v, _)| v.is_finite()) {
            let e = e.unwrap_or(0.0);
            lo = lo.min(v - e);
            hi = hi.max(v + e);
            if v > 0.0 {
                min_positive = min_positive.min(v);
            }
        }
    }
    if !lo.is_finite() {
        return ((0.0, 1.0), false);
    }
    let log = log_allowed && min_positive.is_finite() && hi / min_positive > 20.0;
    if log {
        let (a, b) = (
            (min_positive.min(lo.max(min_positive / 10.0))).log10(),
            hi.log10(),
        );
        let pad = ((b - a) * 0.05).max(0.05);
        ((10f64.powf(a - pad), 10f64.powf(b + pad)), true)
    } else {
        let lo = lo.min(0.0);
        let pad = ((hi - lo) * 0.06).max(1e-3);
        ((lo, hi + pad), false)
    }
}

/// The `E*` range and ticks: log when every `E*` is positive.
fn e_star_axis(lines: &Lines) -> ((f64, f64), bool, Vec<f64>) {
    let e: Vec<f64> = lines
        .lines
        .iter()
        .flat_map(|l| l.points.iter().map(|p| p.e_star))
        .collect();
    let lo = e.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = e.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() {
        return ((0.1, 10.0), true, vec![1.0]);
    }
    let log = lo > 0.0;
    let range = if log {
        let pad = ((hi / lo).log10() * 0.06).max(0.05);
        (lo / 10f64.powf(pad), hi * 10f64.powf(pad))
    } else {
        let pad = ((hi - lo) * 0.06).max(0.05);
        (lo - pad, hi + pad)
    };
    (range, log, grid_ticks(&e, range, log, 10))
}

/// Draws the lines of a sweep as SVG (module doc).
pub fn lines_svg(lines: &Lines) -> Result<String, String> {
    let gammas = lines.gammas();
    if gammas.is_empty() {
        return Err(format!(
            "sweep {}: no finished job of a shaken scene to draw along lines of constant Gamma",
            lines.sweep
        ));
    }
    let quantities: Vec<Quantity> = if lines.wet {
        vec![Quantity::Temperature, Quantity::Bridges, Quantity::Contrast]
    } else {
        vec![Quantity::Temperature, Quantity::Contrast]
    };
    let (x_range, x_log, x_ticks) = e_star_axis(lines);
    let height = HEADER_HEIGHT + ROW_HEIGHT * gammas.len() as u32;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        let err = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(err)?;
        let (header, body) = root.split_vertically(HEADER_HEIGHT);
        legend(&header, lines).map_err(err)?;
        let panels = body.split_evenly((gammas.len(), quantities.len()));
        for (c, &q) in quantities.iter().enumerate() {
            let (y_range, y_log) = column_range(lines, q, matches!(q, Quantity::Temperature));
            for (r, &gamma) in gammas.iter().enumerate() {
                let panel = Panel {
                    lines: lines.at_gamma(gamma),
                    quantity: q,
                    caption: format!("Gamma = {}: {}", label(gamma), q.name(lines)),
                    y_name: q.name(lines),
                    y_range,
                    x_ticks: &x_ticks,
                };
                let area = &panels[r * quantities.len() + c];
                let (x, y) = (x_range.0..x_range.1, y_range.0..y_range.1);
                match (x_log, y_log) {
                    (true, true) => panel.draw(area, x.log_scale(), y.log_scale()),
                    (true, false) => panel.draw(area, x.log_scale(), y),
                    (false, true) => panel.draw(area, x, y.log_scale()),
                    (false, false) => panel.draw(area, x, y),
                }?;
            }
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// The legend above the panels: labels, trend shapes, fill, branches, boundaries.
fn legend(
    area: &DrawingArea<SVGBackend, Shift>,
    lines: &Lines,
) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
    let font = ("sans-serif", 13).into_font();
    let text = |s: &str, x: i32, y: i32| Text::new(s.to_string(), (x, y - 7), font.clone());
    area.draw(&Text::new(
        format!(
            "wetgran lines: {} (order parameters along lines of constant Gamma)",
            lines.sweep
        ),
        (12, 8),
        ("sans-serif", 18).into_font(),
    ))?;
    let mut phases: Vec<&str> = lines
        .lines
        .iter()
        .flat_map(|l| l.points.iter().filter_map(|p| p.phase.as_deref()))
        .collect();
    phases.sort();
    phases.dedup();
    let mut x = 14;
    area.draw(&text("label:", x, 46))?;
    x += 48;
    for ph in phases {
        area.draw(&Circle::new((x, 46), 5, phase_color(ph).filled()))?;
        area.draw(&text(ph, x + 9, 46))?;
        x += 22 + 8 * ph.len() as i32;
    }
    x += 16;
    area.draw(&text("run state:", x, 46))?;
    x += 70;
    let grey = RGBColor(90, 90, 90);
    for state in [
        "stationary",
        "heating",
        "cooling",
        "coarsening",
        "undecided",
    ] {
        marker(area, (x, 46), Some(state), grey, true)?;
        area.draw(&text(state, x + 9, 46))?;
        x += 20 + 7 * state.len() as i32;
    }
    marker(area, (x + 6, 46), None, grey, false)?;
    area.draw(&text("hollow: label may still change", x + 15, 46))?;
    let mut x = 14;
    area.draw(&PathElement::new(
        vec![(x, 78), (x, 78 - 12)],
        grey.stroke_width(1),
    ))?;
    area.draw(&text("bar: standard error (blocks)", x + 8, 72))?;
    x += 210;
    let mut branches: Vec<Option<&str>> = Vec::new();
    for l in &lines.lines {
        if !branches.contains(&l.branch.as_deref()) {
            branches.push(l.branch.as_deref());
        }
    }
    for (k, b) in branches.iter().enumerate() {
        let colour = BRANCH_COLOURS[k % BRANCH_COLOURS.len()];
        area.draw(&PathElement::new(
            vec![(x, 72), (x + 18, 72)],
            colour.stroke_width(2),
        ))?;
        area.draw(&DashedPathElement::new(
            vec![(x + 24, 78), (x + 24, 66)],
            3,
            2,
            colour.stroke_width(1),
        ))?;
        let what = match b {
            Some(b) => format!(
                "{}: mean over replicas, dashed: label change",
                crate::boundary::branch_words(b)
            ),
            None => "mean over replicas; dashed: label change".to_string(),
        };
        area.draw(&text(&what, x + 30, 72))?;
        x += 40 + 7 * what.len() as i32;
    }
    area.draw(&DashedPathElement::new(
        vec![(x, 78), (x, 66)],
        1,
        2,
        RGBColor(150, 150, 150).stroke_width(2),
    ))?;
    area.draw(&text("fluid-gas inflection of T_g", x + 8, 72))?;
    area.draw(&text(
        "E* on a log axis, ticks at the sweep's E* values; panels of a column share their range",
        14,
        100,
    ))?;
    Ok(())
}

/// A marker of a run state at a pixel position: circle stationary (or no trend stored),
/// triangle up heating, triangle down cooling, square coarsening, diamond undecided; filled or
/// hollow.
fn marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    at: (i32, i32),
    state: Option<&str>,
    colour: RGBColor,
    filled: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let shape: Vec<(i32, i32)> = match state {
        Some("heating") => vec![(0, -6), (6, 5), (-6, 5)],
        Some("cooling") => vec![(0, 6), (6, -5), (-6, -5)],
        Some("coarsening") => vec![(-5, -5), (5, -5), (5, 5), (-5, 5)],
        Some("undecided") => vec![(0, -6), (6, 0), (0, 6), (-6, 0)],
        _ if filled => return area.draw(&Circle::new(at, 5, colour.filled())),
        _ => return area.draw(&Circle::new(at, 5, colour.stroke_width(2))),
    };
    super::chart::shape(area, at, &shape, colour, filled)
}

/// One panel: one quantity of the lines (branches) at one Gamma.
struct Panel<'a> {
    lines: Vec<&'a GammaLine>,
    quantity: Quantity,
    caption: String,
    y_name: String,
    y_range: (f64, f64),
    x_ticks: &'a [f64],
}

impl Panel<'_> {
    fn draw<XR, YR>(
        &self,
        area: &DrawingArea<SVGBackend, Shift>,
        x: XR,
        y: YR,
    ) -> Result<(), String>
    where
        XR: AsRangedCoord<Value = f64>,
        YR: AsRangedCoord<Value = f64>,
        XR::CoordDescType: ValueFormatter<f64>,
        YR::CoordDescType: ValueFormatter<f64>,
    {
        let err = |e: DrawingAreaErrorKind<_>| e.to_string();
        let mut chart = ChartBuilder::on(area)
            .caption(&self.caption, ("sans-serif", 14))
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(58)
            .build_cartesian_2d(x, y)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("E*")
            .y_desc(self.y_name.as_str())
            .disable_x_mesh()
            .x_label_formatter(&|_| String::new())
            .set_tick_mark_size(LabelAreaPosition::Bottom, 0)
            .y_labels(6)
            .y_label_formatter(&|v| label(*v))
            .light_line_style(WHITE)
            .draw()
            .map_err(err)?;
        let plot = chart.plotting_area();
        let (y0, y1) = self.y_range;
        // Ticks at the grid's E* values, drawn by hand (the log axis's own ticks skip most).
        super::chart::hand_ticks(area, plot, self.x_ticks, &[]).map_err(err)?;
        let clip = |v: f64| v.clamp(y0, y1);
        for (k, line) in self.lines.iter().enumerate() {
            let colour = BRANCH_COLOURS[k % BRANCH_COLOURS.len()];
            let means = means(line, self.quantity);
            plot.draw(&PathElement::new(
                means.iter().map(|&(e, v)| (e, clip(v))).collect::<Vec<_>>(),
                colour.stroke_width(1),
            ))
            .map_err(err)?;
            for b in &line.boundaries {
                plot.draw(&DashedPathElement::new(
                    vec![(b.e_star, y0), (b.e_star, y1)],
                    4,
                    3,
                    colour.stroke_width(1),
                ))
                .map_err(err)?;
                plot.draw(
                    &(EmptyElement::at((b.e_star, y1))
                        + Text::new(b.pair.clone(), (3, 2), ("sans-serif", 11))),
                )
                .map_err(err)?;
            }
            if let (Quantity::Temperature, Some(e)) = (self.quantity, line.inflection) {
                plot.draw(&DashedPathElement::new(
                    vec![(e, y0), (e, y1)],
                    1,
                    3,
                    RGBColor(150, 150, 150).stroke_width(2),
                ))
                .map_err(err)?;
            }
            for p in &line.points {
                let Some((v, se)) = self.quantity.value(p).filter(|(v, _)| v.is_finite()) else {
                    continue;
                };
                if let Some(se) = se.filter(|s| *s > 0.0) {
                    plot.draw(&PathElement::new(
                        vec![(p.e_star, clip(v - se)), (p.e_star, clip(v + se))],
                        RGBColor(90, 90, 90).stroke_width(1),
                    ))
                    .map_err(err)?;
                }
                let colour = p
                    .phase
                    .as_deref()
                    .map_or(RGBColor(127, 127, 127), phase_color);
                let at = plot.map_coordinate(&(p.e_star, clip(v)));
                let base = area.get_base_pixel();
                marker(
                    area,
                    (at.0 - base.0, at.1 - base.1),
                    p.trend.as_deref(),
                    colour,
                    p.trusted,
                )
                .map_err(err)?;
            }
        }
        Ok(())
    }
}

/// The mean of a quantity over the replicas at each `E*` of a line.
fn means(line: &GammaLine, q: Quantity) -> Vec<(f64, f64)> {
    let finite = |p: &LinePoint| q.value(p).map(|(v, _)| v).filter(|v| v.is_finite());
    let mut out: Vec<(f64, f64, usize)> = Vec::new();
    for (e, v) in line
        .points
        .iter()
        .filter_map(|p| Some((p.e_star, finite(p)?)))
    {
        match out.last_mut() {
            Some((last, sum, n)) if *last == e => {
                *sum += v;
                *n += 1;
            }
            _ => out.push((e, v, 1)),
        }
    }
    out.into_iter().map(|(e, s, n)| (e, s / n as f64)).collect()
}
