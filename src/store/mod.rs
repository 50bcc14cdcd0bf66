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
//! SQL: every statement is a file of `sql/` (one statement each, named after what it does, its
//! bind order in a comment at its top), embedded as a constant of `queries.rs` with
//! `include_str!`; the code here only binds and reads rows. The statements are not checked at
//! compile time (no `DATABASE_URL` or offline data in the build); the tests of `queries.rs`
//! prepare each one against a freshly migrated database. A schema change is a new migration in
//! `migrations/`.

#[cfg(test)]
mod claim_queue_tests;
mod cluster;
pub mod hysteresis;
mod queries;
#[cfg(test)]
mod query_plans;
mod read_only;
mod relabel_queue;
mod stale;
mod summary;

pub use cluster::{TaskRow, TaskState};
pub use read_only::{ReadAccess, read_access};
pub use relabel_queue::PointSpec;
pub use stale::{RunningJob, Stale};
pub use summary::{PointSummary, axis_keeps_report_scene, unconverged_summaries};

use crate::sweep::file::{Axis, SweepFile};
use crate::sweep::job::JobResult;
use crate::sweep::spec::{JobSpec, SweepJob};
use sqlx::sqlite::{SqliteConnectOptions, SqlitePool, SqlitePoolOptions, SqliteSynchronous};
use sqlx::{Row, SqliteConnection};
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
    /// Written by an older wetgran and not writable here, so it cannot be upgraded.
    Outdated { path: String, detail: String },
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
                "{path}: written by an older wetgran ({detail}) and read-only here, so it cannot \
                 be upgraded: run any wetgran command on it once where it can be written, or \
                 work on a writable copy"
            ),
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
}

/// What one finished job cost (`Store::finished_job_costs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FinishedCost {
    /// The simulated time its run ended at.
    pub simulated_time: f64,
    /// Wall seconds of the attempt that finished, plus any extensions.
    pub wall_seconds: f64,
    /// Its convergence verdict; `None` for a run without a run-length policy.
    pub converged: Option<bool>,
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
    /// How far the result's label can be trusted (`observe::trend::trust`): stationary (also
    /// where the result carries no verdict, or there is no result yet), a trend that keeps the
    /// label, or a label that may still change.
    pub fn trust(&self) -> wetgran_core::observe::trend::Trust {
        let converged = self
            .observables
            .as_ref()
            .and_then(wetgran_core::observe::converged_in_json);
        let phase = self.phase.as_deref().and_then(|p| p.parse().ok());
        wetgran_core::observe::trend::trust(self.trend, converged, phase)
    }

    /// Whether the result may carry a phase boundary: stationary, or a trend that cannot change
    /// its label (a heating gas, a cooling solid, a coarsening coexistence).
    pub fn trusted(&self) -> bool {
        self.trust().label_trusted()
    }
}

/// Results that did not reach a stationary window ([`wetgran_core::observe::Observables::converged`]),
/// and the number of results that carry a verdict at all: `(unconverged, with a verdict)`.
pub fn unconverged_count(points: &[PointRow]) -> (u64, u64) {
    let verdicts = points
        .iter()
        .filter_map(|p| p.observables.as_ref())
        .filter_map(wetgran_core::observe::converged_in_json);
    verdicts.fold((0, 0), |(u, n), ok| (u + u64::from(!ok), n + 1))
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

/// Seconds since the Unix epoch.
pub fn now() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty() && !s.contains(':'))
        .unwrap_or_else(|| "localhost".to_string())
}

/// A new owner name `host:pid:nonce` (the nonce tells apart two stores of one process).
fn new_owner() -> String {
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
fn owner_is_dead(owner: &str) -> bool {
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

/// What is at a path before it is opened.
enum Existing {
    New,
    Ours,
    OtherSqlite,
}

fn inspect(path: &Path) -> Result<Existing, StoreError> {
    let p = path.display().to_string();
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
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Existing::New),
        Err(e) => {
            return Err(StoreError::Db {
                path: p,
                detail: format!("cannot read the file: {e}"),
            });
        }
    };
    if bytes.is_empty() {
        return Ok(Existing::New);
    }
    if bytes.len() < 100 || &bytes[..16] != b"SQLite format 3\0" {
        let detail = if bytes.len() < 100 {
            format!("{} bytes, shorter than an SQLite header", bytes.len())
        } else {
            "no SQLite header".to_string()
        };
        return Err(StoreError::NotSqlite { path: p, detail });
    }
    let app_id = i32::from_be_bytes([bytes[68], bytes[69], bytes[70], bytes[71]]);
    if app_id == APPLICATION_ID {
        Ok(Existing::Ours)
    } else if app_id != 0 {
        Err(StoreError::NotWetgran {
            path: p,
            detail: format!("application id {app_id:#x}"),
        })
    } else {
        Ok(Existing::OtherSqlite)
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
        let p = path.display().to_string();
        let existing = inspect(path)?;
        if matches!(existing, Existing::New) && !create {
            return Err(StoreError::Missing { path: p });
        }
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .map_err(|e| StoreError::Db {
                path: p.clone(),
                detail: format!("cannot start the async runtime: {e}"),
            })?;
        let db = |e: sqlx::Error| StoreError::Db {
            path: p.clone(),
            detail: explain(&e),
        };
        let busy = busy_timeout();
        let opts = SqliteConnectOptions::new()
            .filename(path)
            .create_if_missing(true)
            .busy_timeout(busy)
            .foreign_keys(true)
            .synchronous(match durability {
                Durability::Synced => SqliteSynchronous::Full,
                Durability::Fast => SqliteSynchronous::Normal,
            })
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
            .map_err(db)?;
        let store = Store {
            rt,
            pool,
            path: path.to_path_buf(),
            owner: new_owner(),
        };
        store.prepare(existing)?;
        store.rekey_jobs()?;
        Ok(store)
    }

    /// Checks (read-only) what is in the file, then initialises and migrates it.
    fn prepare(&self, existing: Existing) -> Result<(), StoreError> {
        let p = self.path.display().to_string();
        // A file that cannot be read or written is not a damaged one.
        let damaged = |e: sqlx::Error| {
            if is_storage_fault(&e) {
                StoreError::Db {
                    path: p.clone(),
                    detail: explain(&e),
                }
            } else {
                StoreError::Damaged {
                    path: p.clone(),
                    detail: e.to_string(),
                }
            }
        };
        self.rt.block_on(async {
            let mut conn = self.pool.acquire().await.map_err(|e| StoreError::Db {
                path: p.clone(),
                detail: explain(&e),
            })?;
            let conn: &mut SqliteConnection = &mut conn;
            match existing {
                Existing::OtherSqlite => {
                    let tables: Vec<String> = sqlx::query_scalar(queries::LIST_TABLES)
                        .fetch_all(&mut *conn)
                        .await
                        .map_err(damaged)?;
                    if !tables.is_empty() {
                        return Err(StoreError::NotWetgran {
                            path: p.clone(),
                            detail: format!("tables {}", tables.join(", ")),
                        });
                    }
                }
                Existing::Ours => {
                    let check: Vec<String> = sqlx::query_scalar(queries::QUICK_CHECK)
                        .fetch_all(&mut *conn)
                        .await
                        .map_err(damaged)?;
                    if check.first().map(String::as_str) != Some("ok") {
                        return Err(StoreError::Damaged {
                            path: p.clone(),
                            detail: format!("integrity check: {}", check.join("; ")),
                        });
                    }
                }
                Existing::New => {}
            }
            let db = |e: sqlx::Error| StoreError::Db {
                path: p.clone(),
                detail: explain(&e),
            };
            if !matches!(existing, Existing::Ours) {
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
            if !mode.eq_ignore_ascii_case("wal") {
                return Err(StoreError::Db {
                    path: p.clone(),
                    detail: format!("cannot switch to WAL mode (journal mode is {mode})"),
                });
            }
            MIGRATOR.run(&mut *conn).await.map_err(|e| StoreError::Db {
                path: p.clone(),
                detail: match e {
                    sqlx::migrate::MigrateError::Execute(e)
                    | sqlx::migrate::MigrateError::ExecuteMigration(e, _) => {
                        format!("applying the migrations: {}", explain(&e))
                    }
                    e => format!("applying the migrations: {e}"),
                },
            })?;
            Ok(())
        })
    }

    /// Compatibility rule for databases written before job ids left out the `[classify]`
    /// thresholds (docs/model-choices.md, "Job identity"): once per database (meta key
    /// `job_ids` = [`JOB_ID_RULE`]), every job is re-keyed to the id its stored spec has now,
    /// in one transaction. Jobs that differed only in their thresholds become one: its point
    /// rows, runs and cluster tasks follow it; a result is kept (the first one found where the
    /// merged job has none, dropped otherwise: the trajectory is the same).
    fn rekey_jobs(&self) -> Result<(), StoreError> {
        let rule: Option<String> = self
            .rt
            .block_on(sqlx::query_scalar(queries::JOB_ID_RULE).fetch_optional(&self.pool))
            .map_err(|e| self.db(e))?;
        if rule.as_deref() == Some(JOB_ID_RULE) {
            return Ok(());
        }
        let path = self.path.display().to_string();
        self.in_transaction(async |tx| {
            let jobs: Vec<(String, String)> = sqlx::query_as(queries::ALL_JOB_SPECS)
                .fetch_all(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            for (old, text) in jobs {
                let spec = JobSpec::from_json(&text, &format!("job {old}")).map_err(|e| {
                    StoreError::Damaged {
                        path: path.clone(),
                        detail: format!("a job spec is not readable: {e}"),
                    }
                })?;
                let new = spec.id();
                if new == old {
                    continue;
                }
                let exists: Option<String> = sqlx::query_scalar(queries::JOB_EXISTS)
                    .bind(&new)
                    .fetch_optional(&mut **tx)
                    .await
                    .map_err(|e| self.db(e))?;
                if exists.is_none() {
                    sqlx::query(queries::COPY_JOB_TO_NEW_ID)
                        .bind(&old)
                        .bind(&new)
                        .execute(&mut **tx)
                        .await
                        .map_err(|e| self.db(e))?;
                } else {
                    // Merging: the merged job takes this one's result if it has none.
                    let moved = sqlx::query(queries::MOVE_RESULT_IF_NONE)
                        .bind(&old)
                        .bind(&new)
                        .execute(&mut **tx)
                        .await
                        .map_err(|e| self.db(e))?;
                    if moved.rows_affected() > 0 {
                        sqlx::query(queries::MARK_MERGED_JOB_DONE)
                            .bind(&old)
                            .bind(&new)
                            .execute(&mut **tx)
                            .await
                            .map_err(|e| self.db(e))?;
                    }
                    sqlx::query(queries::DELETE_RESULT)
                        .bind(&old)
                        .execute(&mut **tx)
                        .await
                        .map_err(|e| self.db(e))?;
                }
                for sql in [
                    queries::REKEY_SWEEP_POINTS,
                    queries::REKEY_RUNS,
                    queries::REKEY_SUBMISSION_TASKS,
                    queries::REKEY_RESULTS,
                ] {
                    sqlx::query(sql)
                        .bind(&old)
                        .bind(&new)
                        .execute(&mut **tx)
                        .await
                        .map_err(|e| self.db(e))?;
                }
                // A merged job may have taken another's result: its lines are relabelled.
                self.mark_relabel_job(tx, &new).await?;
                sqlx::query(queries::DELETE_JOB)
                    .bind(&old)
                    .execute(&mut **tx)
                    .await
                    .map_err(|e| self.db(e))?;
            }
            sqlx::query(queries::SET_JOB_ID_RULE)
                .bind(JOB_ID_RULE)
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            Ok(())
        })
    }

    /// Sets the phase label and the numbers it was decided on of stored results, in one
    /// transaction (`wetgran reclassify`): `(job id, phase, decided_on)`.
    pub fn relabel(
        &self,
        labels: &[(String, String, serde_json::Value)],
    ) -> Result<(), StoreError> {
        self.in_transaction(async |tx| self.write_labels(tx, labels).await)
    }

    /// Sets the phase label and decision numbers of stored results inside an open transaction.
    async fn write_labels(
        &self,
        tx: &mut sqlx::Transaction<'_, sqlx::Sqlite>,
        labels: &[(String, String, serde_json::Value)],
    ) -> Result<(), StoreError> {
        for (job, phase, decided_on) in labels {
            sqlx::query(queries::SET_RESULT_LABEL)
                .bind(job)
                .bind(phase)
                .bind(decided_on.to_string())
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
        }
        Ok(())
    }

    /// SQLite's full integrity check (`PRAGMA integrity_check`): `["ok"]` for a sound file, else
    /// the problems it found.
    pub fn integrity_check(&self) -> Result<Vec<String>, StoreError> {
        self.rt
            .block_on(sqlx::query_scalar(queries::INTEGRITY_CHECK).fetch_all(&self.pool))
            .map_err(|e| self.db(e))
    }

    /// Number of rows in the `runs` table: simulations started, ever, in this database.
    pub fn runs_started(&self) -> Result<i64, StoreError> {
        self.rt
            .block_on(sqlx::query_scalar(queries::COUNT_RUNS).fetch_one(&self.pool))
            .map_err(|e| self.db(e))
    }

    /// The database file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// This runner's owner name (`host:pid:nonce`).
    pub fn owner(&self) -> &str {
        &self.owner
    }

    fn db(&self, e: sqlx::Error) -> StoreError {
        // A malformed page or header met while reading (read-only opens run no integrity
        // check: docs/reliability.md, "Reading an archive").
        if matches!(sqlite_code(&e), Some(11 | 26)) {
            return StoreError::Damaged {
                path: self.path.display().to_string(),
                detail: e.to_string(),
            };
        }
        StoreError::Db {
            path: self.path.display().to_string(),
            detail: explain(&e),
        }
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

    /// Inserts a job's result row, inside an open transaction (the job row is the caller's).
    async fn insert_result(
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
            .bind(wetgran_core::observe::converged_in_json(&result.observables).map(i64::from))
            .execute(&mut **tx)
            .await
            .map_err(|e| self.db(e))?;
        // The sweeps holding the job relabel its lines after the run (`run::relabel`).
        self.mark_relabel_job(tx, job_id).await?;
        if let Some(state) = &result.checkpoint {
            sqlx::query(queries::UPSERT_CHECKPOINT)
                .bind(job_id)
                .bind(state.time)
                .bind(serde_json::to_string(state).expect("a state serializes"))
                .bind(finished_at)
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
        }
        wetgran_core::test_pause::pause_at("checkpoint");
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
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            wetgran_core::test_pause::pause_at("extend");
            self.insert_result(tx, job_id, result, &owner, t).await?;
            sqlx::query(queries::EXTEND_JOB_TIMES)
                .bind(job_id)
                .bind(t)
                .bind(result.wall_seconds)
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            Ok(())
        })
    }

    /// The spec of a job, if the database has it.
    pub fn job_spec(&self, job_id: &str) -> Result<Option<JobSpec>, StoreError> {
        let row: Option<(String,)> = self
            .rt
            .block_on(
                sqlx::query_as(queries::JOB_SPEC)
                    .bind(job_id)
                    .fetch_optional(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        row.map(|(s,)| {
            JobSpec::from_json(&s, &format!("job {job_id}")).map_err(|e| StoreError::Damaged {
                path: self.path.display().to_string(),
                detail: format!("the spec of job {job_id} is not readable: {e}"),
            })
        })
        .transpose()
    }

    /// The checkpoint (final state) of a finished job, if one was stored.
    pub fn checkpoint(
        &self,
        job_id: &str,
    ) -> Result<Option<wetgran_core::sim::EngineState>, StoreError> {
        let row: Option<(String,)> = self
            .rt
            .block_on(
                sqlx::query_as(queries::CHECKPOINT_STATE)
                    .bind(job_id)
                    .fetch_optional(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        row.map(|(s,)| {
            serde_json::from_str(&s).map_err(|e| StoreError::Damaged {
                path: self.path.display().to_string(),
                detail: format!("the checkpoint of job {job_id} is not readable: {e}"),
            })
        })
        .transpose()
    }

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
        let axes = serde_json::to_string(&file.axes).expect("axes serialize");
        let t = now();
        self.in_transaction(async |tx| {
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
                .bind(&axes)
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
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            self.insert_points(tx, id, jobs, t).await?;
            Ok(())
        })?;
        self.sweep(&file.name)
    }

    /// Records the grid points `skip_invalid` left out of a registered sweep (replacing what
    /// was recorded before).
    pub fn set_left_out(&self, sweep_id: i64, left_out: &[LeftOut]) -> Result<(), StoreError> {
        let text = serde_json::to_string(left_out).expect("left-out points serialize");
        self.rt
            .block_on(
                sqlx::query(queries::SET_LEFT_OUT)
                    .bind(sweep_id)
                    .bind(text)
                    .execute(&self.pool),
            )
            .map_err(|e| self.db(e))?;
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
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            sqlx::query(queries::INSERT_SWEEP_POINT)
                .bind(sweep_id)
                .bind(job.point as i64)
                .bind(job.replica as i64)
                .bind(serde_json::to_string(&job.coords).expect("coords serialize"))
                .bind(&job.id)
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            self.mark_relabel_point(tx, sweep_id, &job.id).await?;
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
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            wetgran_core::test_pause::pause_at("refine");
            Ok(())
        })
    }

    /// The text of a sweep's file as last registered.
    pub fn sweep_source(&self, sweep_id: i64) -> Result<String, StoreError> {
        self.rt
            .block_on(
                sqlx::query_scalar(queries::SWEEP_SOURCE)
                    .bind(sweep_id)
                    .fetch_one(&self.pool),
            )
            .map_err(|e| self.db(e))
    }

    /// All sweeps, oldest first.
    pub fn sweeps(&self) -> Result<Vec<SweepRow>, StoreError> {
        let rows = self
            .rt
            .block_on(sqlx::query(queries::LIST_SWEEPS).fetch_all(&self.pool))
            .map_err(|e| self.db(e))?;
        rows.iter()
            .map(|r| {
                let axes: String = r.get("axes");
                Ok(SweepRow {
                    id: r.get("id"),
                    name: r.get("name"),
                    file: r.get("file"),
                    description: r.get("description"),
                    cost: r.get("cost"),
                    axes: serde_json::from_str(&axes).map_err(|e| StoreError::Damaged {
                        path: self.path.display().to_string(),
                        detail: format!("axes of a sweep are not readable: {e}"),
                    })?,
                    replicas: r.get::<i64, _>("replicas") as u32,
                    created_at: r.get("created_at"),
                    updated_at: r.get("updated_at"),
                    left_out: match r.get::<Option<String>, _>("left_out") {
                        None => Vec::new(),
                        Some(t) => serde_json::from_str(&t).map_err(|e| StoreError::Damaged {
                            path: self.path.display().to_string(),
                            detail: format!("left-out points of a sweep are not readable: {e}"),
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
                    .execute(&mut *tx)
                    .await
                    .map_err(|e| self.db(e))?
                    .rows_affected();
                if n == 1 {
                    sqlx::query(queries::MARK_RUNS_ORPHANED)
                        .bind(&id)
                        .bind(&owner)
                        .bind(now())
                        .execute(&mut *tx)
                        .await
                        .map_err(|e| self.db(e))?;
                    requeued.push(id);
                }
                tx.commit().await.map_err(|e| self.db(e))?;
            }
            Ok(requeued)
        })
    }

    /// Re-queues the failed jobs of the given sweeps; returns how many.
    pub fn retry_failed(&self, sweep_ids: &[i64]) -> Result<u64, StoreError> {
        let mut total = 0;
        for &sid in sweep_ids {
            total += self
                .rt
                .block_on(
                    sqlx::query(queries::RETRY_FAILED_JOBS)
                        .bind(sid)
                        .execute(&self.pool),
                )
                .map_err(|e| self.db(e))?
                .rows_affected();
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
        let damaged = |what: &str, e: String| StoreError::Damaged {
            path: self.path.display().to_string(),
            detail: format!("{what} of job {job_id} is not readable: {e}"),
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
        self.rt
            .block_on(
                sqlx::query(queries::HEARTBEAT)
                    .bind(now())
                    .bind(&self.owner)
                    .execute(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(())
    }

    /// Commits a finished job: job row, result row and run row in one transaction. Returns
    /// `false` (and stores nothing but the run's outcome) when the job already has a result.
    pub fn finish(&self, claim: &Claim, result: &JobResult) -> Result<bool, StoreError> {
        let t = now();
        self.in_transaction(async |tx| {
            let n = sqlx::query(queries::FINISH_JOB)
                .bind(&claim.job_id)
                .bind(&self.owner)
                .bind(t)
                .bind(result.wall_seconds)
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?
                .rows_affected();
            let kept = n == 1;
            if kept {
                self.insert_result(tx, &claim.job_id, result, &self.owner, t)
                    .await?;
            }
            self.end_run(tx, claim.run_id, t, if kept { "done" } else { "discarded" })
                .await?;
            Ok(kept)
        })
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
            .execute(&mut **tx)
            .await
            .map_err(|e| self.db(e))?;
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
                .execute(&mut **tx)
                .await
                .map_err(|e| self.db(e))?;
            self.end_run(tx, claim.run_id, t, "failed").await?;
            Ok(())
        })
    }

    /// Jobs of a sweep by state.
    pub fn counts(&self, sweep_id: i64) -> Result<StateCounts, StoreError> {
        let rows: Vec<(String, i64)> = self
            .rt
            .block_on(
                sqlx::query_as(queries::COUNT_BY_STATUS)
                    .bind(sweep_id)
                    .fetch_all(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        let mut c = StateCounts::default();
        for (status, n) in rows {
            let n = n as u64;
            match status.as_str() {
                "pending" => c.pending = n,
                "running" => c.running = n,
                "done" => c.done = n,
                _ => c.failed = n,
            }
        }
        Ok(c)
    }

    /// Runs one statement on the store's connection (tests that write rows as older versions
    /// did).
    #[cfg(test)]
    pub(crate) fn execute_for_tests(&self, sql: &'static str) {
        self.rt
            .block_on(sqlx::query(sql).execute(&self.pool))
            .unwrap();
    }

    /// Every job of a sweep (grid order), with its result where there is one.
    pub fn points(&self, sweep_id: i64) -> Result<Vec<PointRow>, StoreError> {
        let rows = self
            .rt
            .block_on(
                sqlx::query(queries::SWEEP_POINTS)
                    .bind(sweep_id)
                    .fetch_all(&self.pool),
            )
            .map_err(|e| self.db(e))?;
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

    /// A row of `sweep_points.sql` (or of a page of it) as a [`PointRow`].
    fn point_row(&self, r: &sqlx::sqlite::SqliteRow) -> Result<PointRow, StoreError> {
        let path = self.path.display().to_string();
        let damaged = |what: &str, e: String| StoreError::Damaged {
            path: path.clone(),
            detail: format!("{what} is not readable: {e}"),
        };
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
        self.rt
            .block_on(sqlx::query_as(queries::RUNS_PER_JOB).fetch_all(&self.pool))
            .map_err(|e| self.db(e))
    }

    /// What every finished job in the database cost, by job id (any sweep): the simulated time
    /// its run ended at, its wall seconds (with extensions) and its convergence verdict.
    pub fn finished_job_costs(
        &self,
    ) -> Result<std::collections::HashMap<String, FinishedCost>, StoreError> {
        let rows: Vec<(String, f64, f64, Option<i64>)> = self
            .rt
            .block_on(sqlx::query_as(queries::FINISHED_JOB_COSTS).fetch_all(&self.pool))
            .map_err(|e| self.db(e))?;
        Ok(rows
            .into_iter()
            .map(|(id, simulated_time, wall_seconds, converged)| {
                let cost = FinishedCost {
                    simulated_time,
                    wall_seconds,
                    converged: converged.map(|c| c != 0),
                };
                (id, cost)
            })
            .collect())
    }

    /// Total wall time of the finished and failed attempts of a sweep's jobs, in seconds.
    pub fn time_spent(&self, sweep_id: i64) -> Result<f64, StoreError> {
        let t: Option<f64> = self
            .rt
            .block_on(
                sqlx::query_scalar(queries::TIME_SPENT)
                    .bind(sweep_id)
                    .fetch_one(&self.pool),
            )
            .map_err(|e| self.db(e))?;
        Ok(t.unwrap_or(0.0))
    }
}

impl Drop for Store {
    /// Closes the connection cleanly, so that SQLite checkpoints the WAL into the main file.
    fn drop(&mut self) {
        self.rt.block_on(self.pool.close());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// A database with one registered sweep of three (never simulated) jobs.
    fn store_with_jobs(dir: &Path) -> (PathBuf, i64) {
        let text = "[sweep]\nname = \"s\"\n[scene]\ndimension = 2\n[scene.box]\nsize = [8.0, 4.0]\n\
                    [scene.particles]\ncount = 4\n[scene.initial]\ntemperature = 1.0\n\
                    [scene.run]\nduration = 1.0\n[[axis]]\nkey = \"initial.seed\"\nvalues = [1, 2, 3]\n";
        let file = SweepFile::parse(text, &dir.join("s.toml")).unwrap();
        let jobs = file.expand().unwrap();
        let db = dir.join("w.sqlite");
        let store = Store::open(&db).unwrap();
        let id = store.register_sweep(&file, &jobs).unwrap().id;
        (db, id)
    }

    /// Runs raw SQL on the store's single connection.
    fn exec(store: &Store, sql: &'static str, binds: &[&str]) {
        let mut q = sqlx::query(sql);
        for b in binds {
            q = q.bind(*b);
        }
        store.rt.block_on(q.execute(&store.pool)).unwrap();
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
        exec(&store, "PRAGMA foreign_keys = OFF", &[]);
        for p in store.points(sweep_id).unwrap() {
            let old = crate::sweep::spec::id_of_canonical(&p.spec.canonical_json());
            assert_ne!(old, p.job_id);
            for sql in [
                "UPDATE jobs SET id = ?2 WHERE id = ?1",
                "UPDATE sweep_points SET job_id = ?2 WHERE job_id = ?1",
                "UPDATE results SET job_id = ?2 WHERE job_id = ?1",
                "UPDATE runs SET job_id = ?2 WHERE job_id = ?1",
            ] {
                exec(&store, sql, &[&p.job_id, &old]);
            }
        }
        let mut twin = claim.spec.clone();
        twin.scene.classify.gas_temperature *= 2.0;
        let twin_old = crate::sweep::spec::id_of_canonical(&twin.canonical_json());
        exec(
            &store,
            "INSERT INTO jobs (id, spec, created_at) VALUES (?1, ?2, 0)",
            &[&twin_old, &twin.canonical_json()],
        );
        exec(
            &store,
            "INSERT INTO sweep_points (sweep_id, point, replica, coords, job_id) \
             VALUES (1, 99, 0, '[9]', ?1)",
            &[&twin_old],
        );
        exec(&store, "DELETE FROM meta WHERE key = 'job_ids'", &[]);
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

    #[test]
    fn owner_names_parse_and_a_live_owner_is_not_dead() {
        let o = new_owner();
        assert_eq!(o.split(':').count(), 3);
        assert!(!owner_is_dead(&o), "this process is alive");
        assert!(
            !owner_is_dead("other-host:1:abc"),
            "another host is never judged"
        );
    }
}
