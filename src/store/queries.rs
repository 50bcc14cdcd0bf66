//! The store's SQL: one statement per file in `src/store/sql/`, one constant per statement
//! (named after its file), embedded with `include_str!`. Each file starts with a comment saying
//! what it does and its bind order (`-- ?1: owner, ?2: now, ...`); the code binds in that order.
//!
//! The statements are not checked at compile time: sqlx's `query!` macros need a live database
//! (`DATABASE_URL`) or prepared offline data, and the build has only the Rust toolchain. The
//! tests below check instead that every file is one constant's, and those of `query_plans` that
//! every statement prepares against a migrated database, with as many parameters as its
//! comment names.
//! A constant no code uses fails the build (`dead_code` under `-D warnings`).

/// Declares each query constant from its file `sql/<file>.sql` (whose leading comment says
/// what it does), and (for the tests) the list of all of them.
macro_rules! queries {
    ($($name:ident = $file:literal;)*) => {
        $(
            pub(super) const $name: &str = include_str!(concat!("sql/", $file, ".sql"));
        )*
        /// Every query: its file's stem and its text.
        #[cfg(test)]
        pub(super) const ALL: &[(&str, &str)] = &[$(($file, $name)),*];
    };
}

queries! {
    APPLIED_MIGRATIONS = "applied_migrations";
    CHECKPOINT_TRUNCATE = "checkpoint_truncate";
    CLOSE_INTERRUPTED_RUNS = "close_interrupted_runs";
    OPEN_RUN_OWNERS = "open_run_owners";
    SWEEP_POINT_SUMMARIES_PACKED = "sweep_point_summaries_packed";
    SWEEP_FIRST_SPEC = "sweep_first_spec";
    SWEEP_RUNNING_JOBS = "sweep_running_jobs";
    ALL_JOB_SPECS = "all_job_specs";
    BEGIN_IMMEDIATE = "begin_immediate";
    CHECKPOINT_STATE = "checkpoint_state";
    CLAIM_JOB = "claim_job";
    COPY_JOB_TO_NEW_ID = "copy_job_to_new_id";
    FINISHED_JOB_COSTS = "finished_job_costs";
    COUNT_BY_STATUS = "count_by_status";
    DELETE_GRID_POINTS = "delete_grid_points";
    MARK_RELABEL_JOB = "mark_relabel_job";
    MARK_RELABEL_POINT = "mark_relabel_point";
    RELABEL_PENDING = "relabel_pending";
    CLEAR_RELABEL_PENDING = "clear_relabel_pending";
    SWEEP_POINT_SPECS = "sweep_point_specs";
    SWEEP_POINTS_OF_JOB = "sweep_points_of_job";
    SWEEP_POINTS_WITH_JOB_PREFIX = "sweep_points_with_job_prefix";
    DELETE_JOB = "delete_job";
    DELETE_RESULT = "delete_result";
    DELETE_SUBMISSION = "delete_submission";
    END_RUN = "end_run";
    EXTEND_JOB_TIMES = "extend_job_times";
    FAIL_JOB = "fail_job";
    FINISH_JOB = "finish_job";
    HEARTBEAT = "heartbeat";
    INGEST_DONE_JOB = "ingest_done_job";
    INGEST_FAILED_JOB = "ingest_failed_job";
    INSERT_REMOTE_RUN = "insert_remote_run";
    INSERT_RESULT = "insert_result";
    INSERT_RUN = "insert_run";
    INSERT_SUBMISSION = "insert_submission";
    INSERT_SUBMISSION_TASK = "insert_submission_task";
    INSERT_SWEEP_POINT = "insert_sweep_point";
    JOB_EXISTS = "job_exists";
    JOB_ID_RULE = "job_id_rule";
    JOB_SPEC = "job_spec";
    JOB_STATUS = "job_status";
    LIST_SWEEPS = "list_sweeps";
    LIST_TABLES = "list_tables";
    LIST_TASKS = "list_tasks";
    MARK_MERGED_JOB_DONE = "mark_merged_job_done";
    MARK_RUNS_ORPHANED = "mark_runs_orphaned";
    MOVE_RESULT_IF_NONE = "move_result_if_none";
    NEXT_CLAIMABLE_POINT = "next_claimable_point";
    QUICK_CHECK = "quick_check";
    REKEY_RESULTS = "rekey_results";
    REKEY_RUNS = "rekey_runs";
    REKEY_SUBMISSION_TASKS = "rekey_submission_tasks";
    REKEY_SWEEP_POINTS = "rekey_sweep_points";
    REQUEUE_JOB = "requeue_job";
    RETRY_FAILED_JOBS = "retry_failed_jobs";
    RUNNING_JOBS = "running_jobs";
    RUNS_PER_JOB = "runs_per_job";
    SET_APPLICATION_ID = "set_application_id";
    SET_JOB_ID_RULE = "set_job_id_rule";
    SET_LEFT_OUT = "set_left_out";
    SET_RESULT_LABEL = "set_result_label";
    SET_SLURM_JOB = "set_slurm_job";
    SET_TASK_STATE = "set_task_state";
    SET_WAL_MODE = "set_wal_mode";
    SWEEP_DECISIONS = "sweep_decisions";
    SWEEP_POINTS = "sweep_points";
    SWEEP_POINT_SUMMARIES = "sweep_point_summaries";
    SWEEP_POINTS_PAGE = "sweep_points_page";
    SWEEP_SOURCE = "sweep_source";
    SWEEP_SOURCE_BY_NAME = "sweep_source_by_name";
    TIME_SPENT = "time_spent";
    TOUCH_SWEEP = "touch_sweep";
    UPSERT_CHECKPOINT = "upsert_checkpoint";
    UPSERT_JOB = "upsert_job";
    UPSERT_SWEEP = "upsert_sweep";
}

#[cfg(test)]
mod tests {
    use super::ALL;
    use std::collections::BTreeSet;

    #[test]
    fn every_sql_file_is_one_query_and_nothing_else_is_there() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/store/sql");
        let files: BTreeSet<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        let stems: BTreeSet<String> = ALL.iter().map(|(stem, _)| format!("{stem}.sql")).collect();
        assert_eq!(stems.len(), ALL.len(), "a file is declared twice");
        assert_eq!(
            files, stems,
            "files in src/store/sql/ (only .sql files belong there) and query constants differ"
        );
    }
}
