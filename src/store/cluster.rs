//! The store's side of cluster execution: submitted job arrays and their tasks (table
//! `submissions`, `submission_tasks`), and the ingestion of results computed elsewhere.
//!
//! Submitting changes no job row: a job stays `pending` until `sweep collect` ingests its result
//! file ([`Store::ingest_results`]: job done, result row, run row, in one transaction; a job that
//! already has a result keeps it and nothing is stored) or its error record
//! ([`Store::ingest_failure`]: job failed with the message, unless it is done or running here).

use super::{Exec, Store, StoreError, now, queries};
use crate::sweep::job::JobResult;

/// What `sweep collect` found for a task.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TaskState {
    /// Submitted, nothing collected yet.
    Submitted,
    /// Its result was stored.
    Collected,
    /// Its result arrived, but the job already had one (stored once only).
    Duplicate,
    /// It wrote an error record.
    Failed,
    /// No result file, and the task is no longer in the Slurm queue.
    Missing,
    /// Its result file is unreadable or belongs to another job.
    Corrupt,
}

/// Each state and its name in `submission_tasks.state`.
const TASK_STATES: [(TaskState, &str); 6] = [
    (TaskState::Submitted, "submitted"),
    (TaskState::Collected, "collected"),
    (TaskState::Duplicate, "duplicate"),
    (TaskState::Failed, "failed"),
    (TaskState::Missing, "missing"),
    (TaskState::Corrupt, "corrupt"),
];

impl TaskState {
    pub fn as_str(self) -> &'static str {
        TASK_STATES
            .iter()
            .find(|(t, _)| *t == self)
            .expect("every state")
            .1
    }
}

impl From<String> for TaskState {
    /// The state of a stored name; an unknown name reads as corrupt.
    fn from(s: String) -> TaskState {
        TASK_STATES
            .iter()
            .find(|(_, n)| *n == s)
            .map_or(TaskState::Corrupt, |(t, _)| *t)
    }
}

/// One array task as recorded (a row of `list_tasks.sql`).
#[derive(Debug, Clone, PartialEq, sqlx::FromRow)]
pub struct TaskRow {
    pub submission_id: i64,
    pub sweep_id: i64,
    pub dir: String,
    /// The array's Slurm job id (`None`: sbatch had not answered).
    pub slurm_job: Option<String>,
    pub task: i64,
    pub job_id: String,
    #[sqlx(try_from = "String")]
    pub state: TaskState,
    pub message: Option<String>,
    pub submitted_at: f64,
}

impl Store {
    /// Records a job array about to be submitted: its script and the job of each task (task `k`
    /// runs `jobs[k]`). Returns the submission's id; [`Store::set_slurm_job`] adds the Slurm id.
    pub fn record_submission(
        &self,
        sweep_id: i64,
        dir: &str,
        script: &str,
        jobs: &[String],
    ) -> Result<i64, StoreError> {
        let t = now();
        self.in_transaction(async |tx| {
            let id: i64 = sqlx::query_scalar(queries::INSERT_SUBMISSION)
                .bind(sweep_id)
                .bind(dir)
                .bind(script)
                .bind(jobs.len() as i64)
                .bind(t)
                .fetch_one(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            for (k, job) in jobs.iter().enumerate() {
                sqlx::query(queries::INSERT_SUBMISSION_TASK)
                    .bind(id)
                    .bind(k as i64)
                    .bind(job)
                    .exec(tx, self)
                    .await?;
            }
            Ok(id)
        })
    }

    /// Adds the Slurm job id sbatch answered to a recorded submission.
    pub fn set_slurm_job(&self, submission_id: i64, slurm_job: &str) -> Result<(), StoreError> {
        self.run(
            sqlx::query(queries::SET_SLURM_JOB)
                .bind(submission_id)
                .bind(slurm_job)
                .execute(&self.pool),
        )?;
        Ok(())
    }

    /// Forgets a submission that sbatch refused (its tasks never existed).
    pub fn drop_submission(&self, submission_id: i64) -> Result<(), StoreError> {
        self.run(
            sqlx::query(queries::DELETE_SUBMISSION)
                .bind(submission_id)
                .execute(&self.pool),
        )?;
        Ok(())
    }

    /// Every recorded task of a sweep, oldest submission first.
    pub fn tasks(&self, sweep_id: i64) -> Result<Vec<TaskRow>, StoreError> {
        self.run(
            sqlx::query_as(queries::LIST_TASKS)
                .bind(sweep_id)
                .fetch_all(&self.pool),
        )
    }

    /// Records what collection found for a task.
    pub fn set_task_state(
        &self,
        submission_id: i64,
        task: i64,
        state: TaskState,
        message: Option<&str>,
    ) -> Result<(), StoreError> {
        self.run(
            sqlx::query(queries::SET_TASK_STATE)
                .bind(submission_id)
                .bind(task)
                .bind(state.as_str())
                .bind(message)
                .execute(&self.pool),
        )?;
        Ok(())
    }

    /// The status of each of these jobs that is in the database (`pending`, `running`, `done`,
    /// `failed`).
    pub fn job_statuses(
        &self,
        ids: &[String],
    ) -> Result<std::collections::HashMap<String, String>, StoreError> {
        let mut out = std::collections::HashMap::new();
        for id in ids {
            let s: Option<String> = self.run(
                sqlx::query_scalar(queries::JOB_STATUS)
                    .bind(id)
                    .fetch_optional(&self.pool),
            )?;
            if let Some(s) = s {
                out.insert(id.clone(), s);
            }
        }
        Ok(out)
    }

    /// Stores results computed elsewhere (`owner` names where: `slurm:JOB_TASK@host`; job done,
    /// result row, run row) and the state of the task that brought each (`collected`, or
    /// `duplicate`, storing nothing, where the job already had a result: content-hashed ids
    /// store the same job finished twice once), all in one transaction (one sync for the lot).
    /// Returns, per item, whether its result was stored. A crash before the commit stores none
    /// of them and leaves their tasks `submitted`, so the next collection reads their files
    /// again. An item is `(job id, result, owner, finished at, submission id, task)`.
    pub fn ingest_results(
        &self,
        items: &[(&str, &JobResult, &str, f64, i64, i64)],
    ) -> Result<Vec<bool>, StoreError> {
        self.in_transaction(async |tx| {
            let mut kept = Vec::with_capacity(items.len());
            for &(job_id, result, owner, finished_at, submission_id, task) in items {
                let q = queries::INGEST_DONE_JOB;
                let k = self
                    .commit_result(tx, q, job_id, result, owner, finished_at)
                    .await?;
                if k {
                    let wall = result.wall_seconds;
                    self.insert_remote_run(tx, job_id, owner, wall, finished_at, "done")
                        .await?;
                }
                let state = if k {
                    TaskState::Collected
                } else {
                    TaskState::Duplicate
                };
                sqlx::query(queries::SET_TASK_STATE)
                    .bind(submission_id)
                    .bind(task)
                    .bind(state.as_str())
                    .bind(None::<&str>)
                    .exec(tx, self)
                    .await?;
                kept.push(k);
            }
            Ok(kept)
        })
    }

    /// Records a job that failed elsewhere: status `failed` with the message, one more attempt,
    /// a run row. A job that is done (or running under a runner here) is left as it is; returns
    /// whether the job row changed.
    pub fn ingest_failure(
        &self,
        job_id: &str,
        message: &str,
        wall_seconds: f64,
        owner: &str,
        finished_at: f64,
    ) -> Result<bool, StoreError> {
        self.in_transaction(async |tx| {
            let n = sqlx::query(queries::INGEST_FAILED_JOB)
                .bind(job_id)
                .bind(owner)
                .bind(finished_at)
                .bind(wall_seconds)
                .bind(message)
                .exec(tx, self)
                .await?;
            if n == 1 {
                self.insert_remote_run(tx, job_id, owner, wall_seconds, finished_at, "failed")
                    .await?;
            }
            Ok(n == 1)
        })
    }

    /// Inserts the closed run row of an attempt made elsewhere (it started `wall_seconds`
    /// before `finished_at`), inside an open transaction.
    async fn insert_remote_run(
        &self,
        tx: &mut sqlx::Transaction<'_, sqlx::Sqlite>,
        job_id: &str,
        owner: &str,
        wall_seconds: f64,
        finished_at: f64,
        outcome: &str,
    ) -> Result<(), StoreError> {
        sqlx::query(queries::INSERT_REMOTE_RUN)
            .bind(job_id)
            .bind(owner)
            .bind(finished_at - wall_seconds)
            .bind(finished_at)
            .bind(outcome)
            .exec(tx, self)
            .await?;
        Ok(())
    }
}
