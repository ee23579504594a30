//! `[[material]]`: materials (README, "Scene format", `[[material]]`): the raw table,
//! [`Material`], [`MaterialModel`], the yield parameters [`Plasticity`] and [`JohnsonCook`] (with
//! its thermal softening and adiabatic heating, [`ThermalSoftening`]), the failure criteria [`FailureCriteria`] and [`JohnsonCookDamage`], and their validation. The
//! models themselves are in [`crate::element`] (CPU reference; failure in
//! [`crate::element::failure`]) and `shaders/element.wgsl` (GPU). Host-side only.

use serde::Deserialize;

use super::validate::{fmt_num, number, Validator};
use crate::error::Result;

/// A `[[material]]` table as written (`johnson_cook` kept as a TOML value, checked key by key
/// below).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMaterial {
    name: String,
    model: String,
    density: f64,
    youngs_modulus: f64,
    poisson_ratio: f64,
    yield_stress: Option<f64>,
    hardening_modulus: Option<f64>,
    johnson_cook: Option<toml::Value>,
    specific_heat: Option<f64>,
    taylor_quinney: Option<f64>,
    failure: Option<toml::Value>,
}

/// Constitutive model of a material.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaterialModel {
    /// Small-strain linear elasticity (geometrically linear: for the textbook comparisons).
    LinearElastic,
    /// Compressible neo-Hookean hyperelasticity (finite strain, objective).
    NeoHookean,
    /// J2 (von Mises) plasticity with linear isotropic hardening, finite strain: Hencky
    /// elasticity on the elastic left Cauchy-Green tensor of a multiplicative split, radial return
    /// in logarithmic strain ([`crate::element::plastic`]).
    J2Plastic,
}

/// Yield parameters of a [`MaterialModel::J2Plastic`] material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plasticity {
    /// Initial yield stress sigma_y (Pa), > 0.
    pub yield_stress: f64,
    /// Linear isotropic hardening modulus H (Pa), >= 0: sigma_y + H eps_p.
    pub hardening_modulus: f64,
    /// The Johnson-Cook flow stress instead (then `yield_stress` = a, `hardening_modulus` = 0).
    pub johnson_cook: Option<JohnsonCook>,
}

/// Johnson-Cook flow stress:
/// (a + b eps_p^n)(1 + c ln(max(rate / reference_strain_rate, 1)))(1 - T*^m), rate the
/// equivalent plastic strain rate, T* the homologous temperature (0, no softening, without
/// [`JohnsonCook::thermal`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JohnsonCook {
    /// Initial yield stress A (Pa), > 0.
    pub a: f64,
    /// Hardening coefficient B (Pa), >= 0.
    pub b: f64,
    /// Hardening exponent n, in (0, 10].
    pub n: f64,
    /// Strain-rate coefficient C, >= 0.
    pub c: f64,
    /// Reference strain rate (1/s), > 0.
    pub reference_strain_rate: f64,
    /// Thermal softening with adiabatic heating (`m`, `melt_temperature`, `room_temperature` in
    /// the `johnson_cook` table, `specific_heat` and `taylor_quinney` beside it); `None`: the
    /// temperature stays at room temperature and T* = 0.
    pub thermal: Option<ThermalSoftening>,
}

/// Johnson-Cook thermal softening with adiabatic heating: every element has a temperature T,
/// raised on each step by `taylor_quinney` times the step's plastic work per unit reference
/// volume over (density x `specific_heat`) (the reference density: the heat per unit mass);
/// the flow stress gets the factor 1 - T*^m and the Johnson-Cook damage's d5 term uses the same
/// T* = (T - room_temperature) / (melt_temperature - room_temperature), clamped to [0, 1].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThermalSoftening {
    /// Thermal softening exponent m, > 0.
    pub m: f64,
    /// Melting temperature T_m (K), > room_temperature.
    pub melt_temperature: f64,
    /// Room (reference and initial) temperature T_r (K), >= 0.
    pub room_temperature: f64,
    /// Specific heat c_p (J/(kg K)), > 0.
    pub specific_heat: f64,
    /// Taylor-Quinney coefficient beta: the fraction of the plastic work that heats, in
    /// [0, 1] (0.9 by default).
    pub taylor_quinney: f64,
}

impl ThermalSoftening {
    /// The default Taylor-Quinney coefficient.
    pub const TAYLOR_QUINNEY: f64 = 0.9;

    /// As `check` and `summary.json` state it.
    pub fn describe(&self) -> String {
        format!(
            "thermal softening m {}, melt temperature {} K, room temperature {} K; adiabatic \
             heating: specific heat {} J/(kg K), taylor_quinney {}",
            self.m,
            self.melt_temperature,
            self.room_temperature,
            self.specific_heat,
            self.taylor_quinney
        )
    }
}

/// Johnson-Cook damage (Johnson and Cook 1985): the element fails when
/// D = sum d(eps_p) / eps_f reaches 1, with the failure strain
/// eps_f = [d1 + d2 exp(d3 sigma*)] [1 + d4 ln(max(rate / reference_strain_rate, 1))]
/// [1 + d5 T*], sigma* = sigma_m / sigma_vm the triaxiality (tension positive), rate the
/// equivalent plastic strain rate (its reference the flow stress's `reference_strain_rate`, 1/s
/// without a Johnson-Cook flow stress), T* the homologous temperature (0: no heating modelled).
/// eps_f is bounded below by [`crate::element::failure::MIN_FAILURE_STRAIN`]; no damage
/// accumulates below sigma* = -1/3 (Bao and Wierzbicki's cut-off).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JohnsonCookDamage {
    /// D1 (any finite number).
    pub d1: f64,
    /// D2 (any finite number).
    pub d2: f64,
    /// D3 (any finite number; < 0 makes eps_f fall with the triaxiality).
    pub d3: f64,
    /// D4, the strain-rate term.
    pub d4: f64,
    /// D5, the temperature term.
    pub d5: f64,
    /// Reference strain rate of the rate term (1/s): the flow stress's, 1 without one.
    pub reference_strain_rate: f64,
}

/// The failure criteria of a material (`failure = { ... }`): an element erodes at the first
/// that it meets.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FailureCriteria {
    /// `plastic_strain`: the equivalent plastic strain at failure (> 0; `j2_plastic` only).
    pub plastic_strain: Option<f64>,
    /// `johnson_cook = { d1, d2, d3, d4, d5 }`: Johnson-Cook damage (`j2_plastic` only).
    pub johnson_cook: Option<JohnsonCookDamage>,
    /// `principal_strain`: the largest principal logarithmic (true) strain at failure (> 0).
    pub principal_strain: Option<f64>,
    /// `tensile_pressure`: the spall limit, the tension -p = sigma_m at failure (Pa, > 0).
    pub tensile_pressure: Option<f64>,
}

impl FailureCriteria {
    /// The criteria as `check` and `summary.json` state them: "plastic_strain 0.8, johnson_cook
    /// (d1 0.54, ...)".
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if let Some(x) = self.plastic_strain {
            parts.push(format!("plastic_strain {x}"));
        }
        if let Some(d) = &self.johnson_cook {
            parts.push(format!(
                "johnson_cook (d1 {}, d2 {}, d3 {}, d4 {}, d5 {}, reference strain rate {:e} 1/s)",
                d.d1, d.d2, d.d3, d.d4, d.d5, d.reference_strain_rate
            ));
        }
        if let Some(x) = self.principal_strain {
            parts.push(format!("principal_strain {x}"));
        }
        if let Some(x) = self.tensile_pressure {
            parts.push(format!("tensile_pressure {x:e} Pa"));
        }
        parts.join(", ")
    }
}

/// A material, validated.
#[derive(Debug, Clone)]
pub struct Material {
    /// Name used by bodies.
    pub name: String,
    /// Constitutive model.
    pub model: MaterialModel,
    /// Mass density (kg/m^3).
    pub density: f64,
    /// Young's modulus (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio, in (-1, 0.5).
    pub poisson_ratio: f64,
    /// Yield parameters (`Some` exactly for [`MaterialModel::J2Plastic`]).
    pub plasticity: Option<Plasticity>,
    /// Failure criteria (`None`: the material never fails).
    pub failure: Option<FailureCriteria>,
}

impl Validator<'_> {
    /// The `[[material]]` tables, in order; names must differ.
    pub(super) fn materials(&self, raw: &[RawMaterial]) -> Result<Vec<Material>> {
        let mut materials: Vec<Material> = Vec::new();
        for (i, m) in raw.iter().enumerate() {
            let key = format!("material[{i}]");
            if materials.iter().any(|o| o.name == m.name) {
                return Err(self.invalid(
                    format!("{key}.name"),
                    format!("{:?}", m.name),
                    "duplicate material name",
                ));
            }
            materials.push(self.material(&key, m)?);
        }
        Ok(materials)
    }

    /// One `[[material]]` table at `key`.
    fn material(&self, key: &str, m: &RawMaterial) -> Result<Material> {
        let model = self.keyword(
            &format!("{key}.model"),
            Some(&m.model),
            &[
                ("linear_elastic", MaterialModel::LinearElastic),
                ("neo_hookean", MaterialModel::NeoHookean),
                ("j2_plastic", MaterialModel::J2Plastic),
            ],
            "unknown model; expected \"linear_elastic\", \"neo_hookean\" or \"j2_plastic\"",
        )?;
        let plasticity = self.plasticity(key, m, model)?;
        let density = self.positive(&format!("{key}.density"), m.density)?;
        let youngs_modulus = self.positive(&format!("{key}.youngs_modulus"), m.youngs_modulus)?;
        let nu = m.poisson_ratio;
        if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
            return Err(self.invalid(
                format!("{key}.poisson_ratio"),
                fmt_num(nu),
                "must lie in (-1, 0.5)",
            ));
        }
        let failure = match &m.failure {
            Some(v) => Some(self.failure(&format!("{key}.failure"), v, &m.model, plasticity)?),
            None => None,
        };
        Ok(Material {
            name: m.name.clone(),
            model,
            density,
            youngs_modulus,
            poisson_ratio: nu,
            plasticity,
            failure,
        })
    }

    /// The yield keys of material `key`: required for `j2_plastic`, refused for the elastic models.
    fn plasticity(
        &self,
        key: &str,
        m: &RawMaterial,
        model: MaterialModel,
    ) -> Result<Option<Plasticity>> {
        if model != MaterialModel::J2Plastic {
            let given = [
                ("yield_stress", m.yield_stress.is_some()),
                ("hardening_modulus", m.hardening_modulus.is_some()),
                ("johnson_cook", m.johnson_cook.is_some()),
                ("specific_heat", m.specific_heat.is_some()),
                ("taylor_quinney", m.taylor_quinney.is_some()),
            ];
            if let Some((k, _)) = given.iter().find(|(_, g)| *g) {
                return Err(self.invalid(
                    format!("{key}.{k}"),
                    "given",
                    &format!(
                        "only a \"j2_plastic\" material yields (this one is {:?})",
                        m.model
                    ),
                ));
            }
            return Ok(None);
        }
        if let Some(jc) = &m.johnson_cook {
            for (k, given) in [
                ("yield_stress", m.yield_stress.is_some()),
                ("hardening_modulus", m.hardening_modulus.is_some()),
            ] {
                if given {
                    return Err(self.invalid(
                        format!("{key}.{k}"),
                        "given",
                        "with johnson_cook the flow stress is (a + b eps_p^n)(1 + c ln(rate / \
                         reference_strain_rate)): give either johnson_cook or yield_stress and \
                         hardening_modulus",
                    ));
                }
            }
            let jc = self.johnson_cook(key, m, jc)?;
            return Ok(Some(Plasticity {
                yield_stress: jc.a,
                hardening_modulus: 0.0,
                johnson_cook: Some(jc),
            }));
        }
        for (k, x) in [
            ("specific_heat", m.specific_heat),
            ("taylor_quinney", m.taylor_quinney),
        ] {
            if let Some(x) = x {
                return Err(self.invalid(
                    format!("{key}.{k}"),
                    fmt_num(x),
                    "adiabatic heating needs the Johnson-Cook flow stress's thermal softening: \
                     johnson_cook = { ..., m, melt_temperature, room_temperature }",
                ));
            }
        }
        let Some(y) = m.yield_stress else {
            return Err(self.invalid(
                format!("{key}.yield_stress"),
                "missing",
                "a \"j2_plastic\" material needs yield_stress (Pa, > 0) or johnson_cook",
            ));
        };
        let yield_stress = self.positive(&format!("{key}.yield_stress"), y)?;
        let hardening_modulus = match m.hardening_modulus {
            Some(h) => self.non_negative(&format!("{key}.hardening_modulus"), h)?,
            None => 0.0,
        };
        Ok(Some(Plasticity {
            yield_stress,
            hardening_modulus,
            johnson_cook: None,
        }))
    }

    /// The `johnson_cook = { a, b, n, c, reference_strain_rate }` table (with, for thermal
    /// softening, `m`, `melt_temperature` and `room_temperature`) of material `mkey`, `m` its
    /// table (for `specific_heat` and `taylor_quinney`).
    fn johnson_cook(&self, mkey: &str, m: &RawMaterial, v: &toml::Value) -> Result<JohnsonCook> {
        let key = format!("{mkey}.johnson_cook");
        let key = key.as_str();
        let Some(t) = v.as_table() else {
            return Err(self.invalid(
                key,
                v.to_string(),
                "expected a table { a, b, n, c, reference_strain_rate }",
            ));
        };
        const KEYS: [&str; 8] = [
            "a",
            "b",
            "n",
            "c",
            "reference_strain_rate",
            "m",
            "melt_temperature",
            "room_temperature",
        ];
        if let Some(k) = t.keys().find(|k| !KEYS.contains(&k.as_str())) {
            return Err(self.invalid(
                format!("{key}.{k}"),
                t[k].to_string(),
                "unknown key (expected a, b, n, c, reference_strain_rate and, for thermal \
                 softening, m, melt_temperature, room_temperature)",
            ));
        }
        let get = |k: &str| -> Result<f64> {
            match t.get(k) {
                None => Err(self.invalid(
                    format!("{key}.{k}"),
                    "missing",
                    "the Johnson-Cook flow stress needs a, b, n, c and reference_strain_rate",
                )),
                Some(v) => number(v).ok_or_else(|| {
                    self.invalid(format!("{key}.{k}"), v.to_string(), "expected a number")
                }),
            }
        };
        let a = self.positive(&format!("{key}.a"), get("a")?)?;
        let b = self.non_negative(&format!("{key}.b"), get("b")?)?;
        let n = get("n")?;
        if !(n.is_finite() && n > 0.0 && n <= 10.0) {
            return Err(self.invalid(format!("{key}.n"), fmt_num(n), "must lie in (0, 10]"));
        }
        let c = self.non_negative(&format!("{key}.c"), get("c")?)?;
        let reference_strain_rate = self.positive(
            &format!("{key}.reference_strain_rate"),
            get("reference_strain_rate")?,
        )?;
        Ok(JohnsonCook {
            a,
            b,
            n,
            c,
            reference_strain_rate,
            thermal: self.thermal(mkey, m, t)?,
        })
    }

    /// The thermal softening of material `mkey` (table `m`) from its Johnson-Cook table `t`:
    /// `m`, `melt_temperature` and `room_temperature` all or none; with them `specific_heat`
    /// (required) and `taylor_quinney` (0.9 by default), refused without them.
    fn thermal(
        &self,
        mkey: &str,
        m: &RawMaterial,
        t: &toml::map::Map<String, toml::Value>,
    ) -> Result<Option<ThermalSoftening>> {
        let key = format!("{mkey}.johnson_cook");
        const KEYS: [&str; 3] = ["m", "melt_temperature", "room_temperature"];
        let given: Vec<&str> = KEYS
            .iter()
            .copied()
            .filter(|k| t.contains_key(*k))
            .collect();
        if given.is_empty() {
            for (k, x) in [
                ("specific_heat", m.specific_heat),
                ("taylor_quinney", m.taylor_quinney),
            ] {
                if let Some(x) = x {
                    return Err(self.invalid(
                        format!("{mkey}.{k}"),
                        fmt_num(x),
                        "adiabatic heating needs the Johnson-Cook flow stress's thermal \
                         softening: johnson_cook = { ..., m, melt_temperature, room_temperature }",
                    ));
                }
            }
            return Ok(None);
        }
        if let Some(k) = KEYS.iter().find(|k| !t.contains_key(**k)) {
            return Err(self.invalid(
                format!("{key}.{k}"),
                "missing",
                &format!(
                    "thermal softening needs m, melt_temperature and room_temperature together \
                     (given: {})",
                    given.join(", ")
                ),
            ));
        }
        let num = |k: &str| -> Result<f64> {
            let v = &t[k];
            let x = number(v).ok_or_else(|| {
                self.invalid(format!("{key}.{k}"), v.to_string(), "expected a number")
            })?;
            self.finite(&format!("{key}.{k}"), x)
        };
        let exponent = self.positive(&format!("{key}.m"), num("m")?)?;
        let room_temperature =
            self.non_negative(&format!("{key}.room_temperature"), num("room_temperature")?)?;
        let melt_temperature = num("melt_temperature")?;
        if melt_temperature <= room_temperature {
            return Err(self.invalid(
                format!("{key}.melt_temperature"),
                fmt_num(melt_temperature),
                &format!(
                    "must exceed room_temperature ({} K)",
                    fmt_num(room_temperature)
                ),
            ));
        }
        let Some(cp) = m.specific_heat else {
            return Err(self.invalid(
                format!("{mkey}.specific_heat"),
                "missing",
                "thermal softening heats the material adiabatically: give its specific_heat \
                 (J/(kg K), > 0)",
            ));
        };
        let specific_heat = self.positive(&format!("{mkey}.specific_heat"), cp)?;
        let taylor_quinney = m.taylor_quinney.unwrap_or(ThermalSoftening::TAYLOR_QUINNEY);
        if !(0.0..=1.0).contains(&taylor_quinney) {
            return Err(self.invalid(
                format!("{mkey}.taylor_quinney"),
                fmt_num(taylor_quinney),
                "must lie in [0, 1] (the fraction of the plastic work that heats)",
            ));
        }
        Ok(Some(ThermalSoftening {
            m: exponent,
            melt_temperature,
            room_temperature,
            specific_heat,
            taylor_quinney,
        }))
    }

    /// The `failure = { plastic_strain, johnson_cook, principal_strain, tensile_pressure }`
    /// table at `key` of a material of model `model` (named as written) with the yield
    /// parameters `plasticity`.
    fn failure(
        &self,
        key: &str,
        v: &toml::Value,
        model: &str,
        plasticity: Option<Plasticity>,
    ) -> Result<FailureCriteria> {
        const KEYS: [&str; 4] = [
            "plastic_strain",
            "johnson_cook",
            "principal_strain",
            "tensile_pressure",
        ];
        let expected = "expected a table with one or more of plastic_strain, johnson_cook, \
                        principal_strain, tensile_pressure";
        let Some(t) = v.as_table() else {
            return Err(self.invalid(key, v.to_string(), expected));
        };
        if let Some(k) = t.keys().find(|k| !KEYS.contains(&k.as_str())) {
            return Err(self.invalid(
                format!("{key}.{k}"),
                t[k].to_string(),
                "unknown key (expected plastic_strain, johnson_cook, principal_strain, \
                 tensile_pressure)",
            ));
        }
        if t.is_empty() {
            return Err(self.invalid(key, "{}", expected));
        }
        let num = |k: &str, v: &toml::Value| -> Result<f64> {
            number(v).ok_or_else(|| {
                self.invalid(format!("{key}.{k}"), v.to_string(), "expected a number")
            })
        };
        let plastic_only = |k: &str| -> Result<()> {
            if plasticity.is_none() {
                return Err(self.invalid(
                    format!("{key}.{k}"),
                    "given",
                    &format!("only a \"j2_plastic\" material has a plastic strain (this one is {model:?})"),
                ));
            }
            Ok(())
        };
        let mut c = FailureCriteria::default();
        if let Some(v) = t.get("plastic_strain") {
            plastic_only("plastic_strain")?;
            let k = format!("{key}.plastic_strain");
            c.plastic_strain = Some(self.positive(&k, num("plastic_strain", v)?)?);
        }
        if let Some(v) = t.get("principal_strain") {
            let k = format!("{key}.principal_strain");
            c.principal_strain = Some(self.positive(&k, num("principal_strain", v)?)?);
        }
        if let Some(v) = t.get("tensile_pressure") {
            let k = format!("{key}.tensile_pressure");
            c.tensile_pressure = Some(self.positive(&k, num("tensile_pressure", v)?)?);
        }
        if let Some(v) = t.get("johnson_cook") {
            plastic_only("johnson_cook")?;
            let rate0 = plasticity
                .and_then(|p| p.johnson_cook)
                .map_or(1.0, |j| j.reference_strain_rate);
            c.johnson_cook =
                Some(self.johnson_cook_damage(&format!("{key}.johnson_cook"), v, rate0)?);
        }
        Ok(c)
    }

    /// The `johnson_cook = { d1, d2, d3, d4, d5 }` damage table at `key`, its rate term
    /// referred to `rate0`.
    fn johnson_cook_damage(
        &self,
        key: &str,
        v: &toml::Value,
        rate0: f64,
    ) -> Result<JohnsonCookDamage> {
        const KEYS: [&str; 5] = ["d1", "d2", "d3", "d4", "d5"];
        let Some(t) = v.as_table() else {
            return Err(self.invalid(
                key,
                v.to_string(),
                "expected a table { d1, d2, d3, d4, d5 }",
            ));
        };
        if let Some(k) = t.keys().find(|k| !KEYS.contains(&k.as_str())) {
            return Err(self.invalid(
                format!("{key}.{k}"),
                t[k].to_string(),
                "unknown key (expected d1, d2, d3, d4, d5)",
            ));
        }
        let get = |k: &str| -> Result<f64> {
            let x = match t.get(k) {
                None => {
                    return Err(self.invalid(
                        format!("{key}.{k}"),
                        "missing",
                        "Johnson-Cook damage needs d1, d2, d3, d4 and d5",
                    ))
                }
                Some(v) => number(v).ok_or_else(|| {
                    self.invalid(format!("{key}.{k}"), v.to_string(), "expected a number")
                })?,
            };
            self.finite(&format!("{key}.{k}"), x)
        };
        let d = JohnsonCookDamage {
            d1: get("d1")?,
            d2: get("d2")?,
            d3: get("d3")?,
            d4: get("d4")?,
            d5: get("d5")?,
            reference_strain_rate: rate0,
        };
        // The failure strain at the reference state must be a strain that a test measures:
        // positive where the triaxiality is 0 (the floor would otherwise erode at once).
        if d.d1 + d.d2 <= 0.0 {
            return Err(self.invalid(
                format!("{key}.d1"),
                fmt_num(d.d1),
                &format!(
                    "d1 + d2 = {} is the failure strain at zero triaxiality and must be > 0",
                    fmt_num(d.d1 + d.d2)
                ),
            ));
        }
        Ok(d)
    }
}
