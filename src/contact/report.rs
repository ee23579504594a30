//! What the history records: per `[[contact]]` table or wall (one interface each), the
//! force on the first body averaged over the sample interval, the largest penetration and the
//! active slave nodes at the sample step.
//!
//! A pair's force is the force on its first body. A group's is the sum over its constraints of
//! the impulse on the lower-indexed body of each (slave body, segment body) pair (+ when the
//! slave's body comes first in the scene, - when the segment's does, nothing within one body):
//! the net force the group's bodies exert on each other, counted once per pair from the lower
//! body's side; self-contact adds no net force.

use super::ContactSet;

/// What a contact or wall reports at a history sample.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactSample {
    /// Contact force on the first body (or on the wall's bodies), averaged over the interval since
    /// the previous sample.
    pub force: [f64; 2],
    /// Largest penetration at the sample step (after the correction, for Lagrange).
    pub max_penetration: f64,
    /// Slave nodes with a non-zero impulse at the sample step.
    pub active_nodes: u32,
    /// Friction force, averaged as `force`: the sum of the constraints' friction impulses, each
    /// along its slave's tangent t = (-n_y, n_x), n the normal the slave is pushed along (for a
    /// wall, along the wall's t; both passes of a pair count alike). Its vector is in `force`.
    pub ft: f64,
}

/// A contact or wall as the history sees it.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(super) struct Interface {
    pub(super) name: String,
    /// Impulse on the first body since the last sample.
    impulse: [f64; 2],
    /// Impulse on the first body at the last step.
    step_impulse: [f64; 2],
    /// Friction impulse along the tangents since the last sample.
    #[serde(default)]
    tangential: f64,
    /// Force-weighting time since the last sample.
    elapsed: f64,
    active: u32,
    max_penetration: f64,
}

impl ContactSet {
    /// Accumulates the step's impulses, active nodes and penetrations per interface.
    pub(super) fn record(&mut self, dt: f64, dt_n: f64) {
        for i in &mut self.interfaces {
            i.step_impulse = [0.0; 2];
            i.active = 0;
            i.max_penetration = 0.0;
            i.elapsed += dt_n;
        }
        let mut last_slave = (u32::MAX, u32::MAX);
        for k in 0..self.cons.len() {
            let c = self.cons[k];
            let pen = if c.w < 0.0 {
                c.penetration
            } else {
                -(c.g0 + dt * self.relative(&c))
            };
            let i = &mut self.interfaces[c.interface as usize];
            if c.lt != 0.0 {
                let t = c.tangent();
                i.step_impulse[0] += c.sign * c.lt * t[0];
                i.step_impulse[1] += c.sign * c.lt * t[1];
                i.tangential += c.lt;
            }
            if c.lambda > 0.0 {
                i.step_impulse[0] += c.sign * c.lambda * c.n[0];
                i.step_impulse[1] += c.sign * c.lambda * c.n[1];
                if last_slave != (c.interface, c.s) {
                    i.active += 1;
                    last_slave = (c.interface, c.s);
                }
            }
            i.max_penetration = i.max_penetration.max(pen);
        }
        for i in &mut self.interfaces {
            i.impulse[0] += i.step_impulse[0];
            i.impulse[1] += i.step_impulse[1];
        }
    }

    /// The contacts' history values at a sample; resets the interval averages.
    pub fn sample(&mut self) -> Vec<ContactSample> {
        self.interfaces
            .iter_mut()
            .map(|i| {
                let (force, ft) = if i.elapsed > 0.0 {
                    (
                        [i.impulse[0] / i.elapsed, i.impulse[1] / i.elapsed],
                        i.tangential / i.elapsed,
                    )
                } else {
                    ([0.0; 2], 0.0)
                };
                i.impulse = [0.0; 2];
                i.tangential = 0.0;
                i.elapsed = 0.0;
                ContactSample {
                    force,
                    max_penetration: i.max_penetration,
                    active_nodes: i.active,
                    ft,
                }
            })
            .collect()
    }
}
impl Interface {
    pub(super) fn new(name: &str) -> Self {
        Interface {
            name: name.to_string(),
            impulse: [0.0; 2],
            step_impulse: [0.0; 2],
            tangential: 0.0,
            elapsed: 0.0,
            active: 0,
            max_penetration: 0.0,
        }
    }
}
