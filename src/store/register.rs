//! Registration: sweeps and their jobs (shared between sweeps by content address), the jobs
//! refinement adds, and the points `skip_invalid` left out.

use super::{Exec, LeftOut, REFINED_FROM, Store, StoreError, SweepRow, now, queries};
use crate::sweep::file::SweepFile;
use crate::sweep::spec::SweepJob;
use sqlx::Row;

/// Jobs inserted between two calls of a registration's watcher.
const REGISTER_STEP: usize = 1000;

impl Store {
    /// Registers (or re-registers) a sweep and its jobs in one transaction. Jobs already in the
    /// database (same id, from any sweep) are shared, never duplicated; the sweep's grid in the
    /// point list is replaced by the new expansion. What refinement added (points numbered from
    /// [`REFINED_FROM`], replicas beyond `sweep.replicas`) is kept while the sweep file's text is
    /// unchanged, and dropped with the rest when it changed (its jobs and results stay, so a
    /// refinement planned again finds them).
    pub fn register_sweep(
        &self,
        file: &SweepFile,
        jobs: &[SweepJob],
    ) -> Result<SweepRow, StoreError> {
        self.register_sweep_watched(file, jobs, &mut |_| true)
    }

    /// [`Store::register_sweep`], calling `watch(jobs inserted so far)` every
    /// [`REGISTER_STEP`] jobs (and at the end); when it returns `false` (Ctrl-C) the
    /// registration stops: the transaction is rolled back, the write-ahead log checkpointed and
    /// truncated (so the rolled-back pages leave no large `-wal` file behind), and the error is
    /// [`StoreError::Interrupted`]. Nothing of the sweep is stored then.
    pub fn register_sweep_watched(
        &self,
        file: &SweepFile,
        jobs: &[SweepJob],
        watch: &mut dyn FnMut(usize) -> bool,
    ) -> Result<SweepRow, StoreError> {
        let axes = serde_json::to_string(&file.axes).expect("axes serialize");
        let t = now();
        let registered = self.rt.block_on(async {
            let mut tx = self.begin().await?;
            let out = self.register_in(&mut tx, file, jobs, &axes, t, watch).await;
            match out {
                Ok(()) => tx.commit().await.map_err(|e| self.db(e)),
                Err(e) => {
                    let _ = tx.rollback().await;
                    Err(e)
                }
            }
        });
        if let Err(StoreError::Interrupted { .. }) = &registered {
            // Best effort: a reader holding an old snapshot may keep the log from shrinking.
            let _ = self.run(sqlx::query(queries::CHECKPOINT_TRUNCATE).execute(&self.pool));
        }
        registered?;
        self.sweep(&file.name)
    }

    /// The statements of a registration, inside its transaction.
    async fn register_in(
        &self,
        tx: &mut sqlx::Transaction<'_, sqlx::Sqlite>,
        file: &SweepFile,
        jobs: &[SweepJob],
        axes: &str,
        t: f64,
        watch: &mut dyn FnMut(usize) -> bool,
    ) -> Result<(), StoreError> {
        {
            let old_source: Option<String> = sqlx::query_scalar(queries::SWEEP_SOURCE_BY_NAME)
                .bind(&file.name)
                .fetch_optional(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            let changed = old_source.as_deref() != Some(file.text.as_str());
            let id: i64 = sqlx::query_scalar(queries::UPSERT_SWEEP)
                .bind(&file.name)
                .bind(file.path.display().to_string())
                .bind(&file.text)
                .bind(&file.description)
                .bind(&file.cost)
                .bind(axes)
                .bind(file.replicas as i64)
                .bind(t)
                .fetch_one(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            sqlx::query(queries::DELETE_GRID_POINTS)
                .bind(id)
                .bind(changed)
                .bind(REFINED_FROM)
                .bind(file.replicas as i64)
                .exec(tx, self)
                .await?;
            for (k, chunk) in jobs.chunks(REGISTER_STEP).enumerate() {
                self.insert_points(tx, id, chunk, t).await?;
                self.reached(super::WritePoint::Register);
                if !watch(k * REGISTER_STEP + chunk.len()) {
                    return Err(StoreError::Interrupted {
                        path: self.path.display().to_string(),
                        detail: format!(
                            "interrupted while registering sweep `{}`: nothing of it was stored \
                             (the registration is one transaction, rolled back)",
                            file.name
                        ),
                    });
                }
            }
            Ok(())
        }
    }

    /// Records the grid points `skip_invalid` left out of a registered sweep (replacing what
    /// was recorded before).
    pub fn set_left_out(&self, sweep_id: i64, left_out: &[LeftOut]) -> Result<(), StoreError> {
        let text = serde_json::to_string(left_out).expect("left-out points serialize");
        self.run(
            sqlx::query(queries::SET_LEFT_OUT)
                .bind(sweep_id)
                .bind(text)
                .execute(&self.pool),
        )?;
        Ok(())
    }

    /// Inserts `jobs` (a job already in the database is shared, not duplicated) and their rows
    /// in a sweep's point list, inside an open transaction.
    async fn insert_points(
        &self,
        tx: &mut sqlx::Transaction<'_, sqlx::Sqlite>,
        sweep_id: i64,
        jobs: &[SweepJob],
        t: f64,
    ) -> Result<(), StoreError> {
        for job in jobs {
            // The id leaves out the `[classify]` thresholds: a job registered again with other
            // thresholds keeps its id and result, and its stored spec takes the new thresholds
            // (the ones its next result, or `wetgran reclassify`, labels with).
            sqlx::query(queries::UPSERT_JOB)
                .bind(&job.id)
                .bind(job.spec.canonical_json())
                .bind(t)
                .bind(&job.spec.start_from)
                .exec(tx, self)
                .await?;
            sqlx::query(queries::INSERT_SWEEP_POINT)
                .bind(sweep_id)
                .bind(job.point as i64)
                .bind(job.replica as i64)
                .bind(serde_json::to_string(&job.coords).expect("coords serialize"))
                .bind(&job.id)
                .exec(tx, self)
                .await?;
            sqlx::query(queries::MARK_RELABEL_POINT)
                .bind(sweep_id)
                .bind(&job.id)
                .exec(tx, self)
                .await?;
        }
        Ok(())
    }

    /// Adds jobs to a registered sweep's point list (refinement: new points, more replicas), in
    /// one transaction; jobs already in the database are shared.
    pub fn add_jobs(&self, sweep_id: i64, jobs: &[SweepJob]) -> Result<(), StoreError> {
        let t = now();
        self.in_transaction(async |tx| {
            self.insert_points(tx, sweep_id, jobs, t).await?;
            sqlx::query(queries::TOUCH_SWEEP)
                .bind(sweep_id)
                .bind(t)
                .exec(tx, self)
                .await?;
            self.reached(super::WritePoint::Refine);
            Ok(())
        })
    }

    /// The text of a sweep's file as last registered.
    pub fn sweep_source(&self, sweep_id: i64) -> Result<String, StoreError> {
        self.run(
            sqlx::query_scalar(queries::SWEEP_SOURCE)
                .bind(sweep_id)
                .fetch_one(&self.pool),
        )
    }

    /// All sweeps, oldest first.
    pub fn sweeps(&self) -> Result<Vec<SweepRow>, StoreError> {
        let rows = self.run(sqlx::query(queries::LIST_SWEEPS).fetch_all(&self.pool))?;
        rows.iter()
            .map(|r| {
                let axes: String = r.get("axes");
                Ok(SweepRow {
                    id: r.get("id"),
                    name: r.get("name"),
                    file: r.get("file"),
                    description: r.get("description"),
                    cost: r.get("cost"),
                    axes: serde_json::from_str(&axes).map_err(|e| {
                        self.damaged(format!("axes of a sweep are not readable: {e}"))
                    })?,
                    replicas: r.get::<i64, _>("replicas") as u32,
                    created_at: r.get("created_at"),
                    updated_at: r.get("updated_at"),
                    left_out: match r.get::<Option<String>, _>("left_out") {
                        None => Vec::new(),
                        Some(t) => serde_json::from_str(&t).map_err(|e| {
                            self.damaged(format!(
                                "left-out points of a sweep are not readable: {e}"
                            ))
                        })?,
                    },
                })
            })
            .collect()
    }

    /// The sweep with this name.
    pub fn sweep(&self, name: &str) -> Result<SweepRow, StoreError> {
        self.sweeps()?
            .into_iter()
            .find(|s| s.name == name)
            .ok_or_else(|| StoreError::NoSuchSweep {
                path: self.path.display().to_string(),
                name: name.to_string(),
            })
    }
}
