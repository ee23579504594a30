//! Material failure, CPU reference: the criteria of a material's `failure` table
//! ([`crate::scene::FailureCriteria`]) checked on one element after its evaluation, and the
//! Johnson-Cook damage that accumulates between steps. The solver erodes an element that fails
//! ([`crate::step::cpu`]: it stops carrying stress at once, its mass stays on its nodes).
//!
//! Conventions (README, "Failure and erosion"):
//! - triaxiality sigma* = sigma_m / sigma_vm of the Cauchy stress after the step (tension
//!   positive; sigma_zz included, so plane strain and axisymmetric bodies see their true
//!   triaxiality); no damage accumulates where sigma_vm = 0 (no plastic flow) or
//!   sigma* < -1/3 (Bao and Wierzbicki 2005's cut-off: no fracture in compression);
//! - the rate term is 1 + d4 ln(max(rate / rate0, 1)), as the flow stress's, with the same
//!   reference rate rate0 (`johnson_cook.reference_strain_rate` of the flow stress, 1/s without
//!   one), rate = d(eps_p) / dt of the step;
//! - the temperature term is 1 + d5 T*, T* the homologous temperature at the end of the step
//!   (the flow stress's, [`crate::element::ElementParams::t_star`]; 0 without thermal softening);
//! - eps_f is bounded below by [`MIN_FAILURE_STRAIN`] (d1 < 0, d4 < 0 at high rates or d5 < 0
//!   would make it negative) and a non-finite eps_f (an exponential overflow) means no damage;
//! - D += d(eps_p) / eps_f with eps_f at the end of the step; the element fails at D >= 1.
//!
//! The largest principal strain is the logarithmic (true) strain ln(lambda_max) of the stretches
//! of F (in plane and, F_33, out of plane); the spall limit compares the mean stress sigma_m
//! (tension positive, -p) with `tensile_pressure`.

use crate::scene::{FailureCriteria, JohnsonCookDamage};

/// The smallest Johnson-Cook failure strain: where d1 + d2 exp(d3 sigma*) times the rate and
/// temperature terms falls below it (or goes negative), an element fails after this plastic
/// strain.
pub const MIN_FAILURE_STRAIN: f64 = 1e-3;

/// Mean and von Mises stress of the Cauchy stress `s` (xx, yy, xy, zz).
#[inline(always)]
pub fn invariants(s: &[f64; 4]) -> (f64, f64) {
    let mean = (s[0] + s[1] + s[3]) / 3.0;
    let (a, b, c) = (s[0] - s[1], s[1] - s[3], s[3] - s[0]);
    let vm = (0.5 * (a * a + b * b + c * c) + 3.0 * s[2] * s[2]).sqrt();
    (mean, vm)
}

/// The Johnson-Cook failure strain at triaxiality `triaxiality`, equivalent plastic strain rate
/// `rate` and homologous temperature `t_star` (infinite below sigma* = -1/3 or when not finite;
/// at least [`MIN_FAILURE_STRAIN`] otherwise).
#[inline(always)]
pub fn johnson_cook_failure_strain(
    d: &JohnsonCookDamage,
    triaxiality: f64,
    rate: f64,
    t_star: f64,
) -> f64 {
    if triaxiality.is_nan() || triaxiality < -1.0 / 3.0 {
        return f64::INFINITY;
    }
    let rate_term = 1.0 + d.d4 * (rate / d.reference_strain_rate).max(1.0).ln();
    let eps = (d.d1 + d.d2 * (d.d3 * triaxiality).exp()) * rate_term * (1.0 + d.d5 * t_star);
    if eps.is_nan() || eps == f64::INFINITY {
        f64::INFINITY
    } else {
        eps.max(MIN_FAILURE_STRAIN)
    }
}

/// The largest principal logarithmic strain of the deformation gradient `f` (xx, xy, yx, yy)
/// and out-of-plane stretch `f33`.
#[inline(always)]
pub fn largest_principal_strain(f: &[f64; 4], f33: f64) -> f64 {
    // C = F^T F in plane; its largest eigenvalue is lambda_max^2.
    let c11 = f[0] * f[0] + f[2] * f[2];
    let c22 = f[1] * f[1] + f[3] * f[3];
    let c12 = f[0] * f[1] + f[2] * f[3];
    let m = 0.5 * (c11 + c22);
    let r = (0.5 * (c11 - c22)).hypot(c12);
    (0.5 * (m + r).ln()).max(f33.ln())
}

/// What the failure check of one element found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Check {
    /// Johnson-Cook damage after the step (the input's without Johnson-Cook damage).
    pub damage: f64,
    /// Whether the element failed in this step.
    pub failed: bool,
}

/// The failure check of an element after its evaluation: `c` its material's criteria, `cauchy`
/// its stress (xx, yy, xy, zz), `f`, `f33` its deformation, `alpha_old`, `alpha` its equivalent
/// plastic strain before and after the step, `dt` the step that led here (0 on the first),
/// `damage` its Johnson-Cook damage before the step and `t_star` its homologous temperature.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn check(
    c: &FailureCriteria,
    cauchy: &[f64; 4],
    f: &[f64; 4],
    f33: f64,
    alpha_old: f64,
    alpha: f64,
    dt: f64,
    damage: f64,
    t_star: f64,
) -> Check {
    let mut failed = false;
    let mut damage = damage;
    if let Some(limit) = c.plastic_strain {
        failed |= alpha >= limit;
    }
    let (mean, vm) = invariants(cauchy);
    if let Some(d) = &c.johnson_cook {
        let d_alpha = alpha - alpha_old;
        if d_alpha > 0.0 && vm > 0.0 {
            let rate = if dt > 0.0 { d_alpha / dt } else { 0.0 };
            damage += d_alpha / johnson_cook_failure_strain(d, mean / vm, rate, t_star);
        }
        failed |= damage >= 1.0;
    }
    if let Some(limit) = c.principal_strain {
        failed |= largest_principal_strain(f, f33) >= limit;
    }
    if let Some(limit) = c.tensile_pressure {
        failed |= mean >= limit;
    }
    Check { damage, failed }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Weldox 460 E (Borvik et al. 2001), rate and temperature at reference.
    const WELDOX: JohnsonCookDamage = JohnsonCookDamage {
        d1: 0.0705,
        d2: 1.732,
        d3: -0.54,
        d4: -0.015,
        d5: 0.0,
        reference_strain_rate: 5e-4,
    };

    #[test]
    fn johnson_cook_failure_strain_matches_its_closed_form() {
        // The research note's table (d1 + d2 exp(d3 sigma*), rate and temperature at reference).
        for (s, eps) in [
            (-1.0 / 3.0, 2.1441),
            (0.0, 1.8025),
            (1.0 / 3.0, 1.5172),
            (1.0, 1.0798),
        ] {
            let e = johnson_cook_failure_strain(&WELDOX, s, 0.0, 0.0);
            assert!((e - eps).abs() < 1e-4, "sigma* {s}: {e} vs {eps}");
        }
        // Below -1/3 no damage; the rate term at 1e4 /s: 1 - 0.015 ln(2e7).
        assert_eq!(
            johnson_cook_failure_strain(&WELDOX, -0.4, 0.0, 0.0),
            f64::INFINITY
        );
        let e = johnson_cook_failure_strain(&WELDOX, 0.0, 1e4, 0.0);
        assert!((e / 1.8025 - (1.0 - 0.015 * (2e7f64).ln())).abs() < 1e-4);
        // Armco iron's d1 < 0: the floor at high triaxiality.
        let armco = JohnsonCookDamage {
            d1: -2.2,
            d2: 5.43,
            d3: -0.47,
            d4: 0.0,
            d5: 0.0,
            reference_strain_rate: 1.0,
        };
        assert_eq!(
            johnson_cook_failure_strain(&armco, 5.0, 0.0, 0.0),
            MIN_FAILURE_STRAIN
        );
    }

    #[test]
    fn each_criterion_fails_an_element_at_its_limit() {
        let uniaxial = [3.0e8, 0.0, 0.0, 0.0];
        let id = [1.0, 0.0, 0.0, 1.0];
        let plastic = FailureCriteria {
            plastic_strain: Some(0.5),
            ..Default::default()
        };
        assert!(!check(&plastic, &uniaxial, &id, 1.0, 0.4, 0.49, 1e-7, 0.0, 0.0).failed);
        assert!(check(&plastic, &uniaxial, &id, 1.0, 0.49, 0.5, 1e-7, 0.0, 0.0).failed);
        // Johnson-Cook at uniaxial tension (sigma* = 1/3): D = d(eps_p) / 1.5172.
        let jc = FailureCriteria {
            johnson_cook: Some(WELDOX),
            ..Default::default()
        };
        let c = check(&jc, &uniaxial, &id, 1.0, 0.0, 0.75, 0.0, 0.0, 0.0);
        assert!((c.damage - 0.75 / 1.5172).abs() < 1e-4 && !c.failed);
        assert!(check(&jc, &uniaxial, &id, 1.0, 0.75, 1.6, 0.0, c.damage, 0.0).failed);
        let principal = FailureCriteria {
            principal_strain: Some(0.1),
            ..Default::default()
        };
        let fails_at = |l: f64| {
            check(
                &principal,
                &uniaxial,
                &[l, 0.0, 0.0, 1.0],
                1.0,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            )
            .failed
        };
        assert!(!fails_at(1.1));
        assert!(fails_at(1.106));
        // Rotation leaves the principal strain unchanged.
        let (co, si) = (0.6f64, 0.8f64);
        let rot = [co * 1.2, -si, si * 1.2, co];
        assert!((largest_principal_strain(&rot, 1.0) - 1.2f64.ln()).abs() < 1e-14);
        let spall = FailureCriteria {
            tensile_pressure: Some(1e9),
            ..Default::default()
        };
        let tension = |p: f64| [p, p, 0.0, p];
        assert!(!check(&spall, &tension(0.99e9), &id, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0).failed);
        assert!(check(&spall, &tension(1e9), &id, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0).failed);
    }
}
