//! Checkpoints of a run (`run --checkpoint-interval T`, `run --restart DIR`): everything needed to
//! continue a run where it stood and give the same history and fields, bit for bit, as the run
//! that was never stopped (on the CPU reference, and on the GPU for the same adapter).
//!
//! A checkpoint holds the scene text it was run from (re-validated on restart), the backend and
//! adapter, the solver's changing state (its own encoding, see [`crate::step::Solver::save_state`]),
//! the energy audit, and the output positions: the bytes and rows of `history.csv` and the
//! snapshots listed in `fields.pvd`. It is one file, `checkpoint.bin` in the output folder,
//! replaced by a temporary file and a rename at each checkpoint, so that a crash leaves the
//! previous one whole. The file starts with [`MAGIC`] and is postcard-encoded.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::output::history::EnergyAudit;
use crate::scene::Scene;

/// Name of the checkpoint file in the output folder.
pub const FILE: &str = "checkpoint.bin";

/// First bytes of a checkpoint file (format name and version).
pub const MAGIC: &[u8; 8] = b"RICOCHK1";

/// The largest checkpoint file read (a checkpoint holds a few hundred bytes per node).
pub const MAX_BYTES: u64 = 16 << 30;

/// What a run needs to continue from a checkpoint.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The scene file's path when the run started (for messages and the scene's name).
    pub scene_path: PathBuf,
    /// The scene file's text when the run started.
    pub scene_text: String,
    /// `--end-time`, if the run overrode `run.end_time`.
    pub end_time_override: Option<f64>,
    /// Simulated time between checkpoints (s).
    pub interval: f64,
    /// `"cpu"` or `"gpu"`.
    pub backend: String,
    /// The adapter (or processor) description of the run.
    pub adapter: String,
    /// Steps taken and simulated time at the checkpoint.
    pub steps: u64,
    /// Simulated time at the checkpoint.
    pub time: f64,
    /// Bytes of `history.csv` written (header included) and rows in it.
    pub history_bytes: u64,
    /// Rows of `history.csv` written.
    pub history_rows: u64,
    /// The snapshots written: (time, body, file relative to the output folder).
    pub snapshots: Vec<(f64, String, String)>,
    /// The energy audit's state.
    pub audit: EnergyAudit,
    /// Seconds spent in the time loop so far.
    pub loop_seconds: f64,
    /// The solver's state, in the backend's encoding.
    pub solver: Vec<u8>,
}

impl Checkpoint {
    /// Writes `dir/checkpoint.bin` through a temporary name and a rename.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] if it cannot be encoded, [`Error::Write`] on I/O failure.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let mut bytes = MAGIC.to_vec();
        let body = postcard::to_stdvec(self)
            .map_err(|e| Error::Checkpoint(format!("encoding the checkpoint: {e}")))?;
        bytes.extend(body);
        crate::output::write_file(&dir.join(FILE), &bytes)
    }

    /// Reads `dir/checkpoint.bin`.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] naming the file when it is missing, not a checkpoint, of another
    /// version, or cut short.
    pub fn read(dir: &Path) -> Result<Self> {
        use std::io::Read as _;
        let path = dir.join(FILE);
        let bad = |why: String| Error::Checkpoint(format!("{}: {why}", path.display()));
        let mut bytes = Vec::new();
        std::fs::File::open(&path)
            .and_then(|f| f.take(MAX_BYTES + 1).read_to_end(&mut bytes))
            .map_err(|e| {
                bad(format!(
                    "cannot read it ({e}); a run writes it with --checkpoint-interval"
                ))
            })?;
        if bytes.len() as u64 > MAX_BYTES {
            return Err(bad(format!("larger than {} GiB", MAX_BYTES >> 30)));
        }
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err(bad(format!(
                "not a ricochet checkpoint of this version (it must start with {:?})",
                String::from_utf8_lossy(MAGIC)
            )));
        }
        postcard::from_bytes(&bytes[MAGIC.len()..])
            .map_err(|e| bad(format!("cannot decode it ({e}): cut short or damaged")))
    }

    /// The scene of the run, validated again from its saved text (with the run's `--end-time`).
    ///
    /// # Errors
    /// As [`Scene::parse`].
    pub fn scene(&self) -> Result<Scene> {
        let mut scene = Scene::parse(&self.scene_text, &self.scene_path)?;
        if let Some(t) = self.end_time_override {
            scene.run.end_time = t;
        }
        Ok(scene)
    }
}

/// Checkpointing of a run: where the next checkpoint goes and what it records of the scene.
#[derive(Debug, Clone)]
pub struct Checkpointing {
    /// Simulated time between checkpoints (s), finite and > 0.
    pub interval: f64,
    /// The scene file's path.
    pub scene_path: PathBuf,
    /// The scene file's text.
    pub scene_text: String,
    /// `--end-time`, if given.
    pub end_time_override: Option<f64>,
}
