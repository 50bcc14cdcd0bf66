//! Every file a command writes goes through this module: the pictures (`plot`, `lines`,
//! snapshots and profiles of `show` and `simulate`), the tables (`lines --csv`, `export -o`,
//! `--series`, `--text`), the report folder (`report -o`, [`folder`]), the result records,
//! specs, task lists and batch scripts of the cluster commands. Two promises:
//!
//! - **An output never lands on what it must not.** [`Protected`] holds the database with its
//!   `-wal`, `-shm` and `-journal` files (and any input a command names); an output that
//!   resolves to one of them is refused before anything is written. Resolving follows symbolic
//!   links (the path is canonicalised) and compares the device and inode of every existing
//!   file, so a hard link or a symbolic link to the database is caught as well as the path
//!   itself. An existing file that begins with the SQLite header is refused too, whoever's
//!   database it is: wetgran's outputs are text and pictures, never databases. Two outputs of
//!   one command may not name the same file ([`Outputs`]).
//! - **An output is whole or absent.** A file is written to a temporary file in the folder of
//!   its target (`.NAME.wetgran-PID-N.tmp`), synced, and renamed over the target, so a reader,
//!   a crash or a full disk leaves the old file or the whole new one, never half of either; a
//!   failed write removes the temporary file. A replaced file keeps its permission bits. An
//!   output that is a symbolic link is followed: the file it points to is replaced. A target
//!   that is not a regular file and cannot be replaced by renaming (a character device such as
//!   `/dev/stdout` or `/dev/null`, a named pipe) is written in place; a folder is refused.
//!
//! A process killed in the middle (SIGKILL) may leave its temporary file beside the target;
//! the target itself is untouched.

pub mod folder;

use std::io::Write;
use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Why an output was not written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OutputError {
    /// The output was refused before anything was written (bad input: exit status 2).
    Refused(String),
    /// Writing failed (the message names the file); the old file is untouched.
    Io(String),
}

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OutputError::Refused(m) | OutputError::Io(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for OutputError {}

impl From<OutputError> for std::io::Error {
    fn from(e: OutputError) -> Self {
        std::io::Error::other(e.to_string())
    }
}

/// The first 16 bytes of every SQLite database file.
const SQLITE_MAGIC: &[u8; 16] = b"SQLite format 3\0";

/// The files beside a database that belong to it (SQLite's write-ahead log, its index and the
/// rollback journal).
pub const DATABASE_COMPANIONS: [&str; 3] = ["-wal", "-shm", "-journal"];

/// `path` with `suffix` appended to its file name (`w.sqlite` -> `w.sqlite-wal`).
pub fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(suffix);
    PathBuf::from(name)
}

/// A file an output must never be.
#[derive(Debug, Clone)]
struct Guarded {
    /// What it is, in words (`the database w.sqlite`).
    what: String,
    /// Where it is or would be, symbolic links resolved.
    resolved: Option<PathBuf>,
    /// Its device and inode, if it exists.
    id: Option<(u64, u64)>,
}

/// The files a command's outputs must never be (module doc).
#[derive(Debug, Clone, Default)]
pub struct Protected {
    guarded: Vec<Guarded>,
}

impl Protected {
    /// Nothing named (an existing SQLite file is still refused).
    pub fn none() -> Protected {
        Protected::default()
    }

    /// The database at `db` and its `-wal`, `-shm` and `-journal` files.
    pub fn database(db: &Path) -> Protected {
        let mut p = Protected::none();
        p.add(&format!("the database {}", db.display()), db);
        for suffix in DATABASE_COMPANIONS {
            let companion = with_suffix(db, suffix);
            p.add(
                &format!(
                    "{} (a file of the database {})",
                    companion.display(),
                    db.display()
                ),
                &companion,
            );
        }
        p
    }

    /// Also `path`, described as `what` (an input of the command: `the scene file`).
    pub fn and(mut self, what: &str, path: &Path) -> Protected {
        self.add(&format!("{what} {}", path.display()), path);
        self
    }

    fn add(&mut self, what: &str, path: &Path) {
        self.guarded.push(Guarded {
            what: what.to_string(),
            resolved: resolve(path).ok(),
            id: file_id(path),
        });
    }

    /// The protected file that `out` (resolved to `target`) would overwrite, if any.
    fn hit(&self, target: &Path) -> Option<&Guarded> {
        let id = file_id(target);
        self.guarded
            .iter()
            .find(|g| g.resolved.as_deref() == Some(target) || (id.is_some() && g.id == id))
    }

    /// Whether a protected file lies in the folder `dir` or below it (a report folder that
    /// would hold the database when it replaces that folder).
    fn inside(&self, dir: &Path) -> Option<&Guarded> {
        self.guarded
            .iter()
            .find(|g| g.resolved.as_deref().is_some_and(|r| r.starts_with(dir)))
    }
}

/// The device and inode of the file at `path` (symbolic links followed).
fn file_id(path: &Path) -> Option<(u64, u64)> {
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

/// Where writing `path` lands: the file itself with every symbolic link resolved, also for a
/// file that does not exist yet (its folder resolved, then its name; a dangling link leads to
/// the file it names).
pub fn resolve(path: &Path) -> std::io::Result<PathBuf> {
    let mut path = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&path) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&path)?;
                path = parent_of(&path).join(link);
            }
            Ok(_) => return std::fs::canonicalize(&path),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                let name = match path.components().next_back() {
                    Some(Component::Normal(n)) => n.to_owned(),
                    _ => return Err(std::io::Error::other("not a file name")),
                };
                return Ok(std::fs::canonicalize(parent_of(&path))?.join(name));
            }
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::other("too many levels of symbolic links"))
}

/// The file an output `path` lands in ([`resolve`]: symbolic links followed), or `None` where
/// it is written in place as a stream (a character device or a named pipe: `-o /dev/stdout` on
/// a terminal or a pipe) or cannot be resolved. `export` puts its sidecar file beside it.
pub fn file_target(path: &Path) -> Option<PathBuf> {
    // The kernel follows the path itself (a `/proc/self/fd` link to a pipe has no name to
    // resolve); only a file or a name not there yet lands in a file.
    match std::fs::metadata(path) {
        Ok(m) if !m.file_type().is_file() => return None,
        Ok(_) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(_) => return None,
    }
    resolve(path).ok()
}

/// The folder holding `path` (`.` for a bare file name).
fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// What is at a resolved target.
enum Target {
    /// Nothing yet, or a regular file: written by a temporary file and a rename.
    Replaceable,
    /// A character device or a named pipe (`/dev/stdout`): written in place.
    Stream,
}

/// Checks an output path against `protected` (module doc) and says how it is written.
fn check(out: &Path, protected: &Protected) -> Result<(PathBuf, Target), OutputError> {
    let refuse = |why: String| OutputError::Refused(format!("{}: {why}", out.display()));
    // A stream as the kernel opens it: `/dev/stdout` is a `/proc/self/fd` link whose target
    // (`pipe:[N]`) names no file, so it cannot be resolved by name; it is written in place.
    if std::fs::metadata(out)
        .is_ok_and(|m| m.file_type().is_char_device() || m.file_type().is_fifo())
    {
        return Ok((out.to_path_buf(), Target::Stream));
    }
    let target = resolve(out).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => refuse(format!(
            "the folder {} does not exist",
            parent_of(out).display()
        )),
        _ => refuse(format!("cannot be written: {e}")),
    })?;
    let linked = std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink());
    let via = match linked {
        true => format!(" (a symbolic link to {})", target.display()),
        false => String::new(),
    };
    if let Some(g) = protected.hit(&target) {
        let how = match (linked, g.resolved.as_deref() == Some(target.as_path())) {
            (true, _) => via.clone(),
            (false, false) => " (the same file: a hard link)".to_string(),
            (false, true) => String::new(),
        };
        return Err(refuse(format!(
            "this output would overwrite {}{how}: nothing was written; give another output path",
            g.what
        )));
    }
    let meta = match std::fs::metadata(&target) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Ok((target, Target::Replaceable));
        }
        Err(e) => {
            return Err(OutputError::Io(format!(
                "{}: cannot write: {e}",
                out.display()
            )));
        }
    };
    let kind = meta.file_type();
    if kind.is_dir() {
        return Err(refuse(format!(
            "is a folder{via}: give a file name inside it"
        )));
    }
    if kind.is_char_device() || kind.is_fifo() {
        return Ok((target, Target::Stream));
    }
    if !kind.is_file() {
        return Err(refuse(format!(
            "is neither a file nor a folder{via}: give another output path"
        )));
    }
    if starts_with_sqlite_header(&target) {
        return Err(refuse(format!(
            "is an SQLite database{via}: wetgran never writes an output over a database; remove \
             it first or give another output path"
        )));
    }
    Ok((target, Target::Replaceable))
}

/// Whether the file begins with the SQLite header.
fn starts_with_sqlite_header(path: &Path) -> bool {
    use std::io::Read as _;
    let mut head = [0u8; 16];
    std::fs::File::open(path)
        .and_then(|f| f.take(16).read_exact(&mut head))
        .is_ok()
        && &head == SQLITE_MAGIC
}

/// The outputs of one command, checked together: each against the protected files, and no
/// two naming the same file.
#[derive(Debug)]
pub struct Outputs {
    protected: Protected,
    claimed: Vec<(String, PathBuf)>,
}

impl Outputs {
    pub fn new(protected: Protected) -> Outputs {
        Outputs {
            protected,
            claimed: Vec::new(),
        }
    }

    /// Checks the output `path` of `flag` (`-o`, `--csv`): refused where it would overwrite a
    /// protected file, is a folder, or names the file of an output claimed before.
    pub fn claim(&mut self, flag: &str, path: &Path) -> Result<(), OutputError> {
        let (target, kind) = check(path, &self.protected)?;
        if matches!(kind, Target::Replaceable)
            && let Some((other, _)) = self.claimed.iter().find(|(_, t)| *t == target)
        {
            return Err(OutputError::Refused(format!(
                "{flag} {}: the same file as {other}: give each output its own file",
                path.display()
            )));
        }
        self.claimed
            .push((format!("{flag} {}", path.display()), target));
        Ok(())
    }

    /// The protected files.
    pub fn protected(&self) -> &Protected {
        &self.protected
    }
}

/// A counter that makes temporary names unique within the process.
static TEMPORARIES: AtomicU64 = AtomicU64::new(0);

/// A fresh temporary name beside `target`: `.NAME.wetgran-PID-N.tmp`.
fn temporary_beside(target: &Path, what: &str) -> PathBuf {
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    let n = TEMPORARIES.fetch_add(1, Ordering::Relaxed);
    parent_of(target).join(format!(".{name}.wetgran-{}-{n}.{what}", std::process::id()))
}

/// An output file being written (module doc): bytes go to a temporary file (or, for a device
/// or a pipe, to the target itself); [`AtomicFile::commit`] puts it in place. Dropped without
/// a commit, the temporary file is removed and the target left as it was.
#[derive(Debug)]
pub struct AtomicFile {
    shown: PathBuf,
    target: PathBuf,
    temporary: Option<PathBuf>,
    file: Option<std::io::BufWriter<std::fs::File>>,
}

impl AtomicFile {
    /// Starts writing the output `out` (checked against `protected` first).
    pub fn create(out: &Path, protected: &Protected) -> Result<AtomicFile, OutputError> {
        let (target, kind) = check(out, protected)?;
        let failed =
            |e: std::io::Error| OutputError::Io(format!("{}: cannot write: {e}", out.display()));
        let (file, temporary) = match kind {
            Target::Stream => {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(&target)
                    .map_err(failed)?;
                (f, None)
            }
            Target::Replaceable => {
                let tmp = temporary_beside(&target, "tmp");
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .create_new(true)
                    .open(&tmp)
                    .map_err(failed)?;
                // A replaced file keeps its permission bits.
                if let Ok(m) = std::fs::metadata(&target) {
                    let _ = f.set_permissions(m.permissions());
                }
                (f, Some(tmp))
            }
        };
        Ok(AtomicFile {
            shown: out.to_path_buf(),
            target,
            temporary,
            file: Some(std::io::BufWriter::new(file)),
        })
    }

    /// The output as the user named it.
    pub fn path(&self) -> &Path {
        &self.shown
    }

    /// Flushes, syncs and renames the temporary file over the target (then syncs its folder).
    pub fn commit(mut self) -> Result<(), OutputError> {
        let failed = |e: std::io::Error| {
            OutputError::Io(format!("{}: cannot write: {e}", self.shown.display()))
        };
        let file = self.file.take().expect("an uncommitted file");
        let file = file.into_inner().map_err(|e| failed(e.into_error()))?;
        let Some(tmp) = self.temporary.take() else {
            return Ok(());
        };
        let placed = file
            .sync_all()
            .and_then(|()| std::fs::rename(&tmp, &self.target));
        if let Err(e) = placed {
            let _ = std::fs::remove_file(&tmp);
            return Err(failed(e));
        }
        if let Ok(dir) = std::fs::File::open(parent_of(&self.target)) {
            let _ = dir.sync_all();
        }
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.file.as_mut().expect("an uncommitted file").write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.as_mut().expect("an uncommitted file").flush()
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(tmp) = self.temporary.take() {
            self.file.take();
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// Writes the output `out` whole (module doc), after checking it against `protected`.
pub fn write_file(
    out: &Path,
    bytes: impl AsRef<[u8]>,
    protected: &Protected,
) -> Result<(), OutputError> {
    let mut f = AtomicFile::create(out, protected)?;
    f.write_all(bytes.as_ref())
        .map_err(|e| OutputError::Io(format!("{}: cannot write: {e}", out.display())))?;
    f.commit()
}

#[cfg(test)]
mod tests;
