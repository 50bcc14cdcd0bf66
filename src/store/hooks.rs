//! A hook the caller gives the store ([`Store::with_write_hook`]): a function called at named
//! points inside the store's write transactions, after their rows are written and before the
//! commit, so that the caller can watch or stop the process exactly there (the crash tests kill
//! a child process at each point, `tests/crash_torture.rs`). Without a hook nothing is called.

use super::Store;
use std::fmt;
use std::sync::Arc;

/// A point inside a write transaction of the store.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WritePoint {
    /// A finished or extended job's result and checkpoint rows are written, the transaction
    /// not committed.
    Checkpoint,
    /// An extension's old result is deleted, the new one not written yet.
    Extend,
    /// A refinement round's jobs are inserted, the transaction not committed.
    Refine,
    /// Another thousand of a sweep's jobs are inserted, its registration not committed.
    Register,
}

impl WritePoint {
    /// Every point, in the order of the variants.
    pub const ALL: [WritePoint; 4] = [
        WritePoint::Checkpoint,
        WritePoint::Extend,
        WritePoint::Refine,
        WritePoint::Register,
    ];

    /// The point's name: `checkpoint`, `extend`, `refine` or `register`.
    pub fn name(self) -> &'static str {
        match self {
            WritePoint::Checkpoint => "checkpoint",
            WritePoint::Extend => "extend",
            WritePoint::Refine => "refine",
            WritePoint::Register => "register",
        }
    }
}

/// The function a store calls at every [`WritePoint`] (on the thread that owns the store).
#[derive(Clone)]
pub struct WriteHook(Arc<dyn Fn(WritePoint) + Send + Sync>);

impl WriteHook {
    pub fn new(f: impl Fn(WritePoint) + Send + Sync + 'static) -> Self {
        Self(Arc::new(f))
    }
}

impl fmt::Debug for WriteHook {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("WriteHook")
    }
}

impl Store {
    /// The store with `hook` called at every [`WritePoint`] of its write transactions.
    pub fn with_write_hook(mut self, hook: Option<WriteHook>) -> Store {
        self.write_hook = hook;
        self
    }

    /// Calls the write hook, if any, at `point`.
    pub(super) fn reached(&self, point: WritePoint) {
        if let Some(hook) = &self.write_hook {
            (hook.0)(point);
        }
    }
}
