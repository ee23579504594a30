//! The CPU reference solver (f64, one thread). Every GPU kernel is tested against this path.

mod elements;

use super::erosion::Erosion;
use crate::contact::ContactSet;
use crate::element::plastic::PlasticState;
use crate::element::Dissipation;
use crate::error::Result;
use crate::geometry::QuadGeometry;
use crate::model::Model;
use crate::plan::{Plan, Stage};

use super::{Clock, Event, Failure, Sample, Schedule, Snapshot, Solver};

/// Explicit central-difference integration of a [`Model`] on the CPU.
#[derive(Debug, Clone)]
pub struct CpuSolver {
    model: Model,
    plan: Plan,
    schedule: Schedule,
    inv_mass: Vec<f64>,
    /// Reference geometry of each element (constant).
    geometry: Vec<QuadGeometry>,
    /// Pressure loads flattened: (load, node, force per unit pressure); empty without pressure.
    pressure: Vec<(usize, u32, [f64; 2])>,
    /// What changes while it runs.
    s: CpuState,
    /// The contact set's follows of erosion in this process: how many, and their seconds
    /// ([`crate::step::Counters::erosion_follows`]; not part of a checkpoint).
    follows: (u64, f64),
}

/// Everything of a [`CpuSolver`] that changes while it runs (the model, plan, schedule and what
/// is derived from them are rebuilt from the scene): a checkpoint's solver part.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct CpuState {
    clock: Clock,
    /// Displacements u_n.
    u: Vec<[f64; 2]>,
    /// Half-step velocities (v^{n-1/2} before the node stage, v^{n+1/2} after).
    v: Vec<[f64; 2]>,
    /// v^{n-1/2}, kept on output steps only.
    v_prev: Vec<[f64; 2]>,
    /// Nodal forces f_n.
    f: Vec<[f64; 2]>,
    /// Dissipative element state (empty when the plan has none).
    dissipation: Vec<Dissipation>,
    /// Plastic state of every element at u_n (empty without a J2 plastic material).
    plastic: Vec<PlasticState>,
    /// Work dissipated by plastic flow so far.
    plastic_work: f64,
    /// Contact state (none without contact).
    contact: Option<ContactSet>,
    /// Work of the contact impulses so far, and the part of the last step's after t_n.
    contact_work: f64,
    contact_after: f64,
    /// The friction impulses' share of them.
    #[serde(default)]
    friction_work: f64,
    #[serde(default)]
    friction_after: f64,
    hourglass_work: f64,
    bulk_work: f64,
    external_work: f64,
    /// The pressure impulse of the step on each entry of `pressure`, and v^{n-1/2} there.
    pressure_impulse: Vec<[f64; 2]>,
    pressure_v_old: Vec<[f64; 2]>,
    /// Work of the pressure impulses so far, and the part of the last step's after t_n.
    pressure_work: f64,
    pressure_after: f64,
    /// v^{n-1/2} of each node on damped steps (empty without damping).
    damping_v_old: Vec<[f64; 2]>,
    /// Work of the damping impulses so far (<= 0), and the part of the last step's after t_n.
    damping_work: f64,
    damping_after: f64,
    /// Work of gravity so far, and the part of the last step's after t_n.
    #[serde(default)]
    gravity_work: f64,
    #[serde(default)]
    gravity_after: f64,
    /// Failed elements, damage and the energy eroded with them (empty without failure).
    erosion: Erosion,
    t: f64,
    n: u64,
    dt_prev: f64,
    dt_first: f64,
    dt_range: (f64, f64),
    done: bool,
}

impl CpuSolver {
    /// A solver at t = 0 with the model's initial velocities.
    pub fn new(model: Model, plan: Plan, schedule: Schedule) -> Self {
        let nn = model.node_count();
        let ne = model.element_count();
        let dissipation = if plan.has_dissipation() {
            vec![Dissipation::default(); ne]
        } else {
            Vec::new()
        };
        let pressure: Vec<(usize, u32, [f64; 2])> = if plan.has(Stage::Pressure) {
            model
                .pressures
                .iter()
                .enumerate()
                .flat_map(|(k, p)| p.nodes.iter().map(move |&(n, f)| (k, n, f)))
                .collect()
        } else {
            Vec::new()
        };
        let damping_v_old = if plan.has(Stage::MassDamping) {
            vec![[0.0; 2]; nn]
        } else {
            Vec::new()
        };
        let s = CpuState {
            clock: Clock::new(),
            u: vec![[0.0; 2]; nn],
            v: model.velocity.clone(),
            v_prev: vec![[0.0; 2]; nn],
            f: vec![[0.0; 2]; nn],
            dissipation,
            plastic: if model.has_plasticity() {
                vec![PlasticState::VIRGIN; ne]
            } else {
                Vec::new()
            },
            plastic_work: 0.0,
            contact: ContactSet::new(&model),
            contact_work: 0.0,
            contact_after: 0.0,
            friction_work: 0.0,
            friction_after: 0.0,
            hourglass_work: 0.0,
            bulk_work: 0.0,
            external_work: 0.0,
            pressure_impulse: vec![[0.0; 2]; pressure.len()],
            pressure_v_old: vec![[0.0; 2]; pressure.len()],
            pressure_work: 0.0,
            pressure_after: 0.0,
            damping_v_old,
            damping_work: 0.0,
            damping_after: 0.0,
            gravity_work: 0.0,
            gravity_after: 0.0,
            erosion: Erosion::new(&model, ne, plan.has(Stage::Failure)),
            t: 0.0,
            n: 0,
            dt_prev: 0.0,
            dt_first: 0.0,
            dt_range: (f64::INFINITY, 0.0),
            done: false,
        };
        Self {
            geometry: (0..model.element_count())
                .map(|e| model.geometry(e))
                .collect(),
            inv_mass: model.mass.iter().map(|m| 1.0 / m).collect(),
            pressure,
            model,
            plan,
            schedule,
            s,
            follows: (0, 0.0),
        }
    }

    /// The solver's changing state as bytes (a checkpoint; see [`CpuSolver::restore_state`]).
    ///
    /// # Errors
    /// [`crate::Error::Checkpoint`] if it cannot be encoded.
    pub fn save_state(&self) -> Result<Vec<u8>> {
        postcard::to_stdvec(&self.s)
            .map_err(|e| crate::Error::Checkpoint(format!("encoding the CPU state: {e}")))
    }

    /// Continues from a state saved by [`CpuSolver::save_state`] of a solver of the same model.
    ///
    /// # Errors
    /// [`crate::Error::Checkpoint`] if the bytes do not decode or do not fit this model.
    pub fn restore_state(&mut self, bytes: &[u8]) -> Result<()> {
        let s: CpuState = postcard::from_bytes(bytes)
            .map_err(|e| crate::Error::Checkpoint(format!("decoding the CPU state: {e}")))?;
        let (nn, ne) = (self.model.node_count(), self.model.element_count());
        let fits = s.u.len() == nn
            && s.v.len() == nn
            && s.v_prev.len() == nn
            && s.f.len() == nn
            && s.dissipation.len() == self.s.dissipation.len()
            && s.plastic.len() == self.s.plastic.len()
            && s.pressure_impulse.len() == self.pressure.len()
            && s.pressure_v_old.len() == self.pressure.len()
            && s.damping_v_old.len() == self.s.damping_v_old.len()
            && s.erosion.fits(&self.s.erosion)
            && s.contact.is_some() == self.s.contact.is_some()
            && (self.s.dissipation.is_empty() || self.s.dissipation.len() == ne);
        if !fits {
            return Err(crate::Error::Checkpoint(
                "the saved CPU state does not fit this scene's model (another mesh or plan)".into(),
            ));
        }
        self.s = s;
        Ok(())
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Displacements u_n.
    pub fn displacement(&self) -> &[[f64; 2]] {
        &self.s.u
    }

    /// Current half-step velocities.
    pub fn velocity(&self) -> &[[f64; 2]] {
        &self.s.v
    }

    /// Per element, whether it failed and eroded (empty for a model without failure): the
    /// surface that contact sees changes where one did.
    pub fn eroded(&self) -> &[bool] {
        &self.s.erosion.eroded
    }

    /// Elements eroded so far (a count that grows when elements erode during a batch).
    pub fn eroded_count(&self) -> u64 {
        self.s.erosion.count
    }

    /// Johnson-Cook damage of every element (empty without Johnson-Cook damage).
    pub fn damage(&self) -> &[f64] {
        &self.s.erosion.damage
    }

    /// The contact state, if the model has contact.
    pub fn contact(&self) -> Option<&ContactSet> {
        self.s.contact.as_ref()
    }

    /// The contact state, to choose its solver's options (see
    /// [`ContactSet::set_plain_sweeps`]), if the model has contact.
    pub fn contact_mut(&mut self) -> Option<&mut ContactSet> {
        self.s.contact.as_mut()
    }

    /// Takes `n` steps, discarding outputs (for benchmarks).
    pub fn run_steps(&mut self, n: u64) {
        let mut events = Vec::new();
        for _ in 0..n {
            if self.s.done {
                break;
            }
            self.step(&mut events);
            events.clear();
        }
    }

    /// Stable step of the current state (without the safety factor), and the element that sets it.
    pub fn stable_step(&self) -> (f64, usize) {
        let mut best = (f64::INFINITY, 0);
        for e in 0..self.model.element_count() {
            if self.s.erosion.is_eroded(e) {
                continue;
            }
            let out = self.evaluate(e, &Dissipation::default(), 0.0);
            if out.dt < best.0 {
                best = (out.dt, e);
            }
        }
        best
    }

    fn element_name(&self, e: usize) -> String {
        let b = &self.model.bodies[self.model.element_body[e] as usize];
        format!(
            "element {e} (body {:?}, local element {})",
            b.name,
            e - b.elements.start
        )
    }

    fn node_name(&self, i: usize) -> String {
        let b = self
            .model
            .bodies
            .iter()
            .find(|b| b.nodes.contains(&i))
            .map(|b| (b.name.as_str(), i - b.nodes.start))
            .unwrap_or(("?", i));
        format!("node {i} (body {:?}, local node {})", b.0, b.1)
    }

    fn fail(&mut self, events: &mut Vec<Event>, message: String) {
        self.s.done = true;
        events.push(Event::Failed(Failure {
            step: self.s.n,
            time: self.s.t,
            message,
        }));
    }

    fn step(&mut self, events: &mut Vec<Event>) {
        let s = self.schedule;
        let sample_due = self.s.clock.sample_due(&s, self.s.t, self.s.dt_prev);
        let snapshot_due = self.s.clock.snapshot_due(&s, self.s.t, self.s.dt_prev);
        let at_end = Clock::at_end(&s, self.s.t, self.s.dt_prev);

        // 1. Element stage.
        let eroded_before = self.s.erosion.count;
        let mut st = match self.element_stage(sample_due) {
            Ok(st) => st,
            Err(msg) => return self.fail(events, msg),
        };
        if self.s.erosion.count != eroded_before {
            // Eroding contact: the surfaces follow, and this step's contact searches again.
            if let Some(c) = self.s.contact.as_mut() {
                let t0 = std::time::Instant::now();
                c.follow_erosion(&self.model, &self.s.erosion.eroded);
                self.follows.0 += 1;
                self.follows.1 += t0.elapsed().as_secs_f64();
            }
        }
        if st.dt_min == f64::INFINITY && self.s.erosion.count > 0 && self.s.n > 0 {
            // Every element eroded: free masses, which keep the last step.
            st.dt_min = self.s.dt_prev / s.time_step_scale;
        }
        if !(st.dt_min.is_finite() && st.dt_min > 0.0) {
            let msg = format!(
                "stable step is {:e} at {}: the element is degenerate or its state is not finite",
                st.dt_min,
                self.element_name(st.dt_element)
            );
            return self.fail(events, msg);
        }
        // 2. The step dt^{n+1/2} (penalty springs shorten it).
        let dt_stable = match &self.s.contact {
            Some(c) => c.limit_step(st.dt_min),
            None => st.dt_min,
        };
        let dt_next = match s.time_step {
            Some(fixed) => {
                if fixed > dt_stable {
                    let by = match self.s.contact.as_ref().and_then(|c| c.penalty_step()) {
                        Some((_, what)) => format!(" and the penalty springs of {what}"),
                        None => String::new(),
                    };
                    let msg = format!(
                        "the fixed time_step {fixed:e} exceeds the stable step {dt_stable:e} of {}{by}",
                        self.element_name(st.dt_element)
                    );
                    return self.fail(events, msg);
                }
                fixed
            }
            None => s.time_step_scale * dt_stable,
        };
        if self.s.n == 0 {
            self.s.dt_first = dt_next;
        } else if dt_next < 1e-6 * self.s.dt_first {
            let msg = format!(
                "the stable step collapsed to {dt_next:e} (first step {:e}) at {}",
                self.s.dt_first,
                self.element_name(st.dt_element)
            );
            return self.fail(events, msg);
        }
        let dt_next = super::clip_to_end(dt_next, s.end_time - self.s.t, s.end_time, at_end);
        self.s.dt_range = (
            self.s.dt_range.0.min(dt_next),
            self.s.dt_range.1.max(dt_next),
        );
        // 3. Node stage.
        let dt_n = if self.s.n == 0 {
            0.5 * dt_next
        } else {
            0.5 * (self.s.dt_prev + dt_next)
        };
        let output = sample_due || snapshot_due;
        if output {
            self.s.v_prev.copy_from_slice(&self.s.v);
        }
        if let Some(c) = self.s.contact.as_mut() {
            c.keep_old_velocity(&self.s.v);
        }
        // The pressure impulses of the step: dt_n F_n (dt^{1/2} F_0 on the first step, where the
        // conserved form uses v^{-1/2} = 2 v_0 - v^{1/2}; see the output below), and v^{n-1/2}.
        let load_dt = if self.s.n == 0 { dt_next } else { dt_n };
        for (k, &(_, node, _)) in self.pressure.iter().enumerate() {
            let j = &mut self.s.pressure_impulse[k];
            *j = [load_dt * j[0], load_dt * j[1]];
            self.s.pressure_v_old[k] = self.s.v[node as usize];
        }
        // Gravity: the force m g on every node, and the momentum sum(m v^{n-1/2}) for its work.
        let gravity = self.plan.has(Stage::Gravity);
        let mut momentum_old = [0.0; 2];
        if gravity {
            let g = self.model.gravity_at(self.s.t);
            for (i, f) in self.s.f.iter_mut().enumerate() {
                let m = self.model.mass[i];
                f[0] += m * g[0];
                f[1] += m * g[1];
                momentum_old[0] += m * self.s.v[i][0];
                momentum_old[1] += m * self.s.v[i][1];
            }
        }
        let mut bad = None;
        // Mass damping (from the second step on: the first half step stays undamped so that the
        // start-up v^{-1/2} = 2 v_0 - v^{1/2} keeps its meaning), with the force at t_n taken as
        // -alpha m (v^{n-1/2} + v^{n+1/2}) / 2 of the final velocities:
        // (1 + c) m v+ = (1 - c) m v- + dt_n f + J (c = alpha dt_n / 2, J the boundary and contact
        // impulses), stable for any alpha >= 0. The constraints below therefore see the masses
        // (1 + c) m; the damping impulse -c m (v- + v+) and its work are summed at the end.
        let damped = !self.s.damping_v_old.is_empty() && self.s.n > 0;
        let damp_c = if damped {
            0.5 * self.model.mass_damping * dt_n
        } else {
            0.0
        };
        let mass_scale = 1.0 + damp_c;
        if damped {
            let (keep, scale) = ((1.0 - damp_c) / mass_scale, 1.0 / mass_scale);
            for i in 0..self.s.v.len() {
                let w = scale * dt_n * self.inv_mass[i];
                let v = &mut self.s.v[i];
                self.s.damping_v_old[i] = *v;
                v[0] = keep * v[0] + w * self.s.f[i][0];
                v[1] = keep * v[1] + w * self.s.f[i][1];
                if bad.is_none() && !(v[0].is_finite() && v[1].is_finite()) {
                    bad = Some(i);
                }
            }
        } else {
            for i in 0..self.s.v.len() {
                let w = dt_n * self.inv_mass[i];
                let v = &mut self.s.v[i];
                v[0] += w * self.s.f[i][0];
                v[1] += w * self.s.f[i][1];
                if bad.is_none() && !(v[0].is_finite() && v[1].is_finite()) {
                    bad = Some(i);
                }
            }
        }
        if let Some(i) = bad {
            let msg = format!(
                "velocity of {} is not finite (force {:?}): the run went unstable",
                self.node_name(i),
                self.s.f[i]
            );
            return self.fail(events, msg);
        }
        // Work of the reactions: the impulse j_n = m (v^{n+1/2} - v_free) does the work
        // j_n (v^{n-1/2} + v^{n+1/2}) / 2, half of it after t_n (shared with the interval that
        // follows, see `Sample::external`). v^{n+1/2} is the prescribed value at t_{n+1/2} (a
        // load curve's, or the constant), v^{n-1/2} the one at t_{n-1/2} (on the first step
        // 2 v_0 - v^{1/2}, as for every node): for a constant, val (j_0 + ... + j_n / 2).
        let mut step_work = 0.0;
        let mut reaction_after = 0.0;
        if self.plan.has(Stage::VelocityBoundaries) {
            let t_new = self.s.t + 0.5 * dt_next;
            let t_old = self.s.t - 0.5 * self.s.dt_prev;
            for c in &self.model.constraints {
                let i = c.node as usize;
                let m = mass_scale * self.model.mass[i];
                let new = c.velocity_at(&self.model.curves, t_new);
                let old = if self.s.n == 0 {
                    let v0 = c.velocity_at(&self.model.curves, self.s.t);
                    [0, 1].map(|k| Some(2.0 * v0[k]? - new[k]?))
                } else {
                    c.velocity_at(&self.model.curves, t_old)
                };
                // On the first step the update is a half step (v^{1/2} = v_0 + dt/2 a_0 + j / m),
                // so that M (v^{1/2} - v^{-1/2}) = dt f_0 + 2 j: the reaction's share is 2 j.
                let twice = if self.s.n == 0 { 2.0 } else { 1.0 };
                for k in 0..2 {
                    if let (Some(val), Some(before)) = (new[k], old[k]) {
                        let j = twice * m * (val - self.s.v[i][k]);
                        step_work += 0.5 * j * (before + val);
                        reaction_after += 0.5 * j * val;
                        self.s.v[i][k] = val;
                    }
                }
            }
            self.s.external_work += step_work;
        }
        if output && self.s.n == 0 {
            // v^{-1/2} = v_0 - dt_0 a_0 = 2 v_0 - v^{1/2} (of the uncoupled update: the contact
            // impulse of step 0 then enters M (v^{1/2} - v^{-1/2}) = dt f_0 + J_0 like any other).
            for (p, v) in self.s.v_prev.iter_mut().zip(&self.s.v) {
                *p = [2.0 * p[0] - v[0], 2.0 * p[1] - v[1]];
            }
        }
        if self.s.n == 0 {
            for (k, &(_, node, _)) in self.pressure.iter().enumerate() {
                let (o, v) = (&mut self.s.pressure_v_old[k], self.s.v[node as usize]);
                *o = [2.0 * o[0] - v[0], 2.0 * o[1] - v[1]];
            }
        }
        // CONTACT: correct the penetrating nodes of the uncoupled update.
        if let Some(c) = self.s.contact.as_mut() {
            if self.s.n == 0 {
                c.first_step_old_velocity(&self.s.v);
            }
            let w = c.apply(
                &self.model,
                &self.s.u,
                &mut self.s.v,
                dt_next,
                dt_n,
                mass_scale,
            );
            self.s.contact_work += w.work;
            self.s.contact_after = w.after;
            self.s.friction_work += w.friction;
            self.s.friction_after = w.friction_after;
        }
        // Work of the pressure and damping impulses, J (v^{n-1/2} + v^{n+1/2}) / 2 with the final
        // v^{n+1/2} (boundaries and contact applied), half of it after t_n.
        if !self.pressure.is_empty() {
            let (mut before, mut after) = (0.0, 0.0);
            for (k, &(_, node, _)) in self.pressure.iter().enumerate() {
                let (j, o, v) = (
                    self.s.pressure_impulse[k],
                    self.s.pressure_v_old[k],
                    self.s.v[node as usize],
                );
                before += 0.5 * (j[0] * o[0] + j[1] * o[1]);
                after += 0.5 * (j[0] * v[0] + j[1] * v[1]);
            }
            self.s.pressure_work += before + after;
            self.s.pressure_after = after;
        }
        if gravity {
            // The impulse dt_n m g on every node does the work dt_n g . sum m (v^{n-1/2} +
            // v^{n+1/2}) / 2 with the final v^{n+1/2}, half of it after t_n (on the first step
            // dt^{1/2} and v^{-1/2} = 2 v_0 - v^{1/2}, as for the pressure impulses).
            let mut momentum = [0.0; 2];
            for (v, m) in self.s.v.iter().zip(&self.model.mass) {
                momentum[0] += m * v[0];
                momentum[1] += m * v[1];
            }
            if self.s.n == 0 {
                momentum_old = [
                    2.0 * momentum_old[0] - momentum[0],
                    2.0 * momentum_old[1] - momentum[1],
                ];
            }
            let g = self.model.gravity_at(self.s.t);
            let before = 0.5 * load_dt * (g[0] * momentum_old[0] + g[1] * momentum_old[1]);
            let after = 0.5 * load_dt * (g[0] * momentum[0] + g[1] * momentum[1]);
            self.s.gravity_work += before + after;
            self.s.gravity_after = after;
        }
        if damped {
            let (mut before, mut after) = (0.0, 0.0);
            for ((o, v), m) in self
                .s
                .damping_v_old
                .iter()
                .zip(&self.s.v)
                .zip(&self.model.mass)
            {
                let j = [-damp_c * m * (o[0] + v[0]), -damp_c * m * (o[1] + v[1])];
                before += 0.5 * (j[0] * o[0] + j[1] * o[1]);
                after += 0.5 * (j[0] * v[0] + j[1] * v[1]);
            }
            self.s.damping_work += before + after;
            self.s.damping_after = after;
        }
        // 4. Output at t_n.
        if snapshot_due {
            events.push(Event::Snapshot(Snapshot {
                time: self.s.t,
                step: self.s.n,
                displacement: self.s.u.clone(),
                velocity: self
                    .s
                    .v_prev
                    .iter()
                    .zip(&self.s.v)
                    .map(|(a, b)| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])])
                    .collect(),
                plastic: self.s.plastic.clone(),
                eroded: self.s.erosion.eroded.clone(),
                damage: self.s.erosion.damage.clone(),
            }));
            self.s.clock.took_snapshot(&s, self.s.t, self.s.dt_prev);
        }
        if sample_due {
            let mut kinetic = 0.0;
            for i in 0..self.s.v.len() {
                let (a, b) = (self.s.v_prev[i], self.s.v[i]);
                kinetic += 0.5 * self.model.mass[i] * (a[0] * b[0] + a[1] * b[1]);
            }
            let body_velocity = self
                .model
                .bodies
                .iter()
                .map(|b| {
                    let mut p = [0.0; 2];
                    for i in b.nodes.clone() {
                        let m = self.model.mass[i];
                        p[0] += m * 0.5 * (self.s.v_prev[i][0] + self.s.v[i][0]);
                        p[1] += m * 0.5 * (self.s.v_prev[i][1] + self.s.v[i][1]);
                    }
                    [p[0] / b.mass, p[1] / b.mass]
                })
                .collect();
            events.push(Event::Sample(Sample {
                time: self.s.t,
                step: self.s.n,
                dt: dt_next,
                kinetic,
                internal: st.strain,
                hourglass: st.hourglass_stored + self.s.hourglass_work,
                viscous: self.s.bulk_work - (self.s.damping_work - self.s.damping_after),
                plastic: self.s.plastic_work,
                eroded_elements: self.s.erosion.count,
                eroded_energy: self.s.erosion.energy,
                external: self.s.external_work - reaction_after
                    + (self.s.pressure_work - self.s.pressure_after)
                    + (self.s.gravity_work - self.s.gravity_after),
                // The friction impulses' work apart: dissipated, its own column.
                contact: -(self.s.contact_work - self.s.contact_after)
                    + (self.s.friction_work - self.s.friction_after),
                friction: -(self.s.friction_work - self.s.friction_after),
                contacts: self
                    .s
                    .contact
                    .as_mut()
                    .map(|c| c.sample())
                    .unwrap_or_default(),
                body_velocity,
            }));
            self.s.clock.took_sample(&s, self.s.t, self.s.dt_prev);
        }
        if at_end {
            self.s.done = true;
            events.push(Event::Done);
            return;
        }
        // 5. Displacement update.
        for (u, v) in self.s.u.iter_mut().zip(&self.s.v) {
            u[0] += dt_next * v[0];
            u[1] += dt_next * v[1];
        }
        self.s.t += dt_next;
        self.s.dt_prev = dt_next;
        self.s.n += 1;
    }
}

impl Solver for CpuSolver {
    fn save_state(&mut self) -> Result<Vec<u8>> {
        CpuSolver::save_state(self)
    }

    fn restore_state(&mut self, state: &[u8]) -> Result<()> {
        CpuSolver::restore_state(self, state)
    }

    fn counters(&self) -> crate::step::Counters {
        let s = self
            .s
            .contact
            .as_ref()
            .map(|c| c.sweep_stats())
            .unwrap_or_default();
        crate::step::Counters {
            contact_searches: self.s.contact.as_ref().map_or(0, |c| c.searches()),
            contact_sweeps_mean: s.mean(),
            contact_sweeps_max: s.max,
            contact_unconverged: s.unconverged,
            contact_residual_max: s.residual_max,
            contact_penalty_bounded: self.s.contact.as_ref().map_or(0, |c| c.penalty_bounded()),
            eroded_elements: self.s.erosion.count,
            erosion_follows: self.follows.0,
            erosion_follow_seconds: self.follows.1,
            ..Default::default()
        }
    }

    fn advance(&mut self, events: &mut Vec<Event>) -> Result<()> {
        // Back to the driver at the first event, or after about ADVANCE_SECONDS without one, so
        // that progress, signals and checkpoints are seen between sparse history rows.
        let start = events.len();
        let t0 = std::time::Instant::now();
        let mut k = 0u32;
        while !self.s.done && events.len() == start {
            self.step(events);
            k = k.wrapping_add(1);
            if k.is_multiple_of(16) && t0.elapsed().as_secs_f64() > super::ADVANCE_SECONDS {
                break;
            }
        }
        Ok(())
    }

    fn finished(&self) -> bool {
        self.s.done
    }

    fn steps(&self) -> u64 {
        self.s.n
    }

    fn time(&self) -> f64 {
        self.s.t
    }

    fn dt_range(&self) -> (f64, f64) {
        self.s.dt_range
    }

    fn backend(&self) -> &'static str {
        "cpu"
    }

    fn adapter(&self) -> String {
        "CPU reference (f64, 1 thread)".to_string()
    }

    fn displacement_now(&mut self) -> Result<Vec<[f64; 2]>> {
        Ok(self.displacement().to_vec())
    }

    fn plastic_now(&mut self) -> Result<Vec<PlasticState>> {
        Ok(self.s.plastic.clone())
    }

    fn eroded_inverted_now(&mut self) -> Result<u64> {
        Ok(self.s.erosion.inverted)
    }

    fn eroded_small_step_now(&mut self) -> Result<u64> {
        Ok(self.s.erosion.small_step)
    }
}
