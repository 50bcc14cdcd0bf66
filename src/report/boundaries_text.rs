//! The text of `wetgran boundaries`: the phase map of each sweep as a grid with its boundary
//! points (table), or as CSV; the chain-model note of shear sweeps and the trust marks of the
//! grid points. Pure functions of the phase maps and the stored rows.

use super::trust::{LABEL_KEPT, NOT_STATIONARY, mark};
use crate::boundary::{Extraction, PhaseMap};
use crate::report::plot_phase;
use crate::run::runner::short;
use crate::store::{PointSummary, SweepRow};
use std::collections::HashMap;
use std::fmt::Write as _;
use wetgran_core::observe::criterion::{Criterion, DecidedBy};

/// A number in short form, or nothing.
fn opt_num(v: Option<f64>) -> String {
    v.map(short).unwrap_or_default()
}

/// The fixed coordinates of a slice: `label = value, ...`.
pub fn fixed_text(fixed: &[(String, serde_json::Value)]) -> String {
    fixed
        .iter()
        .map(|(l, v)| format!("{l} = {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `boundaries --format csv`: the points and the boundary points of each sweep's map.
pub fn boundaries_csv(maps: &[(&SweepRow, PhaseMap)]) -> String {
    let mut out = String::from(
        "sweep,slice,kind,phase,x_axis,x,y_axis,y,amplitude,omega,x_lo,x_hi,y_lo,y_hi,confidence,branch,\
         decided_by\n",
    );
    let text = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
    for (s, m) in maps {
        let xl = m.x.as_ref().map(|a| a.key.clone()).unwrap_or_default();
        let yl = m.y.as_ref().map(|a| a.key.clone()).unwrap_or_default();
        for (k, slice) in m.slices.iter().enumerate() {
            // The branch (start mode) of a sweep with an `initial.start` axis; empty otherwise.
            let branch = slice.branch.as_deref().unwrap_or("");
            for p in &slice.points {
                let _ = writeln!(
                    out,
                    "{},{k},point,{},{xl},{},{yl},{},{},{},,,,,,{branch},{}",
                    s.name,
                    p.phase,
                    p.x,
                    p.y,
                    text(p.amplitude),
                    text(p.omega),
                    p.decided_by.as_ref().map_or("", |d| d.criterion.name())
                );
            }
            for b in slice.boundaries.values().flatten() {
                let _ = writeln!(
                    out,
                    "{},{k},boundary,{},{xl},{},{yl},{},{},{},{},{},{},{},{},{branch},",
                    s.name,
                    b.pair,
                    b.x,
                    b.y,
                    text(b.amplitude),
                    text(b.omega),
                    b.x_range[0],
                    b.x_range[1],
                    b.y_range[0],
                    b.y_range[1],
                    b.confidence
                );
            }
        }
    }
    out
}

/// For shear sweeps of wet scenes: the chain model's critical force (docs/model.md 8, Eq. 7.9),
/// `F_max = 0.9229 F_B d / L_x`, over the sweep's points (a range if the axes change it).
pub fn chain_model_note(points: &[PointSummary]) -> Option<String> {
    let values: Vec<f64> = points
        .iter()
        .filter(|p| p.scene.shear_slabs().is_some())
        .filter_map(|p| plot_phase::chain_model_f_max(&p.scene))
        .collect();
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if values.is_empty() {
        return None;
    }
    let value = if hi - lo <= 1e-12 * hi.abs() {
        format!("F_max = {}", short(lo))
    } else {
        format!("F_max from {} to {} over the points", short(lo), short(hi))
    };
    Some(format!(
        "  chain model (docs/model.md 8, Eq. 7.9: solid while F_max L_x / (F_B d) <= {}): {value}",
        plot_phase::CHAIN_MODEL_CONSTANT
    ))
}

/// The grid points (their coordinates as JSON text) with a replica whose result carries a trust
/// mark (`report::trust`), with the mark.
pub fn untrusted_points(points: &[PointSummary]) -> HashMap<String, char> {
    let mut marks = HashMap::new();
    for p in points {
        let Some(mark) = mark(p.trust()) else {
            continue;
        };
        // Among replicas, a label that may change outweighs one that is kept.
        let e = marks
            .entry(serde_json::Value::from(p.coords.clone()).to_string())
            .or_insert(mark);
        if mark == NOT_STATIONARY {
            *e = mark;
        }
    }
    marks
}

/// `boundaries` (table): per sweep and slice, the phase map as a grid and the boundary
/// points by phase pair; `points` are each map's `Store::point_summaries`, for the chain-model
/// note under the sweep's name and the trust marks of the grid points.
pub fn boundaries_table(
    maps: &[(&SweepRow, PhaseMap)],
    points: &[Vec<PointSummary>],
    how: Extraction,
) -> String {
    let mut out = String::new();
    for ((s, m), points) in maps.iter().zip(points) {
        let _ = writeln!(out, "sweep {}", crate::terminal::escape(&s.name));
        if let Some(n) = chain_model_note(points) {
            let _ = writeln!(out, "{n}");
        }
        let marks = untrusted_points(points);
        let (Some(xa), ya) = (&m.x, &m.y) else {
            let _ = writeln!(out, "  no numeric axis: no phase map\n");
            continue;
        };
        let ylabel = ya.as_ref().map(|a| a.label.as_str()).unwrap_or("");
        for slice in &m.slices {
            // A start axis makes each slice one branch (hot, cold, continued start).
            let branch = slice
                .branch
                .as_deref()
                .map(|b| format!(", branch: {}", crate::boundary::branch_words(b)))
                .unwrap_or_default();
            if !slice.fixed.is_empty() {
                let _ = writeln!(out, "  slice {}{branch}", fixed_text(&slice.fixed));
            }
            if slice.points.is_empty() {
                let _ = writeln!(out, "  no classified point yet\n");
                continue;
            }
            // The map as a grid: rows = y (top: largest), columns = x.
            let mut xs: Vec<f64> = slice.points.iter().map(|p| p.x).collect();
            let mut ys: Vec<f64> = slice.points.iter().map(|p| p.y).collect();
            xs.sort_by(f64::total_cmp);
            xs.dedup();
            ys.sort_by(f64::total_cmp);
            ys.dedup();
            if xs.len() > 24 || ys.len() > 60 {
                // A refined map is no grid: list counts only (the points are in csv/json).
                let _ = writeln!(
                    out,
                    "  phase map: {} points ({} x values, {} y values; see --format csv)",
                    slice.points.len(),
                    xs.len(),
                    ys.len()
                );
            } else {
                write_grid(&mut out, slice, xa, ya.as_ref(), &xs, &ys, &marks);
            }
            let unconverged = slice.points.iter().filter(|p| !p.trusted).count();
            if unconverged > 0 {
                let _ = writeln!(
                    out,
                    "  {unconverged} point(s) not settled, their label may change: {}",
                    if how.include_unconverged {
                        "used for the boundaries as asked (--include-unconverged)"
                    } else {
                        "left out of the boundaries (--include-unconverged uses them)"
                    }
                );
            }
            if slice.boundaries.is_empty() {
                let _ = writeln!(out, "  no boundary: {}\n", no_boundary_reason(slice, how));
                continue;
            }
            let y_text = |v: f64| ya.as_ref().map(|_| short(v)).unwrap_or_default();
            let (a, omega) = if m.shaking { ("A", "omega") } else { ("", "") };
            let error = |log: bool, linear: &str| format!("+-{}", if log { "dec" } else { linear });
            let y_log = ya.as_ref().is_some_and(|a| a.log);
            for (pair, list) in &slice.boundaries {
                let _ = writeln!(out, "  boundary {pair} ({} point(s)){branch}", list.len());
                let head = [
                    &xa.label,
                    ylabel,
                    a,
                    omega,
                    &error(xa.log, "x"),
                    &error(y_log, "y"),
                ];
                table_row(&mut out, head.map(String::from), "conf");
                for b in list {
                    let cells = [
                        short(b.x),
                        y_text(b.y),
                        opt_num(b.amplitude),
                        opt_num(b.omega),
                        short(b.x_half),
                        y_text(b.y_half),
                    ];
                    table_row(&mut out, cells, &format!("{:.2}", b.confidence));
                }
            }
            let _ = writeln!(out);
        }
    }
    out
}

/// Why a slice without boundary points has none: too few points carry one, they all share a
/// phase, or no two neighbours differ.
pub fn no_boundary_reason(slice: &crate::boundary::Slice, how: Extraction) -> &'static str {
    let carriers: Vec<&str> = slice
        .points
        .iter()
        .filter(|p| how.include_unconverged || p.trusted)
        .map(|p| p.phase.as_str())
        .collect();
    if carriers.len() < 2 {
        "fewer than two trusted points"
    } else if carriers.iter().all(|p| *p == carriers[0]) {
        "every point that carries one has the same phase"
    } else {
        "no two neighbours differ"
    }
}

/// A row of a boundary's table: six columns of 10 characters, then the confidence in 6.
fn table_row(out: &mut String, cells: [String; 6], confidence: &str) {
    let line: String = cells.iter().map(|c| format!(" {c:>10}")).collect();
    let _ = writeln!(out, "   {line} {confidence:>6}");
}

/// The phase map of a slice as a grid: rows = y (top: largest), columns = x.
fn write_grid(
    out: &mut String,
    slice: &crate::boundary::Slice,
    xa: &crate::boundary::PlaneAxis,
    ya: Option<&crate::boundary::PlaneAxis>,
    xs: &[f64],
    ys: &[f64],
    marks: &HashMap<String, char>,
) {
    let ylabel = ya.map(|a| a.label.as_str()).unwrap_or("");
    let mark_of = |p: &crate::boundary::MapPoint| {
        marks
            .get(&serde_json::Value::from(p.coords.clone()).to_string())
            .copied()
    };
    let _ = writeln!(
        out,
        "  phase map ({} down, {} across{}{}):",
        if ylabel.is_empty() { "-" } else { ylabel },
        xa.label,
        if slice.points.iter().any(|p| p.tie) {
            "; * = replicas tied"
        } else {
            ""
        },
        {
            let has = |m: char| slice.points.iter().any(|p| mark_of(p) == Some(m));
            let mut legend = String::new();
            if has(NOT_STATIONARY) {
                legend += &format!("; {} = not settled, label may change", NOT_STATIONARY);
            }
            if has(LABEL_KEPT) {
                legend += &format!(
                    "; {} = label kept: its regions settled, numbers still drift",
                    LABEL_KEPT
                );
            }
            legend
        }
    );
    for &yv in ys.iter().rev() {
        let mut row = format!("  {:>9} |", ya.map(|_| short(yv)).unwrap_or_default());
        for &xv in xs {
            let cell = slice
                .points
                .iter()
                .find(|p| p.x == xv && p.y == yv)
                .map(|p| {
                    format!(
                        "{}{}{}{}",
                        p.phase,
                        if p.tie { "*" } else { "" },
                        mark_of(p).map(String::from).unwrap_or_default(),
                        p.decided_by
                            .as_ref()
                            .map(|d| String::from(d.criterion.letter()))
                            .unwrap_or_default()
                    )
                })
                .unwrap_or_else(|| ".".to_string());
            let _ = write!(row, " {cell:>7}");
        }
        let _ = writeln!(out, "{row}");
    }
    let mut axis = format!("  {:>9} +", "");
    for _ in xs {
        axis.push_str("--------");
    }
    let _ = writeln!(out, "{axis}");
    let mut labels = format!("  {:>9}  ", xa.label);
    for &xv in xs {
        let _ = write!(labels, " {:>7}", short(xv));
    }
    let _ = writeln!(out, "{labels}");
    if let Some(legend) = criterion_legend(&slice.points) {
        let _ = writeln!(out, "{legend}");
    }
}

/// The legend of the criterion letters of a phase map's cells (`observe::criterion`): the
/// letters present, and how many points rest on a fallback; `None` where no point has one.
pub fn criterion_legend(points: &[crate::boundary::MapPoint]) -> Option<String> {
    let decided: Vec<&DecidedBy> = points
        .iter()
        .filter_map(|p| p.decided_by.as_ref())
        .collect();
    let mut used: Vec<Criterion> = decided.iter().map(|d| d.criterion).collect();
    used.sort();
    used.dedup();
    if used.is_empty() {
        return None;
    }
    let letters: Vec<String> = used
        .iter()
        .map(|c| format!("{} = {}", c.letter(), c.words()))
        .collect();
    let fallback = decided.iter().filter(|d| d.fallback).count();
    Some(format!(
        "  decided by (letter after the label): {}; {fallback} of {} label(s) rest on a fallback",
        letters.join(", "),
        decided.len()
    ))
}
