//! The command line's modules: its arguments ([`args`]), one module per command ([`run`],
//! [`plot`], [`check`], [`bench`](mod@bench), [`verify`], [`study`], [`collect`]), and what `run` wires to the library's
//! run on a terminal: SIGINT and SIGTERM ([`signals`]) and the progress bar ([`progress`]).

pub mod args;
pub mod bench;
pub mod check;
pub mod collect;
pub mod plot;
pub mod progress;
pub mod run;
pub mod signals;
pub mod study;
pub mod verify;
