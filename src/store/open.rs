//! Opening a read-write store: what the file is ([`inspect`], refused before anything is
//! written), the connection shared with read-only opens ([`Store::connect`]), initialisation
//! (application id, WAL mode, migrations) and the one-time re-keying of jobs to
//! [`JOB_ID_RULE`].

use super::{
    APPLICATION_ID, CACHE_KIB, Durability, Exec, JOB_ID_RULE, MIGRATOR, Store, StoreError,
    busy_timeout, db_error, explain, is_storage_fault, new_owner, queries, sqlite_code,
};
use crate::sweep::spec::JobSpec;
use sqlx::SqliteConnection;
use sqlx::sqlite::{SqliteConnectOptions, SqlitePoolOptions, SqliteSynchronous};
use std::path::Path;
use std::time::Duration;

/// What is at a path before it is opened.
pub(super) enum Existing {
    New,
    /// wetgran's; `wal`: its header says write-ahead-log mode.
    Ours {
        wal: bool,
    },
    OtherSqlite,
}

/// What kind of file system object `m` is, in words (for one that is not a regular file).
fn kind_words(m: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = m.file_type();
    if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a named pipe (FIFO)"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// Refuses a database path that is not a regular file (opening a named pipe would wait for a
/// writer forever; beside a device SQLite would create its journal), and one whose `-wal`,
/// `-shm` or `-journal` is not a regular file, before anything opens them.
fn check_kinds(path: &Path) -> Result<(), StoreError> {
    let p = path.display().to_string();
    if let Ok(m) = std::fs::metadata(path)
        && !m.is_file()
    {
        return Err(StoreError::NotAFile {
            path: p,
            detail: format!("it is {}", kind_words(&m)),
        });
    }
    for suffix in crate::output::DATABASE_COMPANIONS {
        let companion = crate::output::with_suffix(path, suffix);
        if let Ok(m) = std::fs::metadata(&companion)
            && !m.is_file()
        {
            return Err(StoreError::NotAFile {
                path: p,
                detail: format!(
                    "the file SQLite keeps beside it, {}, is {}: remove it or give another \
                     path",
                    companion.display(),
                    kind_words(&m)
                ),
            });
        }
    }
    Ok(())
}

/// The size the header of an SQLite file says it has (page size times page count), where the
/// header's page count is valid (SQLite 3.7.0 on: "version-valid-for" equals the change
/// counter).
fn header_size(header: &[u8]) -> Option<u64> {
    let be32 = |at: usize| {
        u32::from_be_bytes([header[at], header[at + 1], header[at + 2], header[at + 3]])
    };
    let page_size = match u16::from_be_bytes([header[16], header[17]]) {
        1 => 65536,
        n => u64::from(n),
    };
    (be32(92) == be32(24) && be32(28) > 0).then(|| page_size * u64::from(be32(28)))
}

/// What is at `path`, from its header; nothing there (a missing or empty file) is
/// [`StoreError::Missing`] unless `create`. A path that is not a regular file, and a file
/// shorter than its header says (with no log beside it that holds the rest), are refused.
pub(super) fn inspect(path: &Path, create: bool) -> Result<Existing, StoreError> {
    check_kinds(path)?;
    let p = path.display().to_string();
    let new = || match create {
        true => Ok(Existing::New),
        false => Err(StoreError::Missing { path: p.clone() }),
    };
    // The 100-byte header only: a database of 10^5 results is gigabytes.
    let header = || -> std::io::Result<Vec<u8>> {
        use std::io::Read as _;
        let mut bytes = Vec::with_capacity(100);
        std::fs::File::open(path)?
            .take(100)
            .read_to_end(&mut bytes)?;
        Ok(bytes)
    };
    let bytes = match header() {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return new(),
        Err(e) => {
            return Err(StoreError::Db {
                path: p,
                detail: format!("cannot read the file: {e}"),
            });
        }
    };
    if bytes.is_empty() {
        return new();
    }
    if bytes.len() < 100 || &bytes[..16] != b"SQLite format 3\0" {
        let detail = if bytes.len() < 100 {
            format!("{} bytes, shorter than an SQLite header", bytes.len())
        } else {
            "no SQLite header".to_string()
        };
        return Err(StoreError::NotSqlite { path: p, detail });
    }
    // In WAL mode the log may hold the pages a checkpoint had not yet written: only a file
    // without a log is measured against its header.
    let len = std::fs::metadata(path).map_or(0, |m| m.len());
    if let Some(size) = header_size(&bytes)
        && len < size
        && log_missing(path)
    {
        return Err(StoreError::Truncated {
            path: p,
            detail: format!("{len} bytes, where its header counts {size}"),
        });
    }
    let app_id = i32::from_be_bytes([bytes[68], bytes[69], bytes[70], bytes[71]]);
    if app_id == APPLICATION_ID {
        // File format bytes 18 and 19: 2 in write-ahead-log mode.
        Ok(Existing::Ours {
            wal: bytes[18] == 2,
        })
    } else if app_id != 0 {
        Err(StoreError::NotWetgran {
            path: p,
            detail: format!("application id {app_id:#x}"),
        })
    } else {
        Ok(Existing::OtherSqlite)
    }
}

/// Whether the write-ahead log beside `path` is missing or empty (holds no commits).
pub(super) fn log_missing(path: &Path) -> bool {
    std::fs::metadata(crate::output::with_suffix(path, "-wal")).map_or(true, |m| m.len() == 0)
}

/// The migrations applied to a database (none where it has no migration table yet).
pub(super) async fn applied_migrations(
    conn: &mut sqlx::SqliteConnection,
) -> Result<Vec<i64>, sqlx::Error> {
    match sqlx::query_scalar::<_, i64>(queries::APPLIED_MIGRATIONS)
        .fetch_all(conn)
        .await
    {
        Ok(v) => Ok(v),
        // No migration table: initialised, never migrated.
        Err(e) if e.to_string().contains("no such table") => Ok(Vec::new()),
        Err(e) => Err(e),
    }
}

impl Store {
    /// Opens (creating if needed) the database at `path` and applies the migrations.
    pub fn open(path: &Path) -> Result<Store, StoreError> {
        Self::open_as(path, true, Durability::Synced)
    }

    /// Opens an existing database; a missing file is an error (nothing is created).
    pub fn open_existing(path: &Path) -> Result<Store, StoreError> {
        Self::open_as(path, false, Durability::Synced)
    }

    /// Opens the database at `path` (creating it if `create`, else a missing file is an error)
    /// with commits as `durability` says.
    pub fn open_as(path: &Path, create: bool, durability: Durability) -> Result<Store, StoreError> {
        // Two runners starting at once on a new file race to initialise it: the loser's
        // journal-mode switch or migration fails (its transaction rolls back) and it tries again,
        // then finding the file initialised.
        let mut attempt = 0;
        loop {
            match Self::open_once(path, create, durability) {
                Err(StoreError::Db { .. }) if attempt < 6 => {
                    attempt += 1;
                    std::thread::sleep(Duration::from_millis(50 * attempt));
                }
                other => return other,
            }
        }
    }

    fn open_once(path: &Path, create: bool, durability: Durability) -> Result<Store, StoreError> {
        let existing = inspect(path, create)?;
        if let Existing::Ours { .. } = existing {
            // What can be refused is refused before SQLite creates the log beside the file.
            Self::probe(path)?;
        }
        let opts = SqliteConnectOptions::new()
            .create_if_missing(true)
            .foreign_keys(true)
            .synchronous(match durability {
                Durability::Synced => SqliteSynchronous::Full,
                Durability::Fast => SqliteSynchronous::Normal,
            });
        let store = Self::connect(path, opts, explain)?;
        store.prepare(existing)?;
        store.rekey_jobs()?;
        store.close_interrupted_runs()?;
        Ok(store)
    }

    /// The store's runtime and its one connection to `path` with `opts` (read-write or
    /// read-only), waiting [`busy_timeout`] for locks; `open_error` words a failed connect.
    pub(super) fn connect(
        path: &Path,
        opts: SqliteConnectOptions,
        open_error: impl Fn(&sqlx::Error) -> String,
    ) -> Result<Store, StoreError> {
        let failed = |detail: String| StoreError::Db {
            path: path.display().to_string(),
            detail,
        };
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .map_err(|e| failed(format!("cannot start the async runtime: {e}")))?;
        let busy = busy_timeout();
        let opts = opts
            .filename(path)
            .busy_timeout(busy)
            // Page cache of the one connection, in KiB (negative: a size, not a page count):
            // job ids are hashes, so every job, result and run row lands on a random page of
            // its index; SQLite's default 2 MiB holds those pages of ~10^3 jobs, this of ~10^5.
            .pragma("cache_size", format!("-{CACHE_KIB}"));
        let pool = rt
            .block_on(
                SqlitePoolOptions::new()
                    .max_connections(1)
                    .min_connections(0)
                    .acquire_timeout(busy * 2 + Duration::from_secs(1))
                    .connect_with(opts),
            )
            .map_err(|e| match sqlite_code(&e) {
                // Connecting reads the header and the schema: a malformed one is damage.
                Some(11 | 26) => StoreError::Damaged {
                    path: path.display().to_string(),
                    detail: e.to_string(),
                },
                _ => failed(open_error(&e)),
            })?;
        Ok(Store {
            rt,
            pool,
            path: path.to_path_buf(),
            owner: new_owner(),
            write_hook: None,
        })
    }

    /// Checks (read-only) what is in the file, then initialises and migrates it.
    fn prepare(&self, existing: Existing) -> Result<(), StoreError> {
        let db = |e: sqlx::Error| db_error(&self.path, &e);
        // A file that cannot be read or written is not a damaged one.
        let damaged = |e: sqlx::Error| match is_storage_fault(&e) {
            true => db(e),
            false => self.damaged(e.to_string()),
        };
        self.rt.block_on(async {
            let mut conn = self.pool.acquire().await.map_err(db)?;
            let conn: &mut SqliteConnection = &mut conn;
            match existing {
                Existing::OtherSqlite => {
                    let tables: Vec<String> = sqlx::query_scalar(queries::LIST_TABLES)
                        .fetch_all(&mut *conn)
                        .await
                        .map_err(damaged)?;
                    if !tables.is_empty() {
                        return Err(self.not_wetgran(&tables));
                    }
                }
                Existing::Ours { wal } => {
                    let check: Vec<String> = sqlx::query_scalar(queries::QUICK_CHECK)
                        .fetch_all(&mut *conn)
                        .await
                        .map_err(damaged)?;
                    if check.first().map(String::as_str) != Some("ok") {
                        return Err(self.damaged(format!("integrity check: {}", check.join("; "))));
                    }
                    let tables: Vec<String> = sqlx::query_scalar(queries::LIST_TABLES)
                        .fetch_all(&mut *conn)
                        .await
                        .map_err(damaged)?;
                    if wal && tables.is_empty() && log_missing(&self.path) {
                        return Err(StoreError::NoContent {
                            path: self.path.display().to_string(),
                        });
                    }
                    let applied = applied_migrations(conn).await.map_err(damaged)?;
                    self.refuse_newer(&applied)?;
                }
                Existing::New => {}
            }
            if !matches!(existing, Existing::Ours { .. }) {
                // Before WAL mode, so that the id is written to the main file at once.
                sqlx::query(queries::SET_APPLICATION_ID)
                    .execute(&mut *conn)
                    .await
                    .map_err(db)?;
            }
            let mode: String = sqlx::query_scalar(queries::SET_WAL_MODE)
                .fetch_one(&mut *conn)
                .await
                .map_err(db)?;
            let failed = |detail: String| StoreError::Db {
                path: self.path.display().to_string(),
                detail,
            };
            if !mode.eq_ignore_ascii_case("wal") {
                return Err(failed(format!(
                    "cannot switch to WAL mode (journal mode is {mode})"
                )));
            }
            MIGRATOR.run(&mut *conn).await.map_err(|e| {
                failed(match e {
                    sqlx::migrate::MigrateError::Execute(e)
                    | sqlx::migrate::MigrateError::ExecuteMigration(e, _) => {
                        format!("applying the migrations: {}", explain(&e))
                    }
                    e => format!("applying the migrations: {e}"),
                })
            })?;
            Ok(())
        })
    }

    /// The refusal of an SQLite database of another program, by the tables it holds.
    pub(super) fn not_wetgran(&self, tables: &[String]) -> StoreError {
        StoreError::NotWetgran {
            path: self.path.display().to_string(),
            detail: format!("tables {}", tables.join(", ")),
        }
    }

    /// Whether the job ids follow [`JOB_ID_RULE`] (meta key `job_ids`).
    pub(super) fn job_ids_current(&self) -> Result<bool, StoreError> {
        let rule: Option<String> =
            self.run(sqlx::query_scalar(queries::JOB_ID_RULE).fetch_optional(&self.pool))?;
        Ok(rule.as_deref() == Some(JOB_ID_RULE))
    }

    /// Compatibility rule for databases written before job ids left out the `[classify]`
    /// thresholds (docs/model-choices.md, "Job identity"): once per database (meta key
    /// `job_ids` = [`JOB_ID_RULE`]), every job is re-keyed to the id its stored spec has now,
    /// in one transaction. Jobs that differed only in their thresholds become one: its point
    /// rows, runs and cluster tasks follow it; a result is kept (the first one found where the
    /// merged job has none, dropped otherwise: the trajectory is the same).
    fn rekey_jobs(&self) -> Result<(), StoreError> {
        if self.job_ids_current()? {
            return Ok(());
        }
        self.in_transaction(async |tx| {
            let jobs: Vec<(String, String)> = sqlx::query_as(queries::ALL_JOB_SPECS)
                .fetch_all(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            for (old, text) in jobs {
                let spec = JobSpec::from_json(&text, &format!("job {old}"))
                    .map_err(|e| self.damaged(format!("a job spec is not readable: {e}")))?;
                let new = spec.id();
                if new == old {
                    continue;
                }
                let exists: Option<String> = sqlx::query_scalar(queries::JOB_EXISTS)
                    .bind(&new)
                    .fetch_optional(&mut **tx)
                    .await
                    .map_err(|e| self.db(e))?;
                // The statements that bind the old id, then the new one.
                let pair = |sql| sqlx::query(sql).bind(old.as_str()).bind(new.as_str());
                if exists.is_none() {
                    pair(queries::COPY_JOB_TO_NEW_ID).exec(tx, self).await?;
                } else {
                    // Merging: the merged job takes this one's result if it has none.
                    if pair(queries::MOVE_RESULT_IF_NONE).exec(tx, self).await? > 0 {
                        pair(queries::MARK_MERGED_JOB_DONE).exec(tx, self).await?;
                    }
                    sqlx::query(queries::DELETE_RESULT)
                        .bind(&old)
                        .exec(tx, self)
                        .await?;
                }
                for sql in [
                    queries::REKEY_SWEEP_POINTS,
                    queries::REKEY_RUNS,
                    queries::REKEY_SUBMISSION_TASKS,
                    queries::REKEY_RESULTS,
                ] {
                    pair(sql).exec(tx, self).await?;
                }
                // A merged job may have taken another's result: its lines are relabelled.
                sqlx::query(queries::MARK_RELABEL_JOB)
                    .bind(&new)
                    .exec(tx, self)
                    .await?;
                sqlx::query(queries::DELETE_JOB)
                    .bind(&old)
                    .exec(tx, self)
                    .await?;
            }
            sqlx::query(queries::SET_JOB_ID_RULE)
                .bind(JOB_ID_RULE)
                .exec(tx, self)
                .await?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::store_with_jobs;
    use crate::sweep::job::JobResult;

    #[test]
    fn application_id_pragma_matches_the_constant() {
        // The PRAGMA text cannot take a bound parameter; keep it in step with the constant.
        assert_eq!(APPLICATION_ID, 1464291918);
        let statement = queries::SET_APPLICATION_ID
            .lines()
            .find(|l| !l.starts_with("--"))
            .unwrap();
        assert_eq!(
            statement,
            format!("PRAGMA application_id = {APPLICATION_ID}")
        );
    }

    #[test]
    fn a_database_with_old_job_ids_is_rekeyed_once_and_keeps_its_results() {
        let dir = tempfile::tempdir().unwrap();
        let (db, sweep_id) = store_with_jobs(dir.path());
        let store = Store::open(&db).unwrap();
        let claim = store.claim(&[sweep_id]).unwrap().unwrap();
        let result = JobResult {
            phase: Some("g".into()),
            decided_on: None,
            observables: serde_json::json!({"k": 1}),
            simulated_time: 1.0,
            wall_seconds: 0.5,
            events: 3,
            checkpoint: None,
        };
        assert!(store.finish(&claim, &result).unwrap());
        let done_id = claim.job_id.clone();
        // Write the database as the old rule did: ids hashed with the `[classify]` thresholds,
        // plus a second job that differed from the finished one only in its thresholds.
        store.execute_for_tests("PRAGMA foreign_keys = OFF", &[]);
        for p in store.points(sweep_id).unwrap() {
            let old = crate::sweep::spec::id_of_canonical(&p.spec.canonical_json());
            assert_ne!(old, p.job_id);
            for sql in [
                "UPDATE jobs SET id = ?2 WHERE id = ?1",
                "UPDATE sweep_points SET job_id = ?2 WHERE job_id = ?1",
                "UPDATE results SET job_id = ?2 WHERE job_id = ?1",
                "UPDATE runs SET job_id = ?2 WHERE job_id = ?1",
            ] {
                store.execute_for_tests(sql, &[&p.job_id, &old]);
            }
        }
        let mut twin = claim.spec.clone();
        twin.scene.classify.gas_temperature *= 2.0;
        let twin_old = crate::sweep::spec::id_of_canonical(&twin.canonical_json());
        store.execute_for_tests(
            "INSERT INTO jobs (id, spec, created_at) VALUES (?1, ?2, 0)",
            &[&twin_old, &twin.canonical_json()],
        );
        store.execute_for_tests(
            "INSERT INTO sweep_points (sweep_id, point, replica, coords, job_id) \
             VALUES (1, 99, 0, '[9]', ?1)",
            &[&twin_old],
        );
        store.execute_for_tests("DELETE FROM meta WHERE key = 'job_ids'", &[]);
        drop(store);

        let store = Store::open_existing(&db).unwrap();
        let points = store.points(sweep_id).unwrap();
        assert_eq!(points.len(), 4);
        for p in &points {
            assert_eq!(
                p.job_id,
                p.spec.id(),
                "every job carries its id under the new rule"
            );
        }
        // The twin merged into the finished job and shares its result.
        let twin_row = points.iter().find(|p| p.point == 99).unwrap();
        assert_eq!(twin_row.job_id, done_id);
        for p in points.iter().filter(|p| p.job_id == done_id) {
            assert_eq!(p.status, "done");
            assert_eq!(p.observables, Some(serde_json::json!({"k": 1})));
        }
        let jobs: i64 = store
            .rt
            .block_on(sqlx::query_scalar("SELECT count(*) FROM jobs").fetch_one(&store.pool))
            .unwrap();
        assert_eq!(jobs, 3);
        assert_eq!(store.runs_per_job().unwrap(), vec![(done_id.clone(), 1)]);
        // Marked once: opening again changes nothing.
        let rule: String = store
            .rt
            .block_on(sqlx::query_scalar(queries::JOB_ID_RULE).fetch_one(&store.pool))
            .unwrap();
        assert_eq!(rule, JOB_ID_RULE);
    }
}
