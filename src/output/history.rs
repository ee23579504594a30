//! `history.csv`: one row per history sample, with the energy audit and the body velocities.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use xxhash_rust::xxh3::Xxh3;

use crate::error::{Error, Result};
use crate::step::Sample;

/// Fixed leading columns of `history.csv`.
pub const COLUMNS: [&str; 10] = [
    "time",
    "step",
    "dt",
    "kinetic_energy",
    "internal_energy",
    "hourglass_energy",
    "viscous_work",
    "contact_energy",
    "external_work",
    "energy_error",
];

/// The comment line before the header of a scene with an axisymmetric body (readers skip lines
/// that start with `#`).
pub const PER_RADIAN: &str = "# axisymmetric: energies, works, contact forces and masses are per \
     radian (times 2 pi for the whole part); x is the radius r, y the axis";

/// The energy audit: turns samples into balance errors relative to the largest energy seen.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct EnergyAudit {
    initial: Option<f64>,
    largest: f64,
    /// Largest balance error so far.
    pub max_error: f64,
}

impl EnergyAudit {
    /// Total energy of a sample: kinetic + internal + hourglass + viscous work + plastic work +
    /// eroded energy + contact energy + friction work - external work.
    pub fn total(s: &Sample) -> f64 {
        s.kinetic
            + s.internal
            + s.hourglass
            + s.viscous
            + s.plastic
            + s.eroded_energy
            + s.contact
            + s.friction
            - s.external
    }

    /// Whether every number of the audit is finite (a checkpoint's is checked before a restart
    /// takes it over: a NaN would end in `summary.json` as `null`).
    pub fn is_finite(&self) -> bool {
        self.initial.is_none_or(f64::is_finite)
            && self.largest.is_finite()
            && self.max_error.is_finite()
    }

    /// The balance error of `s` relative to the largest energy seen so far (this sample included).
    pub fn error(&mut self, s: &Sample) -> f64 {
        let total = Self::total(s);
        let e0 = *self.initial.get_or_insert(total);
        let stored = s.kinetic
            + s.internal
            + s.hourglass
            + s.viscous
            + s.plastic
            + s.eroded_energy
            + s.contact.abs()
            + s.friction.abs();
        self.largest = self
            .largest
            .max(stored.abs())
            .max(s.external.abs())
            .max(e0.abs());
        let err = if self.largest > 0.0 {
            (total - e0).abs() / self.largest
        } else {
            0.0
        };
        self.max_error = self.max_error.max(err);
        err
    }
}

/// Writes `history.csv` row by row, keeping the digest of what it wrote (a checkpoint records
/// it, and a restart compares the file with it).
pub struct HistoryWriter {
    path: PathBuf,
    out: BufWriter<File>,
    /// XXH3 of the bytes written so far.
    hash: Xxh3,
    /// Bytes and rows written so far (header included in the bytes).
    bytes: u64,
    rows: u64,
    /// Whether the rows have the `plastic_work` column.
    plastic: bool,
    /// Whether the rows have the `friction_work` column and the contacts' `.ft` columns.
    friction: bool,
    /// Whether the rows have the `eroded_elements` and `eroded_energy` columns.
    erosion: bool,
}

impl HistoryWriter {
    /// Creates the file and writes the header; `bodies` name the per-body columns and `contacts`
    /// the per-contact (and rigid wall) columns; `plastic` adds the `plastic_work` column after
    /// `viscous_work` (scenes with a J2 plastic material); `erosion` adds `eroded_elements` and
    /// `eroded_energy` after them (scenes with failure); `per_radian` writes the comment line
    /// [`PER_RADIAN`] before the header (scenes with an axisymmetric body).
    ///
    /// # Errors
    /// [`Error::Write`] when the file cannot be created.
    pub fn create(
        path: &Path,
        bodies: &[String],
        contacts: &[String],
        plastic: bool,
        friction: bool,
        erosion: bool,
        per_radian: bool,
    ) -> Result<Self> {
        let file = File::create(path).map_err(|source| Error::Write {
            path: path.to_path_buf(),
            source,
        })?;
        let mut w = Self {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            hash: Xxh3::new(),
            bytes: 0,
            rows: 0,
            plastic,
            friction,
            erosion,
        };
        if per_radian {
            w.line(PER_RADIAN)?;
        }
        let mut header = COLUMNS.join(",");
        if plastic {
            header = header.replace(",viscous_work,", ",viscous_work,plastic_work,");
        }
        if erosion {
            header = header.replace(
                ",contact_energy,",
                ",eroded_elements,eroded_energy,contact_energy,",
            );
        }
        if friction {
            header = header.replace(",contact_energy,", ",contact_energy,friction_work,");
        }
        for b in bodies {
            header.push_str(&format!(",{b}.vx,{b}.vy"));
        }
        for c in contacts {
            header.push_str(&format!(
                ",{c}.fx,{c}.fy,{c}.max_penetration,{c}.active_nodes"
            ));
            if friction {
                header.push_str(&format!(",{c}.ft"));
            }
        }
        w.line(&header)?;
        Ok(w)
    }

    /// Continues the file at `path` after its first `bytes` bytes (`rows` rows, digest
    /// `digest`): what a checkpoint recorded. Those bytes are read first and must be what the
    /// run wrote (their digest, whole rows, `rows` of them); anything after them (rows written
    /// after the checkpoint) is then cut off.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] naming the file when it is not a regular file, is shorter than
    /// `bytes`, or its first `bytes` bytes are not the checkpoint's (another run's history,
    /// resaved with other line ends, cut mid-row); [`Error::Write`] when it cannot be opened.
    pub fn resume(
        path: &Path,
        bytes: u64,
        rows: u64,
        digest: u64,
        plastic: bool,
        friction: bool,
        erosion: bool,
    ) -> Result<Self> {
        use std::io::{Read, Seek, SeekFrom};
        let write_err = |source| Error::Write {
            path: path.to_path_buf(),
            source,
        };
        let not_ours = |why: String| {
            Error::Checkpoint(format!(
                "{}: {why}: not the history the checkpoint was taken after (changed since, or \
                 another run's)",
                path.display()
            ))
        };
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(write_err)?;
        let meta = file.metadata().map_err(write_err)?;
        if !meta.is_file() {
            return Err(not_ours("not a regular file".into()));
        }
        let len = meta.len();
        if len < bytes {
            return Err(not_ours(format!(
                "{len} bytes, but the checkpoint was taken after {bytes}"
            )));
        }
        // The first `bytes` bytes, read in pieces: their digest, their lines.
        let mut hash = Xxh3::new();
        let (mut lines, mut comments, mut last) = (0u64, 0u64, b'\n');
        let mut line_start = true;
        let mut buf = vec![0u8; 1 << 16];
        let mut reader = (&mut file).take(bytes);
        loop {
            let n = reader.read(&mut buf).map_err(write_err)?;
            if n == 0 {
                break;
            }
            let piece = &buf[..n];
            hash.update(piece);
            for &b in piece {
                if line_start && b == b'#' {
                    comments += 1;
                }
                line_start = b == b'\n';
                if line_start {
                    lines += 1;
                }
            }
            last = piece[n - 1];
        }
        if hash.digest() != digest {
            return Err(not_ours(format!(
                "its first {bytes} bytes differ from those the run wrote"
            )));
        }
        // The digest matches: these checks find a checkpoint whose counts were changed.
        if last != b'\n' || lines < comments + 1 || lines - comments - 1 != rows {
            return Err(not_ours(format!(
                "its first {bytes} bytes hold {} rows (ending {}), the checkpoint says {rows}",
                lines.saturating_sub(comments + 1),
                if last == b'\n' {
                    "at a row's end"
                } else {
                    "mid-row"
                }
            )));
        }
        file.set_len(bytes).map_err(write_err)?;
        file.seek(SeekFrom::End(0)).map_err(write_err)?;
        Ok(Self {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            hash,
            bytes,
            rows,
            plastic,
            friction,
            erosion,
        })
    }

    /// The digest of the bytes written so far (as a checkpoint records it).
    pub fn digest(&self) -> u64 {
        self.hash.digest()
    }

    /// Flushes the rows written so far and returns (bytes, rows) of the file.
    ///
    /// # Errors
    /// [`Error::Write`] on I/O failure.
    pub fn flush(&mut self) -> Result<(u64, u64)> {
        self.out.flush().map_err(|source| Error::Write {
            path: self.path.clone(),
            source,
        })?;
        Ok((self.bytes, self.rows))
    }

    fn line(&mut self, s: &str) -> Result<()> {
        self.bytes += s.len() as u64 + 1;
        self.hash.update(s.as_bytes());
        self.hash.update(b"\n");
        writeln!(self.out, "{s}").map_err(|source| Error::Write {
            path: self.path.clone(),
            source,
        })
    }

    /// Appends one row.
    ///
    /// # Errors
    /// [`Error::Write`] on I/O failure.
    pub fn row(&mut self, s: &Sample, energy_error: f64) -> Result<()> {
        let plastic = if self.plastic {
            format!(",{:e}", s.plastic)
        } else {
            String::new()
        };
        let friction = if self.friction {
            format!(",{:e}", s.friction)
        } else {
            String::new()
        };
        let eroded = if self.erosion {
            format!(",{},{:e}", s.eroded_elements, s.eroded_energy)
        } else {
            String::new()
        };
        let mut line = format!(
            "{:e},{},{:e},{:e},{:e},{:e},{:e}{plastic}{eroded},{:e}{friction},{:e},{:e}",
            s.time,
            s.step,
            s.dt,
            s.kinetic,
            s.internal,
            s.hourglass,
            s.viscous,
            s.contact,
            s.external,
            energy_error
        );
        for v in &s.body_velocity {
            line.push_str(&format!(",{:e},{:e}", v[0], v[1]));
        }
        for c in &s.contacts {
            line.push_str(&format!(
                ",{:e},{:e},{:e},{}",
                c.force[0], c.force[1], c.max_penetration, c.active_nodes
            ));
            if self.friction {
                line.push_str(&format!(",{:e}", c.ft));
            }
        }
        self.rows += 1;
        self.line(&line)
    }

    /// Flushes the file.
    ///
    /// # Errors
    /// [`Error::Write`] on I/O failure.
    pub fn finish(mut self) -> Result<()> {
        self.out.flush().map_err(|source| Error::Write {
            path: self.path.clone(),
            source,
        })
    }
}
