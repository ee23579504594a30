//! The CPU reference's erosion state ([`Erosion`]): which elements failed and left the mesh, the
//! Johnson-Cook damage, and the energy the eroded elements took with them (with, apart, how many
//! eroded because they were about to invert, `run.erosion.inverted`, and how many because their
//! stable step fell below `run.erosion.min_time_step`). The failure criteria
//! themselves are [`crate::element::failure`]; the solver's element stage
//! ([`super::cpu::CpuSolver`]) asks `Erosion::fails` and records with `Erosion::erode`.

use crate::element::{failure, ElementOut};
use crate::model::Model;

/// Erosion state of a CPU run: empty (and never consulted) for a scene without `failure`.
///
/// Saved in checkpoints as part of the solver state (postcard encodes its fields in order, as
/// they stood in the state before they were gathered here).
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Erosion {
    /// Per element: whether it failed and eroded (empty without failure).
    #[serde(default)]
    pub(crate) eroded: Vec<bool>,
    /// Johnson-Cook damage of every element (empty without Johnson-Cook damage).
    #[serde(default)]
    pub(crate) damage: Vec<f64>,
    /// Elements eroded so far.
    #[serde(default)]
    pub(crate) count: u64,
    /// The strain and stored hourglass energy the eroded elements held when they eroded (with
    /// the half-step work of their unapplied last forces).
    #[serde(default)]
    pub(crate) energy: f64,
    /// Of `count`, the elements eroded because they were about to invert
    /// (`run.erosion.inverted`).
    #[serde(default)]
    pub(crate) inverted: u64,
    /// Of `count`, the elements eroded because their stable step fell below
    /// `run.erosion.min_time_step`.
    #[serde(default)]
    pub(crate) small_step: u64,
}

impl Erosion {
    /// The state of `model`'s `ne` elements: flags with `failure`, damage with Johnson-Cook
    /// damage, nothing otherwise.
    pub(crate) fn new(model: &Model, ne: usize, failure: bool) -> Self {
        Erosion {
            eroded: if failure { vec![false; ne] } else { Vec::new() },
            damage: if failure && model.has_damage() {
                vec![0.0; ne]
            } else {
                Vec::new()
            },
            count: 0,
            energy: 0.0,
            inverted: 0,
            small_step: 0,
        }
    }

    /// Whether the scene has failure at all.
    #[inline]
    pub(crate) fn active(&self) -> bool {
        !self.eroded.is_empty()
    }

    /// Whether element `e` has eroded.
    #[inline]
    pub(crate) fn is_eroded(&self, e: usize) -> bool {
        self.eroded.get(e) == Some(&true)
    }

    /// Whether element `e` of `model`, evaluated as `out` over a step `dt` from the equivalent
    /// plastic strain `alpha_old`, fails (its Johnson-Cook damage updated).
    pub(crate) fn fails(
        &mut self,
        model: &Model,
        e: usize,
        out: &ElementOut,
        alpha_old: f64,
        dt: f64,
    ) -> bool {
        let Some(c) = model.params(e).failure else {
            return false;
        };
        let damage = self.damage.get(e).copied().unwrap_or(0.0);
        let check = failure::check(
            &c,
            &out.stress,
            &out.def_grad,
            out.hoop_stretch,
            alpha_old,
            out.plastic.alpha,
            dt,
            damage,
            model.params(e).t_star(out.plastic.heat),
        );
        if let Some(d) = self.damage.get_mut(e) {
            *d = check.damage;
        }
        check.failed
    }

    /// Records element `e` as eroded, taking `energy` with it.
    pub(crate) fn erode(&mut self, e: usize, energy: f64) {
        self.eroded[e] = true;
        self.count += 1;
        self.energy += energy;
    }

    /// Whether a restored state fits a model whose fresh state is `fresh`.
    pub(crate) fn fits(&self, fresh: &Erosion) -> bool {
        self.eroded.len() == fresh.eroded.len()
            && self.damage.len() == fresh.damage.len()
            && self.count as usize <= self.eroded.len()
            && self.inverted + self.small_step <= self.count
    }
}
