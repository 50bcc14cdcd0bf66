//! One run's time series as SVG (`wetgran show --series`, the report's point pages): whether the
//! run settled, at a glance. Stacked panels against time: `T_g / E_cb` (`T_g / m g d` dry; log
//! when it spans more than a factor of 20), bridges per grain and `Delta n_cb` (wet scenes), each
//! with the block means of the tested stretch (`trend.tests`, the numbers the settling test
//! compared) as steps with their errors. `Delta n_cb` is stored per block only (the monitored
//! per-sample values are not kept), so its panel shows the block means alone. Every time panel
//! marks the transient (grey: from 0 to where MSER found the history relaxed), the window the
//! averages cover (blue band), the policy's checks (ticks at the top) and the run's end (a red
//! line for a run stopped by its cap, green for a settled one). A coexistence adds a panel of
//! its regions' temperatures (`trend.region_tests`: bonded-cluster members and the other grains),
//! each block mean over its own tested history, so that panel is against block number, not time.
//!
//! Each panel is a `<g class="panel" data-quantity="...">`, its sampled curve a `<path
//! class="samples">`, its block means `<path class="blocks">`, the marks `<rect class=
//! "transient">`, `<rect class="window">`, `<line class="ending">`: tests and scripts read them.

use super::svg::{esc, label, n};
use std::fmt::Write;
use wetgran_core::observe::Observables;
use wetgran_core::observe::convergence::BlockTest;
use wetgran_core::observe::settling::{MEMBER_TEMPERATURE, UNBONDED_TEMPERATURE};
use wetgran_core::observe::trend::{BRIDGES, DELTA_N_CB, Ending, TEMPERATURE};

const WIDTH: f64 = 780.0;
const PANEL_H: f64 = 130.0;
const GAP: f64 = 44.0;
const LEFT: f64 = 78.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 62.0;

/// One panel: its title, its id, its sampled curve `(t, value)` and its block tests (each drawn
/// as steps over `[from, to]` of the trend, or against block number where `by_block`).
struct Panel<'a> {
    title: String,
    quantity: &'static str,
    samples: Vec<(f64, f64)>,
    blocks: Vec<(&'a BlockTest, &'static str, &'static str)>,
    by_block: bool,
}

/// The panels of a result, in drawing order (module doc); `coexistence`: its label names a
/// dense and a dilute region.
fn panels(obs: &Observables, coexistence: bool) -> Vec<Panel<'_>> {
    let unit = &obs.temperature_unit_name;
    let wet = unit == "E_cb";
    let trend = obs.trend.as_ref();
    let test = |name: &str| trend.and_then(|t| t.tests.iter().find(|b| b.quantity == name));
    let region =
        |name: &str| trend.and_then(|t| t.region_tests.iter().find(|b| b.quantity == name));
    let series = obs.series.as_ref();
    let pairs = |v: Option<&Vec<f64>>| -> Vec<(f64, f64)> {
        match (series, v) {
            (Some(s), Some(v)) => s.time.iter().copied().zip(v.iter().copied()).collect(),
            _ => Vec::new(),
        }
    };
    let mut out = vec![Panel {
        title: format!("T_g / {unit}, whole system"),
        quantity: "temperature",
        samples: pairs(series.map(|s| &s.temperature_reduced)),
        blocks: test(TEMPERATURE)
            .map(|b| (b, "#d62728", "block means"))
            .into_iter()
            .collect(),
        by_block: false,
    }];
    if wet {
        out.push(Panel {
            title: "bridges per grain".to_string(),
            quantity: "bridges",
            samples: pairs(series.map(|s| &s.bridges_per_particle)),
            blocks: test(BRIDGES)
                .map(|b| (b, "#d62728", "block means"))
                .into_iter()
                .collect(),
            by_block: false,
        });
        out.push(Panel {
            title: "Delta n_cb (block means of the tested stretch; per-sample values are not \
                    stored)"
                .to_string(),
            quantity: "delta_n_cb",
            samples: Vec::new(),
            blocks: test(DELTA_N_CB)
                .map(|b| (b, "#d62728", "block means"))
                .into_iter()
                .collect(),
            by_block: false,
        });
    }
    let regions: Vec<_> = [
        (MEMBER_TEMPERATURE, "#1f77b4", "dense: cluster members"),
        (UNBONDED_TEMPERATURE, "#ff7f0e", "dilute: other grains"),
    ]
    .into_iter()
    .filter_map(|(q, c, what)| region(q).map(|b| (b, c, what)))
    .filter(|(b, _, _)| !b.block_means.is_empty())
    .collect();
    if coexistence && !regions.is_empty() {
        out.push(Panel {
            title: format!(
                "T_g / {unit} per region: block means, each over its own tested history"
            ),
            quantity: "regions",
            samples: Vec::new(),
            blocks: regions,
            by_block: true,
        });
    }
    out
}

/// The value range of a panel (with the error bars) and whether it is logarithmic.
fn range(p: &Panel) -> ((f64, f64), bool) {
    let mut vals: Vec<f64> = p.samples.iter().map(|s| s.1).collect();
    for (b, _, _) in &p.blocks {
        for (m, e) in b
            .block_means
            .iter()
            .zip(b.block_errors.iter().chain(std::iter::repeat(&0.0)))
        {
            let e = if e.is_finite() { *e } else { 0.0 };
            vals.extend([m - e, m + e]);
        }
    }
    vals.retain(|v| v.is_finite());
    let lo = vals.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = vals.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !lo.is_finite() {
        return ((0.0, 1.0), false);
    }
    let positive = vals
        .iter()
        .copied()
        .filter(|v| *v > 0.0)
        .fold(f64::INFINITY, f64::min);
    let temperature = p.quantity == "temperature" || p.quantity == "regions";
    if temperature && positive.is_finite() && hi / positive > 20.0 {
        return ((positive / 1.3, hi * 1.3), true);
    }
    let (lo, hi) = if hi - lo < 1e-12 * hi.abs().max(1e-12) {
        let pad = 0.5 * hi.abs().max(1e-3);
        (lo - pad, hi + pad)
    } else {
        (lo, hi)
    };
    let pad = 0.06 * (hi - lo);
    ((lo - pad, hi + pad), false)
}

/// Round tick values inside `[lo, hi]`: multiples of 1, 2 or 5 times a power of ten, about
/// `want` of them (exact multiples, so no float noise such as `-1.4e-17` shows).
fn nice_ticks(lo: f64, hi: f64, want: usize) -> Vec<f64> {
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return vec![lo];
    }
    let raw = (hi - lo) / want.max(1) as f64;
    let p = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p);
    let (a, b) = ((lo / step).ceil() as i64, (hi / step).floor() as i64);
    (a..=b)
        .map(|k| {
            let v = k as f64 * step;
            // Round away the last bits of the product (0.30000000000000004).
            let digits = (-step.log10().floor()).max(0.0) as i32 + 1;
            let f = 10f64.powi(digits);
            (v * f).round() / f
        })
        .collect()
}

/// The time of a result's end: its last sample, else the window's end.
fn end_time(obs: &Observables) -> f64 {
    obs.series
        .as_ref()
        .and_then(|s| s.time.last().copied())
        .unwrap_or(obs.window_end)
        .max(obs.window_end)
}

/// The policy's check times: the first check, then one window later each (module doc of
/// `observe::run`; the window length is the stored window's).
fn checks(obs: &Observables) -> Vec<f64> {
    let Some(p) = obs.trend.as_ref().and_then(|t| t.policy.as_ref()) else {
        return Vec::new();
    };
    let w = obs.window_end - obs.window_start;
    (0..p.checks)
        .map(|k| p.first_check + k as f64 * w)
        .filter(|t| w > 0.0 && *t <= end_time(obs) + 1e-9)
        .collect()
}

/// How the run ended, in words, with the colour of its mark.
pub fn ending_words(obs: &Observables) -> (String, &'static str) {
    let end = end_time(obs);
    match obs.trend.as_ref().and_then(|t| t.policy.as_ref()) {
        Some(p) => match p.ending {
            Ending::Stationary => (
                format!(
                    "ended at t = {}: stationary (check {})",
                    label(end),
                    p.checks
                ),
                "#2ca02c",
            ),
            Ending::Settled => (
                format!(
                    "ended at t = {}: settled, label kept at two checks in a row (check {})",
                    label(end),
                    p.checks
                ),
                "#2ca02c",
            ),
            Ending::Cap => (
                format!(
                    "ended at t = {}: reached the cap t = {} before its label settled",
                    label(end),
                    label(p.cap)
                ),
                "#d62728",
            ),
        },
        None => (
            format!("ended at t = {} (fixed run length)", label(end)),
            "#444444",
        ),
    }
}

/// The pixel mapping of one panel: its top `y0`, its value range (log or not) and its x range
/// (time, or block number).
struct Axes {
    y0: f64,
    lo: f64,
    hi: f64,
    log: bool,
    x_lo: f64,
    x_hi: f64,
}

impl Axes {
    fn px(&self, t: f64) -> f64 {
        LEFT + (t - self.x_lo) / (self.x_hi - self.x_lo) * (WIDTH - LEFT - RIGHT)
    }

    fn py(&self, v: f64) -> f64 {
        let f = |v: f64| if self.log { v.max(self.lo).log10() } else { v };
        self.y0 + PANEL_H - (f(v) - f(self.lo)) / (f(self.hi) - f(self.lo)) * PANEL_H
    }
}

/// The transient, the window and the checks of a time panel.
fn draw_marks(s: &mut String, obs: &Observables, ax: &Axes, t_end: f64, relaxed: Option<f64>) {
    let (px, y0) = (|t: f64| ax.px(t), ax.y0);
    if let Some(r) = relaxed.filter(|r| *r > 0.0) {
        let _ = writeln!(
            s,
            "<rect class=\"transient\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{PANEL_H}\" \
             fill=\"#dddddd\"/>",
            n(px(0.0)),
            n(y0),
            n(px(r.min(t_end)) - px(0.0))
        );
    }
    let _ = writeln!(
        s,
        "<rect class=\"window\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{PANEL_H}\" \
         fill=\"#1f77b4\" fill-opacity=\"0.12\"/>",
        n(px(obs.window_start)),
        n(y0),
        n(px(obs.window_end) - px(obs.window_start))
    );
    for c in checks(obs) {
        let _ = writeln!(
            s,
            "<line class=\"check\" x1=\"{0}\" x2=\"{0}\" y1=\"{1}\" y2=\"{2}\" stroke=\"black\"/>",
            n(px(c)),
            n(y0),
            n(y0 + 7.0)
        );
    }
}

/// The ticks and labels of a panel's axes.
fn draw_ticks(s: &mut String, p: &Panel, ax: &Axes, blocks_n: usize, t_end: f64) {
    let (px, py, y0, lo, hi, log) = (
        |t: f64| ax.px(t),
        |v: f64| ax.py(v),
        ax.y0,
        ax.lo,
        ax.hi,
        ax.log,
    );
    let pw = WIDTH - LEFT - RIGHT;
    // y ticks: decades on a log axis, else three values.
    let ticks: Vec<f64> = if log {
        let (a, b) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
        (a..=b).map(|e| 10f64.powi(e)).collect()
    } else {
        nice_ticks(lo, hi, 4)
    };
    for v in ticks {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
            n(LEFT - 4.0),
            n(py(v) + 4.0),
            label(v)
        );
    }
    let x_ticks: Vec<f64> = if p.by_block {
        (1..=blocks_n).map(|b| b as f64).collect()
    } else {
        nice_ticks(0.0, t_end, 6)
    };
    for x in x_ticks {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
            n(px(x)),
            n(y0 + PANEL_H + 13.0),
            label(x)
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
        n(LEFT + pw),
        n(y0 + PANEL_H + 27.0),
        if p.by_block {
            "block of the tested history"
        } else {
            "t (time units)"
        }
    );
}

/// A panel's sampled curve and its block means with their errors and verdicts.
fn draw_data(s: &mut String, obs: &Observables, p: &Panel, ax: &Axes, t_end: f64) {
    let (px, py, y0) = (|t: f64| ax.px(t), |v: f64| ax.py(v), ax.y0);
    let pw = WIDTH - LEFT - RIGHT;
    if !p.samples.is_empty() {
        let mut d = String::new();
        for (i, (t, v)) in p.samples.iter().filter(|(_, v)| v.is_finite()).enumerate() {
            let _ = write!(
                d,
                "{}{} {}",
                if i == 0 { "M" } else { "L" },
                n(px(*t)),
                n(py(*v))
            );
        }
        let _ = writeln!(
            s,
            "<path class=\"samples\" d=\"{d}\" fill=\"none\" stroke=\"#555555\" stroke-width=\"0.8\"/>"
        );
    }
    let (from, to) = obs.trend.as_ref().map_or((0.0, t_end), |t| (t.from, t.to));
    for (legend_row, (b, colour, what)) in p.blocks.iter().enumerate() {
        let m = b.block_means.len();
        if m == 0 {
            continue;
        }
        let span = |i: usize| -> (f64, f64) {
            if p.by_block {
                (i as f64 + 0.6, i as f64 + 1.4)
            } else {
                let w = (to - from) / m as f64;
                (from + i as f64 * w, from + (i + 1) as f64 * w)
            }
        };
        let mut d = String::new();
        for (i, v) in b.block_means.iter().enumerate() {
            let (a, z) = span(i);
            let _ = write!(d, "M{} {}H{}", n(px(a)), n(py(*v)), n(px(z)));
            if let Some(e) = b.block_errors.get(i).filter(|e| e.is_finite() && **e > 0.0) {
                let c = px(0.5 * (a + z));
                let _ = write!(d, "M{} {}V{}", n(c), n(py(v - e)), n(py(v + e)));
            }
        }
        let _ = writeln!(
            s,
            "<path class=\"blocks\" data-quantity=\"{}\" d=\"{d}\" fill=\"none\" stroke=\"{colour}\" \
             stroke-width=\"2\"/>",
            esc(&b.quantity)
        );
        let verdict = if b.ok() {
            "flat"
        } else if b.no_trend {
            "blocks disagree"
        } else {
            "drifts"
        };
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\" fill=\"{colour}\">{what}: {}, drift {} +- {}</text>",
            n(LEFT + pw - 4.0),
            n(y0 + 12.0 + 13.0 * legend_row as f64),
            verdict,
            label(b.drift),
            label(b.drift_error)
        );
    }
}

/// The SVG of a result's time series; `title` heads it (the job and its label), `phase` is its
/// label (a coexistence, `sfc`, `sgc` or `fgc`, adds the regions' panel).
pub fn series_svg(obs: &Observables, title: &str, phase: Option<&str>) -> String {
    let coexistence = phase.is_some_and(|p| p.len() == 3 && p.ends_with('c'));
    let panels = panels(obs, coexistence);
    let h = TOP + panels.len() as f64 * (PANEL_H + GAP) + 10.0;
    let pw = WIDTH - LEFT - RIGHT;
    let t_end = end_time(obs);
    let relaxed = obs.trend.as_ref().map(|t| t.relaxed_at);
    let (ending, ending_colour) = ending_words(obs);
    let mut s = super::svg::open(WIDTH, h);
    let _ = writeln!(s, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
    let _ = writeln!(
        s,
        "<text x=\"{LEFT}\" y=\"16\" font-size=\"13\">{}</text>",
        esc(title)
    );
    let _ = writeln!(
        s,
        "<text x=\"{LEFT}\" y=\"32\">grey: transient (relaxed at t = {}); blue: window t = {} .. {} \
         (the averages); red steps: block means of the tested stretch t = {} .. {}; ticks: checks</text>",
        relaxed.map_or("?".to_string(), label),
        label(obs.window_start),
        label(obs.window_end),
        obs.trend
            .as_ref()
            .map_or("?".to_string(), |t| label(t.from)),
        obs.trend.as_ref().map_or("?".to_string(), |t| label(t.to)),
    );
    let _ = writeln!(
        s,
        "<text x=\"{LEFT}\" y=\"47\" fill=\"{ending_colour}\">{}</text>",
        esc(&ending)
    );
    for (k, p) in panels.iter().enumerate() {
        let y0 = TOP + k as f64 * (PANEL_H + GAP);
        let ((lo, hi), log) = range(p);
        let blocks_n = p
            .blocks
            .iter()
            .map(|b| b.0.block_means.len())
            .max()
            .unwrap_or(1)
            .max(1);
        let (x_lo, x_hi) = if p.by_block {
            (0.5, blocks_n as f64 + 0.5)
        } else {
            (0.0, t_end.max(1e-9))
        };
        let _ = writeln!(s, "<g class=\"panel\" data-quantity=\"{}\">", p.quantity);
        let _ = writeln!(
            s,
            "<text x=\"{LEFT}\" y=\"{}\">{}</text>",
            n(y0 - 5.0),
            esc(&p.title)
        );
        let ax = Axes {
            y0,
            lo,
            hi,
            log,
            x_lo,
            x_hi,
        };
        if !p.by_block {
            draw_marks(&mut s, obs, &ax, t_end, relaxed);
        }
        let _ = writeln!(
            s,
            "<rect x=\"{LEFT}\" y=\"{}\" width=\"{}\" height=\"{PANEL_H}\" fill=\"none\" stroke=\"black\"/>",
            n(y0),
            n(pw)
        );
        draw_ticks(&mut s, p, &ax, blocks_n, t_end);
        draw_data(&mut s, obs, p, &ax, t_end);
        if !p.by_block {
            let _ = writeln!(
                s,
                "<line class=\"ending\" x1=\"{0}\" x2=\"{0}\" y1=\"{1}\" y2=\"{2}\" stroke=\"{ending_colour}\" \
                 stroke-width=\"2\"/>",
                n(ax.px(t_end)),
                n(y0),
                n(y0 + PANEL_H)
            );
        }
        if p.samples.is_empty() && p.blocks.is_empty() {
            let _ = writeln!(
                s,
                "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">not stored for this result</text>",
                n(LEFT + pw / 2.0),
                n(y0 + PANEL_H / 2.0)
            );
        }
        let _ = writeln!(s, "</g>");
    }
    s.push_str("</svg>\n");
    s
}
