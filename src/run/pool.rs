//! The worker pool of every run (`sweep run`/`resume`, refinement rounds, `sweep resume
//! --extend`): worker threads that each run one job at a time, synchronously, and a calling
//! thread that claims jobs, hands them out and commits each finished one on its own.
//!
//! Only the calling thread talks to the store; workers receive claimed jobs over a channel and
//! send back progress and outcomes. Between messages the calling thread refreshes the heartbeat
//! of the running jobs every `store::HEARTBEAT_INTERVAL`. What a run claims and how it commits
//! is its [`Queue`]: the sweep queue of the store (`runner`), or the unconverged finished jobs
//! to extend from their checkpoints (`extend`).
//!
//! The pool owns the wall-table cache of its jobs (`table` wall solver): one bounded
//! [`TableCache`] per run, capped by `table_cache_mib`, handed to every job in its
//! [`RunSettings`] and dropped with the run, so a sweep over many drives keeps at most the cap
//! in cached tables (plus the two tables each running job holds).
//!
//! The pool also shares the machine's cores among its jobs: each job runs in a [`RunSettings`]
//! whose [`Threads`] are its share, `cores / workers` (at least one; `sim::threads`), and whose
//! hook is the run's (`on_extend`).

use super::progress::Progress;
use crate::store::{HEARTBEAT_INTERVAL, Store, StoreError};
use std::sync::{Arc, mpsc};
use std::thread;
use std::time::{Duration, Instant};
use wetgran_core::sim::event_driven::table_cache::TableCache;
use wetgran_core::sim::threads::{self, Threads};
use wetgran_core::sim::{ExtendHook, RunSettings};

/// What a run claims and how it stores what its workers return.
pub(crate) trait Queue {
    /// A claimed job, as a worker receives it.
    type Job: Send + 'static;
    /// What a worker returns for a job.
    type Outcome: Send + 'static;
    /// Claims the next job and its label for the progress display; `None` when none is
    /// claimable now (one may become claimable when a running job ends).
    fn claim(
        &mut self,
        store: &Store,
        progress: &mut Progress,
    ) -> Result<Option<(Self::Job, String)>, StoreError>;
    /// Commits a finished job (`wall`: seconds its worker ran it); returns the line the
    /// progress display prints for it.
    fn commit(
        &mut self,
        store: &Store,
        job: Self::Job,
        outcome: Self::Outcome,
        wall: f64,
    ) -> Result<String, StoreError>;
}

/// What a worker calls to run one job, with the run's settings (the shared table cache) and a
/// progress callback taking the fraction done.
pub(crate) type Work<Q> = Arc<
    dyn Fn(&<Q as Queue>::Job, &RunSettings, &mut dyn FnMut(f64)) -> <Q as Queue>::Outcome
        + Send
        + Sync,
>;

/// The run's wall-table cache at its end: tables built, and the most bytes held at once.
pub(crate) struct TableStats {
    pub(crate) built: u64,
    pub(crate) peak_bytes: usize,
}

enum Msg<J, O> {
    Progress(usize, f64),
    Finished(usize, Box<J>, O, f64),
}

/// Runs the jobs of `queue` on `n_workers` threads until it has none left and none is running;
/// `on_extend` is every job's hook (`RunSettings::on_extend`).
pub(crate) fn run_queue<Q: Queue>(
    store: &Store,
    queue: &mut Q,
    n_workers: usize,
    table_cache_mib: usize,
    on_extend: Option<ExtendHook>,
    progress: &mut Progress,
    work: Work<Q>,
) -> Result<TableStats, StoreError> {
    let n_workers = n_workers.max(1);
    let (msg_tx, msg_rx) = mpsc::channel::<Msg<Q::Job, Q::Outcome>>();
    let tables = TableCache::with_cap_mib(table_cache_mib);
    let settings = RunSettings {
        threads: Threads::new(threads::available_cores() / n_workers),
        on_extend,
        ..RunSettings::new(tables.clone())
    };
    let (job_tx, handles) = spawn_workers::<Q>(n_workers, &msg_tx, &settings, &work);
    drop(msg_tx);

    let mut idle: Vec<usize> = (0..n_workers).rev().collect();
    let mut busy = 0usize;
    let mut last_beat = Instant::now();
    let outcome = (|| -> Result<(), StoreError> {
        loop {
            while let Some(&w) = idle.last() {
                // None: nothing claimable now (a continuation job may become claimable when
                // its predecessor ends).
                let Some((job, label)) = queue.claim(store, progress)? else {
                    break;
                };
                idle.pop();
                progress.start(w, &label);
                job_tx[w].send(job).expect("worker alive");
                busy += 1;
            }
            if busy == 0 {
                return Ok(());
            }
            let wait = HEARTBEAT_INTERVAL.saturating_sub(last_beat.elapsed());
            match msg_rx.recv_timeout(wait.max(Duration::from_millis(10))) {
                Ok(Msg::Progress(w, f)) => progress.update(w, f),
                Ok(Msg::Finished(w, job, result, wall)) => {
                    let line = queue.commit(store, *job, result, wall)?;
                    progress.finish(w, &line);
                    idle.push(w);
                    busy -= 1;
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(StoreError::Db {
                        path: store.path().display().to_string(),
                        detail: "all worker threads stopped".to_string(),
                    });
                }
            }
            if last_beat.elapsed() >= HEARTBEAT_INTERVAL {
                store.heartbeat()?;
                last_beat = Instant::now();
            }
        }
    })();
    drop(job_tx);
    if outcome.is_ok() {
        for h in handles {
            let _ = h.join();
        }
    }
    progress.close();
    outcome?;
    Ok(TableStats {
        built: tables.builds(),
        peak_bytes: tables.peak_bytes(),
    })
}

/// Handles of the workers and the channels that hand each its jobs.
type Workers<J> = (Vec<mpsc::Sender<J>>, Vec<thread::JoinHandle<()>>);

/// Starts `n_workers` worker threads, each running its jobs with settings like `settings` (the
/// run's table cache and hook) on threads of its own.
fn spawn_workers<Q: Queue>(
    n_workers: usize,
    msg_tx: &mpsc::Sender<Msg<Q::Job, Q::Outcome>>,
    settings: &RunSettings,
    work: &Work<Q>,
) -> Workers<Q::Job> {
    let mut job_tx = Vec::new();
    let mut handles = Vec::new();
    for w in 0..n_workers {
        let (tx, rx) = mpsc::channel::<Q::Job>();
        job_tx.push(tx);
        let out = msg_tx.clone();
        let settings = RunSettings {
            threads: Threads::new(settings.threads.count()),
            ..settings.clone()
        };
        let work = work.clone();
        handles.push(
            thread::Builder::new()
                .name(format!("wetgran-worker-{w}"))
                .spawn(move || worker::<Q>(w, rx, out, &settings, work))
                .expect("spawn a worker thread"),
        );
    }
    (job_tx, handles)
}

/// A worker: runs every job it receives and reports back.
fn worker<Q: Queue>(
    w: usize,
    jobs: mpsc::Receiver<Q::Job>,
    out: mpsc::Sender<Msg<Q::Job, Q::Outcome>>,
    settings: &RunSettings,
    work: Work<Q>,
) {
    while let Ok(job) = jobs.recv() {
        let t0 = Instant::now();
        let mut last = -1.0;
        let mut report = |f: f64| {
            // At most one message per percent.
            if f - last >= 0.01 || f >= 1.0 {
                last = f;
                let _ = out.send(Msg::Progress(w, f));
            }
        };
        let outcome = work(&job, settings, &mut report);
        let wall = t0.elapsed().as_secs_f64();
        if out
            .send(Msg::Finished(w, Box::new(job), outcome, wall))
            .is_err()
        {
            return;
        }
    }
}
