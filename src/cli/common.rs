//! What the command modules share: the flags of several commands (`--db` and `--sweep`, the
//! worker flags), the failure kinds and their exit codes, choosing sweeps in a database, loading
//! a sweep file (with the grid points it leaves out), the regrid check of `sweep run` / `sweep
//! submit`, reading a job spec, and the reports after a run.

use crate::output::{OutputError, Protected};
use crate::refine::driver::{Outcome, RefineError};
use crate::report::sweep_text::left_out_text;
use crate::report::sweep_text::refinement_text;
use crate::run::RunOptions;
use crate::run::progress::Steps;
use crate::store::{LeftOut, Store, StoreError, SweepRow};
use crate::sweep::{JobSpec, SweepFile};
use crate::terminal::{escape, escape_lines};
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use wetgran_core::sim::event_driven::table_cache::DEFAULT_TABLE_CACHE_MIB;

/// Default database file, in the working directory.
pub(super) const DEFAULT_DB: &str = "wetgran.sqlite";

/// `--db` and `--sweep` of the commands that work on the whole database (`sweep collect`).
#[derive(Debug, Args)]
pub struct DbSweeps {
    /// Database file; also from WETGRAN_DB (the flag wins).
    #[arg(long, env = "WETGRAN_DB", default_value = DEFAULT_DB)]
    pub db: PathBuf,
    /// Only this sweep (default: all).
    #[arg(long)]
    pub sweep: Option<String>,
}

/// The help of `--sweep` of the commands that read a sweep's results: the one rule by which
/// they take a sweep (docs/cli.md, "Which sweep a command takes").
pub(super) const SWEEP_HELP: &str = "The sweep [default: the one registered (`sweep run`) or \
     refined last; named on standard error when the database holds several]";

/// `--db`, `--sweep` and `--all-sweeps` of the commands that read sweeps' results and can
/// combine several (`boundaries`, `export`, `inflection`): one sweep by the rule of
/// [`latest_sweep`], or every sweep.
#[derive(Debug, Args)]
pub struct DbPick {
    /// Database file; also from WETGRAN_DB (the flag wins).
    #[arg(long, env = "WETGRAN_DB", default_value = DEFAULT_DB)]
    pub db: PathBuf,
    #[arg(long, help = SWEEP_HELP, conflicts_with = "all_sweeps")]
    pub sweep: Option<String>,
    /// Every sweep of the database, one after the other, instead of one.
    #[arg(long)]
    pub all_sweeps: bool,
}

impl DbPick {
    /// The sweeps the command reads: `--sweep NAME`, every sweep with `--all-sweeps` (none in an
    /// empty database), else the one registered or refined last ([`latest_sweep`]).
    pub(super) fn select(&self, store: &Store) -> Result<Vec<SweepRow>, Failure> {
        if self.all_sweeps {
            return Ok(store.sweeps()?);
        }
        Ok(vec![latest_sweep(store, self.sweep.as_deref(), true)?])
    }
}

/// The sweep a command reads (docs/cli.md, "Which sweep a command takes"): the one named, or
/// else the one registered (`sweep run`) or refined last (`sweeps.updated_at`; the later
/// registered of two at the same time), named on stderr when the database holds several. An
/// empty database is refused.
/// `combines`: the command also takes `--all-sweeps`, which the note then names.
pub(super) fn latest_sweep(
    store: &Store,
    name: Option<&str>,
    combines: bool,
) -> Result<SweepRow, Failure> {
    if let Some(n) = name {
        return Ok(store.sweep(n)?);
    }
    let mut all = store.sweeps()?;
    // Stable: among equal times the order of registration (`sweeps()` is by id) stays.
    all.sort_by(|a, b| a.updated_at.total_cmp(&b.updated_at));
    let last = all.pop().ok_or_else(|| {
        Failure::BadInput(format!(
            "{}: no sweep in this database: start one with `wetgran sweep run FILE`",
            store.path().display()
        ))
    })?;
    if !all.is_empty() {
        note(&format!(
            "sweep {} (registered or refined last of the {} sweeps in {}; --sweep NAME takes \
             another{})",
            escape(&last.name),
            all.len() + 1,
            store.path().display(),
            if combines {
                ", --all-sweeps every one"
            } else {
                ""
            }
        ));
    }
    Ok(last)
}

/// Worker threads of the commands that run jobs (`sweep run`; `sweep resume` and `sweep refine`
/// say what their workers run with `mut_arg`).
#[derive(Debug, Args)]
pub(super) struct Workers {
    /// Worker threads, one simulation each, for the sweep's jobs and then the refinement of a
    /// `[refine]` table: 1 to the available cores (default: all of them).
    #[arg(long)]
    jobs: Option<usize>,
    /// Allow --jobs above the available cores (several simulations share a core; each
    /// runs slower, the sweep no faster).
    #[arg(long)]
    oversubscribe: bool,
}

impl Workers {
    /// The options of a local run: `--jobs` workers (by default the available cores; in
    /// `[1, available cores]` unless `--oversubscribe`), progress shown, failed jobs left as
    /// they are, the wall-table cache at its default cap (no shipped sweep selects the `table`
    /// wall solver), no hook.
    pub(super) fn options(&self) -> Result<RunOptions, Failure> {
        self.options_with(&super::Hooks::default())
    }

    /// [`Self::options`] with the extension hook of `hooks`.
    pub(super) fn options_with(&self, hooks: &super::Hooks) -> Result<RunOptions, Failure> {
        let cores = available_cores();
        let jobs = match self.jobs {
            None => cores,
            Some(0) => {
                return Err(Failure::BadInput(format!(
                    "--jobs 0 is out of range: must be in [1, {cores}] (the available cores)"
                )));
            }
            Some(n) if n > cores && !self.oversubscribe => {
                return Err(Failure::BadInput(format!(
                    "--jobs {n} is out of range: must be in [1, {cores}] (the available cores; \
                     one simulation per worker); add --oversubscribe to start more workers than \
                     cores"
                )));
            }
            Some(n) => n,
        };
        Ok(RunOptions {
            jobs,
            retry_failed: false,
            show_progress: true,
            table_cache_mib: DEFAULT_TABLE_CACHE_MIB,
            on_extend: hooks.extend.clone(),
        })
    }
}

/// How a command failed: bad input (exit code 2), a sweep that finished with failed jobs
/// (exit code 4: everything else was done and stored; 3 is a broken engine invariant in
/// `simulate` and `stress`), Ctrl-C before anything was stored (130) or anything else (exit
/// code 1).
pub(super) enum Failure {
    BadInput(String),
    JobsFailed(String),
    Other(String),
    /// Stopped by Ctrl-C before anything was stored (exit code 130).
    Interrupted(String),
}

impl From<StoreError> for Failure {
    fn from(e: StoreError) -> Self {
        match e {
            StoreError::NotSqlite { .. }
            | StoreError::NotWetgran { .. }
            | StoreError::Damaged { .. }
            | StoreError::Missing { .. }
            | StoreError::Outdated { .. }
            | StoreError::Newer { .. }
            | StoreError::NotAFile { .. }
            | StoreError::Truncated { .. }
            | StoreError::NoContent { .. }
            | StoreError::NoSuchSweep { .. } => Failure::BadInput(e.to_string()),
            StoreError::Interrupted { .. } => Failure::Interrupted(e.to_string()),
            _ => Failure::Other(e.to_string()),
        }
    }
}

pub(super) fn exit(r: Result<(), Failure>) -> ExitCode {
    let (m, code) = match r {
        Ok(()) => return ExitCode::SUCCESS,
        Err(Failure::BadInput(m)) => (m, 2),
        Err(Failure::JobsFailed(m)) => (m, 4),
        Err(Failure::Other(m)) => (m, 1),
        Err(Failure::Interrupted(m)) => (m, 130),
    };
    eprintln!("error: {}", escape_lines(&m));
    ExitCode::from(code)
}

/// The context of a run on its own (`simulate`, `job run`): every core the process may use
/// (`sim::threads::available_cores`, `WETGRAN_THREADS`), no hook.
pub(super) fn all_cores() -> wetgran_core::sim::RunSettings {
    use wetgran_core::sim::threads::{Threads, available_cores};
    wetgran_core::sim::RunSettings::on(Threads::new(available_cores()))
}

/// The cores this process may use (`std::thread::available_parallelism`, 1 if unknown).
pub(super) fn available_cores() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
}

/// Prints a value as pretty JSON.
pub(super) fn print_json(value: &impl serde::Serialize) {
    println!(
        "{}",
        serde_json::to_string_pretty(value).expect("serializes")
    );
}

/// Writes an output file whole (`output::write_file`), refused where it would overwrite a file
/// of `protected`; a failure names the file.
pub(super) fn write_file(
    path: &Path,
    text: impl AsRef<[u8]>,
    protected: &Protected,
) -> Result<(), Failure> {
    Ok(crate::output::write_file(path, text, protected)?)
}

/// The failure of a write to `path`, which it names.
pub(super) fn cannot_write(path: &Path) -> impl FnOnce(std::io::Error) -> Failure + '_ {
    move |e| Failure::Other(format!("{}: cannot write: {e}", path.display()))
}

impl From<OutputError> for Failure {
    fn from(e: OutputError) -> Self {
        match e {
            OutputError::Refused(m) => Failure::BadInput(m),
            OutputError::Io(m) => Failure::Other(m),
        }
    }
}

/// Prints a block of text a command composed (a report, a table) on standard output, with
/// whatever came from a database or a sweep file made inert (`terminal`).
pub(super) fn show(text: &str) {
    print!("{}", escape_lines(text));
}

/// Prints one message line on standard error, made inert as [`show`] does.
pub(super) fn note(text: &str) {
    eprintln!("{}", escape_lines(text));
}

impl From<RefineError> for Failure {
    fn from(e: RefineError) -> Self {
        match e {
            RefineError::Store(e) => e.into(),
            RefineError::Bad(m) => Failure::BadInput(m),
        }
    }
}

/// The sweep named `name`, or every sweep of the database.
pub(super) fn select(store: &Store, name: Option<&str>) -> Result<Vec<SweepRow>, Failure> {
    Ok(match name {
        Some(n) => vec![store.sweep(n)?],
        None => store.sweeps()?,
    })
}

/// Loads and expands a sweep file; also returns the grid points `skip_invalid` left out, each
/// with the scene constraint it fails, after listing them on stderr.
pub(super) fn load_sweep(
    file: &Path,
) -> Result<(SweepFile, Vec<crate::sweep::SweepJob>, Vec<LeftOut>), Failure> {
    let sweep = SweepFile::load(file).map_err(|e| Failure::BadInput(e.to_string()))?;
    let mut progress = Steps::new("expanding grid points", sweep.points(), true);
    let expanded = sweep.expand_watched(&mut |done| progress.set(done));
    progress.finish();
    let (jobs, skipped) = expanded.map_err(|e| Failure::BadInput(e.to_string()))?;
    let left_out: Vec<LeftOut> = skipped
        .iter()
        .map(|k| LeftOut {
            coords: k.coords.clone(),
            constraint: k
                .reason
                .constraint
                .map(|c| c.reason().to_string())
                .unwrap_or_default(),
            reason: k.reason.to_string(),
        })
        .collect();
    if !left_out.is_empty() {
        note(&format!(
            "{}: left out {} grid point(s) (sweep.skip_invalid: the scene fails a constraint):",
            file.display(),
            left_out.len()
        ));
        eprint!("{}", escape_lines(&left_out_text(&sweep.axes, &left_out)));
    }
    if jobs.is_empty() {
        return Err(Failure::BadInput(format!(
            "{}: the sweep has no valid grid point",
            file.display()
        )));
    }
    Ok((sweep, jobs, left_out))
}

/// Registers a sweep (`Store::register_sweep_watched`) with its progress shown for a large
/// grid, and Ctrl-C turned into a rolled-back registration (`interrupt::registering`): then the
/// failure says that nothing was stored.
pub(super) fn register(
    store: &Store,
    sweep: &SweepFile,
    expanded: &[crate::sweep::SweepJob],
) -> Result<SweepRow, Failure> {
    let mut progress = Steps::new("registering jobs", expanded.len(), true);
    let registered = super::interrupt::registering(|cancelled| {
        store.register_sweep_watched(sweep, expanded, &mut |done| {
            progress.set(done);
            !cancelled()
        })
    });
    progress.finish();
    registered.map_err(|e| match e {
        StoreError::Interrupted { path, detail } => Failure::Interrupted(format!(
            "{path}: {detail}; run `wetgran sweep run {}` again to register and run it",
            escape(&sweep.path.display().to_string())
        )),
        e => e.into(),
    })
}

/// A sweep name registered before with another grid (axes or replicas) is refused unless
/// `--replace`: the error says what would be replaced.
pub(super) fn check_regrid(
    store: &Store,
    old: &SweepRow,
    sweep: &SweepFile,
    expanded: &[crate::sweep::SweepJob],
    replace: bool,
) -> Result<(), Failure> {
    let grid = |axes: &[crate::sweep::Axis], replicas: u32| {
        let mut parts: Vec<String> = axes
            .iter()
            .map(|a| {
                let v: Vec<String> = a.values.iter().map(|v| v.to_string()).collect();
                format!("{} = [{}]", a.label, v.join(", "))
            })
            .collect();
        parts.push(format!("{replicas} replica(s)"));
        parts.join("; ")
    };
    let same_axes = old.axes.len() == sweep.axes.len()
        && old
            .axes
            .iter()
            .zip(&sweep.axes)
            .all(|(a, b)| a.key == b.key && a.values == b.values);
    if (same_axes && old.replicas == sweep.replicas) || replace {
        return Ok(());
    }
    let new_ids: std::collections::HashSet<&str> = expanded.iter().map(|j| j.id.as_str()).collect();
    let points = store.points(old.id)?;
    let leaving: Vec<_> = points
        .iter()
        .filter(|p| !new_ids.contains(p.job_id.as_str()))
        .collect();
    let with_result = leaving.iter().filter(|p| p.observables.is_some()).count();
    Err(Failure::BadInput(format!(
        "{}: sweep `{}` is already in {} with another grid (registered from {}):\n  \
         old grid: {} ({} job(s))\n  new grid: {} ({} job(s))\n  {} job(s) of the old grid, \
         {with_result} of them with a result, would no longer be in the sweep (their results \
         stay in the database); run again with --replace to replace the grid, or give the \
         sweep another name",
        sweep.path.display(),
        sweep.name,
        store.path().display(),
        escape(&old.file),
        grid(&old.axes, old.replicas),
        points.len(),
        grid(&sweep.axes, sweep.replicas),
        expanded.len(),
        leaving.len(),
    )))
}

/// Reads a job spec file: a bare spec or a line of `sweep expand --specs` (`-`: standard input).
pub(super) fn read_spec(path: &Path) -> Result<JobSpec, Failure> {
    let text = if path.as_os_str() == "-" {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut std::io::stdin(), &mut s)
            .map_err(|e| Failure::Other(format!("reading standard input: {e}")))?;
        s
    } else {
        std::fs::read_to_string(path)
            .map_err(|e| Failure::BadInput(format!("{}: cannot read: {e}", path.display())))?
    };
    let origin = path.display().to_string();
    let value: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| Failure::BadInput(format!("{origin}: not JSON: {e}")))?;
    let spec_value = value.get("spec").cloned().unwrap_or(value);
    JobSpec::from_json(&spec_value.to_string(), &origin).map_err(Failure::BadInput)
}

/// The line rule's labels (docs/model.md 7) over the lines of constant Gamma with new or
/// extended results (after a run, an extension or a collection), with what changed on stdout:
/// without it a result kept its point's own label, where the same job in a whole run got its
/// line's.
pub(super) fn relabel_lines(store: &Store, row: &SweepRow) -> Result<(), Failure> {
    let relabelled = crate::run::relabel::relabel_changed(store, row)?;
    if relabelled.changed() > 0 {
        show(&format!(
            "sweep {}: labels along lines of constant Gamma (docs/model.md 7): {}\n",
            escape(&row.name),
            relabelled.text()
        ));
    }
    Ok(())
}

/// Reports a refinement on stdout (a result, as the job lines are).
pub(super) fn refinement_report(row: &SweepRow, o: &Outcome) {
    show(&(refinement_text(&escape(&row.name), o.added, o.rounds, o.resolved) + "\n"));
}

/// After `sweep run` / `sweep resume`: continues the refinement of every given sweep whose file
/// has a `[refine]` table, up to its budget (`refine::driver::continue_refinement`).
pub(super) fn continue_refinement(
    store: &Store,
    rows: &[SweepRow],
    opts: &RunOptions,
) -> Result<(), Failure> {
    crate::refine::driver::continue_refinement(store, rows, opts, &mut |row, o| {
        refinement_report(row, o)
    })?;
    Ok(())
}

/// `--snapshot` files must be named `.xyz` (extended XYZ) or `.svg` (a picture).
pub(super) fn check_snapshot_names(paths: &[std::path::PathBuf]) -> Result<(), Failure> {
    for path in paths {
        if !matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("xyz" | "svg")
        ) {
            return Err(Failure::BadInput(format!(
                "--snapshot {}: the file name must end in .xyz or .svg",
                path.display()
            )));
        }
    }
    Ok(())
}

/// The folder of a `--db` path must exist: without this check SQLite's "unable to open database
/// file" reads as a read-only folder, and a reader's "no database here" hides the typo in the
/// folder. Every command checks its `--db` before anything else (`Command::databases`).
pub(super) fn folder_of_database(db: &Path, creates: bool) -> Result<(), Failure> {
    if db.exists() {
        return Ok(());
    }
    match db.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if !dir.is_dir() => Err(Failure::BadInput(format!(
            "{}: the folder {} does not exist: {}give another --db (or WETGRAN_DB)",
            db.display(),
            dir.display(),
            if creates {
                format!("create it (`mkdir -p {}`) or ", dir.display())
            } else {
                String::new()
            }
        ))),
        _ => Ok(()),
    }
}
