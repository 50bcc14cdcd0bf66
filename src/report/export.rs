//! Export of a database's results, one row per finished job with its sweep, grid point, axis
//! values, container motion, phase, trust verdict and observables: CSV for pandas and
//! spreadsheets (the scalar observables as dotted columns; every array, a time series or a
//! profile, goes to a separate long-format series CSV `job_id,series,index,value`), JSON
//! (nested, series included) for anything else.

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
    /// Container amplitude and angular frequency of a shaken scene (docs/model.md 4.1).
    pub amplitude: Option<f64>,
    pub omega: Option<f64>,
    pub phase: Option<String>,
    /// The run's stationarity verdict (`report::trust::stationary`).
    pub stationary: Option<bool>,
    /// The run's trend state (stationary, heating, cooling, coarsening, undecided; `None` for
    /// results stored before trend states).
    pub trend: Option<String>,
    /// The trust mark: `?` label may change, `~` label kept by its trend, `None` stationary.
    pub trust: Option<String>,
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
                stationary: p.observables.as_ref().and_then(super::trust::stationary),
                trend: p.trend.map(|t| t.name().to_string()),
                trust: super::trust::mark(p.trust()).map(String::from),
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

/// Scalar leaves of a JSON value with dotted paths (`events.pair_collisions`) into `out`; every
/// array is a series and goes to `series` instead: `(name, index, value)` per element leaf, the
/// name being the array's path plus the leaf's path inside the element
/// (`obs.stationarity.checks.relative_change`, `obs.location_changes.1`).
fn flatten(
    prefix: &str,
    v: &serde_json::Value,
    out: &mut BTreeMap<String, String>,
    series: &mut Vec<(String, usize, String)>,
) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                flatten(&join(prefix, k), x, out, series);
            }
        }
        serde_json::Value::Array(a) => {
            for (k, x) in a.iter().enumerate() {
                let mut leaves = BTreeMap::new();
                // Nested arrays inside an element stay in that element's series, flattened.
                flatten_all("", x, &mut leaves);
                for (leaf, value) in leaves {
                    let name = if leaf.is_empty() {
                        prefix.to_string()
                    } else {
                        join(prefix, &leaf)
                    };
                    series.push((name, k, value));
                }
            }
        }
        other => {
            out.insert(prefix.to_string(), scalar_text(other));
        }
    }
}

/// Every scalar leaf of a JSON value with dotted paths, arrays indexed (`a.0`).
fn flatten_all(prefix: &str, v: &serde_json::Value, out: &mut BTreeMap<String, String>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                flatten_all(&join(prefix, k), x, out);
            }
        }
        serde_json::Value::Array(a) => {
            for (k, x) in a.iter().enumerate() {
                flatten_all(&join(prefix, &k.to_string()), x, out);
            }
        }
        other => {
            out.insert(prefix.to_string(), scalar_text(other));
        }
    }
}

fn scalar_text(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Null => String::new(),
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
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

/// The series of every row in long format: a header `job_id,series,index,value`, then one line
/// per element of every array of the observables and decision inputs.
pub fn series_csv(rows: &[ExportRow]) -> String {
    let mut out = String::from("job_id,series,index,value\n");
    for r in rows {
        let (_, series) = scalars_and_series(r);
        for (name, index, value) in series {
            out.push_str(&format!(
                "{},{},{index},{}\n",
                csv_field(&r.job_id),
                csv_field(&name),
                csv_field(&value)
            ));
        }
    }
    out
}

/// The scalar columns (`obs.`- and `decided_on.`-prefixed) and the series of a row.
#[allow(clippy::type_complexity)]
fn scalars_and_series(r: &ExportRow) -> (BTreeMap<String, String>, Vec<(String, usize, String)>) {
    let mut m = BTreeMap::new();
    let mut series = Vec::new();
    flatten("obs", &r.observables, &mut m, &mut series);
    if let Some(d) = &r.decided_on {
        flatten("decided_on", d, &mut m, &mut series);
    }
    (m, series)
}

/// CSV with a header row, one row per result, scalar columns only: fixed columns, then one
/// column per axis key (union over sweeps), `stationary` and `trust` (the result's trust mark,
/// `report::trust`), then the `obs.`-prefixed scalar observables and `decided_on.`-prefixed
/// decision inputs. Arrays are left out: see [`series_csv`].
pub fn to_csv(rows: &[ExportRow]) -> String {
    let params: BTreeSet<&String> = rows.iter().flat_map(|r| r.params.keys()).collect();
    let flat: Vec<BTreeMap<String, String>> =
        rows.iter().map(|r| scalars_and_series(r).0).collect();
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
            "stationary",
            "trend",
            "trust",
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
            opt(&r.stationary),
            opt(&r.trend),
            opt(&r.trust),
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
    fn flatten_keeps_scalars_and_sends_arrays_to_series() {
        let v = serde_json::json!({"a": {"b": 1, "c": [2.5, null]}, "d": "x",
            "e": [[0.5, 3.0], [1.0, 4.0]], "f": [{"q": "T", "ok": false}]});
        let mut m = BTreeMap::new();
        let mut series = Vec::new();
        flatten("obs", &v, &mut m, &mut series);
        assert_eq!(m.len(), 2, "{m:?}");
        assert_eq!(m["obs.a.b"], "1");
        assert_eq!(m["obs.d"], "x");
        let has = |name: &str, k: usize, value: &str| {
            series
                .iter()
                .any(|(n, i, x)| n == name && *i == k && x == value)
        };
        assert!(has("obs.a.c", 0, "2.5"), "{series:?}");
        assert!(has("obs.a.c", 1, ""), "{series:?}");
        assert!(has("obs.e.0", 1, "1.0"), "{series:?}");
        assert!(has("obs.e.1", 1, "4.0"), "{series:?}");
        assert!(has("obs.f.q", 0, "T"), "{series:?}");
        assert!(has("obs.f.ok", 0, "false"), "{series:?}");
        assert_eq!(series.len(), 8);
    }
}
