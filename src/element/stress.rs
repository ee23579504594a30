//! The stress of the material models, CPU reference: linear elastic (small strain),
//! neo-Hookean and, from the virgin state, J2 plastic ([`super::plastic`]); plane strain, plane
//! stress (the neo-Hookean's out-of-plane stretch by Newton) and axisymmetric. The GPU twin is
//! the stress part of `shaders/element.wgsl`.

use super::params::ElementParams;
use super::plastic::{j2_stress, PlasticState};
use crate::scene::{Formulation, MaterialModel};

/// First Piola-Kirchhoff stress (xx xy yx yy), strain energy per reference volume, the Cauchy
/// stress (xx yy xy zz) and the out-of-plane first Piola-Kirchhoff stress P_33 for the in-plane
/// deformation gradient `f` with determinant `j` and the out-of-plane stretch `f33` (used by
/// axisymmetric bodies: r / R; 1 otherwise). A J2 plastic material from the virgin state: see
/// [`super::evaluate_state`] for a yielded one.
#[inline(always)]
pub fn stress(p: &ElementParams, f: &[f64; 4], j: f64, f33: f64) -> ([f64; 4], f64, [f64; 4], f64) {
    match p.model {
        MaterialModel::LinearElastic => {
            let exx = f[0] - 1.0;
            let eyy = f[3] - 1.0;
            let exy = 0.5 * (f[1] + f[2]);
            // The hoop strain u_r / R (axisymmetric; 0 in plane strain, free in plane stress).
            let ezz = f33 - 1.0;
            let tr = exx + eyy + ezz;
            let sxx = p.lambda_plane * tr + 2.0 * p.mu * exx;
            let syy = p.lambda_plane * tr + 2.0 * p.mu * eyy;
            let sxy = 2.0 * p.mu * exy;
            let szz = match p.formulation {
                Formulation::PlaneStrain => p.lambda * tr,
                Formulation::PlaneStress => 0.0,
                Formulation::Axisymmetric => p.lambda * tr + 2.0 * p.mu * ezz,
            };
            let w = 0.5 * (sxx * exx + syy * eyy + 2.0 * sxy * exy + szz * ezz);
            ([sxx, sxy, sxy, syy], w, [sxx, syy, sxy, szz], szz)
        }
        MaterialModel::NeoHookean => {
            // F33 = 1 (plane strain), from sigma_33 = 0 (plane stress, Newton on ln-form) or
            // r / R (axisymmetric, given).
            let f33 = match p.formulation {
                Formulation::PlaneStrain => 1.0,
                Formulation::PlaneStress => plane_stress_stretch(p.lambda, p.mu, j),
                Formulation::Axisymmetric => f33,
            };
            let jj = j * f33;
            let ln_j = jj.ln();
            // F^-T = cof(F)/J2 : (xx xy yx yy) of F^-T = [f3, -f2, -f1, f0]/j
            let fit = [f[3] / j, -f[2] / j, -f[1] / j, f[0] / j];
            let pk: [f64; 4] =
                std::array::from_fn(|i| p.mu * (f[i] - fit[i]) + p.lambda * ln_j * fit[i]);
            let i1 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] + f[3] * f[3] + f33 * f33;
            let w = 0.5 * p.mu * (i1 - 3.0 - 2.0 * ln_j) + 0.5 * p.lambda * ln_j * ln_j;
            // Cauchy = P F^T / J
            let sxx = (pk[0] * f[0] + pk[1] * f[1]) / jj;
            let sxy = (pk[0] * f[2] + pk[1] * f[3]) / jj;
            let syy = (pk[2] * f[2] + pk[3] * f[3]) / jj;
            // P_33 = mu (F_33 - 1 / F_33) + lambda ln J / F_33; sigma_33 = P_33 F_33 / J.
            let p33 = match p.formulation {
                Formulation::PlaneStress => 0.0,
                _ => p.mu * (f33 - 1.0 / f33) + p.lambda * ln_j / f33,
            };
            let szz = p33 * f33 / jj;
            (pk, w, [sxx, syy, sxy, szz], p33)
        }
        MaterialModel::J2Plastic => {
            let s = j2_stress(p, f, j, f33, &PlasticState::VIRGIN, 0.0);
            (s.pk, s.stored, s.cauchy, s.p33)
        }
    }
}

/// Out-of-plane stretch of a plane-stress neo-Hookean element with in-plane Jacobian `j2`:
/// the root of mu (z^2 - 1) + lambda ln(j2 z) = 0, by a fixed number of Newton steps.
pub fn plane_stress_stretch(lambda: f64, mu: f64, j2: f64) -> f64 {
    let ln_j2 = j2.ln();
    // Small-strain start: z = 1 - lambda ln j2 / (2 mu + lambda).
    let mut z = (1.0 - lambda * ln_j2 / (2.0 * mu + lambda)).max(0.1);
    for _ in 0..6 {
        let g = mu * (z * z - 1.0) + lambda * (ln_j2 + z.ln());
        let dg = 2.0 * mu * z + lambda / z;
        z -= g / dg;
    }
    z
}
