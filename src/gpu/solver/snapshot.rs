//! Snapshots of the nodal state read back from the device: at the snapshot times of a run
//! (displacements, velocities at t_n, the plastic state, the erosion flags and damage), and on demand (the nodes now). The CPU
//! reference takes the same snapshots from its own arrays ([`crate::step::cpu::CpuSolver`]).

use crate::element::plastic::PlasticState;
use crate::error::{Error, Result};
use crate::step::Snapshot;

use super::{GpuSolver, NodalField};
#[cfg(doc)]
use crate::gpu::element::{ERODED_INVERTED, ERODED_SMALL_STEP};

impl GpuSolver {
    pub(super) fn read_snapshot(&mut self, step: u64, time: f64) -> Result<Snapshot> {
        let (Some(rb), Some(u_snap)) = (self.snap_readback.clone(), self.state.u_snap.clone())
        else {
            return Err(Error::Gpu(
                "snapshot requested without field buffers".into(),
            ));
        };
        let nn = self.names.nodes as u64;
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("snapshot"),
            });
        enc.copy_buffer_to_buffer(&u_snap, 0, &rb, 0, 8 * nn);
        enc.copy_buffer_to_buffer(&self.state.v_prev, 0, &rb, 8 * nn, 8 * nn);
        enc.copy_buffer_to_buffer(&self.state.nodes, 0, &rb, 16 * nn, 16 * nn);
        self.ctx.queue.submit([enc.finish()]);
        let bytes = self.map_read(&rb)?;
        self.counters.readbacks += 1;
        let f: &[f32] = bytemuck::cast_slice(&bytes);
        let n = nn as usize;
        let displacement = (0..n)
            .map(|i| [f[2 * i] as f64, f[2 * i + 1] as f64])
            .collect();
        let velocity = (0..n)
            .map(|i| {
                let vp = [f[2 * n + 2 * i], f[2 * n + 2 * i + 1]];
                let v = [f[4 * n + 4 * i + 2], f[4 * n + 4 * i + 3]];
                [0.5 * (vp[0] + v[0]) as f64, 0.5 * (vp[1] + v[1]) as f64]
            })
            .collect();
        let plastic = self.plastic_state()?;
        let (eroded, damage) = self.erosion_state()?;
        Ok(Snapshot {
            time,
            step,
            displacement,
            velocity,
            plastic,
            eroded,
            damage,
        })
    }

    /// Per element whether it eroded (empty without failure) and its Johnson-Cook damage (empty
    /// without Johnson-Cook damage), as the CPU reference's snapshots carry them.
    pub(crate) fn erosion_state(&mut self) -> Result<(Vec<bool>, Vec<f64>)> {
        let Some(buf) = self.state.erosion.clone() else {
            return Ok((Vec::new(), Vec::new()));
        };
        let ne = self.state.params.n_elems as u64;
        let bytes = self.read_copies("erosion_readback", &[(&buf, 0, 16 * ne)])?;
        let f: &[f32] = bytemuck::cast_slice(&bytes);
        let eroded = (0..ne as usize).map(|e| f[4 * e + 1] != 0.0).collect();
        let damage = if self.state.damage {
            (0..ne as usize).map(|e| f[4 * e + 2] as f64).collect()
        } else {
            Vec::new()
        };
        Ok((eroded, damage))
    }

    /// Elements eroded for `reason`, the erosion state's fourth word: [`ERODED_INVERTED`]
    /// (`run.erosion.inverted`) or [`ERODED_SMALL_STEP`] (`run.erosion.min_time_step`); one
    /// readback, 0 without erosion.
    pub(super) fn eroded_apart(&mut self, reason: f32) -> Result<u64> {
        let Some(buf) = self.state.erosion.clone() else {
            return Ok(0);
        };
        let ne = self.state.params.n_elems as u64;
        let bytes = self.read_copies("erosion_readback", &[(&buf, 0, 16 * ne)])?;
        let f: &[f32] = bytemuck::cast_slice(&bytes);
        Ok((0..ne as usize).filter(|&e| f[4 * e + 3] == reason).count() as u64)
    }

    /// The plastic state of every element (empty without a plastic body): C_p^-1 = I + the
    /// stored deviation, alpha and the temperature rise (0 without thermal softening).
    pub(super) fn plastic_state(&mut self) -> Result<Vec<PlasticState>> {
        let Some(buf) = self.state.plastic.clone() else {
            return Ok(Vec::new());
        };
        let ne = self.state.params.n_elems as u64;
        let bytes = self.read_copies("plastic_readback", &[(&buf, 0, 32 * ne)])?;
        let f: &[f32] = bytemuck::cast_slice(&bytes);
        Ok((0..ne as usize)
            .map(|e| {
                let d = &f[8 * e..8 * e + 4];
                PlasticState {
                    cp_inv: [
                        1.0 + d[0] as f64,
                        1.0 + d[1] as f64,
                        d[2] as f64,
                        1.0 + d[3] as f64,
                    ],
                    alpha: f[8 * e + 4] as f64,
                    heat: f[8 * e + 6] as f64,
                }
            })
            .collect())
    }

    /// Reads the current nodal displacements and half-step velocities (one extra readback).
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost.
    pub fn nodes(&mut self) -> Result<(NodalField, NodalField)> {
        let nn = self.names.nodes as u64;
        let nodes = self.state.nodes.clone();
        let bytes = self.read_copies("nodes_readback", &[(&nodes, 0, 16 * nn)])?;
        let f: &[f32] = bytemuck::cast_slice(&bytes);
        let n = nn as usize;
        Ok((
            (0..n)
                .map(|i| [f[4 * i] as f64, f[4 * i + 1] as f64])
                .collect(),
            (0..n)
                .map(|i| [f[4 * i + 2] as f64, f[4 * i + 3] as f64])
                .collect(),
        ))
    }
}
