//! Collection: reads the result files of a sweep's submitted tasks into the database.
//!
//! Idempotent: only tasks still marked `submitted` are looked at, and a result whose job already
//! has one (the same content-hashed job finished by two tasks, or by a local run) is not stored
//! again (`duplicate`). Per task, the file `results/<job id>.json` gives:
//! - a result: stored, task `collected` (or `duplicate`);
//! - an error record: the job is marked failed with its message, task `failed`;
//! - unreadable, another format, or another job's record: task `corrupt`, job left pending;
//! - no file: the task is `missing` when Slurm no longer has it queued (killed at its time or
//!   memory limit, node failure, cancelled); while it is queued, or where the queue cannot be
//!   asked, it stays `submitted` (waiting). A missing task's file is looked for again at every
//!   collection (a network filesystem may show a new file late).
//!
//! Missing, failed and corrupt tasks are what the next `sweep submit` submits again.

use super::record::{Outcome, ResultRecord, SweepDir};
use super::slurm::Queue;
use crate::store::{Store, StoreError, SweepRow, TaskRow, TaskState};
use std::collections::HashMap;
use std::path::Path;

/// What one collection did, task by task.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Collected {
    /// Results stored now.
    pub stored: Vec<TaskRow>,
    /// Results of jobs that already had one (not stored again).
    pub duplicates: Vec<TaskRow>,
    /// Error records (`message` holds the error).
    pub failed: Vec<TaskRow>,
    /// Unreadable result files (`message` holds why).
    pub corrupt: Vec<TaskRow>,
    /// No result and no longer queued.
    pub missing: Vec<TaskRow>,
    /// No result yet, with the Slurm state (`None`: the queue could not be asked).
    pub waiting: Vec<(TaskRow, Option<String>)>,
    /// Tasks collected by an earlier call (nothing done).
    pub earlier: usize,
    /// Why the queue could not be asked, if it could not.
    pub queue_note: Option<String>,
}

/// Collects the tasks of `sweep`; `queue(array_job)` asks Slurm for the queued tasks of an
/// array (asked once per array).
pub fn collect(
    store: &Store,
    sweep: &SweepRow,
    queue: &mut dyn FnMut(&str) -> Queue,
) -> Result<Collected, StoreError> {
    let mut out = Collected::default();
    let tasks = store.tasks(sweep.id)?;
    // The queue is asked before any result file is read: a task it no longer lists had ended
    // before, so a result it wrote is there for the reads below (no task is judged missing
    // because it finished between the read and the question).
    let mut queues: HashMap<String, Queue> = HashMap::new();
    for t in &tasks {
        if t.state == TaskState::Submitted
            && let Some(j) = &t.slurm_job
            && !queues.contains_key(j)
        {
            queues.insert(j.clone(), queue(j));
        }
    }
    let mut batch = Vec::new();
    for task in tasks {
        // A missing task is looked at again: its file may show up late (a network filesystem's
        // cache can hide a new file for a while).
        let recheck = task.state == TaskState::Missing;
        if task.state != TaskState::Submitted && !recheck {
            out.earlier += 1;
            continue;
        }
        let dir = SweepDir::new(Path::new(&task.dir));
        let path = dir.result(&task.job_id);
        let record = match ResultRecord::read(&path, &task.job_id) {
            Ok(None) if recheck => {
                out.earlier += 1;
                continue;
            }
            Ok(r) => r,
            Err(reason) => {
                let msg = format!("{}: {reason}", path.display());
                out.corrupt
                    .push(mark(store, task, TaskState::Corrupt, msg)?);
                continue;
            }
        };
        let Some(record) = record else {
            // No result yet: still queued?
            let state = match &task.slurm_job {
                None => Queue::Unavailable("sbatch gave no job id".to_string()),
                Some(j) => queues[j].clone(),
            };
            match state {
                Queue::Unavailable(why) => {
                    out.queue_note.get_or_insert(why);
                    out.waiting.push((task, None));
                }
                Queue::Tasks(tasks) => match tasks.get(&task.task) {
                    Some(s) => out.waiting.push((task, Some(s.clone()))),
                    None => {
                        let msg = format!(
                            "no result file and no longer in the Slurm queue: the task was \
                             killed (time or memory limit, node failure, scancel) or crashed; \
                             see {}/logs/{}_{}.out",
                            task.dir,
                            task.slurm_job.as_deref().unwrap_or("?"),
                            task.task
                        );
                        out.missing
                            .push(mark(store, task, TaskState::Missing, msg)?);
                    }
                },
            }
            continue;
        };
        let owner = record.owner();
        match &record.outcome {
            Outcome::Done(_) => {
                batch.push((task, record, owner));
                if batch.len() >= BATCH {
                    store_batch(store, &mut batch, &mut out)?;
                }
            }
            Outcome::Failed(message) => {
                // The results read before are stored first, in task order, as one by one.
                store_batch(store, &mut batch, &mut out)?;
                store.ingest_failure(
                    &task.job_id,
                    message,
                    record.wall_seconds,
                    &owner,
                    record.finished_at,
                )?;
                out.failed
                    .push(mark(store, task, TaskState::Failed, message.clone())?);
            }
        }
    }
    store_batch(store, &mut batch, &mut out)?;
    Ok(out)
}

/// Records `state` with its message for `task`; returns the task as recorded.
fn mark(
    store: &Store,
    mut task: TaskRow,
    state: TaskState,
    message: String,
) -> Result<TaskRow, StoreError> {
    store.set_task_state(task.submission_id, task.task, state, Some(&message))?;
    task.state = state;
    task.message = Some(message);
    Ok(task)
}

/// Results stored per transaction by [`collect`]: one synced commit for this many tasks
/// instead of two per task.
const BATCH: usize = 256;

/// Stores the results of `batch` (tasks whose record is a result, with its owner) and their
/// task states in one transaction (`Store::ingest_results`), files each task under stored or
/// duplicates, and empties the batch.
fn store_batch(
    store: &Store,
    batch: &mut Vec<(TaskRow, ResultRecord, String)>,
    out: &mut Collected,
) -> Result<(), StoreError> {
    if batch.is_empty() {
        return Ok(());
    }
    let items: Vec<_> = batch
        .iter()
        .filter_map(|(t, r, owner)| match &r.outcome {
            Outcome::Done(result) => Some((
                t.job_id.as_str(),
                result,
                owner.as_str(),
                r.finished_at,
                t.submission_id,
                t.task,
            )),
            Outcome::Failed(_) => None,
        })
        .collect();
    let kept = store.ingest_results(&items)?;
    for ((mut task, _, _), kept) in batch.drain(..).zip(kept) {
        if kept {
            task.state = TaskState::Collected;
            out.stored.push(task);
        } else {
            task.state = TaskState::Duplicate;
            out.duplicates.push(task);
        }
    }
    Ok(())
}

/// The jobs of `sweep` to submit (again): every job that is not done, unless a task of it is
/// still waiting (submitted, not collected). In grid order, each job once.
pub fn jobs_to_submit(store: &Store, sweep: &SweepRow) -> Result<Vec<String>, StoreError> {
    let waiting: std::collections::HashSet<String> = store
        .tasks(sweep.id)?
        .into_iter()
        .filter(|t| t.state == TaskState::Submitted)
        .map(|t| t.job_id)
        .collect();
    let mut seen = std::collections::HashSet::new();
    Ok(store
        .points(sweep.id)?
        .into_iter()
        .filter(|p| p.status != "done" && !waiting.contains(&p.job_id))
        .filter(|p| seen.insert(p.job_id.clone()))
        .map(|p| p.job_id)
        .collect())
}

/// Where the tasks not collected yet stand, for `sweep status`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct QueueStates {
    /// One per task still marked `submitted`, in task order: its state in the Slurm queue,
    /// `finished, not collected`, `left the queue without a result` or `state unknown`.
    pub states: Vec<String>,
    /// Why the queue could not be asked (the first answer that said so).
    pub unavailable: Option<String>,
}

/// Asks the queue (once per Slurm job) where each task still marked `submitted` stands; a task
/// that left the queue is told apart by its result file.
pub fn queue_states(tasks: &[TaskRow], queue: &mut dyn FnMut(&str) -> Queue) -> QueueStates {
    let mut out = QueueStates::default();
    let mut queues: HashMap<String, Queue> = HashMap::new();
    for t in tasks {
        if t.state != TaskState::Submitted {
            continue;
        }
        let j = t.slurm_job.clone().unwrap_or_else(|| "?".to_string());
        let q = queues.entry(j.clone()).or_insert_with(|| queue(&j)).clone();
        let state = match q {
            Queue::Unavailable(why) => {
                out.unavailable.get_or_insert(why);
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
        out.states.push(state);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::{JobResult, SweepFile};

    /// A database with a registered sweep of four jobs (one with its spec twice: two grid
    /// points, temperature 1 and 1.0, share it) and a sweep directory.
    fn setup(dir: &Path) -> (Store, SweepRow, Vec<String>, SweepDir) {
        let text = "[sweep]\nname = \"c\"\n[scene]\ndimension = 2\n[scene.box]\n\
                    size = [8.0, 4.0]\n[scene.particles]\ncount = 4\n[scene.initial]\n\
                    temperature = 1.0\n[scene.run]\nduration = 1.0\n[[axis]]\n\
                    key = \"initial.temperature\"\nvalues = [1, 2, 3, 4, 1.0]\n";
        let file = SweepFile::parse(text, &dir.join("c.toml")).unwrap();
        let jobs = file.expand().unwrap();
        let store = Store::open(&dir.join("w.sqlite")).unwrap();
        let sweep = store.register_sweep(&file, &jobs).unwrap();
        let ids = jobs_to_submit(&store, &sweep).unwrap();
        // Five points, four distinct jobs.
        assert_eq!(ids.len(), 4);
        let sd = SweepDir::new(&dir.join("cluster"));
        sd.create().unwrap();
        (store, sweep, ids, sd)
    }

    fn result(x: f64) -> JobResult {
        JobResult {
            checkpoint: None,
            phase: Some("g".to_string()),
            decided_on: None,
            observables: serde_json::json!({ "x": x }),
            simulated_time: 1.0,
            wall_seconds: 0.2,
            events: 7,
        }
    }

    fn submit(store: &Store, sweep: &SweepRow, sd: &SweepDir, ids: &[String], job: &str) -> i64 {
        let s = store
            .record_submission(sweep.id, &sd.root.display().to_string(), "x.sbatch", ids)
            .unwrap();
        store.set_slurm_job(s, job).unwrap();
        s
    }

    fn done(sd: &SweepDir, id: &str, x: f64) {
        ResultRecord::new(id, Outcome::Done(result(x)), 0.2)
            .write(&sd.result(id))
            .unwrap();
    }

    /// A queue in which nothing is left.
    fn empty(_: &str) -> Queue {
        Queue::Tasks(HashMap::new())
    }

    #[test]
    fn results_are_stored_once_however_often_they_are_collected() {
        let dir = tempfile::tempdir().unwrap();
        let (store, sweep, ids, sd) = setup(dir.path());
        // Job 0 is in two arrays (submitted twice), so two tasks bring the same result.
        submit(&store, &sweep, &sd, &ids, "100");
        submit(&store, &sweep, &sd, &ids[..1], "101");
        for (k, id) in ids.iter().enumerate() {
            done(&sd, id, k as f64);
        }
        let c = collect(&store, &sweep, &mut empty).unwrap();
        assert_eq!(c.stored.len(), 4);
        assert_eq!(c.duplicates.len(), 1);
        assert_eq!(c.duplicates[0].job_id, ids[0]);
        assert!(c.missing.is_empty() && c.corrupt.is_empty() && c.failed.is_empty());
        // Five points (two share a job): all done, one result row per job.
        let counts = store.counts(sweep.id).unwrap();
        assert_eq!((counts.done, counts.pending), (5, 0));
        let runs = store.runs_per_job().unwrap();
        assert_eq!(runs.len(), 4);
        assert!(runs.iter().all(|(_, n)| *n == 1), "{runs:?}");
        // The stored observables are the files' (point order: temperatures 1, 2, 3, 4, 1).
        let xs: Vec<f64> = store
            .points(sweep.id)
            .unwrap()
            .iter()
            .map(|p| p.observables.as_ref().unwrap()["x"].as_f64().unwrap())
            .collect();
        assert_eq!(xs, [0.0, 1.0, 2.0, 3.0, 0.0]);
        assert_eq!(
            store.points(sweep.id).unwrap()[0].result_owner.as_deref(),
            Some(
                ResultRecord::new("", Outcome::Failed(String::new()), 0.0)
                    .owner()
                    .as_str()
            )
        );
        // A second collection finds nothing to do and changes nothing.
        let again = collect(&store, &sweep, &mut empty).unwrap();
        assert_eq!(again.earlier, 5);
        assert!(again.stored.is_empty() && again.duplicates.is_empty());
        assert_eq!(store.runs_per_job().unwrap(), runs);
        // Nothing is left to submit.
        assert!(jobs_to_submit(&store, &sweep).unwrap().is_empty());
    }

    /// Truncated, empty, binary, foreign (another program's JSON, another job's or version's
    /// record, a record whose result wetgran never writes) result files: each task reported
    /// corrupt with the file and the reason, nothing stored, the job still pending and
    /// submitted again.
    #[test]
    fn truncated_and_foreign_result_files_are_reported_never_stored() {
        let dir = tempfile::tempdir().unwrap();
        let (store, sweep, ids, sd) = setup(dir.path());
        // Four jobs: one record of each bad kind per collection round, in two rounds.
        let record = |id: &str, res: JobResult| {
            serde_json::to_string(&ResultRecord::new(id, Outcome::Done(res), 0.2)).unwrap()
        };
        let with = |f: &dyn Fn(&mut JobResult)| {
            let mut r = result(1.0);
            f(&mut r);
            r
        };
        let good = record(&ids[0], result(1.0));
        let cases: Vec<(String, &str)> = vec![
            (good[..good.len() / 2].to_string(), "not a result record"),
            (String::new(), "not a result record"),
            (
                "\u{0}\u{1}binary\u{fffd}".to_string(),
                "not a result record",
            ),
            (
                r#"{"job_id": "x", "result": {"phase": "g"}}"#.to_string(),
                "not a result record",
            ),
            (record("0123abcd", result(1.0)), "not this file's job"),
            (
                record(&ids[0], result(1.0)).replace("\"format\":1", "\"format\":7"),
                "record format 7",
            ),
            (
                record(&ids[0], with(&|r| r.phase = Some("banana".into()))),
                "unknown phase label `banana`",
            ),
            (
                record(
                    &ids[0],
                    with(&|r| r.observables = serde_json::json!([1, 2])),
                ),
                "observables are not a JSON object",
            ),
            (
                record(&ids[0], with(&|r| r.simulated_time = -1.0)),
                "not finite non-negative",
            ),
            (
                record(
                    &ids[0],
                    with(&|r| r.decided_on = Some(serde_json::json!(3))),
                ),
                "decision numbers are not a JSON object",
            ),
        ];
        for (k, (text, why)) in cases.iter().enumerate() {
            submit(&store, &sweep, &sd, &ids[..1], &format!("{}", 400 + k));
            let path = sd.result(&ids[0]);
            std::fs::write(&path, text).unwrap();
            let c = collect(&store, &sweep, &mut empty).unwrap();
            assert!(c.stored.is_empty() && c.duplicates.is_empty(), "case {k}");
            assert_eq!(c.corrupt.len(), 1, "case {k}: {c:?}");
            let msg = c.corrupt[0].message.clone().unwrap();
            assert!(msg.starts_with(&path.display().to_string()), "{msg}");
            assert!(msg.contains(why), "case {k}: {msg}");
            assert_eq!(store.job_statuses(&ids).unwrap()[&ids[0]], "pending");
            assert_eq!(jobs_to_submit(&store, &sweep).unwrap()[0], ids[0]);
        }
        assert!(store.runs_per_job().unwrap().is_empty(), "nothing stored");
        // The good record is stored.
        submit(&store, &sweep, &sd, &ids[..1], "499");
        std::fs::write(sd.result(&ids[0]), good).unwrap();
        assert_eq!(collect(&store, &sweep, &mut empty).unwrap().stored.len(), 1);
    }

    #[test]
    fn a_task_finishing_while_the_queue_is_asked_is_not_missing() {
        let dir = tempfile::tempdir().unwrap();
        let (store, sweep, ids, sd) = setup(dir.path());
        submit(&store, &sweep, &sd, &ids[..1], "300");
        // The task writes its result and leaves the queue just as the queue is asked.
        let mut finishing = |_: &str| {
            done(&sd, &ids[0], 9.0);
            Queue::Tasks(HashMap::new())
        };
        let c = collect(&store, &sweep, &mut finishing).unwrap();
        assert!(c.missing.is_empty(), "{:?}", c.missing);
        assert_eq!(c.stored.len(), 1);
    }

    #[test]
    fn a_partial_collection_reports_waiting_missing_failed_and_corrupt_tasks() {
        let dir = tempfile::tempdir().unwrap();
        let (store, sweep, ids, sd) = setup(dir.path());
        submit(&store, &sweep, &sd, &ids, "200");
        // Task 0: a result. Task 1: an error record. Task 2: a file cut in half. Task 3: no
        // file; first still running, then gone from the queue.
        done(&sd, &ids[0], 1.0);
        ResultRecord::new(
            &ids[1],
            Outcome::Failed("numerical guard: boom".into()),
            0.1,
        )
        .write(&sd.result(&ids[1]))
        .unwrap();
        done(&sd, &ids[2], 2.0);
        let text = std::fs::read_to_string(sd.result(&ids[2])).unwrap();
        std::fs::write(sd.result(&ids[2]), &text[..text.len() - 20]).unwrap();
        let mut asked = Vec::new();
        let mut running = |j: &str| {
            asked.push(j.to_string());
            Queue::Tasks(HashMap::from([(3, "RUNNING".to_string())]))
        };
        let c = collect(&store, &sweep, &mut running).unwrap();
        assert_eq!(asked, ["200"], "the queue is asked once per array");
        assert_eq!(c.stored.len(), 1);
        assert_eq!(c.failed.len(), 1);
        assert_eq!(
            c.failed[0].message.as_deref(),
            Some("numerical guard: boom")
        );
        assert_eq!(c.corrupt.len(), 1);
        assert!(
            c.corrupt[0]
                .message
                .as_deref()
                .unwrap()
                .contains("not a result record"),
            "{:?}",
            c.corrupt[0]
        );
        assert_eq!(c.waiting.len(), 1);
        assert_eq!(c.waiting[0].1.as_deref(), Some("RUNNING"));
        assert!(c.missing.is_empty());
        // The failure is in the job row; the corrupt job is still pending.
        let statuses = store.job_statuses(&ids).unwrap();
        assert_eq!(statuses[&ids[0]], "done");
        assert_eq!(statuses[&ids[1]], "failed");
        assert_eq!(statuses[&ids[2]], "pending");
        assert_eq!(statuses[&ids[3]], "pending");
        // Submitting again now: the failed and the corrupt job, not the running one.
        assert_eq!(
            jobs_to_submit(&store, &sweep).unwrap(),
            [ids[1].clone(), ids[2].clone()]
        );
        // Without a queue to ask, a task without result keeps waiting (it may still run).
        let mut none = |_: &str| Queue::Unavailable("no squeue".to_string());
        let c = collect(&store, &sweep, &mut none).unwrap();
        assert_eq!(c.waiting.len(), 1);
        assert_eq!(c.waiting[0].1, None);
        assert_eq!(c.queue_note.as_deref(), Some("no squeue"));
        // The task left the queue without a result: missing, and submitted again.
        let c = collect(&store, &sweep, &mut empty).unwrap();
        assert_eq!(c.missing.len(), 1);
        assert!(
            c.missing[0]
                .message
                .as_deref()
                .unwrap()
                .contains("logs/200_3.out")
        );
        assert_eq!(
            jobs_to_submit(&store, &sweep).unwrap(),
            [ids[1].clone(), ids[2].clone(), ids[3].clone()]
        );
        // Still no file: nothing changes.
        let c = collect(&store, &sweep, &mut empty).unwrap();
        assert!(c.missing.is_empty() && c.stored.is_empty());
        assert_eq!(c.earlier, 4);
        // Its file shows up late: stored after all.
        done(&sd, &ids[3], 3.0);
        let c = collect(&store, &sweep, &mut empty).unwrap();
        assert_eq!(c.stored.len(), 1);
        assert_eq!(c.stored[0].job_id, ids[3]);
        assert_eq!(
            jobs_to_submit(&store, &sweep).unwrap(),
            [ids[1].clone(), ids[2].clone()]
        );
        // The resubmitted tasks succeed: everything is stored, the failed job is done.
        submit(&store, &sweep, &sd, &ids[1..3], "201");
        for id in &ids[1..3] {
            done(&sd, id, 5.0);
        }
        let c = collect(&store, &sweep, &mut empty).unwrap();
        assert_eq!(c.stored.len(), 2);
        let counts = store.counts(sweep.id).unwrap();
        assert_eq!((counts.done, counts.failed, counts.pending), (5, 0, 0));
        // The failed attempt stays on record: two runs for that job.
        let runs: HashMap<String, i64> = store.runs_per_job().unwrap().into_iter().collect();
        assert_eq!(runs[&ids[1]], 2);
        assert_eq!(runs[&ids[0]], 1);
    }
}
