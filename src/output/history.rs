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

/// The energy audit: turns samples into balance errors relative to the largest energy seen.
#[derive(Debug, Clone, Default)]
pub struct EnergyAudit {
    initial: Option<f64>,
    largest: f64,
    /// Largest balance error so far.
    pub max_error: f64,
}

impl EnergyAudit {
    /// Total energy of a sample: kinetic + internal + hourglass + viscous work + contact energy
    /// - external work.
    pub fn total(s: &Sample) -> f64 {
        s.kinetic + s.internal + s.hourglass + s.viscous + s.contact - s.external
    }

    /// The balance error of `s` relative to the largest energy seen so far (this sample included).
    pub fn error(&mut self, s: &Sample) -> f64 {
        let total = Self::total(s);
        let e0 = *self.initial.get_or_insert(total);
        let stored = s.kinetic + s.internal + s.hourglass + s.viscous + s.contact.abs();
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
}

impl HistoryWriter {
    /// Creates the file and writes the header; `bodies` name the per-body columns and `contacts`
    /// the per-contact (and rigid wall) columns.
    ///
    /// # Errors
    /// [`Error::Write`] when the file cannot be created.
    pub fn create(path: &Path, bodies: &[String], contacts: &[String]) -> Result<Self> {
        let file = File::create(path).map_err(|source| Error::Write {
            path: path.to_path_buf(),
            source,
        })?;
        let mut w = Self {
            path: path.to_path_buf(),
            out: BufWriter::new(file),
        };
        let mut header = COLUMNS.join(",");
        for b in bodies {
            header.push_str(&format!(",{b}.vx,{b}.vy"));
        }
        for c in contacts {
            header.push_str(&format!(
                ",{c}.fx,{c}.fy,{c}.max_penetration,{c}.active_nodes"
            ));
        }
        w.line(&header)?;
        Ok(w)
    }

    fn line(&mut self, s: &str) -> Result<()> {
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
        let mut line = format!(
            "{:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
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
        }
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
