//! The threads one simulation may use: a [`Threads`] value its caller chooses and passes in
//! (the sweep runner gives each job its share of the cores, `wetgran simulate` all of them). A
//! pure speed choice: the results do not depend on it (ARCHITECTURE.md, "Threads"). The run
//! executes the engine's steps, the wall-table fill and the observers on that pool.

use rayon::{ThreadPool, ThreadPoolBuilder};
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

/// A pool of threads for one run (cloning shares the pool). The pool's threads start when the
/// run first uses them.
#[derive(Debug, Clone)]
pub struct Threads {
    count: usize,
    pool: Arc<OnceLock<ThreadPool>>,
}

impl Default for Threads {
    /// One thread.
    fn default() -> Self {
        Self::new(1)
    }
}

impl Threads {
    /// A pool of `count` threads (at least 1).
    pub fn new(count: usize) -> Self {
        Self {
            count: count.max(1),
            pool: Arc::new(OnceLock::new()),
        }
    }

    /// Threads in the pool.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Runs `f` on the pool (inside `f`, rayon's parallel loops use its threads).
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        let count = self.count;
        self.pool
            .get_or_init(|| {
                ThreadPoolBuilder::new()
                    .num_threads(count)
                    .thread_name(|i| format!("wetgran-sim-{i}"))
                    .build()
                    .expect("build a simulation thread pool")
            })
            .install(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_on_threads_sees_exactly_their_count() {
        for n in [1, 3] {
            let t = Threads::new(n);
            assert_eq!(t.install(rayon::current_num_threads), n);
            // A clone shares the pool.
            assert_eq!(t.clone().install(rayon::current_num_threads), n);
        }
        assert_eq!(Threads::new(0).count(), 1);
    }
}
