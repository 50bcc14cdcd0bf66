//! The store's SQL: one statement per file in `src/store/sql/`, one constant per statement
//! (named after its file), embedded with `include_str!`. Each file starts with a comment saying
//! what it does and its bind order (`-- ?1: owner, ?2: now, ...`); the code binds in that order.
//!
//! The statements are not checked at compile time: sqlx's `query!` macros need a live database
//! (`DATABASE_URL`) or prepared offline data, and the build has only the Rust toolchain. The
//! tests below check instead that every file is one constant's and that every statement
//! prepares against a freshly migrated database, with as many parameters as its comment names.
//! A constant no code uses fails the build (`dead_code` under `-D warnings`).

/// Declares each query constant from its file `sql/<file>.sql`, and (for the tests) the list
/// of all of them.
macro_rules! queries {
    ($($(#[$doc:meta])* $name:ident = $file:literal;)*) => {
        $(
            $(#[$doc])*
            pub(super) const $name: &str = include_str!(concat!("sql/", $file, ".sql"));
        )*
        /// Every query: its file's stem and its text.
        #[cfg(test)]
        pub(super) const ALL: &[(&str, &str)] = &[$(($file, $name)),*];
    };
}

queries! {
    /// The versions of the applied migrations (read-only opens).
    APPLIED_MIGRATIONS = "applied_migrations";
    /// A sweep's report rows packed into one JSON array (no specs).
    SWEEP_POINT_SUMMARIES_PACKED = "sweep_point_summaries_packed";
    /// The spec of a sweep's first job in grid order.
    SWEEP_FIRST_SPEC = "sweep_first_spec";
    /// The running jobs of a sweep with their runner and heartbeat (`sweep status`).
    SWEEP_RUNNING_JOBS = "sweep_running_jobs";
    /// Every job's id and stored spec, oldest first (re-keying).
    ALL_JOB_SPECS = "all_job_specs";
    /// Opens a write transaction, taking the write lock at once.
    BEGIN_IMMEDIATE = "begin_immediate";
    /// SQLite's full integrity check.
    INTEGRITY_CHECK = "integrity_check";
    /// A job's checkpoint state (JSON).
    CHECKPOINT_STATE = "checkpoint_state";
    /// Claims a pending job for a runner; returns its spec.
    CLAIM_JOB = "claim_job";
    /// Copies a job row under its new id (re-keying).
    COPY_JOB_TO_NEW_ID = "copy_job_to_new_id";
    /// Every finished job's simulated time, wall seconds and convergence (`sweep estimate`).
    FINISHED_JOB_COSTS = "finished_job_costs";
    /// A sweep's jobs counted by status.
    COUNT_BY_STATUS = "count_by_status";
    /// Rows of the runs table: simulations started, ever.
    COUNT_RUNS = "count_runs";
    /// Deletes a sweep's grid points before re-registering it (refined ones too if its file
    /// changed).
    DELETE_GRID_POINTS = "delete_grid_points";
    /// Marks a job's result as not yet relabelled in every sweep that holds it.
    MARK_RELABEL_JOB = "mark_relabel_job";
    /// Marks a job added to a sweep with a result already stored as not yet relabelled there.
    MARK_RELABEL_POINT = "mark_relabel_point";
    /// The marks of a sweep's results not yet relabelled.
    RELABEL_PENDING = "relabel_pending";
    /// Forgets marks of results not yet relabelled in a key range.
    CLEAR_RELABEL_PENDING = "clear_relabel_pending";
    /// A sweep's rows with their specs, no results (line keys).
    SWEEP_POINT_SPECS = "sweep_point_specs";
    /// One job's rows in a sweep with its result.
    SWEEP_POINTS_OF_JOB = "sweep_points_of_job";
    /// The rows of every sweep whose job id starts with a prefix, with their results (`show`).
    SWEEP_POINTS_WITH_JOB_PREFIX = "sweep_points_with_job_prefix";
    /// Deletes a job row.
    DELETE_JOB = "delete_job";
    /// Deletes a job's result.
    DELETE_RESULT = "delete_result";
    /// Forgets a submission sbatch refused.
    DELETE_SUBMISSION = "delete_submission";
    /// Closes a run row with its end time and outcome.
    END_RUN = "end_run";
    /// A finished job extended from its checkpoint: new finish time, wall time added.
    EXTEND_JOB_TIMES = "extend_job_times";
    /// Marks a job this runner is running failed.
    FAIL_JOB = "fail_job";
    /// Marks a job done, unless it already has a result.
    FINISH_JOB = "finish_job";
    /// Refreshes the heartbeat of a runner's running jobs.
    HEARTBEAT = "heartbeat";
    /// Marks a job done with a result computed elsewhere, unless it already has a result.
    INGEST_DONE_JOB = "ingest_done_job";
    /// Marks a job failed elsewhere, unless it is done or running.
    INGEST_FAILED_JOB = "ingest_failed_job";
    /// Inserts the closed run row of an attempt made elsewhere.
    INSERT_REMOTE_RUN = "insert_remote_run";
    /// Inserts a job's result row.
    INSERT_RESULT = "insert_result";
    /// Opens a run row for a claimed job; returns its id.
    INSERT_RUN = "insert_run";
    /// Records a job array about to be submitted; returns its id.
    INSERT_SUBMISSION = "insert_submission";
    /// Records the job of one array task.
    INSERT_SUBMISSION_TASK = "insert_submission_task";
    /// Adds a job to a sweep's point list.
    INSERT_SWEEP_POINT = "insert_sweep_point";
    /// Whether a job with this id exists.
    JOB_EXISTS = "job_exists";
    /// The rule the job ids of this database follow (meta key `job_ids`).
    JOB_ID_RULE = "job_id_rule";
    /// A job's stored spec.
    JOB_SPEC = "job_spec";
    /// A job's status.
    JOB_STATUS = "job_status";
    /// All sweeps, oldest first.
    LIST_SWEEPS = "list_sweeps";
    /// Tables of a database that is SQLite but not (yet) wetgran's.
    LIST_TABLES = "list_tables";
    /// Every recorded task of a sweep, oldest submission first.
    LIST_TASKS = "list_tasks";
    /// Marks the merged job done with the times of the job whose result it took (re-keying).
    MARK_MERGED_JOB_DONE = "mark_merged_job_done";
    /// Closes an orphaned job's open run rows.
    MARK_RUNS_ORPHANED = "mark_runs_orphaned";
    /// Moves a result to the merged job, unless that job already has one (re-keying).
    MOVE_RESULT_IF_NONE = "move_result_if_none";
    /// The next claimable row of a sweep's queue (chain heads first, then grid order).
    NEXT_CLAIMABLE_POINT = "next_claimable_point";
    /// SQLite's quick integrity check of an existing wetgran database.
    QUICK_CHECK = "quick_check";
    /// Points the result of a job at its new id.
    REKEY_RESULTS = "rekey_results";
    /// Points the run rows of a job at its new id.
    REKEY_RUNS = "rekey_runs";
    /// Points the cluster tasks of a job at its new id.
    REKEY_SUBMISSION_TASKS = "rekey_submission_tasks";
    /// Points the sweep points of a job at its new id.
    REKEY_SWEEP_POINTS = "rekey_sweep_points";
    /// Puts an orphaned running job back to pending (if it is still that owner's).
    REQUEUE_JOB = "requeue_job";
    /// Puts a sweep's failed jobs back to pending.
    RETRY_FAILED_JOBS = "retry_failed_jobs";
    /// Every running job with its owner and heartbeat.
    RUNNING_JOBS = "running_jobs";
    /// Number of run rows per job.
    RUNS_PER_JOB = "runs_per_job";
    /// Marks a new file as wetgran's (APPLICATION_ID, "WGRN"); a PRAGMA takes no bound parameter.
    SET_APPLICATION_ID = "set_application_id";
    /// Records the rule the job ids follow (meta key `job_ids`).
    SET_JOB_ID_RULE = "set_job_id_rule";
    /// Records the grid points skip_invalid left out of a sweep.
    SET_LEFT_OUT = "set_left_out";
    /// Sets the phase label of a stored result and the numbers it was decided on.
    SET_RESULT_LABEL = "set_result_label";
    /// Adds the Slurm job id to a submission.
    SET_SLURM_JOB = "set_slurm_job";
    /// Records what collection found for a task.
    SET_TASK_STATE = "set_task_state";
    /// Switches the database to WAL mode; returns the journal mode now in effect.
    SET_WAL_MODE = "set_wal_mode";
    /// Every job of a sweep (grid order) with its result where there is one.
    SWEEP_POINTS = "sweep_points";
    /// Every job of a sweep (grid order) with what the reports read: scalar columns only.
    SWEEP_POINT_SUMMARIES = "sweep_point_summaries";
    /// A page of a sweep's jobs with their results, after a given point and replica.
    SWEEP_POINTS_PAGE = "sweep_points_page";
    /// The file text a sweep was last registered with.
    SWEEP_SOURCE = "sweep_source";
    /// The file text a sweep was last registered with, by name.
    SWEEP_SOURCE_BY_NAME = "sweep_source_by_name";
    /// Total wall time of a sweep's finished and failed jobs.
    TIME_SPENT = "time_spent";
    /// Sets a sweep's update time.
    TOUCH_SWEEP = "touch_sweep";
    /// Stores (replacing) a job's checkpoint.
    UPSERT_CHECKPOINT = "upsert_checkpoint";
    /// Inserts a job, or gives an existing one its new spec (same id: other thresholds).
    UPSERT_JOB = "upsert_job";
    /// Registers a sweep, or updates the one of this name; returns its id.
    UPSERT_SWEEP = "upsert_sweep";
}

#[cfg(test)]
mod tests {
    use super::ALL;
    use crate::store::MIGRATOR;
    use sqlx::sqlite::{SqliteConnectOptions, SqliteConnection};
    use sqlx::{Connection, Executor, SqlSafeStr, Statement};
    use std::collections::BTreeSet;

    #[test]
    fn every_sql_file_is_the_text_of_exactly_one_query() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/store/sql");
        let files: BTreeSet<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        for f in &files {
            assert!(
                f.ends_with(".sql"),
                "{f}: only .sql files belong in {}",
                dir.display()
            );
        }
        let mut stems = BTreeSet::new();
        for (stem, text) in ALL {
            assert!(
                stems.insert(format!("{stem}.sql")),
                "{stem}.sql: declared twice"
            );
            let on_disk = std::fs::read_to_string(dir.join(format!("{stem}.sql"))).unwrap();
            assert_eq!(
                *text, on_disk,
                "{stem}: the constant is not the file's text"
            );
        }
        assert_eq!(
            files, stems,
            "files in src/store/sql/ and query constants differ"
        );
    }

    /// The `?N` named in a query's leading comment lines.
    fn documented_parameters(text: &str) -> Vec<usize> {
        let mut out = Vec::new();
        for line in text.lines().take_while(|l| l.starts_with("--")) {
            for part in line.split('?').skip(1) {
                let digits: String = part.chars().take_while(char::is_ascii_digit).collect();
                if let Ok(n) = digits.parse() {
                    out.push(n);
                }
            }
        }
        out
    }

    #[test]
    fn every_query_prepares_against_a_migrated_database() {
        // A database migrated directly (not through `Store::open`, whose own queries are among
        // those checked here).
        let dir = tempfile::tempdir().unwrap();
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap();
        rt.block_on(async {
            let opts = SqliteConnectOptions::new()
                .filename(dir.path().join("q.sqlite"))
                .create_if_missing(true)
                .foreign_keys(true);
            let mut conn = SqliteConnection::connect_with(&opts).await.unwrap();
            MIGRATOR.run(&mut conn).await.unwrap();
            for (stem, text) in ALL {
                let statement = (&mut conn)
                    .prepare(text.into_sql_str())
                    .await
                    .unwrap_or_else(|e| panic!("{stem}.sql does not prepare: {e}"));
                let count = statement
                    .parameters()
                    .map_or(0, |p| p.either(|types| types.len(), |n| n));
                let documented = documented_parameters(text);
                let want: Vec<usize> = (1..=count).collect();
                assert_eq!(
                    documented, want,
                    "{stem}.sql: its comment names parameters {documented:?}, the statement has \
                     {count}"
                );
                assert!(
                    text.lines()
                        .any(|l| !l.trim().is_empty() && !l.starts_with("--")),
                    "{stem}.sql: no statement"
                );
            }
        });
    }
}
