//! The cluster commands: `sweep submit --slurm`, `sweep collect`, the Slurm part of
//! `sweep status`, and `job run` (what an array task executes).
//! Exit codes as for the other sweep commands: 0 ok, 2 bad input, 1 any other error; `job run`
//! exits 1 when the job failed (its error record is written all the same).

use super::sweep_cmd::{Failure, load_sweep_left_out, select};
use crate::cluster::slurm::{self, ArrayScript, Queue, SbatchOptions};
use crate::cluster::{Collected, Outcome, ResultRecord, SweepDir, collect, jobs_to_submit};
use crate::run::runner::point_label;
use crate::store::{Store, SweepRow, TaskState};
use crate::sweep::{JobSpec, run_job};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Folder of the sweep directories where `--dir` is not given: beside the database (which a
/// cluster user keeps on the shared filesystem), `<db folder>/wetgran-slurm/<sweep name>`.
pub const DEFAULT_DIR: &str = "wetgran-slurm";

/// `sweep submit` settings.
#[derive(Debug, Clone)]
pub struct Submit {
    pub options: SbatchOptions,
    pub array_limit: Option<usize>,
    pub dry_run: bool,
    pub dir: Option<PathBuf>,
    /// Allow a registered sweep name to get another grid (`--replace`).
    pub replace: bool,
}

fn absolute(p: &Path) -> Result<PathBuf, Failure> {
    std::path::absolute(p)
        .map_err(|e| Failure::Other(format!("{}: cannot make it absolute: {e}", p.display())))
}

/// The sweep directory of `sweep` for the database `db`.
pub fn sweep_dir(db: &Path, sweep: &str, dir: Option<&Path>) -> Result<PathBuf, Failure> {
    match dir {
        Some(d) => absolute(d),
        None => {
            let db = absolute(db)?;
            let parent = db.parent().unwrap_or(Path::new("/"));
            Ok(parent.join(DEFAULT_DIR).join(slurm::file_name(sweep)))
        }
    }
}

/// The first free `array-NNNN` name in the arrays folder.
fn next_array_name(arrays: &Path) -> String {
    (1..)
        .map(|n| format!("array-{n:04}"))
        .find(|name| !arrays.join(format!("{name}.sbatch")).exists())
        .expect("a free name")
}

/// `wetgran sweep submit FILE --slurm`.
pub(super) fn submit(file: &Path, db: &Path, s: &Submit) -> Result<(), Failure> {
    let (sweep, expanded, left_out) = load_sweep_left_out(file)?;
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
    let dir = sweep_dir(db, &sweep.name, s.dir.as_deref())?;
    slurm::check_directive("the sweep directory", &dir.display().to_string())
        .map_err(Failure::BadInput)?;
    for (what, v) in [
        ("--partition", &s.options.partition),
        ("--time", &s.options.time),
    ] {
        if let Some(v) = v {
            slurm::check_directive(what, v).map_err(Failure::BadInput)?;
        }
    }
    let exe = std::env::current_exe()
        .map_err(|e| Failure::Other(format!("cannot find the wetgran executable: {e}")))?;
    let max = slurm::max_array_size();
    let limit = slurm::array_limit(s.array_limit, max);
    let sd = SweepDir::new(&dir);
    // The batch script of an array of `n` tasks whose job ids are listed in `tasks_file`.
    let array_script = |tasks_file: &Path, n: usize| {
        slurm::array_script(&ArrayScript {
            sweep: &sweep.name,
            dir: &dir,
            tasks_file,
            tasks: n,
            wetgran: &exe,
            options: &s.options,
        })
        .map_err(Failure::BadInput)
    };

    if s.dry_run {
        // Nothing is written: the jobs not done in the database (all where there is none).
        let mut ids: Vec<String> = Vec::new();
        for j in &expanded {
            if !ids.contains(&j.id) {
                ids.push(j.id.clone());
            }
        }
        if db.exists() {
            let store = Store::open_existing(db)?;
            let st = store.job_statuses(&ids)?;
            ids.retain(|id| st.get(id).map(String::as_str) != Some("done"));
        }
        let parts = slurm::split(&ids, limit);
        println!(
            "# dry run: {} job(s) to submit as {} array(s) of at most {limit} task(s) ({}); \
             sweep directory {}",
            ids.len(),
            parts.len(),
            match max {
                Some(m) => format!("cluster MaxArraySize {m}"),
                None => "scontrol not available".to_string(),
            },
            dir.display()
        );
        for (k, part) in parts.iter().enumerate() {
            let tasks = sd.arrays().join(format!("array-dryrun-{}.tasks", k + 1));
            let script = array_script(&tasks, part.len())?;
            println!(
                "# ---- array {} of {}: {}",
                k + 1,
                parts.len(),
                tasks.display()
            );
            print!("{script}");
        }
        return Ok(());
    }

    let store = Store::open(db)?;
    if let Ok(old) = store.sweep(&sweep.name) {
        super::sweep_cmd::check_regrid(&store, &old, &sweep, &expanded, s.replace)?;
    }
    let row = store.register_sweep(&sweep, &expanded)?;
    store.set_left_out(row.id, &left_out)?;
    sd.create()
        .map_err(|e| Failure::Other(format!("{}: cannot create: {e}", dir.display())))?;
    // Results already on disk count before anything is submitted again.
    let c = collect(&store, &row, &mut slurm::squeue)?;
    if c.stored.len() + c.failed.len() + c.missing.len() + c.corrupt.len() > 0 {
        eprint!("{}", collected_text(&store, &row, &c)?);
    }
    let ids = jobs_to_submit(&store, &row)?;
    if ids.is_empty() {
        let counts = store.counts(row.id)?;
        eprintln!(
            "sweep {}: nothing to submit ({} job(s) done, {} task(s) still queued or running: \
             `wetgran sweep status --db {}`)",
            row.name,
            counts.done,
            c.waiting.len(),
            db.display()
        );
        return Ok(());
    }
    let specs: HashMap<String, JobSpec> = store
        .points(row.id)?
        .into_iter()
        .map(|p| (p.job_id, p.spec))
        .collect();
    let io = |p: &Path, e: std::io::Error| Failure::Other(format!("{}: {e}", p.display()));
    for id in &ids {
        let spec = &specs[id];
        sd.write_spec(spec).map_err(|e| io(&sd.spec(id), e))?;
        // An earlier task's error record or broken file must not pass for the new task's.
        let old = sd.result(id);
        if old.exists() {
            std::fs::remove_file(&old).map_err(|e| io(&old, e))?;
        }
    }
    let parts = slurm::split(&ids, limit);
    let mut submitted = Vec::new();
    for part in &parts {
        let name = next_array_name(&sd.arrays());
        let tasks = sd.arrays().join(format!("{name}.tasks"));
        let script_path = sd.arrays().join(format!("{name}.sbatch"));
        let script = array_script(&tasks, part.len())?;
        crate::cluster::record::write_atomic(&tasks, (part.join("\n") + "\n").as_bytes())
            .map_err(|e| io(&tasks, e))?;
        crate::cluster::record::write_atomic(&script_path, script.as_bytes())
            .map_err(|e| io(&script_path, e))?;
        let sub = store.record_submission(
            row.id,
            &dir.display().to_string(),
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
                return Err(Failure::Other(format!(
                    "{e}{}",
                    if submitted.is_empty() {
                        String::new()
                    } else {
                        format!(
                            " (arrays {} were submitted; submit again for the rest)",
                            submitted.join(", ")
                        )
                    }
                )));
            }
        }
    }
    eprintln!(
        "sweep {}: {} job(s) submitted as {} array(s) of at most {limit} task(s); sweep directory \
         {}. Watch with `wetgran sweep status --db {db}`, then `wetgran sweep collect --db {db}`",
        row.name,
        ids.len(),
        parts.len(),
        dir.display(),
        db = db.display()
    );
    Ok(())
}

/// Counts one more `key` in a list of (key, count) kept in order of first appearance.
fn count(counts: &mut Vec<(String, usize)>, key: String) {
    match counts.iter_mut().find(|(k, _)| *k == key) {
        Some((_, n)) => *n += 1,
        None => counts.push((key, 1)),
    }
}

/// `3 running, 1 pending`: the counts in their order.
fn counts_text(counts: &[(String, usize)]) -> String {
    counts
        .iter()
        .map(|(s, n)| format!("{n} {s}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The lines `sweep collect` prints for one sweep.
fn collected_text(store: &Store, sweep: &SweepRow, c: &Collected) -> Result<String, Failure> {
    let labels: HashMap<String, String> = store
        .points(sweep.id)?
        .into_iter()
        .map(|p| (p.job_id, point_label(sweep, &p.coords, p.replica)))
        .collect();
    let label = |id: &str| labels.get(id).cloned().unwrap_or_else(|| "?".to_string());
    let mut out = String::new();
    let mut by_state: Vec<(String, usize)> = Vec::new();
    for (_, s) in &c.waiting {
        let s = s.clone().unwrap_or_else(|| "state unknown".to_string());
        count(&mut by_state, s);
    }
    let _ = writeln!(
        out,
        "sweep {}: {} result(s) stored, {} already stored (not stored twice), {} failed, {} \
         corrupt, {} missing, {} waiting{}{}",
        sweep.name,
        c.stored.len(),
        c.duplicates.len(),
        c.failed.len(),
        c.corrupt.len(),
        c.missing.len(),
        c.waiting.len(),
        if by_state.is_empty() {
            String::new()
        } else {
            format!(" ({})", counts_text(&by_state))
        },
        if c.earlier > 0 {
            format!("; {} task(s) collected before", c.earlier)
        } else {
            String::new()
        }
    );
    for (what, list) in [
        ("failed ", &c.failed),
        ("corrupt", &c.corrupt),
        ("missing", &c.missing),
    ] {
        for t in list {
            let _ = writeln!(
                out,
                "  {what} {} (job {}, task {}_{}): {}",
                label(&t.job_id),
                &t.job_id[..12],
                t.slurm_job.as_deref().unwrap_or("?"),
                t.task,
                t.message.as_deref().unwrap_or("")
            );
        }
    }
    if let Some(note) = &c.queue_note {
        let _ = writeln!(
            out,
            "  (the Slurm queue could not be asked: {note}; tasks without a result count as \
             waiting)"
        );
    }
    let again = c.failed.len() + c.corrupt.len() + c.missing.len();
    if again > 0 {
        let _ = writeln!(
            out,
            "  `wetgran sweep submit {} --slurm` submits the {again} failed, corrupt or missing \
             job(s) again",
            sweep.file
        );
    }
    Ok(out)
}

/// `wetgran sweep collect`.
pub(super) fn collect_cmd(db: &Path, name: Option<&str>) -> Result<(), Failure> {
    let store = Store::open_existing(db)?;
    let sweeps = select(&store, name)?;
    let mut any = false;
    for s in &sweeps {
        if store.tasks(s.id)?.is_empty() {
            continue;
        }
        any = true;
        let c = collect(&store, s, &mut slurm::squeue)?;
        print!("{}", collected_text(&store, s, &c)?);
    }
    if !any {
        println!(
            "{}: no submitted tasks to collect (`wetgran sweep submit FILE --slurm` submits a \
             sweep)",
            db.display()
        );
    }
    Ok(())
}

/// The Slurm part of `sweep status` for one sweep (empty when it was never submitted):
/// task states as recorded, and for the tasks not yet collected their state in the queue.
pub fn slurm_status_text(
    store: &Store,
    sweep: &SweepRow,
    queue: &mut dyn FnMut(&str) -> Queue,
) -> Result<String, Failure> {
    let tasks = store.tasks(sweep.id)?;
    if tasks.is_empty() {
        return Ok(String::new());
    }
    let mut arrays: Vec<String> = Vec::new();
    let mut recorded: HashMap<&'static str, usize> = HashMap::new();
    let mut queued: Vec<(String, usize)> = Vec::new();
    let mut queues: HashMap<String, Queue> = HashMap::new();
    let mut unavailable = None;
    for t in &tasks {
        let j = t.slurm_job.clone().unwrap_or_else(|| "?".to_string());
        if !arrays.contains(&j) {
            arrays.push(j.clone());
        }
        *recorded.entry(t.state.as_str()).or_default() += 1;
        if t.state != TaskState::Submitted {
            continue;
        }
        let q = queues.entry(j.clone()).or_insert_with(|| queue(&j)).clone();
        let state = match q {
            Queue::Unavailable(why) => {
                unavailable.get_or_insert(why);
                "state unknown".to_string()
            }
            Queue::Tasks(m) => match m.get(&t.task) {
                Some(s) => s.clone(),
                None => {
                    if SweepDir::new(Path::new(&t.dir)).result(&t.job_id).exists() {
                        "finished, not collected".to_string()
                    } else {
                        "left the queue without a result".to_string()
                    }
                }
            },
        };
        count(&mut queued, state);
    }
    let mut out = String::new();
    let order = [
        "submitted",
        "collected",
        "duplicate",
        "failed",
        "missing",
        "corrupt",
    ];
    let _ = writeln!(
        out,
        "  slurm  {} task(s) in {} array(s) (job {}): {}",
        tasks.len(),
        arrays.len(),
        arrays.join(", "),
        order
            .iter()
            .filter_map(|s| recorded.get(s).map(|n| format!("{n} {s}")))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if !queued.is_empty() {
        let _ = writeln!(out, "         not collected yet: {}", counts_text(&queued));
    }
    if let Some(why) = unavailable {
        let _ = writeln!(out, "         (no Slurm queue to ask: {why})");
    }
    Ok(out)
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

/// `wetgran job run SPEC [--out RESULT]`: runs one job and writes its result record (to
/// standard output without `--out`). A failed job, or a spec that cannot be read, still writes
/// a record (outcome `failed`), so that `sweep collect` can tell a failure from a task that
/// never ran; the job id of an unreadable spec is its file name without `.json`.
pub fn job_run(spec_path: &Path, out: Option<&Path>) -> ExitCode {
    let t0 = std::time::Instant::now();
    let (record, code) = match read_spec(spec_path) {
        Err(Failure::BadInput(m) | Failure::Other(m)) => {
            eprintln!("error: {m}");
            let id = spec_path
                .file_stem()
                .map(|s| s.to_string_lossy().to_string())
                .unwrap_or_default();
            (
                ResultRecord::new(
                    &id,
                    Outcome::Failed(format!("the job spec cannot be read: {m}")),
                    t0.elapsed().as_secs_f64(),
                ),
                2,
            )
        }
        Ok(spec) => {
            let id = spec.id();
            match run_job(&spec, &mut |_| {}) {
                Ok(r) => (
                    ResultRecord::new(&id, Outcome::Done(r), t0.elapsed().as_secs_f64()),
                    0,
                ),
                Err(e) => {
                    eprintln!("error: job {id} failed: {e}");
                    (
                        ResultRecord::new(
                            &id,
                            Outcome::Failed(e.to_string()),
                            t0.elapsed().as_secs_f64(),
                        ),
                        1,
                    )
                }
            }
        }
    };
    match out {
        Some(p) => {
            if let Err(e) = record.write(p) {
                eprintln!("error: {}: cannot write the result: {e}", p.display());
                return ExitCode::from(1);
            }
        }
        None => println!(
            "{}",
            serde_json::to_string_pretty(&record).expect("serializes")
        ),
    }
    ExitCode::from(code)
}
