//! One element's evaluation, CPU reference: from its reference corners, displacements and
//! lagged velocities, the deformation gradient and its rate, the stress ([`super::stress`], or
//! the J2 return of [`super::plastic`]), the nodal forces of the stress, of the hourglass control
//! ([`super::hourglass`]) and of the bulk viscosity, the element's stable step, its energies and
//! the work its viscous parts dissipated over the last step. The GPU twin is
//! `shaders/element.wgsl` ([`crate::gpu::element`]), which follows [`evaluate_state`] line by line
//! in f32.

use super::hourglass;
use super::params::ElementParams;
use super::plastic::{j2_elastic, j2_stress, step_plastic_work, PlasticState};
use super::stress::stress;
use crate::geometry::{
    centre_weights, characteristic_length, min_corner_cross, quad_geometry, QuadGeometry,
};
use crate::scene::{Formulation, MaterialModel};

/// What one element evaluation produces.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ElementOut {
    /// Nodal forces (external minus internal) of the element on its 4 nodes.
    pub force: [[f64; 2]; 4],
    /// Stable step of the element (without the safety factor).
    pub dt: f64,
    /// Strain energy.
    pub strain_energy: f64,
    /// Energy stored in the stiffness hourglass springs.
    pub hourglass_stored: f64,
    /// The viscous forces of this step: the dissipative state the next step pairs its work with
    /// (its `prev`).
    pub dissipation: Dissipation,
    /// Work dissipated by the viscous hourglass forces over the last step (pairing n-1 and n).
    pub hourglass_work: f64,
    /// Work dissipated by the bulk viscosity over the last step.
    pub bulk_work: f64,
    /// Smallest corner Jacobian ratio of the current geometry (<= 0: inverted).
    pub min_corner: f64,
    /// Cauchy stress (xx, yy, xy, zz).
    pub stress: [f64; 4],
    /// Deformation gradient (xx, xy, yx, yy).
    pub def_grad: [f64; 4],
    /// Out-of-plane stretch F_33 (axisymmetric: r / R; 1 otherwise).
    pub hoop_stretch: f64,
    /// Plastic state after the step (J2 plastic materials; the input state otherwise), with the
    /// temperature rise of the step's adiabatic heating (Johnson-Cook thermal softening).
    pub plastic: PlasticState,
    /// Energy the plastic return dissipated in this evaluation (J2 plastic materials).
    pub plastic_work: f64,
}

/// Dissipative state of an element: the viscous forces of a step, with which the next step pairs
/// its dissipated work (trapezoidal).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Dissipation {
    /// Viscous hourglass generalized force Q_i (force on node a is -gamma_a Q_i).
    pub hourglass_q: [f64; 2],
    /// Bulk-viscosity first Piola-Kirchhoff stress (xx, xy, yx, yy).
    pub bulk_p: [f64; 4],
    /// Its hoop component (axisymmetric elements).
    pub bulk_hoop: f64,
}

fn det(f: &[f64; 4]) -> f64 {
    f[0] * f[3] - f[1] * f[2]
}

/// The nodal forces `-A0 t P b_a` of the first Piola-Kirchhoff stress `pk` (xx, xy, yx, yy) on
/// the reference gradients of `g`, `a0t` the reference volume (A0 t, or A0 R per radian).
#[inline(always)]
fn stress_forces(g: &QuadGeometry, a0t: f64, pk: &[f64; 4]) -> [[f64; 2]; 4] {
    std::array::from_fn(|a| {
        [
            -a0t * (pk[0] * g.bx[a] + pk[1] * g.by[a]),
            -a0t * (pk[2] * g.bx[a] + pk[3] * g.by[a]),
        ]
    })
}

/// Adds the forces of the hoop stress `hoop` (A0 R P_33 / R) on u_r to `force`: dF_33 / du_r,a =
/// N_a / R at the centre, with its weights `wc` (1/4, or 1/3 on a triangle).
#[inline(always)]
fn add_hoop_forces(force: &mut [[f64; 2]; 4], wc: &[f64; 4], hoop: f64) {
    for a in 0..4 {
        force[a][0] -= wc[a] * hoop;
    }
}

/// Evaluates one element. `dx`: reference corner offsets; `u`, `v`: corner displacements and
/// lagged velocities; `prev`: the dissipative state of the previous step; `dt_prev`: the step
/// that took u^{n-1} to u^n (0 on the first step, which dissipates nothing).
#[inline]
pub fn evaluate(
    p: &ElementParams,
    dx: &[[f64; 2]; 4],
    u: &[[f64; 2]; 4],
    v: &[[f64; 2]; 4],
    prev: &Dissipation,
    dt_prev: f64,
) -> ElementOut {
    evaluate_with(p, &quad_geometry(dx), dx, u, v, prev, dt_prev)
}

/// [`evaluate`] with the reference geometry `g` of `dx` computed ahead (the solver keeps it per
/// element, since it never changes), for a virgin plastic state.
#[inline(always)]
pub fn evaluate_with(
    p: &ElementParams,
    g: &QuadGeometry,
    dx: &[[f64; 2]; 4],
    u: &[[f64; 2]; 4],
    v: &[[f64; 2]; 4],
    prev: &Dissipation,
    dt_prev: f64,
) -> ElementOut {
    evaluate_state(p, g, dx, u, v, prev, dt_prev, &PlasticState::VIRGIN)
}

/// [`evaluate_with`] from the plastic state `plastic` of the previous step (used by J2 plastic
/// materials; the returned [`ElementOut::plastic`] is the state after this step).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn evaluate_state(
    p: &ElementParams,
    g: &QuadGeometry,
    dx: &[[f64; 2]; 4],
    u: &[[f64; 2]; 4],
    v: &[[f64; 2]; 4],
    prev: &Dissipation,
    dt_prev: f64,
    plastic: &PlasticState,
) -> ElementOut {
    // Axisymmetric: the hoop stretch F_33 = r / R at the centre (N_a = 1/4 there), its rate, and
    // the volume per radian A0 R instead of A0 t.
    let axi = p.formulation == Formulation::Axisymmetric;
    let wc = centre_weights(g.triangle);
    let (f33, f33d, a0t) = if axi {
        let ur: f64 = (0..4).map(|a| wc[a] * u[a][0]).sum();
        let vr: f64 = (0..4).map(|a| wc[a] * v[a][0]).sum();
        (1.0 + ur / g.radius, vr / g.radius, g.area * g.radius)
    } else {
        (1.0, 0.0, g.area * p.thickness)
    };
    // Deformation gradient F = I + sum_a u_a (x) b_a and its rate.
    let mut f = [1.0, 0.0, 0.0, 1.0];
    let mut fd = [0.0; 4];
    for a in 0..4 {
        f[0] += u[a][0] * g.bx[a];
        f[1] += u[a][0] * g.by[a];
        f[2] += u[a][1] * g.bx[a];
        f[3] += u[a][1] * g.by[a];
        fd[0] += v[a][0] * g.bx[a];
        fd[1] += v[a][0] * g.by[a];
        fd[2] += v[a][1] * g.bx[a];
        fd[3] += v[a][1] * g.by[a];
    }
    let j = det(&f);
    // Stress (first Piola-Kirchhoff, xx xy yx yy) and strain energy density.
    let (pk, p33, w, cauchy, new_plastic, plastic_density) = if p.model == MaterialModel::J2Plastic
    {
        let s = j2_stress(p, &f, j, f33, plastic, dt_prev);
        let mut d = s.dissipated;
        if s.state.alpha > plastic.alpha && dt_prev > 0.0 {
            // F_n = F_{n+1} - dt Fdot with the old state: the start of the step that yielded.
            let f_old: [f64; 4] = std::array::from_fn(|i| f[i] - dt_prev * fd[i]);
            let f33_old = f33 - dt_prev * f33d;
            let old = j2_elastic(p, &f_old, det(&f_old), f33_old, plastic);
            d = step_plastic_work(&old, &s, &fd, f33d, dt_prev);
        }
        let mut state = s.state;
        if p.has_thermal() && state.alpha > plastic.alpha {
            // Adiabatic heating: beta dW_p / (rho_0 c_p) of the step's plastic work per unit
            // reference volume (never negative: round-off cannot cool).
            state.heat = plastic.heat + p.heating * d.max(0.0);
        }
        (s.pk, s.p33, s.stored, s.cauchy, state, d)
    } else {
        let (pk, w, cauchy, p33) = stress(p, &f, j, f33);
        (pk, p33, w, cauchy, *plastic, 0.0)
    };

    // Current geometry.
    let x: [[f64; 2]; 4] = std::array::from_fn(|a| [dx[a][0] + u[a][0], dx[a][1] + u[a][1]]);
    let area = 0.5
        * ((x[2][0] - x[0][0]) * (x[3][1] - x[1][1]) - (x[3][0] - x[1][0]) * (x[2][1] - x[0][1]));
    let min_corner = min_corner_cross(&x) * g.inv_area;
    let length = characteristic_length(&x, area.abs());
    // Wave speed with the current density rho0 A0 / A.
    let c = (p.reference_speed * p.reference_speed * area.abs() * g.inv_area).sqrt();

    let mut force = stress_forces(g, a0t, &pk);
    if axi {
        // The hoop stress on u_r.
        add_hoop_forces(&mut force, &wc, a0t * p33 / g.radius);
    }

    // Hourglass control (Flanagan-Belytschko), on the reference gamma.
    let hg = hourglass::add_forces(p, g, a0t, u, v, &prev.hourglass_q, dt_prev, &mut force);

    // Bulk viscosity: pressure q in compression, acting as Cauchy stress -q I.
    let mut bulk_p = [0.0; 4];
    let mut bulk_hoop = 0.0;
    let mut bulk_work = 0.0;
    let mut dt = length / c;
    if p.has_bulk_viscosity() {
        // Volumetric strain rate tr(Fdot F^-1) (= tr Fdot for the small-strain model).
        let rate = match p.model {
            MaterialModel::LinearElastic => fd[0] + fd[3] + f33d,
            MaterialModel::NeoHookean | MaterialModel::J2Plastic => {
                (fd[0] * f[3] - fd[1] * f[2] - fd[2] * f[1] + fd[3] * f[0]) / j + f33d / f33
            }
        };
        // Compression only, and not for round-off rates (rigid motion): the strain rate over one
        // wave transit of the element must exceed 1e-9.
        if rate * length < -1e-9 * c {
            let rho = p.density * g.area / area.abs().max(f64::MIN_POSITIVE);
            let q =
                rho * length * (p.bulk_quadratic * length * rate * rate - p.bulk_linear * c * rate);
            (bulk_p, bulk_hoop) = match p.model {
                MaterialModel::LinearElastic => ([-q, 0.0, 0.0, -q], if axi { -q } else { 0.0 }),
                // -q J F^-T: in plane -q F_33 cof(F), hoop -q det(F) (J = det(F) F_33).
                MaterialModel::NeoHookean | MaterialModel::J2Plastic => (
                    [
                        -q * f33 * f[3],
                        q * f33 * f[2],
                        q * f33 * f[1],
                        -q * f33 * f[0],
                    ],
                    if axi { -q * j } else { 0.0 },
                ),
            };
        }
        // Stable step with the viscosity: the linear part always (so that dt does not jump when
        // an element switches between compression and expansion), the quadratic part in compression.
        let qs = p.bulk_linear * c + p.bulk_quadratic * length * (-rate).max(0.0);
        dt = length / (qs + (qs * qs + c * c).sqrt());
        // (x - a0t P b equals x + (-a0t P b) to the bit.)
        for (f, b) in force.iter_mut().zip(stress_forces(g, a0t, &bulk_p)) {
            f[0] += b[0];
            f[1] += b[1];
        }
        if axi {
            add_hoop_forces(&mut force, &wc, a0t * bulk_hoop / g.radius);
        }
        // Dissipated: 1/2 A0 t (P^{n-1} + P^n) : dH, dH = dt_prev Fdot.
        bulk_work = 0.5
            * a0t
            * dt_prev
            * ((prev.bulk_p[0] + bulk_p[0]) * fd[0]
                + (prev.bulk_p[1] + bulk_p[1]) * fd[1]
                + (prev.bulk_p[2] + bulk_p[2]) * fd[2]
                + (prev.bulk_p[3] + bulk_p[3]) * fd[3]
                + (prev.bulk_hoop + bulk_hoop) * f33d);
    }

    ElementOut {
        force,
        dt,
        strain_energy: w * a0t,
        hourglass_stored: hg.stored,
        dissipation: Dissipation {
            hourglass_q: hg.q,
            bulk_p,
            bulk_hoop,
        },
        hourglass_work: hg.work,
        bulk_work,
        min_corner,
        stress: cauchy,
        def_grad: f,
        hoop_stretch: f33,
        plastic: new_plastic,
        plastic_work: plastic_density * a0t,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::stress::plane_stress_stretch;
    use crate::geometry::HOURGLASS_BASE;
    use crate::scene::{HourglassForm, Material};

    fn steel(model: MaterialModel) -> Material {
        Material {
            name: "steel".into(),
            model,
            density: 7850.0,
            youngs_modulus: 210e9,
            poisson_ratio: 0.3,
            plasticity: None,
            failure: None,
        }
    }

    fn params(model: MaterialModel, form: Formulation, hg: HourglassForm) -> ElementParams {
        ElementParams::new(&steel(model), form, 1.0, hg, 0.1, (0.0, 0.0))
    }

    const SQUARE: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];

    #[test]
    fn plane_stress_neo_hookean_has_zero_szz_and_matches_linear_for_small_strain() {
        let p = params(
            MaterialModel::NeoHookean,
            Formulation::PlaneStress,
            HourglassForm::None,
        );
        let pl = params(
            MaterialModel::LinearElastic,
            Formulation::PlaneStress,
            HourglassForm::None,
        );
        let e = 1e-6;
        let f = [1.0 + e, 0.3 * e, 0.3 * e, 1.0 - 0.5 * e];
        let (pk, _, _, _) = stress(&p, &f, det(&f), 1.0);
        let (pkl, _, _, _) = stress(&pl, &f, det(&f), 1.0);
        for i in 0..4 {
            assert!(
                (pk[i] - pkl[i]).abs() < 1e-4 * 210e9 * e,
                "{i}: {} vs {}",
                pk[i],
                pkl[i]
            );
        }
        // residual of the sigma_33 = 0 condition
        let z = plane_stress_stretch(p.lambda, p.mu, 0.7);
        let g = p.mu * (z * z - 1.0) + p.lambda * (0.7f64 * z).ln();
        assert!(g.abs() < 1e-6 * p.mu);
    }

    #[test]
    fn hourglass_mode_is_resisted_only_with_control() {
        // Pure hourglass displacement: u_x = d * h_a. One-point quadrature sees no strain.
        let d = 1e-4;
        let u: [[f64; 2]; 4] = std::array::from_fn(|a| [d * HOURGLASS_BASE[a], 0.0]);
        let zero = [[0.0; 2]; 4];
        let none = params(
            MaterialModel::LinearElastic,
            Formulation::PlaneStrain,
            HourglassForm::None,
        );
        let out = evaluate(&none, &SQUARE, &u, &zero, &Dissipation::default(), 0.0);
        assert!(out.strain_energy.abs() < 1e-6);
        assert!(out
            .force
            .iter()
            .all(|f| f[0].abs() < 1e-3 && f[1].abs() < 1e-3));
        let stiff = params(
            MaterialModel::LinearElastic,
            Formulation::PlaneStrain,
            HourglassForm::Stiffness,
        );
        let out = evaluate(&stiff, &SQUARE, &u, &zero, &Dissipation::default(), 0.0);
        // Restoring: the force opposes the mode, and the work of the force equals the stored energy.
        let work: f64 = (0..4).map(|a| out.force[a][0] * u[a][0]).sum();
        assert!(work < 0.0);
        assert!(out.hourglass_stored > 0.0);
        assert!((-0.5 * work - out.hourglass_stored).abs() < 1e-9 * out.hourglass_stored);
        let visc = params(
            MaterialModel::LinearElastic,
            Formulation::PlaneStrain,
            HourglassForm::Viscous,
        );
        let out = evaluate(&visc, &SQUARE, &zero, &u, &Dissipation::default(), 1e-7);
        let power: f64 = (0..4).map(|a| out.force[a][0] * u[a][0]).sum();
        assert!(
            power < 0.0,
            "viscous hourglass force must oppose the hourglass velocity"
        );
        assert!(out.hourglass_work > 0.0);
    }

    #[test]
    fn stable_step_of_a_square_matches_the_dilatational_mode() {
        // nu = 0 plane stress: the 1D bar limit dt = h / c.
        let m = Material {
            name: "m".into(),
            model: MaterialModel::LinearElastic,
            density: 7850.0,
            youngs_modulus: 210e9,
            poisson_ratio: 0.0,
            plasticity: None,
            failure: None,
        };
        let p = ElementParams::new(
            &m,
            Formulation::PlaneStress,
            1.0,
            HourglassForm::None,
            0.0,
            (0.0, 0.0),
        );
        let zero = [[0.0; 2]; 4];
        let out = evaluate(&p, &SQUARE, &zero, &zero, &Dissipation::default(), 0.0);
        let c = (210e9f64 / 7850.0).sqrt();
        assert!((out.dt - 1.0 / c).abs() < 1e-12 / c);
    }
    /// A triangle `[a, b, c, c]` of corners `t`.
    fn collapsed(t: [[f64; 2]; 3]) -> [[f64; 2]; 4] {
        [t[0], t[1], t[2], t[2]]
    }

    fn elastic(nu: f64, hg: HourglassForm) -> ElementParams {
        let m = Material {
            name: "m".into(),
            model: MaterialModel::LinearElastic,
            density: 7850.0,
            youngs_modulus: 210e9,
            poisson_ratio: nu,
            plasticity: None,
            failure: None,
        };
        ElementParams::new(&m, Formulation::PlaneStrain, 0.01, hg, 0.1, (0.0, 0.0))
    }

    /// The forces of a linear-elastic triangle for the nodal displacements `u` of its three
    /// nodes (the repeated corner's force added to its node).
    fn triangle_forces(p: &ElementParams, x: &[[f64; 2]; 4], u: [[f64; 2]; 3]) -> [[f64; 2]; 3] {
        let ue = [u[0], u[1], u[2], u[2]];
        let out = evaluate(p, x, &ue, &[[0.0; 2]; 4], &Dissipation::default(), 0.0);
        let f = out.force;
        [f[0], f[1], [f[2][0] + f[3][0], f[2][1] + f[3][1]]]
    }

    #[test]
    fn a_collapsed_quad_is_the_constant_strain_triangle_without_hourglass_forces() {
        let t = [[0.1, -0.2], [1.3, 0.15], [0.4, 0.9]];
        let x = collapsed(t);
        let g = quad_geometry(&x);
        assert!(g.triangle && g.gamma == [0.0; 4]);
        // The CST's gradients: b_a = (y_b - y_c) / 2A, c_a = (x_c - x_b) / 2A (a, b, c cyclic).
        let area = 0.5
            * ((t[1][0] - t[0][0]) * (t[2][1] - t[0][1])
                - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]));
        assert!((g.area - area).abs() < 1e-15);
        for a in 0..3 {
            let (b, c) = (t[(a + 1) % 3], t[(a + 2) % 3]);
            let (bx, by) = if a == 2 {
                (g.bx[2] + g.bx[3], g.by[2] + g.by[3])
            } else {
                (g.bx[a], g.by[a])
            };
            assert!((bx - (b[1] - c[1]) / (2.0 * area)).abs() < 1e-12, "b_{a}");
            assert!((by - (c[0] - b[0]) / (2.0 * area)).abs() < 1e-12, "c_{a}");
        }
        // Every hourglass form gives the same forces as none: a triangle has no hourglass mode.
        let u = [[1e-4, -3e-5], [-2e-5, 7e-5], [4e-5, 1e-5]];
        let none = triangle_forces(&elastic(0.3, HourglassForm::None), &x, u);
        for hg in [HourglassForm::Stiffness, HourglassForm::Viscous] {
            let p = elastic(0.3, hg);
            assert_eq!(triangle_forces(&p, &x, u), none, "{hg:?}");
            let ue = [u[0], u[1], u[2], u[2]];
            let out = evaluate(&p, &x, &ue, &ue, &Dissipation::default(), 1e-7);
            assert_eq!((out.hourglass_stored, out.hourglass_work), (0.0, 0.0));
        }
        // The forces balance and are those of the constant stress: f_a = -A t sigma (b_a, c_a).
        let sum = [0, 1].map(|k| none.iter().map(|f| f[k]).sum::<f64>());
        assert!(sum[0].abs() < 1e-6 && sum[1].abs() < 1e-6, "{sum:?}");
        // Its corner check sees the one real corner set, and it reads as 2 A / A0 = 2 at rest.
        let zero = [[0.0; 2]; 4];
        let out = evaluate(
            &elastic(0.3, HourglassForm::Stiffness),
            &x,
            &zero,
            &zero,
            &Dissipation::default(),
            0.0,
        );
        assert!((out.min_corner - 2.0).abs() < 1e-12, "{}", out.min_corner);
    }

    /// Largest eigenvalue of the symmetric positive semi-definite `k` (power iteration).
    fn largest_eigenvalue(k: &[[f64; 6]; 6]) -> f64 {
        let mut v = [1.0, 0.3, -0.7, 0.2, 0.5, -0.9];
        let mut lambda = 0.0;
        for _ in 0..5000 {
            let w: [f64; 6] = std::array::from_fn(|i| (0..6).map(|j| k[i][j] * v[j]).sum());
            let norm = w.iter().map(|x| x * x).sum::<f64>().sqrt();
            lambda =
                (0..6).map(|i| v[i] * w[i]).sum::<f64>() / v.iter().map(|x| x * x).sum::<f64>();
            v = w.map(|x| x / norm);
        }
        lambda
    }

    #[test]
    fn stable_step_of_a_triangle_is_within_its_largest_eigenfrequency() {
        // The element bound dt = 2 / omega_max of a constant-strain triangle with lumped masses
        // rho t A / 3, its stiffness assembled from the element's own forces: the triangle's
        // step (TRIANGLE_LENGTH) must not exceed it, on slender, flat, right and equilateral
        // shapes and from nu = 0 to nearly incompressible; nor be far below it (at least 0.6).
        let shapes = [
            [[0.0, 0.0], [1.0, 0.0], [0.5, 0.866_025_403_784_438_6]],
            [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            [[0.0, 0.0], [1.0, 0.0], [0.5, 10.0]],
            [[0.0, 0.0], [1.0, 0.0], [0.5, 0.05]],
            [[0.0, 0.0], [10.0, 0.0], [0.0, 1.0]],
            [[0.2, 0.1], [0.9, 0.3], [-0.4, 0.8]],
        ];
        let mut worst = (f64::INFINITY, 0.0f64);
        for nu in [0.0, 0.2, 0.3, 0.45, 0.499] {
            let p = elastic(nu, HourglassForm::None);
            for t in shapes {
                let x = collapsed(t);
                let area = quad_geometry(&x).area;
                let mut k = [[0.0; 6]; 6];
                for j in 0..6 {
                    let mut u = [[0.0; 2]; 3];
                    u[j / 2][j % 2] = 1e-9;
                    let f = triangle_forces(&p, &x, u);
                    for i in 0..6 {
                        k[i][j] = -f[i / 2][i % 2] / 1e-9 / (p.density * p.thickness * area / 3.0);
                    }
                }
                let zero = [[0.0; 2]; 4];
                let dt = evaluate(&p, &x, &zero, &zero, &Dissipation::default(), 0.0).dt;
                let bound = 2.0 / largest_eigenvalue(&k).sqrt();
                let r = dt / bound;
                worst = (worst.0.min(r), worst.1.max(r));
                assert!(
                    r <= 1.0 + 1e-6,
                    "nu {nu}, {t:?}: dt {dt:e} above the bound {bound:e}"
                );
                assert!(
                    r >= 0.6,
                    "nu {nu}, {t:?}: dt {dt:e} is {r} of the bound {bound:e}"
                );
            }
        }
        println!(
            "triangle stable step / element bound: {:.3} .. {:.3}",
            worst.0, worst.1
        );
    }
}
