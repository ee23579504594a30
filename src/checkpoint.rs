//! Checkpoints of a run (`run --checkpoint-interval T`, `run --restart DIR`): everything needed to
//! continue a run where it stood and give the same history and fields, bit for bit, as the run
//! that was never stopped (on the CPU reference, and on the GPU for the same adapter).
//!
//! A checkpoint holds the scene text it was run from (re-validated on restart), the backend and
//! adapter, the solver's changing state (its own encoding, see [`crate::step::Solver::save_state`];
//! the GPU's in `src/gpu/checkpoint.rs`), the energy audit, and the output positions: the bytes,
//! rows and digest of `history.csv` and the snapshots listed in `fields.pvd`. It is one file,
//! `checkpoint.bin` in the output folder, replaced by a temporary file and a rename at each
//! checkpoint, so that a crash leaves the previous one whole.
//!
//! It proves that it is whole and that it belongs to its folder: the file is [`MAGIC`], the
//! length of the postcard-encoded body (8 bytes, little-endian), the body, and an XXH3 checksum
//! of all that (8 bytes); the body keeps digests of the scene text, of the solver state, of every
//! mesh file the scene reads, and of the bytes of `history.csv` it was taken after. [`read`]
//! refuses a file that is not a regular file, larger than [`MAX_BYTES`] or than the memory
//! available, cut short, extended or damaged before it decodes anything large, and [`Checkpoint::check`]
//! refuses values that cannot be restored (a time that is not finite, counts beyond the limits
//! of a run, snapshot files outside `fields/`). A restart then compares the mesh files with
//! their digests ([`Checkpoint::scene`]), `history.csv` with its digest and rows
//! ([`crate::output::history::HistoryWriter::resume`]) and the snapshot files with the list.
//!
//! [`read`]: Checkpoint::read

use std::io::Read as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::output::history::EnergyAudit;
use crate::scene::{MeshSpec, Scene};

/// Name of the checkpoint file in the output folder.
pub const FILE: &str = "checkpoint.bin";

/// First bytes of a checkpoint file (format name and version: 7 since the GPU's counters hold
/// the contact surfaces' follows of erosion, [`crate::step::Counters::erosion_follows`]).
pub const MAGIC: &[u8; 8] = b"RICOCHK7";

/// The largest checkpoint file read (a checkpoint holds a few hundred bytes per node).
pub const MAX_BYTES: u64 = 16 << 30;

/// Bytes before the body (the magic and the body's length) and after it (the checksum).
const HEAD: u64 = 16;
const TAIL: u64 = 8;

/// Steps a checkpoint may have taken at most (as `run::MAX_STEPS`, the limit of a run).
const MAX_STEPS: u64 = 1_000_000_000;

/// The digest of some bytes (64-bit XXH3), as the checkpoint keeps it.
pub fn digest(bytes: &[u8]) -> u64 {
    xxhash_rust::xxh3::xxh3_64(bytes)
}

/// A mesh file the scene reads and its digest when the run started.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct MeshDigest {
    /// The file (as the scene resolved it).
    pub file: PathBuf,
    /// Its digest ([`crate::gmsh::digest`]).
    pub digest: u64,
}

/// The mesh files of `scene` (its Gmsh bodies' files, each once) with the digests of the bytes
/// that were read.
pub fn mesh_digests(scene: &Scene) -> Vec<MeshDigest> {
    let mut out: Vec<MeshDigest> = Vec::new();
    for b in &scene.bodies {
        if let MeshSpec::Gmsh { file, mesh, .. } = &b.mesh {
            if !out.iter().any(|m| m.file == *file) {
                out.push(MeshDigest {
                    file: file.clone(),
                    digest: mesh.digest,
                });
            }
        }
    }
    out
}

/// What a run needs to continue from a checkpoint.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The scene file's path when the run started (for messages and the scene's name).
    pub scene_path: PathBuf,
    /// The scene file's text when the run started.
    pub scene_text: String,
    /// The digest of `scene_text`.
    pub scene_digest: u64,
    /// The mesh files the scene reads, with their digests ([`mesh_digests`]).
    pub meshes: Vec<MeshDigest>,
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
    /// The digest of the first `history_bytes` bytes of `history.csv`.
    pub history_digest: u64,
    /// The snapshots written: (time, body, file relative to the output folder).
    pub snapshots: Vec<(f64, String, String)>,
    /// The energy audit's state.
    pub audit: EnergyAudit,
    /// Seconds spent in the time loop so far.
    pub loop_seconds: f64,
    /// The solver's state, in the backend's encoding.
    pub solver: Vec<u8>,
    /// The digest of `solver`.
    pub solver_digest: u64,
}

impl Checkpoint {
    /// Writes `dir/checkpoint.bin` through a temporary name and a rename.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] if it cannot be encoded, [`Error::Write`] on I/O failure.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let body = postcard::to_stdvec(self)
            .map_err(|e| Error::Checkpoint(format!("encoding the checkpoint: {e}")))?;
        let mut head = MAGIC.to_vec();
        head.extend((body.len() as u64).to_le_bytes());
        let mut hasher = xxhash_rust::xxh3::Xxh3::new();
        hasher.update(&head);
        hasher.update(&body);
        let sum = hasher.digest().to_le_bytes();
        crate::output::write_pieces(&dir.join(FILE), &[&head[..], &body[..], &sum[..]])
    }

    /// Reads `dir/checkpoint.bin`: the header first (a file that is not a checkpoint, or whose
    /// length is not the one its header gives, is refused having read 16 bytes), then the rest
    /// within its length, its checksum, and the values ([`Checkpoint::check`]).
    ///
    /// # Errors
    /// [`Error::Checkpoint`] naming the file when it is missing, not a regular file, larger
    /// than [`MAX_BYTES`] or the memory available, not a checkpoint, of another version, cut
    /// short or extended, damaged (its checksum or a digest), or holding values that cannot
    /// be restored.
    pub fn read(dir: &Path) -> Result<Self> {
        let path = dir.join(FILE);
        let bad = |why: String| Error::Checkpoint(format!("{}: {why}", path.display()));
        let meta = std::fs::metadata(&path).map_err(|e| {
            bad(format!(
                "cannot read it ({e}); a run writes it with --checkpoint-interval"
            ))
        })?;
        if !meta.is_file() {
            return Err(bad(
                "not a regular file (a device, a FIFO or a folder): a run writes its checkpoint \
                 as a regular file"
                    .into(),
            ));
        }
        let len = meta.len();
        if len > MAX_BYTES {
            return Err(bad(format!(
                "it has {len} bytes, more than the {} read at most",
                crate::input::show(MAX_BYTES)
            )));
        }
        let mut file =
            std::fs::File::open(&path).map_err(|e| bad(format!("cannot read it ({e})")))?;
        let mut head = Vec::new();
        (&mut file)
            .take(HEAD)
            .read_to_end(&mut head)
            .map_err(|e| bad(format!("cannot read it ({e})")))?;
        if head.len() < MAGIC.len() || &head[..MAGIC.len()] != MAGIC {
            return Err(bad(format!(
                "not a ricochet checkpoint of this version (it must start with {:?})",
                String::from_utf8_lossy(MAGIC)
            )));
        }
        if (head.len() as u64) < HEAD {
            return Err(bad("cut short: it ends inside its header".into()));
        }
        let mut n = [0u8; 8];
        n.copy_from_slice(&head[8..16]);
        let body_len = u64::from_le_bytes(n);
        let want = body_len.checked_add(HEAD + TAIL);
        if want != Some(len) {
            return Err(bad(format!(
                "cut short or extended: its header announces {body_len} bytes of state, which \
                 makes a file of {} bytes, and it has {len}",
                want.map_or_else(|| "more than 2^64".to_string(), |w| w.to_string())
            )));
        }
        if let Some(have) = crate::input::available_memory() {
            if body_len > have {
                return Err(bad(format!(
                    "its {body_len} bytes of state are more than the {have} bytes of memory \
                     available"
                )));
            }
        }
        let mut rest = Vec::with_capacity((body_len + TAIL) as usize);
        file.take(body_len + TAIL + 1)
            .read_to_end(&mut rest)
            .map_err(|e| bad(format!("cannot read it ({e})")))?;
        if rest.len() as u64 != body_len + TAIL {
            return Err(bad(format!(
                "cut short or extended while it was read: {} bytes after the header instead of \
                 {}",
                rest.len(),
                body_len + TAIL
            )));
        }
        let (body, sum) = rest.split_at(body_len as usize);
        let mut hasher = xxhash_rust::xxh3::Xxh3::new();
        hasher.update(&head);
        hasher.update(body);
        let mut s = [0u8; 8];
        s.copy_from_slice(sum);
        if hasher.digest() != u64::from_le_bytes(s) {
            return Err(bad(
                "damaged: its checksum does not match its contents (a byte changed since it \
                 was written)"
                    .into(),
            ));
        }
        let c: Self = postcard::from_bytes(body)
            .map_err(|e| bad(format!("cannot decode it ({e}): cut short or damaged")))?;
        c.check().map_err(bad)?;
        Ok(c)
    }

    /// The checks of the values a restart takes over, file by itself: the digests of the scene
    /// text and of the solver state, a finite time and interval, counts within the limits of a
    /// run, a finite energy audit and wall time, snapshot files under `fields/`.
    ///
    /// # Errors
    /// A sentence naming the value that cannot be restored.
    pub fn check(&self) -> std::result::Result<(), String> {
        if digest(self.scene_text.as_bytes()) != self.scene_digest {
            return Err("damaged: its scene text does not match the scene's digest".into());
        }
        if digest(&self.solver) != self.solver_digest {
            return Err("damaged: its solver state does not match the state's digest".into());
        }
        if !(self.time.is_finite() && self.time >= 0.0) {
            return Err(format!(
                "its time t = {:e} s is not a finite time >= 0",
                self.time
            ));
        }
        if !(self.interval.is_finite() && self.interval > 0.0) {
            return Err(format!(
                "its checkpoint interval {:e} s is not positive and finite",
                self.interval
            ));
        }
        if let Some(t) = self.end_time_override {
            if !(t.is_finite() && t > 0.0) {
                return Err(format!("its --end-time {t:e} is not positive and finite"));
            }
        }
        if !(self.loop_seconds.is_finite() && self.loop_seconds >= 0.0) {
            return Err(format!(
                "its wall time {:e} s is not a finite time >= 0",
                self.loop_seconds
            ));
        }
        if self.backend != "cpu" && self.backend != "gpu" {
            return Err(format!(
                "its backend {:?} is neither \"cpu\" nor \"gpu\"",
                self.backend
            ));
        }
        if self.steps > MAX_STEPS {
            return Err(format!(
                "its step count {} is beyond the {MAX_STEPS} steps a run may take",
                self.steps
            ));
        }
        // A history row is at least a time, a step and 8 numbers with their commas.
        if self.history_rows.saturating_mul(20) > self.history_bytes {
            return Err(format!(
                "its {} history rows do not fit in the {} bytes of history it was taken after",
                self.history_rows, self.history_bytes
            ));
        }
        if !self.audit.is_finite() {
            return Err("its energy audit holds a number that is not finite".into());
        }
        for (t, body, file) in &self.snapshots {
            let name = file.strip_prefix("fields/").unwrap_or("");
            if !t.is_finite()
                || name.is_empty()
                || name.contains(['/', '\\'])
                || name.starts_with('.')
                || body.is_empty()
            {
                return Err(format!(
                    "its snapshot list names the file {file:?} of body {body:?} at t = {t:e} s: \
                     not a snapshot file under fields/"
                ));
            }
        }
        Ok(())
    }

    /// The scene of the run, validated again from its saved text (with the run's `--end-time`),
    /// with the checks that need it: the checkpoint's time within the run, and the mesh files
    /// the scene reads unchanged since the checkpoint (their digests).
    ///
    /// # Errors
    /// As [`Scene::parse`]; [`Error::Checkpoint`] naming the checkpoint and the mesh file that
    /// changed, or the time.
    pub fn scene(&self, dir: &Path) -> Result<Scene> {
        let mut scene = Scene::parse(&self.scene_text, &self.scene_path)?;
        if let Some(t) = self.end_time_override {
            scene.run.end_time = t;
        }
        let path = dir.join(FILE);
        let bad = |why: String| Error::Checkpoint(format!("{}: {why}", path.display()));
        if self.time > scene.run.end_time {
            return Err(bad(format!(
                "its time t = {:e} s is past the run's end time {:e} s",
                self.time, scene.run.end_time
            )));
        }
        let now = mesh_digests(&scene);
        for m in &self.meshes {
            match now.iter().find(|n| n.file == m.file) {
                Some(n) if n.digest == m.digest => {}
                Some(_) => {
                    return Err(bad(format!(
                        "the mesh file {} changed since the checkpoint (its digest differs): \
                         the saved state is that of the old mesh; run the scene again instead",
                        m.file.display()
                    )))
                }
                None => {
                    return Err(bad(format!(
                        "the scene no longer reads the mesh file {} it read at the checkpoint",
                        m.file.display()
                    )))
                }
            }
        }
        if let Some(n) = now
            .iter()
            .find(|n| !self.meshes.iter().any(|m| m.file == n.file))
        {
            return Err(bad(format!(
                "the scene reads the mesh file {}, which the checkpoint did not record",
                n.file.display()
            )));
        }
        Ok(scene)
    }

    /// Refuses a checkpoint whose snapshot files are not in the output folder `dir` (deleted
    /// since): a restart would list them in `fields.pvd`.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] naming the first missing file.
    pub fn check_snapshots(&self, dir: &Path) -> Result<()> {
        for (_, _, file) in &self.snapshots {
            let p = dir.join(file);
            if !p.is_file() {
                return Err(Error::Checkpoint(format!(
                    "{}: the snapshot {} it lists is missing (fields/ deleted or changed since \
                     the checkpoint): fields.pvd would list a file that does not exist",
                    dir.join(FILE).display(),
                    p.display()
                )));
            }
        }
        Ok(())
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
