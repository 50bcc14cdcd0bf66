//! Export of a database's results in tidy form, one row per finished job (`wetgran export`):
//! CSV for pandas and spreadsheets, or JSON with the same fields (an array of flat objects,
//! numbers as numbers).
//!
//! Columns, in order: the sweep's axes in the sweep's order (keyed by scene key,
//! `drive.gamma`), then `sweep,point,replica,job_id`, the container motion
//! (`amplitude,omega`), the verdict (`phase,stationary,trend,trust`) and the run's cost
//! (`simulated_time,wall_seconds,events,finished_at`): these are always there. Then the scalar
//! observables as dotted `obs.` columns and the scalar decision inputs as `decided_on.` columns,
//! sorted by name, but only those that carry information: a column empty in every row, or (with
//! two rows or more) holding the same value in every row, is left out unless `all` is asked for
//! (`--all`). Every array (time series, profiles, the blocks of the convergence check) is a
//! series and goes to the series file instead, `job_id,series,index,value`, numbers only (an
//! empty value is a missing number); the text and true/false entries of those arrays (the names
//! of the monitored quantities, the checks' verdicts) go to their own file of the same shape.
//!
//! Standard errors (issue 45): every averaged observable whose run stores an error gets a
//! column `NAME_se` beside it ([`STANDARD_ERRORS`]): the block standard error of the window mean
//! from the run's trend test (`trend.tests[].standard_error` of the monitored quantity:
//! `temperature_reduced`, `bridges_per_particle`, `delta_n_cb`, `e_par`); for a contrast
//! `Delta n` without a block test, `sqrt(2)` times the root mean square of its bins' standard
//! errors (`profiles.n_cb_standard_error`, `profiles.packing_standard_error`), the error of a
//! difference of two bins, as `wetgran lines` takes it. A row without either has an empty cell
//! (JSON `null`). An `_se` column is kept exactly when its observable's column is.
//!
//! The system (issue 45): each row's constants of the scene (`sys.` columns: `N`, the box,
//! `eps`, `E_cb`, `s_crit`, diameter, mass, gravity, [`system_of`]) go through the same rule as
//! the observables, so a constant one is left out of the rows; [`Columns::meta`] is the sidecar
//! file that says what the rows do not: those constants with their values, every other column
//! left out as constant (with its value) or empty, the sweeps and wetgran's version.
//!
//! Streaming (issue 35): the export is written row by row as the store reads it
//! (`Store::scan_points`, a page of rows at a time), so its memory does not grow with the number
//! of results. Which columns carry information is known only after every row, so the export
//! reads the rows twice inside one read transaction: the first pass keeps, per column, its first
//! value and whether another differs ([`Columns::add`]), the second writes the rows. The state
//! is a few hundred columns whatever the number of rows.

use crate::store::{PointRow, SweepRow};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::io::Write;
use wetgran_core::observe::trend;
use wetgran_core::scene::Scene;

/// One finished job.
#[derive(Debug, Clone)]
pub struct ExportRow {
    pub job_id: String,
    /// Axis values by scene key, in the sweep's axis order.
    pub params: Vec<(String, Value)>,
    /// The values of the [`FIXED`] columns.
    pub fixed: [Value; FIXED.len()],
    pub decided_on: Option<Value>,
    pub observables: Value,
    /// The scene's constants ([`system_of`]), a JSON object.
    pub system: Value,
}

impl ExportRow {
    /// The export row of a job of `sweep`; `None` unless the job is done.
    pub fn of(sweep: &SweepRow, p: &PointRow) -> Option<ExportRow> {
        if p.status != "done" {
            return None;
        }
        let motion = p.spec.scene.drive_motion();
        let decided_by = p
            .decided_on
            .as_ref()
            .and_then(wetgran_core::observe::criterion::DecidedBy::of_json);
        Some(ExportRow {
            job_id: p.job_id.clone(),
            params: sweep
                .axes
                .iter()
                .zip(&p.coords)
                .map(|(a, v)| (a.key.clone(), v.clone()))
                .collect(),
            fixed: [
                sweep.name.clone().into(),
                p.point.into(),
                p.replica.into(),
                p.job_id.clone().into(),
                motion.map(|m| m.0).into(),
                motion.map(|m| m.1).into(),
                p.phase.clone().into(),
                p.verdict().map(|v| v.name()).into(),
                p.trend.map(|t| t.name()).into(),
                super::trust::mark(p.trust()).map(String::from).into(),
                decided_by.as_ref().map(|d| d.criterion.name()).into(),
                decided_by.as_ref().map(|d| d.fallback).into(),
                p.simulated_time.into(),
                p.wall_seconds.into(),
                p.events.into(),
                p.finished_at.into(),
            ],
            decided_on: p.decided_on.clone(),
            observables: p.observables.clone().unwrap_or(Value::Null),
            system: system_of(&p.spec.scene),
        })
    }
}

/// The constants of a scene that say what system a row is (the `sys.` columns, module doc):
/// `dimension`, `N` (`particles.count`), `box.0`, `box.1` (, `box.2`) (`box.size`, in `d`),
/// `diameter`, `polydispersity`, `mass`, `gravity`, `eps` and `eps_wall`
/// (`contact.restitution`, `contact.wall_restitution`), the capillary model, and for a wet
/// scene `E_cb` and `s_crit` with their defaults filled in (empty for a dry one).
pub fn system_of(scene: &Scene) -> Value {
    let mut m = serde_json::Map::new();
    m.insert("dimension".into(), scene.dimension.into());
    m.insert("N".into(), scene.particles.count.into());
    for (k, l) in scene.container.size.iter().enumerate() {
        m.insert(format!("box.{k}"), (*l).into());
    }
    m.insert("diameter".into(), scene.particles.diameter.into());
    m.insert(
        "polydispersity".into(),
        scene.particles.polydispersity.into(),
    );
    m.insert("mass".into(), scene.particles.mass.into());
    m.insert("gravity".into(), scene.gravity.into());
    m.insert("eps".into(), scene.contact.restitution.into());
    m.insert("eps_wall".into(), scene.contact.wall_restitution.into());
    m.insert(
        "capillary".into(),
        serde_json::to_value(scene.capillary.model).unwrap_or(Value::Null),
    );
    let wet = scene.is_wet();
    m.insert("E_cb".into(), wet.then(|| scene.e_cb()).into());
    m.insert("s_crit".into(), wet.then(|| scene.s_crit()).into());
    Value::Object(m)
}

/// The suffix of a standard-error column (`obs.bridges_per_particle_se`).
pub const SE_SUFFIX: &str = "_se";

/// The averaged observables exported with a standard error (module doc): the column, the
/// monitored quantity of the trend test whose block standard error it takes, and the profile's
/// root-mean-square bin error (a JSON pointer into the observables) whose `sqrt(2)` multiple
/// stands in where the run stored no block test of it.
pub const STANDARD_ERRORS: [(&str, Option<&str>, Option<&str>); 5] = [
    (
        "obs.granular_temperature_reduced",
        Some(trend::TEMPERATURE),
        None,
    ),
    ("obs.bridges_per_particle", Some(trend::BRIDGES), None),
    (
        "obs.profiles.delta_n_cb",
        Some(trend::DELTA_N_CB),
        Some("/profiles/n_cb_standard_error"),
    ),
    (
        "obs.profiles.delta_n_area",
        None,
        Some("/profiles/packing_standard_error"),
    ),
    ("obs.shear.e_par", Some(trend::E_PAR), None),
];

/// The standard error of one of [`STANDARD_ERRORS`] in `observables`, `None` where the run
/// stored neither source (or a non-finite one).
fn standard_error(observables: &Value, block: Option<&str>, bins: Option<&str>) -> Option<f64> {
    let finite = |x: Option<f64>| x.filter(|e| e.is_finite());
    let from_block = block
        .and_then(|q| super::lines::block_test(observables, q))
        .and_then(|t| finite(t["standard_error"].as_f64()));
    from_block.or_else(|| {
        let e = finite(bins.and_then(|p| observables.pointer(p)?.as_f64()))?;
        Some(std::f64::consts::SQRT_2 * e)
    })
}

/// The observable column a standard-error column belongs to.
fn se_base(column: &str) -> Option<&'static str> {
    let base = column.strip_suffix(SE_SUFFIX)?;
    STANDARD_ERRORS
        .iter()
        .map(|(c, _, _)| *c)
        .find(|c| *c == base)
}

/// The columns every row has, after the axis columns: the container motion of a shaken scene
/// (`amplitude,omega`, docs/model.md 4.1), the run's settling verdict (`observe::Verdict`:
/// stationary, label_kept or not_settled), its trend state (empty for results stored before
/// trend states) and trust mark (`?` not settled, `~` label kept by its settled regions, empty
/// stationary), the criterion that decided the label (`observe::criterion`: its snake_case
/// name, and whether a fallback decided it; empty for a record this wetgran cannot read), and
/// the run's cost.
pub const FIXED: [&str; 16] = [
    "sweep",
    "point",
    "replica",
    "job_id",
    "amplitude",
    "omega",
    "phase",
    "verdict",
    "trend",
    "trust",
    "decided_by",
    "decided_by_fallback",
    "simulated_time",
    "wall_seconds",
    "events",
    "finished_at",
];

/// One element of a series: `(name, index, value)`.
pub type SeriesEntry = (String, usize, Value);

/// Scalar leaves of a JSON value with dotted paths (`events.pair_collisions`) into `out`. With
/// `series`, every array is a series and goes there instead: `(name, index, value)` per element
/// leaf, the name being the array's path plus the leaf's path inside the element
/// (`obs.stationarity.checks.relative_change`, `obs.location_changes.1`); without, arrays are
/// indexed (`a.0`), as nested arrays inside an element are.
fn flatten(
    prefix: &str,
    v: &Value,
    out: &mut BTreeMap<String, Value>,
    mut series: Option<&mut Vec<SeriesEntry>>,
) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                flatten(&join(prefix, k), x, out, series.as_deref_mut());
            }
        }
        Value::Array(a) => {
            for (k, x) in a.iter().enumerate() {
                let Some(series) = series.as_deref_mut() else {
                    flatten(&join(prefix, &k.to_string()), x, out, None);
                    continue;
                };
                let mut leaves = BTreeMap::new();
                flatten("", x, &mut leaves, None);
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
            out.insert(prefix.to_string(), other.clone());
        }
    }
}

/// The text of a scalar in a CSV cell: empty for null, strings unquoted.
fn scalar_text(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
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

pub(crate) fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The header of the series files (numbers, and text).
pub const SERIES_HEADER: &str = "job_id,series,index,value\n";

/// The scalar columns (`obs.`- and `decided_on.`-prefixed) and the series of a row.
pub fn scalars_and_series(r: &ExportRow) -> (BTreeMap<String, Value>, Vec<SeriesEntry>) {
    let mut m = BTreeMap::new();
    let mut series = Vec::new();
    flatten("obs", &r.observables, &mut m, Some(&mut series));
    for (column, block, bins) in STANDARD_ERRORS {
        if m.contains_key(column) {
            let se = standard_error(&r.observables, block, bins);
            m.insert(format!("{column}{SE_SUFFIX}"), se.into());
        }
    }
    if let Some(d) = &r.decided_on {
        flatten("decided_on", d, &mut m, Some(&mut series));
    }
    flatten("sys", &r.system, &mut m, None);
    (m, series)
}

/// Which entries of a row's series a file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesFile {
    /// Numbers, and missing numbers as an empty value (`--series`).
    Numbers,
    /// Text and true/false entries (`--text`).
    Text,
}

/// Writes the entries of a row's series that belong in `file`, one `job_id,series,index,value`
/// line each.
pub fn write_series(
    w: &mut impl Write,
    file: SeriesFile,
    r: &ExportRow,
    series: &[SeriesEntry],
) -> std::io::Result<()> {
    let job = csv_field(&r.job_id);
    for (name, index, value) in series {
        let numeric = matches!(value, Value::Number(_) | Value::Null);
        let value = match file {
            SeriesFile::Numbers if numeric => scalar_text(value),
            SeriesFile::Text if !numeric => csv_field(&scalar_text(value)),
            _ => continue,
        };
        writeln!(w, "{job},{},{index},{value}", csv_field(name))?;
    }
    Ok(())
}

/// What the first pass knows of a scalar column.
#[derive(Debug, Clone)]
struct ColumnSeen {
    /// The first non-empty value.
    first: Value,
    /// Rows with a non-empty value.
    filled: usize,
    /// Whether a non-empty value differs from the first.
    varies: bool,
}

/// The columns of an export (module doc): the first pass adds every row, the second writes.
#[derive(Debug, Default)]
pub struct Columns {
    axes: Vec<String>,
    seen: BTreeMap<String, Option<ColumnSeen>>,
    rows: usize,
    all: bool,
    /// The scalar columns kept, fixed after the first pass.
    kept: Option<Vec<String>>,
    /// CSV, else JSON.
    csv: bool,
    /// Rows written.
    written: usize,
}

impl Columns {
    /// The columns of a CSV (`csv`) or JSON export that keeps every scalar (`all`) or only those
    /// that carry information.
    pub fn new(all: bool, csv: bool) -> Columns {
        Columns {
            all,
            csv,
            ..Columns::default()
        }
    }

    /// Adds a row of the first pass (`scalars`: its [`scalars_and_series`] scalars).
    pub fn add(&mut self, r: &ExportRow, scalars: &BTreeMap<String, Value>) {
        for (k, _) in &r.params {
            if !self.axes.contains(k) {
                self.axes.push(k.clone());
            }
        }
        self.rows += 1;
        for (k, v) in scalars {
            let entry = self.seen.entry(k.clone()).or_insert(None);
            if v.is_null() {
                continue;
            }
            match entry {
                None => {
                    *entry = Some(ColumnSeen {
                        first: v.clone(),
                        filled: 1,
                        varies: false,
                    })
                }
                Some(c) => {
                    c.filled += 1;
                    c.varies |= c.first != *v;
                }
            }
        }
    }

    /// The scalar columns written: all, or those with a value somewhere that differs between
    /// rows (a value in some rows only differs from the empty ones); with one row, every
    /// column with a value.
    /// A standard-error column goes with its observable's.
    fn kept(&self) -> Vec<String> {
        self.seen
            .keys()
            .filter(|k| match se_base(k) {
                Some(base) => self.carries(base),
                None => self.carries(k),
            })
            .cloned()
            .collect()
    }

    /// Whether the column `k` carries information (or `--all` keeps everything).
    fn carries(&self, k: &str) -> bool {
        self.all
            || self.seen.get(k).is_some_and(|c| {
                c.as_ref()
                    .is_some_and(|c| self.rows < 2 || c.varies || c.filled < self.rows)
            })
    }

    /// The value of a column that holds the same value in every row (after the first pass).
    fn constant(&self, k: &str) -> Option<&Value> {
        match self.seen.get(k)? {
            Some(c) if !c.varies && c.filled == self.rows => Some(&c.first),
            _ => None,
        }
    }

    /// The sidecar of the export (module doc), after the first pass: wetgran's version, the
    /// database and the sweeps, the rows, the system's constants (`system`: every `sys.` column
    /// with one value in every row, by its name without the prefix; `system_columns`: those
    /// that vary, which the rows hold), the other columns left out of the rows (`constant`:
    /// name and value; `empty`), and the rule of the `_se` columns.
    pub fn meta(&self, database: &str, sweeps: &[String]) -> Value {
        let kept = self.kept();
        let mut system = serde_json::Map::new();
        let mut system_columns = Vec::new();
        let mut constant = serde_json::Map::new();
        let mut empty = Vec::new();
        for k in self.seen.keys() {
            if let Some(name) = k.strip_prefix("sys.") {
                match (self.constant(k), &self.seen[k]) {
                    (Some(v), _) => {
                        system.insert(name.to_string(), v.clone());
                    }
                    // Empty in every row (a dry scene's E_cb).
                    (None, None) => {
                        system.insert(name.to_string(), Value::Null);
                    }
                    (None, Some(_)) => system_columns.push(k.clone()),
                }
            } else if !kept.contains(k) {
                match self.constant(k) {
                    Some(v) => {
                        constant.insert(k.clone(), v.clone());
                    }
                    None => empty.push(k.clone()),
                }
            }
        }
        json!({
            "wetgran_version": env!("CARGO_PKG_VERSION"),
            "database": database,
            "sweeps": sweeps,
            "rows": self.rows,
            "units": "docs/model.md 1.1: lengths in d, masses in m, accelerations in g; times in \
                sqrt(d/g), energies in m g d",
            "system": system,
            "system_columns": system_columns,
            "constant": constant,
            "empty": empty,
            "standard_errors": "COLUMN_se: the block standard error of the window mean (trend \
                test); for a Delta n without one, sqrt(2) x the rms of its bins' standard \
                errors; empty where the run stored neither",
        })
    }

    /// The scalar columns left out (empty or constant), for a note.
    pub fn left_out(&self) -> usize {
        self.seen.len() - self.kept_names().len()
    }

    /// Ends the first pass and, for CSV, writes the header line; what comes after the first
    /// call does nothing.
    fn start(&mut self, w: &mut impl Write) -> std::io::Result<()> {
        if self.kept.is_none() {
            self.kept = Some(self.kept());
            if self.csv {
                let header: Vec<String> = self.names().iter().map(|h| csv_field(h)).collect();
                writeln!(w, "{}", header.join(","))?;
            }
        }
        Ok(())
    }

    fn kept_names(&self) -> &[String] {
        self.kept.as_deref().unwrap_or(&[])
    }

    /// Every column name, in order.
    pub fn names(&self) -> Vec<String> {
        self.axes
            .iter()
            .cloned()
            .chain(FIXED.iter().map(|s| s.to_string()))
            .chain(self.kept_names().iter().cloned())
            .collect()
    }

    /// The values of a row in column order (null where the row lacks the column).
    fn values(&self, r: &ExportRow, scalars: &BTreeMap<String, Value>) -> Vec<Value> {
        let mut out: Vec<Value> = self
            .axes
            .iter()
            .map(|a| {
                r.params
                    .iter()
                    .find(|(k, _)| k == a)
                    .map_or(Value::Null, |(_, v)| v.clone())
            })
            .collect();
        out.extend(r.fixed.iter().cloned());
        out.extend(
            self.kept_names()
                .iter()
                .map(|k| scalars.get(k).cloned().unwrap_or(Value::Null)),
        );
        out
    }

    /// Writes one row of the second pass (the first call ends the first pass): a CSV line (a
    /// column the row lacks is empty), or a JSON object on one line with the CSV's columns in
    /// the CSV's order (a column the row lacks is null) in an array opened by the first row.
    pub fn write_row(
        &mut self,
        w: &mut impl Write,
        r: &ExportRow,
        scalars: &BTreeMap<String, Value>,
    ) -> std::io::Result<()> {
        self.start(w)?;
        let values = self.values(r, scalars);
        if self.csv {
            let line: Vec<String> = values.iter().map(|v| csv_field(&scalar_text(v))).collect();
            writeln!(w, "{}", line.join(","))?;
        } else {
            let cells: Vec<String> = self
                .names()
                .iter()
                .zip(values)
                .map(|(k, v)| format!("{}: {}", Value::from(k.as_str()), v))
                .collect();
            let open = if self.written == 0 { "[\n  " } else { ",\n  " };
            write!(w, "{open}{{{}}}", cells.join(", "))?;
        }
        self.written += 1;
        Ok(())
    }

    /// Ends the export: the CSV header alone where there is no row, the JSON array closed
    /// (`[]` for no row) and its line ended.
    pub fn finish(&mut self, w: &mut impl Write) -> std::io::Result<()> {
        self.start(w)?;
        if !self.csv {
            w.write_all(if self.written == 0 { b"[]\n" } else { b"\n]\n" })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn csv_quotes_fields_with_separators() {
        assert_eq!(csv_field("a,b"), "\"a,b\"");
        assert_eq!(csv_field("say \"x\""), "\"say \"\"x\"\"\"");
        assert_eq!(csv_field("plain"), "plain");
    }

    #[test]
    fn flatten_keeps_scalars_and_sends_arrays_to_series() {
        let v = json!({"a": {"b": 1, "c": [2.5, null]}, "d": "x",
            "e": [[0.5, 3.0], [1.0, 4.0]], "f": [{"q": "T", "ok": false}]});
        let mut m = BTreeMap::new();
        let mut series = Vec::new();
        flatten("obs", &v, &mut m, Some(&mut series));
        assert_eq!(m.len(), 2, "{m:?}");
        assert_eq!(m["obs.a.b"], json!(1));
        assert_eq!(m["obs.d"], json!("x"));
        let has = |name: &str, k: usize, value: Value| {
            series
                .iter()
                .any(|(n, i, x)| n == name && *i == k && *x == value)
        };
        assert!(has("obs.a.c", 0, json!(2.5)), "{series:?}");
        assert!(has("obs.a.c", 1, Value::Null), "{series:?}");
        assert!(has("obs.e.0", 1, json!(1.0)), "{series:?}");
        assert!(has("obs.e.1", 1, json!(4.0)), "{series:?}");
        assert!(has("obs.f.q", 0, json!("T")), "{series:?}");
        assert!(has("obs.f.ok", 0, json!(false)), "{series:?}");
        assert_eq!(series.len(), 8);
    }

    /// A row of sweep `s` with axes `gamma` then `e_star` (not alphabetical) and observables
    /// `obs`.
    fn row(job: &str, gamma: f64, obs: Value) -> ExportRow {
        ExportRow {
            job_id: job.into(),
            params: vec![
                ("drive.gamma".to_string(), json!(gamma)),
                ("drive.e_star".to_string(), json!(2.0)),
            ],
            fixed: [
                json!("s"),
                json!(3),
                json!(1),
                json!(job),
                json!(0.25),
                Value::Null,
                json!("g"),
                json!("label_kept"),
                json!("heating"),
                json!("~"),
                json!("gas_temperature_fallback"),
                json!(true),
                json!(10.0),
                json!(0.5),
                json!(7),
                json!(1.0),
            ],
            decided_on: Some(json!({"reason": "line one\nline \"two\"", "t": [1, 2]})),
            observables: obs,
            system: json!({"N": 300, "E_cb": 0.2844, "box.0": 100.0}),
        }
    }

    /// Both passes over `rows`: the columns, the CSV and the JSON.
    fn export(rows: &[ExportRow], all: bool) -> (Columns, String, String) {
        let mut texts = Vec::new();
        let mut columns = Columns::default();
        for csv in [true, false] {
            columns = Columns::new(all, csv);
            for r in rows {
                columns.add(r, &scalars_and_series(r).0);
            }
            let mut w = Vec::new();
            for r in rows {
                columns
                    .write_row(&mut w, r, &scalars_and_series(r).0)
                    .unwrap();
            }
            columns.finish(&mut w).unwrap();
            texts.push(String::from_utf8(w).unwrap());
        }
        let json = texts.pop().unwrap();
        (columns, texts.pop().unwrap(), json)
    }

    #[test]
    fn empty_and_constant_columns_are_left_out_unless_all() {
        let rows = vec![
            row(
                "a",
                0.5,
                json!({"t": 1.0, "unit": "E_cb", "gone": null, "some": 3}),
            ),
            row("b", 2.0, json!({"t": 2.5, "unit": "E_cb", "gone": null})),
        ];
        let (columns, csv, _) = export(&rows, false);
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        // Axes first, in the sweep's order; then the fixed columns.
        assert_eq!(header[..3], ["drive.gamma", "drive.e_star", "sweep"]);
        assert_eq!(header[2..2 + FIXED.len()], FIXED);
        // obs.t varies, obs.some is only in one row: kept. obs.unit is constant, obs.gone
        // always empty, decided_on.reason constant: left out.
        let extra: Vec<&str> = header[2 + FIXED.len()..].to_vec();
        assert_eq!(extra, ["obs.some", "obs.t"], "{header:?}");
        // ... and the system's constants, the same in both rows.
        assert_eq!(columns.left_out(), 6);
        let (_, all, _) = export(&rows, true);
        let header: Vec<&str> = all.lines().next().unwrap().split(',').collect();
        for c in ["obs.unit", "obs.gone", "decided_on.reason", "obs.t"] {
            assert!(header.contains(&c), "{c}: {header:?}");
        }
        // One row: every column with a value stays (nothing to compare with).
        let (_, one, _) = export(&rows[..1], false);
        assert!(one.lines().next().unwrap().contains("obs.unit"), "{one}");
    }

    #[test]
    fn standard_errors_sit_beside_their_observables() {
        let obs = |t: f64, b: f64, se_t: f64| {
            json!({"granular_temperature_reduced": t, "bridges_per_particle": b,
                "profiles": {"delta_n_cb": 0.5 * t, "n_cb_standard_error": 0.1, "delta_n_area": 1.0},
                "trend": {"tests": [{"quantity": "temperature_reduced", "standard_error": se_t}]}})
        };
        let rows = vec![
            row("a", 0.5, obs(1.0, 2.0, 0.25)),
            row("b", 2.0, obs(3.0, 4.0, 0.5)),
        ];
        let (_, csv, json) = export(&rows, false);
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let at = |c: &str| header.iter().position(|h| *h == c);
        for base in [
            "obs.granular_temperature_reduced",
            "obs.bridges_per_particle",
            "obs.profiles.delta_n_cb",
        ] {
            let k = at(base).unwrap_or_else(|| panic!("{base}: {header:?}"));
            assert_eq!(header[k + 1], format!("{base}_se"), "{header:?}");
        }
        // Delta n_area is the same in both rows: left out, and its error with it.
        assert_eq!(at("obs.profiles.delta_n_area"), None, "{header:?}");
        assert_eq!(at("obs.profiles.delta_n_area_se"), None, "{header:?}");
        let v: Vec<serde_json::Map<String, Value>> = serde_json::from_str(&json).unwrap();
        // From the block test; from the bins (sqrt(2) x 0.1); none stored: null.
        assert_eq!(v[1]["obs.granular_temperature_reduced_se"], json!(0.5));
        let se_cb = v[0]["obs.profiles.delta_n_cb_se"].as_f64().unwrap();
        assert!(
            (se_cb - 0.1 * std::f64::consts::SQRT_2).abs() < 1e-15,
            "{se_cb}"
        );
        assert_eq!(v[0]["obs.bridges_per_particle_se"], Value::Null);
        // The CSV cell of a missing error is empty.
        let line: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
        assert_eq!(line[at("obs.bridges_per_particle_se").unwrap()], "");
        assert_eq!(
            line[at("obs.granular_temperature_reduced_se").unwrap()],
            "0.25"
        );
    }

    #[test]
    fn the_meta_names_the_system_and_what_the_rows_leave_out() {
        let mut rows = vec![
            row("a", 0.5, json!({"t": 1.0, "unit": "E_cb", "gone": null})),
            row("b", 2.0, json!({"t": 2.5, "unit": "E_cb", "gone": null})),
        ];
        rows[1].system = json!({"N": 600, "E_cb": 0.2844, "box.0": 100.0});
        let (columns, csv, _) = export(&rows, false);
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let meta = columns.meta("w.sqlite", &["s".to_string()]);
        // The constants are in the meta, not in the rows; N varies: a column, named there.
        assert_eq!(meta["system"], json!({"E_cb": 0.2844, "box.0": 100.0}));
        assert_eq!(meta["system_columns"], json!(["sys.N"]));
        assert!(
            header.contains(&"sys.N") && !header.contains(&"sys.E_cb"),
            "{header:?}"
        );
        assert_eq!(meta["constant"]["obs.unit"], json!("E_cb"));
        assert_eq!(
            meta["constant"]["decided_on.reason"],
            json!("line one\nline \"two\"")
        );
        assert_eq!(meta["empty"], json!(["obs.gone"]));
        assert_eq!(meta["sweeps"], json!(["s"]));
        assert_eq!(meta["rows"], json!(2));
        assert_eq!(meta["wetgran_version"], json!(env!("CARGO_PKG_VERSION")));
    }

    #[test]
    fn the_json_has_the_csv_columns_in_order_with_typed_values() {
        let rows = vec![
            row("a", 0.5, json!({"t": 1.0, "s": [1, 2]})),
            row("b", 2.0, json!({"t": 2.5})),
        ];
        let (columns, csv, json) = export(&rows, false);
        assert!(json.starts_with("[\n"), "{json}");
        let v: Vec<serde_json::Map<String, Value>> = serde_json::from_str(&json).unwrap();
        assert_eq!(v.len(), 2);
        let names = columns.names();
        let header: Vec<String> = csv
            .lines()
            .next()
            .unwrap()
            .split(',')
            .map(String::from)
            .collect();
        assert_eq!(header, names);
        let mut keys: Vec<&String> = v[0].keys().collect();
        let mut want: Vec<&String> = names.iter().collect();
        keys.sort();
        want.sort();
        assert_eq!(keys, want);
        // In the text, the keys come in column order.
        let line = json.lines().nth(1).unwrap();
        assert!(line.find("\"drive.gamma\"").unwrap() < line.find("\"drive.e_star\"").unwrap());
        assert_eq!(v[1]["drive.gamma"], json!(2.0));
        assert_eq!(v[1]["obs.t"], json!(2.5));
        assert_eq!(v[0]["verdict"], json!("label_kept"));
        assert_eq!(v[0]["trust"], json!("~"));
        assert_eq!(v[0]["omega"], Value::Null);
        // The series stay out of both.
        assert!(!v[0].contains_key("obs.s"));
        let mut empty = Vec::new();
        Columns::new(false, false).finish(&mut empty).unwrap();
        assert_eq!(empty, b"[]\n");
    }

    #[test]
    fn the_series_file_holds_numbers_and_the_text_file_the_rest() {
        let r = row(
            "a",
            0.5,
            json!({"s": [1.5, null], "checks": [{"quantity": "T_g", "ok": true, "x": 0.25}]}),
        );
        let (_, series) = scalars_and_series(&r);
        let (mut numbers, mut text) = (Vec::new(), Vec::new());
        write_series(&mut numbers, SeriesFile::Numbers, &r, &series).unwrap();
        write_series(&mut text, SeriesFile::Text, &r, &series).unwrap();
        let numbers = String::from_utf8(numbers).unwrap();
        let text = String::from_utf8(text).unwrap();
        for line in numbers.lines() {
            let value = line.rsplit(',').next().unwrap();
            assert!(value.is_empty() || value.parse::<f64>().is_ok(), "{line}");
        }
        assert!(numbers.contains("a,obs.s,0,1.5\na,obs.s,1,\n"), "{numbers}");
        assert!(numbers.contains("a,obs.checks.x,0,0.25"), "{numbers}");
        assert!(text.contains("a,obs.checks.quantity,0,T_g"), "{text}");
        assert!(text.contains("a,obs.checks.ok,0,true"), "{text}");
        // decided_on's array t = [1, 2] is numeric.
        assert!(numbers.contains("a,decided_on.t,1,2"), "{numbers}");
    }
}
