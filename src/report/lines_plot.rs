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
//! Log axes have decade ticks (`report::ticks`), each axis one tick format; error bars have caps.
//!
//! [`overlay_svg`] (`lines --overlay`) draws each quantity in one panel for all Gamma, one colour
//! per Gamma (dark blue at the lowest to yellow at the highest), where a collapse of the lines
//! shows first; its markers have the Gamma's colour and the run state's shape.

use super::chart::{AXIS_FONT, LEGEND_FONT, TICK_FONT, font, px};
use super::lines::{GammaLine, LinePoint, Lines};
use super::plot_phase::phase_color;
use super::svg::label;
use super::ticks::{Tick, axis_ticks};
use super::typeset::{marked, typeset_svg};
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
fn e_star_axis(lines: &Lines) -> ((f64, f64), bool, Vec<Tick>) {
    let e: Vec<f64> = lines
        .lines
        .iter()
        .flat_map(|l| l.points.iter().map(|p| p.e_star))
        .collect();
    let lo = e.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = e.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() {
        return ((0.1, 10.0), true, axis_ticks((0.1, 10.0), true));
    }
    let log = lo > 0.0;
    let range = if log {
        let pad = ((hi / lo).log10() * 0.06).max(0.05);
        (lo / 10f64.powf(pad), hi * 10f64.powf(pad))
    } else {
        let pad = ((hi - lo) * 0.06).max(0.05);
        (lo - pad, hi + pad)
    };
    (range, log, axis_ticks(range, log))
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
                    lines: lines
                        .at_gamma(gamma)
                        .into_iter()
                        .enumerate()
                        .map(|(k, l)| (l, BRANCH_COLOURS[k % BRANCH_COLOURS.len()]))
                        .collect(),
                    by_gamma: false,
                    quantity: q,
                    caption: marked(&format!("Gamma = {}", label(gamma))),
                    y_name: marked(&q.name(lines)),
                    y_range,
                    y_ticks: axis_ticks(y_range, y_log),
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
    Ok(typeset_svg(&svg))
}

/// The colour of Gamma `k` of `n` in an overlay (dark blue to yellow, `svg::colour`).
fn gamma_colour(k: usize, n: usize) -> RGBColor {
    let hex = super::svg::colour(
        if n > 1 {
            k as f64 / (n - 1) as f64
        } else {
            0.0
        } * 0.9,
    );
    let c = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).unwrap_or(0);
    RGBColor(c(1), c(3), c(5))
}

/// The width and the panel height of an overlay, in pixels.
const OVERLAY_WIDTH: u32 = 480;
const OVERLAY_PANEL: u32 = 300;

/// Draws each quantity of the lines in one panel for all Gamma (module doc), the panels one
/// above the other, a legend of the Gamma values on top.
pub fn overlay_svg(lines: &Lines) -> Result<String, String> {
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
    let per_row = 4;
    let header = 30 + 18 * gammas.len().div_ceil(per_row) as u32 + 36;
    let height = header + OVERLAY_PANEL * quantities.len() as u32;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (OVERLAY_WIDTH, height)).into_drawing_area();
        let err = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(err)?;
        let (top, body) = root.split_vertically(header);
        top.draw(&Text::new(
            marked(&format!("{}: all lines of constant Γ", lines.sweep)),
            (10, 6),
            font(14.0),
        ))
        .map_err(err)?;
        let left = TextStyle::from(font(LEGEND_FONT)).pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Left,
            plotters::style::text_anchor::VPos::Center,
        ));
        for (k, &g) in gammas.iter().enumerate() {
            let (x, y) = (
                14 + 115 * (k % per_row) as i32,
                36 + 18 * (k / per_row) as i32,
            );
            let c = gamma_colour(k, gammas.len());
            top.draw(&PathElement::new(
                vec![(x, y), (x + 20, y)],
                c.stroke_width(2),
            ))
            .map_err(err)?;
            top.draw(&Circle::new((x + 10, y), 4, c.filled()))
                .map_err(err)?;
            top.draw(&Text::new(
                marked(&format!("Gamma = {}", label(g))),
                (x + 26, y),
                left.clone(),
            ))
            .map_err(err)?;
        }
        for (k, note) in [
            "shape: run state (circle stationary, triangles heating/cooling);",
            "hollow: label may change; bars: standard error",
        ]
        .iter()
        .enumerate()
        {
            top.draw(&Text::new(
                note.to_string(),
                (14, header as i32 - 30 + 14 * k as i32),
                font(11.5),
            ))
            .map_err(err)?;
        }
        let panels = body.split_evenly((quantities.len(), 1));
        for (r, &q) in quantities.iter().enumerate() {
            let (y_range, y_log) = column_range(lines, q, matches!(q, Quantity::Temperature));
            let panel = Panel {
                lines: lines
                    .lines
                    .iter()
                    .map(|l| {
                        let k = gammas
                            .iter()
                            .position(|g| (g - l.gamma).abs() <= 1e-9 * g.abs())
                            .unwrap_or(0);
                        (l, gamma_colour(k, gammas.len()))
                    })
                    .collect(),
                by_gamma: true,
                quantity: q,
                caption: String::new(),
                y_name: marked(&q.name(lines)),
                y_range,
                y_ticks: axis_ticks(y_range, y_log),
                x_ticks: &x_ticks,
            };
            let area = &panels[r];
            let (x, y) = (x_range.0..x_range.1, y_range.0..y_range.1);
            match (x_log, y_log) {
                (true, true) => panel.draw(area, x.log_scale(), y.log_scale()),
                (true, false) => panel.draw(area, x.log_scale(), y),
                (false, true) => panel.draw(area, x, y.log_scale()),
                (false, false) => panel.draw(area, x, y),
            }?;
        }
        root.present().map_err(err)?;
    }
    Ok(typeset_svg(&svg))
}

/// The legend above the panels: labels, trend shapes, fill, branches, boundaries.
fn legend(
    area: &DrawingArea<SVGBackend, Shift>,
    lines: &Lines,
) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
    let small = font(LEGEND_FONT);
    let text = |s: &str, x: i32, y: i32| Text::new(marked(s), (x, y - 7), small.clone());
    area.draw(&Text::new(
        format!(
            "wetgran lines: {} (order parameters along lines of constant Gamma)",
            lines.sweep
        ),
        (12, 8),
        font(16.0),
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
        let name = super::plot_phase::phase_name(ph);
        area.draw(&text(&name, x + 9, 46))?;
        x += 22 + 8 * name.len() as i32;
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
        "E* on a log axis; panels of a column share their range; --overlay: all Gamma in one panel",
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

/// One panel: one quantity of the lines (the branches at one Gamma, or every line of an
/// overlay), each with its colour; `by_gamma`: the markers take the line's colour (an overlay)
/// rather than their label's, and label changes and inflections are left out.
struct Panel<'a> {
    lines: Vec<(&'a GammaLine, RGBColor)>,
    by_gamma: bool,
    quantity: Quantity,
    caption: String,
    y_name: String,
    y_range: (f64, f64),
    y_ticks: Vec<Tick>,
    x_ticks: &'a [Tick],
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
        let mut builder = ChartBuilder::on(area);
        if !self.caption.is_empty() {
            builder.caption(&self.caption, font(TICK_FONT + 1.0));
        }
        let mut chart = builder
            .margin(8)
            .margin_right(14)
            .x_label_area_size(42)
            .y_label_area_size(62)
            .build_cartesian_2d(x, y)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(marked("E*"))
            .y_desc(self.y_name.as_str())
            .axis_desc_style(("sans-serif", px(AXIS_FONT)))
            .disable_mesh()
            .x_label_formatter(&|_| String::new())
            .y_label_formatter(&|_| String::new())
            .set_all_tick_mark_size(0)
            .draw()
            .map_err(err)?;
        let plot = chart.plotting_area();
        let (y0, y1) = self.y_range;
        // Decade ticks drawn by hand (the log axis's own ticks skip most), one format per axis.
        super::chart::hand_ticks(area, plot, self.x_ticks, &self.y_ticks).map_err(err)?;
        let clip = |v: f64| v.clamp(y0, y1);
        for &(line, colour) in &self.lines {
            let means = means(line, self.quantity);
            plot.draw(&PathElement::new(
                means.iter().map(|&(e, v)| (e, clip(v))).collect::<Vec<_>>(),
                colour.stroke_width(1),
            ))
            .map_err(err)?;
            for b in line.boundaries.iter().filter(|_| !self.by_gamma) {
                plot.draw(&DashedPathElement::new(
                    vec![(b.e_star, y0), (b.e_star, y1)],
                    4,
                    3,
                    colour.stroke_width(1),
                ))
                .map_err(err)?;
                plot.draw(
                    &(EmptyElement::at((b.e_star, y1))
                        + Text::new(b.pair.clone(), (3, 2), font(11.0))),
                )
                .map_err(err)?;
            }
            if let (Quantity::Temperature, Some(e), false) =
                (self.quantity, line.inflection, self.by_gamma)
            {
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
                let base = area.get_base_pixel();
                let to_area = |v: f64| {
                    let at = plot.map_coordinate(&(p.e_star, clip(v)));
                    (at.0 - base.0, at.1 - base.1)
                };
                // The standard error: a bar with caps, 1.5 px, drawn under the marker.
                if let Some(se) = se.filter(|s| *s > 0.0) {
                    let (lo, hi) = (to_area(v - se), to_area(v + se));
                    let bar = RGBColor(60, 60, 60).stroke_width(1);
                    area.draw(&PathElement::new(vec![lo, hi], bar))
                        .map_err(err)?;
                    for end in [lo, hi] {
                        area.draw(&PathElement::new(
                            vec![(end.0 - 3, end.1), (end.0 + 3, end.1)],
                            bar,
                        ))
                        .map_err(err)?;
                    }
                }
                let colour = if self.by_gamma {
                    colour
                } else {
                    p.phase
                        .as_deref()
                        .map_or(RGBColor(127, 127, 127), phase_color)
                };
                let at = plot.map_coordinate(&(p.e_star, clip(v)));
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::figure_read::{svg_count, svg_texts};

    /// Three lines of constant Gamma, five E* each (0.001 .. 10: four decades), with errors.
    fn lines() -> Lines {
        let line = |gamma: f64| GammaLine {
            gamma,
            branch: None,
            points: (0..5)
                .map(|k| {
                    let e = 10f64.powi(k - 3);
                    LinePoint {
                        job_id: format!("j{gamma}{k}"),
                        point: k as i64,
                        replica: 0,
                        e_star: e,
                        phase: Some(if k < 3 { "f" } else { "g" }.into()),
                        trend: Some("stationary".into()),
                        trust: None,
                        trusted: true,
                        temperature: 0.01 * gamma * 10f64.powi(k),
                        temperature_error: Some(0.002 * gamma * 10f64.powi(k)),
                        bridges: Some(1.0 - 0.2 * k as f64),
                        bridges_error: Some(0.05),
                        contrast: 0.1,
                        contrast_error: Some(0.02),
                    }
                })
                .collect(),
            boundaries: vec![],
            inflection: None,
        };
        Lines {
            sweep: "s".into(),
            wet: true,
            energy_unit: "E_cb".into(),
            lines: vec![line(1.0), line(2.0), line(4.0)],
            left_out: 0,
        }
    }

    /// The number of panels of a drawing: the frames plotters draws around each plot area
    /// are not elements of their own, so count the y axis names.
    fn axis_names(svg: &str, name: &str) -> usize {
        svg_texts(svg).iter().filter(|t| *t == name).count()
    }

    #[test]
    fn the_panels_have_one_tick_format_per_axis_and_error_bars_with_caps() {
        let svg = lines_svg(&lines()).unwrap();
        // 3 Gamma x 3 quantities: one T_g/E_cb panel per Gamma, typeset.
        assert_eq!(axis_names(&svg, "Tg / Ecb"), 3);
        assert_eq!(axis_names(&svg, "bridges per grain"), 3);
        assert_eq!(axis_names(&svg, "E*"), 9);
        let texts = svg_texts(&svg);
        // E* over four decades: decades in plain decimals, no 1.00e-3 beside 0.01.
        for t in ["0.001", "0.01", "0.1", "1", "10"] {
            assert!(texts.iter().any(|x| x == t), "no tick {t}: {texts:?}");
        }
        assert!(!texts.iter().any(|t| t.contains("e-")));
        // Error bars: a bar and two caps per point and quantity (45 points x 3).
        let bars = svg_count(&svg, "polyline", Some(("stroke", "#3C3C3C")));
        assert_eq!(bars, 3 * 45, "{bars}");
    }

    #[test]
    fn the_overlay_draws_every_gamma_in_one_panel_per_quantity() {
        let svg = overlay_svg(&lines()).unwrap();
        assert_eq!(axis_names(&svg, "Tg / Ecb"), 1);
        assert_eq!(axis_names(&svg, "bridges per grain"), 1);
        assert_eq!(axis_names(&svg, "ΔNcb".replace('N', "n").as_str()), 1);
        let texts = svg_texts(&svg);
        for g in ["Γ = 1", "Γ = 2", "Γ = 4"] {
            assert!(
                texts.iter().any(|t| t == g),
                "no legend entry {g}: {texts:?}"
            );
        }
        // One line per Gamma in each panel, each in its own colour.
        let colours: std::collections::BTreeSet<String> = (0..3)
            .map(|k| {
                let c = gamma_colour(k, 3);
                format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
            })
            .collect();
        assert_eq!(colours.len(), 3);
        for c in &colours {
            // The legend's line and one mean line per panel.
            assert_eq!(
                svg_count(&svg, "polyline", Some(("stroke", c))),
                1 + 3,
                "{c}"
            );
        }
    }
}
