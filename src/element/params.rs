//! A body's element parameters: its material's constants in the forms the element uses
//! ([`ElementParams`]), its hourglass control and bulk viscosity. Built once per body by the
//! model; the GPU solver uploads them per body in f32 ([`crate::gpu::element::GpuBody`]).

use crate::scene::{FailureCriteria, Formulation, HourglassForm, Material, MaterialModel};

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
    /// Johnson-Cook thermal softening exponent m (0: no thermal softening nor heating; the
    /// flow stress then has no temperature term and the temperature stays at room temperature).
    pub jc_m: f64,
    /// T_m - T_r: the temperature rise at which T* reaches 1 (1 without thermal softening).
    pub melt_rise: f64,
    /// The temperature rise per unit plastic work per unit reference volume,
    /// taylor_quinney / (density specific_heat) (K m^3 / J; 0 without heating).
    pub heating: f64,
    /// Room (initial) temperature T_r (K; 0 without thermal softening): an element's
    /// temperature is T_r plus its rise ([`super::plastic::PlasticState::heat`]).
    pub room_temperature: f64,
    /// The material's failure criteria (`None`: its elements never fail; see
    /// [`crate::element::failure`]).
    pub failure: Option<FailureCriteria>,
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
        let thermal = jc.and_then(|j| j.thermal);
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
            jc_m: thermal.map_or(0.0, |t| t.m),
            melt_rise: thermal.map_or(1.0, |t| t.melt_temperature - t.room_temperature),
            heating: thermal.map_or(0.0, |t| {
                t.taylor_quinney / (material.density * t.specific_heat)
            }),
            room_temperature: thermal.map_or(0.0, |t| t.room_temperature),
            failure: material.failure,
        }
    }

    /// Dilatational wave speed of the formulation, sqrt((lambda_plane + 2 mu) / rho).
    pub fn dilatational_speed(&self) -> f64 {
        ((self.lambda_plane + 2.0 * self.mu) / self.density).sqrt()
    }

    /// Whether the material softens with temperature and heats adiabatically (Johnson-Cook
    /// `m`, `melt_temperature`, `room_temperature`).
    #[inline(always)]
    pub fn has_thermal(&self) -> bool {
        self.jc_m > 0.0
    }

    /// The homologous temperature T* of the temperature rise `heat`: heat / (T_m - T_r), clamped
    /// to [0, 1] (0 without thermal softening).
    #[inline(always)]
    pub fn t_star(&self, heat: f64) -> f64 {
        (heat / self.melt_rise).clamp(0.0, 1.0)
    }

    /// The thermal softening factor 1 - T*^m of the temperature rise `heat` (1 without thermal
    /// softening).
    #[inline(always)]
    pub fn softening(&self, heat: f64) -> f64 {
        if self.has_thermal() {
            1.0 - self.t_star(heat).powf(self.jc_m)
        } else {
            1.0
        }
    }

    /// Whether the bulk viscosity is on.
    pub fn has_bulk_viscosity(&self) -> bool {
        self.bulk_linear > 0.0 || self.bulk_quadratic > 0.0
    }
}
