//! The cluster commands: `sweep submit --slurm`, `sweep collect`, the Slurm part of
//! `sweep status`, and `job run` (what an array task executes).
//! Exit codes as for the other sweep commands: 0 ok, 2 bad input, 1 any other error; `job run`
//! exits 1 when the job failed (its error record is written all the same).

use super::common::{
    Failure, check_regrid, load_sweep, print_json, read_spec, register, relabel_lines, select, show,
};
use crate::cluster::record::write_atomic;
use crate::cluster::slurm::{self, ArrayScript, SbatchOptions};
use crate::cluster::{Outcome, ResultRecord, SweepDir, collect, jobs_to_submit};
use crate::output::{Outputs, Protected};
use crate::report::cluster_text::collected_text;
use crate::store::{Store, SweepRow};
use crate::sweep::{JobSpec, run_job};
use crate::terminal::{escape, escape_lines};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct SubmitArgs {
    /// The sweep file.
    file: PathBuf,
    /// Submit with Slurm's sbatch (the only cluster backend).
    #[arg(long)]
    slurm: bool,
    /// Slurm partition (default: the cluster's).
    #[arg(long)]
    partition: Option<String>,
    /// Wall-time limit per task, as sbatch takes it (`30`, `2:00:00`, `1-00:00:00`).
    #[arg(long)]
    time: Option<String>,
    /// CPUs per task (a job is one simulation on one thread).
    #[arg(long, default_value_t = 1)]
    cpus_per_task: u32,
    /// Most tasks per array (default 1000, and never more than the cluster's MaxArraySize).
    #[arg(long)]
    array_limit: Option<usize>,
    /// Print the array script(s) and submit nothing (nothing is written).
    #[arg(long)]
    dry_run: bool,
    /// Database file (created if missing); also from WETGRAN_DB (the flag wins).
    #[arg(long, env = "WETGRAN_DB", default_value = super::common::DEFAULT_DB)]
    pub db: PathBuf,
    /// The sweep directory (default: `wetgran-slurm/<sweep name>` beside the database).
    #[arg(long)]
    dir: Option<PathBuf>,
    /// Allow a registered sweep name to get a different grid (as `sweep run --replace`).
    #[arg(long)]
    replace: bool,
}

fn absolute(p: &Path) -> Result<PathBuf, Failure> {
    std::path::absolute(p)
        .map_err(|e| Failure::Other(format!("{}: cannot make it absolute: {e}", p.display())))
}

/// The first free `array-NNNN` name in the arrays folder.
fn next_array_name(arrays: &Path) -> String {
    (1..)
        .map(|n| format!("array-{n:04}"))
        .find(|name| !arrays.join(format!("{name}.sbatch")).exists())
        .expect("a free name")
}

pub(super) fn submit(s: SubmitArgs) -> Result<(), Failure> {
    if !s.slurm {
        return Err(Failure::BadInput(
            "sweep submit: give --slurm (the only cluster backend so far)".to_string(),
        ));
    }
    let (file, db) = (&s.file, &s.db);
    let (sweep, expanded, left_out) = load_sweep(file)?;
    if expanded.iter().any(|j| j.spec.start_from.is_some()) {
        // Each task of an array runs on its own; a chain needs its predecessor's final state.
        return Err(Failure::BadInput(format!(
            "{}: sweep {} continues points along an axis ([sweep.continuation]); Slurm arrays \
             run their tasks independently, so run it with `wetgran sweep run` (or submit the \
             same grid without [sweep.continuation])",
            file.display(),
            sweep.name
        )));
    }
    let target = ArrayTarget::new(db, &sweep.name, &s)?;
    if s.dry_run {
        return dry_run(db, &expanded, &target);
    }
    let store = Store::open(db)?;
    if let Ok(old) = store.sweep(&sweep.name) {
        check_regrid(&store, &old, &sweep, &expanded, s.replace)?;
    }
    let row = register(&store, &sweep, &expanded)?;
    store.set_left_out(row.id, &left_out)?;
    let Some(ids) = jobs_left(&store, &row, db, &target)? else {
        return Ok(());
    };
    write_task_specs(&store, &row, &target.sd, &ids)?;
    let parts = slurm::split(&ids, target.limit);
    submit_arrays(&store, &row, &target, &parts)?;
    eprintln!(
        "sweep {}: {} job(s) submitted as {} array(s) of at most {} task(s); sweep directory \
         {}. Watch with `wetgran sweep status --db {db}`, then `wetgran sweep collect --db {db}`",
        escape(&row.name),
        ids.len(),
        parts.len(),
        target.limit,
        target.sd.root.display(),
        db = db.display()
    );
    Ok(())
}

/// Where and how a sweep's arrays go: its sweep directory, the executable the tasks run, the
/// array size limit and the sbatch options.
struct ArrayTarget {
    sweep: String,
    sd: SweepDir,
    exe: PathBuf,
    /// The cluster's `MaxArraySize` (`None`: scontrol not available).
    max: Option<usize>,
    limit: usize,
    options: SbatchOptions,
}

impl ArrayTarget {
    /// Checks the directives that go into the batch script.
    fn new(db: &Path, sweep: &str, s: &SubmitArgs) -> Result<Self, Failure> {
        // Without `--dir`: beside the database (which a cluster user keeps on the shared
        // filesystem), `<db folder>/wetgran-slurm/<sweep name>`.
        let dir = match &s.dir {
            Some(d) => absolute(d)?,
            None => absolute(db)?
                .parent()
                .unwrap_or(Path::new("/"))
                .join("wetgran-slurm")
                .join(slurm::file_name(sweep)),
        };
        slurm::check_directive("the sweep directory", &dir.display().to_string())
            .map_err(Failure::BadInput)?;
        for (what, v) in [("--partition", &s.partition), ("--time", &s.time)] {
            if let Some(v) = v {
                slurm::check_directive(what, v).map_err(Failure::BadInput)?;
            }
        }
        let exe = std::env::current_exe()
            .map_err(|e| Failure::Other(format!("cannot find the wetgran executable: {e}")))?;
        let max = slurm::max_array_size();
        Ok(ArrayTarget {
            sweep: sweep.to_string(),
            sd: SweepDir::new(&dir),
            exe,
            max,
            limit: slurm::array_limit(s.array_limit, max),
            options: SbatchOptions {
                partition: s.partition.clone(),
                time: s.time.clone(),
                cpus_per_task: s.cpus_per_task,
            },
        })
    }

    /// The batch script of an array of `n` tasks whose job ids are listed in `tasks_file`.
    fn script(&self, tasks_file: &Path, n: usize) -> Result<String, Failure> {
        slurm::array_script(&ArrayScript {
            sweep: &self.sweep,
            dir: &self.sd.root,
            tasks_file,
            tasks: n,
            wetgran: &self.exe,
            options: &self.options,
        })
        .map_err(Failure::BadInput)
    }
}

/// `--dry-run`: prints the arrays that would be submitted (the jobs not done in the database,
/// all where there is none); writes nothing.
fn dry_run(
    db: &Path,
    expanded: &[crate::sweep::SweepJob],
    target: &ArrayTarget,
) -> Result<(), Failure> {
    // Each job once, in grid order.
    let mut seen = std::collections::HashSet::new();
    let mut ids: Vec<String> = expanded
        .iter()
        .filter(|j| seen.insert(j.id.as_str()))
        .map(|j| j.id.clone())
        .collect();
    if db.exists() {
        let store = Store::open_read_only(db)?;
        let st = store.job_statuses(&ids)?;
        ids.retain(|id| st.get(id).map(String::as_str) != Some("done"));
    }
    let parts = slurm::split(&ids, target.limit);
    println!(
        "# dry run: {} job(s) to submit as {} array(s) of at most {} task(s) ({}); sweep \
         directory {}",
        ids.len(),
        parts.len(),
        target.limit,
        match target.max {
            Some(m) => format!("cluster MaxArraySize {m}"),
            None => "scontrol not available".to_string(),
        },
        target.sd.root.display()
    );
    for (k, part) in parts.iter().enumerate() {
        let tasks = target
            .sd
            .arrays()
            .join(format!("array-dryrun-{}.tasks", k + 1));
        let script = target.script(&tasks, part.len())?;
        println!(
            "# ---- array {} of {}: {}",
            k + 1,
            parts.len(),
            tasks.display()
        );
        print!("{script}");
    }
    Ok(())
}

/// The jobs to submit, after collecting the results already on disk (they count before
/// anything is submitted again); `None`, with a message, where there are none.
fn jobs_left(
    store: &Store,
    row: &SweepRow,
    db: &Path,
    target: &ArrayTarget,
) -> Result<Option<Vec<String>>, Failure> {
    target
        .sd
        .create()
        .map_err(|e| Failure::Other(format!("{}: cannot create: {e}", target.sd.root.display())))?;
    let c = collect(store, row, &mut slurm::squeue)?;
    relabel_lines(store, row)?;
    if c.stored.len() + c.failed.len() + c.missing.len() + c.corrupt.len() > 0 {
        eprint!(
            "{}",
            escape_lines(&collected_text(row, &store.points(row.id)?, &c))
        );
    }
    let ids = jobs_to_submit(store, row)?;
    if ids.is_empty() {
        let counts = store.counts(row.id)?;
        eprintln!(
            "sweep {}: nothing to submit ({} job(s) done, {} task(s) still queued or running: \
             `wetgran sweep status --db {}`)",
            escape(&row.name),
            counts.done,
            c.waiting.len(),
            db.display()
        );
        return Ok(None);
    }
    Ok(Some(ids))
}

fn io_failure(p: &Path, e: std::io::Error) -> Failure {
    Failure::Other(format!("{}: {e}", p.display()))
}

/// Writes each job's spec file into the sweep directory and removes an earlier task's result
/// file (its error record or broken file must not pass for the new task's).
fn write_task_specs(
    store: &Store,
    row: &SweepRow,
    sd: &SweepDir,
    ids: &[String],
) -> Result<(), Failure> {
    let specs: HashMap<String, JobSpec> = store
        .points(row.id)?
        .into_iter()
        .map(|p| (p.job_id, p.spec))
        .collect();
    for id in ids {
        sd.write_spec(&specs[id])
            .map_err(|e| io_failure(&sd.spec(id), e))?;
        let old = sd.result(id);
        if old.exists() {
            std::fs::remove_file(&old).map_err(|e| io_failure(&old, e))?;
        }
    }
    Ok(())
}

/// Writes each array's task list and batch script, records the submission and runs `sbatch`;
/// a failed `sbatch` drops its submission and names the arrays already submitted.
fn submit_arrays(
    store: &Store,
    row: &SweepRow,
    target: &ArrayTarget,
    parts: &[&[String]],
) -> Result<(), Failure> {
    let arrays = target.sd.arrays();
    let mut submitted = Vec::new();
    for part in parts {
        let name = next_array_name(&arrays);
        let tasks = arrays.join(format!("{name}.tasks"));
        let script_path = arrays.join(format!("{name}.sbatch"));
        let script = target.script(&tasks, part.len())?;
        write_atomic(&tasks, (part.join("\n") + "\n").as_bytes())
            .map_err(|e| io_failure(&tasks, e))?;
        write_atomic(&script_path, script.as_bytes()).map_err(|e| io_failure(&script_path, e))?;
        let sub = store.record_submission(
            row.id,
            &target.sd.root.display().to_string(),
            &script_path.display().to_string(),
            part,
        )?;
        match slurm::sbatch(&script_path) {
            Ok(job) => {
                store.set_slurm_job(sub, &job)?;
                eprintln!(
                    "submitted {} as Slurm job {job} ({} task(s))",
                    script_path.display(),
                    part.len()
                );
                submitted.push(job);
            }
            Err(e) => {
                store.drop_submission(sub)?;
                let done = if submitted.is_empty() {
                    String::new()
                } else {
                    format!(
                        " (arrays {} were submitted; submit again for the rest)",
                        submitted.join(", ")
                    )
                };
                return Err(Failure::Other(format!("{e}{done}")));
            }
        }
    }
    Ok(())
}

pub(super) fn collect_cmd(a: super::common::DbSweeps) -> Result<(), Failure> {
    let db = &a.db;
    let store = Store::open_existing(db)?;
    let sweeps = select(&store, a.sweep.as_deref())?;
    let mut any = false;
    let (mut total_failed, mut total_lost) = (0, 0);
    for s in &sweeps {
        if store.tasks(s.id)?.is_empty() {
            continue;
        }
        any = true;
        let c = collect(&store, s, &mut slurm::squeue)?;
        relabel_lines(&store, s)?;
        let points = store.points(s.id)?;
        show(&collected_text(s, &points, &c));
        let (failed, lost) = unfinished_for_good(&points, &store.tasks(s.id)?);
        total_failed += failed;
        total_lost += lost;
    }
    if !any {
        println!(
            "{}: no submitted tasks to collect (`wetgran sweep submit FILE --slurm` submits a \
             sweep)",
            db.display()
        );
    }
    if total_failed + total_lost == 0 {
        return Ok(());
    }
    // Exit status 4, as `sweep run` with failed jobs: a script (`sweep collect && sweep
    // boundaries`) must not take a partial diagram for a whole one. Tasks still queued or
    // running are not a failure.
    Err(Failure::JobsFailed(format!(
        "{total_failed} job(s) failed and {total_lost} lost (no result, or an unreadable one, \
         and no longer queued); the others are stored: `wetgran sweep submit FILE --slurm` \
         submits them again"
    )))
}

/// Jobs of a sweep that will not finish without a new submission: `(failed, lost)`. A job's
/// latest task decides (earlier tasks were submitted again): lost jobs have no result and a
/// latest task that is missing or corrupt (no result file, or an unreadable one, and no longer
/// in the queue); failed jobs wrote an error record and were not submitted again since. A job
/// with a result counts as neither; one whose latest task is still queued is waiting.
fn unfinished_for_good(
    points: &[crate::store::PointRow],
    tasks: &[crate::store::TaskRow],
) -> (usize, usize) {
    use crate::store::TaskState;
    let mut latest: HashMap<&str, &crate::store::TaskRow> = HashMap::new();
    for t in tasks {
        let e = latest.entry(t.job_id.as_str()).or_insert(t);
        if (t.submission_id, t.task) > (e.submission_id, e.task) {
            *e = t;
        }
    }
    let (mut failed, mut lost) = (0, 0);
    for p in points.iter().filter(|p| p.status != "done") {
        match latest.get(p.job_id.as_str()).map(|t| t.state) {
            Some(TaskState::Missing | TaskState::Corrupt) => lost += 1,
            Some(TaskState::Submitted) => {}
            _ if p.status == "failed" => failed += 1,
            _ => {}
        }
    }
    (failed, lost)
}

/// `wetgran job run SPEC [--out RESULT]`: runs one job and writes its result record (to
/// standard output without `--out`). A failed job, or a spec that cannot be read, still writes
/// a record (outcome `failed`), so that `sweep collect` can tell a failure from a task that
/// never ran; the job id of an unreadable spec is its file name without `.json`.
pub(super) fn job_run(spec_path: &Path, out: Option<&Path>) -> ExitCode {
    let t0 = std::time::Instant::now();
    if let Some(p) = out {
        let mut outputs = Outputs::new(Protected::none().and("the job spec", spec_path));
        if let Err(e) = outputs.claim("--out", p) {
            return super::common::exit(Err(e.into()));
        }
    }
    let record = |id: &str, o: Outcome| ResultRecord::new(id, o, t0.elapsed().as_secs_f64());
    let (record, code) = match read_spec(spec_path) {
        Err(
            Failure::BadInput(m)
            | Failure::JobsFailed(m)
            | Failure::Other(m)
            | Failure::Interrupted(m),
        ) => {
            eprintln!("error: {}", escape_lines(&m));
            let id = spec_path
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_default();
            let why = format!("the job spec cannot be read: {m}");
            (record(&id, Outcome::Failed(why)), 2)
        }
        Ok(spec) => {
            let id = spec.id();
            match run_job(&spec, &super::common::all_cores(), &mut |_| {}) {
                Ok(r) => (record(&id, Outcome::Done(r)), 0),
                Err(e) => {
                    eprintln!("error: job {id} failed: {}", escape_lines(&e.to_string()));
                    (record(&id, Outcome::Failed(e.to_string())), 1)
                }
            }
        }
    };
    match out {
        Some(p) => {
            if let Err(e) = record.write(p) {
                eprintln!(
                    "error: {}: cannot write the result: {}",
                    p.display(),
                    escape_lines(&e.to_string())
                );
                return ExitCode::from(1);
            }
        }
        None => print_json(&record),
    }
    ExitCode::from(code)
}
