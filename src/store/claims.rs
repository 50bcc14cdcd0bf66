//! The claim protocol (module doc of `store`, "Claims and crashes"): owner names, re-queueing
//! of orphaned jobs, claims with their run rows, heartbeats, and the commits of finished,
//! failed and extended jobs (a result row and its checkpoint).

use super::{Claim, Exec, STALE_AFTER, Store, StoreError, now, queries};
use crate::sweep::job::JobResult;
use crate::sweep::spec::JobSpec;
use std::path::Path;
use std::time::{SystemTime, UNIX_EPOCH};

/// This host's name, as owner names and result records carry it.
pub(crate) fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty() && !s.contains(':'))
        .unwrap_or_else(|| "localhost".to_string())
}

/// A new owner name `host:pid:nonce` (the nonce tells apart two stores of one process).
pub(super) fn new_owner() -> String {
    use std::hash::{BuildHasher, Hasher};
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u128(
        SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0),
    );
    format!(
        "{}:{}:{:08x}",
        host_name(),
        std::process::id(),
        h.finish() as u32
    )
}

/// Whether an owner name belongs to a process of this host that no longer exists.
pub(super) fn owner_is_dead(owner: &str) -> bool {
    let mut parts = owner.split(':');
    let (Some(host), Some(pid)) = (parts.next(), parts.next()) else {
        return false;
    };
    if host != host_name() || !cfg!(target_os = "linux") {
        return false;
    }
    match pid.parse::<u32>() {
        Ok(pid) => !Path::new(&format!("/proc/{pid}")).exists(),
        Err(_) => false,
    }
}

impl Store {
    /// Inserts a job's result row, inside an open transaction (the job row is the caller's).
    pub(super) async fn insert_result(
        &self,
        tx: &mut sqlx::Transaction<'_, sqlx::Sqlite>,
        job_id: &str,
        result: &JobResult,
        owner: &str,
        finished_at: f64,
    ) -> Result<(), StoreError> {
        sqlx::query(queries::INSERT_RESULT)
            .bind(job_id)
            .bind(&result.phase)
            .bind(result.decided_on.as_ref().map(|v| v.to_string()))
            .bind(result.observables.to_string())
            .bind(result.simulated_time)
            .bind(result.wall_seconds)
            .bind(result.events as i64)
            .bind(owner)
            .bind(finished_at)
            .exec(tx, self)
            .await?;
        // The sweeps holding the job relabel its lines after the run (`run::relabel`).
        sqlx::query(queries::MARK_RELABEL_JOB)
            .bind(job_id)
            .exec(tx, self)
            .await?;
        if let Some(state) = &result.checkpoint {
            sqlx::query(queries::UPSERT_CHECKPOINT)
                .bind(job_id)
                .bind(state.time)
                .bind(serde_json::to_string(state).expect("a state serializes"))
                .bind(finished_at)
                .exec(tx, self)
                .await?;
        }
        self.reached(super::WritePoint::Checkpoint);
        Ok(())
    }

    /// Replaces the result and the checkpoint of a finished job (an extension from its
    /// checkpoint, `sweep resume --extend`) in one transaction.
    pub fn replace_result(&self, job_id: &str, result: &JobResult) -> Result<(), StoreError> {
        let t = now();
        let owner = self.owner.clone();
        self.in_transaction(async |tx| {
            sqlx::query(queries::DELETE_RESULT)
                .bind(job_id)
                .exec(tx, self)
                .await?;
            self.reached(super::WritePoint::Extend);
            self.insert_result(tx, job_id, result, &owner, t).await?;
            sqlx::query(queries::EXTEND_JOB_TIMES)
                .bind(job_id)
                .bind(t)
                .bind(result.wall_seconds)
                .exec(tx, self)
                .await?;
            Ok(())
        })
    }

    /// Re-queues orphaned running jobs (see the module doc); returns their ids.
    pub fn requeue_orphans(&self) -> Result<Vec<String>, StoreError> {
        let stale_before = now() - STALE_AFTER.as_secs_f64();
        self.rt.block_on(async {
            let running: Vec<(String, Option<String>, Option<f64>)> =
                sqlx::query_as(queries::RUNNING_JOBS)
                    .fetch_all(&self.pool)
                    .await
                    .map_err(|e| self.db(e))?;
            let mut requeued = Vec::new();
            for (id, owner, heartbeat) in running {
                let owner = owner.unwrap_or_default();
                if owner == self.owner {
                    continue;
                }
                let stale = heartbeat.is_none_or(|h| h < stale_before);
                if !(stale || owner_is_dead(&owner)) {
                    continue;
                }
                let mut tx = self.begin().await?;
                let n = sqlx::query(queries::REQUEUE_JOB)
                    .bind(&id)
                    .bind(&owner)
                    .exec(&mut tx, self)
                    .await?;
                if n == 1 {
                    sqlx::query(queries::MARK_RUNS_ORPHANED)
                        .bind(&id)
                        .bind(&owner)
                        .bind(now())
                        .exec(&mut tx, self)
                        .await?;
                    requeued.push(id);
                }
                tx.commit().await.map_err(|e| self.db(e))?;
            }
            Ok(requeued)
        })
    }

    /// Closes the open run rows (no outcome) of every runner whose process is gone (this host,
    /// `/proc/PID` absent: a runner stopped by Ctrl-C, SIGKILL or a crash) with the outcome
    /// `interrupted`, in one transaction; returns how many. Every writer's open calls it, so
    /// the books of an interrupted run are closed by the next command that writes (a resume
    /// re-queues the jobs themselves). A runner of another host is judged by its heartbeat
    /// when its jobs are re-queued ([`Store::requeue_orphans`], outcome `orphaned`).
    pub fn close_interrupted_runs(&self) -> Result<u64, StoreError> {
        let owners: Vec<String> =
            self.run(sqlx::query_scalar(queries::OPEN_RUN_OWNERS).fetch_all(&self.pool))?;
        let gone: Vec<&String> = owners
            .iter()
            .filter(|o| **o != self.owner && owner_is_dead(o))
            .collect();
        if gone.is_empty() {
            return Ok(0);
        }
        let t = now();
        self.in_transaction(async |tx| {
            let mut closed = 0;
            for owner in gone {
                closed += sqlx::query(queries::CLOSE_INTERRUPTED_RUNS)
                    .bind(owner)
                    .bind(t)
                    .exec(tx, self)
                    .await?;
            }
            Ok(closed)
        })
    }

    /// Re-queues the failed jobs of the given sweeps; returns how many.
    pub fn retry_failed(&self, sweep_ids: &[i64]) -> Result<u64, StoreError> {
        let mut total = 0;
        for &sid in sweep_ids {
            let retry = sqlx::query(queries::RETRY_FAILED_JOBS).bind(sid);
            total += self.run(retry.execute(&self.pool))?.rows_affected();
        }
        Ok(total)
    }

    /// Atomically claims the next pending job of any of the given sweeps (grid order). A
    /// continuation job (`JobSpec::start_from`) is claimable once its predecessor has ended
    /// (done, or failed: the runner then fails it with the reason).
    pub fn claim(&self, sweep_ids: &[i64]) -> Result<Option<Claim>, StoreError> {
        for &sid in sweep_ids {
            if let Some(c) = self.claim_in(sid)? {
                return Ok(Some(c));
            }
        }
        Ok(None)
    }

    fn claim_in(&self, sweep_id: i64) -> Result<Option<Claim>, StoreError> {
        let t = now();
        let claimed = self.in_transaction(async |tx| {
            // Both statements run under the transaction's write lock: the row read first is
            // still pending when it is claimed. The guard `status = 'pending'` in CLAIM_JOB
            // holds anyway (a queue row with a rank is always a pending job's).
            let next: Option<(String, i64, i64, String, String)> =
                sqlx::query_as(queries::NEXT_CLAIMABLE_POINT)
                    .bind(sweep_id)
                    .fetch_optional(&mut **tx)
                    .await
                    .map_err(|e| self.db(e))?;
            let Some((job_id, point, replica, coords, sweep)) = next else {
                return Ok(None);
            };
            let spec: Option<String> = sqlx::query_scalar(queries::CLAIM_JOB)
                .bind(&job_id)
                .bind(&self.owner)
                .bind(t)
                .fetch_optional(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            let Some(spec) = spec else {
                return Ok(None);
            };
            let run_id: i64 = sqlx::query_scalar(queries::INSERT_RUN)
                .bind(&job_id)
                .bind(&self.owner)
                .bind(t)
                .fetch_one(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            Ok::<_, StoreError>(Some((job_id, run_id, spec, point, replica, coords, sweep)))
        })?;
        let Some((job_id, run_id, spec, point, replica, coords, sweep)) = claimed else {
            return Ok(None);
        };
        let damaged = |what: &str, e: String| {
            self.damaged(format!("{what} of job {job_id} is not readable: {e}"))
        };
        Ok(Some(Claim {
            spec: JobSpec::from_json(&spec, &format!("job {job_id}"))
                .map_err(|e| damaged("the spec", e))?,
            coords: serde_json::from_str(&coords)
                .map_err(|e| damaged("the coords", e.to_string()))?,
            job_id,
            run_id,
            sweep,
            point,
            replica,
            start: None,
        }))
    }

    /// Refreshes the heartbeat of every job this runner is running.
    pub fn heartbeat(&self) -> Result<(), StoreError> {
        let beat = sqlx::query(queries::HEARTBEAT)
            .bind(now())
            .bind(&self.owner);
        self.run(beat.execute(&self.pool))?;
        Ok(())
    }

    /// Commits a finished job: job row, result row and run row in one transaction. Returns
    /// `false` (and stores nothing but the run's outcome) when the job already has a result.
    pub fn finish(&self, claim: &Claim, result: &JobResult) -> Result<bool, StoreError> {
        let t = now();
        self.in_transaction(async |tx| {
            let kept = self
                .commit_result(
                    tx,
                    queries::FINISH_JOB,
                    &claim.job_id,
                    result,
                    &self.owner,
                    t,
                )
                .await?;
            self.end_run(tx, claim.run_id, t, if kept { "done" } else { "discarded" })
                .await?;
            Ok(kept)
        })
    }

    /// Marks a job done with `mark` ([`queries::FINISH_JOB`] for a claim here,
    /// [`queries::INGEST_DONE_JOB`] for a result computed elsewhere: both bind job id, owner,
    /// finish time, wall seconds) and, where the job had no result yet, inserts this one;
    /// returns whether it did. Inside an open transaction.
    pub(super) async fn commit_result(
        &self,
        tx: &mut sqlx::Transaction<'_, sqlx::Sqlite>,
        mark: &'static str,
        job_id: &str,
        result: &JobResult,
        owner: &str,
        t: f64,
    ) -> Result<bool, StoreError> {
        let n = sqlx::query(mark)
            .bind(job_id)
            .bind(owner)
            .bind(t)
            .bind(result.wall_seconds)
            .exec(tx, self)
            .await?;
        if n == 1 {
            self.insert_result(tx, job_id, result, owner, t).await?;
        }
        Ok(n == 1)
    }

    /// Closes an attempt's row in `runs` with its end time and outcome.
    async fn end_run(
        &self,
        tx: &mut sqlx::Transaction<'_, sqlx::Sqlite>,
        run_id: i64,
        t: f64,
        outcome: &str,
    ) -> Result<(), StoreError> {
        sqlx::query(queries::END_RUN)
            .bind(run_id)
            .bind(t)
            .bind(outcome)
            .exec(tx, self)
            .await?;
        Ok(())
    }

    /// Records a failed job with its message.
    pub fn fail(&self, claim: &Claim, message: &str, wall_seconds: f64) -> Result<(), StoreError> {
        let t = now();
        self.in_transaction(async |tx| {
            sqlx::query(queries::FAIL_JOB)
                .bind(&claim.job_id)
                .bind(&self.owner)
                .bind(t)
                .bind(wall_seconds)
                .bind(message)
                .exec(tx, self)
                .await?;
            self.end_run(tx, claim.run_id, t, "failed").await?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::store_with_jobs;

    fn set_owner(store: &Store, job: &str, owner: &str, heartbeat: f64) {
        store
            .rt
            .block_on(
                sqlx::query("UPDATE jobs SET owner = ?2, heartbeat = ?3 WHERE id = ?1")
                    .bind(job)
                    .bind(owner)
                    .bind(heartbeat)
                    .execute(&store.pool),
            )
            .unwrap();
    }

    #[test]
    fn only_jobs_of_dead_or_silent_runners_are_requeued() {
        let dir = tempfile::tempdir().unwrap();
        let (db, sweep) = store_with_jobs(dir.path());
        let a = Store::open(&db).unwrap();
        let jobs: Vec<String> = (0..3)
            .map(|_| a.claim(&[sweep]).unwrap().unwrap().job_id)
            .collect();
        // A process of this host that has exited: its pid is free.
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead_pid = child.id();
        child.wait().unwrap();
        let t = now();
        // jobs[0]: another host, heartbeat fresh -> kept.
        set_owner(&a, &jobs[0], "elsewhere:1:aa", t - 10.0);
        // jobs[1]: another host, heartbeat older than STALE_AFTER -> re-queued.
        set_owner(
            &a,
            &jobs[1],
            "elsewhere:1:bb",
            t - STALE_AFTER.as_secs_f64() - 1.0,
        );
        // jobs[2]: this host, a dead pid, heartbeat fresh -> re-queued at once (Linux).
        set_owner(&a, &jobs[2], &format!("{}:{dead_pid}:cc", host_name()), t);
        let b = Store::open(&db).unwrap();
        let mut requeued = b.requeue_orphans().unwrap();
        requeued.sort();
        let mut want = vec![jobs[1].clone()];
        if cfg!(target_os = "linux") {
            want.push(jobs[2].clone());
        }
        want.sort();
        assert_eq!(requeued, want);
        let c = b.counts(sweep).unwrap();
        assert_eq!(
            (c.running, c.pending),
            (3 - want.len() as u64, want.len() as u64)
        );
        // A's own running jobs are never taken from it by A itself.
        let mine = a.claim(&[sweep]).unwrap().unwrap();
        assert!(a.requeue_orphans().unwrap().is_empty());
        assert_eq!(b.counts(sweep).unwrap().running, 3 - want.len() as u64 + 1);
        drop(mine);
    }
}
