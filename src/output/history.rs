//! `history.csv`: one row per history sample, with the energy audit and the body velocities.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

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
    /// contact energy + friction work - external work.
    pub fn total(s: &Sample) -> f64 {
        s.kinetic + s.internal + s.hourglass + s.viscous + s.plastic + s.contact + s.friction
            - s.external
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

/// Writes `history.csv` row by row.
pub struct HistoryWriter {
    path: PathBuf,
    out: BufWriter<File>,
    /// Bytes and rows written so far (header included in the bytes).
    bytes: u64,
    rows: u64,
    /// Whether the rows have the `plastic_work` column.
    plastic: bool,
    /// Whether the rows have the `friction_work` column and the contacts' `.ft` columns.
    friction: bool,
}

impl HistoryWriter {
    /// Creates the file and writes the header; `bodies` name the per-body columns and `contacts`
    /// the per-contact (and rigid wall) columns; `plastic` adds the `plastic_work` column after
    /// `viscous_work` (scenes with a J2 plastic material); `per_radian` writes the comment line
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
        per_radian: bool,
    ) -> Result<Self> {
        let file = File::create(path).map_err(|source| Error::Write {
            path: path.to_path_buf(),
            source,
        })?;
        let mut w = Self {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            bytes: 0,
            rows: 0,
            plastic,
            friction,
        };
        if per_radian {
            w.line(PER_RADIAN)?;
        }
        let mut header = COLUMNS.join(",");
        if plastic {
            header = header.replace(",viscous_work,", ",viscous_work,plastic_work,");
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

    /// Continues the file at `path` after its first `bytes` bytes (`rows` rows): what a
    /// checkpoint recorded. Anything after them (rows written after the checkpoint) is cut off.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] when the file is shorter than `bytes` (it is not the checkpoint's),
    /// [`Error::Write`] when it cannot be opened.
    pub fn resume(
        path: &Path,
        bytes: u64,
        rows: u64,
        plastic: bool,
        friction: bool,
    ) -> Result<Self> {
        use std::io::{Seek, SeekFrom};
        let write_err = |source| Error::Write {
            path: path.to_path_buf(),
            source,
        };
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(write_err)?;
        let len = file.metadata().map_err(write_err)?.len();
        if len < bytes {
            return Err(Error::Checkpoint(format!(
                "{}: {len} bytes, but the checkpoint was taken after {bytes}: not the \
                 checkpoint's history",
                path.display()
            )));
        }
        file.set_len(bytes).map_err(write_err)?;
        file.seek(SeekFrom::End(0)).map_err(write_err)?;
        Ok(Self {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
            bytes,
            rows,
            plastic,
            friction,
        })
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
        let mut line = format!(
            "{:e},{},{:e},{:e},{:e},{:e},{:e}{plastic},{:e}{friction},{:e},{:e}",
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
