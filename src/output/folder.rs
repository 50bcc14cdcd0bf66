//! A folder of outputs written as a whole (`wetgran report -o DIR`): the files go into a fresh
//! temporary folder beside the target (`.DIR.wetgran-PID-N.new`), which is renamed into place
//! once every file is written, so a failure half-way leaves the target as it was and a
//! finished report holds exactly the files of this run (no page of an earlier sweep survives).
//!
//! The folder carries a marker file, [`MARKER`], whose first line is [`MARKER_LINE`]. An
//! existing target is replaced only when it holds that marker (a report this command wrote);
//! any other existing target (a user's folder, `.`, a file) is refused, with `--force` named
//! for a folder. A target that is a symbolic link is refused even with `--force`: wetgran does
//! not write through a link it did not make. Nothing inside the old folder is followed either:
//! the new folder is built from scratch (every file created new, `create_new`), and the old
//! one is renamed aside and removed without following the links in it. Refused whatever the
//! flags: a target that holds the database (or a protected file) or the working folder, since
//! replacing it would delete them.

use super::{OutputError, Protected, parent_of, resolve, temporary_beside};
use std::path::{Component, Path, PathBuf};

/// The marker file of a folder [`SiteFolder`] wrote.
pub const MARKER: &str = ".wetgran-report";
/// The first line of [`MARKER`].
pub const MARKER_LINE: &str =
    "wetgran report: this folder is replaced by the next `wetgran report -o` into it";

/// A report folder being written (module doc); dropped without [`SiteFolder::commit`], the
/// temporary folder is removed and the target left as it was.
#[derive(Debug)]
pub struct SiteFolder {
    shown: PathBuf,
    target: PathBuf,
    temporary: Option<PathBuf>,
    force: bool,
    protected: Protected,
}

/// Whether `dir` holds the marker as a regular file (a link named like it does not count).
fn holds_marker(dir: &Path) -> bool {
    let marker = dir.join(MARKER);
    std::fs::symlink_metadata(&marker).is_ok_and(|m| m.file_type().is_file())
        && std::fs::read_to_string(&marker).is_ok_and(|t| t.lines().next() == Some(MARKER_LINE))
}

impl SiteFolder {
    /// Checks the target `out` and creates the temporary folder beside it; `force` lets an
    /// existing folder without the marker be replaced.
    pub fn create(
        out: &Path,
        force: bool,
        protected: &Protected,
    ) -> Result<SiteFolder, OutputError> {
        let target = check_target(out, force, protected)?;
        let temporary = temporary_beside(&target, "new");
        std::fs::create_dir(&temporary)
            .map_err(|e| OutputError::Io(format!("{}: cannot create: {e}", temporary.display())))?;
        Ok(SiteFolder {
            shown: out.to_path_buf(),
            target,
            temporary: Some(temporary),
            force,
            protected: protected.clone(),
        })
    }

    /// Writes the file `rel` (a relative path of plain names: `points/point-3.html`) of the
    /// new folder; a path with `..`, a root or an empty part is refused (a name that came from
    /// a database must not leave the folder).
    pub fn write(&self, rel: &str, bytes: impl AsRef<[u8]>) -> Result<(), OutputError> {
        let root = self.temporary.as_deref().expect("an uncommitted folder");
        let parts: Vec<Component> = Path::new(rel).components().collect();
        if parts.is_empty()
            || rel.contains('\0')
            || !parts.iter().all(|c| matches!(c, Component::Normal(_)))
            || rel == MARKER
        {
            return Err(OutputError::Refused(format!(
                "{}: the report file name {:?} is not a plain path inside the folder: nothing was \
                 written",
                self.shown.display(),
                rel
            )));
        }
        let path = root.join(rel);
        let failed = |p: &Path, e: std::io::Error| {
            OutputError::Io(format!(
                "{}: cannot write {rel}: {e} ({})",
                self.shown.display(),
                p.display()
            ))
        };
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| failed(dir, e))?;
        }
        use std::io::Write as _;
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
            .and_then(|mut f| f.write_all(bytes.as_ref()))
            .map_err(|e| failed(&path, e))
    }

    /// Writes the marker and puts the new folder in place of the target (the old folder, if
    /// any, renamed aside first and then removed).
    pub fn commit(mut self) -> Result<(), OutputError> {
        let fresh = self.temporary.clone().expect("an uncommitted folder");
        std::fs::write(fresh.join(MARKER), format!("{MARKER_LINE}\n"))
            .map_err(|e| OutputError::Io(format!("{}: cannot write: {e}", fresh.display())))?;
        // The target is checked again: it may have changed while the files were made.
        check_target(&self.shown, self.force, &self.protected)?;
        let failed = |e: std::io::Error| {
            OutputError::Io(format!(
                "{}: cannot put the report in place: {e}; the new report is in {}",
                self.shown.display(),
                fresh.display()
            ))
        };
        let old = match std::fs::symlink_metadata(&self.target) {
            Ok(_) => {
                let aside = temporary_beside(&self.target, "old");
                std::fs::rename(&self.target, &aside).map_err(failed)?;
                Some(aside)
            }
            Err(_) => None,
        };
        if let Err(e) = std::fs::rename(&fresh, &self.target) {
            if let Some(aside) = &old {
                let _ = std::fs::rename(aside, &self.target);
            }
            self.temporary = None;
            return Err(failed(e));
        }
        self.temporary = None;
        if let Some(aside) = old {
            // `remove_dir_all` removes links, never what they point to.
            std::fs::remove_dir_all(&aside).map_err(|e| {
                OutputError::Io(format!(
                    "{}: the report is in place, but its old version could not be removed: {e} \
                     ({})",
                    self.shown.display(),
                    aside.display()
                ))
            })?;
        }
        if let Ok(dir) = std::fs::File::open(parent_of(&self.target)) {
            let _ = dir.sync_all();
        }
        Ok(())
    }
}

impl Drop for SiteFolder {
    fn drop(&mut self) {
        if let Some(tmp) = self.temporary.take() {
            let _ = std::fs::remove_dir_all(tmp);
        }
    }
}

/// The resolved target of a report folder, or why it is refused (module doc).
fn check_target(out: &Path, force: bool, protected: &Protected) -> Result<PathBuf, OutputError> {
    let refuse = |why: String| OutputError::Refused(format!("-o {}: {why}", out.display()));
    match out.components().next_back() {
        Some(Component::Normal(_)) => {}
        _ => {
            return Err(refuse(
                "names no folder of its own (`.`, `..` or a root): give the path of the report \
                 folder, e.g. `-o report`"
                    .to_string(),
            ));
        }
    }
    let meta = std::fs::symlink_metadata(out);
    if meta.as_ref().is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(refuse(
            "is a symbolic link: wetgran does not write a report through a link; give the folder \
             itself or another path"
                .to_string(),
        ));
    }
    let target = resolve(out).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => refuse(format!(
            "the folder {} does not exist",
            parent_of(out).display()
        )),
        _ => refuse(format!("cannot be written: {e}")),
    })?;
    if meta.as_ref().is_ok_and(|m| !m.is_dir()) {
        return Err(refuse(
            "exists and is not a folder: give another path for the report folder".to_string(),
        ));
    }
    if let Some(g) = protected.inside(&target) {
        return Err(refuse(format!(
            "holds {}: replacing the folder would delete it; give another path",
            g.what
        )));
    }
    if let Ok(cwd) = std::env::current_dir().and_then(std::fs::canonicalize)
        && cwd.starts_with(&target)
    {
        return Err(refuse(
            "holds the working folder: replacing it would delete what is in it; give another path"
                .to_string(),
        ));
    }
    match meta {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(target),
        Err(e) => Err(OutputError::Io(format!("-o {}: {e}", out.display()))),
        Ok(_) if holds_marker(&target) || force => Ok(target),
        Ok(_) => Err(refuse(format!(
            "exists and is not a report wetgran wrote (it has no {MARKER} file): its files would \
             be replaced; give another path, or add --force to replace the whole folder with the \
             report"
        ))),
    }
}
