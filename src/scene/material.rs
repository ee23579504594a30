//! `[[material]]`: materials (README, "Scene format", `[[material]]`): the raw table,
//! [`Material`], [`MaterialModel`], the yield parameters [`Plasticity`] and [`JohnsonCook`], and
//! their validation. The models themselves are in [`crate::step`] (CPU reference) and
//! `shaders/element.wgsl` (GPU). Host-side only.

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

/// Johnson-Cook flow stress without thermal softening:
/// (a + b eps_p^n)(1 + c ln(max(rate / reference_strain_rate, 1))), rate the equivalent plastic
/// strain rate.
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
        Ok(Material {
            name: m.name.clone(),
            model,
            density,
            youngs_modulus,
            poisson_ratio: nu,
            plasticity,
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
            let jc = self.johnson_cook(&format!("{key}.johnson_cook"), jc)?;
            return Ok(Some(Plasticity {
                yield_stress: jc.a,
                hardening_modulus: 0.0,
                johnson_cook: Some(jc),
            }));
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

    /// The `johnson_cook = { a, b, n, c, reference_strain_rate }` table at `key`.
    fn johnson_cook(&self, key: &str, v: &toml::Value) -> Result<JohnsonCook> {
        let Some(t) = v.as_table() else {
            return Err(self.invalid(
                key,
                v.to_string(),
                "expected a table { a, b, n, c, reference_strain_rate }",
            ));
        };
        const KEYS: [&str; 5] = ["a", "b", "n", "c", "reference_strain_rate"];
        if let Some(k) = t.keys().find(|k| !KEYS.contains(&k.as_str())) {
            return Err(self.invalid(
                format!("{key}.{k}"),
                t[k].to_string(),
                "unknown key (expected a, b, n, c, reference_strain_rate)",
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
        })
    }
}
