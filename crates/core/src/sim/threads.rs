//! How many threads one simulation uses, and the rayon pool it runs on (a pure speed choice:
//! the results do not depend on it, ARCHITECTURE.md, "Threads"). Inside a rayon pool (a
//! benchmark or test that installed one) the engine uses that pool; on a thread where a
//! [`CoreShare`] is entered (the sweep runner's workers), a pool of its share of the cores
//! (`CoreShare::threads_per_job`: the idle workers' cores go to the jobs still running once the
//! queue is empty); elsewhere the process pool of all available cores. [`install`] runs once
//! per `run_until` of the engine, so a job picks up a larger share at its next sample.

use rayon::{ThreadPool, ThreadPoolBuilder};
use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// Cores a simulation process may use: `std::thread::available_parallelism` (1 if unknown),
/// or the environment variable `WETGRAN_THREADS` when it is set to a positive number.
pub fn available_cores() -> usize {
    std::env::var("WETGRAN_THREADS")
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// The cores of a machine shared among the workers of a sweep run (see the module doc).
#[derive(Debug)]
pub struct CoreShare {
    cores: usize,
    workers: usize,
    /// Workers running a job now.
    busy: AtomicUsize,
    /// No job left to claim: the running jobs may take the idle workers' cores.
    drained: AtomicBool,
}

impl CoreShare {
    /// `cores` shared by at most `workers` concurrent jobs.
    pub fn new(cores: usize, workers: usize) -> Arc<Self> {
        Arc::new(Self {
            cores: cores.max(1),
            workers: workers.max(1),
            busy: AtomicUsize::new(0),
            drained: AtomicBool::new(false),
        })
    }

    /// The runner's view: `busy` workers run a job; `drained`: the queue is empty.
    pub fn set(&self, busy: usize, drained: bool) {
        self.busy.store(busy, Ordering::Relaxed);
        self.drained.store(drained, Ordering::Relaxed);
    }

    /// Threads for one running job: `cores / workers` while jobs wait in the queue, else
    /// `cores / busy` (rounded down, so the running jobs never hold more than the cores); at
    /// least 1.
    pub(crate) fn threads_per_job(&self) -> usize {
        let sharers = if self.drained.load(Ordering::Relaxed) {
            self.busy.load(Ordering::Relaxed).clamp(1, self.workers)
        } else {
            self.workers
        };
        (self.cores / sharers).max(1)
    }
}

/// A worker's entry: its share and the pool it last built.
struct Entered {
    share: Arc<CoreShare>,
    /// The worker's number (names its pool threads).
    worker: usize,
    pool: Option<(usize, ThreadPool)>,
}

thread_local! {
    static CURRENT: RefCell<Option<Entered>> = const { RefCell::new(None) };
}

/// Keeps a [`CoreShare`] entered on the current thread; dropping it leaves it (and drops the
/// worker's pool).
#[must_use = "the share is entered only while the guard lives"]
#[derive(Debug)]
pub struct ShareScope(());

impl Drop for ShareScope {
    fn drop(&mut self) {
        CURRENT.with(|c| c.borrow_mut().take());
    }
}

/// Enters `share` as worker `worker` on the current thread (the sweep runner's workers).
pub fn enter(share: &Arc<CoreShare>, worker: usize) -> ShareScope {
    CURRENT.with(|c| {
        *c.borrow_mut() = Some(Entered {
            share: share.clone(),
            worker,
            pool: None,
        })
    });
    ShareScope(())
}

/// The pool of all available cores (threads without an entered share).
fn process_pool() -> &'static ThreadPool {
    static POOL: OnceLock<ThreadPool> = OnceLock::new();
    POOL.get_or_init(|| {
        ThreadPoolBuilder::new()
            .num_threads(available_cores())
            .thread_name(|i| format!("wetgran-sim-{i}"))
            .build()
            .expect("build the simulation thread pool")
    })
}

/// Runs `f` on the pool this thread's simulation should use (see the module doc).
pub fn install<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() {
        return f();
    }
    CURRENT.with(|c| {
        let mut c = c.borrow_mut();
        let Some(e) = c.as_mut() else {
            return process_pool().install(f);
        };
        let want = e.share.threads_per_job();
        if e.pool.as_ref().map(|(n, _)| *n) != Some(want) {
            let w = e.worker;
            let pool = ThreadPoolBuilder::new()
                .num_threads(want)
                .thread_name(move |i| format!("wetgran-job{w}-{i}"))
                .build()
                .expect("build a job thread pool");
            e.pool = Some((want, pool));
        }
        let (_, pool) = e.pool.as_ref().expect("built above");
        pool.install(f)
    })
}

/// A pool of `threads` threads (tests that compare thread counts).
#[cfg(test)]
pub(crate) fn test_pool(threads: usize) -> ThreadPool {
    ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a pool")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_never_exceed_the_cores_and_grow_when_the_queue_drains() {
        let s = CoreShare::new(8, 3);
        s.set(3, false);
        assert_eq!(s.threads_per_job(), 2);
        // Queue empty, two jobs left: 4 threads each; one job left: every core.
        s.set(2, true);
        assert_eq!(s.threads_per_job(), 4);
        s.set(1, true);
        assert_eq!(s.threads_per_job(), 8);
        // Seven cores, two jobs left: 3 each, never more than the cores.
        let s = CoreShare::new(7, 4);
        s.set(2, true);
        assert_eq!(s.threads_per_job(), 3);
        // More workers than cores: one thread each (the user's choice of `--jobs`).
        let s = CoreShare::new(2, 4);
        s.set(4, false);
        assert_eq!(s.threads_per_job(), 1);
    }
}
