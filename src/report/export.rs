//! Export of a database's results, one row per finished job with its sweep, grid point, axis
//! values, container motion, phase and observables: CSV (observables flattened to dotted
//! columns) for pandas, JSON (nested) for anything else.

use crate::store::{PointRow, SweepRow};
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};

/// One finished job.
#[derive(Debug, Clone, Serialize)]
pub struct ExportRow {
    pub sweep: String,
    pub point: i64,
    pub replica: i64,
    pub job_id: String,
    /// Axis values by scene key (`drive.gamma`).
    pub params: BTreeMap<String, serde_json::Value>,
    /// Container amplitude and angular frequency of a shaken scene (MODEL.md 4.1).
    pub amplitude: Option<f64>,
    pub omega: Option<f64>,
    pub phase: Option<String>,
    pub decided_on: Option<serde_json::Value>,
    pub observables: serde_json::Value,
    pub simulated_time: Option<f64>,
    pub wall_seconds: Option<f64>,
    pub events: Option<i64>,
    pub finished_at: Option<f64>,
}

/// The finished jobs of a sweep as export rows.
pub fn rows(sweep: &SweepRow, points: &[PointRow]) -> Vec<ExportRow> {
    points
        .iter()
        .filter(|p| p.status == "done")
        .map(|p| {
            let motion = p.spec.scene.drive_motion();
            ExportRow {
                sweep: sweep.name.clone(),
                point: p.point,
                replica: p.replica,
                job_id: p.job_id.clone(),
                params: sweep
                    .axes
                    .iter()
                    .zip(&p.coords)
                    .map(|(a, v)| (a.key.clone(), v.clone()))
                    .collect(),
                amplitude: motion.map(|m| m.0),
                omega: motion.map(|m| m.1),
                phase: p.phase.clone(),
                decided_on: p.decided_on.clone(),
                observables: p.observables.clone().unwrap_or(serde_json::Value::Null),
                simulated_time: p.simulated_time,
                wall_seconds: p.wall_seconds,
                events: p.events,
                finished_at: p.finished_at,
            }
        })
        .collect()
}

/// JSON array of the rows.
pub fn to_json(rows: &[ExportRow]) -> String {
    serde_json::to_string_pretty(rows).expect("rows serialize") + "\n"
}

/// Scalar leaves of a JSON value with dotted paths (`events.pair_collisions`; arrays `a.0`).
fn flatten(prefix: &str, v: &serde_json::Value, out: &mut BTreeMap<String, String>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                flatten(&join(prefix, k), x, out);
            }
        }
        serde_json::Value::Array(a) => {
            for (k, x) in a.iter().enumerate() {
                flatten(&join(prefix, &k.to_string()), x, out);
            }
        }
        serde_json::Value::Null => {
            out.insert(prefix.to_string(), String::new());
        }
        serde_json::Value::String(s) => {
            out.insert(prefix.to_string(), s.clone());
        }
        other => {
            out.insert(prefix.to_string(), other.to_string());
        }
    }
}

fn join(prefix: &str, k: &str) -> String {
    if prefix.is_empty() {
        k.to_string()
    } else {
        format!("{prefix}.{k}")
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn opt<T: ToString>(v: &Option<T>) -> String {
    v.as_ref().map(ToString::to_string).unwrap_or_default()
}

/// CSV with a header row: fixed columns, then one column per axis key (union over sweeps), then
/// `obs.`-prefixed flattened observables and `decided_on.`-prefixed decision inputs.
pub fn to_csv(rows: &[ExportRow]) -> String {
    let params: BTreeSet<&String> = rows.iter().flat_map(|r| r.params.keys()).collect();
    let flat: Vec<BTreeMap<String, String>> = rows
        .iter()
        .map(|r| {
            let mut m = BTreeMap::new();
            flatten("obs", &r.observables, &mut m);
            if let Some(d) = &r.decided_on {
                flatten("decided_on", d, &mut m);
            }
            m
        })
        .collect();
    let extra: BTreeSet<&String> = flat.iter().flat_map(|m| m.keys()).collect();
    let mut header: Vec<String> = ["sweep", "point", "replica", "job_id"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    header.extend(params.iter().map(|p| p.to_string()));
    header.extend(
        [
            "amplitude",
            "omega",
            "phase",
            "simulated_time",
            "wall_seconds",
            "events",
            "finished_at",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    header.extend(extra.iter().map(|s| s.to_string()));
    let mut out = header
        .iter()
        .map(|h| csv_field(h))
        .collect::<Vec<_>>()
        .join(",");
    out.push('\n');
    for (r, f) in rows.iter().zip(&flat) {
        let mut cells = vec![
            r.sweep.clone(),
            r.point.to_string(),
            r.replica.to_string(),
            r.job_id.clone(),
        ];
        for p in &params {
            cells.push(match r.params.get(*p) {
                Some(serde_json::Value::String(s)) => s.clone(),
                Some(v) => v.to_string(),
                None => String::new(),
            });
        }
        cells.extend([
            opt(&r.amplitude),
            opt(&r.omega),
            opt(&r.phase),
            opt(&r.simulated_time),
            opt(&r.wall_seconds),
            opt(&r.events),
            opt(&r.finished_at),
        ]);
        for k in &extra {
            cells.push(f.get(*k).cloned().unwrap_or_default());
        }
        out.push_str(
            &cells
                .iter()
                .map(|c| csv_field(c))
                .collect::<Vec<_>>()
                .join(","),
        );
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_quotes_fields_with_separators() {
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"x\""), "\"say \"\"x\"\"\"");
        assert_eq!(csv_field("plain"), "plain");
    }

    #[test]
    fn flatten_names_nested_leaves() {
        let v = serde_json::json!({"a": {"b": 1, "c": [2.5, null]}, "d": "x"});
        let mut m = BTreeMap::new();
        flatten("obs", &v, &mut m);
        assert_eq!(m["obs.a.b"], "1");
        assert_eq!(m["obs.a.c.0"], "2.5");
        assert_eq!(m["obs.a.c.1"], "");
        assert_eq!(m["obs.d"], "x");
    }
}
