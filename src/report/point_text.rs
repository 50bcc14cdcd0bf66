//! The text of the commands on stored points: `wetgran show` (a job, its phase and the numbers
//! it was decided on) and `wetgran inflection` (the fluid-gas inflection of T_g/E_cb against E*
//! along each line of constant Gamma, docs/model.md 7). Pure functions of the stored rows.

use super::lines::gamma_e_star;
use super::trust::unsettled;
use crate::store::PointRow;
use std::fmt::Write as _;
use wetgran_core::observe::Verdict;
use wetgran_core::observe::criterion::DecidedBy;
use wetgran_core::observe::fluid_gas_inflection;
use wetgran_core::observe::line::LinePoint;

/// The first lines of `show`: the job, its sweep, coordinates and status.
pub fn job_text(sweep: &str, p: &PointRow) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "job {} (sweep {sweep}, point {}, replica {})",
        p.job_id, p.point, p.replica
    );
    let _ = writeln!(
        out,
        "coordinates {}",
        serde_json::Value::from(p.coords.clone())
    );
    let _ = writeln!(out, "status      {}", p.status);
    if let Some(e) = &p.last_error {
        let _ = writeln!(out, "last error  {}", crate::terminal::escape(e));
    }
    out
}

/// The phase of a stored job, whether its run was stationary, and the numbers the phase was
/// decided on.
pub fn decision_text(p: &PointRow) -> String {
    let mut out = String::new();
    if let Some(phase) = &p.phase {
        let _ = writeln!(out, "phase       {phase}");
    }
    if let Some(by) = p.decided_on.as_ref().and_then(DecidedBy::of_json) {
        let fallback = if by.fallback {
            " (a fallback decided it)"
        } else {
            ""
        };
        let _ = writeln!(
            out,
            "decided by  {}{fallback}: {}",
            by.criterion, by.summary
        );
    }
    if let Some(t) = p.trend {
        let _ = writeln!(out, "trend       {t} (what the whole system's history did)");
    }
    if p.phase.is_some() {
        let verdict = match p.verdict() {
            Some(Verdict::Stationary) => "stationary: every quantity the label rests on is flat",
            Some(Verdict::LabelKept) => {
                "label kept (~): every region settled, some quantity still drifts in a direction \
                 that cannot change its phase"
            }
            Some(Verdict::NotSettled) => "NOT SETTLED (?): the label may still change",
            None => "none stored (a result of an older run policy: outdated, its label may change)",
        };
        let _ = writeln!(out, "settled     {verdict}");
        for u in p.decided_on.as_ref().map(unsettled).unwrap_or_default() {
            let _ = writeln!(out, "            {u}");
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
            let _ = writeln!(out, "ended       {why}");
        }
    }
    if let Some(d) = &p.decided_on {
        let _ = writeln!(
            out,
            "decided on  {}",
            serde_json::to_string_pretty(d).expect("JSON prints")
        );
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
            Err(why) => writeln!(
                out,
                "{:>10.4} {:>7} {:>12} ({why})",
                gamma,
                pts.len(),
                "none"
            ),
        };
    }
    out
}

/// `show --json`: the job of [`job_text`] and the decision of [`decision_text`] as one object
/// (the observables themselves are left out: `export --json` has them).
pub fn job_json(sweep: &str, p: &PointRow) -> serde_json::Value {
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
