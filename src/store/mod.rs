//! The SQLite store (sqlx): sweeps, content-addressed jobs, results, and the claim/heartbeat
//! protocol that lets several runners share one database file.
//!
//! Opening: a file that is not SQLite, an SQLite database of another program, or a damaged one is
//! refused with a message naming the file, before anything is written to it. A new file gets the
//! wetgran application id (SQLite header offset 68, written before WAL mode so it always lands
//! in the main file), then WAL mode, then the embedded migrations of `migrations/`. Every
//! connection waits up to [`busy_timeout`] (default [`BUSY_TIMEOUT`]) for a lock held by another
//! process.
//!
//! Storage faults (docs/reliability.md): a database locked for longer than that, a read-only
//! file, folder or filesystem, a full disk or an I/O error fail the command with an error that
//! names the file and says which fault it is ([`explain`]); the failed transaction rolls back,
//! so every result committed before stays, and a file that cannot be opened is never called
//! damaged.
//!
//! Async stays inside: the store owns a one-thread tokio runtime and a one-connection pool, and
//! every method blocks on it. Only the thread that owns the store talks to the database.
//!
//! Claims and crashes:
//! - A claim reads the first row of its sweep's queue (`sweep_points.claim_rank`, kept by
//!   triggers: migration `20261127000000_claim_queue.sql`) and sets that job running, inside
//!   one `BEGIN IMMEDIATE` transaction: two runners cannot claim the same job. The queue is a
//!   partial index ordered as the claim takes it, so a claim costs the same at any sweep size.
//! - A runner owns its jobs under an owner name `host:pid:nonce` and refreshes their heartbeat
//!   every [`HEARTBEAT_INTERVAL`].
//! - A running job is orphaned when its heartbeat is older than [`STALE_AFTER`] (twelve missed
//!   heartbeats), or at once when its owner ran on this host and that process no longer exists
//!   (Linux, `/proc/PID`). Orphans are re-queued when a runner starts (`sweep run`,
//!   `sweep resume`).
//! - A finished job is committed on its own transaction (job row, result row, run row); a crash
//!   loses at most the jobs that were running. A result arriving for a job that another runner
//!   already finished is discarded, so a job never has two results.
//!
//! SQL: one statement per file of `sql/`, embedded by `queries.rs` (which says how they are
//! checked). A schema change is a new migration in `migrations/`. The files here split the
//! store by concern; each says which in its header.

#[cfg(test)]
mod claim_queue_tests;
mod claims;
mod cluster;
mod hooks;
pub mod hysteresis;
mod open;
mod queries;
#[cfg(test)]
mod query_plans;
mod read_only;
mod reads;
mod register;
mod relabel_queue;
mod stale;
mod summary;

pub use cluster::{TaskRow, TaskState};
pub use hooks::{WriteHook, WritePoint};
pub use read_only::{ReadAccess, read_access};
pub use relabel_queue::PointSpec;
pub use stale::{RunningJob, Stale};
pub use summary::{PointSummary, axis_keeps_report_scene, unconverged_summaries};

use crate::sweep::file::Axis;
use crate::sweep::spec::JobSpec;
pub(crate) use claims::host_name;
use claims::{new_owner, owner_is_dead};
use sqlx::sqlite::SqlitePool;
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// SQLite `application_id` of a wetgran database ("WGRN").
pub const APPLICATION_ID: i32 = 0x5747_524e;
/// How long a statement waits for another process's lock, unless [`BUSY_TIMEOUT_VAR`] says
/// otherwise ([`busy_timeout`]).
pub const BUSY_TIMEOUT: Duration = Duration::from_secs(30);
/// The environment variable that sets the busy timeout, in seconds (a slow shared filesystem may
/// want more; the storage-fault tests want less).
pub const BUSY_TIMEOUT_VAR: &str = "WETGRAN_BUSY_TIMEOUT";
/// How often a runner refreshes the heartbeat of its running jobs.
pub const HEARTBEAT_INTERVAL: Duration = Duration::from_secs(5);
/// The page cache of a store's connection, KiB.
const CACHE_KIB: u32 = 64 * 1024;
/// Rows per page of [`Store::scan_points`] (observables of up to ~150 kB each: ~10 MB a page).
pub const POINTS_PAGE: i64 = 64;
/// A running job whose heartbeat is older than this is re-queued.
pub const STALE_AFTER: Duration = Duration::from_secs(60);

static MIGRATOR: sqlx::migrate::Migrator = sqlx::migrate!("./migrations");

/// Why the store could not do what was asked.
#[derive(Debug, Clone, PartialEq)]
pub enum StoreError {
    /// The file exists but is not an SQLite database.
    NotSqlite { path: String, detail: String },
    /// An SQLite database, but not one of wetgran's.
    NotWetgran { path: String, detail: String },
    /// The database is damaged (failed integrity check or unreadable pages).
    Damaged { path: String, detail: String },
    /// No database at the path (commands that only read).
    Missing { path: String },
    /// A name that is not in the database.
    NoSuchSweep { path: String, name: String },
    /// Written by an older wetgran; commands that only read never upgrade it
    /// (`wetgran upgrade` does).
    Outdated { path: String, detail: String },
    /// Written by a newer wetgran (a migration this one does not know).
    Newer { path: String, detail: String },
    /// Not a regular file (a folder, a named pipe, a device, a socket), or a file of its own
    /// beside it (`-wal`, `-shm`, `-journal`) that is not one.
    NotAFile { path: String, detail: String },
    /// Shorter than its own header says: an incomplete copy or download.
    Truncated { path: String, detail: String },
    /// wetgran's, in write-ahead-log mode, but without any table and without its log: the
    /// main file of a database copied without its `-wal` file while a run was writing it.
    NoContent { path: String },
    /// Stopped by the user (Ctrl-C) in the middle of a transaction, which was rolled back.
    Interrupted { path: String, detail: String },
    /// Any other database error.
    Db { path: String, detail: String },
}

impl fmt::Display for StoreError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StoreError::NotSqlite { path, detail } => write!(
                f,
                "{path}: not a wetgran database: the file is not SQLite ({detail}); it was left \
                 unchanged. Give another path with --db"
            ),
            StoreError::NotWetgran { path, detail } => write!(
                f,
                "{path}: not a wetgran database: an SQLite database of another program \
                 ({detail}); it was left unchanged. Give another path with --db"
            ),
            StoreError::Damaged { path, detail } => write!(
                f,
                "{path}: the wetgran database is damaged ({detail}); it was left unchanged. \
                 Restore a copy, or start a new database with --db"
            ),
            StoreError::Missing { path } => write!(
                f,
                "{path}: no database here: run `wetgran sweep run FILE` first, or give the \
                 database with --db"
            ),
            StoreError::NoSuchSweep { path, name } => {
                write!(f, "{path}: no sweep named `{name}` in this database")
            }
            StoreError::Outdated { path, detail } => write!(
                f,
                "{path}: written by an older wetgran ({detail}); a command that only reads never \
                 changes a database: `wetgran upgrade --db {path}` upgrades it in place where it \
                 can be written (copy the file first to keep the old one; commands that write, \
                 such as `sweep resume`, also upgrade it){}",
                if open::log_missing(Path::new(path)) {
                    format!(
                        ". If the file is a copy taken while wetgran was writing the database, \
                         its write-ahead log {path}-wal was left behind: copy that file beside it \
                         instead"
                    )
                } else {
                    String::new()
                }
            ),
            StoreError::Newer { path, detail } => write!(
                f,
                "{path}: written by a newer wetgran ({detail}); it was left unchanged: use that \
                 version (this is wetgran {})",
                env!("CARGO_PKG_VERSION")
            ),
            StoreError::NotAFile { path, detail } => write!(
                f,
                "{path}: not a database file: {detail}; nothing was opened or created. Give the \
                 path of a database file (or of a new one) with --db"
            ),
            StoreError::Truncated { path, detail } => write!(
                f,
                "{path}: the wetgran database is cut short ({detail}): an incomplete copy or \
                 download; it was left unchanged. Copy it again whole (with its -wal file, if \
                 it has one), or restore a backup"
            ),
            StoreError::NoContent { path } => write!(
                f,
                "{path}: a wetgran database without its content: the file holds no table and \
                 its write-ahead log {path}-wal is missing. It looks like the main file of a \
                 database copied alone while wetgran was writing it: copy the -wal file with it \
                 (both while no wetgran runs on the database), or restore a backup. It was left \
                 unchanged"
            ),
            StoreError::Interrupted { path, detail } => write!(f, "{path}: {detail}"),
            StoreError::Db { path, detail } => write!(f, "{path}: database error: {detail}"),
        }
    }
}

impl std::error::Error for StoreError {}

/// A sweep as registered.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRow {
    pub id: i64,
    pub name: String,
    pub file: String,
    pub description: Option<String>,
    pub cost: Option<String>,
    pub axes: Vec<Axis>,
    pub replicas: u32,
    pub created_at: f64,
    pub updated_at: f64,
    /// Grid points left out by `sweep.skip_invalid` when last registered.
    pub left_out: Vec<LeftOut>,
}

/// A grid point left out by `sweep.skip_invalid`, as stored with its sweep.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LeftOut {
    pub coords: Vec<serde_json::Value>,
    /// The failed scene constraint, in words ([`wetgran_core::scene::Constraint::reason`]).
    pub constraint: String,
    /// The full validation message.
    pub reason: String,
}

/// A job this runner claimed.
#[derive(Debug, Clone)]
pub struct Claim {
    pub job_id: String,
    /// The row of this attempt in the `runs` table.
    pub run_id: i64,
    pub spec: JobSpec,
    pub sweep: String,
    pub point: i64,
    pub replica: i64,
    pub coords: Vec<serde_json::Value>,
    /// A continuation job's start state (its predecessor's final state carried into its
    /// container); filled in by the runner, `None` from [`Store::claim`].
    pub start: Option<Box<wetgran_core::sim::EngineState>>,
}

/// Jobs of a sweep by state (counted per grid point and replica).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StateCounts {
    pub pending: u64,
    pub running: u64,
    pub done: u64,
    pub failed: u64,
}

impl StateCounts {
    pub fn total(&self) -> u64 {
        self.pending + self.running + self.done + self.failed
    }

    /// Counts `n` jobs of a stored status (any but pending, running and done is failed).
    fn add(&mut self, status: &str, n: u64) {
        *match status {
            "pending" => &mut self.pending,
            "running" => &mut self.running,
            "done" => &mut self.done,
            _ => &mut self.failed,
        } += n;
    }
}

/// One job of a sweep with everything known about it (for boundaries, plots, exports).
#[derive(Debug, Clone)]
pub struct PointRow {
    pub point: i64,
    pub replica: i64,
    pub coords: Vec<serde_json::Value>,
    pub job_id: String,
    pub status: String,
    pub spec: JobSpec,
    pub attempts: i64,
    pub last_error: Option<String>,
    pub phase: Option<String>,
    pub decided_on: Option<serde_json::Value>,
    pub observables: Option<serde_json::Value>,
    pub simulated_time: Option<f64>,
    pub wall_seconds: Option<f64>,
    pub events: Option<i64>,
    pub finished_at: Option<f64>,
    /// The runner that committed the result.
    pub result_owner: Option<String>,
    /// The result's trend state (`results.trend`; `None` without a result, or for a result
    /// stored before trend states existed).
    pub trend: Option<wetgran_core::observe::trend::TrendState>,
}

impl PointRow {
    /// The verdict on the result's label, from its decision (`settling.verdict`); `None`
    /// without a result or for a result stored before verdicts.
    pub fn verdict(&self) -> Option<wetgran_core::observe::Verdict> {
        self.decided_on
            .as_ref()?
            .pointer("/settling/verdict")?
            .as_str()
            .and_then(wetgran_core::observe::Verdict::parse)
    }

    /// The verdict as the reports read it: stationary, label kept, or a label that may still
    /// change (also a result stored before verdicts); no result yet reads as stationary.
    pub fn trust(&self) -> wetgran_core::observe::Verdict {
        use wetgran_core::observe::Verdict;
        match (&self.phase, self.verdict()) {
            (_, Some(v)) => v,
            (Some(_), None) => Verdict::NotSettled,
            (None, None) => Verdict::Stationary,
        }
    }

    /// Whether the result may carry a phase boundary: stationary, or a trend that cannot change
    /// its label (a heating gas, a cooling solid, a coarsening coexistence).
    pub fn trusted(&self) -> bool {
        self.trust().label_trusted()
    }
}

/// Points added by refinement are numbered from here on (grid points are below: a sweep has at
/// most `MAX_JOBS` jobs).
pub const REFINED_FROM: i64 = crate::sweep::file::MAX_JOBS as i64;

/// The rule job ids follow (meta key `job_ids`): the spec without its `[classify]` thresholds
/// ([`JobSpec::identity`]). A database without it is re-keyed when opened.
pub const JOB_ID_RULE: &str = "spec-without-classify";

/// When a commit reaches the disk (docs/reliability.md, "Commits without a sync").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Durability {
    /// Every commit syncs the write-ahead log to disk before it returns (SQLite
    /// `synchronous = FULL`): a committed transaction survives a power loss.
    Synced,
    /// Commits append to the write-ahead log without a sync; the log is synced when SQLite
    /// checkpoints it into the database (`synchronous = NORMAL` in WAL mode). A committed
    /// transaction survives the death of the process (kill -9: its writes are in the operating
    /// system's cache); a power loss or an operating-system crash may roll back the last
    /// transactions, each whole, and never damages the file. For local runs (`sweep run`,
    /// `sweep resume`), where every such transaction can be made again.
    Fast,
}

/// An open wetgran database.
#[derive(Debug)]
pub struct Store {
    rt: tokio::runtime::Runtime,
    pool: SqlitePool,
    path: PathBuf,
    owner: String,
    /// Called inside the write transactions (`hooks`).
    write_hook: Option<WriteHook>,
}

/// How long a statement waits for another process's lock: [`BUSY_TIMEOUT_VAR`] seconds when
/// set to a number >= 0, else [`BUSY_TIMEOUT`].
pub fn busy_timeout() -> Duration {
    std::env::var(BUSY_TIMEOUT_VAR)
        .ok()
        .and_then(|s| s.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s >= 0.0)
        .map(Duration::from_secs_f64)
        .unwrap_or(BUSY_TIMEOUT)
}

/// SQLite's primary result code of a database error (`None` for other errors).
fn sqlite_code(e: &sqlx::Error) -> Option<i64> {
    match e {
        sqlx::Error::Database(d) => d.code()?.parse::<i64>().ok().map(|c| c & 0xff),
        _ => None,
    }
}

/// Whether an error is a fault of the file or its storage (locked, read-only, full, cannot be
/// opened, I/O), not of its content.
fn is_storage_fault(e: &sqlx::Error) -> bool {
    matches!(sqlite_code(e), Some(5 | 6 | 8 | 10 | 13 | 14))
}

/// The text of a database error, led by what it means for the storage faults a user can fix
/// (SQLite primary result codes 5/6 busy or locked, 8 read-only, 10 I/O error, 13 full, 14
/// cannot open). A failed statement's transaction is rolled back, so what was committed before
/// stays.
fn explain(e: &sqlx::Error) -> String {
    let text = e.to_string();
    let hint = match sqlite_code(e) {
        Some(5 | 6) => format!(
            "the database is locked by another program for longer than the busy timeout ({} s; \
             {BUSY_TIMEOUT_VAR} sets it in seconds): stop that program or wait, then run the \
             command again",
            busy_timeout().as_secs_f64()
        ),
        Some(8) => "the database is read-only (the file, its folder or its filesystem): nothing \
                    was written; make it writable, or work on a copy"
            .to_string(),
        Some(10) => "an I/O error on the database file (a full or failing disk, or a filesystem \
                     that went away): the last transaction was rolled back"
            .to_string(),
        Some(13) => "the disk holding the database is full: the last transaction was rolled \
                     back, results committed before are kept; free space, then `sweep resume` \
                     continues"
            .to_string(),
        Some(14) => "cannot open the database for writing (a read-only folder or filesystem, or \
                     its -wal and -shm files cannot be created beside it): nothing was written"
            .to_string(),
        _ => return text,
    };
    format!("{hint} ({text})")
}

/// A database error of the file at `path`, explained ([`explain`]).
fn db_error(path: &Path, e: &sqlx::Error) -> StoreError {
    StoreError::Db {
        path: path.display().to_string(),
        detail: explain(e),
    }
}

/// Seconds since the Unix epoch.
pub fn now() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

impl Store {
    /// The database file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A database error in the store's words: a malformed page or header met while reading is
    /// damage (read-only opens run no integrity check: docs/reliability.md, "Reading an
    /// archive"); anything else is explained ([`explain`]).
    fn db(&self, e: sqlx::Error) -> StoreError {
        if matches!(sqlite_code(&e), Some(11 | 26)) {
            return self.damaged(e.to_string());
        }
        db_error(&self.path, &e)
    }

    /// A damaged-file error naming this store's file.
    fn damaged(&self, detail: String) -> StoreError {
        StoreError::Damaged {
            path: self.path.display().to_string(),
            detail,
        }
    }

    /// Runs one statement (or a read of rows) on the pool and waits for it.
    fn run<T>(
        &self,
        statement: impl std::future::Future<Output = Result<T, sqlx::Error>>,
    ) -> Result<T, StoreError> {
        self.rt.block_on(statement).map_err(|e| self.db(e))
    }

    /// Opens a write transaction (`BEGIN IMMEDIATE`: the write lock is taken at once, so two
    /// processes cannot both read a job as free and then both write it).
    async fn begin(&self) -> Result<sqlx::Transaction<'_, sqlx::Sqlite>, StoreError> {
        self.pool
            .begin_with(queries::BEGIN_IMMEDIATE)
            .await
            .map_err(|e| self.db(e))
    }

    /// Runs `body` in one write transaction ([`Store::begin`]) and commits it; an error rolls it
    /// back (the transaction is dropped uncommitted).
    fn in_transaction<T>(
        &self,
        body: impl AsyncFnOnce(&mut sqlx::Transaction<'_, sqlx::Sqlite>) -> Result<T, StoreError>,
    ) -> Result<T, StoreError> {
        self.rt.block_on(async {
            let mut tx = self.begin().await?;
            let out = body(&mut tx).await?;
            tx.commit().await.map_err(|e| self.db(e))?;
            Ok(out)
        })
    }
}

/// One statement run inside an open transaction, its error in the store's words
/// ([`Store::db`]); returns how many rows it changed.
trait Exec {
    async fn exec(
        self,
        tx: &mut sqlx::Transaction<'_, sqlx::Sqlite>,
        store: &Store,
    ) -> Result<u64, StoreError>;
}

impl Exec for sqlx::query::Query<'_, sqlx::Sqlite, sqlx::sqlite::SqliteArguments> {
    async fn exec(
        self,
        tx: &mut sqlx::Transaction<'_, sqlx::Sqlite>,
        store: &Store,
    ) -> Result<u64, StoreError> {
        let done = self.execute(&mut **tx).await.map_err(|e| store.db(e))?;
        Ok(done.rows_affected())
    }
}

impl Drop for Store {
    /// Closes the connection cleanly, so that SQLite checkpoints the WAL into the main file.
    fn drop(&mut self) {
        self.rt.block_on(self.pool.close());
    }
}

/// A database with one registered sweep of three (never simulated) jobs.
#[cfg(test)]
fn store_with_jobs(dir: &Path) -> (PathBuf, i64) {
    let text = "[sweep]\nname = \"s\"\n[scene]\ndimension = 2\n[scene.box]\nsize = [8.0, 4.0]\n\
                [scene.particles]\ncount = 4\n[scene.initial]\ntemperature = 1.0\n\
                [scene.run]\nduration = 1.0\n[[axis]]\nkey = \"initial.seed\"\nvalues = [1, 2, 3]\n";
    let file = crate::sweep::file::SweepFile::parse(text, &dir.join("s.toml")).unwrap();
    let jobs = file.expand().unwrap();
    let db = dir.join("w.sqlite");
    let store = Store::open(&db).unwrap();
    let id = store.register_sweep(&file, &jobs).unwrap().id;
    (db, id)
}
