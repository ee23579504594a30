//! Hourglass control of the one-point quad (Flanagan and Belytschko 1981), CPU reference: the
//! forces along the hourglass vector gamma that resist the quad's zero-energy mode, as a
//! stiffness or a viscosity, scaled with the body's shear modulus (see
//! [`ElementParams::hourglass_modulus`]). The GPU twin is the hourglass part of
//! `shaders/element.wgsl`.

use super::params::ElementParams;
use crate::geometry::QuadGeometry;
use crate::scene::HourglassForm;

/// What the hourglass control of one element gives besides its forces.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Hourglass {
    /// Energy stored in the stiffness hourglass springs.
    pub stored: f64,
    /// Viscous hourglass generalized force Q_i (force on node a is -gamma_a Q_i).
    pub q: [f64; 2],
    /// Work dissipated by the viscous hourglass forces over the last step (pairing n-1 and n).
    pub work: f64,
}

/// Adds the hourglass forces of an element (parameters `p`, reference geometry `g`, reference
/// volume `a0t`) at the corner displacements `u` and lagged velocities `v` to `force`, on the
/// reference gamma. `prev_q` is the viscous generalized force of the previous step and `dt_prev`
/// the step that took u^{n-1} to u^n, for the dissipated work. A triangle has no hourglass mode
/// (see [`crate::element`]): no force, not even round-off.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn add_forces(
    p: &ElementParams,
    g: &QuadGeometry,
    a0t: f64,
    u: &[[f64; 2]; 4],
    v: &[[f64; 2]; 4],
    prev_q: &[f64; 2],
    dt_prev: f64,
    force: &mut [[f64; 2]; 4],
) -> Hourglass {
    let mut out = Hourglass::default();
    let form = if g.triangle {
        HourglassForm::None
    } else {
        p.hourglass
    };
    match form {
        HourglassForm::None => {}
        HourglassForm::Stiffness => {
            let k = p.hourglass_coefficient * p.hourglass_modulus * a0t * g.hourglass_stiffness;
            let mut q = [0.0; 2];
            for a in 0..4 {
                q[0] += g.gamma[a] * u[a][0];
                q[1] += g.gamma[a] * u[a][1];
            }
            for a in 0..4 {
                force[a][0] -= k * g.gamma[a] * q[0];
                force[a][1] -= k * g.gamma[a] * q[1];
            }
            out.stored = 0.5 * k * (q[0] * q[0] + q[1] * q[1]);
        }
        HourglassForm::Viscous => {
            // rho c with c = sqrt(2 mu / rho): sqrt(2 mu rho).
            let rho_c = (p.hourglass_modulus * p.density).sqrt();
            let damp = p.hourglass_coefficient * rho_c * a0t * g.hourglass_viscous;
            let mut qd = [0.0; 2];
            for a in 0..4 {
                qd[0] += g.gamma[a] * v[a][0];
                qd[1] += g.gamma[a] * v[a][1];
            }
            out.q = [damp * qd[0], damp * qd[1]];
            for a in 0..4 {
                force[a][0] -= g.gamma[a] * out.q[0];
                force[a][1] -= g.gamma[a] * out.q[1];
            }
            // Dissipated: 1/2 (gamma . du)(Q^{n-1} + Q^n), du = dt_prev v^{n-1/2}.
            out.work =
                0.5 * dt_prev * (qd[0] * (prev_q[0] + out.q[0]) + qd[1] * (prev_q[1] + out.q[1]));
        }
    }
    out
}
