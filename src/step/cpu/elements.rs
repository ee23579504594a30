//! The CPU reference's element stage: every element's stress, nodal forces and stable step at
//! the current state (the plastic return, hourglass and bulk viscosity, the failure check and
//! erosion, pressure forces), summed into the solver's nodal forces. Its GPU twin is
//! `shaders/element.wgsl` (room `src/gpu/element.rs`); the order of the step is in `mod.rs`.

use super::CpuSolver;
use crate::element::plastic::PlasticState;
use crate::element::{evaluate_state, Dissipation, ElementOut};

/// Result of one element stage.
pub(super) struct ElementStage {
    /// The smallest stable step of the elements left (infinite when every one has eroded).
    pub(super) dt_min: f64,
    /// The element that sets it.
    pub(super) dt_element: usize,
    /// Strain energy, when asked for (a sample step).
    pub(super) strain: f64,
    /// Stored hourglass energy, when asked for.
    pub(super) hourglass_stored: f64,
}

impl CpuSolver {
    /// Element `e` at the current displacements and velocities from its plastic state, with the
    /// dissipative state `prev` of the step `dt_prev` before.
    #[inline(always)]
    pub(super) fn evaluate(&self, e: usize, prev: &Dissipation, dt_prev: f64) -> ElementOut {
        let (ue, ve) = self.gather(e);
        evaluate_state(
            self.model.params(e),
            &self.geometry[e],
            &self.model.corners[e],
            &ue,
            &ve,
            prev,
            dt_prev,
            self.s.plastic.get(e).unwrap_or(&PlasticState::VIRGIN),
        )
    }

    #[inline(always)] // not inlined otherwise (stack spills in `step`; +18 % throughput measured)
    fn gather(&self, e: usize) -> ([[f64; 2]; 4], [[f64; 2]; 4]) {
        let q = self.model.quads[e];
        (
            q.map(|i| self.s.u[i as usize]),
            q.map(|i| self.s.v[i as usize]),
        )
    }

    pub(super) fn element_stage(
        &mut self,
        need_energy: bool,
    ) -> std::result::Result<ElementStage, String> {
        for f in &mut self.s.f {
            *f = [0.0; 2];
        }
        let mut st = ElementStage {
            dt_min: f64::INFINITY,
            dt_element: 0,
            strain: 0.0,
            hourglass_stored: 0.0,
        };
        let keep = !self.s.dissipation.is_empty();
        let plastic = !self.s.plastic.is_empty();
        let failure = self.s.erosion.active();
        for e in 0..self.model.element_count() {
            if failure && self.s.erosion.is_eroded(e) {
                continue;
            }
            let q = self.model.quads[e];
            let prev = if keep {
                self.s.dissipation[e]
            } else {
                Dissipation::default()
            };
            let out = self.evaluate(e, &prev, self.s.dt_prev);
            let failed = failure && {
                let alpha_old = self.s.plastic.get(e).map_or(0.0, |p| p.alpha);
                self.s
                    .erosion
                    .fails(&self.model, e, &out, alpha_old, self.s.dt_prev)
            };
            let inverted = out.min_corner.is_nan() || out.min_corner <= 0.0;
            // `run.erosion.min_time_step`: a stable step below the limit erodes the element.
            let small_step = !failed && !inverted && out.dt < self.model.erode_min_dt;
            if failed || (inverted && self.model.erode_inverted) || small_step {
                // Eroded at once (failed, about to invert with `run.erosion.inverted`, or with a
                // stable step below `run.erosion.min_time_step`): no
                // force, no stable step from now on. Its strain and stored hourglass energy
                // leave with it, less the work its forces f_n would have done over the half step
                // before t_n: the energy of the interval pairs f_{n-1} and f_n (trapezoidal),
                // and f_n is never applied, so that the balance closes as on any other step. Its
                // viscous and plastic work of the step are done.
                let v = self.gather(e).1;
                let half_work: f64 = (0..4)
                    .map(|a| out.force[a][0] * v[a][0] + out.force[a][1] * v[a][1])
                    .sum::<f64>()
                    * 0.5
                    * self.s.dt_prev;
                if keep {
                    self.s.hourglass_work += out.hourglass_work;
                    self.s.bulk_work += out.bulk_work;
                    self.s.dissipation[e] = Dissipation::default();
                }
                if plastic {
                    self.s.plastic[e] = out.plastic;
                    self.s.plastic_work += out.plastic_work;
                }
                self.s
                    .erosion
                    .erode(e, out.strain_energy + out.hourglass_stored + half_work);
                if small_step {
                    self.s.erosion.small_step += 1;
                } else if !failed {
                    self.s.erosion.inverted += 1;
                }
                continue;
            }
            if inverted {
                return Err(format!(
                    "{} inverted: smallest corner Jacobian ratio {:.3e}; reduce time_step_scale, \
                     refine the mesh or raise the hourglass coefficient",
                    self.element_name(e),
                    out.min_corner
                ));
            }
            for a in 0..4 {
                let n = q[a] as usize;
                self.s.f[n][0] += out.force[a][0];
                self.s.f[n][1] += out.force[a][1];
            }
            if out.dt < st.dt_min {
                st.dt_min = out.dt;
                st.dt_element = e;
            }
            if keep {
                self.s.hourglass_work += out.hourglass_work;
                self.s.bulk_work += out.bulk_work;
                self.s.dissipation[e] = out.dissipation;
            }
            if plastic {
                self.s.plastic[e] = out.plastic;
                self.s.plastic_work += out.plastic_work;
            }
            if need_energy {
                st.strain += out.strain_energy;
                st.hourglass_stored += out.hourglass_stored;
            }
        }
        // Pressure loads: consistent nodal forces of the pressure at t_n.
        for (k, &(load, node, per_pa)) in self.pressure.iter().enumerate() {
            let p = self.model.pressures[load].at(self.s.t);
            let f = [p * per_pa[0], p * per_pa[1]];
            self.s.f[node as usize][0] += f[0];
            self.s.f[node as usize][1] += f[1];
            // Kept as the force until the node stage turns it into the step's impulse.
            self.s.pressure_impulse[k] = f;
        }
        Ok(st)
    }
}
