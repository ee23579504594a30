//! The bench's timing: rounds of variants timed in alternation (the order reversed every other
//! round) and their medians, the bare element-and-update loop a full step is compared with, and
//! the [`Timed`] solvers (the CPU reference, [`crate::step::cpu::CpuSolver`], and its GPU twin,
//! [`crate::gpu::GpuSolver`]) as the block and contact benches drive them.

use std::time::Instant;

use crate::element::{evaluate_with, Dissipation};
use crate::error::{Error, Result};
use crate::geometry::{quad_geometry, QuadGeometry};
use crate::gpu::GpuSolver;
use crate::model::Model;
use crate::step::cpu::CpuSolver;
use crate::step::Solver;

/// Rounds by default: each variant is timed this many times, alternating, and medians reported.
pub const DEFAULT_ROUNDS: u32 = 5;

pub(super) use crate::gpu::probe::median;

/// The bare element-and-update loop on the CPU: what the element kernel does every step (gather,
/// stress, hourglass and bulk-viscosity forces scattered to the nodes, the dissipative state and
/// its work, each element's stable step and inversion measure, kept as a running minimum), then
/// the central-difference velocity and displacement update, at a fixed step; nothing else (no step
/// control or failure handling, no energies, boundaries, loads, contact or outputs). The floor a
/// step of a scene without contact is compared with.
pub(super) struct BareLoop {
    model: Model,
    geometry: Vec<QuadGeometry>,
    inv_mass: Vec<f64>,
    u: Vec<[f64; 2]>,
    v: Vec<[f64; 2]>,
    f: Vec<[f64; 2]>,
    dissipation: Vec<Dissipation>,
    dt: f64,
    /// Smallest element step and corner measure of the last step, and the work so far (kept so
    /// that the element evaluation is not pruned as unused).
    dt_min: f64,
    min_corner: f64,
    work: f64,
}

impl BareLoop {
    /// The loop over `model` at the fixed step `dt`, from rest but for the model's initial
    /// velocities.
    pub(super) fn new(model: Model, dt: f64) -> Self {
        let (nn, ne) = (model.node_count(), model.element_count());
        Self {
            geometry: model.corners.iter().map(quad_geometry).collect(),
            inv_mass: model.mass.iter().map(|m| 1.0 / m).collect(),
            u: vec![[0.0; 2]; nn],
            v: model.velocity.clone(),
            f: vec![[0.0; 2]; nn],
            dissipation: vec![Dissipation::default(); ne],
            model,
            dt,
            dt_min: f64::INFINITY,
            min_corner: f64::INFINITY,
            work: 0.0,
        }
    }

    /// Takes `steps` steps.
    pub(super) fn run_steps(&mut self, steps: u64) {
        let dt = self.dt;
        for _ in 0..steps {
            for f in &mut self.f {
                *f = [0.0; 2];
            }
            let (mut dt_min, mut min_corner) = (f64::INFINITY, f64::INFINITY);
            for e in 0..self.model.element_count() {
                let q = self.model.quads[e];
                let ue = q.map(|i| self.u[i as usize]);
                let ve = q.map(|i| self.v[i as usize]);
                let out = evaluate_with(
                    self.model.params(e),
                    &self.geometry[e],
                    &self.model.corners[e],
                    &ue,
                    &ve,
                    &self.dissipation[e],
                    dt,
                );
                for a in 0..4 {
                    let n = q[a] as usize;
                    self.f[n][0] += out.force[a][0];
                    self.f[n][1] += out.force[a][1];
                }
                dt_min = dt_min.min(out.dt);
                min_corner = min_corner.min(out.min_corner);
                self.work += out.hourglass_work + out.bulk_work;
                self.dissipation[e] = out.dissipation;
            }
            self.dt_min = std::hint::black_box(dt_min);
            self.min_corner = std::hint::black_box(min_corner);
            for ((v, f), m) in self.v.iter_mut().zip(&self.f).zip(&self.inv_mass) {
                v[0] += dt * m * f[0];
                v[1] += dt * m * f[1];
            }
            for (u, v) in self.u.iter_mut().zip(&self.v) {
                u[0] += dt * v[0];
                u[1] += dt * v[1];
            }
        }
        self.work = std::hint::black_box(self.work);
    }
}

/// Times `f(steps)` and returns the wall seconds.
pub(super) fn timed(f: impl FnOnce() -> Result<()>) -> Result<f64> {
    let t0 = Instant::now();
    f()?;
    Ok(t0.elapsed().as_secs_f64())
}

/// Times `steps` steps of `solver` and returns the wall seconds; [`Error::Bench`] naming `what`
/// when it took fewer.
pub(super) fn timed_steps(solver: &mut dyn Timed, steps: u64, what: &str) -> Result<f64> {
    let mut taken = 0;
    let t = timed(|| {
        taken = solver.take(steps)?;
        Ok(())
    })?;
    if taken < steps {
        return Err(stopped(what, taken, steps));
    }
    Ok(t)
}

/// Per-round wall seconds of the four variants of the block bench, timed in alternation (see
/// [`alternate`]).
pub(super) struct Rounds {
    /// The full step.
    pub(super) full: Vec<f64>,
    /// The bare loop.
    pub(super) bare: Vec<f64>,
    /// The block on its base with contact.
    pub(super) contact: Vec<f64>,
    /// The same without contact.
    pub(super) free: Vec<f64>,
}

impl Rounds {
    /// Runs `rounds` rounds of `variants` (full, bare, contact, free) in alternation.
    pub(super) fn measure(
        rounds: u32,
        mut variants: [&mut dyn FnMut() -> Result<f64>; 4],
    ) -> Result<Rounds> {
        let mut times = alternate(rounds, &mut variants)?.into_iter();
        let mut next = || times.next().unwrap_or_default();
        Ok(Rounds {
            full: next(),
            bare: next(),
            contact: next(),
            free: next(),
        })
    }

    /// (median full / bare, median extra seconds per step of the contact, median contact share).
    pub(super) fn ratios(&self, per_round: u64) -> (f64, f64, f64) {
        let pairs = |a: &[f64], b: &[f64], g: &dyn Fn(f64, f64) -> f64| {
            median(a.iter().zip(b).map(|(x, y)| g(*x, *y)).collect())
        };
        (
            pairs(&self.full, &self.bare, &|f, b| f / b),
            pairs(&self.contact, &self.free, &|c, f| {
                (c - f) / per_round as f64
            }),
            pairs(&self.contact, &self.free, &|c, f| (c - f) / c),
        )
    }
}

/// Steps per round: `steps` split over `rounds` (at least one each).
pub(super) fn per_round(steps: u64, rounds: u32) -> u64 {
    steps.div_ceil(u64::from(rounds.max(1))).max(1)
}

/// The error of a run that stopped after `taken` of its `wanted` steps.
pub(super) fn stopped(what: &str, taken: u64, wanted: u64) -> Error {
    Error::Bench(format!(
        "the {what} run stopped after {taken} of {wanted} steps"
    ))
}

/// Times `variants` in `rounds` rounds, alternating (the order reversed every other round, so
/// that a drift of the machine's speed falls on all of them alike); returns each variant's
/// per-round wall seconds.
pub(super) fn alternate(
    rounds: u32,
    variants: &mut [&mut dyn FnMut() -> Result<f64>],
) -> Result<Vec<Vec<f64>>> {
    let mut times = vec![Vec::new(); variants.len()];
    let mut order: Vec<usize> = (0..variants.len()).collect();
    for k in 0..rounds {
        if k > 0 {
            order.reverse();
        }
        for &i in &order {
            let t = (variants[i])()?;
            times[i].push(t);
        }
    }
    Ok(times)
}

/// A solver of one variant of a contact scene, as the bench drives it.
pub(super) trait Timed {
    /// Takes `steps` steps; the steps taken.
    fn take(&mut self, steps: u64) -> Result<u64>;
    /// The solver's counters.
    fn count(&self) -> crate::step::Counters;
}

impl Timed for CpuSolver {
    fn take(&mut self, steps: u64) -> Result<u64> {
        let before = self.steps();
        self.run_steps(steps);
        Ok(self.steps() - before)
    }
    fn count(&self) -> crate::step::Counters {
        self.counters()
    }
}

impl Timed for GpuSolver {
    fn take(&mut self, steps: u64) -> Result<u64> {
        self.run_steps(steps)
    }
    fn count(&self) -> crate::step::Counters {
        self.counters()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
    }
}
