//! Test hooks of the GPU solver: the contact search's candidates and active slots and the contact
//! tables read back from the device (checked against the CPU reference's broad phase, `crate::contact::broad`, in
//! `tests/gpu/general.rs`), the grow events, and the element stage run alone on given nodes
//! (against [`crate::element::evaluate`] in `tests/gpu.rs`).

use crate::error::{Error, Result};
use crate::gpu::contact::colouring::{PAIR_INDEX, PAIR_LEADER, PARTNER};
use crate::gpu::contact::narrow::CONS_SIZE;
use crate::gpu::contact::tables::{GpuSegment, GpuSlot};

use super::GpuSolver;

impl GpuSolver {
    /// Times a contact buffer grew (the candidates) or a colouring was enlarged during the run.
    pub fn contact_grows(&self) -> u32 {
        self.state.contact.as_ref().map_or(0, |c| c.grows)
    }

    /// Test hook: each slot's candidate segments from the last device search ([`crate::contact::Tables`]
    /// numbering), read back from the device (one extra readback).
    ///
    /// # Errors
    /// [`Error::Gpu`] when the scene has no contact or the device is lost.
    pub fn contact_candidates(&mut self) -> Result<Vec<Vec<u32>>> {
        let Some(c) = self.state.contact.as_ref() else {
            return Err(Error::Gpu("the scene has no contact".into()));
        };
        let p = c.params;
        let (Some(ws), Some(grow)) = (c.binding(13).cloned(), c.binding(14).cloned()) else {
            return Err(Error::Gpu("contact buffers missing".into()));
        };
        let n = p.n_slots as u64;
        let off_bytes = 4 * (n + 1);
        let cand_bytes = 4 * p.cand_capacity as u64;
        let bytes = self.read_copies(
            "candidates_readback",
            &[
                (&ws, 4 * p.o_coff as u64, off_bytes),
                (&grow, 0, cand_bytes),
            ],
        )?;
        let w: &[u32] = bytemuck::cast_slice(&bytes);
        let (off, cand) = w.split_at(n as usize + 1);
        Ok((0..n as usize)
            .map(|k| cand[off[k] as usize..off[k + 1] as usize].to_vec())
            .collect())
    }

    /// Test hook: the active slots of the last device search (those that can have a constraint
    /// until the next: a pass slot with candidates, a wall slot near its wall), in slot order
    /// ([`crate::contact::Tables`] numbering), read back from the device (one extra readback).
    ///
    /// # Errors
    /// [`Error::Gpu`] when the scene has no contact or the device is lost.
    pub fn contact_active_slots(&mut self) -> Result<Vec<u32>> {
        let Some(c) = self.state.contact.as_ref() else {
            return Err(Error::Gpu("the scene has no contact".into()));
        };
        let p = c.params;
        let Some(ws) = c.binding(13).cloned() else {
            return Err(Error::Gpu("contact buffers missing".into()));
        };
        let n = p.n_slots as u64;
        let bytes = self.read_copies(
            "active_readback",
            &[
                (&ws, 4 * (p.o_aoff as u64 + n), 4),
                (&ws, 4 * p.o_alist as u64, 4 * n.max(1)),
            ],
        )?;
        let w: &[u32] = bytemuck::cast_slice(&bytes);
        let count = (w[0] as usize).min(n as usize);
        Ok(w[1..1 + count].to_vec())
    }

    /// Test hook: the contact slots and segments as the device holds them (the fixed candidate
    /// lists of an eroding scene under their mask), read back (one extra readback).
    ///
    /// # Errors
    /// [`Error::Gpu`] when the scene has no contact or the device is lost.
    pub fn contact_tables(&mut self) -> Result<(Vec<GpuSlot>, Vec<GpuSegment>)> {
        let Some(c) = self.state.contact.as_ref() else {
            return Err(Error::Gpu("the scene has no contact".into()));
        };
        let (Some(slots), Some(segs)) = (c.binding(7).cloned(), c.binding(8).cloned()) else {
            return Err(Error::Gpu("contact buffers missing".into()));
        };
        let (ns, ng) = (slots.size(), segs.size());
        let bytes = self.read_copies("tables_readback", &[(&slots, 0, ns), (&segs, 0, ng)])?;
        let (a, b) = bytes.split_at(ns as usize);
        Ok((
            bytemuck::pod_collect_to_vec(a),
            bytemuck::pod_collect_to_vec(b),
        ))
    }

    /// Test hook: the one-workgroup solve's last compaction: its Lagrange constraints in the
    /// order of their colours ([`LastColouring`]), read back from the device (one extra readback).
    /// Compare with [`crate::gpu::contact::colouring::colours`].
    ///
    /// # Errors
    /// [`Error::Gpu`] when the scene has no contact, its solve takes the per-colour path, or the
    /// device is lost.
    pub fn contact_last_colouring(&mut self) -> Result<LastColouring> {
        let Some(c) = self.state.contact.as_ref() else {
            return Err(Error::Gpu("the scene has no contact".into()));
        };
        if c.multi() {
            return Err(Error::Gpu(
                "the per-colour path colours in the search".into(),
            ));
        }
        let p = c.params;
        let (Some(ws), Some(slots), Some(cons)) = (
            c.binding(13).cloned(),
            c.binding(7).cloned(),
            c.binding(11).cloned(),
        ) else {
            return Err(Error::Gpu("contact buffers missing".into()));
        };
        let n = p.n_slots as u64;
        let ends = PARTNER as u64 + 2;
        let (sb, cb) = (slots.size(), cons.size());
        let bytes = self.read_copies(
            "colouring_readback",
            &[
                (&ws, 4 * p.o_loff as u64, 4 * ends),
                (&ws, 4 * p.o_act as u64, 4 * n.max(1)),
                (&ws, 4 * p.o_color as u64, 4 * n.max(1)),
                (&ws, 4 * p.o_pair as u64, 4 * n.max(1)),
                (&slots, 0, sb),
                (&cons, 0, cb),
            ],
        )?;
        let w: &[u32] = bytemuck::cast_slice(&bytes);
        let (offsets, rest) = w.split_at(ends as usize);
        let (act, rest) = rest.split_at(n.max(1) as usize);
        let (listed, rest) = rest.split_at(n.max(1) as usize);
        let (codes, rest) = rest.split_at(n.max(1) as usize);
        let (slot_words, cons_words) = rest.split_at((sb / 4) as usize);
        let table: Vec<GpuSlot> = bytemuck::pod_collect_to_vec(slot_words);
        let total = (offsets[ends as usize - 1] as usize).min(n as usize);
        let stride = (CONS_SIZE / 4) as usize;
        let constraints = act[..total]
            .iter()
            .map(|&k| {
                let at = k as usize * stride;
                (
                    k,
                    [table[k as usize].s, cons_words[at + 1], cons_words[at + 2]],
                )
            })
            .collect();
        let pairs = act[..total]
            .iter()
            .filter(|&&k| codes[k as usize] & PAIR_LEADER != 0)
            .map(|&k| (k, listed[(codes[k as usize] & PAIR_INDEX) as usize]))
            .collect();
        Ok(LastColouring {
            constraints,
            offsets: offsets.to_vec(),
            pairs,
        })
    }

    /// Kernel test hook: uploads displacements `u` and half-step velocities `v`, runs the element
    /// stage once, and returns each element's nodal forces and stable step.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the device is lost.
    #[allow(clippy::type_complexity)]
    pub fn element_stage(
        &mut self,
        u: &[[f64; 2]],
        v: &[[f64; 2]],
    ) -> Result<(Vec<[[f64; 2]; 4]>, Vec<f64>)> {
        let data: Vec<[f32; 4]> = u
            .iter()
            .zip(v)
            .map(|(u, v)| [u[0] as f32, u[1] as f32, v[0] as f32, v[1] as f32])
            .collect();
        self.ctx
            .queue
            .write_buffer(&self.state.nodes, 0, bytemuck::cast_slice(&data));
        let ne = self.state.params.n_elems as u64;
        let enc = self.encode_pass("element", |pass| {
            self.state.record_element(&self.kernels, pass)
        });
        self.ctx.queue.submit([enc.finish()]);
        let (force, dt) = (self.state.elem_force.clone(), self.state.elem_dt.clone());
        let bytes = self.read_copies(
            "element_readback",
            &[(&force, 0, 32 * ne), (&dt, 0, 4 * ne)],
        )?;
        let f: &[f32] = bytemuck::cast_slice(&bytes);
        let n = ne as usize;
        let forces = (0..n)
            .map(|e| {
                std::array::from_fn(|a| [f[8 * e + 2 * a] as f64, f[8 * e + 2 * a + 1] as f64])
            })
            .collect();
        let dt = (0..n).map(|e| f[8 * n + e] as f64).collect();
        Ok((forces, dt))
    }
}

/// The one-workgroup solve's last compaction ([`GpuSolver::contact_last_colouring`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LastColouring {
    /// Its Lagrange constraints by colour, each its slot and its nodes (slave, segment ends;
    /// `u32::MAX` for a wall's missing segment).
    pub constraints: Vec<(u32, [u32; 3])>,
    /// Where each colour starts in `constraints` (colours 0 to 31, the serial colour
    /// [`crate::gpu::contact::colouring::SERIAL`], then the partners of the pairs, [`PARTNER`]),
    /// then the end: [`PARTNER`] + 2 entries.
    pub offsets: Vec<u32>,
    /// The pairs solved as 2 x 2 blocks: (leader's slot, partner's slot), the leader coloured
    /// with both constraints' nodes, the partner listed under [`PARTNER`].
    pub pairs: Vec<(u32, u32)>,
}
