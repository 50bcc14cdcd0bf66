//! Sweep files: what a user writes to describe a phase-diagram sweep (TOML), and the errors that
//! point at the file, line and key of a bad value.
//!
//! A sweep file has a `[sweep]` header (name, optional base scene file, replicas, run length in
//! driving periods), an optional inline `[scene]` table merged over the base scene, optional
//! `[observe]` and `[classify]` tables handed to the observers and the classifier, an optional
//! `[convergence]` table (the run-length policy, `scene::convergence`), and one
//! `[[axis]]` table per swept scene key. An axis is a list (`values = [...]`), a linear range
//! (`linear = { from, to, steps }`) or a logarithmic range (`log = { from, to, steps }`).
//! The shaking axes `gamma` (`drive.gamma`), `e_star` (`drive.e_star`), `e_d_star` (`drive.e_star`
//! of a dry scene) and the shear force `f_max` (`drive.f_max`) are short names; any other scene
//! key is written in dotted form (`capillary.e_cb`, `contact.restitution`).

mod continuation;

use continuation::parse_continuation;
pub use continuation::{Continuation, RawContinuation};
use serde::Deserialize;
use std::fmt;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Why a sweep file (or a job it expands to) was rejected.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepError {
    /// The file the bad value is in (the sweep file or its base scene).
    pub file: String,
    /// 1-based line of the bad value, where known.
    pub line: Option<usize>,
    /// The offending key in dotted form, empty for syntax errors.
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
    /// The scene constraint the point fails, for an invalid grid point (each key in its own
    /// range, their combination not); only such points may be left out by `skip_invalid`.
    pub constraint: Option<wetgran_core::scene::Constraint>,
}

impl SweepError {
    pub(crate) fn new(
        file: &str,
        line: Option<usize>,
        key: &str,
        message: impl Into<String>,
    ) -> Self {
        Self {
            file: file.to_string(),
            line,
            key: key.to_string(),
            message: message.into(),
            constraint: None,
        }
    }
}

impl fmt::Display for SweepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        if !self.key.is_empty() {
            write!(f, ": key `{}`", self.key)?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for SweepError {}

/// The `[sweep]` header.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    /// Name of the sweep in the database (letters, digits, `-`, `_`, `.`).
    pub name: Spanned<String>,
    /// Free text shown by `sweep status`.
    pub description: Option<String>,
    /// Base scene file, relative to the sweep file.
    pub base: Option<Spanned<String>>,
    /// Independent runs per grid point; replica `r` uses `initial.seed = base seed + r`. Read
    /// as any TOML integer, so that a value beyond `u32` gets the range of the key.
    #[serde(default = "one")]
    pub replicas: Spanned<i64>,
    /// Run length in driving periods `T = 2 pi / omega` (one time unit `sqrt(d/g)` without a
    /// drive); sets `run.duration`. Without it the base scene's `run.duration` is kept.
    pub periods: Option<Spanned<f64>>,
    /// Free-text cost note for long runs (shown by `sweep status`).
    pub cost: Option<String>,
    /// Leave out grid points whose scene fails a constraint between keys
    /// ([`wetgran_core::scene::Constraint`], e.g. more grains than fit in the box) instead of rejecting
    /// the sweep; a key outside its own range is still an error. They are listed by
    /// `sweep expand`, `sweep run` and `sweep status`.
    #[serde(default)]
    pub skip_invalid: bool,
    /// `[sweep.continuation]`: run the points along one axis as chains, each starting from its
    /// neighbour's final state.
    pub continuation: Option<Spanned<RawContinuation>>,
}

fn one() -> Spanned<i64> {
    Spanned::new(0..0, 1)
}

/// A linear or logarithmic range: `steps` values from `from` to `to`, both included.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    pub from: f64,
    pub to: f64,
    pub steps: usize,
}

/// One `[[axis]]` table as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawAxis {
    pub key: Spanned<String>,
    pub values: Option<Spanned<Vec<toml::Value>>>,
    pub linear: Option<Spanned<Range>>,
    pub log: Option<Spanned<Range>>,
}

/// The whole file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSweep {
    pub sweep: Header,
    pub scene: Option<toml::Table>,
    pub observe: Option<toml::Table>,
    pub classify: Option<toml::Table>,
    /// Run to stationarity: the scene's `[convergence]` keys for every job.
    pub convergence: Option<toml::Table>,
    #[serde(default, rename = "axis")]
    pub axes: Vec<RawAxis>,
    pub refine: Option<RawRefine>,
}

/// The `[refine]` table as written (adaptive refinement of the boundaries, `src/refine`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawRefine {
    /// Jobs refinement may add to the sweep in all.
    pub budget: usize,
    pub rounds: Option<usize>,
    pub resolution: Option<f64>,
    /// Any TOML integer (checked against its range in [`parse_refine`]).
    pub max_replicas: Option<i64>,
}

/// The `[refine]` table, checked: after the grid, `sweep run` adds up to `budget` jobs in rounds
/// of `budget / rounds` where neighbouring points differ in phase, until every boundary edge
/// spans at most `resolution` of each plane axis' range; noisy points get replicas up to
/// `max_replicas`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineSection {
    pub budget: usize,
    /// Default 4.
    pub rounds: usize,
    /// Default 0 (stop at the budget only).
    pub resolution: f64,
    /// Default 3 times `sweep.replicas`.
    pub max_replicas: u32,
}

/// How an axis was written (the plot and the boundary extraction use log scaling for `Log`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AxisKind {
    Values,
    Linear,
    Log,
}

/// A swept scene key with its expanded values.
#[derive(Debug, Clone, PartialEq, serde::Serialize, Deserialize)]
pub struct Axis {
    /// The key as written (`gamma`, `drive.gamma`, `capillary.e_cb`).
    pub name: String,
    /// The dotted scene key the values are written to (`drive.gamma`).
    pub key: String,
    /// Label for tables and plots (`Gamma`, `E*`, `E_d*`, `F_max`, or the key).
    pub label: String,
    pub kind: AxisKind,
    /// The values, as TOML values turned into JSON (numbers, strings, booleans, arrays).
    pub values: Vec<serde_json::Value>,
    /// Line of the axis table in the sweep file.
    #[serde(skip)]
    pub line: usize,
}

impl Axis {
    /// Whether this axis is the peak acceleration `Gamma` (docs/model.md 4.1).
    pub fn is_gamma(&self) -> bool {
        self.key == "drive.gamma"
    }
    /// Whether this axis is the driving energy `E*` or `E_d*` (docs/model.md 4.1).
    pub fn is_e_star(&self) -> bool {
        self.key == "drive.e_star"
    }
}

/// The short names of the first-class axes: (name, scene key, label).
pub const AXIS_ALIASES: [(&str, &str, &str); 5] = [
    ("gamma", "drive.gamma", "Gamma"),
    ("e_star", "drive.e_star", "E*"),
    ("e_d_star", "drive.e_star", "E_d*"),
    ("f_max", "drive.f_max", "F_max"),
    ("l_x", "box.size[0]", "L_x"),
];

/// A parsed sweep file: the header, the base scene tree (base file merged with `[scene]`), the
/// observer and classifier settings and the expanded axes.
#[derive(Debug, Clone)]
pub struct SweepFile {
    /// The sweep file as given on the command line.
    pub path: PathBuf,
    /// Its text (stored with the sweep in the database).
    pub text: String,
    pub name: String,
    pub description: Option<String>,
    pub cost: Option<String>,
    pub skip_invalid: bool,
    pub replicas: u32,
    pub periods: Option<f64>,
    /// The base scene file (resolved against the sweep file's folder) and its text.
    pub base: Option<(PathBuf, String)>,
    /// Base scene merged with the sweep file's `[scene]` table.
    pub scene_tree: toml::Table,
    pub observe: toml::Table,
    pub classify: toml::Table,
    /// The `[convergence]` table (run-length policy), handed to every job's scene.
    pub convergence: toml::Table,
    pub axes: Vec<Axis>,
    /// The `[refine]` table, if any.
    pub refine: Option<RefineSection>,
    /// `[sweep.continuation]`, if any.
    pub continuation: Option<Continuation>,
}

/// Line (1-based) of byte offset `pos` in `text`.
pub(crate) fn line_of(text: &str, pos: usize) -> usize {
    text[..pos.min(text.len())].matches('\n').count() + 1
}

/// The line of a dotted key (`drive.gamma`, `box.size[1]` is looked up as `box.size`) in a TOML
/// text, below the table path `prefix` (empty for the top level).
pub(crate) fn key_line(text: &str, prefix: &[&str], key: &str) -> Option<usize> {
    use toml::de::{DeTable, DeValue};
    let table = DeTable::parse(text).ok()?;
    let key = key.split('[').next().unwrap_or(key);
    let path: Vec<&str> = prefix
        .iter()
        .copied()
        .chain(key.split('.').filter(|s| !s.is_empty()))
        .collect();
    let mut current: &DeTable = table.get_ref();
    let mut found = None;
    for (k, part) in path.iter().enumerate() {
        let (name, value) = current
            .iter()
            .find(|(n, _)| n.get_ref().as_ref() == *part)?;
        found = Some(name.span().start);
        if k + 1 < path.len() {
            match value.get_ref() {
                DeValue::Table(t) => current = t,
                _ => return found.map(|p| line_of(text, p)),
            }
        }
    }
    found.map(|p| line_of(text, p))
}

/// `steps` values of a linear or logarithmic range, both ends included.
pub fn range_values(r: &Range, log: bool) -> Vec<f64> {
    if r.steps == 1 {
        return vec![r.from];
    }
    (0..r.steps)
        .map(|k| {
            let t = k as f64 / (r.steps - 1) as f64;
            if k == r.steps - 1 {
                r.to
            } else if log {
                // Geometric spacing: from * (to / from)^t.
                (r.from.ln() + t * (r.to.ln() - r.from.ln())).exp()
            } else {
                r.from + t * (r.to - r.from)
            }
        })
        .collect()
}

/// Deep merge: entries of `over` replace those of `base`, tables merge recursively.
pub(crate) fn merge_tables(base: &mut toml::Table, over: &toml::Table) {
    for (k, v) in over {
        match (base.get_mut(k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge_tables(b, o),
            _ => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}

/// Most points a sweep may expand to (grid points times replicas).
pub const MAX_JOBS: usize = 1_000_000;

impl SweepFile {
    /// Reads and parses a sweep file (and its base scene), without expanding it into jobs.
    pub fn load(path: &Path) -> Result<SweepFile, SweepError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| {
            SweepError::new(&file, None, "", format!("cannot read the sweep file: {e}"))
        })?;
        Self::parse(&text, path)
    }

    /// Parses a sweep file's text; `path` names it in errors and anchors the base scene path.
    pub fn parse(text: &str, path: &Path) -> Result<SweepFile, SweepError> {
        let file = path.display().to_string();
        let raw: RawSweep = toml::from_str(text).map_err(|e| toml_error(&file, text, &e))?;
        let src = Source { text, file: &file };
        let (name, replicas, periods) = parse_header(&src, &raw.sweep)?;
        let (mut scene_tree, base) = parse_base_scene(&src, &raw, path)?;
        let mut axes: Vec<Axis> = Vec::new();
        for a in &raw.axes {
            let axis = parse_axis(&src, a, &axes, replicas)?;
            axes.push(axis);
        }
        check_job_count(&src, &axes, replicas)?;
        let refine = match &raw.refine {
            None => None,
            Some(r) => Some(parse_refine(&src, r, replicas, &axes)?),
        };
        let continuation = match &raw.sweep.continuation {
            None => None,
            Some(c) => Some(parse_continuation(text, &file, c, &axes, &mut scene_tree)?),
        };
        Ok(SweepFile {
            continuation,
            refine,
            path: path.to_path_buf(),
            text: text.to_string(),
            name,
            description: raw.sweep.description.clone(),
            cost: raw.sweep.cost.clone(),
            skip_invalid: raw.sweep.skip_invalid,
            replicas,
            periods,
            base,
            scene_tree,
            observe: raw.observe.unwrap_or_default(),
            classify: raw.classify.unwrap_or_default(),
            convergence: raw.convergence.unwrap_or_default(),
            axes,
        })
    }

    /// Number of grid points (product of the axis lengths).
    pub fn points(&self) -> usize {
        self.axes.iter().map(|a| a.values.len()).product()
    }

    /// The line of `key` (`convergence.blocks`) in the sweep file's own `[observe]`,
    /// `[classify]` or `[convergence]` table, where it sets that key; the table's header line
    /// for the bare section name (`convergence`).
    pub(crate) fn own_table_line(&self, key: &str) -> Option<usize> {
        let bare = key.split('[').next().unwrap_or(key);
        let section = bare.split('.').next().unwrap_or(bare);
        if !matches!(section, "observe" | "classify" | "convergence") {
            return None;
        }
        key_line(&self.text, &[], key)
    }

    /// Where a scene key's value comes from, for error messages: the axis that sets it, the
    /// inline `[scene]` table of the sweep file, or the base scene file.
    pub(crate) fn locate(&self, key: &str) -> (String, Option<usize>) {
        let file = self.path.display().to_string();
        let bare = key.split('[').next().unwrap_or(key);
        if let Some(a) = self.axes.iter().find(|a| a.key == bare) {
            return (file, Some(a.line));
        }
        // The sweep's own `[observe]`, `[classify]` and `[convergence]` tables set the scene
        // sections of those names over the base scene.
        if let Some(l) = self.own_table_line(key) {
            return (file, Some(l));
        }
        if let Some(l) = key_line(&self.text, &["scene"], key) {
            return (file, Some(l));
        }
        if let Some((p, t)) = &self.base
            && let Some(l) = key_line(t, &[], key)
        {
            return (p.display().to_string(), Some(l));
        }
        match &self.base {
            Some((p, _)) => (p.display().to_string(), None),
            None => (file, key_line(&self.text, &[], "scene")),
        }
    }
}

/// A scene tree with, where there is one, the base scene file's path and text.
type SceneTree = (toml::Table, Option<(PathBuf, String)>);

/// The text and name of the sweep file being parsed, for errors with a line.
struct Source<'a> {
    text: &'a str,
    file: &'a str,
}

impl Source<'_> {
    fn err(&self, line: Option<usize>, key: &str, msg: String) -> SweepError {
        SweepError::new(self.file, line, key, msg)
    }
}

/// The `[sweep]` header: name, replicas and run length in periods, checked.
fn parse_header(src: &Source<'_>, h: &Header) -> Result<(String, u32, Option<f64>), SweepError> {
    let name = h.name.get_ref().trim().to_string();
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
    {
        return Err(src.err(
            Some(line_of(src.text, h.name.span().start)),
            "sweep.name",
            format!(
                "= {name:?} is not allowed: must be non-empty letters, digits, '-', '_' or '.'"
            ),
        ));
    }
    // A name is a word of the commands that name it (`sweep resume NAME`, `--sweep NAME`):
    // one starting with `-` reads as an option there, and `.`, `..` as folders.
    if name.starts_with('-') || name == "." || name == ".." {
        return Err(src.err(
            Some(line_of(src.text, h.name.span().start)),
            "sweep.name",
            format!(
                "= {name:?} is not allowed: must not start with '-' (it would read as an option \
                 in `wetgran sweep resume NAME`) nor be \".\" or \"..\""
            ),
        ));
    }
    let replicas = *h.replicas.get_ref();
    if !(1..=10_000).contains(&replicas) {
        return Err(src.err(
            key_line(src.text, &["sweep"], "replicas"),
            "sweep.replicas",
            format!("= {replicas} is out of range: must be in [1, 10000]"),
        ));
    }
    let replicas = replicas as u32;
    let periods = match &h.periods {
        Some(p) => {
            let v = *p.get_ref();
            if !(v.is_finite() && v > 0.0) {
                return Err(src.err(
                    Some(line_of(src.text, p.span().start)),
                    "sweep.periods",
                    format!("= {v} is out of range: must be finite and > 0"),
                ));
            }
            Some(v)
        }
        None => None,
    };
    Ok((name, replicas, periods))
}

/// The base scene: the file (relative to the sweep file) merged with the inline `[scene]`;
/// also the base file's path and text, for error locations.
fn parse_base_scene(
    src: &Source<'_>,
    raw: &RawSweep,
    path: &Path,
) -> Result<SceneTree, SweepError> {
    let mut scene_tree = toml::Table::new();
    let mut base = None;
    if let Some(b) = &raw.sweep.base {
        let dir = path.parent().unwrap_or(Path::new(""));
        let base_path = dir.join(b.get_ref());
        let base_text = std::fs::read_to_string(&base_path).map_err(|e| {
            src.err(
                Some(line_of(src.text, b.span().start)),
                "sweep.base",
                format!("cannot read the base scene {}: {e}", base_path.display()),
            )
        })?;
        let base_file = base_path.display().to_string();
        scene_tree =
            toml::from_str(&base_text).map_err(|e| toml_error(&base_file, &base_text, &e))?;
        base = Some((base_path, base_text));
    }
    if let Some(over) = &raw.scene {
        merge_tables(&mut scene_tree, over);
    }
    if scene_tree.is_empty() {
        return Err(src.err(
            None,
            "sweep.base",
            "no scene: give a base scene file (`base = \"scene.toml\"` under [sweep]) or a \
             [scene] table"
                .to_string(),
        ));
    }
    Ok((scene_tree, base))
}

/// One `[[axis]]`: its key (or short name), checked against the axes before it, and its values.
fn parse_axis(
    src: &Source<'_>,
    a: &RawAxis,
    axes: &[Axis],
    replicas: u32,
) -> Result<Axis, SweepError> {
    let line = line_of(src.text, a.key.span().start);
    let name = a.key.get_ref().trim().to_string();
    let (key, label) = match AXIS_ALIASES.iter().find(|(n, _, _)| *n == name) {
        Some((_, key, label)) => (key.to_string(), label.to_string()),
        None => (name.clone(), name.clone()),
    };
    // Dotted identifiers; the last part may index an array (`box.size[0]`).
    let ident = |p: &str| !p.is_empty() && p.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    let parts: Vec<&str> = key.split('.').collect();
    let last_ok = |p: &str| match p.split_once('[') {
        Some((name, rest)) => {
            ident(name)
                && rest
                    .strip_suffix(']')
                    .is_some_and(|d| !d.is_empty() && d.chars().all(|c| c.is_ascii_digit()))
        }
        None => ident(p),
    };
    if key.is_empty()
        || !parts[..parts.len() - 1].iter().all(|p| ident(p))
        || !last_ok(parts[parts.len() - 1])
    {
        return Err(src.err(
            Some(line),
            "axis.key",
            format!(
                "= {name:?} is not a scene key: write a dotted key such as \
                 \"drive.gamma\" (or \"box.size[0]\") or one of gamma, e_star, e_d_star, f_max, l_x"
            ),
        ));
    }
    if axes.iter().any(|b| b.key == key) {
        return Err(src.err(
            Some(line),
            &key,
            "appears on two axes: each scene key may be swept once".to_string(),
        ));
    }
    if key == "initial.seed" && replicas > 1 {
        return Err(src.err(
            Some(line),
            &key,
            "is swept while sweep.replicas > 1 also sets the seed: use one of the two".to_string(),
        ));
    }
    let (kind, values) = axis_values(src, a, &key)?;
    Ok(Axis {
        name,
        key,
        label,
        kind,
        values,
        line,
    })
}

/// The values of an axis: exactly one of a `values` list, a `linear` or a `log` range, checked.
fn axis_values(
    src: &Source<'_>,
    a: &RawAxis,
    key: &str,
) -> Result<(AxisKind, Vec<serde_json::Value>), SweepError> {
    let line = line_of(src.text, a.key.span().start);
    let given = [a.values.is_some(), a.linear.is_some(), a.log.is_some()];
    if given.iter().filter(|g| **g).count() != 1 {
        return Err(src.err(
            Some(line),
            key,
            "needs exactly one of `values = [...]`, `linear = { from, to, steps }` or \
             `log = { from, to, steps }`"
                .to_string(),
        ));
    }
    let (kind, values) = if let Some(v) = &a.values {
        let vline = Some(line_of(src.text, v.span().start));
        if v.get_ref().is_empty() {
            return Err(src.err(vline, key, "has an empty `values` list".to_string()));
        }
        let mut out = Vec::new();
        for x in v.get_ref() {
            if let toml::Value::Float(f) = x
                && !f.is_finite()
            {
                return Err(src.err(vline, key, format!("value {f} is not a finite number")));
            }
            let j = serde_json::to_value(x)
                .map_err(|e| src.err(vline, key, format!("value {x} cannot be used: {e}")))?;
            if out.contains(&j) {
                return Err(src.err(vline, key, format!("value {x} appears twice")));
            }
            out.push(j);
        }
        (AxisKind::Values, out)
    } else {
        let (r, log) = match (&a.linear, &a.log) {
            (Some(r), _) => (r, false),
            (None, Some(r)) => (r, true),
            _ => unreachable!("one of the three is given"),
        };
        let rline = Some(line_of(src.text, r.span().start));
        let Range { from, to, steps } = *r.get_ref();
        let bad = |msg: String| Err(src.err(rline, key, msg));
        if !(from.is_finite() && to.is_finite()) {
            return bad("range ends must be finite numbers".to_string());
        }
        if steps == 0 || steps > 100_000 {
            return bad(format!(
                "steps = {steps} is out of range: must be in [1, 100000]"
            ));
        }
        if steps == 1 && from != to {
            return bad(format!(
                "steps = 1 with from = {from} != to = {to}: a range needs steps >= 2 (or write \
                 `values = [{from}]` for one value)"
            ));
        }
        if steps > 1 && from == to {
            return bad(format!(
                "from = to = {from} with steps = {steps}: the values would repeat"
            ));
        }
        if log && !(from > 0.0 && to > 0.0) {
            return bad(format!(
                "log range from {from} to {to}: both ends must be > 0"
            ));
        }
        let vals = range_values(r.get_ref(), log)
            .into_iter()
            .map(|x| serde_json::json!(x))
            .collect();
        (if log { AxisKind::Log } else { AxisKind::Linear }, vals)
    };
    Ok((kind, values))
}

/// The axes and replicas may expand to at most [`MAX_JOBS`] jobs.
fn check_job_count(src: &Source<'_>, axes: &[Axis], replicas: u32) -> Result<(), SweepError> {
    let jobs = axes
        .iter()
        .try_fold(replicas as usize, |n, a| n.checked_mul(a.values.len()))
        .unwrap_or(usize::MAX);
    if jobs > MAX_JOBS {
        return Err(src.err(
            None,
            "axis",
            format!("expands to {jobs} jobs: at most {MAX_JOBS} are allowed"),
        ));
    }
    Ok(())
}

/// The `[refine]` table, checked against the header and the axes.
fn parse_refine(
    src: &Source<'_>,
    r: &RawRefine,
    replicas: u32,
    axes: &[Axis],
) -> Result<RefineSection, SweepError> {
    let rerr = |key: &str, msg: String| {
        src.err(
            key_line(src.text, &["refine"], key),
            &format!("refine.{key}"),
            msg,
        )
    };
    if !(1..=MAX_JOBS).contains(&r.budget) {
        return Err(rerr(
            "budget",
            format!("= {} is out of range: must be in [1, {MAX_JOBS}]", r.budget),
        ));
    }
    let rounds = r.rounds.unwrap_or(4);
    if !(1..=r.budget).contains(&rounds) {
        return Err(rerr(
            "rounds",
            format!(
                "= {rounds} is out of range: must be in [1, budget = {}]",
                r.budget
            ),
        ));
    }
    let resolution = r.resolution.unwrap_or(0.0);
    if !(0.0..1.0).contains(&resolution) {
        return Err(rerr(
            "resolution",
            format!("= {resolution} is out of range: must be in [0, 1)"),
        ));
    }
    let max_replicas = r.max_replicas.unwrap_or(3 * i64::from(replicas));
    if !(i64::from(replicas)..=10_000).contains(&max_replicas) {
        return Err(rerr(
            "max_replicas",
            format!(
                "= {max_replicas} is out of range: must be in [sweep.replicas = \
                     {replicas}, 10000]"
            ),
        ));
    }
    let max_replicas = max_replicas as u32;
    if axes.iter().any(|a| a.key == "initial.seed") && max_replicas > replicas {
        return Err(rerr(
            "max_replicas",
            format!(
                "= {max_replicas} adds replicas (seeds) while an axis sweeps \
                     initial.seed: set it to sweep.replicas = {replicas}"
            ),
        ));
    }
    Ok(RefineSection {
        budget: r.budget,
        rounds,
        resolution,
        max_replicas,
    })
}

/// A TOML syntax or type error with its line and (where the message names one) key.
fn toml_error(file: &str, text: &str, e: &toml::de::Error) -> SweepError {
    let line = e.span().map(|s| line_of(text, s.start));
    let msg = e.message().trim_end().to_string();
    // The table path the deserializer recorded plus the field of an unknown or missing key
    // (`sweep.replicas`, `axis.linear.steps`), as for a scene.
    let key = wetgran_core::scene::parse_error_key(e);
    let msg = msg
        .replace("expected usize", "expected an integer >= 0")
        .replace("expected u32", "expected an integer >= 0")
        .replace("expected f64", "expected a number");
    SweepError::new(file, line, &key, msg)
}
