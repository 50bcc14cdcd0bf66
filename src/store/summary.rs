//! Lean rows for the reports (issue 35): what `sweep status`, `boundaries` and `plot` read of
//! each job of a sweep, from indexed scalar columns (`results.phase`, `wall_seconds`, `trend`,
//! `converged`) instead of the observables JSON (7 to 150 kB per result) and the spec JSON of
//! every job that [`Store::points`] parses.
//!
//! The scene. The reports read of a job's scene only what sets its units and geometry: the
//! container motion `(A, omega)` from `(Gamma, E*)` needs `E_cb`, `m`, `g`, `d` and whether
//! the scene is wet (`boundary::drive_at`); `plot`'s landmarks and the chain model read the
//! particles, box, dimension, capillary and gravity; `boundaries` reads the drive kind and slab
//! width (`Scene::shear_slabs`); hysteresis reads the start mode. Every job of a sweep is an
//! expansion of the same sweep file (re-registering a changed file drops every point, refined
//! ones included: `delete_grid_points.sql`), so jobs differ only where the expansion sets
//! something per point: the axis values, the seed of a replica, the run length in periods, and
//! the start of a continuation chain's first job. The start mode is read per job from its column
//! `jobs.start_mode`. The rest is shared: where every axis key is one that changes
//! none of the fields above ([`axis_keeps_report_scene`]), each summary carries the scene of
//! the sweep's first job, parsed once; otherwise each carries its own job's scene, parsed from
//! its spec as [`Store::points`] does (a slower read, the same output).

use super::{PointRow, StateCounts, Store, StoreError, SweepRow, queries};
use crate::sweep::spec::JobSpec;
use sqlx::Row;
use std::sync::Arc;
use wetgran_core::observe::Verdict;
use wetgran_core::observe::trend::TrendState;
use wetgran_core::scene::{Scene, StartMode};

/// A row of the summary statements, as read (`sweep_point_summaries.sql`, or one element of
/// `sweep_point_summaries_packed.sql`: the same columns in the same order).
#[derive(Debug, serde::Deserialize)]
struct SummaryRow {
    point: i64,
    replica: i64,
    coords: Vec<serde_json::Value>,
    job_id: String,
    status: String,
    attempts: i64,
    last_error: Option<String>,
    job_wall_seconds: Option<f64>,
    start: Option<String>,
    spec: Option<String>,
    phase: Option<String>,
    wall_seconds: Option<f64>,
    trend: Option<String>,
    verdict: Option<String>,
}

/// One job of a sweep as the reports see it (see the module doc).
#[derive(Debug, Clone)]
pub struct PointSummary {
    pub point: i64,
    pub replica: i64,
    pub coords: Vec<serde_json::Value>,
    pub job_id: String,
    pub status: String,
    pub attempts: i64,
    pub last_error: Option<String>,
    /// The start mode of its spec (`initial.start`).
    pub start: StartMode,
    pub phase: Option<String>,
    /// Wall seconds of its result (`None` without a result).
    pub wall_seconds: Option<f64>,
    /// The result's trend state (`results.trend`).
    pub trend: Option<TrendState>,
    /// The verdict on the result's label (`results.verdict`); `None` without a result, or for
    /// a result stored before verdicts (outdated: its label may change).
    pub verdict: Option<Verdict>,
    /// A scene equal to the job's in every field the reports read (module doc); its axis
    /// values, seed, run length and start mode may be another job's of the same sweep.
    pub scene: Arc<Scene>,
}

impl PointSummary {
    /// The summary of a full row (the same values, read from the row's JSON).
    pub fn of_row(row: &PointRow) -> PointSummary {
        PointSummary {
            point: row.point,
            replica: row.replica,
            coords: row.coords.clone(),
            job_id: row.job_id.clone(),
            status: row.status.clone(),
            attempts: row.attempts,
            last_error: row.last_error.clone(),
            start: row.spec.scene.initial.start,
            phase: row.phase.clone(),
            wall_seconds: row.wall_seconds,
            trend: row.trend,
            verdict: row.verdict(),
            scene: Arc::new(row.spec.scene.clone()),
        }
    }

    /// The verdict on the label as the reports read it: a result without one (stored before
    /// verdicts) may change; no result yet reads as stationary (nothing to mark).
    pub fn trust(&self) -> Verdict {
        match (&self.phase, self.verdict) {
            (_, Some(v)) => v,
            (Some(_), None) => Verdict::NotSettled,
            (None, None) => Verdict::Stationary,
        }
    }
}

impl StateCounts {
    /// The jobs of a sweep by state, counted from its summaries: what [`Store::counts`] counts
    /// (its statement groups the same rows by status), without reading every job row again.
    pub fn of_summaries(points: &[PointSummary]) -> StateCounts {
        let mut c = StateCounts::default();
        for p in points {
            c.add(&p.status, 1);
        }
        c
    }
}

/// Results whose label had not settled, and results with a verdict: `(not settled, with a
/// verdict)`.
pub fn unconverged_summaries(points: &[PointSummary]) -> (u64, u64) {
    points
        .iter()
        .filter_map(|p| p.verdict)
        .fold((0, 0), |(u, n), v| {
            (u + u64::from(!v.label_trusted()), n + 1)
        })
}

/// Whether an axis with this (dotted scene) key leaves every scene field the reports read as
/// the base sets it (module doc): the drive's strength (`Gamma`, `E*`, `F_max`, `A`, `omega`;
/// the motion is recomputed from the coordinates), the seed, the start mode (read per job),
/// the initial temperature, and the run, observer, classifier, convergence and engine
/// settings.
pub fn axis_keeps_report_scene(key: &str) -> bool {
    const KEYS: [&str; 9] = [
        "drive.gamma",
        "drive.e_star",
        "drive.f_max",
        "drive.amplitude",
        "drive.omega",
        "initial.seed",
        "initial.start",
        "initial.temperature",
        "initial.temperature_over_ecb",
    ];
    const SECTIONS: [&str; 5] = ["run.", "observe.", "classify.", "convergence.", "engine."];
    KEYS.contains(&key) || SECTIONS.iter().any(|s| key.starts_with(s))
}

impl Store {
    /// Every job of a sweep (grid order) as the reports see it (module doc): one row per job
    /// from scalar columns, without the observables; the scene parsed once per sweep where its
    /// axes allow, else once per job.
    pub fn point_summaries(&self, sweep: &SweepRow) -> Result<Vec<PointSummary>, StoreError> {
        Ok(self.status_summaries(sweep)?.0)
    }

    /// [`Store::point_summaries`], and the wall time of the sweep's finished and failed jobs
    /// ([`Store::time_spent`], each job once) from the same rows.
    pub fn status_summaries(
        &self,
        sweep: &SweepRow,
    ) -> Result<(Vec<PointSummary>, f64), StoreError> {
        let every_spec = !sweep.axes.iter().all(|a| axis_keeps_report_scene(&a.key));
        let shared = if every_spec {
            None
        } else {
            self.first_scene(sweep.id)?
        };
        let rows = if every_spec {
            self.summary_rows_streamed(sweep.id)?
        } else {
            self.summary_rows_packed(sweep.id)?
        };
        let mut spent = 0.0;
        let mut counted: std::collections::HashSet<&str> = std::collections::HashSet::new();
        for r in &rows {
            if matches!(r.status.as_str(), "done" | "failed") && counted.insert(&r.job_id) {
                spent += r.job_wall_seconds.unwrap_or(0.0);
            }
        }
        let out = rows
            .into_iter()
            .map(|r| self.summary_of(r, shared.as_ref()))
            .collect::<Result<Vec<_>, _>>()?;
        Ok((out, spent))
    }

    /// The rows of `sweep_point_summaries.sql` with every spec, mapped as they arrive (a
    /// `fetch_all` would hold every row's SQLite values at once: ~1.3 kB a job).
    fn summary_rows_streamed(&self, sweep_id: i64) -> Result<Vec<SummaryRow>, StoreError> {
        self.rt.block_on(async {
            let mut out = Vec::new();
            let mut rows = sqlx::query(queries::SWEEP_POINT_SUMMARIES)
                .bind(sweep_id)
                .bind(true)
                .fetch(&self.pool);
            while let Some(r) = std::future::poll_fn(|cx| rows.as_mut().poll_next(cx)).await {
                let r = r.map_err(|e| self.db(e))?;
                out.push(SummaryRow {
                    point: r.get("point"),
                    replica: r.get("replica"),
                    coords: serde_json::from_str(r.get::<&str, _>("coords"))
                        .map_err(|e| self.damaged(format!("coords are not readable: {e}")))?,
                    job_id: r.get("job_id"),
                    status: r.get("status"),
                    attempts: r.get("attempts"),
                    last_error: r.get("last_error"),
                    job_wall_seconds: r.get("job_wall_seconds"),
                    start: r.get("start"),
                    spec: r.get("spec"),
                    phase: r.get("phase"),
                    wall_seconds: r.get("wall_seconds"),
                    trend: r.get("trend"),
                    verdict: r.get("verdict"),
                });
            }
            Ok(out)
        })
    }

    /// The rows of `sweep_point_summaries_packed.sql` (no specs), in grid order.
    fn summary_rows_packed(&self, sweep_id: i64) -> Result<Vec<SummaryRow>, StoreError> {
        let text: Option<String> = self.run(
            sqlx::query_scalar(queries::SWEEP_POINT_SUMMARIES_PACKED)
                .bind(sweep_id)
                .fetch_one(&self.pool),
        )?;
        let mut rows: Vec<SummaryRow> = match text {
            None => Vec::new(),
            Some(t) => serde_json::from_str(&t)
                .map_err(|e| self.damaged(format!("the report rows are not readable: {e}")))?,
        };
        rows.sort_by_key(|r| (r.point, r.replica));
        Ok(rows)
    }

    /// One row of the summary statements as a summary; `shared` the sweep's scene where every
    /// job shares it (else the row's spec is parsed).
    fn summary_of(
        &self,
        r: SummaryRow,
        shared: Option<&Arc<Scene>>,
    ) -> Result<PointSummary, StoreError> {
        let damaged = |what: &str, e: String| self.damaged(format!("{what} is not readable: {e}"));
        let job_id = r.job_id;
        let scene = match (shared, &r.spec) {
            (Some(s), _) => Arc::clone(s),
            (None, spec) => Arc::new(
                JobSpec::from_json(spec.as_deref().unwrap_or(""), &format!("job {job_id}"))
                    .map_err(|e| damaged("a job spec", e))?
                    .scene,
            ),
        };
        let start = match r.start {
            // Not written: the default (the spec leaves out a hot start).
            None => StartMode::default(),
            Some(s) => serde_json::from_value(serde_json::Value::String(s))
                .map_err(|e| damaged(&format!("the start of job {job_id}"), e.to_string()))?,
        };
        Ok(PointSummary {
            point: r.point,
            replica: r.replica,
            coords: r.coords,
            status: r.status,
            attempts: r.attempts,
            last_error: r.last_error,
            start,
            phase: r.phase,
            wall_seconds: r.wall_seconds,
            trend: r.trend.as_deref().and_then(TrendState::parse),
            verdict: r.verdict.as_deref().and_then(Verdict::parse),
            scene,
            job_id,
        })
    }

    /// The scene of a sweep's first job in grid order (`None`: the sweep has no job).
    fn first_scene(&self, sweep_id: i64) -> Result<Option<Arc<Scene>>, StoreError> {
        let row: Option<(String, String)> = self.run(
            sqlx::query_as(queries::SWEEP_FIRST_SPEC)
                .bind(sweep_id)
                .fetch_optional(&self.pool),
        )?;
        row.map(|(id, text)| {
            JobSpec::from_json(&text, &format!("job {id}"))
                .map(|spec| Arc::new(spec.scene))
                .map_err(|e| self.damaged(format!("a job spec is not readable: {e}")))
        })
        .transpose()
    }
}
