//! Read-only opens, for the commands that only read (`sweep status`, `show`, `boundaries`,
//! `plot`, `export`, `inflection`, `sweep estimate --db`, `sweep submit --dry-run`): the
//! database is opened with `SQLITE_OPEN_READONLY`, nothing is created, initialised, migrated or
//! re-keyed, and no integrity check runs (docs/reliability.md, "Reading an archive").
//!
//! How the file is reached ([`ReadAccess`]):
//! - **shared** (`mode=ro`): SQLite's locks and the write-ahead log as any reader; another
//!   process may run `sweep run` on the database meanwhile. SQLite then needs the `-wal` and
//!   `-shm` files beside the database, and creates them (empty) where they are missing and the
//!   folder can be written.
//! - **immutable** (`immutable=1`): no locks and no `-wal`/`-shm`, for a database that cannot
//!   change while it is read: its file or its folder is marked read-only (no write permission
//!   bit for anyone), and the log beside it holds no commits (is missing or empty). A writer in
//!   WAL mode must write the database or create the `-wal` file in that folder before it
//!   changes anything, so no writer can exist during the read (root aside, who ignores the
//!   bits), and the main file holds every committed transaction. Also where a shared open fails
//!   because SQLite cannot create the `-wal`/`-shm` files (a folder this user cannot write, with
//!   write bits for another): no writer of this user can exist either.
//!
//! A read-only open never changes the database: one written by an older wetgran (migrations or
//! the job-id rule not applied) is refused with [`StoreError::Outdated`], which names
//! `wetgran upgrade` ([`Store::upgrade`]); one written by a newer wetgran with
//! [`StoreError::Newer`]; the main file of a database copied without its `-wal` file while a
//! run was writing it (wetgran's header, no table, no log) with [`StoreError::NoContent`].

use super::open::{Existing, applied_migrations, inspect, log_missing};
use super::{MIGRATOR, Store, StoreError, explain, queries, sqlite_code};
use sqlx::sqlite::SqliteConnectOptions;
use std::path::{Path, PathBuf};

/// How a read-only open reaches the file (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReadAccess {
    Shared,
    Immutable,
}

/// The file beside a database named with `suffix` (`-wal`: its write-ahead log, `-shm`: the
/// log's index).
fn beside(path: &Path, suffix: &str) -> PathBuf {
    crate::output::with_suffix(path, suffix)
}

/// Whether no write permission bit is set on `path` (an archive marked read-only, also for
/// root).
fn marked_read_only(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.permissions().readonly())
}

/// How the database at `path` is read (module doc).
pub fn read_access(path: &Path) -> ReadAccess {
    let log_has_commits = std::fs::metadata(beside(path, "-wal")).is_ok_and(|m| m.len() > 0);
    if log_has_commits {
        return ReadAccess::Shared;
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if marked_read_only(path) || marked_read_only(&dir) {
        ReadAccess::Immutable
    } else {
        ReadAccess::Shared
    }
}

impl Store {
    /// Opens an existing database for reading only (module doc); a database from an older
    /// wetgran is refused, never upgraded.
    pub fn open_read_only(path: &Path) -> Result<Store, StoreError> {
        let (store, outdated) = Self::open_viewer(path)?;
        match outdated {
            None => Ok(store),
            Some(detail) => Err(StoreError::Outdated {
                path: path.display().to_string(),
                detail,
            }),
        }
    }

    /// Upgrades a database written by an older wetgran in place (`wetgran upgrade`): the
    /// migrations and the job-id rule, as any writer's open applies them. Returns what was
    /// upgraded (`None`: it was up to date, nothing was written).
    pub fn upgrade(path: &Path) -> Result<Option<String>, StoreError> {
        let (store, outdated) = Self::open_viewer(path)?;
        drop(store);
        let Some(detail) = outdated else {
            return Ok(None);
        };
        drop(Self::open_existing(path)?);
        Ok(Some(detail))
    }

    /// Refuses, without creating anything beside it, a database whose main file is all of it
    /// (no log with commits beside it) and whose schema page is damaged, that a newer wetgran
    /// wrote, or that is the main file alone of a copied database ([`StoreError::NoContent`]):
    /// an immutable open (no `-wal`, no `-shm`) sees exactly what a shared one would. Where the
    /// log holds commits the main file is not the whole database, and the open itself checks.
    pub(super) fn probe(path: &Path) -> Result<(), StoreError> {
        if !log_missing(path) {
            return Ok(());
        }
        let store = Self::open_reader(path, ReadAccess::Immutable)?;
        store.outdated()?;
        Ok(())
    }

    /// The read-only store and what an older wetgran left undone in it.
    fn open_viewer(path: &Path) -> Result<(Store, Option<String>), StoreError> {
        Self::probe(path)?;
        let access = read_access(path);
        let store = match Self::open_reader(path, access) {
            Err(StoreError::Db { .. })
                if access == ReadAccess::Shared && cannot_create_beside(path) =>
            {
                Self::open_reader(path, ReadAccess::Immutable)?
            }
            other => other?,
        };
        let outdated = store.outdated()?;
        Ok((store, outdated))
    }

    /// The read-only connection itself; checks what the file holds (header, tables) first.
    fn open_reader(path: &Path, access: ReadAccess) -> Result<Store, StoreError> {
        let existing = inspect(path, false)?;
        let opts = SqliteConnectOptions::new()
            .read_only(true)
            .immutable(access == ReadAccess::Immutable);
        let store = Self::connect(path, opts, |e| read_open_error(path, e))?;
        // The first read: SQLite opens the log here, so a log it cannot open fails here.
        let tables: Vec<String> = store
            .rt
            .block_on(sqlx::query_scalar(queries::LIST_TABLES).fetch_all(&store.pool))
            .map_err(|e| match sqlite_code(&e) {
                Some(11 | 26) => store.db(e),
                _ => StoreError::Db {
                    path: path.display().to_string(),
                    detail: read_open_error(path, &e),
                },
            })?;
        match existing {
            Existing::OtherSqlite if tables.is_empty() => Err(StoreError::Missing {
                path: path.display().to_string(),
            }),
            Existing::OtherSqlite => Err(store.not_wetgran(&tables)),
            Existing::Ours { wal: true } if tables.is_empty() && log_missing(path) => {
                Err(StoreError::NoContent {
                    path: path.display().to_string(),
                })
            }
            _ => Ok(store),
        }
    }

    /// What an older wetgran left undone (migrations, the job-id rule), in words; `None` when
    /// the database is as this wetgran writes it. Migrations of a newer wetgran are an error.
    fn outdated(&self) -> Result<Option<String>, StoreError> {
        let applied = self
            .rt
            .block_on(async {
                let mut conn = self.pool.acquire().await?;
                applied_migrations(&mut conn).await
            })
            .map_err(|e| self.db(e))?;
        let known: Vec<i64> = MIGRATOR.iter().map(|m| m.version).collect();
        self.refuse_newer(&applied)?;
        let missing: Vec<String> = known
            .iter()
            .filter(|v| !applied.contains(v))
            .map(|v| v.to_string())
            .collect();
        if !missing.is_empty() {
            return Ok(Some(format!(
                "migrations {} not applied",
                missing.join(", ")
            )));
        }
        Ok((!self.job_ids_current()?).then(|| "its job ids follow an older rule".to_string()))
    }
}

impl Store {
    /// [`StoreError::Newer`] where `applied` holds a migration this wetgran does not know.
    pub(super) fn refuse_newer(&self, applied: &[i64]) -> Result<(), StoreError> {
        match applied
            .iter()
            .find(|v| !MIGRATOR.iter().any(|m| m.version == **v))
        {
            None => Ok(()),
            Some(v) => Err(StoreError::Newer {
                path: self.path.display().to_string(),
                detail: format!("its migration {v} is unknown to this one"),
            }),
        }
    }
}

/// Whether a shared open may have failed for want of the `-wal`/`-shm` files: neither is
/// there (SQLite would have created them where it could).
fn cannot_create_beside(path: &Path) -> bool {
    !beside(path, "-wal").exists() && !beside(path, "-shm").exists()
}

/// The text of a failed read-only open: a log with commits that SQLite cannot read without
/// the `-shm` file it cannot create is named as such.
fn read_open_error(path: &Path, e: &sqlx::Error) -> String {
    if sqlite_code(e) == Some(14) && beside(path, "-wal").exists() {
        return format!(
            "cannot read the database: its write-ahead log {} holds commits that SQLite reads \
             with the index file {}, which is missing and cannot be created here (a read-only \
             folder): open it once where the folder can be written, or copy the three files \
             ({e})",
            beside(path, "-wal").display(),
            beside(path, "-shm").display()
        );
    }
    explain(e)
}
