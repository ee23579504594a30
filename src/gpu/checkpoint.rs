//! Saving and restoring a [`GpuSolver`]'s state for checkpoints ([`crate::checkpoint`]): every
//! device buffer of the scene read back as it stands between two submissions, with the host's
//! copy of the control block, its counters and the contact stage's grown sizes; restored by
//! writing the same bytes into the buffers of a solver built from the same scene, so that the
//! run continues with the same bits on the same adapter.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::step::Counters;

use super::contact::{ContactCounters, ContactParams};
use super::layout::Control;
use super::solver::GpuSolver;

/// The encoded state (postcard).
#[derive(Serialize, Deserialize)]
struct GpuSaved {
    control: Vec<u8>,
    rows_read: u32,
    dt_estimate: f64,
    counters: Counters,
    finished: bool,
    /// The contact stage's parameters (grown sizes), counters and grow count.
    contact: Option<(Vec<u8>, Vec<u8>, u32)>,
    /// (name, bytes) of every buffer, in allocation order.
    buffers: Vec<(String, Vec<u8>)>,
}

fn bad(why: String) -> Error {
    Error::Checkpoint(format!("GPU state: {why}"))
}

impl GpuSolver {
    /// The buffers a checkpoint holds, in order, with the contact candidates' current buffer.
    fn checkpoint_buffers(&self) -> Vec<(&'static str, wgpu::Buffer)> {
        let current = self.state().contact.as_ref().map(|c| c.candidates_buffer());
        self.state()
            .buffers
            .iter()
            .map(|(name, b)| match (*name, current) {
                ("contact_candidates", Some(c)) => (*name, c.clone()),
                _ => (*name, b.clone()),
            })
            .collect()
    }

    /// The solver's state as bytes: one readback of every buffer (counted in the bytes read
    /// back).
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost, [`Error::Checkpoint`] if it cannot be encoded.
    pub fn save_state(&mut self) -> Result<Vec<u8>> {
        let list = self.checkpoint_buffers();
        let parts: Vec<(&wgpu::Buffer, u64, u64)> =
            list.iter().map(|(_, b)| (b, 0, b.size())).collect();
        let bytes = self.read_copies("checkpoint_readback", &parts)?;
        let mut at = 0usize;
        let buffers = list
            .iter()
            .map(|(name, b)| {
                let n = b.size() as usize;
                let part = bytes[at..at + n].to_vec();
                at += n;
                (name.to_string(), part)
            })
            .collect();
        let (control, rows_read, dt_estimate, counters, finished) = self.host_state();
        let saved = GpuSaved {
            control: bytemuck::bytes_of(&control).to_vec(),
            rows_read,
            dt_estimate,
            counters,
            finished,
            contact: self.state().contact.as_ref().map(|c| {
                (
                    bytemuck::bytes_of(&c.params).to_vec(),
                    bytemuck::bytes_of(&c.counters).to_vec(),
                    c.grows,
                )
            }),
            buffers,
        };
        postcard::to_stdvec(&saved).map_err(|e| bad(format!("cannot encode it: {e}")))
    }

    /// Continues from a state saved by [`GpuSolver::save_state`] of a solver of the same scene.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] when the bytes do not decode or do not fit this solver's buffers.
    pub fn restore_state(&mut self, bytes: &[u8]) -> Result<()> {
        let s: GpuSaved =
            postcard::from_bytes(bytes).map_err(|e| bad(format!("cannot decode it: {e}")))?;
        let control: Control = pod(&s.control, "control block")?;
        let contact = match (&s.contact, self.state().contact.is_some()) {
            (Some((p, c, grows)), true) => Some((
                pod::<ContactParams>(p, "contact parameters")?,
                pod::<ContactCounters>(c, "contact counters")?,
                *grows,
            )),
            (None, false) => None,
            _ => {
                return Err(bad(
                    "saved with and restored without contact, or the reverse".into(),
                ))
            }
        };
        // The candidate buffer grown as it was, before the sizes are compared.
        if let Some((params, _, _)) = contact {
            self.resize_contact_candidates(params.cand_capacity)?;
        }
        let list = self.checkpoint_buffers();
        let fits = list.len() == s.buffers.len()
            && list
                .iter()
                .zip(&s.buffers)
                .all(|((n, b), (m, bytes))| *n == m && b.size() == bytes.len() as u64);
        if !fits {
            return Err(bad(
                "its buffers do not match this scene's (another scene, plan or version)".into(),
            ));
        }
        let queue = &self.context().queue;
        for ((_, b), (_, bytes)) in list.iter().zip(&s.buffers) {
            queue.write_buffer(b, 0, bytes);
        }
        if let Some((params, counters, grows)) = contact {
            if let Some(c) = self.state_mut().contact.as_mut() {
                c.params = params;
                c.counters = counters;
                c.grows = grows;
                c.forget_written();
            }
        }
        self.set_host_state(control, s.rows_read, s.dt_estimate, s.counters, s.finished);
        Ok(())
    }
}

fn pod<T: bytemuck::Pod>(bytes: &[u8], what: &str) -> Result<T> {
    if bytes.len() != std::mem::size_of::<T>() {
        return Err(bad(format!("{what}: {} bytes", bytes.len())));
    }
    Ok(bytemuck::pod_read_unaligned(bytes))
}
