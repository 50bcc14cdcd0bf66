//! The lateral-profile plot: `T_g / E_cb`, packing fraction, bridge density `n_cb`, the
//! mobility `D_lat` and (when observed) `f_lc` against `x`, one stacked panel each,
//! time-averaged over the window. With 3D plane bins each panel is a map over `(x, y)`
//! (darker is larger). Ticks at steps of 1, 2 or 5 times a power of ten, one format per axis
//! (`report::ticks`); `x` in grain diameters; names typeset (`report::typeset`). The packing
//! and `n_cb` panels carry error bars of one standard error (`Profiles::packing_standard_error`,
//! `n_cb_standard_error`: the root mean square over the bins of each bin's block standard error,
//! so one bar length for every bin); the others store no per-bin error and have none.

use super::svg::{esc, label, n};
use std::fmt::Write;
use wetgran_core::observe::Observables;

/// One panel of the profile plot: its title, its value per bin (`None`: no value) and the
/// standard error of a bin's value where one is stored.
struct Panel {
    title: String,
    values: Vec<Option<f64>>,
    standard_error: Option<f64>,
}

/// The profiles plotted, one panel each.
fn profile_panels(obs: &Observables) -> Vec<Panel> {
    let p = &obs.profiles;
    let unit = &obs.temperature_unit_name;
    let panel = |title: String, values: Vec<Option<f64>>, standard_error: Option<f64>| Panel {
        title,
        values,
        standard_error,
    };
    let mut panels = vec![
        panel(format!("T_g / {unit}"), p.temperature_reduced.clone(), None),
        panel(
            if obs.dimension == 2 {
                "packing fraction (areal)".to_string()
            } else {
                "packing fraction (volume)".to_string()
            },
            p.packing.iter().map(|&x| Some(x)).collect(),
            p.packing_standard_error,
        ),
        panel(
            format!(
                "n_cb (bridges per d^{}, averaged over the height), Delta n_cb = {}",
                obs.dimension,
                label(p.delta_n_cb)
            ),
            p.n_cb.iter().map(|&x| Some(x)).collect(),
            p.n_cb_standard_error,
        ),
    ];
    if !p.diffusion.is_empty() {
        panels.push(panel(
            "D_lat (lateral mobility, d^2 per time unit)".to_string(),
            p.diffusion.clone(),
            None,
        ));
    }
    if let Some(f) = &p.flc {
        panels.push(panel(
            "f_lc (per particle per time unit)".to_string(),
            f.iter().map(|&x| Some(x)).collect(),
            None,
        ));
    }
    panels
}

/// SVG of the lateral profiles of one result.
pub fn profiles_svg(obs: &Observables) -> String {
    let p = &obs.profiles;
    let panels = profile_panels(obs);
    if let Some((nx, ny)) = p.grid {
        return maps_svg(obs, &panels, nx, ny);
    }
    let (w, ph, ml, mr, mt, gap) = (760.0, 120.0, 70.0, 20.0, 44.0, 40.0);
    let h = mt + panels.len() as f64 * (ph + gap) + 10.0;
    let pw = w - ml - mr;
    let lx = p.centres.len() as f64 * p.bin_width;
    let mut s = super::svg::open(w, h);
    let _ = writeln!(s, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
    let _ = writeln!(
        s,
        "<text x=\"{ml}\" y=\"16\">lateral profiles, window t = {:.2} .. {:.2} ({} samples), bin width {:.3} d</text>",
        obs.window_start, obs.window_end, obs.window_samples, p.bin_width
    );
    for (k, panel) in panels.iter().enumerate() {
        let (name, values) = (&panel.title, &panel.values);
        let se = panel.standard_error.filter(|e| e.is_finite() && *e > 0.0);
        let y0 = mt + k as f64 * (ph + gap);
        let vals: Vec<f64> = values.iter().flatten().copied().collect();
        let (lo, hi) = value_range(&vals, se.unwrap_or(0.0));
        let px = |x: f64| ml + x / lx * pw;
        let py = |v: f64| y0 + ph - (v - lo) / (hi - lo) * ph;
        let _ = writeln!(
            s,
            "<rect x=\"{ml}\" y=\"{}\" width=\"{}\" height=\"{ph}\" fill=\"none\" stroke=\"black\"/>",
            n(y0),
            n(pw)
        );
        let _ = writeln!(
            s,
            "<text x=\"{ml}\" y=\"{}\">{}{}{}</text>",
            n(y0 - 4.0),
            super::typeset::MARK,
            esc(name),
            if se.is_some() {
                "; bars: one standard error"
            } else {
                ""
            }
        );
        for t in super::ticks::axis_ticks((lo, hi), false) {
            let Some(text) = t.label else { continue };
            let y = py(t.value);
            let _ = writeln!(
                s,
                "<path d=\"M{} {}H{}\" stroke=\"black\"/><text x=\"{}\" y=\"{}\" \
                 text-anchor=\"end\">{}</text>",
                n(ml - 4.0),
                n(y),
                n(ml),
                n(ml - 6.0),
                n(y + 4.0),
                text
            );
        }
        for t in super::ticks::axis_ticks((0.0, lx), false) {
            let Some(text) = t.label else { continue };
            let x = px(t.value);
            let _ = writeln!(
                s,
                "<path d=\"M{} {}V{}\" stroke=\"black\"/><text x=\"{}\" y=\"{}\" \
                 text-anchor=\"middle\">{}</text>",
                n(x),
                n(y0 + ph),
                n(y0 + ph + 4.0),
                n(x),
                n(y0 + ph + 15.0),
                text
            );
        }
        // One polyline per run of bins with values.
        let mut path = String::new();
        let mut pen = false;
        for (b, v) in values.iter().enumerate() {
            match v {
                Some(v) => {
                    let _ = write!(
                        path,
                        "{}{} {}",
                        if pen { "L" } else { "M" },
                        n(px(p.centres[b])),
                        n(py(*v))
                    );
                    pen = true;
                }
                None => pen = false,
            }
        }
        let _ = writeln!(
            s,
            "<path d=\"{path}\" fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"1.5\"/>"
        );
        if vals.is_empty() {
            // Say so rather than leave an empty frame (D_lat of a run shorter than its lag).
            let _ = writeln!(
                s,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" fill=\"#555\">no value in any \
                 bin</text>",
                n(ml + pw / 2.0),
                n(y0 + ph / 2.0)
            );
        }
        if let Some(e) = se {
            s.push_str(&error_bars(values, &p.centres, e, &px, &py));
        }
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\"><tspan font-style=\"italic\">x</tspan> \
         (grain diameters <tspan font-style=\"italic\">d</tspan>)</text>",
        n(ml + pw / 2.0),
        n(h - 2.0)
    );
    s.push_str("</svg>\n");
    super::typeset::typeset_svg(&s)
}

/// The value axis of a panel: the values with their bars (`bar`: half a bar's length), widened
/// where they are all equal and padded by 5 % on each side; `(0, 1)` without values.
fn value_range(vals: &[f64], bar: f64) -> (f64, f64) {
    let (mut lo, mut hi) = vals
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v - bar), b.max(v + bar))
        });
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    if hi - lo < 1e-12 * hi.abs().max(1.0) {
        let pad = 0.5 * hi.abs().max(1e-3);
        (lo, hi) = (lo - pad, hi + pad);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// The bars of +- one standard error `e` with caps at each bin with a value, one SVG path
/// (`px`, `py`: the panel's scales).
fn error_bars(
    values: &[Option<f64>],
    centres: &[f64],
    e: f64,
    px: &dyn Fn(f64) -> f64,
    py: &dyn Fn(f64) -> f64,
) -> String {
    const CAP: f64 = 3.0;
    let mut bars = String::new();
    for (b, v) in values.iter().enumerate() {
        let Some(v) = v else { continue };
        let (x, top, bottom) = (px(centres[b]), py(v + e), py(v - e));
        let _ = write!(
            bars,
            "M{} {}V{}M{} {}H{}M{} {}H{}",
            n(x),
            n(top),
            n(bottom),
            n(x - CAP),
            n(top),
            n(x + CAP),
            n(x - CAP),
            n(bottom),
            n(x + CAP)
        );
    }
    format!(
        "<path class=\"errorbar\" d=\"{bars}\" fill=\"none\" stroke=\"#1f77b4\" \
         stroke-width=\"1\"/>\n"
    )
}

/// The panels as maps over the lateral plane (3D plane bins, numbered `ix + nx iy`).
fn maps_svg(obs: &Observables, panels: &[Panel], nx: usize, ny: usize) -> String {
    let p = &obs.profiles;
    let (ml, mt, gap, pw) = (20.0, 44.0, 40.0, 360.0);
    let ph = (pw * ny as f64 / nx as f64).min(360.0);
    let cols = 2usize;
    let rows = panels.len().div_ceil(cols);
    let w = ml + cols as f64 * (pw + gap);
    let h = mt + rows as f64 * (ph + gap) + 10.0;
    let mut s = super::svg::open(w, h);
    let _ = writeln!(s, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
    let _ = writeln!(
        s,
        "<text x=\"{ml}\" y=\"16\">lateral maps over (x, y), window t = {:.2} .. {:.2} ({} samples), cells {:.3} x {:.3}</text>",
        obs.window_start,
        obs.window_end,
        obs.window_samples,
        p.bin_width,
        p.bin_width_y.unwrap_or(p.bin_width)
    );
    let (cw, ch) = (pw / nx as f64, ph / ny as f64);
    for (k, panel) in panels.iter().enumerate() {
        let (name, values) = (&panel.title, &panel.values);
        let x0 = ml + (k % cols) as f64 * (pw + gap);
        let y0 = mt + (k / cols) as f64 * (ph + gap);
        let vals: Vec<f64> = values.iter().flatten().copied().collect();
        let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\">{} [{} .. {}]</text>",
            n(x0),
            n(y0 - 4.0),
            // The short name: the maps sit side by side.
            esc(name
                .split(" (")
                .next()
                .unwrap_or(name)
                .split(',')
                .next()
                .unwrap_or(name)),
            label(lo),
            label(hi)
        );
        for (b, v) in values.iter().enumerate() {
            let (ix, iy) = (b % nx, b / nx);
            let fill = match v {
                Some(v) if hi > lo => {
                    let g = (255.0 * (1.0 - (v - lo) / (hi - lo))).round() as u8;
                    format!("rgb({g},{g},255)")
                }
                Some(_) => "rgb(128,128,255)".to_string(),
                None => "rgb(230,230,230)".to_string(),
            };
            let _ = writeln!(
                s,
                "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"{fill}\"/>",
                n(x0 + ix as f64 * cw),
                n(y0 + ph - (iy + 1) as f64 * ch),
                n(cw + 0.3),
                n(ch + 0.3)
            );
        }
        let _ = writeln!(
            s,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>",
            n(x0),
            n(y0),
            n(pw),
            n(ph)
        );
    }
    s.push_str("</svg>\n");
    s
}
