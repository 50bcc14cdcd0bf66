//! The order parameters along the lines of constant Gamma of a shaking sweep, from its stored
//! results: for every finished job `T_g / E_cb` (or `T_g / m g d` dry), the bridges per grain and
//! the bridge-density contrast `Delta n_cb` (the packing contrast `Delta n_area` for dry scenes)
//! against `E*`, with their standard errors, the label, the trend state and the trust of the run
//! (`report::trust`). What `wetgran lines` draws (`lines_plot`) and writes as CSV or JSON.
//!
//! Errors: the standard error of the monitored quantity's mean from the blocks of the run's
//! trend test (`observables.trend.tests[].standard_error`, docs/observables.md "Run to a settled
//! label"). Where a run stored no such test (`Delta n_area`, which is not monitored), the contrast's error is `sqrt(2)` times the root mean square of the
//! bins' standard errors (`profiles.n_cb_standard_error`, `profiles.packing_standard_error`): the
//! error of a difference of two bins; the other quantities then have none.
//!
//! The boundary of a line ([`LineBoundary`]): between two neighbouring `E*` of a line (one
//! branch) whose majority labels over trusted replicas differ, at their geometric mean; a grid
//! point without a trusted majority (or with a tie) is stepped over, so a boundary always rests on
//! two trusted labels. The fluid-gas inflection of `T_g` (`observe::fluid_gas_inflection`,
//! docs/model.md 7) is given beside it, over the homogeneous mobile points only, as the line
//! rule takes it: a solid is off the fluid-gas curve, and the whole-system temperature of a
//! coexistence mixes its dense and dilute parts.

use crate::boundary::{START_AXIS, majority};
use crate::store::{PointRow, SweepRow};
use serde::Serialize;
use std::fmt::Write as _;
use wetgran_core::observe::fluid_gas_inflection;
use wetgran_core::observe::trend::TrendState;

/// One finished job on a line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinePoint {
    pub job_id: String,
    pub point: i64,
    pub replica: i64,
    pub e_star: f64,
    pub phase: Option<String>,
    /// The run's trend state (`None` for results stored before trend states).
    pub trend: Option<String>,
    /// The trust mark (`?` label may change, `~` label kept by its trend, `None` stationary).
    pub trust: Option<char>,
    /// Whether the label may carry a boundary (stationary, or a trend that keeps it).
    pub trusted: bool,
    /// `T_g` over the energy unit (`E_cb`, or `m g d` dry) and its standard error.
    pub temperature: f64,
    pub temperature_error: Option<f64>,
    /// Bridges per grain and its standard error (`None` for dry scenes).
    pub bridges: Option<f64>,
    pub bridges_error: Option<f64>,
    /// `Delta n_cb` (wet) or `Delta n_area` (dry) and its standard error.
    pub contrast: f64,
    pub contrast_error: Option<f64>,
}

/// Where the label changes along a line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LineBoundary {
    /// The two labels, low `E*` first (`f|g`).
    pub pair: String,
    /// The geometric mean of the two `E*` that straddle it.
    pub e_star: f64,
    pub between: [f64; 2],
}

/// One line of constant Gamma of one branch.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GammaLine {
    pub gamma: f64,
    /// The start mode (`hot`, `continue`) when the sweep has an `initial.start` axis.
    pub branch: Option<String>,
    /// By increasing `E*`, replicas in order.
    pub points: Vec<LinePoint>,
    pub boundaries: Vec<LineBoundary>,
    /// `E*` of the fluid-gas inflection of `T_g` over the line's homogeneous mobile points
    /// (`None`: fewer than four such points, or no slope that stands out of the scatter).
    pub inflection: Option<f64>,
}

/// The lines of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Lines {
    pub sweep: String,
    /// Wet scene: `Delta n_cb` and bridges; dry: `Delta n_area`, no bridges.
    pub wet: bool,
    /// `E_cb` or `m g d`.
    pub energy_unit: String,
    /// By increasing Gamma, branches in the order the sweep gives them.
    pub lines: Vec<GammaLine>,
    /// Finished jobs left out: no drive motion (not a shaking scene) or no observables.
    pub left_out: usize,
}

impl Lines {
    /// The lines at one Gamma (one per branch).
    pub fn at_gamma(&self, gamma: f64) -> Vec<&GammaLine> {
        self.lines.iter().filter(|l| same(l.gamma, gamma)).collect()
    }

    /// The distinct Gamma values, increasing.
    pub fn gammas(&self) -> Vec<f64> {
        let mut g: Vec<f64> = self.lines.iter().map(|l| l.gamma).collect();
        g.dedup_by(|a, b| same(*a, *b));
        g
    }
}

fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs())
}

pub use crate::run::relabel::gamma_e_star;

/// The stored block test of monitored quantity `name` (`trend.tests`).
pub(crate) fn block_test<'a>(
    obs: &'a serde_json::Value,
    name: &str,
) -> Option<&'a serde_json::Value> {
    obs.pointer("/trend/tests")?
        .as_array()?
        .iter()
        .find(|t| t["quantity"].as_str() == Some(name))
}

/// The block standard error of monitored quantity `name` (module doc).
fn block_error(obs: &serde_json::Value, name: &str) -> Option<f64> {
    block_test(obs, name)?["standard_error"]
        .as_f64()
        .filter(|e| e.is_finite())
}

/// The line point of a finished job, with its branch and Gamma; `None` without observables or
/// drive motion.
/// `axes`: the sweep's `initial.start`, Gamma and `E*` axes (each where it has one); an axis
/// value is taken as written, else the value is derived from the drive.
fn line_point(p: &PointRow, axes: [Option<usize>; 3]) -> Option<(Option<String>, f64, LinePoint)> {
    let obs = p.observables.as_ref()?;
    let (gamma, e_star) = gamma_e_star(&p.spec.scene)?;
    let given = |k: Option<usize>| k.and_then(|k| p.coords.get(k)).and_then(|v| v.as_f64());
    let (gamma, e_star) = (
        given(axes[1]).unwrap_or(gamma),
        given(axes[2]).unwrap_or(e_star),
    );
    let start_axis = axes[0];
    let wet = p.spec.scene.is_wet();
    let num = |ptr: &str| obs.pointer(ptr).and_then(|v| v.as_f64());
    let temperature = num("/granular_temperature_reduced")?;
    let (contrast, bins_error) = match wet {
        true => ("/profiles/delta_n_cb", "/profiles/n_cb_standard_error"),
        false => ("/profiles/delta_n_area", "/profiles/packing_standard_error"),
    };
    let (contrast, bins_error) = (num(contrast)?, num(bins_error));
    // Only wet runs monitor their contrast (`Delta n_cb`) in blocks.
    let block = |name| wet.then(|| block_error(obs, name)).flatten();
    let contrast_error = block(wetgran_core::observe::trend::DELTA_N_CB)
        .or(bins_error.map(|e| std::f64::consts::SQRT_2 * e));
    let branch = start_axis
        .and_then(|k| p.coords.get(k))
        .and_then(|v| v.as_str())
        .map(String::from);
    let point = LinePoint {
        job_id: p.job_id.clone(),
        point: p.point,
        replica: p.replica,
        e_star,
        phase: p.phase.clone(),
        trend: p.trend.map(|t: TrendState| t.name().to_string()),
        trust: super::trust::mark(p.trust()),
        trusted: p.trusted(),
        temperature,
        temperature_error: block_error(obs, wetgran_core::observe::trend::TEMPERATURE),
        bridges: wet.then(|| num("/bridges_per_particle")).flatten(),
        bridges_error: block(wetgran_core::observe::trend::BRIDGES),
        contrast,
        contrast_error,
    };
    Some((branch, gamma, point))
}

/// Whether a point of this label lies on the fluid-gas curve of `T_g`: homogeneous and
/// mobile (f or g), as in the line rule (`observe::line::classify_line`).
pub(crate) fn on_fluid_gas_curve(phase: Option<&str>) -> bool {
    matches!(phase, Some("f" | "g"))
}

/// The fluid-gas inflection of `T_g` over a line's points (sorted by `E*`) that lie on the
/// fluid-gas curve.
fn line_inflection(points: &[LinePoint]) -> Option<f64> {
    let curve: Vec<wetgran_core::observe::line::LinePoint> = points
        .iter()
        .filter(|p| on_fluid_gas_curve(p.phase.as_deref()))
        .map(|p| wetgran_core::observe::line::LinePoint {
            e_star: p.e_star,
            t: p.temperature,
            rel_error: p.temperature_error.map(|e| e / p.temperature.abs()),
        })
        .collect();
    fluid_gas_inflection(&curve).ok().map(|i| i.e_star)
}

/// The lines of constant Gamma of a sweep's finished jobs (`points`: its `Store::points`).
pub fn lines_of(sweep: &SweepRow, points: &[PointRow]) -> Lines {
    let start_axis = sweep.axes.iter().position(|a| a.key == START_AXIS);
    let axes = [
        start_axis,
        sweep.axes.iter().position(crate::sweep::Axis::is_gamma),
        sweep.axes.iter().position(crate::sweep::Axis::is_e_star),
    ];
    let branch_order: Vec<String> = start_axis
        .map(|k| {
            sweep.axes[k]
                .values
                .iter()
                .filter_map(|v| v.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    let mut lines: Vec<GammaLine> = Vec::new();
    let mut left_out = 0;
    let mut wet = None;
    let mut energy_unit = None;
    for p in points.iter().filter(|p| p.status == "done") {
        let Some((branch, gamma, lp)) = line_point(p, axes) else {
            left_out += 1;
            continue;
        };
        wet.get_or_insert(p.spec.scene.is_wet());
        if energy_unit.is_none() {
            energy_unit = p
                .observables
                .as_ref()
                .and_then(|o| o["temperature_unit_name"].as_str().map(String::from));
        }
        match lines
            .iter_mut()
            .find(|l| same(l.gamma, gamma) && l.branch == branch)
        {
            Some(l) => l.points.push(lp),
            None => lines.push(GammaLine {
                gamma,
                branch,
                points: vec![lp],
                boundaries: Vec::new(),
                inflection: None,
            }),
        }
    }
    let rank = |b: &Option<String>| {
        b.as_ref()
            .and_then(|b| branch_order.iter().position(|o| o == b))
            .unwrap_or(usize::MAX)
    };
    lines.sort_by(|a, b| {
        a.gamma
            .total_cmp(&b.gamma)
            .then(rank(&a.branch).cmp(&rank(&b.branch)))
    });
    for l in &mut lines {
        l.points.sort_by(|a, b| {
            a.e_star
                .total_cmp(&b.e_star)
                .then(a.replica.cmp(&b.replica))
        });
        l.boundaries = label_changes(&l.points);
        l.inflection = line_inflection(&l.points);
    }
    Lines {
        sweep: sweep.name.clone(),
        wet: wet.unwrap_or(true),
        energy_unit: energy_unit.unwrap_or_else(|| "E_cb".to_string()),
        lines,
        left_out,
    }
}

/// The label changes along a line's points (sorted by `E*`; module doc).
fn label_changes(points: &[LinePoint]) -> Vec<LineBoundary> {
    // Majority label of the trusted replicas at each E*.
    let mut labels: Vec<(f64, String)> = Vec::new();
    for group in points.chunk_by(|a, b| same(a.e_star, b.e_star)) {
        let votes: Vec<Option<String>> = group
            .iter()
            .filter(|p| p.trusted)
            .map(|p| p.phase.clone())
            .collect();
        if let Some((phase, false)) = majority(&votes) {
            labels.push((group[0].e_star, phase));
        }
    }
    labels
        .windows(2)
        .filter(|w| w[0].1 != w[1].1)
        .map(|w| {
            let (a, b) = (w[0].0, w[1].0);
            LineBoundary {
                pair: format!("{}|{}", w[0].1, w[1].1),
                e_star: if a > 0.0 && b > 0.0 {
                    (a * b).sqrt()
                } else {
                    0.5 * (a + b)
                },
                between: [a, b],
            }
        })
        .collect()
}

fn csv_number(v: Option<f64>) -> String {
    v.filter(|x| x.is_finite())
        .map(|x| format!("{x}"))
        .unwrap_or_default()
}

/// CSV, one row per finished job: `sweep,branch,gamma,e_star,point,replica,job_id,phase,trend,
/// trust,T_g_reduced,T_g_reduced_se,bridges_per_grain,bridges_per_grain_se,delta_n_cb,
/// delta_n_cb_se` (`delta_n_area` dry; no bridge columns dry).
pub fn lines_csv(lines: &Lines) -> String {
    let contrast = if lines.wet {
        "delta_n_cb"
    } else {
        "delta_n_area"
    };
    let mut out = String::from(
        "sweep,branch,gamma,e_star,point,replica,job_id,phase,trend,trust,T_g_reduced,\
         T_g_reduced_se",
    );
    if lines.wet {
        out.push_str(",bridges_per_grain,bridges_per_grain_se");
    }
    let _ = writeln!(out, ",{contrast},{contrast}_se");
    for l in &lines.lines {
        for p in &l.points {
            let _ = write!(
                out,
                "{},{},{},{},{},{},{},{},{},{},{},{}",
                lines.sweep,
                l.branch.as_deref().unwrap_or(""),
                l.gamma,
                p.e_star,
                p.point,
                p.replica,
                p.job_id,
                p.phase.as_deref().unwrap_or(""),
                p.trend.as_deref().unwrap_or(""),
                p.trust.map(String::from).unwrap_or_default(),
                csv_number(Some(p.temperature)),
                csv_number(p.temperature_error),
            );
            if lines.wet {
                let _ = write!(
                    out,
                    ",{},{}",
                    csv_number(p.bridges),
                    csv_number(p.bridges_error)
                );
            }
            let _ = writeln!(
                out,
                ",{},{}",
                csv_number(Some(p.contrast)),
                csv_number(p.contrast_error)
            );
        }
    }
    out
}

/// The table `wetgran lines` prints: per line, its points, label changes and inflection.
pub fn lines_table(lines: &Lines) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "sweep {}: order parameters along lines of constant Gamma",
        lines.sweep
    );
    let _ = writeln!(
        out,
        "{:>9} {:<12} {:>6} {:>12}  label changes (E*)",
        "Gamma", "branch", "points", "inflection"
    );
    for l in &lines.lines {
        let changes: Vec<String> = l
            .boundaries
            .iter()
            .map(|b| format!("{} at {:.4}", b.pair, b.e_star))
            .collect();
        let _ = writeln!(
            out,
            "{:>9.4} {:<12} {:>6} {:>12}  {}",
            l.gamma,
            l.branch.as_deref().unwrap_or("-"),
            l.points.len(),
            l.inflection.map_or("-".to_string(), |e| format!("{e:.4}")),
            if changes.is_empty() {
                "none".to_string()
            } else {
                changes.join(", ")
            }
        );
    }
    if lines.left_out > 0 {
        let _ = writeln!(
            out,
            "{} finished job(s) left out: not a shaken scene, or no observables",
            lines.left_out
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lp(e: f64, phase: &str, trusted: bool, replica: i64) -> LinePoint {
        LinePoint {
            job_id: format!("{e}-{replica}"),
            point: 0,
            replica,
            e_star: e,
            phase: Some(phase.into()),
            trend: Some("stationary".into()),
            trust: (!trusted).then_some('?'),
            trusted,
            temperature: e,
            temperature_error: Some(0.1),
            bridges: Some(1.0),
            bridges_error: None,
            contrast: 0.5,
            contrast_error: None,
        }
    }

    #[test]
    fn a_boundary_rests_on_two_trusted_majorities() {
        // E* = 1: f; 2: untrusted g (stepped over); 4: g, g, f (majority g); 8: g|f tie (stepped
        // over); 16: s.
        let points = vec![
            lp(1.0, "f", true, 0),
            lp(2.0, "g", false, 0),
            lp(4.0, "g", true, 0),
            lp(4.0, "g", true, 1),
            lp(4.0, "f", true, 2),
            lp(8.0, "g", true, 0),
            lp(8.0, "f", true, 1),
            lp(16.0, "s", true, 0),
        ];
        let b = label_changes(&points);
        assert_eq!(b.len(), 2, "{b:?}");
        assert_eq!(b[0].pair, "f|g");
        assert_eq!(b[0].between, [1.0, 4.0]);
        assert!((b[0].e_star - 2.0).abs() < 1e-12);
        assert_eq!(b[1].pair, "g|s");
        assert_eq!(b[1].between, [4.0, 16.0]);
        assert!((b[1].e_star - 8.0).abs() < 1e-12);
        // One label all along: no boundary.
        assert!(label_changes(&points[2..5]).is_empty());
    }

    /// A coexistence's whole-system temperature is off the fluid-gas curve: a hot one in the
    /// middle of a smooth line makes a steep rise only when it is counted.
    #[test]
    fn the_inflection_leaves_coexistences_out() {
        let line = |middle: &str| {
            let mut points: Vec<LinePoint> = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0]
                .iter()
                .map(|&e| {
                    let mut p = lp(e, if e < 10.0 { "f" } else { "g" }, true, 0);
                    p.temperature = 0.1 * e;
                    p.temperature_error = Some(0.001 * e);
                    p
                })
                .collect();
            let mut hot = lp(5.0, middle, true, 0);
            hot.temperature = 50.0;
            hot.temperature_error = Some(0.05);
            points.insert(3, hot);
            points
        };
        assert!(line_inflection(&line("f")).is_some());
        assert_eq!(line_inflection(&line("fgc")), None);
        assert_eq!(line_inflection(&line("sgc")), None);
    }

    #[test]
    fn block_errors_are_read_by_quantity() {
        let obs = serde_json::json!({"trend": {"tests": [
            {"quantity": "temperature_reduced", "standard_error": 0.25},
            {"quantity": "delta_n_cb", "standard_error": 0.5}]}});
        assert_eq!(block_error(&obs, "temperature_reduced"), Some(0.25));
        assert_eq!(block_error(&obs, "delta_n_cb"), Some(0.5));
        assert_eq!(block_error(&obs, "bridges_per_particle"), None);
        assert_eq!(block_error(&serde_json::json!({}), "delta_n_cb"), None);
    }
}
