//! SIGINT and SIGTERM during `ricochet run`: each sets its flag of the run's
//! [`ricochet::run::Interrupt`], which the run reads after every batch of steps (it then flushes
//! the history and writes `summary.json` with status "interrupted"); a second signal of the same
//! kind ends the process at once.

use std::sync::Arc;

use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::flag;

use ricochet::run::Interrupt;

/// The signals caught: (number, name, exit status 128 + number), in the order a run reads them.
const CAUGHT: [(i32, &str, u8); 2] = [(SIGINT, "SIGINT", 130), (SIGTERM, "SIGTERM", 143)];

/// The flags SIGINT and SIGTERM set.
pub struct Signals {
    interrupt: Interrupt,
}

impl Signals {
    /// Installs the handlers.
    pub fn register() -> anyhow::Result<Self> {
        let mut interrupt = Interrupt::new();
        for (sig, name, code) in CAUGHT {
            let f = interrupt.flag(name);
            // Order matters: the conditional shutdown sees the flag set by the first signal.
            flag::register_conditional_shutdown(sig, i32::from(code), Arc::clone(&f))?;
            flag::register(sig, f)?;
        }
        Ok(Self { interrupt })
    }

    /// The run's stop flags.
    pub fn interrupt(&self) -> &Interrupt {
        &self.interrupt
    }

    /// The exit status of the signal caught, if any (128 + its number).
    pub fn exit_code(&self) -> Option<u8> {
        let name = self.interrupt.caught()?;
        CAUGHT
            .iter()
            .find(|(_, n, _)| *n == name)
            .map(|(_, _, code)| *code)
    }
}
