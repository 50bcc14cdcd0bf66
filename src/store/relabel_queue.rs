//! The results a sweep's line-rule relabelling has not seen yet (`run::relabel`). A result
//! stored, replaced or added to a sweep leaves a mark `relabel:<sweep id>:<job id>` in the
//! `meta` table, written in the same transaction as the result (or the sweep row), and the
//! relabelling clears the marks in the transaction that writes the labels. A crash between
//! the two leaves the marks, so the next relabelling still sees those results: the marks are
//! what lets a relabelling after a run read only the lines that changed instead of every
//! result of the sweep. The marks are written by `mark_relabel_job.sql` (a stored or merged
//! result, in every sweep holding the job) and `mark_relabel_point.sql` (a job with a result
//! added to a sweep).

use super::{Exec, PointRow, Store, StoreError, queries};
use crate::sweep::spec::JobSpec;
use sqlx::Row;

/// The key prefix of a sweep's marks and the end of its range (`:` raised to `;`).
fn range(sweep_id: i64) -> (String, String) {
    (
        format!("relabel:{sweep_id}:"),
        format!("relabel:{sweep_id};"),
    )
}

/// One row of a sweep with its job's spec (no result columns).
#[derive(Debug)]
pub struct PointSpec {
    pub job_id: String,
    pub spec: JobSpec,
}

impl Store {
    /// The jobs of sweep `sweep_id` whose result (or its removal) no relabelling has seen.
    pub fn relabel_pending(&self, sweep_id: i64) -> Result<Vec<String>, StoreError> {
        let (lo, hi) = range(sweep_id);
        let keys: Vec<String> = self.run(
            sqlx::query_scalar(queries::RELABEL_PENDING)
                .bind(&lo)
                .bind(&hi)
                .fetch_all(&self.pool),
        )?;
        Ok(keys
            .into_iter()
            .map(|k| k[lo.len()..].to_string())
            .collect())
    }

    /// Every row of a sweep with its spec, in no particular order.
    pub fn point_specs(&self, sweep_id: i64) -> Result<Vec<PointSpec>, StoreError> {
        let rows = self.run(
            sqlx::query(queries::SWEEP_POINT_SPECS)
                .bind(sweep_id)
                .fetch_all(&self.pool),
        )?;
        rows.iter()
            .map(|r| {
                let spec: String = r.get("spec");
                let job_id: String = r.get("job_id");
                let spec = serde_json::from_str(&spec).map_err(|e| {
                    self.damaged(format!("job {job_id}: stored spec unreadable: {e}"))
                })?;
                Ok(PointSpec { job_id, spec })
            })
            .collect()
    }

    /// The rows of the given jobs in a sweep with their results, as [`Store::points`] reads
    /// them, in grid order.
    pub fn points_of_jobs(
        &self,
        sweep_id: i64,
        job_ids: &[String],
    ) -> Result<Vec<PointRow>, StoreError> {
        let mut out = Vec::new();
        for job in job_ids {
            let rows = self.run(
                sqlx::query(queries::SWEEP_POINTS_OF_JOB)
                    .bind(sweep_id)
                    .bind(job)
                    .fetch_all(&self.pool),
            )?;
            for r in &rows {
                out.push(self.point_row(r)?);
            }
        }
        out.sort_by_key(|p| (p.point, p.replica));
        out.dedup_by_key(|p| (p.point, p.replica));
        Ok(out)
    }

    /// Sets the phase label and the numbers it was decided on of stored results (`(job id,
    /// phase, decided_on)`) and clears marks, in one transaction: for each `(sweep id, jobs)`,
    /// the marks of those jobs, or every mark of the sweep when `jobs` is `None`.
    pub fn relabel_and_clear(
        &self,
        labels: &[(String, String, serde_json::Value)],
        clear: &[(i64, Option<Vec<String>>)],
    ) -> Result<(), StoreError> {
        let mut ranges = Vec::new();
        for (sweep_id, jobs) in clear {
            let (lo, hi) = range(*sweep_id);
            match jobs {
                None => ranges.push((lo, hi)),
                Some(jobs) => ranges.extend(
                    jobs.iter()
                        .map(|j| (format!("{lo}{j}"), format!("{lo}{j}\u{1}"))),
                ),
            }
        }
        self.in_transaction(async |tx| {
            for (job, phase, decided_on) in labels {
                sqlx::query(queries::SET_RESULT_LABEL)
                    .bind(job)
                    .bind(phase)
                    .bind(decided_on.to_string())
                    .exec(tx, self)
                    .await?;
            }
            for (a, b) in &ranges {
                sqlx::query(queries::CLEAR_RELABEL_PENDING)
                    .bind(a)
                    .bind(b)
                    .exec(tx, self)
                    .await?;
            }
            Ok(())
        })
    }
}
