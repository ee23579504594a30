//! The diagonal-mass Lagrange correction on the device (`shaders/contact_solve.wgsl`): projected
//! Gauss-Seidel over the colours of the last search and the active-set update, either in one
//! workgroup (`solve_one`, its re-checks inside it or, with many slots, in `recheck_active`
//! over many workgroups) or one dispatch per colour and sweep (`sweep_color`, `recheck`); the
//! choice of path by size, the pipelines and their dispatches. CPU reference: the sweeps and
//! re-check of [`crate::contact::ContactSet::apply`] (`crate::contact::solve`).

use super::kernels::stage_kernels;
use super::{groups, Dispatch, COLOR_ENTRY, MAX_COLORS, MAX_SWEEP_SLOTS, ROUND_ENTRIES};

/// WGSL source (compiled after [`super::narrow::SOURCE`] and [`super::colouring::SOURCE`]).
pub const SOURCE: &str = include_str!("../../../shaders/contact_solve.wgsl");

/// The solve's shader module: its label and stage files (after contact_common.wgsl).
pub const MODULE: (&str, &[&str]) = (
    "contact_solve",
    &[super::narrow::SOURCE, super::colouring::SOURCE, SOURCE],
);

/// Sweeps per solve at most on the device (one-workgroup path), as on the CPU.
pub const MAX_SWEEPS: u32 = crate::contact::MAX_SWEEPS as u32;

/// Sweeps per round on the per-colour path (each sweep is one dispatch per colour, so they are
/// recorded ahead; WGSL `MAX_SWEEP_SLOTS` = 5 rounds of these). A solve still above its tolerance
/// at a round's last sweep goes on in the next round's sweeps (after that round's re-check), so a
/// step takes up to 80: with 16 a solve and a new one only after a re-check that added
/// constraints, the per-colour path left 39 of the 0.3 c impact's steps unconverged
/// (`tests/gpu/stress.rs`, 1.4e-6 m of penetration reported, 1 step and 5.5e-8 m going on;
/// the one-workgroup path 0 and 4.1e-8 m) on lavapipe, 2026-11-29.
pub const MULTI_SWEEPS: u32 = 16;

/// A sweep converges when no gap changes by more than this fraction of the search margin. The
/// margin is half the shortest segment, and f32 resolves relative coordinates to about 1e-7 of
/// an element, so this is about 50 f32 units of a gap: reachable, and 1e-5 of half an element.
pub const TOLERANCE: f64 = 1e-4;

/// The Lagrange solve stops its sweeps at this fraction of the largest penetration of the step's
/// free update among its constraints, within [`STOP_FLOOR`] and 1 times [`TOLERANCE`] of the
/// margin, on both paths (WGSL `stop_tolerance`; the narrow phase and the re-checks keep the
/// step's largest penetration in the contact state), and a step whose last sweep changed a gap
/// by more counts as not converged. With the margin's tolerance alone, a contact under a steady
/// load stopped after one sweep a step with the multipliers up to a tenth of that step's impulse
/// off: on the contact patch test's 8/6 mesh (8.6e-5 m of free penetration a step, a stop of
/// 8e-6 m), the GPUs' parallel colouring (stress error 1.6e-2 p, kinetic over strain energy
/// 1.3e-4, on lavapipe with the GPUs' options, 2026-11-28) and the per-colour path (2.5e-2 p,
/// 2026-11-29) settled into an oscillation instead of the uniform pressure, where the
/// one-workgroup solve in slot order passed. Impacts, whose free update
/// penetrates by far more than the margin's tolerance a hundredfold, keep it: the bench
/// striker's sweeps stayed 15.4 (10^4 elements) and 27.7 (10^5); the pile's resting disks went
/// 1.2 -> 1.9 a step.
pub const STOP_PENETRATION: f64 = 1e-2;

/// The tightest stop of the device's solve, as a fraction of [`TOLERANCE`]: 1e-5 of the
/// margin, the CPU reference's stop ([`crate::contact::SWEEP_TOLERANCE`]), about 5 f32 units of
/// a gap.
pub const STOP_FLOOR: f64 = 0.1;

/// Slots from which the per-colour path is used on a discrete or integrated GPU. On CPU adapters
/// (lavapipe) a dispatch costs more than a colour's work, and the one-workgroup path is used.
///
/// Measured on an NVIDIA H100 (BENCHMARKS.md, GPU timestamps per stage): the per-colour path
/// records its sweeps ahead, 80 sweeps x 8 colours of indirect dispatches a step, and these cost
/// about 2.8 ms of device time a step even when empty, against 5 us to 1.9 ms for the
/// one-workgroup solve on every bench scene up to 10^6 elements (the striker at 10^6: 1.86 ms
/// with 65 sweeps a step, against 3.53 ms). So the one workgroup is used up to 2^20 slots.
pub const MULTI_SLOTS: usize = 1 << 20;

/// Slots from which the one-workgroup solve leaves its active-set re-checks to their own
/// dispatches (`recheck_active`, one thread per active slot) on a discrete or integrated GPU:
/// each re-check runs the narrow phase again on every active slot, which the solve's one
/// workgroup does serially. Split, a step records 4 re-checks and 4 more rounds of `solve_one`,
/// most of which return at once.
///
/// Measured on an NVIDIA H100 (BENCHMARKS.md, 2026-11-24, d7fa36a; device time of the solve
/// part, the disks in contact): the 10^6-element pile (480 000 slots) 335 -> 134 us a step
/// split, the step 1 070 -> 855 us; the 10^5 pile (49 152 slots) 47 -> 51 us, and the 10^5 striker
/// (about 2 000 slots, 100 sweeps a step) 1 038 -> 1 068 us: below this size the extra
/// dispatches cost more than the re-checks they spread.
pub const SPLIT_SLOTS: usize = 1 << 16;

/// Whether the per-colour path is used for `slots` slots on an adapter of `device_type`.
pub fn multi_path(slots: usize, device_type: wgpu::DeviceType) -> bool {
    device_type != wgpu::DeviceType::Cpu && slots >= MULTI_SLOTS
}

/// Whether the one-workgroup solve leaves its re-checks to their own dispatches, for `slots`
/// slots on an adapter of `device_type` (see [`SPLIT_SLOTS`]).
pub fn split_path(slots: usize, device_type: wgpu::DeviceType) -> bool {
    device_type != wgpu::DeviceType::Cpu && slots >= SPLIT_SLOTS
}

stage_kernels! {
    /// The solve's pipelines: the one-workgroup path's (`solve_one`, `recheck_active`) and the
    /// per-colour path's (`sweep_color`, `recheck`).
    SolveKernels: solve_one, recheck_active, sweep_color, recheck
}

impl SolveKernels {
    /// Records the solve on the path of the parameters: in one workgroup (split: each round of
    /// `solve_one`, index entry r, then its re-check over the active slots), or per colour (the
    /// sweeps recorded ahead, one dispatch per colour and sweep, index entry (colour, sweep), and
    /// a re-check after each round's sweeps).
    pub(crate) fn record(&self, d: &Dispatch<'_>, pass: &mut wgpu::ComputePass<'_>) {
        let p = d.params;
        if p.multi == 0 && p.split != 0 {
            let rounds = crate::contact::ACTIVE_SET_ROUNDS as u64;
            for r in 0..=rounds {
                d.bind(pass, r);
                d.direct(pass, &self.solve_one, 1);
                if r < rounds {
                    d.active(pass, &self.recheck_active);
                }
            }
            d.bind(pass, 0);
        } else if p.multi == 0 {
            d.direct(pass, &self.solve_one, 1);
        } else {
            let rounds = MAX_SWEEP_SLOTS / p.max_sweeps;
            for r in 0..rounds {
                pass.set_pipeline(&self.sweep_color);
                for s in 0..p.max_sweeps {
                    let q = r * p.max_sweeps + s;
                    for c in 0..p.colors_recorded {
                        d.bind(pass, ROUND_ENTRIES + (q * MAX_COLORS + c) as u64);
                        d.indirect(pass, (COLOR_ENTRY + c) as u64);
                    }
                }
                if r + 1 < rounds {
                    pass.set_pipeline(&self.recheck);
                    d.bind(pass, r as u64);
                    pass.dispatch_workgroups(groups(p.n_slots), 1, 1);
                }
            }
            d.bind(pass, 0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The WGSL stop (`stop_tolerance`) has the constants documented here, and its floor is
    /// the CPU reference's stop.
    #[test]
    fn the_kernel_stops_where_the_constants_say() {
        let common = super::super::COMMON;
        assert!(common.contains(&format!(
            "const STOP_PENETRATION: f32 = {STOP_PENETRATION:e};"
        )));
        assert!(common.contains(&format!("const STOP_FLOOR: f32 = {STOP_FLOOR};")));
        assert!((STOP_FLOOR * TOLERANCE - crate::contact::SWEEP_TOLERANCE).abs() < 1e-20);
    }
}
