//! The metric extractors of the verification cases: each reads a finished run (its history
//! samples, the final displacement and the model) and returns one number.

use std::collections::BTreeMap;

use super::case::{eval, Metric, MetricKind};
use crate::element::plastic::PlasticState;
use crate::model::surface::Surface;
use crate::model::Model;
use crate::output::fields::{element_fields, element_fields_state};
use crate::scene::RigidWall;
use crate::step::Sample;

/// A surface node touches a rigid wall when its distance to the wall is below this fraction of
/// its tributary length (Lagrange contact closes the gap to round-off; just outside a Hertz
/// contact zone, half an element from its edge, the gap is still about 1e-2 of the element).
pub const TOUCH_FRACTION: f64 = 1e-3;

/// The contact pressure at one surface node touching a rigid wall, from the static nodal balance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodalPressure {
    /// Global node index.
    pub node: u32,
    /// Current position.
    pub position: [f64; 2],
    /// Contact pressure (Pa, compressive positive).
    pub pressure: f64,
    /// Tributary length along the wall: half the sum of the lengths of the node's two surface
    /// segments (reference configuration) projected on the wall.
    pub length: f64,
    /// Reference coordinate along the wall (the tangent is the normal turned clockwise).
    pub along: f64,
    /// Smallest and largest coordinate along the wall of the node's two surface neighbours.
    pub neighbours: [f64; 2],
}

/// The contact pressure at every surface node of `body` that touches `wall`, for the
/// displacement `u` at time `t`.
///
/// In static equilibrium the contact force on a node balances the element forces and the
/// external (pressure) loads on it: `f_c = -(f_elements + f_ext)`, with the element forces
/// evaluated in f64 from `u` alone (stress and stiffness hourglass; no velocity, so no viscous
/// part). The pressure is the component of `f_c` along the wall normal over the tributary area
/// (the tributary length along the wall times the thickness), lengths taken in the reference
/// configuration: the nominal traction, the one the small-strain theory (Hertz) and the
/// geometrically linear material balance. A node touches the wall when its current distance to
/// it is below [`TOUCH_FRACTION`] of its tributary length. The result depends only on
/// `u`, so CPU and GPU runs are measured alike; it is exact for a converged dynamic relaxation
/// (no inertia or damping force left).
pub fn contact_pressures(
    model: &crate::model::Model,
    u: &[[f64; 2]],
    body: usize,
    wall: &RigidWall,
    t: f64,
) -> Vec<NodalPressure> {
    let b = &model.bodies[body];
    let mut force = vec![[0.0f64; 2]; model.node_count()];
    for e in b.elements.clone() {
        let q = model.quads[e];
        let out = model.element_at(e, u, &PlasticState::VIRGIN);
        for (a, &n) in q.iter().enumerate() {
            force[n as usize][0] += out.force[a][0];
            force[n as usize][1] += out.force[a][1];
        }
    }
    for load in &model.pressures {
        let p = load.at(t);
        for (n, f) in &load.nodes {
            force[*n as usize][0] += p * f[0];
            force[*n as usize][1] += p * f[1];
        }
    }
    let x = |n: u32| {
        let (p, d) = (model.position[n as usize], u[n as usize]);
        [p[0] + d[0], p[1] + d[1]]
    };
    let nw = wall.normal;
    let surface = Surface::of_body(model, body);
    let along = |p: [f64; 2]| p[0] * nw[1] - p[1] * nw[0];
    let mut length = vec![0.0f64; model.node_count()];
    let mut neighbours = vec![[f64::INFINITY, f64::NEG_INFINITY]; model.node_count()];
    let reference = |n: u32| model.position[n as usize];
    for s in &surface.segments {
        let [a, c] = s.nodes;
        let (sa, sc) = (along(reference(a)), along(reference(c)));
        length[a as usize] += 0.5 * (sc - sa).abs();
        length[c as usize] += 0.5 * (sc - sa).abs();
        for (n, other) in [(a, sc), (c, sa)] {
            let nb = &mut neighbours[n as usize];
            nb[0] = nb[0].min(other);
            nb[1] = nb[1].max(other);
        }
    }
    let thickness = b.params.thickness;
    surface
        .nodes
        .iter()
        .filter_map(|&n| {
            let i = n as usize;
            let xn = x(n);
            let gap = (xn[0] - wall.point[0]) * nw[0] + (xn[1] - wall.point[1]) * nw[1];
            if !(length[i] > 0.0 && gap <= TOUCH_FRACTION * length[i]) {
                return None;
            }
            // f_c . n_wall = -(f_elements + f_ext) . n_wall
            let fc = -(force[i][0] * nw[0] + force[i][1] * nw[1]);
            Some(NodalPressure {
                node: n,
                position: xn,
                pressure: fc / (length[i] * thickness),
                length: length[i],
                along: along(reference(n)),
                neighbours: neighbours[i],
            })
        })
        .collect()
}

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
    /// The plastic state of every element at the end (empty without a J2 plastic material).
    pub plastic: &'a [PlasticState],
}

/// The least-squares line through `points` (t, v): its slope and its value at the mean t;
/// `None` for fewer than two distinct times.
pub fn line_fit(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let mt = points.iter().map(|p| p.0).sum::<f64>() / n;
    let mv = points.iter().map(|p| p.1).sum::<f64>() / n;
    let (num, den) = points.iter().fold((0.0, 0.0), |(a, c), (t, v)| {
        (a + (t - mt) * (v - mv), c + (t - mt) * (t - mt))
    });
    (den > 0.0).then(|| (num / den, mv))
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
        MetricKind::ResidualVelocity => {
            let b = body()?;
            let v0 = first.0.body_velocity[b][comp];
            if v0 == 0.0 {
                return Err(format!("body {:?} starts at rest", m.body));
            }
            (last.0.body_velocity[b][comp] * v0.signum()).max(0.0)
        }
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
        MetricKind::ErosionTime => {
            samples
                .iter()
                .find(|(s, _)| s.eroded_elements > 0)
                .ok_or("no element eroded")?
                .0
                .time
        }
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
        MetricKind::KineticRatio => {
            if last.0.internal <= 0.0 {
                return Err("no internal energy at the end".into());
            }
            last.0.kinetic / last.0.internal
        }
        MetricKind::FinalForce => last
            .0
            .contacts
            .get(contact()?)
            .map_or(0.0, |c| c.force[comp].abs()),
        MetricKind::FinalPenetration => last
            .0
            .contacts
            .get(contact()?)
            .map_or(0.0, |c| c.max_penetration),
        MetricKind::PeakPressure | MetricKind::ContactHalfWidth | MetricKind::EdgeError => {
            let name = m.contact.as_deref().unwrap_or("");
            let wall = r
                .model
                .walls
                .iter()
                .find(|w| w.name == name)
                .ok_or_else(|| format!("no rigid wall named {name:?}"))?;
            let p = contact_pressures(r.model, r.displacement, body()?, wall, last.0.time);
            let loaded: Vec<&NodalPressure> = p.iter().filter(|x| x.pressure > 0.0).collect();
            if loaded.is_empty() {
                return Err(format!("no contact pressure on body {:?}", m.body));
            }
            let a = 0.5 * loaded.iter().map(|x| x.length).sum::<f64>();
            match m.kind {
                MetricKind::PeakPressure => p.iter().map(|x| x.pressure).fold(0.0, f64::max),
                MetricKind::ContactHalfWidth => a,
                _ => {
                    // The element sizes across the two edges of the loaded zone: from the outermost
                    // loaded node to its outer neighbour.
                    let first = loaded.iter().min_by(|u, v| u.along.total_cmp(&v.along));
                    let last = loaded.iter().max_by(|u, v| u.along.total_cmp(&v.along));
                    let (Some(first), Some(last)) = (first, last) else {
                        return Err("no loaded node".into());
                    };
                    let h = 0.5
                        * ((last.neighbours[1] - last.along) + (first.along - first.neighbours[0]));
                    if !(h.is_finite() && h > 0.0) {
                        return Err("no surface node beyond the loaded zone".into());
                    }
                    let a_ref = m.half_width.ok_or("no half_width")?;
                    (a - a_ref) / h
                }
            }
        }
        MetricKind::Extent | MetricKind::MaxCoordinate => {
            let b = &r.model.bodies[body()?];
            let x = |n: usize| r.model.position[n][comp] + r.displacement[n][comp];
            let hi = b.nodes.clone().map(x).fold(f64::NEG_INFINITY, f64::max);
            let lo = b.nodes.clone().map(x).fold(f64::INFINITY, f64::min);
            if m.kind == MetricKind::Extent {
                hi - lo
            } else {
                hi
            }
        }
        MetricKind::StopTime => {
            let b = body()?;
            let v0 = first.0.body_velocity[b][comp];
            let phase: Vec<(f64, f64)> = samples
                .iter()
                .map(|(s, _)| (s.time, s.body_velocity[b][comp]))
                .filter(|(_, v)| v0 != 0.0 && (0.1..=0.9).contains(&(v / v0)))
                .collect();
            let (slope, at) = line_fit(&phase)
                .ok_or_else(|| format!("body {:?} has no sliding phase to fit", m.body))?;
            if slope * v0 >= 0.0 {
                return Err(format!("body {:?} does not decelerate", m.body));
            }
            // v(t) = at + slope (t - mean t): zero at mean t - at / slope.
            let mean_t = phase.iter().map(|p| p.0).sum::<f64>() / phase.len() as f64;
            mean_t - at / slope
        }
        MetricKind::Displacement => {
            let b = &r.model.bodies[body()?];
            b.nodes
                .clone()
                .map(|n| r.model.mass[n] * r.displacement[n][comp])
                .sum::<f64>()
                / b.mass
        }
        MetricKind::FrictionWork => last.0.friction,
        MetricKind::Acceleration => {
            let b = body()?;
            let points: Vec<(f64, f64)> = samples
                .iter()
                .map(|(s, _)| (s.time, s.body_velocity[b][comp]))
                .collect();
            line_fit(&points).ok_or("fewer than two history rows")?.0
        }
        MetricKind::PeakPlasticStrain => {
            let b = &r.model.bodies[body()?];
            if r.plastic.is_empty() {
                return Err("the run has no plastic state".into());
            }
            b.elements
                .clone()
                .map(|e| r.plastic[e].alpha)
                .fold(0.0, f64::max)
        }
        MetricKind::LameStressError | MetricKind::LameDisplacementError => {
            let [a, bo, p] = m.lame.ok_or("no lame = [a, b, p]")?;
            let b = &r.model.bodies[body()?];
            let (aa, bb) = (
                p * a * a / (bo * bo - a * a),
                p * a * a * bo * bo / (bo * bo - a * a),
            );
            let mut err = 0.0f64;
            if m.kind == MetricKind::LameStressError {
                for e in b.elements.clone() {
                    // The closed form is small-strain: at the centre's reference radius (the
                    // current one shifts sigma_theta(a) by 2 B u_r / a^3, 0.24 % of p here).
                    let q = r.model.quads[e];
                    let rc = 0.25
                        * q.iter()
                            .map(|&n| r.model.position[n as usize][0])
                            .sum::<f64>();
                    let s = element_fields_state(
                        r.model,
                        r.displacement,
                        e,
                        r.plastic.get(e).unwrap_or(&PlasticState::VIRGIN),
                    )
                    .stress;
                    err = err
                        .max((s[0] - (aa - bb / (rc * rc))).abs())
                        .max((s[3] - (aa + bb / (rc * rc))).abs());
                }
            } else {
                let pr = &b.params;
                let e_mod = pr.mu * (3.0 * pr.lambda + 2.0 * pr.mu) / (pr.lambda + pr.mu);
                let nu = pr.lambda / (2.0 * (pr.lambda + pr.mu));
                for n in b.nodes.clone() {
                    let x = r.model.position[n][0];
                    let ur = (1.0 + nu) / e_mod * ((1.0 - 2.0 * nu) * aa * x + bb / x);
                    err = err.max((r.displacement[n][0] - ur).abs());
                }
            }
            err
        }
        MetricKind::ThermalSofteningError => {
            let b = &r.model.bodies[body()?];
            let p = &b.params;
            if !(p.has_thermal() && p.jc_m == 1.0 && p.jc_c == 0.0) {
                return Err(format!(
                    "body {:?}: the closed form needs Johnson-Cook thermal softening with m = 1 \
                     and no rate term (c = 0)",
                    b.name
                ));
            }
            if r.plastic.is_empty() {
                return Err("the run has no plastic state".into());
            }
            let k = p.heating / p.melt_rise;
            let mut err = 0.0f64;
            for e in b.elements.clone() {
                let s = &r.plastic[e];
                let a = s.alpha;
                let w0 = p.yield_stress * a
                    + 0.5 * p.hardening * a * a
                    + p.jc_b * a.powf(p.jc_n + 1.0) / (p.jc_n + 1.0);
                let closed = -(-k * w0).exp_m1();
                err = err.max((p.t_star(s.heat) - closed).abs());
            }
            err
        }
        MetricKind::UniaxialJ2Error => {
            let b = &r.model.bodies[body()?];
            let pr = &b.params;
            let y = |n: usize, u: bool| {
                r.model.position[n][1] + if u { r.displacement[n][1] } else { 0.0 }
            };
            let ext = |u: bool| {
                let hi = b
                    .nodes
                    .clone()
                    .map(|n| y(n, u))
                    .fold(f64::NEG_INFINITY, f64::max);
                let lo = b
                    .nodes
                    .clone()
                    .map(|n| y(n, u))
                    .fold(f64::INFINITY, f64::min);
                hi - lo
            };
            let x = (1.0 - ext(true) / ext(false)).abs();
            let first = pr.yield_stress / (2.0 * pr.mu);
            let closed = if x <= first {
                2.0 * pr.mu * x
            } else {
                pr.yield_stress
                    + 2.0 * pr.mu * pr.hardening / (3.0 * pr.mu + pr.hardening) * (x - first)
            };
            let mut err = 0.0f64;
            for e in b.elements.clone() {
                let f = element_fields_state(
                    r.model,
                    r.displacement,
                    e,
                    r.plastic.get(e).unwrap_or(&PlasticState::VIRGIN),
                );
                err = err.max((f.von_mises - closed).abs());
            }
            err
        }
    })
}

/// The metric's reference for a run's variables, and the error of `value` against it:
/// |value - reference| / scale.
///
/// # Errors
/// A message when the reference or the scale cannot be evaluated, or the scale is not > 0.
pub fn relative_error(
    m: &Metric,
    value: f64,
    vars: &BTreeMap<String, f64>,
) -> std::result::Result<(f64, f64), String> {
    let reference = m
        .reference
        .value(vars)
        .map_err(|e| format!("reference: {e}"))?;
    let scale = match &m.scale {
        Some(s) => s.value(vars).map_err(|e| format!("scale: {e}"))?,
        None if reference != 0.0 => reference.abs(),
        None => 1.0,
    };
    if scale.is_nan() || scale <= 0.0 {
        return Err(format!("scale {scale} is not > 0"));
    }
    Ok((reference, (value - reference).abs() / scale))
}
