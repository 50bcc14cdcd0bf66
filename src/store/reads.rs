//! The report reads: integrity, counts by state, a sweep's jobs with their results (whole or
//! page by page), job specs and checkpoints, what finished jobs cost, and the criterion that
//! decided each label.

use super::{POINTS_PAGE, PointRow, StateCounts, Store, StoreError, queries};
use crate::sweep::estimate::MeasuredCost;
use crate::sweep::spec::JobSpec;
use sqlx::Row;
use std::collections::HashMap;
use wetgran_core::observe::Verdict;
use wetgran_core::observe::criterion::DecidedBy;

impl Store {
    /// The spec of a job, if the database has it.
    pub fn job_spec(&self, job_id: &str) -> Result<Option<JobSpec>, StoreError> {
        let row: Option<(String,)> = self.run(
            sqlx::query_as(queries::JOB_SPEC)
                .bind(job_id)
                .fetch_optional(&self.pool),
        )?;
        row.map(|(s,)| {
            JobSpec::from_json(&s, &format!("job {job_id}"))
                .map_err(|e| self.damaged(format!("the spec of job {job_id} is not readable: {e}")))
        })
        .transpose()
    }

    /// The checkpoint (final state) of a finished job, if one was stored.
    pub fn checkpoint(
        &self,
        job_id: &str,
    ) -> Result<Option<wetgran_core::sim::EngineState>, StoreError> {
        let row: Option<(String,)> = self.run(
            sqlx::query_as(queries::CHECKPOINT_STATE)
                .bind(job_id)
                .fetch_optional(&self.pool),
        )?;
        row.map(|(s,)| {
            serde_json::from_str(&s).map_err(|e| {
                self.damaged(format!(
                    "the checkpoint of job {job_id} is not readable: {e}"
                ))
            })
        })
        .transpose()
    }

    /// Jobs of a sweep by state.
    pub fn counts(&self, sweep_id: i64) -> Result<StateCounts, StoreError> {
        let rows: Vec<(String, i64)> = self.run(
            sqlx::query_as(queries::COUNT_BY_STATUS)
                .bind(sweep_id)
                .fetch_all(&self.pool),
        )?;
        let mut c = StateCounts::default();
        for (status, n) in rows {
            c.add(&status, n as u64);
        }
        Ok(c)
    }

    /// Runs one statement with its text parameters on the store's connection (tests that write
    /// rows as older versions did).
    #[cfg(test)]
    pub(crate) fn execute_for_tests(&self, sql: &'static str, binds: &[&str]) {
        let q = binds.iter().fold(sqlx::query(sql), |q, b| q.bind(*b));
        self.rt.block_on(q.execute(&self.pool)).unwrap();
    }

    /// Every job of a sweep (grid order), with its result where there is one.
    pub fn points(&self, sweep_id: i64) -> Result<Vec<PointRow>, StoreError> {
        let rows = self.run(
            sqlx::query(queries::SWEEP_POINTS)
                .bind(sweep_id)
                .fetch_all(&self.pool),
        )?;
        rows.iter().map(|r| self.point_row(r)).collect()
    }

    /// Every job of the given sweeps with its result, in sweep order and each sweep's grid
    /// order, handed to `f` as `(pass, index of the sweep in sweep_ids, row)`, `passes` times
    /// over (`export`: a first pass for the CSV columns, a second for the rows). The rows are
    /// read [`POINTS_PAGE`] at a time (`sweep_points_page.sql`), so memory does not grow with
    /// the sweeps; every pass reads inside one read transaction, so every pass sees the same
    /// database even while a runner commits results.
    pub fn scan_points<E: From<StoreError>>(
        &self,
        sweep_ids: &[i64],
        passes: usize,
        mut f: impl FnMut(usize, usize, PointRow) -> Result<(), E>,
    ) -> Result<(), E> {
        self.rt.block_on(async {
            let mut tx = self.pool.begin().await.map_err(|e| self.db(e))?;
            for pass in 0..passes {
                for (k, &sweep_id) in sweep_ids.iter().enumerate() {
                    let mut after = (-1i64, -1i64);
                    loop {
                        let rows = sqlx::query(queries::SWEEP_POINTS_PAGE)
                            .bind(sweep_id)
                            .bind(after.0)
                            .bind(after.1)
                            .bind(POINTS_PAGE)
                            .fetch_all(&mut *tx)
                            .await
                            .map_err(|e| self.db(e))?;
                        for r in &rows {
                            let row = self.point_row(r)?;
                            after = (row.point, row.replica);
                            f(pass, k, row)?;
                        }
                        if rows.len() < POINTS_PAGE as usize {
                            break;
                        }
                    }
                }
            }
            // Read only: nothing to commit.
            tx.rollback().await.map_err(|e| self.db(e))?;
            Ok::<(), E>(())
        })
    }

    /// The rows, in every sweep, of the jobs whose id starts with `prefix` (hex digits, any
    /// case), with their results: `(sweep id, row)` by sweep and grid order. An index range, so
    /// finding one job does not read the others' observables.
    pub fn points_with_job_prefix(&self, prefix: &str) -> Result<Vec<(i64, PointRow)>, StoreError> {
        let low = prefix.to_ascii_lowercase();
        // Job ids are lowercase hex: every id that starts with `low` sorts below `low` + "g".
        let high = format!("{low}g");
        let rows = self.run(
            sqlx::query(queries::SWEEP_POINTS_WITH_JOB_PREFIX)
                .bind(&low)
                .bind(&high)
                .fetch_all(&self.pool),
        )?;
        let mut out = rows
            .iter()
            .map(|r| Ok((r.get("sweep_id"), self.point_row(r)?)))
            .collect::<Result<Vec<(i64, PointRow)>, StoreError>>()?;
        out.sort_by_key(|(sweep, p)| (*sweep, p.point, p.replica));
        Ok(out)
    }

    /// A row of `sweep_points.sql` (or of a page of it) as a [`PointRow`].
    pub(super) fn point_row(&self, r: &sqlx::sqlite::SqliteRow) -> Result<PointRow, StoreError> {
        let damaged = |what: &str, e: String| self.damaged(format!("{what} is not readable: {e}"));
        let job_id: String = r.get("job_id");
        let json = |col: &str| -> Result<Option<serde_json::Value>, StoreError> {
            let s: Option<String> = r.get(col);
            s.map(|s| serde_json::from_str(&s))
                .transpose()
                .map_err(|e| damaged(&format!("{col} of job {job_id}"), e.to_string()))
        };
        let spec: String = r.get("spec");
        Ok(PointRow {
            point: r.get("point"),
            replica: r.get("replica"),
            coords: serde_json::from_str(r.get::<&str, _>("coords"))
                .map_err(|e| damaged("coords", e.to_string()))?,
            status: r.get("status"),
            spec: JobSpec::from_json(&spec, &format!("job {job_id}"))
                .map_err(|e| damaged("a job spec", e))?,
            attempts: r.get("attempts"),
            last_error: r.get("last_error"),
            phase: r.get("phase"),
            decided_on: json("decided_on")?,
            observables: json("observables")?,
            simulated_time: r.get("simulated_time"),
            wall_seconds: r.get("wall_seconds"),
            events: r.get("events"),
            finished_at: r.get("finished_at"),
            result_owner: r.get("result_owner"),
            trend: r
                .get::<Option<String>, _>("trend")
                .as_deref()
                .and_then(wetgran_core::observe::trend::TrendState::parse),
            job_id,
        })
    }

    /// Number of attempts recorded in the `runs` table per job (audit of "no job ran twice").
    pub fn runs_per_job(&self) -> Result<Vec<(String, i64)>, StoreError> {
        self.run(sqlx::query_as(queries::RUNS_PER_JOB).fetch_all(&self.pool))
    }

    /// What every finished job in the database cost, by job id (any sweep): the simulated time
    /// its run ended at, its wall seconds (with extensions) and whether its label settled.
    pub fn finished_job_costs(
        &self,
    ) -> Result<std::collections::HashMap<String, MeasuredCost>, StoreError> {
        let rows: Vec<(String, f64, f64, Option<String>)> =
            self.run(sqlx::query_as(queries::FINISHED_JOB_COSTS).fetch_all(&self.pool))?;
        Ok(rows
            .into_iter()
            .map(|(id, simulated_time, wall_seconds, verdict)| {
                let cost = MeasuredCost {
                    simulated_time,
                    wall_seconds,
                    settled: verdict
                        .as_deref()
                        .and_then(Verdict::parse)
                        .map(Verdict::label_trusted),
                };
                (id, cost)
            })
            .collect())
    }

    /// The criterion that decided each stored label of a sweep, by job id
    /// (`observe::criterion`, from `results.decided_on`); a record this wetgran cannot read
    /// (another version's) has none.
    pub fn decisions(&self, sweep_id: i64) -> Result<HashMap<String, DecidedBy>, StoreError> {
        let rows: Vec<(String, String)> = self.run(
            sqlx::query_as(queries::SWEEP_DECISIONS)
                .bind(sweep_id)
                .fetch_all(&self.pool),
        )?;
        Ok(rows
            .into_iter()
            .filter_map(|(job, text)| {
                let record: serde_json::Value = serde_json::from_str(&text).ok()?;
                Some((job, DecidedBy::of_json(&record)?))
            })
            .collect())
    }

    /// Total wall time of the finished and failed attempts of a sweep's jobs, in seconds.
    pub fn time_spent(&self, sweep_id: i64) -> Result<f64, StoreError> {
        let t: Option<f64> = self.run(
            sqlx::query_scalar(queries::TIME_SPENT)
                .bind(sweep_id)
                .fetch_one(&self.pool),
        )?;
        Ok(t.unwrap_or(0.0))
    }
}
