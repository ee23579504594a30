//! The metric extractors of the verification cases: each reads a finished run (its history
//! samples, the final displacement and the model) and returns one number.

use std::collections::BTreeMap;

use super::case::{eval, Metric, MetricKind};
use crate::model::Model;
use crate::output::fields::element_fields;
use crate::step::Sample;

/// What a metric sees of a finished run.
pub struct RunData<'a> {
    /// The model.
    pub model: &'a Model,
    /// History samples with their energy-balance errors.
    pub samples: &'a [(Sample, f64)],
    /// The displacement at the end.
    pub displacement: &'a [[f64; 2]],
    /// Names of the contacts then walls, in the order of `Sample::contacts`.
    pub contacts: &'a [String],
    /// The run's variables (case and level).
    pub vars: &'a BTreeMap<String, f64>,
}

/// The value of `m` for a run, or why it cannot be measured.
///
/// # Errors
/// A message when the run has no such contact or body, or never made contact.
pub fn measure(m: &Metric, r: &RunData<'_>) -> std::result::Result<f64, String> {
    let samples = r.samples;
    let first = samples.first().ok_or("no history rows")?;
    let last = samples.last().ok_or("no history rows")?;
    let comp = m.component_index();
    let contact = || -> std::result::Result<usize, String> {
        let name = m.contact.as_deref().unwrap_or("");
        r.contacts
            .iter()
            .position(|c| c == name)
            .ok_or_else(|| format!("no contact or wall named {name:?} (have {:?})", r.contacts))
    };
    let body = || -> std::result::Result<usize, String> {
        let name = m.body.as_deref().unwrap_or("");
        r.model
            .bodies
            .iter()
            .position(|b| b.name == name)
            .ok_or_else(|| format!("no body named {name:?}"))
    };
    // Contact window: first to last row with a force (rows are intervals ending at their time).
    let window = |k: usize| -> std::result::Result<(usize, usize, Vec<f64>), String> {
        let f: Vec<f64> = samples
            .iter()
            .map(|(s, _)| s.contacts.get(k).map_or(0.0, |c| c.force[comp]))
            .collect();
        let a = f
            .iter()
            .position(|x| *x != 0.0)
            .ok_or("the contact never carried a force")?;
        let b = f.iter().rposition(|x| *x != 0.0).unwrap_or(a);
        Ok((a, b, f))
    };
    // The initial energy: the conserved total of the first row (kinetic + stored + dissipated +
    // contact - external), which holds the energy at t = 0 however the first step went.
    let e0 = crate::output::history::EnergyAudit::total(&first.0);
    Ok(match m.kind {
        MetricKind::ContactDuration => {
            let (a, b, _) = window(contact()?)?;
            let interval = if samples.len() > 1 {
                samples[1].0.time - samples[0].0.time
            } else {
                0.0
            };
            samples[b].0.time - samples[a].0.time + interval
        }
        MetricKind::PlateauForce => {
            let (a, b, f) = window(contact()?)?;
            let mut inside: Vec<f64> = f[a..=b].iter().map(|x| x.abs()).collect();
            inside.sort_by(f64::total_cmp);
            inside[inside.len() / 2]
        }
        MetricKind::PeakForce => {
            let (_, _, f) = window(contact()?)?;
            f.iter().fold(0.0f64, |m, x| m.max(x.abs()))
        }
        MetricKind::BodyVelocity => last.0.body_velocity[body()?][comp],
        MetricKind::Restitution => {
            let b = body()?;
            let v0 = first.0.body_velocity[b][comp];
            if v0 == 0.0 {
                return Err(format!("body {:?} starts at rest", m.body));
            }
            -last.0.body_velocity[b][comp] / v0
        }
        MetricKind::ContactEnergyRatio => {
            let factor = match &m.factor {
                Some(f) => eval(f, r.vars)?,
                None => 1.0,
            };
            factor * last.0.contact / e0
        }
        MetricKind::EnergyDrift => samples
            .iter()
            .map(|(s, _)| ((s.kinetic + s.internal + s.hourglass) / e0 - 1.0).abs())
            .fold(0.0, f64::max),
        MetricKind::EnergyBalance => samples.iter().map(|(_, e)| *e).fold(0.0, f64::max),
        MetricKind::StressError => {
            let [rxx, ryy, rxy] = m.stress.unwrap_or([0.0; 3]);
            let mut err = 0.0f64;
            for e in 0..r.model.element_count() {
                let [sxx, syy, sxy, _] = element_fields(r.model, r.displacement, e).stress;
                err = err
                    .max((sxx - rxx).abs())
                    .max((syy - ryy).abs())
                    .max((sxy - rxy).abs());
            }
            err
        }
    })
}

/// The error of `value` against the metric's reference: |value - reference| / scale.
pub fn relative_error(m: &Metric, value: f64) -> f64 {
    let scale = m.scale.unwrap_or(if m.reference != 0.0 {
        m.reference.abs()
    } else {
        1.0
    });
    (value - m.reference).abs() / scale
}
