//! Plotting helpers shared by the pictures drawn with plotters (`plot_phase`, `lines_plot`):
//! font sizes in the SVG's pixels, tick marks drawn by hand (`report::ticks`: decades and minor
//! ticks, which plotters' own log axis does not draw), a legend in a framed box of one or two
//! columns, and line breaking of a note.

use super::ticks::Tick;
use plotters::coord::Shift;
use plotters::prelude::*;

/// The plotters font size that comes out as `px` pixels in the SVG (plotters writes its size
/// divided by 1.24).
pub(crate) fn px(px: f64) -> f64 {
    px * 1.24
}

/// A sans-serif font of `size` SVG pixels.
pub(crate) fn font(size: f64) -> FontDesc<'static> {
    ("sans-serif", px(size)).into_font()
}

/// Font sizes of the figures, in SVG pixels: at a column width of 8.5 cm a figure 480 px wide
/// prints its 13 px text at 6.5 pt and its 15 px axis names at 7.5 pt.
pub(crate) const TICK_FONT: f64 = 13.0;
pub(crate) const AXIS_FONT: f64 = 15.0;
pub(crate) const LEGEND_FONT: f64 = 12.5;

/// The mark of a legend entry.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Swatch {
    Line(RGBColor),
    /// A dashed line (a guide).
    Dashed(RGBColor),
    /// A shaded square with a dot: a phase's region and its sampled points.
    Region(RGBColor, RGBColor),
    /// A marker with a horizontal error bar (a boundary point and its uncertainty).
    ErrorBar(RGBColor),
    Ring(RGBColor),
    /// A grey disc with a white centre (label kept by its trend).
    Kept,
    /// A disc split into `n` grey sectors (bistable).
    Split(usize),
    /// A square outline (a label decided by a fallback).
    Square(RGBColor),
    /// Text only (a continued line).
    None,
}

/// The width in pixels a legend entry's text takes (an estimate: 0.52 em a character).
fn text_width(text: &str) -> i32 {
    (0.52 * LEGEND_FONT * text.chars().filter(|c| *c != super::typeset::MARK).count() as f64).ceil()
        as i32
}

/// The size in pixels of the legend of `entries` when it may be `width` pixels wide: one or two
/// columns (two where the longest entry fits twice).
pub(crate) fn legend_size(entries: &[(String, Swatch)], width: i32) -> (i32, i32, usize) {
    let widest = entries
        .iter()
        .map(|(t, _)| text_width(t) + 34)
        .max()
        .unwrap_or(0);
    let columns = if 2 * widest + 10 <= width { 2 } else { 1 };
    let rows = entries.len().div_ceil(columns) as i32;
    (columns as i32 * widest + 10, LEGEND_ROW * rows + 8, columns)
}

/// The height of a legend row in pixels.
pub(crate) const LEGEND_ROW: i32 = 17;

/// Draws the legend entries in a framed box at `at` (pixels), at most `width` wide: in two
/// columns where they fit (down the first, then the second), else one.
pub(crate) fn draw_legend(
    root: &DrawingArea<SVGBackend, Shift>,
    at: (i32, i32),
    width: i32,
    entries: &[(String, Swatch)],
) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
    if entries.is_empty() {
        return Ok(());
    }
    let (w, h, columns) = legend_size(entries, width);
    let (x0, y0) = at;
    root.draw(&Rectangle::new(
        [(x0, y0), (x0 + w, y0 + h)],
        WHITE.filled(),
    ))?;
    root.draw(&Rectangle::new(
        [(x0, y0), (x0 + w, y0 + h)],
        RGBColor(120, 120, 120).stroke_width(1),
    ))?;
    let font = TextStyle::from(font(LEGEND_FONT)).pos(plotters::style::text_anchor::Pos::new(
        plotters::style::text_anchor::HPos::Left,
        plotters::style::text_anchor::VPos::Center,
    ));
    let rows = entries.len().div_ceil(columns);
    let column_width = (w - 10) / columns as i32;
    for (k, (text, swatch)) in entries.iter().enumerate() {
        let x = x0 + 4 + column_width * (k / rows) as i32;
        let y = y0 + 12 + LEGEND_ROW * (k % rows) as i32;
        let c = (x + 12, y);
        match *swatch {
            Swatch::Line(col) => root.draw(&PathElement::new(
                vec![(x + 2, y), (x + 22, y)],
                col.stroke_width(2),
            ))?,
            Swatch::Dashed(col) => root.draw(&plotters::element::DashedPathElement::new(
                vec![(x + 2, y), (x + 22, y)],
                5,
                3,
                col.stroke_width(2),
            ))?,
            Swatch::Region(tint, col) => {
                root.draw(&Rectangle::new(
                    [(x + 2, y - 7), (x + 22, y + 7)],
                    tint.filled(),
                ))?;
                root.draw(&Circle::new(c, 3, col.filled()))?;
            }
            Swatch::ErrorBar(col) => {
                root.draw(&PathElement::new(
                    vec![(x + 2, y), (x + 22, y)],
                    col.stroke_width(1),
                ))?;
                for end in [x + 2, x + 22] {
                    root.draw(&PathElement::new(
                        vec![(end, y - 3), (end, y + 3)],
                        col.stroke_width(1),
                    ))?;
                }
                root.draw(&Circle::new(c, 3, WHITE.filled()))?;
                root.draw(&Circle::new(c, 3, BLACK.stroke_width(1)))?;
            }
            Swatch::Ring(col) => root.draw(&Circle::new(c, 4, col.stroke_width(2)))?,
            Swatch::Kept => {
                root.draw(&Circle::new(c, 4, RGBColor(90, 90, 90).filled()))?;
                root.draw(&Circle::new(c, 2, WHITE.filled()))?;
            }
            Swatch::Split(n) => {
                let greys = [RGBColor(60, 60, 60), RGBColor(190, 190, 190)];
                for k in 0..n.min(2) {
                    shape(root, c, &sector(k, n, 5), greys[k], true)?;
                }
            }
            Swatch::Square(col) => root.draw(&Rectangle::new(
                [(c.0 - 6, c.1 - 6), (c.0 + 6, c.1 + 6)],
                col.stroke_width(1),
            ))?,
            Swatch::None => {}
        }
        root.draw(&Text::new(text.clone(), (x + 28, y), font.clone()))?;
    }
    Ok(())
}

/// Tick marks and labels of both axes of a chart (`plot`: its plotting area; `area`: the
/// drawing area the chart was built on), in the chart's scale: labelled ticks 5 px long, minor
/// ones 3 px (`report::ticks`). Ticks outside the plot are skipped.
pub(crate) fn hand_ticks<CT>(
    area: &DrawingArea<SVGBackend, Shift>,
    plot: &DrawingArea<SVGBackend, CT>,
    xs: &[Tick],
    ys: &[Tick],
) -> Result<(), DrawingAreaErrorKind<std::io::Error>>
where
    CT: plotters::coord::CoordTranslate<From = (f64, f64)>,
{
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let (xr, yr) = plot.get_pixel_range();
    let base = area.get_base_pixel();
    let font = TextStyle::from(font(TICK_FONT));
    let below = font.pos(Pos::new(HPos::Center, VPos::Top));
    let left = font.pos(Pos::new(HPos::Right, VPos::Center));
    let (left_edge, bottom) = (xr.start - base.0, yr.end - base.1);
    let y_any = ys.first().map_or(1.0, |t| t.value);
    let x_any = xs.first().map_or(1.0, |t| t.value);
    // The x ticks below the plot, then the y ticks left of it.
    for (ticks, on_x) in [(xs, true), (ys, false)] {
        for t in ticks {
            let v = t.value;
            let (px, py) = plot.map_coordinate(&if on_x { (v, y_any) } else { (x_any, v) });
            let len = if t.label.is_some() { 5 } else { 3 };
            let (tick, at, style) = if on_x {
                if px < xr.start || px > xr.end {
                    continue;
                }
                let x = px - base.0;
                ([(x, bottom), (x, bottom + len)], (x, bottom + 7), &below)
            } else {
                if py < yr.start || py > yr.end {
                    continue;
                }
                let y = py - base.1;
                (
                    [(left_edge - len, y), (left_edge, y)],
                    (left_edge - 7, y),
                    &left,
                )
            };
            area.draw(&PathElement::new(tick, BLACK.stroke_width(1)))?;
            if let Some(label) = &t.label {
                let text = super::typeset::marked(label);
                area.draw(&Text::new(text, at, style.clone()))?;
            }
        }
    }
    Ok(())
}

/// A polygon of pixel offsets from `at` (in `area`'s pixels): filled, or (hollow) its outline
/// 2 px wide.
pub(crate) fn shape<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    at: (i32, i32),
    offsets: &[(i32, i32)],
    colour: RGBColor,
    filled: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let mut v: Vec<(i32, i32)> = offsets.iter().map(|(a, b)| (a + at.0, b + at.1)).collect();
    if filled {
        area.draw(&Polygon::new(v, colour.filled()))
    } else {
        v.push(v[0]);
        area.draw(&PathElement::new(v, colour.stroke_width(2)))
    }
}

/// Splits a note into lines of at most about `width` characters, at spaces.
pub(crate) fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut out: Vec<String> = vec![String::new()];
    for word in text.split(' ') {
        let last = out.last_mut().expect("non-empty");
        if !last.is_empty() && last.len() + 1 + word.len() > width {
            out.push(word.to_string());
        } else {
            if !last.is_empty() {
                last.push(' ');
            }
            last.push_str(word);
        }
    }
    out
}

/// Sector `k` of `n` of a disc of radius `r` in pixel offsets from its centre: two sectors are
/// the left and the right half; more start at the top and go anticlockwise.
pub(crate) fn sector(k: usize, n: usize, r: i32) -> Vec<(i32, i32)> {
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
