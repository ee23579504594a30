//! Stopping a run from outside it: [`Interrupt`], a set of named flags that another thread, a
//! signal handler (the command line's SIGINT and SIGTERM, `src/cli/signals.rs`) or a binding's
//! Ctrl-C check sets, and that [`super::Prepared::run`] reads after every batch of steps. No GPU
//! twin: the flags are read on the CPU between batches on both backends.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Named stop flags for a run: once one is set, the run stops after the batch of steps under
/// way, flushes the history, writes a checkpoint (when checkpoints are on) and ends with
/// `status = "interrupted"` and the message `interrupted by <cause> at step ...`.
///
/// Clones share the flags, so a clone may be handed to another thread.
///
/// ```
/// use std::sync::atomic::Ordering;
/// let mut interrupt = ricochet::run::Interrupt::new();
/// let stop = interrupt.flag("a stop request");
/// assert_eq!(interrupt.caught(), None);
/// stop.store(true, Ordering::Relaxed);
/// assert_eq!(interrupt.caught(), Some("a stop request"));
/// ```
#[derive(Debug, Clone, Default)]
pub struct Interrupt {
    causes: Vec<(String, Arc<AtomicBool>)>,
}

impl Interrupt {
    /// No flags: a run that nothing stops.
    pub fn new() -> Self {
        Self::default()
    }

    /// A new flag, unset, for `cause` (a signal's name such as `"SIGINT"`, or any words that
    /// complete "interrupted by ..."): set it (from any thread or a signal handler, e.g. with
    /// `signal_hook::flag::register`) to stop the run.
    pub fn flag(&mut self, cause: &str) -> Arc<AtomicBool> {
        let flag = Arc::new(AtomicBool::new(false));
        self.causes.push((cause.to_string(), Arc::clone(&flag)));
        flag
    }

    /// The cause of the first flag that is set, in the order the flags were made; `None` while
    /// none is.
    pub fn caught(&self) -> Option<&str> {
        self.causes
            .iter()
            .find(|(_, f)| f.load(Ordering::Relaxed))
            .map(|(cause, _)| cause.as_str())
    }
}
