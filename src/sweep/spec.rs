//! Job specs: the self-contained description of one simulation of a sweep, its canonical JSON
//! and its content-hashed id, and the expansion of a sweep file into job specs.
//!
//! A job spec holds the complete, validated scene (every default filled in) and the observer
//! and classifier settings. Its canonical JSON has the object keys sorted at every level and the
//! numbers printed by `serde_json` (shortest text that reads back to the same `f64`); its id is
//! the SHA-256 of that text without the `[classify]` thresholds (which only label a result) in
//! hex. So a job written twice, in any key order, with or without keys at their default, or with
//! other thresholds, gets one id and is computed once across all sweeps of a database; a changed
//! parameter of the trajectory or of the observers is a new job. Nothing in a spec refers to its
//! sweep: the grid coordinates of a job live beside it in the sweep's point list.

use super::file::{Continuation, SweepError, SweepFile};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use wetgran_core::scene::Scene;

/// Version of the job-spec layout; part of the hashed text, so a change of layout is a new job.
pub const SPEC_FORMAT: u32 = 1;

/// Default number of samples per driving period where neither the sweep file nor its base scene
/// gives one: the observers' own default (the location-change counter needs fine sampling,
/// docs/observables.md).
pub const DEFAULT_SAMPLES_PER_PERIOD: f64 = 20.0;
/// Default transient, as a fraction of the run, where the sweep file gives none.
pub const DEFAULT_TRANSIENT_FRACTION: f64 = 0.25;

/// Everything needed to run one job, anywhere. Unknown keys are refused, as in a scene (a
/// misspelt `start_from` would silently run a continuation job hot).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JobSpec {
    /// [`SPEC_FORMAT`].
    pub format: u32,
    /// The validated scene, defaults filled in; `run.duration` and `run.sample_interval` already
    /// converted from driving periods. Its `[observe]` section (observers, sampling, transient)
    /// and `[classify]` thresholds come from the sweep file's tables of those names.
    pub scene: Scene,
    /// A continuation job (`initial.start = "continue"`): the id of the job whose final state
    /// it starts from, its neighbour along the sweep's continuation axis. Part of the id: the
    /// trajectory depends on it. Absent (and not serialized) for every other job.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_from: Option<String>,
}

impl JobSpec {
    /// The canonical JSON text: keys sorted at every level, no whitespace.
    pub fn canonical_json(&self) -> String {
        let v = serde_json::to_value(self).expect("a job spec serializes");
        canonical_json(&v)
    }

    /// The job's id: SHA-256 of the canonical JSON of [`JobSpec::identity`], lower-case hex.
    pub fn id(&self) -> String {
        id_of_canonical(&canonical_json(&self.identity()))
    }

    /// What the id hashes: the spec without the scene's `[classify]` thresholds, which do not
    /// change the trajectory or the observables (they only label a result, and the thresholds
    /// used are stored with it in `decided_on`; `wetgran reclassify` re-labels). Everything else,
    /// `[observe]` included, stays: the observables depend on the sampling and the observers
    /// (docs/model-choices.md, "Job identity").
    pub fn identity(&self) -> serde_json::Value {
        let mut v = serde_json::to_value(self).expect("a job spec serializes");
        if let Some(scene) = v.get_mut("scene").and_then(|s| s.as_object_mut()) {
            scene.remove("classify");
        }
        v
    }

    /// Reads a job spec from JSON (any key order) and validates its scene. Every error names
    /// `origin` and, where it has one, the key (`key `scene.particles.count``): the path of
    /// a value of the wrong type, of a missing or an unknown key.
    pub fn from_json(text: &str, origin: &str) -> Result<JobSpec, String> {
        let mut de = serde_json::Deserializer::from_str(text);
        let mut spec: JobSpec = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            // serde names a missing field in its message, below the path it recorded.
            let missing = inner
                .to_string()
                .strip_prefix("missing field `")
                .and_then(|r| r.split_once('`'))
                .map(|(f, _)| f.to_string());
            let key = match (path.as_str(), missing) {
                (".", Some(f)) => f,
                (p, Some(f)) => format!("{p}.{f}"),
                (".", None) => String::new(),
                (p, None) => p.to_string(),
            };
            if key.is_empty() {
                format!("{origin}: not a job spec: {inner}")
            } else {
                format!("{origin}: key `{key}`: not a job spec: {inner}")
            }
        })?;
        de.end()
            .map_err(|e| format!("{origin}: not a job spec: {e}"))?;
        spec.scene.resolve_observers();
        spec.scene.validate(origin).map_err(|e| e.to_string())?;
        if spec.format != SPEC_FORMAT {
            return Err(format!(
                "{origin}: key `format`: job spec format {} is not supported (this wetgran reads \
                 {SPEC_FORMAT})",
                spec.format
            ));
        }
        Ok(spec)
    }

    /// The scene's period ([`Scene::driving_period`]).
    pub fn period(&self) -> f64 {
        self.scene.driving_period()
    }
}

/// SHA-256 of a canonical JSON text, lower-case hex.
pub fn id_of_canonical(canonical: &str) -> String {
    let digest = Sha256::digest(canonical.as_bytes());
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// JSON text with object keys sorted at every level and no whitespace; scalars as `serde_json`
/// prints them (floats in the shortest form that reads back exactly). `serde_json`'s map is a
/// `BTreeMap` (the workspace leaves its `preserve_order` feature off), so its compact text has
/// the keys sorted already; the pinned ids of `tests/sweep_expand.rs` fail if that changes.
pub fn canonical_json(v: &serde_json::Value) -> String {
    serde_json::to_string(v).expect("a JSON value serializes")
}

/// One job of a sweep: its place in the grid and its spec.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SweepJob {
    /// Index of the grid point (row-major over the axes, the last axis fastest).
    pub point: usize,
    /// Replica number, `0 .. replicas`.
    pub replica: u32,
    /// The axis values of the point, in axis order.
    pub coords: Vec<serde_json::Value>,
    pub id: String,
    pub spec: JobSpec,
}

/// What every job of a sweep shares (see [`SweepFile::expand_with_skips`]).
#[derive(Debug, Clone, Copy)]
struct Prepared {
    samples_given: Option<f64>,
    samples_per_period: f64,
    transient: Option<f64>,
    base_seed: u64,
}

/// A grid point left out by `sweep.skip_invalid`.
#[derive(Debug, Clone, PartialEq)]
pub struct Skipped {
    pub point: usize,
    pub coords: Vec<serde_json::Value>,
    /// Why its scene was rejected (`reason.constraint` names the failed scene constraint).
    pub reason: SweepError,
}

/// Writes `value` at a dotted `key` in a TOML tree, creating tables on the way.
fn set_key(tree: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    let mut t = tree;
    for (k, part) in parts.iter().enumerate() {
        if k + 1 == parts.len() {
            // `name[i]`: element i of an existing array (`box.size[0]`).
            if let Some((name, rest)) = part.split_once('[') {
                let i: usize = rest
                    .trim_end_matches(']')
                    .parse()
                    .map_err(|_| format!("`{part}` is not `name[index]`"))?;
                return match t.get_mut(name) {
                    Some(toml::Value::Array(a)) if i < a.len() => {
                        a[i] = value;
                        Ok(())
                    }
                    Some(toml::Value::Array(a)) => Err(format!(
                        "`{key}`: index {i} is past the end of `{name}` ({} entries)",
                        a.len()
                    )),
                    _ => Err(format!(
                        "`{key}`: the scene has no array `{name}` to index (give it in the base \
                         scene or [scene])"
                    )),
                };
            }
            t.insert(part.to_string(), value);
            return Ok(());
        }
        let entry = t
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        t = match entry {
            toml::Value::Table(sub) => sub,
            other => {
                return Err(format!(
                    "`{}` is a {}, not a table: cannot set `{key}` in it",
                    parts[..=k].join("."),
                    other.type_str()
                ));
            }
        };
    }
    unreachable!("the loop returns at the last part")
}

/// A job's scene tree, its base `observe.transient_periods`, and the `[observe]` keys in time
/// units held back until the run length is known (see `SweepFile::point_tree`).
type PointTree = (toml::Table, Option<f64>, Vec<(&'static str, toml::Value)>);

impl SweepFile {
    /// Whether the scene tree (base scene plus the sweep's `[scene]` table) sets a dotted key.
    fn base_sets(&self, dotted: &str) -> bool {
        let mut parts = dotted.split('.');
        let Some(first) = parts.next() else {
            return false;
        };
        let mut node = self.scene_tree.get(first);
        for part in parts {
            node = node.and_then(|n| n.get(part));
        }
        node.is_some()
    }

    /// Expands the sweep into its jobs: every grid point times every replica, each with a
    /// validated scene. Errors name the sweep file (or base scene), the line and the key. With
    /// `sweep.skip_invalid` the points whose scene fails a scene constraint are left out (see
    /// [`SweepFile::expand_with_skips`]).
    pub fn expand(&self) -> Result<Vec<SweepJob>, SweepError> {
        Ok(self.expand_with_skips()?.0)
    }

    /// An error about key `observe.<key>` of the sweep file, at its line.
    fn observe_err(&self, key: &str, msg: String) -> SweepError {
        SweepError::new(
            &self.path.display().to_string(),
            super::file::key_line(&self.text, &["observe"], key),
            &format!("observe.{key}"),
            msg,
        )
    }

    /// `observe.<key>` of the sweep file as a number, if given.
    fn observe_number(&self, key: &str) -> Result<Option<f64>, SweepError> {
        match self.observe.get(key) {
            None => Ok(None),
            Some(toml::Value::Float(f)) => Ok(Some(*f)),
            Some(toml::Value::Integer(i)) => Ok(Some(*i as f64)),
            Some(other) => Err(self.observe_err(key, format!("= {other} is not a number"))),
        }
    }

    /// The settings every job of the sweep shares, checked.
    fn prepare(&self) -> Result<Prepared, SweepError> {
        let samples_given = self.observe_number("samples_per_period")?;
        let samples_per_period = samples_given.unwrap_or(DEFAULT_SAMPLES_PER_PERIOD);
        if !(samples_per_period.is_finite() && samples_per_period > 0.0) {
            return Err(self.observe_err(
                "samples_per_period",
                format!("= {samples_per_period} is out of range: must be finite and > 0"),
            ));
        }
        let transient = self.observe_number("transient_periods")?;
        if let Some(t) = transient
            && !(t.is_finite() && t >= 0.0)
        {
            return Err(self.observe_err(
                "transient_periods",
                format!("= {t} is out of range: must be finite and >= 0"),
            ));
        }

        // The base scene must be valid on its own terms only where no axis overrides it; each
        // job's scene is validated in full below.
        let base_seed = match self.scene_tree.get("initial").and_then(|i| i.get("seed")) {
            None => 0,
            Some(toml::Value::Integer(s)) if *s >= 0 => *s as u64,
            Some(other) => {
                let (f, l) = self.locate("initial.seed");
                return Err(SweepError::new(
                    &f,
                    l,
                    "initial.seed",
                    format!("= {other} is not an integer >= 0"),
                ));
            }
        };

        Ok(Prepared {
            samples_given,
            samples_per_period,
            transient,
            base_seed,
        })
    }

    /// [`SweepFile::expand`], also returning the grid points left out by `sweep.skip_invalid`
    /// with the reason (empty without it).
    pub fn expand_with_skips(&self) -> Result<(Vec<SweepJob>, Vec<Skipped>), SweepError> {
        self.expand_watched(&mut |_| {})
    }

    /// [`SweepFile::expand_with_skips`], calling `watch(grid points expanded so far)` every
    /// thousand points and at the end (the progress of a large grid).
    pub fn expand_watched(
        &self,
        watch: &mut dyn FnMut(usize),
    ) -> Result<(Vec<SweepJob>, Vec<Skipped>), SweepError> {
        let prep = self.prepare()?;
        let points = self.points();
        let mut jobs = Vec::with_capacity(points * self.replicas as usize);
        let mut skipped = Vec::new();
        let lens: Vec<usize> = self.axes.iter().map(|a| a.values.len()).collect();
        'points: for point in 0..points {
            if point % 1000 == 0 {
                watch(point);
            }
            let idx = grid_index(point, &lens);
            let coords: Vec<serde_json::Value> = self
                .axes
                .iter()
                .zip(&idx)
                .map(|(a, &i)| a.values[i].clone())
                .collect();
            for replica in 0..self.replicas {
                match self.job_at(&prep, point, replica, &coords)? {
                    Ok(job) => jobs.push(job),
                    Err(e) if self.skip_invalid => {
                        skipped.push(Skipped {
                            point,
                            coords: coords.clone(),
                            reason: e,
                        });
                        jobs.retain(|j: &SweepJob| j.point != point);
                        continue 'points;
                    }
                    Err(e) => return Err(e),
                }
            }
        }
        watch(points);
        self.chain_continuations(&mut jobs)?;
        Ok((jobs, skipped))
    }

    /// Links the continuation chains (`[sweep.continuation]`): the jobs whose
    /// `initial.start` is `"continue"`, grouped by their other coordinates and replica and
    /// ordered along the continuation axis. The first of a chain starts as
    /// `continuation.first` says; every other one names its predecessor in `start_from`, and
    /// the ids are recomputed in chain order (each id covers its predecessor's). Neighbours
    /// must share dimension, box, particles and gravity: the state passes between them.
    fn chain_continuations(&self, jobs: &mut [SweepJob]) -> Result<(), SweepError> {
        use wetgran_core::scene::StartMode;
        let file = self.path.display().to_string();
        let continuing = |j: &SweepJob| j.spec.scene.initial.start == StartMode::Continue;
        let Some(c) = self.continuation else {
            if let Some(j) = jobs.iter().find(|j| continuing(j)) {
                let (f, line) = self.locate("initial.start");
                return Err(SweepError::new(
                    &f,
                    line,
                    "initial.start",
                    format!(
                        "= \"continue\"{} needs a `[sweep.continuation]` table naming the axis \
                         to continue along",
                        describe_point(self, &j.coords, j.replica)
                    ),
                ));
            }
            return Ok(());
        };
        let mut chains: std::collections::BTreeMap<String, Vec<usize>> = Default::default();
        for (k, j) in jobs.iter().enumerate().filter(|(_, j)| continuing(j)) {
            let mut others = j.coords.clone();
            others.remove(c.axis);
            let key = format!("{}#{}", serde_json::Value::from(others), j.replica);
            chains.entry(key).or_default().push(k);
        }
        for members in chains.values_mut() {
            let at = |k: usize| jobs[k].coords[c.axis].as_f64().unwrap_or(f64::NAN);
            members.sort_by(|&a, &b| at(a).total_cmp(&at(b)));
            if c.descending {
                members.reverse();
            }
            for w in 0..members.len() {
                let k = members[w];
                if w == 0 {
                    self.start_as_chain_head(&mut jobs[k], c)?;
                } else {
                    let prev = &jobs[members[w - 1]];
                    let (a, b) = (&prev.spec.scene, &jobs[k].spec.scene);
                    if a.dimension != b.dimension
                        || a.container != b.container
                        || a.particles != b.particles
                        || a.gravity != b.gravity
                    {
                        return Err(SweepError::new(
                            &file,
                            Some(c.line),
                            "sweep.continuation.axis",
                            format!(
                                "{} changes the box, the particles or gravity between{} and{}: \
                                 a state cannot be continued across that",
                                self.axes[c.axis].key,
                                describe_point(self, &prev.coords, prev.replica),
                                describe_point(self, &jobs[k].coords, jobs[k].replica)
                            ),
                        ));
                    }
                    jobs[k].spec.start_from = Some(prev.id.clone());
                }
                jobs[k].id = jobs[k].spec.id();
            }
        }
        Ok(())
    }

    /// Gives `job` the start of a continuation chain's first job (`continuation.first`, no
    /// predecessor) and validates it again: the start mode is part of what validation checks
    /// (the time engine's damping calibration reads it). The caller recomputes the id.
    fn start_as_chain_head(&self, job: &mut SweepJob, c: Continuation) -> Result<(), SweepError> {
        job.spec.scene.initial.start = c.first;
        job.spec.start_from = None;
        let file = self.path.display().to_string();
        job.spec.scene.validate(&file).map_err(|e| {
            SweepError::new(
                &file,
                Some(c.line),
                &e.key,
                format!(
                    "{} as the first job of its continuation chain{}",
                    e.message,
                    describe_point(self, &job.coords, job.replica)
                ),
            )
        })
    }

    /// The jobs of one point at any coordinates (not only the grid's: refinement adds points
    /// between grid points), replicas `replicas`, expanded and validated as in
    /// [`SweepFile::expand`]. An invalid scene is an error here whatever `sweep.skip_invalid`
    /// says: `Ok(Err(reason))`.
    pub fn jobs_at(
        &self,
        point: usize,
        coords: &[serde_json::Value],
        replicas: std::ops::Range<u32>,
    ) -> Result<Result<Vec<SweepJob>, SweepError>, SweepError> {
        let prep = self.prepare()?;
        let mut out = Vec::new();
        for replica in replicas {
            match self.job_at(&prep, point, replica, coords)? {
                Ok(mut job) => {
                    // A point between grid points has no chain: it starts as a chain's first.
                    if let Some(c) = self.continuation
                        && job.spec.scene.initial.start == wetgran_core::scene::StartMode::Continue
                    {
                        if let Err(e) = self.start_as_chain_head(&mut job, c) {
                            return Ok(Err(e));
                        }
                        job.id = job.spec.id();
                    }
                    out.push(job)
                }
                Err(e) => return Ok(Err(e)),
            }
        }
        Ok(Ok(out))
    }

    /// The scene tree of one job before its conversion from periods: the base scene with the
    /// sweep's `[observe]`, `[classify]`, `[convergence]` tables, the point's axis values and the
    /// replica's seed. Returns it with the base scene's `observe.transient_periods` (replaced by
    /// a placeholder) and the `[observe]` keys in time units taken out of it, which are checked
    /// once the run length is known.
    fn point_tree(
        &self,
        coords: &[serde_json::Value],
        replica: u32,
        base_seed: u64,
    ) -> Result<PointTree, SweepError> {
        let file = self.path.display().to_string();
        let mut tree = self.scene_tree.clone();
        // The sweep's `[observe]`, `[classify]` and `[convergence]` tables go into the scene's
        // sections of those names (over what the base scene sets), validated with the scene.
        for (section, table) in [
            ("observe", &self.observe),
            ("classify", &self.classify),
            ("convergence", &self.convergence),
        ] {
            for (key, value) in table {
                set_key(&mut tree, &format!("{section}.{key}"), value.clone())
                    .map_err(|m| SweepError::new(&file, None, section, m))?;
            }
        }
        // The transient is checked against the run length once that is converted from
        // periods (below); until then it is a placeholder.
        let base_transient = tree
            .get("observe")
            .and_then(|o| o.get("transient_periods"))
            .and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)));
        set_key(
            &mut tree,
            "observe.transient_periods",
            toml::Value::Float(0.0),
        )
        .map_err(|m| SweepError::new(&file, None, "observe", m))?;
        // The same for the keys in time units that are checked against the first window.
        let mut deferred = Vec::new();
        for key in ["transient_time", "min_sample_interval"] {
            if let Some(v) = tree
                .get_mut("observe")
                .and_then(|o| o.as_table_mut())
                .and_then(|o| o.remove(key))
            {
                deferred.push((key, v));
            }
        }
        for (axis, v) in self.axes.iter().zip(coords) {
            // A JSON axis value as a TOML value, written at its key.
            toml::Value::try_from(v)
                .map_err(|e| format!("value {v} cannot be written to a scene: {e}"))
                .and_then(|value| set_key(&mut tree, &axis.key, value))
                .map_err(|m| SweepError::new(&file, Some(axis.line), &axis.key, m))?;
        }
        if self.replicas > 1 || replica > 0 {
            let seed = base_seed.checked_add(replica as u64).ok_or_else(|| {
                SweepError::new(&file, None, "initial.seed", "overflows with the replicas")
            })?;
            set_key(&mut tree, "initial.seed", toml::Value::Integer(seed as i64))
                .map_err(|m| SweepError::new(&file, None, "initial.seed", m))?;
        }
        if self.periods.is_some() {
            // The run length comes from `sweep.periods`; a placeholder lets a base scene
            // without `run.duration` parse (it is replaced below).
            let run = tree
                .entry("run")
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            if let toml::Value::Table(run) = run {
                run.entry("duration").or_insert(toml::Value::Float(1.0));
            }
        }
        Ok((tree, base_transient, deferred))
    }

    /// One job; `Ok(Err(_))`: its scene fails a constraint between keys
    /// ([`wetgran_core::scene::Constraint`], skippable), `Err(_)`: the sweep is invalid (a key outside
    /// its own range included).
    fn job_at(
        &self,
        prep: &Prepared,
        point: usize,
        replica: u32,
        coords: &[serde_json::Value],
    ) -> Result<Result<SweepJob, SweepError>, SweepError> {
        let file = self.path.display().to_string();
        let Prepared {
            samples_given,
            samples_per_period,
            transient,
            base_seed,
        } = *prep;
        let where_ = describe_point(self, coords, replica);
        let (mut tree, base_transient, deferred) = self.point_tree(coords, replica, base_seed)?;
        // `[convergence]` is checked against the run length, which `sweep.periods` sets
        // below: it joins the scene after that conversion (a base scene's own run length
        // would otherwise decide whether its cap is long enough).
        let convergence = if self.periods.is_some() {
            tree.remove("convergence")
        } else {
            None
        };
        let mut scene = match self.scene_of(&tree, &where_) {
            Ok(s) => s,
            // A point failing a constraint of the scene may be left out; a key outside its
            // own range is an error of the sweep file.
            Err(e) if e.constraint.is_some() => return Ok(Err(e)),
            Err(e) => return Err(e),
        };
        let period = scene.driving_period();
        if let Some(p) = self.periods {
            scene.run.duration = p * period;
        }
        if let Some(c) = convergence {
            scene.convergence = Some(c.try_into().map_err(|e: toml::de::Error| {
                // The field the error is about (an unknown or a missing one, or the table).
                let field = wetgran_core::scene::parse_error_key(&e);
                let key = match field.as_str() {
                    "" => "convergence".to_string(),
                    f => format!("convergence.{f}"),
                };
                let (file, line) = self.locate(&key);
                let line = line.or_else(|| self.own_table_line("convergence"));
                SweepError::new(&file, line, &key, format!("{}{where_}", e.message()))
            })?);
        }
        // Sampling: the sweep's `samples_per_period`, else the scene's own `[observe]`
        // setting if the base scene has one, else the sweep default.
        let samples_per_period =
            if samples_given.is_some() || !self.base_sets("observe.samples_per_period") {
                samples_per_period
            } else {
                scene.observe.samples_per_period
            };
        scene.run.sample_interval = period / samples_per_period;
        scene.observe.samples_per_period = samples_per_period;
        let transient_periods = match (transient, base_transient) {
            (Some(t), _) | (None, Some(t)) => t,
            (None, None) => DEFAULT_TRANSIENT_FRACTION * scene.run.duration / period,
        };
        scene.observe.transient_periods = transient_periods;
        for (key, v) in deferred {
            let Some(x) = v.as_float().or(v.as_integer().map(|i| i as f64)) else {
                return Err(self.observe_err(key, format!("= {v} is not a number{where_}")));
            };
            match key {
                "transient_time" => scene.observe.transient_time = x,
                _ => scene.observe.min_sample_interval = x,
            }
        }
        if transient_periods * period >= scene.run.duration {
            return Err(self.observe_err(
                "transient_periods",
                format!(
                    "= {transient_periods} periods is not shorter than the run \
                         ({} periods){where_}",
                    scene.run.duration / period
                ),
            ));
        }
        // The converted run length and sampling must pass validation too: an error of a key
        // of the sweep's own `[observe]` or `[convergence]` table points at it, any other at
        // `sweep.periods`, which did the converting.
        scene.validate(&file).map_err(|e| {
            let line = self.own_table_line(&e.key).or_else(|| {
                self.periods
                    .and(super::file::key_line(&self.text, &["sweep"], "periods"))
            });
            SweepError::new(&file, line, &e.key, format!("{}{where_}", e.message))
        })?;
        // The time engine's damping calibration is spelled out in the spec: its default
        // changed (issue 18, "engines like for like"), and a job id must not match a result
        // computed under the old default (speed 1).
        let c = &scene.contact;
        let converts = (c.damping.is_none() && c.restitution < 1.0)
            || (c.wall_damping.is_none() && c.wall_restitution < 1.0);
        if scene.engine.kind == wetgran_core::scene::EngineKind::Time
            && converts
            && c.restitution_speed.is_none()
        {
            scene.contact.restitution_speed = Some(wetgran_core::scene::RestitutionSpeed::Word(
                wetgran_core::scene::AutoWord::Auto,
            ));
        }
        let spec = JobSpec {
            format: SPEC_FORMAT,
            scene,
            start_from: None,
        };
        let id = spec.id();
        Ok(Ok(SweepJob {
            point,
            replica,
            coords: coords.to_vec(),
            id,
            spec,
        }))
    }

    /// Parses and validates one job's scene tree; errors point at the axis, the `[scene]` table
    /// or the base file that set the offending key.
    fn scene_of(&self, tree: &toml::Table, where_: &str) -> Result<Scene, SweepError> {
        let text = toml::to_string(tree).map_err(|e| {
            SweepError::new(
                &self.path.display().to_string(),
                None,
                "scene",
                e.to_string(),
            )
        })?;
        let origin = self.path.display().to_string();
        Scene::from_toml_str(&text, &origin).map_err(|e| {
            let (file, line) = self.locate(&e.key);
            // A parse-level message from the re-serialized tree carries a position in and a
            // snippet of that text, not of the user's file: keep only what it says is wrong.
            let message = e
                .message
                .lines()
                .filter(|l| !l.starts_with("TOML parse error") && !is_snippet_line(l))
                .collect::<Vec<_>>()
                .join(" ");
            let mut out = SweepError::new(&file, line, &e.key, format!("{message}{where_}"));
            out.constraint = e.constraint;
            out
        })
    }
}

/// Whether `line` is a line of the source snippet a TOML error prints (`  |`, `6 | key = ...`,
/// `  |   ^^^`): an optional line number, then ` |` at its start. The reason below it may hold
/// a `|` of its own (`unknown variant `a|b``).
fn is_snippet_line(line: &str) -> bool {
    line.trim_start_matches(|c: char| c.is_ascii_digit())
        .trim_start()
        .starts_with('|')
}

/// A grid point's index along each axis of lengths `lens` (row-major, the last axis fastest).
pub(crate) fn grid_index(point: usize, lens: &[usize]) -> Vec<usize> {
    let mut rest = point;
    let mut index = vec![0; lens.len()];
    for (a, &len) in lens.iter().enumerate().rev() {
        index[a] = rest % len;
        rest /= len;
    }
    index
}

/// `" (at Gamma = 2, E* = 3, replica 1)"` for error messages.
fn describe_point(file: &SweepFile, coords: &[serde_json::Value], replica: u32) -> String {
    if file.axes.is_empty() && file.replicas == 1 {
        return String::new();
    }
    let mut parts: Vec<String> = file
        .axes
        .iter()
        .zip(coords)
        .map(|(a, v)| format!("{} = {v}", a.label))
        .collect();
    if file.replicas > 1 {
        parts.push(format!("replica {replica}"));
    }
    format!(" (at {})", parts.join(", "))
}
