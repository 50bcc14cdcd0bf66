//! The text of the commands on stored points: `wetgran show` (a job, its phase and the numbers
//! it was decided on) and `wetgran inflection` (the fluid-gas inflection of T_g/E_cb against E*
//! along each line of constant Gamma, docs/model.md 7). Pure functions of the stored rows.

use super::lines::gamma_e_star;
use super::trust::unsettled;
use crate::boundary::{START_AXIS, branch_words};
use crate::store::PointRow;
use crate::sweep::file::Axis;
use serde::Deserialize as _;
use std::fmt::Write as _;
use wetgran_core::observe::Verdict;
use wetgran_core::observe::classify::DecisionInputs;
use wetgran_core::observe::criterion::Region;
use wetgran_core::observe::criterion::{DecidedBy, sig};
use wetgran_core::observe::fluid_gas_inflection;
use wetgran_core::observe::line::LinePoint;
use wetgran_core::observe::settling::Region as SettlingRegion;

/// A point's coordinates with their axes' labels, rounded for reading (`Gamma = 2.187, E* =
/// 1.194`); an `initial.start` axis shows as its branch in words (`branch: cold start`).
pub fn coordinates_text(axes: &[Axis], p: &PointRow) -> String {
    axes.iter()
        .zip(&p.coords)
        .map(
            |(a, v)| match (a.key == START_AXIS, v.as_f64(), v.as_str()) {
                (true, _, Some(b)) => format!("branch: {}", branch_words(b)),
                (_, Some(x), _) => format!("{} = {}", a.label, super::svg::label(x)),
                (_, _, Some(t)) => format!("{} = {t}", a.label),
                _ => format!("{} = {v}", a.label),
            },
        )
        .collect::<Vec<_>>()
        .join(", ")
}

/// A time for reading (`39.906`, `1.2e4`).
pub fn time_label(t: f64) -> String {
    super::svg::label(t)
}

/// The first lines of `show`: the job, its sweep, coordinates and status.
pub fn job_text(sweep: &str, axes: &[Axis], p: &PointRow) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "job         {} (sweep {sweep}, point {}, replica {})",
        p.job_id, p.point, p.replica
    );
    let _ = writeln!(
        out,
        "at          {}",
        crate::terminal::escape(&coordinates_text(axes, p))
    );
    let _ = writeln!(out, "status      {}", p.status);
    if let Some(e) = &p.last_error {
        let _ = writeln!(out, "last error  {}", crate::terminal::escape(e));
    }
    out
}

/// The heading of a job's series figure: the job, where it is, its label and what decided it.
pub fn series_title(sweep: &str, axes: &[Axis], p: &PointRow) -> String {
    let label = p.phase.clone().unwrap_or_else(|| p.status.clone());
    let mark = super::trust::mark(p.trust())
        .map(|m| m.to_string())
        .unwrap_or_default();
    format!(
        "job {} (sweep {sweep}): {}; phase {label}{mark}",
        &p.job_id[..12.min(p.job_id.len())],
        coordinates_text(axes, p)
    )
}

/// The verdict on a stored label in words (`None`: no verdict stored).
fn verdict_words(v: Option<Verdict>) -> &'static str {
    match v {
        Some(Verdict::Stationary) => "stationary: every quantity the label rests on is flat",
        Some(Verdict::LabelKept) => {
            "label kept (~): every region settled, some quantity still drifts in a direction that \
             cannot change its phase"
        }
        Some(Verdict::NotSettled) => "NOT SETTLED (?): the label may still change",
        None => "none stored (a result of an older run policy: outdated, its label may change)",
    }
}

/// The table of the regions a label was decided on: per region its phase, grains, `T_g / E_cb`,
/// `D_lat`, the criteria that decided solid or mobile and fluid or gas, and which of its
/// quantities had not settled.
fn regions_table(d: &DecisionInputs, by: &DecidedBy, unit: &str) -> String {
    let settling = &d.settling;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "  {:<7} {:<6} {:<12} {:>10} {:>10}  {:<22} {:<25} settled",
        "region",
        "phase",
        "grains",
        format!("T_g/{unit}"),
        "D_lat",
        "solid/mobile by",
        "fluid/gas by"
    );
    for r in &by.regions {
        let (name, settling_region) = match r.region {
            Region::Whole => ("whole", SettlingRegion::Whole),
            Region::Dense => ("dense", SettlingRegion::Dense),
            Region::Dilute => ("dilute", SettlingRegion::Dilute),
        };
        let inputs = match r.region {
            Region::Whole => Some(&d.whole),
            Region::Dense => d.dense.as_ref(),
            Region::Dilute => d.dilute.as_ref(),
        };
        let (grains, t, dl) =
            inputs.map_or(("-".to_string(), "-".to_string(), "-".to_string()), |i| {
                (
                    i.grains.clone(),
                    sig(i.temperature),
                    i.diffusion.map_or("-".to_string(), sig),
                )
            });
        let drifting: Vec<String> = settling
            .regions
            .iter()
            .filter(|s| s.region == settling_region)
            .flat_map(|s| {
                s.unsettled()
                    .map(|q| format!("{} {}", q.quantity, q.direction))
            })
            .collect();
        let settled = if settling.regions.iter().all(|s| s.region != settling_region) {
            "-".to_string()
        } else if drifting.is_empty() {
            "yes".to_string()
        } else {
            format!("no: {}", drifting.join(", "))
        };
        let _ = writeln!(
            out,
            "  {:<7} {:<6} {:<12} {:>10} {:>10}  {:<22} {:<25} {settled}",
            name,
            r.phase.to_string(),
            crate::terminal::escape(&grains),
            t,
            dl,
            r.mobility.name().replace('_', " "),
            r.fluid_gas
                .map_or("-".to_string(), |c| c.name().replace('_', " ")),
        );
    }
    out
}

/// The decision summary of a stored job: its phase and verdict, one line of the criterion that
/// decided it with the numbers compared, the regions' table, the trend, how the run ended, and
/// the decisions that lay near their thresholds. The full record is `show --json`'s.
pub fn decision_text(p: &PointRow) -> String {
    let mut out = String::new();
    if let Some(phase) = &p.phase {
        let mark = super::trust::mark(p.trust())
            .map(|m| m.to_string())
            .unwrap_or_default();
        let _ = writeln!(out, "phase       {phase}{mark}");
    }
    let inputs = p
        .decided_on
        .as_ref()
        .and_then(|d| DecisionInputs::deserialize(d).ok());
    let by = p.decided_on.as_ref().and_then(DecidedBy::of_json);
    if let Some(by) = &by {
        let fallback = if by.fallback {
            " (a fallback decided it)"
        } else {
            ""
        };
        let _ = writeln!(out, "decided by  {}{fallback}", by.summary);
    }
    let mut table = false;
    if let (Some(d), Some(by)) = (&inputs, &by)
        && !by.regions.is_empty()
    {
        table = true;
        let unit = if d.reason.contains("T_g/m g d") {
            "mgd"
        } else {
            "E_cb"
        };
        let _ = writeln!(out, "regions");
        out.push_str(&regions_table(d, by, unit));
    }
    if let Some(t) = p.trend {
        let _ = writeln!(out, "trend       {t} (what the whole system's history did)");
    }
    if p.phase.is_some() {
        let _ = writeln!(out, "settled     {}", verdict_words(p.verdict()));
        // The regions' table names what did not settle; without it, a line each.
        if !table {
            for u in p.decided_on.as_ref().map(unsettled).unwrap_or_default() {
                let _ = writeln!(out, "            {u}");
            }
        }
        if let Some(ending) = p
            .observables
            .as_ref()
            .and_then(|o| o.pointer("/trend/policy/ending"))
            .and_then(|e| e.as_str())
        {
            let why = match ending {
                "stationary" => "its label's verdict was stationary",
                "settled" => "its label was kept, every region settled, at two checks in a row",
                "cap" => "it reached the cap of the run-length policy before its label settled",
                other => other,
            };
            let at = p
                .simulated_time
                .map(|t| format!(" at t = {}", super::svg::label(t)))
                .unwrap_or_default();
            let _ = writeln!(out, "ended       {why}{at}");
        }
    }
    if let Some(d) = &inputs {
        for b in &d.borderline {
            let _ = writeln!(out, "borderline  {}", crate::terminal::escape(b));
        }
    }
    out
}

/// The relative error of a stored result's `T_g / E_cb`: its temperature block test
/// (`convergence.tests`, `observe::line::temperature_rel_error`), `None` where none is stored.
fn temperature_rel_error(obs: &serde_json::Value) -> Option<f64> {
    let test = super::lines::block_test(obs, wetgran_core::observe::trend::TEMPERATURE)?;
    let r = test["standard_error"].as_f64()? / test["mean"].as_f64()?.abs();
    (r.is_finite() && r >= 0.0).then_some(r)
}

/// The lines of constant Gamma of a sweep's stored points: `(Gamma, [(E*, T_g / E_cb, relative
/// error)])` of every finished job of a shaken scene labelled f or g, by increasing Gamma. Solids
/// and coexistences are off the fluid-gas curve, as in the line rule that labels the points.
pub fn gamma_lines(points: &[PointRow]) -> Vec<(f64, Vec<LinePoint>)> {
    let mut lines: Vec<(f64, Vec<LinePoint>)> = Vec::new();
    for p in points {
        let (Some(obs), Some((gamma, e_star))) = (&p.observables, gamma_e_star(&p.spec.scene))
        else {
            continue;
        };
        if !crate::report::lines::on_fluid_gas_curve(p.phase.as_deref()) {
            continue;
        }
        let Some(t) = obs["granular_temperature_reduced"].as_f64() else {
            continue;
        };
        let point = LinePoint {
            e_star,
            t,
            rel_error: temperature_rel_error(obs),
        };
        match lines
            .iter_mut()
            .find(|(g, _)| (g - gamma).abs() <= 1e-9 * gamma.abs())
        {
            Some((_, pts)) => pts.push(point),
            None => lines.push((gamma, vec![point])),
        }
    }
    lines.sort_by(|a, b| a.0.total_cmp(&b.0));
    lines
}

/// A reason of `observe::line` split into what it says and its note on the errors used
/// (`...; errors: ...`), which `inflection` prints once below its table.
fn split_errors(why: &str) -> (String, Option<String>) {
    match why.split_once("; errors: ") {
        Some((what, e)) => (what.to_string(), Some(format!("errors: {e}"))),
        None => match why.split_once("; no block errors stored") {
            Some((what, e)) => (what.to_string(), Some(format!("no block errors stored{e}"))),
            None => (why.to_string(), None),
        },
    }
}

/// `inflection` for one sweep: per line of constant Gamma, the inflection point of T_g/E_cb
/// against E* and the bracket it lies in, where it stands out of the line's scatter
/// (`observe::line`), else why there is none. The homogeneous mobile points enter (see
/// [`gamma_lines`]).
pub fn inflection_text(sweep: &str, lines: &[(f64, Vec<LinePoint>)]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "sweep {}: fluid-gas inflection of T_g/E_cb(E*) along constant Gamma",
        sweep
    );
    let _ = writeln!(
        out,
        "{:>10} {:>7} {:>12} {:>10} {:>22}",
        "Gamma", "points", "E* inflect.", "max slope", "between E*"
    );
    let mut notes: Vec<String> = Vec::new();
    for (gamma, pts) in lines {
        let _ = match fluid_gas_inflection(pts) {
            Ok(i) => writeln!(
                out,
                "{:>10.4} {:>7} {:>12.4} {:>10.3} {:>10.4} .. {:<10.4} p = {:.1e}",
                gamma,
                pts.len(),
                i.e_star,
                i.max_slope,
                i.bracket.0,
                i.bracket.1,
                i.p_value
            ),
            Err(why) => {
                let (why, errors) = split_errors(&why);
                if let Some(e) = errors
                    && !notes.contains(&e)
                {
                    notes.push(e);
                }
                writeln!(
                    out,
                    "{:>10.4} {:>7} {:>12}  {why}",
                    gamma,
                    pts.len(),
                    "none:"
                )
            }
        };
    }
    for e in notes {
        let _ = writeln!(out, "  ({e})");
    }
    out
}

/// `show --json`: the job of [`job_text`] and the decision of [`decision_text`] as one object
/// (the observables themselves are left out: `export --json` has them).
pub fn job_json(sweep: &str, axes: &[Axis], p: &PointRow) -> serde_json::Value {
    let trust = match p.trust() {
        Verdict::Stationary => "stationary",
        Verdict::LabelKept => "label kept (not stationary)",
        Verdict::NotSettled => "label may change (not settled)",
    };
    let ending = p
        .observables
        .as_ref()
        .and_then(|o| o.pointer("/trend/policy/ending"))
        .cloned();
    serde_json::json!({
        "job_id": p.job_id,
        "sweep": sweep,
        "point": p.point,
        "replica": p.replica,
        "coords": p.coords,
        "coordinates": axes
            .iter()
            .zip(&p.coords)
            .map(|(a, v)| (a.name.clone(), v.clone()))
            .collect::<serde_json::Map<String, serde_json::Value>>(),
        "status": p.status,
        "attempts": p.attempts,
        "last_error": p.last_error,
        "phase": p.phase,
        "trend": p.trend.map(|t| t.to_string()),
        "trust": if p.phase.is_some() { Some(trust) } else { None },
        "ended": ending,
        "verdict": p.verdict().map(|v| v.name()),
        "unsettled": p.decided_on.as_ref().map(unsettled).unwrap_or_default(),
        "decided_by": p.decided_on.as_ref().and_then(DecidedBy::of_json),
        "decided_on": p.decided_on,
        "simulated_time": p.simulated_time,
        "wall_seconds": p.wall_seconds,
        "events": p.events,
        "finished_at": p.finished_at,
    })
}

/// `inflection --json` for one sweep: per line of constant Gamma, its points and the inflection
/// point (`null` where [`inflection_text`] says none).
pub fn inflection_json(sweep: &str, lines: &[(f64, Vec<LinePoint>)]) -> serde_json::Value {
    let lines: Vec<serde_json::Value> = lines
        .iter()
        .map(|(gamma, pts)| {
            let (inflection, none) = match fluid_gas_inflection(pts) {
                Ok(i) => (
                    serde_json::json!({
                        "e_star": i.e_star, "max_slope": i.max_slope,
                        "between_e_star": [i.bracket.0, i.bracket.1],
                        "p_value": i.p_value,
                    }),
                    None,
                ),
                Err(why) => (serde_json::Value::Null, Some(why)),
            };
            serde_json::json!({
                "gamma": gamma,
                "points": pts.iter().map(|p| serde_json::json!({
                    "e_star": p.e_star, "tg_over_ecb": p.t, "relative_error": p.rel_error,
                })).collect::<Vec<_>>(),
                "inflection": inflection,
                "no_inflection_because": none,
            })
        })
        .collect();
    serde_json::json!({ "sweep": sweep, "lines": lines })
}
