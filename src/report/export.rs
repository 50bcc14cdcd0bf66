//! Export of a database's results, one row per finished job with its sweep, grid point, axis
//! values, container motion, phase, trust verdict and observables: CSV for pandas and
//! spreadsheets (the scalar observables as dotted columns; every array, a time series or a
//! profile, goes to a separate long-format series CSV `job_id,series,index,value`), JSON
//! (nested, series included) for anything else.
//!
//! Streaming (issue 35): the export is written row by row as the store reads it
//! (`Store::scan_points`, a page of rows at a time), so its memory does not grow with the number
//! of results. The CSV header is the union of the scalar columns of every row, which the first
//! row cannot tell (results stored before a new observable existed lack its column), so a CSV
//! export reads the rows twice inside one read transaction: a first pass collects the column
//! names ([`CsvColumns::add`], the keys only), a second writes the rows. A declared schema would
//! save the first pass but would have to follow every change of the observables; the names
//! alone are small (a few hundred), whatever the number of rows. The JSON export and the series
//! CSV need one pass each.

use crate::store::{PointRow, SweepRow};
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;

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
        .filter_map(|p| ExportRow::of(sweep, p))
        .collect()
}

impl ExportRow {
    /// The export row of a job of `sweep`; `None` unless the job is done.
    pub fn of(sweep: &SweepRow, p: &PointRow) -> Option<ExportRow> {
        if p.status != "done" {
            return None;
        }
        let motion = p.spec.scene.drive_motion();
        Some(ExportRow {
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
        })
    }
}

/// JSON array of the rows.
pub fn to_json(rows: &[ExportRow]) -> String {
    let mut out = Vec::new();
    let mut w = JsonWriter::default();
    for r in rows {
        w.row(&mut out, r).expect("writes to memory");
    }
    w.finish(&mut out).expect("writes to memory");
    String::from_utf8(out).expect("JSON is UTF-8")
}

/// Writes a JSON array of rows one row at a time, as `serde_json::to_string_pretty` writes the
/// whole array (two-space indent), then a newline.
#[derive(Debug, Default)]
pub struct JsonWriter {
    rows: usize,
}

impl JsonWriter {
    /// Writes one row: the array's opening bracket before the first, a comma before the others,
    /// the row pretty-printed and indented one level (a JSON text has no raw newline inside a
    /// string, so indenting every line indents exactly the structure).
    pub fn row(&mut self, w: &mut impl Write, r: &ExportRow) -> std::io::Result<()> {
        w.write_all(if self.rows == 0 { b"[\n" } else { b",\n" })?;
        let text = serde_json::to_string_pretty(r).expect("a row serializes");
        for (k, line) in text.split('\n').enumerate() {
            if k > 0 {
                w.write_all(b"\n")?;
            }
            w.write_all(b"  ")?;
            w.write_all(line.as_bytes())?;
        }
        self.rows += 1;
        Ok(())
    }

    /// Closes the array (`[]` for no row) and ends the line.
    pub fn finish(self, w: &mut impl Write) -> std::io::Result<()> {
        w.write_all(if self.rows == 0 { b"[]\n" } else { b"\n]\n" })
    }
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

/// The names [`flatten`] gives the scalar leaves of `v` (its `out` keys), without their values
/// and without the series: the first pass of a CSV export.
fn scalar_names(prefix: &str, v: &serde_json::Value, out: &mut BTreeSet<String>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                scalar_names(&join(prefix, k), x, out);
            }
        }
        serde_json::Value::Array(_) => {}
        _ => {
            if !out.contains(prefix) {
                out.insert(prefix.to_string());
            }
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

/// The header of the series CSV.
pub const SERIES_HEADER: &str = "job_id,series,index,value\n";

/// The series of every row in long format: a header `job_id,series,index,value`, then one line
/// per element of every array of the observables and decision inputs.
pub fn series_csv(rows: &[ExportRow]) -> String {
    let mut out = Vec::from(SERIES_HEADER);
    for r in rows {
        write_series(&mut out, r, &scalars_and_series(r).1).expect("writes to memory");
    }
    String::from_utf8(out).expect("CSV is UTF-8")
}

/// The series lines of one row (`series`: its [`scalars_and_series`]).
pub fn write_series(
    w: &mut impl Write,
    r: &ExportRow,
    series: &[(String, usize, String)],
) -> std::io::Result<()> {
    let job = csv_field(&r.job_id);
    for (name, index, value) in series {
        writeln!(w, "{job},{},{index},{}", csv_field(name), csv_field(value))?;
    }
    Ok(())
}

/// The scalar columns (`obs.`- and `decided_on.`-prefixed) and the series of a row.
#[allow(clippy::type_complexity)]
pub fn scalars_and_series(
    r: &ExportRow,
) -> (BTreeMap<String, String>, Vec<(String, usize, String)>) {
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
    let mut columns = CsvColumns::default();
    for r in rows {
        columns.add(r);
    }
    let mut out = Vec::new();
    columns.write_header(&mut out).expect("writes to memory");
    for r in rows {
        columns
            .write_row(&mut out, r, &scalars_and_series(r).0)
            .expect("writes to memory");
    }
    String::from_utf8(out).expect("CSV is UTF-8")
}

/// The columns of a CSV export: the axis keys and the scalar names over every row (the first
/// pass of a streamed export; [`to_csv`]).
#[derive(Debug, Default)]
pub struct CsvColumns {
    params: BTreeSet<String>,
    extra: BTreeSet<String>,
}

/// The columns every row has, between the axis keys and the scalar observables.
const FIXED_AFTER_PARAMS: [&str; 10] = [
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
];

impl CsvColumns {
    /// Adds a row's axis keys and scalar names.
    pub fn add(&mut self, r: &ExportRow) {
        for k in r.params.keys() {
            if !self.params.contains(k) {
                self.params.insert(k.clone());
            }
        }
        scalar_names("obs", &r.observables, &mut self.extra);
        if let Some(d) = &r.decided_on {
            scalar_names("decided_on", d, &mut self.extra);
        }
    }

    /// The header line.
    pub fn write_header(&self, w: &mut impl Write) -> std::io::Result<()> {
        let header: Vec<String> = ["sweep", "point", "replica", "job_id"]
            .iter()
            .map(|s| s.to_string())
            .chain(self.params.iter().cloned())
            .chain(FIXED_AFTER_PARAMS.iter().map(|s| s.to_string()))
            .chain(self.extra.iter().cloned())
            .map(|h| csv_field(&h))
            .collect();
        writeln!(w, "{}", header.join(","))
    }

    /// The line of one row (`scalars`: its [`scalars_and_series`] scalars); a column the row
    /// lacks is empty.
    pub fn write_row(
        &self,
        w: &mut impl Write,
        r: &ExportRow,
        scalars: &BTreeMap<String, String>,
    ) -> std::io::Result<()> {
        let mut cells = vec![
            r.sweep.clone(),
            r.point.to_string(),
            r.replica.to_string(),
            r.job_id.clone(),
        ];
        for p in &self.params {
            cells.push(match r.params.get(p) {
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
        for k in &self.extra {
            cells.push(scalars.get(k).cloned().unwrap_or_default());
        }
        let line: Vec<String> = cells.iter().map(|c| csv_field(c)).collect();
        writeln!(w, "{}", line.join(","))
    }
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

    /// A row with nested objects, arrays, an empty object and array, a string with a newline and
    /// a quote, and a null.
    fn sample_row(job: &str, extra: serde_json::Value) -> ExportRow {
        ExportRow {
            sweep: "s".into(),
            point: 3,
            replica: 1,
            job_id: job.into(),
            params: BTreeMap::from([("drive.gamma".to_string(), serde_json::json!(2.5))]),
            amplitude: Some(0.25),
            omega: None,
            phase: Some("g".into()),
            stationary: Some(false),
            trend: Some("heating".into()),
            trust: Some("~".into()),
            decided_on: Some(serde_json::json!({"reason": "line one\nline \"two\"", "t": [1, 2]})),
            observables: serde_json::json!({"a": {"b": 1.5, "e": {}, "f": []}, "n": null,
                "s": [[0.5, 1.0], [2.0, 3.0]], "x": extra}),
            simulated_time: Some(10.0),
            wall_seconds: Some(0.5),
            events: Some(7),
            finished_at: Some(1.0),
        }
    }

    #[test]
    fn the_streamed_json_is_the_pretty_printed_array() {
        let rows = [
            sample_row("a", serde_json::json!(1)),
            sample_row("b", serde_json::json!({"deep": [{"k": "v"}]})),
        ];
        for n in 0..=rows.len() {
            let want = serde_json::to_string_pretty(&rows[..n]).unwrap() + "\n";
            assert_eq!(to_json(&rows[..n]), want, "{n} row(s)");
        }
    }

    #[test]
    fn the_first_pass_finds_the_columns_that_flatten_writes() {
        let rows = vec![
            sample_row("a", serde_json::json!(1)),
            sample_row("b", serde_json::json!({"only_here": true, "list": [1]})),
        ];
        let mut columns = CsvColumns::default();
        let mut want = BTreeSet::new();
        for r in &rows {
            columns.add(r);
            want.extend(scalars_and_series(r).0.into_keys());
        }
        assert_eq!(columns.extra, want);
        assert!(
            want.contains("obs.x.only_here") && want.contains("obs.x"),
            "{want:?}"
        );
        // A column one row lacks is empty in that row.
        let csv = to_csv(&rows);
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let k = header.iter().position(|h| *h == "obs.x.only_here").unwrap();
        assert!(
            !header.contains(&"obs.s"),
            "the series stay out of the CSV: {header:?}"
        );
        assert_eq!(header.len(), 4 + 1 + FIXED_AFTER_PARAMS.len() + want.len());
        assert!(k >= 4 + 1 + FIXED_AFTER_PARAMS.len());
    }
}
