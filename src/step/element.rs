//! The element stage, CPU reference: one-point 4-node quad in total-Lagrangian form.
//!
//! A 3-node triangle is a collapsed quad: its last corner repeats its third (`[a, b, c, c]`),
//! which [`is_triangle`] and [`QuadGeometry::triangle`] recognise. The quad's uniform gradients
//! then equal the constant-strain triangle's exactly (the repeated corner's two columns sum to
//! the triangle's third), every nodal displacement of a triangle is a linear field, to which the
//! hourglass vector is orthogonal, so there is no hourglass mode and no hourglass force; what
//! differs is kept apart here: no hourglass control (not even its round-off), the centroid
//! weights 1/3 (axisymmetric hoop terms), the corner check on the one real corner set and the
//! stable-step length of the triangle ([`characteristic_length`]). One kernel, one connectivity
//! layout and one node gather serve both kinds.
//!
//! For each element, from its reference node offsets `dx`, displacements `u` and the lagged
//! half-step velocities `v` (v^{n-1/2}), it computes
//! - the nodal forces (`f = -A0 t P b0` for the stress, plus hourglass and bulk-viscosity forces),
//! - the stable step of the element from the current geometry,
//! - the strain energy and stored hourglass energy (conservative parts),
//! - the increments of dissipated work of the viscous parts, with the trapezoidal pairing that
//!   makes the discrete energy balance close exactly for fixed steps (see [`ElementOut`]).
//!
//! The WGSL element kernel (`shaders/element.wgsl`) follows this function line by line in f32.

use crate::scene::{Formulation, HourglassForm, Material, MaterialModel};

use super::plastic::{j2_elastic, j2_stress, step_plastic_work, PlasticState};

/// The sign vector of the hourglass mode of a 4-node quad.
pub const HOURGLASS_BASE: [f64; 4] = [1.0, -1.0, 1.0, -1.0];

/// sqrt(8/3): the stable-step length of a triangle is this times area / longest side (see
/// [`characteristic_length`]).
pub const TRIANGLE_LENGTH: f64 = 1.632_993_161_855_452;

/// Whether the element with nodes `q` is a triangle (a collapsed quad `[a, b, c, c]`).
#[inline]
pub fn is_triangle(q: &[u32; 4]) -> bool {
    q[2] == q[3]
}

/// Whether the corners `x` are those of a triangle (the last repeats the third).
#[inline]
pub fn is_triangle_geometry(x: &[[f64; 2]; 4]) -> bool {
    x[2] == x[3]
}

/// Weights of the corners at the element's centre: 1/4 each for a quad, 1/3 on the three
/// corners of a triangle (its centroid; the repeated corner gets 0).
#[inline]
pub fn centre_weights(triangle: bool) -> [f64; 4] {
    if triangle {
        [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 0.0]
    } else {
        [0.25; 4]
    }
}

/// The centre of the element with corners `x` (the centroid of a triangle).
#[inline]
pub fn element_centre(x: &[[f64; 2]; 4]) -> [f64; 2] {
    let w = centre_weights(is_triangle_geometry(x));
    let mut c = [0.0; 2];
    for a in 0..4 {
        c[0] += w[a] * x[a][0];
        c[1] += w[a] * x[a][1];
    }
    c
}

/// Constitutive and control parameters shared by all elements of one body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementParams {
    /// Constitutive model.
    pub model: MaterialModel,
    /// Plane strain or plane stress.
    pub formulation: Formulation,
    /// Reference density.
    pub density: f64,
    /// Thickness.
    pub thickness: f64,
    /// 3D Lame constant lambda.
    pub lambda: f64,
    /// Shear modulus.
    pub mu: f64,
    /// In-plane effective lambda (plane stress: 2 lambda mu / (lambda + 2 mu)).
    pub lambda_plane: f64,
    /// Modulus that sets the element's fastest (dilatational) mode: lambda_plane + 2 mu + max(lambda_plane, 0).
    pub wave_modulus: f64,
    /// sqrt(wave_modulus / density): the speed of that mode in the reference state.
    pub reference_speed: f64,
    /// Hourglass form.
    pub hourglass: HourglassForm,
    /// Hourglass coefficient.
    pub hourglass_coefficient: f64,
    /// Modulus the hourglass forces scale with: 2 mu. The hourglass mode of a quad is a bending
    /// (isochoric to first order) mode, so its physical stiffness is set by shear, as in the
    /// physically stabilized quads of Belytschko and Bachrach (1986). Scaling it with the
    /// dilatational modulus instead over-stiffens and over-damps it as nu approaches 1/2
    /// (lambda grows without bound) and the hourglass work swamps the strain energy.
    pub hourglass_modulus: f64,
    /// Linear bulk-viscosity coefficient (0 = off).
    pub bulk_linear: f64,
    /// Quadratic bulk-viscosity coefficient (0 = off).
    pub bulk_quadratic: f64,
    /// Bulk modulus K = lambda + 2 mu / 3.
    pub bulk_modulus: f64,
    /// Initial yield stress (J2 plastic materials; infinite otherwise).
    pub yield_stress: f64,
    /// Linear isotropic hardening modulus (J2 plastic materials; 0 otherwise).
    pub hardening: f64,
    /// Johnson-Cook B, n, C and reference strain rate (0, 1, 0, 1 without Johnson-Cook): the
    /// flow stress is (sigma_y + H alpha + B alpha^n)(1 + C ln(max(rate / rate0, 1))).
    pub jc_b: f64,
    /// Johnson-Cook n.
    pub jc_n: f64,
    /// Johnson-Cook C.
    pub jc_c: f64,
    /// Johnson-Cook reference strain rate.
    pub jc_rate0: f64,
}

impl ElementParams {
    /// Builds the parameters of a body from its material, formulation and thickness.
    pub fn new(
        material: &Material,
        formulation: Formulation,
        thickness: f64,
        hourglass: HourglassForm,
        hourglass_coefficient: f64,
        bulk: (f64, f64),
    ) -> Self {
        let e = material.youngs_modulus;
        let nu = material.poisson_ratio;
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        let jc = material.plasticity.and_then(|p| p.johnson_cook);
        let lambda_plane = match formulation {
            Formulation::PlaneStrain | Formulation::Axisymmetric => lambda,
            Formulation::PlaneStress => 2.0 * lambda * mu / (lambda + 2.0 * mu),
        };
        Self {
            model: material.model,
            formulation,
            density: material.density,
            thickness,
            lambda,
            mu,
            lambda_plane,
            wave_modulus: lambda_plane + 2.0 * mu + lambda_plane.max(0.0),
            reference_speed: ((lambda_plane + 2.0 * mu + lambda_plane.max(0.0)) / material.density)
                .sqrt(),
            hourglass,
            hourglass_coefficient,
            hourglass_modulus: 2.0 * mu,
            bulk_linear: bulk.0,
            bulk_quadratic: bulk.1,
            bulk_modulus: lambda + 2.0 * mu / 3.0,
            yield_stress: material
                .plasticity
                .map_or(f64::INFINITY, |p| p.yield_stress),
            hardening: material.plasticity.map_or(0.0, |p| p.hardening_modulus),
            jc_b: jc.map_or(0.0, |j| j.b),
            jc_n: jc.map_or(1.0, |j| j.n),
            jc_c: jc.map_or(0.0, |j| j.c),
            jc_rate0: jc.map_or(1.0, |j| j.reference_strain_rate),
        }
    }

    /// Dilatational wave speed of the formulation, sqrt((lambda_plane + 2 mu) / rho).
    pub fn dilatational_speed(&self) -> f64 {
        ((self.lambda_plane + 2.0 * self.mu) / self.density).sqrt()
    }

    /// Whether the bulk viscosity is on.
    pub fn has_bulk_viscosity(&self) -> bool {
        self.bulk_linear > 0.0 || self.bulk_quadratic > 0.0
    }
}

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
    /// Viscous hourglass generalized force Q_i (force on node a is -gamma_a Q_i).
    pub hourglass_q: [f64; 2],
    /// Bulk-viscosity first Piola-Kirchhoff stress (xx, xy, yx, yy).
    pub bulk_p: [f64; 4],
    /// Its hoop component (axisymmetric elements).
    pub bulk_hoop: f64,
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
    /// Plastic state after the step (J2 plastic materials; the input state otherwise).
    pub plastic: PlasticState,
    /// Energy the plastic return dissipated in this evaluation (J2 plastic materials).
    pub plastic_work: f64,
}

/// Dissipative state of an element from the previous step, for the trapezoidal work pairing.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Dissipation {
    /// Viscous hourglass generalized force of the previous step.
    pub hourglass_q: [f64; 2],
    /// Bulk-viscosity stress of the previous step.
    pub bulk_p: [f64; 4],
    /// Its hoop component (axisymmetric elements).
    pub bulk_hoop: f64,
}

/// Reference geometry of a quad at its centre: area and shape-function gradients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadGeometry {
    /// Area.
    pub area: f64,
    /// dN_a/dX at the centre, per node.
    pub bx: [f64; 4],
    /// dN_a/dY at the centre, per node.
    pub by: [f64; 4],
    /// Flanagan-Belytschko hourglass vector gamma_a.
    pub gamma: [f64; 4],
    /// 1 / area.
    pub inv_area: f64,
    /// (b . b) / (gamma . gamma): geometry factor of the stiffness hourglass coefficient.
    pub hourglass_stiffness: f64,
    /// sqrt(b . b) / (gamma . gamma): geometry factor of the viscous hourglass coefficient.
    pub hourglass_viscous: f64,
    /// Reference radius of the centre (axisymmetric elements; 0 otherwise, see
    /// [`crate::model::Model::geometry`]).
    pub radius: f64,
    /// A triangle (collapsed quad): no hourglass mode, so `gamma` and the hourglass factors are 0.
    pub triangle: bool,
}

/// Centre gradients and hourglass vector of the quad with corners `x` (counter-clockwise).
#[inline]
pub fn quad_geometry(x: &[[f64; 2]; 4]) -> QuadGeometry {
    let (x1, x2, x3, x4) = (x[0][0], x[1][0], x[2][0], x[3][0]);
    let (y1, y2, y3, y4) = (x[0][1], x[1][1], x[2][1], x[3][1]);
    let area = 0.5 * ((x3 - x1) * (y4 - y2) - (x4 - x2) * (y3 - y1));
    let s = 0.5 / area;
    let bx = [s * (y2 - y4), s * (y3 - y1), s * (y4 - y2), s * (y1 - y3)];
    let by = [s * (x4 - x2), s * (x1 - x3), s * (x2 - x4), s * (x3 - x1)];
    let h = HOURGLASS_BASE;
    let hx = h[0] * x1 + h[1] * x2 + h[2] * x3 + h[3] * x4;
    let hy = h[0] * y1 + h[1] * y2 + h[2] * y3 + h[3] * y4;
    let gamma = [
        h[0] - hx * bx[0] - hy * by[0],
        h[1] - hx * bx[1] - hy * by[1],
        h[2] - hx * bx[2] - hy * by[2],
        h[3] - hx * bx[3] - hy * by[3],
    ];
    let bb: f64 = (0..4).map(|a| bx[a] * bx[a] + by[a] * by[a]).sum();
    let gg: f64 = gamma.iter().map(|x| x * x).sum();
    if is_triangle_geometry(x) {
        return QuadGeometry {
            area,
            inv_area: 1.0 / area,
            hourglass_stiffness: 0.0,
            hourglass_viscous: 0.0,
            radius: 0.0,
            bx,
            by,
            gamma: [0.0; 4],
            triangle: true,
        };
    }
    QuadGeometry {
        area,
        inv_area: 1.0 / area,
        hourglass_stiffness: bb / gg,
        hourglass_viscous: bb.sqrt() / gg,
        radius: 0.0,
        bx,
        by,
        gamma,
        triangle: false,
    }
}

/// Characteristic length of a quad: area over max(longest side, longest diagonal / sqrt 2).
/// Equal to the side for a square, to the short side for a thin rectangle.
///
/// A triangle (collapsed quad, whose longest side is then the maximum) gets [`TRIANGLE_LENGTH`]
/// times that, sqrt(2/3) of its smallest altitude: with lumped masses A/3, the largest
/// eigenfrequency of a constant-strain triangle is at most 2 c / (sqrt(2/3) h_min), for
/// c^2 = (lambda + 2 mu + max(lambda, 0)) / rho, on every shape and Poisson ratio (the bound is
/// reached by slender isosceles triangles at nu = 0; the unit test below checks it against the
/// element's eigenvalues).
#[inline]
pub fn characteristic_length(x: &[[f64; 2]; 4], area: f64) -> f64 {
    let d = |a: usize, b: usize| {
        let dx = x[b][0] - x[a][0];
        let dy = x[b][1] - x[a][1];
        dx * dx + dy * dy
    };
    let side = d(0, 1).max(d(1, 2)).max(d(2, 3)).max(d(3, 0));
    let diag = 0.5 * d(0, 2).max(d(1, 3));
    let l = area / side.max(diag).sqrt();
    if is_triangle_geometry(x) {
        TRIANGLE_LENGTH * l
    } else {
        l
    }
}

/// Smallest corner cross product of `x` (twice the area of the corner's triangle). A triangle
/// has one: its corners 0 and 1 (corners 2 and 3 meet a zero-length side).
#[inline]
pub fn min_corner_cross(x: &[[f64; 2]; 4]) -> f64 {
    let corners = if is_triangle_geometry(x) { 1 } else { 4 };
    let mut m = f64::INFINITY;
    for a in 0..corners {
        let p = x[(a + 3) % 4];
        let c = x[a];
        let n = x[(a + 1) % 4];
        m = m.min((n[0] - c[0]) * (p[1] - c[1]) - (n[1] - c[1]) * (p[0] - c[0]));
    }
    m
}

/// Smallest corner Jacobian of `x`, relative to the quad's area (1 for a parallelogram, 2 for a
/// triangle).
#[inline]
pub fn min_corner_ratio(x: &[[f64; 2]; 4], area: f64) -> f64 {
    let m = min_corner_cross(x);
    if area.abs() > 0.0 {
        m / area.abs()
    } else {
        m
    }
}

fn det(f: &[f64; 4]) -> f64 {
    f[0] * f[3] - f[1] * f[2]
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
        (s.pk, s.p33, s.stored, s.cauchy, s.state, d)
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

    let mut force = [[0.0; 2]; 4];
    for a in 0..4 {
        force[a][0] = -a0t * (pk[0] * g.bx[a] + pk[1] * g.by[a]);
        force[a][1] = -a0t * (pk[2] * g.bx[a] + pk[3] * g.by[a]);
    }
    if axi {
        // The hoop stress on u_r: dF_33 / du_r,a = N_a / R (N_a = 1/4, or 1/3 on a triangle).
        let hoop = a0t * p33 / g.radius;
        for a in 0..4 {
            force[a][0] -= wc[a] * hoop;
        }
    }

    // Hourglass control (Flanagan-Belytschko), on the reference gamma.
    let mut hourglass_stored = 0.0;
    let mut hourglass_q = [0.0; 2];
    let mut hourglass_work = 0.0;
    // A triangle has no hourglass mode (see the module documentation).
    let hourglass = if g.triangle {
        HourglassForm::None
    } else {
        p.hourglass
    };
    match hourglass {
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
            hourglass_stored = 0.5 * k * (q[0] * q[0] + q[1] * q[1]);
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
            hourglass_q = [damp * qd[0], damp * qd[1]];
            for a in 0..4 {
                force[a][0] -= g.gamma[a] * hourglass_q[0];
                force[a][1] -= g.gamma[a] * hourglass_q[1];
            }
            // Dissipated: 1/2 (gamma . du)(Q^{n-1} + Q^n), du = dt_prev v^{n-1/2}.
            hourglass_work = 0.5
                * dt_prev
                * (qd[0] * (prev.hourglass_q[0] + hourglass_q[0])
                    + qd[1] * (prev.hourglass_q[1] + hourglass_q[1]));
        }
    }

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
        for a in 0..4 {
            force[a][0] -= a0t * (bulk_p[0] * g.bx[a] + bulk_p[1] * g.by[a]);
            force[a][1] -= a0t * (bulk_p[2] * g.bx[a] + bulk_p[3] * g.by[a]);
        }
        if axi {
            let hoop = a0t * bulk_hoop / g.radius;
            for a in 0..4 {
                force[a][0] -= wc[a] * hoop;
            }
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
        hourglass_stored,
        hourglass_q,
        bulk_p,
        bulk_hoop,
        hourglass_work,
        bulk_work,
        min_corner,
        stress: cauchy,
        def_grad: f,
        hoop_stretch: f33,
        plastic: new_plastic,
        plastic_work: plastic_density * a0t,
    }
}

/// First Piola-Kirchhoff stress (xx xy yx yy), strain energy per reference volume, the Cauchy
/// stress (xx yy xy zz) and the out-of-plane first Piola-Kirchhoff stress P_33 for the in-plane
/// deformation gradient `f` with determinant `j` and the out-of-plane stretch `f33` (used by
/// axisymmetric bodies: r / R; 1 otherwise). A J2 plastic material from the virgin state: see
/// [`evaluate_state`] for a yielded one.
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

#[cfg(test)]
mod tests {
    use super::*;

    fn steel(model: MaterialModel) -> Material {
        Material {
            name: "steel".into(),
            model,
            density: 7850.0,
            youngs_modulus: 210e9,
            poisson_ratio: 0.3,
            plasticity: None,
        }
    }

    fn params(model: MaterialModel, form: Formulation, hg: HourglassForm) -> ElementParams {
        ElementParams::new(&steel(model), form, 1.0, hg, 0.1, (0.0, 0.0))
    }

    const SQUARE: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];

    #[test]
    fn gamma_is_orthogonal_to_linear_fields() {
        let x = [[0.0, 0.0], [2.0, 0.1], [2.3, 1.7], [-0.2, 1.1]];
        let g = quad_geometry(&x);
        let sx: f64 = (0..4).map(|a| g.gamma[a] * x[a][0]).sum();
        let sy: f64 = (0..4).map(|a| g.gamma[a] * x[a][1]).sum();
        let s1: f64 = g.gamma.iter().sum();
        assert!(sx.abs() < 1e-12 && sy.abs() < 1e-12 && s1.abs() < 1e-12);
        // b reproduces the gradient of linear fields
        let gx: f64 = (0..4).map(|a| g.bx[a] * x[a][0]).sum();
        let gy: f64 = (0..4).map(|a| g.by[a] * x[a][0]).sum();
        assert!((gx - 1.0).abs() < 1e-12 && gy.abs() < 1e-12);
    }

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
