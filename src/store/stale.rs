//! Running jobs as `sweep status` shows them: held by a live runner, or stale, i.e. held by a
//! runner that is gone (its process no longer exists on this host) or silent (no heartbeat for
//! [`STALE_AFTER`]). A stale job is not running: `sweep resume` re-queues it (the rule of
//! [`Store::requeue_orphans`], module doc of `store`).

use super::{STALE_AFTER, Store, StoreError, owner_is_dead, queries};

/// A running job of a sweep with its runner (a row of `sweep_running_jobs.sql`).
#[derive(Debug, Clone, PartialEq, sqlx::FromRow)]
pub struct RunningJob {
    pub point: i64,
    pub replica: i64,
    pub job_id: String,
    /// The runner's owner name (`host:pid:nonce`).
    pub owner: Option<String>,
    /// The runner's last heartbeat for this job (seconds since the epoch).
    pub heartbeat: Option<f64>,
}

/// Why a running job is stale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stale {
    /// Seconds since its last heartbeat (`None`: never sent one).
    pub heartbeat_age: Option<f64>,
    /// Its runner's process no longer exists (same host).
    pub process_gone: bool,
}

impl RunningJob {
    /// Whether the job is stale at time `now` (module doc); `None` while its runner lives.
    pub fn stale(&self, now: f64) -> Option<Stale> {
        let heartbeat_age = self.heartbeat.map(|h| (now - h).max(0.0));
        let process_gone = self.owner.as_deref().is_some_and(owner_is_dead);
        let silent = heartbeat_age.is_none_or(|a| a > STALE_AFTER.as_secs_f64());
        (process_gone || silent).then_some(Stale {
            heartbeat_age,
            process_gone,
        })
    }
}

impl Store {
    /// The running jobs of a sweep, in grid order, with their runner and heartbeat.
    pub fn running_jobs(&self, sweep_id: i64) -> Result<Vec<RunningJob>, StoreError> {
        let mut jobs: Vec<RunningJob> = self.run(
            sqlx::query_as(queries::SWEEP_RUNNING_JOBS)
                .bind(sweep_id)
                .fetch_all(&self.pool),
        )?;
        jobs.sort_by_key(|j| (j.point, j.replica));
        Ok(jobs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(owner: &str, heartbeat: Option<f64>) -> RunningJob {
        RunningJob {
            point: 0,
            replica: 0,
            job_id: "ab".repeat(32),
            owner: Some(owner.to_string()),
            heartbeat,
        }
    }

    #[test]
    fn silent_or_gone_runners_make_their_jobs_stale() {
        // This runner's owner name `host:pid:nonce`: alive.
        let me = super::super::new_owner();
        assert_eq!(me.split(':').count(), 3);
        // Live: this process, a recent heartbeat.
        assert_eq!(job(&me, Some(100.0)).stale(110.0), None);
        // Silent for longer than STALE_AFTER.
        let late = 100.0 + STALE_AFTER.as_secs_f64() + 1.0;
        let s = job(&me, Some(100.0)).stale(late).unwrap();
        assert!(!s.process_gone);
        assert!((s.heartbeat_age.unwrap() - (late - 100.0)).abs() < 1e-9);
        // A process of this host that does not exist (pid beyond the kernel's limit).
        let gone = format!("{}:4294967295:0", super::super::host_name());
        let s = job(&gone, Some(100.0)).stale(101.0).unwrap();
        assert!(s.process_gone);
        assert_eq!(s.heartbeat_age, Some(1.0));
        // Another host's runner is judged by its heartbeat alone.
        assert_eq!(job("elsewhere:1:0", Some(100.0)).stale(130.0), None);
    }
}
