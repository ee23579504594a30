//! J2 (von Mises) plasticity at finite strain, CPU reference (the GPU twin is the J2 branch of
//! `shaders/element.wgsl`).
//!
//! The model is hyperelastic-multiplicative (F = F_e F_p), not hypoelastic: the elastic response
//! is Hencky's (stored energy W = K/2 (ln J)^2 + mu |dev ln V_e|^2, V_e the elastic left stretch)
//! and the flow rule is the classical radial return, done in logarithmic strain on the
//! principal axes of the elastic left Cauchy-Green tensor b_e = F C_p^-1 F^T (Eterovic and Bathe
//! 1990; Simo 1992, the exponential-map algorithm). Why this rather than a Jaumann or
//! Green-Naghdi rate:
//! - it is objective exactly, not to first order in the step: a rigid rotation R of F maps b_e to
//!   R b_e R^T, rotates the Kirchhoff stress with it and leaves the state C_p^-1 and the
//!   equivalent plastic strain untouched, whatever the size of the rotation;
//! - an elastic step stores energy in a potential, so the work of the internal forces is the
//!   change of W and the plastic dissipation of a step is the energy the return removes at fixed
//!   F, W(trial) - W(returned): the energy audit of the run closes as it does for the elastic
//!   models, with the dissipation in its own column;
//! - at small strain it is the small-strain radial return (REFERENCES.md section 10), and the
//!   return itself is the closed form of linear hardening: no iteration.
//!
//! Plane strain (F_zz = 1) and axisymmetric (F_zz = r / R, the hoop stretch): the state is
//! C_p^-1 (xx, yy, xy, zz) and the equivalent plastic strain alpha. The stress is the Kirchhoff stress tau = K ln J I + 2 mu dev ln V_e on the return
//! mapped strain; the Cauchy stress is tau / J and the first Piola-Kirchhoff stress tau F^-T.
//! The yield condition is on the Cauchy (true) stress, sigma_vm = tau_vm / J <= sigma_y + H alpha,
//! as a tensile test measures it (on the Kirchhoff stress the yield stress would drift by the
//! elastic volume change, 1 % at 1 % uniaxial strain); with linear hardening the return is still
//! one closed-form step: d alpha = (tau_vm - J (sigma_y + H alpha)) / (3 mu + J H).

use super::params::ElementParams;

/// Plastic state of one element: C_p^-1 (xx, yy, xy, zz), the equivalent plastic strain and
/// the temperature rise of adiabatic heating.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlasticState {
    /// Inverse plastic right Cauchy-Green tensor C_p^-1 (xx, yy, xy, zz); I when virgin.
    pub cp_inv: [f64; 4],
    /// Equivalent plastic strain alpha (the integral of sqrt(2/3) |d_p| dt).
    pub alpha: f64,
    /// Temperature rise above room temperature T - T_r (K) of a material with Johnson-Cook
    /// thermal softening: the sum over the steps of beta dW_p / (rho_0 c_p), dW_p the step's
    /// plastic work per unit reference volume ([`step_plastic_work`]); 0 without heating.
    pub heat: f64,
}

impl PlasticState {
    /// A virgin element: C_p^-1 = I, alpha = 0, at room temperature.
    pub const VIRGIN: Self = Self {
        cp_inv: [1.0, 1.0, 0.0, 1.0],
        alpha: 0.0,
        heat: 0.0,
    };
}

impl Default for PlasticState {
    fn default() -> Self {
        Self::VIRGIN
    }
}

/// The stress of a J2 element and its new state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct J2Stress {
    /// First Piola-Kirchhoff stress (xx, xy, yx, yy).
    pub pk: [f64; 4],
    /// Its out-of-plane (hoop) component P_33 = tau_33 / F_33.
    pub p33: f64,
    /// Cauchy stress (xx, yy, xy, zz).
    pub cauchy: [f64; 4],
    /// Stored (elastic) energy per reference volume after the return.
    pub stored: f64,
    /// Energy the return dissipated, per reference volume: W(trial) - W(returned) >= 0.
    pub dissipated: f64,
    /// The state after the step (bit for bit the old one on an elastic step; its `heat` the
    /// old one: [`crate::element::evaluate_state`] adds the step's heating).
    pub state: PlasticState,
}

/// Principal values and axis of a symmetric 2x2 tensor (xx, yy, xy): (l1 >= l2, cos, sin) of
/// the angle of the first axis.
#[inline(always)]
fn principal(xx: f64, yy: f64, xy: f64) -> (f64, f64, f64, f64) {
    let m = 0.5 * (xx + yy);
    let d = 0.5 * (xx - yy);
    let r = d.hypot(xy);
    let l1 = m + r;
    // The smaller root from the determinant (no cancellation when r is close to m).
    let l2 = (xx * yy - xy * xy) / l1;
    let theta = 0.5 * xy.atan2(d);
    (l1, l2, theta.cos(), theta.sin())
}

/// The symmetric tensor (xx, yy, xy) with principal values `a`, `b` on the axes (c, s).
#[inline(always)]
fn compose(a: f64, b: f64, c: f64, s: f64) -> [f64; 3] {
    [
        a * c * c + b * s * s,
        a * s * s + b * c * c,
        (a - b) * c * s,
    ]
}

/// Stress and new state of a J2 element with in-plane deformation gradient `f` (xx, xy, yx,
/// yy), its determinant `j`, the out-of-plane stretch `f33` (1 in plane strain, r / R in an
/// axisymmetric body), the previous state `old` and the step `dt` that led here (for the strain
/// rate of the Johnson-Cook flow stress; 0: no rate effect). See the module documentation.
#[inline(always)]
pub fn j2_stress(
    p: &ElementParams,
    f: &[f64; 4],
    j: f64,
    f33: f64,
    old: &PlasticState,
    dt: f64,
) -> J2Stress {
    j2_update(p, f, j, f33, old, true, dt)
}

/// The flow stress at equivalent plastic strain `alpha` and plastic strain rate `rate`, at room
/// temperature: (sigma_y + H alpha + B alpha^n)(1 + C ln(max(rate / rate0, 1))) (linear
/// hardening: B = C = 0). Thermal softening multiplies it by
/// [`ElementParams::softening`] of the temperature at the start of the step.
#[inline(always)]
pub fn flow_stress(p: &ElementParams, alpha: f64, rate: f64) -> f64 {
    let hard = p.yield_stress + p.hardening * alpha + p.jc_b * alpha.max(0.0).powf(p.jc_n);
    hard * (1.0 + p.jc_c * (rate / p.jc_rate0).max(1.0).ln())
}

/// The increment of alpha of a return from the von Mises stress `q` of the trial (Kirchhoff),
/// volume ratio `j` (times the thermal softening factor 1 - T*^m, held at its start-of-step
/// value through the return, so that Newton's derivative below is exact for the function it
/// solves), plastic strain `alpha` and step `dt`: the root of
/// q - 3 mu d = j flow(alpha + d, d / dt) in (0, q / 3 mu), by Newton's method kept inside a
/// bracket (bisection where a Newton step leaves it). Closed form for linear hardening.
#[inline(always)]
fn return_increment(p: &ElementParams, q: f64, j: f64, alpha: f64, dt: f64) -> f64 {
    let mu = p.mu;
    if p.jc_b == 0.0 && p.jc_c == 0.0 {
        let flow = p.yield_stress + p.hardening * alpha;
        return (q - j * flow) / (3.0 * mu + j * p.hardening);
    }
    let rate = |x: f64| if dt > 0.0 { x / dt } else { 0.0 };
    let g = |x: f64| q - 3.0 * mu * x - j * flow_stress(p, alpha + x, rate(x));
    let (mut lo, mut hi) = (0.0, q / (3.0 * mu));
    let mut x = 0.5 * hi;
    for _ in 0..100 {
        let gx = g(x);
        if gx > 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let a = alpha + x;
        let r = rate(x) / p.jc_rate0;
        let rate_factor = 1.0 + p.jc_c * r.max(1.0).ln();
        let hard = p.yield_stress + p.hardening * a + p.jc_b * a.powf(p.jc_n);
        let d_hard = p.hardening + p.jc_b * p.jc_n * a.powf(p.jc_n - 1.0);
        let d_rate = if r > 1.0 { p.jc_c / x } else { 0.0 };
        let dg = -3.0 * mu - j * (d_hard * rate_factor + hard * d_rate);
        let mut next = x - gx / dg;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - x).abs() <= 1e-15 * (hi + lo) || hi - lo <= 1e-15 * hi {
            return next;
        }
        x = next;
    }
    x
}

/// The elastic response of the state `state` at (`f`, `f33`), with no return.
#[inline(always)]
pub fn j2_elastic(
    p: &ElementParams,
    f: &[f64; 4],
    j: f64,
    f33: f64,
    state: &PlasticState,
) -> J2Stress {
    j2_update(p, f, j, f33, state, false, 0.0)
}

/// The plastic work of a step that yielded, per reference volume: the work of the stress over
/// the step, `dt` long, by the trapezoidal rule on the first Piola-Kirchhoff stresses at its two
/// ends (`old` at the start, from the old state; `new` at the end, returned; `fd` and `f33d` the
/// rates of F and F_33), less the change of the stored energy. This is the part of the internal
/// work that the stored energy does not hold, so that the energy audit of a run closes to
/// round-off on the steps that yield, as it closes to second order on elastic ones
/// (W(trial) - W(returned) alone leaves an error of first order in the step).
#[inline(always)]
pub fn step_plastic_work(old: &J2Stress, new: &J2Stress, fd: &[f64; 4], f33d: f64, dt: f64) -> f64 {
    let mut work = (old.p33 + new.p33) * f33d;
    for i in 0..4 {
        work += (old.pk[i] + new.pk[i]) * fd[i];
    }
    0.5 * dt * work - (new.stored - old.stored)
}

#[inline(always)]
fn j2_update(
    p: &ElementParams,
    f: &[f64; 4],
    j2: f64,
    f33: f64,
    old: &PlasticState,
    allow_return: bool,
    dt: f64,
) -> J2Stress {
    let [c0, c1, c2, c3] = old.cp_inv;
    // The volume ratio.
    let j = j2 * f33;
    // Trial b_e = F C_p^-1 F^T (in plane; b_zz = C_p^-1 zz since F_zz = 1).
    let fc00 = f[0] * c0 + f[1] * c2;
    let fc01 = f[0] * c2 + f[1] * c1;
    let fc10 = f[2] * c0 + f[3] * c2;
    let fc11 = f[2] * c2 + f[3] * c1;
    let bxx = fc00 * f[0] + fc01 * f[1];
    let bxy = fc00 * f[2] + fc01 * f[3];
    let byy = fc10 * f[2] + fc11 * f[3];
    let (l1, l2, cs, sn) = principal(bxx, byy, bxy);
    // Logarithmic elastic strains, their volume and deviatoric parts.
    // b_zz = F_33^2 C_p^-1 zz.
    let eps = [0.5 * l1.ln(), 0.5 * l2.ln(), 0.5 * c3.ln() + f33.ln()];
    let ev = eps[0] + eps[1] + eps[2];
    let mut e = eps.map(|x| x - ev / 3.0);
    let e2_trial = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
    let mu = p.mu;
    // von Mises stress of the trial: sqrt(3/2) |2 mu e|.
    let q = 2.0 * mu * (1.5 * e2_trial).sqrt();
    // The yield condition is on the Cauchy stress, tau_vm / J <= flow stress (its rate term is 0
    // at the elastic trial), softened at the temperature of the start of the step (a factor of
    // exactly 1 without thermal softening).
    let soft = p.softening(old.heat);
    let flow = flow_stress(p, old.alpha, 0.0) * soft;
    let mut state = *old;
    let mut dissipated = 0.0;
    if allow_return && q > j * flow {
        let d_alpha = return_increment(p, q, j * soft, old.alpha, dt);
        let scale = 1.0 - 3.0 * mu * d_alpha / q;
        e = e.map(|x| x * scale);
        let e2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
        dissipated = mu * (e2_trial - e2);
        state.alpha = old.alpha + d_alpha;
        // b_e = exp(2 eps) on the same axes; C_p^-1 = F^-1 b_e F^-T.
        let b1 = (2.0 * (e[0] + ev / 3.0)).exp();
        let b2 = (2.0 * (e[1] + ev / 3.0)).exp();
        let b3 = (2.0 * (e[2] + ev / 3.0)).exp();
        let [nxx, nyy, nxy] = compose(b1, b2, cs, sn);
        // F^-1 = [f3 -f1; -f2 f0] / det F (in plane), 1 / F_33 out of plane.
        let (i00, i01, i10, i11) = (f[3] / j2, -f[1] / j2, -f[2] / j2, f[0] / j2);
        let t00 = i00 * nxx + i01 * nxy;
        let t01 = i00 * nxy + i01 * nyy;
        let t10 = i10 * nxx + i11 * nxy;
        let t11 = i10 * nxy + i11 * nyy;
        state.cp_inv = [
            t00 * i00 + t01 * i01,
            t10 * i10 + t11 * i11,
            t00 * i10 + t01 * i11,
            b3 / (f33 * f33),
        ];
    }
    let k = p.bulk_modulus;
    let stored = 0.5 * k * ev * ev + mu * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    let tau = e.map(|x| 2.0 * mu * x + k * ev);
    let [txx, tyy, txy] = compose(tau[0], tau[1], cs, sn);
    // P = tau F^-T, F^-T = [f3 -f2; -f1 f0] / det F in plane.
    let (m00, m01, m10, m11) = (f[3] / j2, -f[2] / j2, -f[1] / j2, f[0] / j2);
    let pk = [
        txx * m00 + txy * m10,
        txx * m01 + txy * m11,
        txy * m00 + tyy * m10,
        txy * m01 + tyy * m11,
    ];
    J2Stress {
        pk,
        p33: tau[2] / f33,
        cauchy: [txx / j, tyy / j, txy / j, tau[2] / j],
        stored,
        dissipated,
        state,
    }
}

/// Von Mises equivalent of a Cauchy stress (xx, yy, xy, zz).
pub fn von_mises(s: &[f64; 4]) -> f64 {
    let [xx, yy, xy, zz] = *s;
    (0.5 * ((xx - yy).powi(2) + (yy - zz).powi(2) + (zz - xx).powi(2)) + 3.0 * xy * xy).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Formulation, HourglassForm, Material, MaterialModel, Plasticity};

    /// Copper's elastic constants with `plasticity`.
    fn copper_with(plasticity: Plasticity) -> ElementParams {
        let m = Material {
            name: "copper".into(),
            model: MaterialModel::J2Plastic,
            density: 8930.0,
            youngs_modulus: 117e9,
            poisson_ratio: 0.35,
            plasticity: Some(plasticity),
            failure: None,
        };
        ElementParams::new(
            &m,
            Formulation::PlaneStrain,
            1.0,
            HourglassForm::None,
            0.0,
            (0.0, 0.0),
        )
    }

    fn copper() -> ElementParams {
        copper_with(Plasticity {
            yield_stress: 400e6,
            hardening_modulus: 100e6,
            johnson_cook: None,
        })
    }

    fn det(f: &[f64; 4]) -> f64 {
        f[0] * f[3] - f[1] * f[2]
    }

    /// F = R G for the rotation by `angle`.
    fn rotate(angle: f64, g: &[f64; 4]) -> [f64; 4] {
        let (s, c) = angle.sin_cos();
        [
            c * g[0] - s * g[2],
            c * g[1] - s * g[3],
            s * g[0] + c * g[2],
            s * g[1] + c * g[3],
        ]
    }

    #[test]
    fn an_elastic_step_is_hencky_and_matches_linear_elasticity_at_small_strain() {
        let p = copper();
        let e = 1e-6;
        let f = [1.0 + e, 0.4 * e, 0.4 * e, 1.0 - 0.3 * e];
        let s = j2_stress(&p, &f, det(&f), 1.0, &PlasticState::VIRGIN, 0.0);
        assert_eq!(s.state, PlasticState::VIRGIN);
        assert_eq!(s.dissipated, 0.0);
        let tr = f[0] + f[3] - 2.0;
        let sxx = p.lambda * tr + 2.0 * p.mu * (f[0] - 1.0);
        let sxy = p.mu * (f[1] + f[2]);
        let szz = p.lambda * tr;
        let scale = 2.0 * p.mu * e;
        assert!((s.cauchy[0] - sxx).abs() < 1e-5 * scale, "{:?}", s.cauchy);
        assert!((s.cauchy[2] - sxy).abs() < 1e-5 * scale);
        assert!((s.cauchy[3] - szz).abs() < 1e-5 * scale);
    }

    #[test]
    fn the_return_lands_on_the_hardened_yield_surface_and_dissipates() {
        let p = copper();
        let f = [1.0, 0.0, 0.0, 0.98];
        let s = j2_stress(&p, &f, det(&f), 1.0, &PlasticState::VIRGIN, 0.0);
        assert!(s.state.alpha > 0.0 && s.dissipated > 0.0);
        let flow = p.yield_stress + p.hardening * s.state.alpha;
        // Cauchy von Mises = flow stress exactly.
        assert!((von_mises(&s.cauchy) - flow).abs() < 1e-9 * flow);
        // Plastic flow is isochoric: det C_p^-1 = 1.
        let c = s.state.cp_inv;
        assert!(((c[0] * c[1] - c[2] * c[2]) * c[3] - 1.0).abs() < 1e-12);
        // Re-evaluating at the same F from the new state gives the same state and stress (to
        // round-off: the trial then lies on the yield surface).
        let again = j2_stress(&p, &f, det(&f), 1.0, &s.state, 0.0);
        assert!((again.state.alpha - s.state.alpha).abs() < 1e-14);
        assert!(again.dissipated < 1e-12 * s.dissipated);
        for i in 0..4 {
            assert!((again.cauchy[i] - s.cauchy[i]).abs() < 1e-6 * flow);
        }
    }

    fn johnson_cook(c: f64) -> ElementParams {
        johnson_cook_with(c, None)
    }

    /// Johnson-Cook copper without rate term, with thermal softening m = 1 (T_r 300 K, T_m
    /// 1356 K) and adiabatic heating.
    fn johnson_cook_thermal() -> ElementParams {
        johnson_cook_with(
            0.0,
            Some(crate::scene::ThermalSoftening {
                m: 1.0,
                melt_temperature: 1356.0,
                room_temperature: 300.0,
                specific_heat: 383.0,
                taylor_quinney: 0.9,
            }),
        )
    }

    /// Johnson-Cook copper with rate coefficient `c` and `thermal`.
    fn johnson_cook_with(c: f64, thermal: Option<crate::scene::ThermalSoftening>) -> ElementParams {
        copper_with(Plasticity {
            yield_stress: 9.0e7,
            hardening_modulus: 0.0,
            johnson_cook: Some(crate::scene::JohnsonCook {
                a: 9.0e7,
                b: 2.92e8,
                n: 0.31,
                c,
                reference_strain_rate: 1.0,
                thermal,
            }),
        })
    }

    #[test]
    fn thermal_softening_scales_the_flow_stress_by_one_minus_t_star_to_the_m() {
        let p = johnson_cook_thermal();
        assert!(p.has_thermal());
        assert_eq!(p.melt_rise, 1056.0);
        assert!((p.heating - 0.9 / (8930.0 * 383.0)).abs() < 1e-20);
        assert_eq!(p.softening(0.0), 1.0);
        assert_eq!(p.t_star(-5.0), 0.0);
        assert_eq!(p.t_star(2000.0), 1.0);
        assert!((p.softening(264.0) - 0.75).abs() < 1e-15);
        // The return lands on the softened flow stress of the start-of-step temperature, and
        // carries the temperature rise unchanged (the element function adds the heating).
        let f = [1.0, 0.01, 0.0, 0.985];
        let cold = j2_stress(&p, &f, det(&f), 1.0, &PlasticState::VIRGIN, 1e-6);
        let hot_state = PlasticState {
            heat: 264.0,
            ..PlasticState::VIRGIN
        };
        let hot = j2_stress(&p, &f, det(&f), 1.0, &hot_state, 1e-6);
        assert_eq!(hot.state.heat, 264.0);
        let a = hot.state.alpha;
        assert!(a > cold.state.alpha);
        let flow = 0.75 * flow_stress(&p, a, 0.0);
        let vm = von_mises(&hot.cauchy);
        assert!((vm - flow).abs() < 1e-9 * flow, "{vm} against {flow}");
        // Without thermal softening nothing changes: the same bits as before the heat existed.
        let plain = johnson_cook(0.0);
        assert!(!plain.has_thermal());
        assert_eq!(plain.softening(264.0), 1.0);
        let s = j2_stress(&plain, &f, det(&f), 1.0, &hot_state, 1e-6);
        let r = j2_stress(&plain, &f, det(&f), 1.0, &PlasticState::VIRGIN, 1e-6);
        assert_eq!(s.cauchy, r.cauchy);
        assert_eq!(s.state.alpha, r.state.alpha);
    }

    #[test]
    fn a_yielding_step_heats_by_beta_times_its_plastic_work_over_rho_c() {
        use crate::element::{evaluate_state, Dissipation};
        use crate::geometry::quad_geometry;
        let p = johnson_cook_thermal();
        let dx = [[0.0, 0.0], [1e-3, 0.0], [1e-3, 1e-3], [0.0, 1e-3]];
        let g = quad_geometry(&dx);
        // Simple shear, u_x = gamma y, at the rate v_x = gamma y / dt.
        let (gamma, dt) = (0.01, 1e-6);
        let u: [[f64; 2]; 4] = std::array::from_fn(|a| [gamma * dx[a][1], 0.0]);
        let v: [[f64; 2]; 4] = std::array::from_fn(|a| [gamma * dx[a][1] / dt, 0.0]);
        let out = evaluate_state(
            &p,
            &g,
            &dx,
            &u,
            &v,
            &Dissipation::default(),
            dt,
            &PlasticState::VIRGIN,
        );
        assert!(out.plastic.alpha > 0.0 && out.plastic_work > 0.0);
        // plastic_work is the element's (per reference volume times A0 t, t = 1).
        let expect = p.heating * out.plastic_work / 1e-6;
        assert!(
            (out.plastic.heat - expect).abs() < 1e-12 * expect,
            "{} against {expect}",
            out.plastic.heat
        );
    }

    #[test]
    fn the_johnson_cook_return_lands_on_its_flow_stress_at_the_step_rate() {
        for (c, dt) in [(0.0, 0.0), (0.025, 1e-7), (0.025, 1e-3)] {
            let p = johnson_cook(c);
            let f = [1.0, 0.01, 0.0, 0.985];
            let s = j2_stress(&p, &f, det(&f), 1.0, &PlasticState::VIRGIN, dt);
            let a = s.state.alpha;
            assert!(a > 0.0);
            let rate = if dt > 0.0 { a / dt } else { 0.0 };
            let flow = flow_stress(&p, a, rate);
            let vm = von_mises(&s.cauchy);
            assert!(
                (vm - flow).abs() < 1e-9 * flow,
                "c {c} dt {dt}: {vm} against {flow}"
            );
            let expect = (9.0e7 + 2.92e8 * a.powf(0.31)) * (1.0 + c * rate.max(1.0).ln());
            assert!((flow - expect).abs() < 1e-12 * expect);
        }
        // Faster steps (higher rates) raise the flow stress.
        let p = johnson_cook(0.025);
        let f = [1.0, 0.01, 0.0, 0.985];
        let slow = j2_stress(&p, &f, det(&f), 1.0, &PlasticState::VIRGIN, 1e-3);
        let fast = j2_stress(&p, &f, det(&f), 1.0, &PlasticState::VIRGIN, 1e-7);
        assert!(von_mises(&fast.cauchy) > von_mises(&slow.cauchy));
        assert!(fast.state.alpha < slow.state.alpha);
    }

    #[test]
    fn a_rigid_rotation_leaves_the_state_and_the_rotated_stress_unchanged() {
        let p = copper();
        let g = [1.01, 0.02, -0.01, 0.97];
        let a = j2_stress(&p, &g, det(&g), 1.0, &PlasticState::VIRGIN, 0.0);
        assert!(a.state.alpha > 0.0);
        for angle in [0.3, 1.2, std::f64::consts::PI, -2.5] {
            let f = rotate(angle, &g);
            let b = j2_stress(&p, &f, det(&f), 1.0, &PlasticState::VIRGIN, 0.0);
            assert!((b.state.alpha - a.state.alpha).abs() < 1e-14);
            for i in 0..4 {
                assert!(
                    (b.state.cp_inv[i] - a.state.cp_inv[i]).abs() < 1e-12,
                    "{angle}"
                );
            }
            // sigma_b = R sigma_a R^T.
            let (s, c) = angle.sin_cos();
            let [xx, yy, xy, zz] = a.cauchy;
            let rxx = c * c * xx - 2.0 * c * s * xy + s * s * yy;
            let ryy = s * s * xx + 2.0 * c * s * xy + c * c * yy;
            let rxy = c * s * (xx - yy) + (c * c - s * s) * xy;
            let tol = 1e-9 * p.yield_stress;
            assert!((b.cauchy[0] - rxx).abs() < tol, "{angle}");
            assert!((b.cauchy[1] - ryy).abs() < tol);
            assert!((b.cauchy[2] - rxy).abs() < tol);
            assert!((b.cauchy[3] - zz).abs() < tol);
        }
    }
}
