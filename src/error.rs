//! The library's error type.

use std::path::PathBuf;

/// Everything that can go wrong in ricochet's library code.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene file could not be read.
    #[error("{file}: cannot read: {source}")]
    Read {
        /// The file.
        file: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A scene file is not valid TOML or does not have the expected shape.
    #[error("{file}: {message}")]
    Parse {
        /// The file.
        file: PathBuf,
        /// What the parser said (it names line, column and key).
        message: String,
    },
    /// A key has a value that is not allowed. The message shows at most [`VALUE_CHARS`]
    /// characters of the key and the value and [`REASON_CHARS`] of the reason (a string value
    /// can be as long as the file: a 100 000-character `model` made a message of 100 KB).
    #[error(
        "{file}: key `{}` = {}: {}",
        clip(.key, VALUE_CHARS),
        clip(.value, VALUE_CHARS),
        clip(.reason, REASON_CHARS)
    )]
    Invalid {
        /// The file.
        file: PathBuf,
        /// The key, as a dotted path such as `material[1].density`.
        key: String,
        /// The offending value, as written.
        value: String,
        /// Why it is rejected.
        reason: String,
    },
    /// Writing an output file failed.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The output folder is in use by another run (its lock, `ricochet.lock`, is held).
    #[error(
        "the output folder {dir} is in use by process {holder} (another ricochet run or restart \
         writing it): wait for it to end, or choose another --out"
    )]
    InUse {
        /// The output folder.
        dir: PathBuf,
        /// The process id written in the lock file.
        holder: String,
    },
    /// A checkpoint could not be written, read, or continued (`run --restart`).
    #[error("checkpoint: {0}")]
    Checkpoint(String),
    /// A benchmark run did not take the steps it was asked to (the scene stopped early).
    #[error("bench: {0}")]
    Bench(String),
    /// The verification suite could not be run (a case file, a run or a report).
    #[error("verify: {0}")]
    Verify(String),
    /// A picture could not be drawn or encoded (`ricochet plot`).
    #[error("plot: {0}")]
    Plot(String),
    /// The GPU backend could not be used.
    #[error("GPU: {0}")]
    Gpu(String),
    /// A study could not run its cases, submit them to Slurm or find its threshold.
    #[error("study: {0}")]
    Study(String),
}

/// Characters of the key and of the value shown in the message of [`Error::Invalid`].
pub const VALUE_CHARS: usize = 200;
/// Characters of the reason shown in the message of [`Error::Invalid`].
pub const REASON_CHARS: usize = 1000;

/// `s` cut to `n` characters, saying how long it was.
fn clip(s: &str, n: usize) -> std::borrow::Cow<'_, str> {
    match s.char_indices().nth(n) {
        Some((i, _)) => format!("{}... ({} characters in all)", &s[..i], s.chars().count()).into(),
        None => s.into(),
    }
}

/// Shorthand for results with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
