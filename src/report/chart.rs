//! Plotting helpers shared by the pictures drawn with plotters (`plot_phase`, `lines_plot`):
//! tick marks at chosen values (a sweep's grid values, which plotters' own log axis skips), a
//! legend drawn outside the plot, and line breaking of a note.

use plotters::coord::Shift;
use plotters::prelude::*;

/// The mark of a legend entry.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Swatch {
    Line(RGBColor),
    Dot(RGBColor),
    Ring(RGBColor),
    /// A grey disc with a white centre (label kept by its trend).
    Kept,
    /// A disc split into `n` grey sectors (bistable).
    Split(usize),
    Cross(RGBColor),
    /// A square outline (a label decided by a fallback).
    Square(RGBColor),
    /// Text only (a continued line).
    None,
}

/// Draws the legend entries from `at` (pixels) downwards, framed.
pub(crate) fn draw_legend(
    root: &DrawingArea<SVGBackend, Shift>,
    at: (i32, i32),
    entries: &[(String, Swatch)],
) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
    const ROW: i32 = 18;
    let (x, y0) = at;
    let width = entries
        .iter()
        .map(|(t, _)| 7 * t.len() as i32 + 34)
        .max()
        .unwrap_or(0);
    root.draw(&Rectangle::new(
        [(x, y0), (x + width, y0 + ROW * entries.len() as i32 + 8)],
        BLACK.stroke_width(1),
    ))?;
    let font = TextStyle::from(("sans-serif", 13).into_font()).pos(
        plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Left,
            plotters::style::text_anchor::VPos::Center,
        ),
    );
    for (k, (text, swatch)) in entries.iter().enumerate() {
        let y = y0 + 13 + ROW * k as i32;
        let c = (x + 14, y);
        match *swatch {
            Swatch::Line(col) => root.draw(&PathElement::new(
                vec![(x + 5, y), (x + 23, y)],
                col.stroke_width(2),
            ))?,
            Swatch::Dot(col) => root.draw(&Circle::new(c, 5, col.filled()))?,
            Swatch::Ring(col) => root.draw(&Circle::new(c, 5, col.stroke_width(2)))?,
            Swatch::Kept => {
                root.draw(&Circle::new(c, 5, RGBColor(90, 90, 90).filled()))?;
                root.draw(&Circle::new(c, 2, WHITE.filled()))?;
            }
            Swatch::Split(n) => {
                let greys = [RGBColor(60, 60, 60), RGBColor(190, 190, 190)];
                for k in 0..n.min(2) {
                    shape(root, c, &sector(k, n, 6), greys[k], true)?;
                }
            }
            Swatch::Cross(col) => root.draw(&Cross::new(c, 4, col.stroke_width(2)))?,
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

/// Tick marks and labels at the given values of both axes of a chart (`plot`: its plotting
/// area; `area`: the drawing area the chart was built on), in the chart's scale: the ticks a
/// log axis of plotters would not draw at a sweep's grid values. Values outside the plot are
/// skipped.
pub(crate) fn hand_ticks<CT>(
    area: &DrawingArea<SVGBackend, Shift>,
    plot: &DrawingArea<SVGBackend, CT>,
    xs: &[f64],
    ys: &[f64],
) -> Result<(), DrawingAreaErrorKind<std::io::Error>>
where
    CT: plotters::coord::CoordTranslate<From = (f64, f64)>,
{
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let (xr, yr) = plot.get_pixel_range();
    let base = area.get_base_pixel();
    let font = TextStyle::from(("sans-serif", 12).into_font());
    let below = font.pos(Pos::new(HPos::Center, VPos::Top));
    let left = font.pos(Pos::new(HPos::Right, VPos::Center));
    let (left_edge, bottom) = (xr.start - base.0, yr.end - base.1);
    let y_any = ys.first().copied().unwrap_or(1.0);
    let x_any = xs.first().copied().unwrap_or(1.0);
    // The x ticks below the plot, then the y ticks left of it.
    for (values, on_x) in [(xs, true), (ys, false)] {
        for &t in values {
            let (px, py) = plot.map_coordinate(&if on_x { (t, y_any) } else { (x_any, t) });
            let (tick, at, style) = if on_x {
                if px < xr.start || px > xr.end {
                    continue;
                }
                let x = px - base.0;
                ([(x, bottom), (x, bottom + 5)], (x, bottom + 7), &below)
            } else {
                if py < yr.start || py > yr.end {
                    continue;
                }
                let y = py - base.1;
                (
                    [(left_edge - 5, y), (left_edge, y)],
                    (left_edge - 7, y),
                    &left,
                )
            };
            area.draw(&PathElement::new(tick, BLACK.stroke_width(1)))?;
            area.draw(&Text::new(super::svg::label(t), at, style.clone()))?;
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
