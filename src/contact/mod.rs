//! Contact: node-to-segment contact between bodies, within a body (self-contact) and with planar
//! rigid walls, enforced after the uncoupled update of all bodies (the CONTACT step of the
//! explicit flowchart, Belytschko X.6).
//!
//! One [`ContactSet`] holds every contact of a model, built on the bodies' boundary edges and
//! nodes ([`crate::model::surface`]); [`ContactSet::apply`] (here) runs the stages of a step in
//! order, each in its own file:
//!
//! - [`search`] (with the `parry2d` BVH in [`broad`]): candidate (slave node, master segment)
//!   pairs, inflated by a search margin and swept over the step; searched again only when some
//!   contact node has moved more than half the margin since the last search.
//! - [`narrow`]: which candidates may pair at all ([`rules::admissible`]: other bodies, or the
//!   same body with self-contact away from the node's own neighbourhood and far side), each
//!   slave node's penetrated segment (projection, selection, the corner rules), its parameter
//!   xi, normal and gap: the step's constraints. Its pure rules, shared with the GPU kernels,
//!   are in [`rules`].
//! - [`solve`]: the Lagrange correction (projected Gauss-Seidel sweeps with the diagonal mass,
//!   warm start, active-set re-check) and the bounded penalty impulse with its stable step.
//! - [`report`]: what the history records per `[[contact]]` table or wall.
//! - [`overlap`]: nodes behind a surface at t = 0, moved onto it before the run.
//! - [`erosion`]: the surfaces following eroded elements (exposed edges join, eroded ones leave,
//!   free nodes stay slaves), and how the GPU should mirror it.
//! - [`tables`]: the same contact set as flat tables for the GPU kernel.
//!
//! Passes: a contact between two bodies has one pass per direction (slave nodes of one body
//! against master segments of the other; two unless `two_pass = false`). A group (`bodies =
//! "all"`, three or more bodies, or `self_contact`) is one symmetric pass: all its bodies' surface
//! nodes against all their surface segments, each tagged with its body.
//!
//! The work the contact impulses do is accounted for in the conserved form of the energy audit:
//! an impulse J_n at step n does the work J_n (v^{n-1/2} + v^{n+1/2}) / 2, half of it after t_n.

pub mod broad;
mod build;
pub mod erosion;
pub mod narrow;
pub mod overlap;
pub mod report;
pub mod rules;
pub mod search;
pub mod solve;
pub mod tables;

use crate::model::Model;
use crate::scene::ContactMethod;

pub use report::ContactSample;
pub use solve::{
    extrapolation, penalty_impulse, SweepStats, ACTIVE_SET_ROUNDS, EXTRAPOLATION, MAX_SWEEPS,
    SWEEP_TOLERANCE,
};
pub use tables::{SegmentTable, SlotTable, Tables};

use report::Interface;

/// One pass: slave nodes against master segments, of two bodies or of a group.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Pass {
    interface: usize,
    method: ContactMethod,
    /// A pair: whether the slave body is the interface's first body.
    slave_is_first: bool,
    /// Whether each node pair is met from both sides (a two-pass contact or a group): each
    /// direction carries half the stiffness, and both springs act on a node.
    two_pass: bool,
    /// A group: the impulse's sign follows the bodies' order, per constraint.
    group: bool,
    /// A group that admits a body's nodes against its own segments.
    self_contact: bool,
    /// Slave nodes (local indices).
    slaves: Vec<u32>,
    /// Each slave node's body.
    slave_body: Vec<u32>,
    /// Each slave node's neighbours along its own surface (previous, next; local indices): its
    /// outward normal is the perpendicular of next - previous.
    neighbours: Vec<[u32; 2]>,
    /// The same neighbours as positions in `slaves` (`u32::MAX`: none, or not a slave of the
    /// pass): the perturbed Lagrangian reads their gaps.
    #[serde(default)]
    neighbour_slaves: Vec<[u32; 2]>,
    /// Master segments (local node indices a -> b).
    segments: Vec<[u32; 2]>,
    /// Each segment's body.
    segment_body: Vec<u32>,
    /// Penalty stiffness of each segment.
    stiffness: Vec<f64>,
    /// The interface's contact law.
    law: Law,
    /// Admissible candidate (position in `slaves`, segment) pairs from the last search, sorted.
    candidates: Vec<(u32, u32)>,
}

impl Pass {
    /// Fills `neighbour_slaves` from `neighbours`.
    fn link_neighbours(&mut self) {
        let at: std::collections::HashMap<u32, u32> = self
            .slaves
            .iter()
            .enumerate()
            .map(|(i, &s)| (s, i as u32))
            .collect();
        self.neighbour_slaves = self
            .neighbours
            .iter()
            .zip(&self.slaves)
            .map(|(nb, &s)| {
                nb.map(|j| {
                    if j == s {
                        u32::MAX
                    } else {
                        at.get(&j).copied().unwrap_or(u32::MAX)
                    }
                })
            })
            .collect();
    }

    /// Sign of the impulse on the interface's first body for slave `si` against segment `j`:
    /// in a pair, by direction; in a group, +1 when the slave's body comes first, -1 when the
    /// segment's does, 0 within one body (self-contact exerts no net force).
    fn sign(&self, si: usize, j: usize) -> f64 {
        if self.group {
            match self.slave_body[si].cmp(&self.segment_body[j]) {
                std::cmp::Ordering::Less => 1.0,
                std::cmp::Ordering::Greater => -1.0,
                std::cmp::Ordering::Equal => 0.0,
            }
        } else if self.slave_is_first {
            1.0
        } else {
            -1.0
        }
    }
}

/// A rigid wall.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Wall {
    interface: usize,
    method: ContactMethod,
    point: [f64; 2],
    normal: [f64; 2],
    /// Nodes (local indices).
    nodes: Vec<u32>,
    /// Each node's body.
    body: Vec<u32>,
    /// Each node's neighbours along its own surface (previous, next; local indices): the
    /// perturbed Lagrangian interpolates the penetration along them.
    #[serde(default)]
    neighbours: Vec<[u32; 2]>,
    /// Penalty stiffness of each node.
    stiffness: Vec<f64>,
    /// The wall's contact law.
    law: Law,
}

/// The contact law of an interface (a `[[contact]]` table's passes, or a wall) besides its method
/// and penalty stiffness: friction, and the penalty's form and augmentation.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
struct Law {
    /// Coulomb friction coefficient.
    #[serde(default)]
    friction: f64,
    /// Penalty friction: the tangential spring over the normal one.
    #[serde(default = "one")]
    friction_stiffness: f64,
    /// Penalty in the mass form (k = s m* / dt^2): outside the stable step.
    #[serde(default)]
    mass_form: bool,
    /// Augmented Lagrangian: the multipliers' update rate (1/s; 0 for the other methods).
    #[serde(default)]
    augmentation: f64,
}

fn one() -> f64 {
    1.0
}

/// An active constraint of the step.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
struct Constraint {
    interface: u32,
    s: u32,
    /// Master nodes, `u32::MAX` for a wall.
    a: u32,
    b: u32,
    xi: f64,
    n: [f64; 2],
    /// Gap at u_{n+1} from the velocities before this constraint's impulse.
    g0: f64,
    /// dt (1/m_s + (1-xi)^2/m_a + xi^2/m_b) along n; negative (and the impulse in `lambda`) for
    /// a penalty constraint.
    w: f64,
    lambda: f64,
    /// Impulse on the first body = sign * lambda * n.
    sign: f64,
    /// Penetration reported for it.
    penetration: f64,
    /// Coulomb coefficient (0: frictionless).
    #[serde(default)]
    mu: f64,
    /// (1/m_s + (1-xi)^2/m_a + xi^2/m_b) along the tangent t = (-n_y, n_x): the relative
    /// tangential velocity change per unit tangential impulse.
    #[serde(default)]
    wt: f64,
    /// Tangential (friction) impulse along t, |lt| <= mu lambda.
    #[serde(default)]
    lt: f64,
}

impl Constraint {
    /// The tangent t = (-n_y, n_x) of the friction impulse.
    #[inline]
    fn tangent(&self) -> [f64; 2] {
        [-self.n[1], self.n[0]]
    }
}

/// Result of the contact step.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepWork {
    /// Work of the step's contact impulses, J (v^{n-1/2} + v^{n+1/2}) / 2 (friction included).
    pub work: f64,
    /// The part of it after t_n, J v^{n+1/2} / 2.
    pub after: f64,
    /// The friction impulses' share of `work` (<= 0: friction dissipates).
    pub friction: f64,
    /// Its part after t_n.
    pub friction_after: f64,
}

/// Contact state of a model on the CPU.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ContactSet {
    /// What the erosion rebuilds reuse (each erodible body's candidate edges and surface as
    /// meshed; filled at the first rebuild, not saved in checkpoints).
    #[serde(skip)]
    surfaces: build::Cache,
    interfaces: Vec<Interface>,
    passes: Vec<Pass>,
    walls: Vec<Wall>,
    /// Global index of each local contact node.
    nodes: Vec<u32>,
    /// Reference (undeformed) position of each local node.
    reference: Vec<[f64; 2]>,
    /// Whether each local node lies on the axis of an axisymmetric body (empty: none does; see
    /// [`rules::project`]).
    #[serde(default)]
    axis: Vec<bool>,
    /// Inverse mass per local node and direction (0 on a velocity-constrained direction).
    inv_mass: Vec<[f64; 2]>,
    mass: Vec<f64>,
    /// 1 / the factor on the masses of the step's velocity update (1 without damping).
    inv_mass_scale: f64,
    /// The Lagrange multipliers of the last step by constraint (interface, slave node), sorted,
    /// and that step's dt_n: the next step's projected Gauss-Seidel starts from them.
    warm: Vec<([u32; 2], f64)>,
    warm_dt: f64,
    /// The force each spring constraint (interface, slave node) carries from the last step,
    /// sorted: penalty friction's tangential spring force (Curnier-Mroz: its elastic stick), or
    /// the augmented Lagrangian's multiplier (which has no friction).
    #[serde(default)]
    pen_ft: Vec<([u32; 2], f64)>,
    /// Scratch: this step's, to become `pen_ft`.
    #[serde(default)]
    pen_ft_next: Vec<([u32; 2], f64)>,
    /// v^{n-1/2} of the local nodes.
    v_old: Vec<[f64; 2]>,
    /// Positions at the last search.
    x_ref: Vec<[f64; 2]>,
    searched: bool,
    margin: f64,
    searches: u64,
    sweep_stats: solve::SweepStats,
    penalty_step: Option<(f64, String)>,
    /// Penalty impulses bounded by the perfectly plastic impulse so far (constraint-steps; see
    /// [`penalty_impulse`]).
    #[serde(default)]
    penalty_bounded: u64,
    // Scratch.
    x_n: Vec<[f64; 2]>,
    x_tr: Vec<[f64; 2]>,
    /// Corrected positions x_tr + dt dv of an active-set re-check (scratch).
    x_c: Vec<[f64; 2]>,
    /// Constrained (interface, node) keys of a re-check (scratch).
    done: Vec<[u32; 2]>,
    /// The step's dt (set by `apply`).
    dt: f64,
    v_free: Vec<[f64; 2]>,
    dv: Vec<[f64; 2]>,
    /// The friction impulses' share of `dv` (scratch; empty without friction).
    #[serde(default)]
    dvt: Vec<[f64; 2]>,
    cons: Vec<Constraint>,
    /// Plain projected Gauss-Seidel, without the sweeps' extrapolation (see
    /// [`extrapolation`]); for comparisons.
    #[serde(default)]
    plain_sweeps: bool,
    /// Scratch of the extrapolated sweeps: each Lagrange constraint's (lambda, lt) and each of
    /// their nodes' (dv, dvt) after the last sweep, the nodes, and a mark per local node.
    #[serde(skip)]
    last_lambda: Vec<[f64; 2]>,
    #[serde(skip)]
    last_dv: Vec<[[f64; 2]; 2]>,
    #[serde(skip)]
    touched: Vec<u32>,
    #[serde(skip)]
    mark: Vec<bool>,
    /// Scratch of the sweeps: each constraint's partner in a 2 x 2 block (`u32::MAX`: none),
    /// and the (slave node, constraint) pairs that find them.
    #[serde(skip)]
    partner: Vec<u32>,
    #[serde(skip)]
    by_slave: Vec<(u32, u32)>,
    /// Scratch of the pairing: (coupling, constraint, constraint) candidates.
    #[serde(skip)]
    pairs: Vec<(f64, u32, u32)>,
}

impl ContactSet {
    /// Whether the local nodes `ends` lie on the axis of an axisymmetric body.
    pub(super) fn on_axis(&self, ends: [u32; 2]) -> [bool; 2] {
        ends.map(|n| self.axis.get(n as usize) == Some(&true))
    }

    /// Names of the contacts and walls, in history-column order.
    pub fn names(&self) -> Vec<String> {
        self.interfaces.iter().map(|i| i.name.clone()).collect()
    }

    /// Plain projected Gauss-Seidel sweeps (`true`), or extrapolated ones (the default; see
    /// [`extrapolation`]).
    pub fn set_plain_sweeps(&mut self, plain: bool) {
        self.plain_sweeps = plain;
    }

    /// Search margin (half the shortest segment).
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// Broad-phase searches so far.
    pub fn searches(&self) -> u64 {
        self.searches
    }

    /// Penalty impulses bounded so far (constraint-steps with a spring too stiff for the step;
    /// see [`penalty_impulse`]).
    pub fn penalty_bounded(&self) -> u64 {
        self.penalty_bounded
    }

    /// The Lagrange sweeps so far.
    pub fn sweep_stats(&self) -> solve::SweepStats {
        self.sweep_stats
    }

    /// Keeps v^{n-1/2} of the contact nodes (call before the node update).
    pub fn keep_old_velocity(&mut self, v: &[[f64; 2]]) {
        for (o, &g) in self.v_old.iter_mut().zip(&self.nodes) {
            *o = v[g as usize];
        }
    }

    /// On the first step v^{-1/2} = 2 v_0 - v^{1/2}: call after the node update and boundaries.
    pub fn first_step_old_velocity(&mut self, v: &[[f64; 2]]) {
        for (o, &g) in self.v_old.iter_mut().zip(&self.nodes) {
            let w = v[g as usize];
            *o = [2.0 * o[0] - w[0], 2.0 * o[1] - w[1]];
        }
    }

    /// Positions at u_n and at the free update's end, and the free velocities.
    fn positions(&mut self, model: &Model, u: &[[f64; 2]], v: &[[f64; 2]], dt: f64) {
        for (l, &g) in self.nodes.iter().enumerate() {
            let g = g as usize;
            let p = model.position[g];
            let x = [p[0] + u[g][0], p[1] + u[g][1]];
            self.x_n[l] = x;
            self.v_free[l] = v[g];
            self.x_tr[l] = [x[0] + dt * v[g][0], x[1] + dt * v[g][1]];
        }
    }

    /// The CONTACT step: after the uncoupled update (v = v^{n+1/2} of the free bodies, boundaries
    /// applied), corrects the velocities of penetrating nodes so that u_{n+1} = u_n + dt v^{n+1/2}
    /// satisfies the constraints (Lagrange), or applies the bounded penalty impulses.
    /// `dt` is dt^{n+1/2}, `dt_n` the step of the velocity update; `mass_scale` multiplies every
    /// mass in the update (1 + alpha dt_n / 2 with mass damping, whose force -alpha m v^n then
    /// takes its share of each correction, so that the impulses reported are the contact's own).
    pub fn apply(
        &mut self,
        model: &Model,
        u: &[[f64; 2]],
        v: &mut [[f64; 2]],
        dt: f64,
        dt_n: f64,
        mass_scale: f64,
    ) -> StepWork {
        self.inv_mass_scale = 1.0 / mass_scale;
        self.positions(model, u, v, dt);
        // Search (search.rs).
        if self.search_due() {
            self.search();
        }
        // Narrow phase: the step's constraints (narrow.rs).
        self.cons.clear();
        for d in &mut self.dv {
            *d = [0.0; 2];
        }
        for d in &mut self.dvt {
            *d = [0.0; 2];
        }
        self.dt = dt;
        self.collect_passes(dt, dt_n, None);
        self.collect_walls(dt, dt_n, None);
        // Penalty impulses and the Lagrange correction (solve.rs).
        self.solve(dt, dt_n);
        // History (report.rs).
        self.record(dt, dt_n);
        // Velocities and the work of the impulses (free directions only: on a constrained one the
        // boundary absorbs the impulse and its reaction cancels it).
        let mut work = StepWork::default();
        for (l, &g) in self.nodes.iter().enumerate() {
            let d = self.dv[l];
            if d == [0.0; 2] {
                continue;
            }
            let g = g as usize;
            let m = self.mass[l] / self.inv_mass_scale;
            let dt_part = self.dvt.get(l).copied().unwrap_or([0.0; 2]);
            for k in 0..2 {
                let vn = v[g][k] + d[k];
                let j = m * d[k];
                work.work += 0.5 * j * (self.v_old[l][k] + vn);
                work.after += 0.5 * j * vn;
                let jt = m * dt_part[k];
                work.friction += 0.5 * jt * (self.v_old[l][k] + vn);
                work.friction_after += 0.5 * jt * vn;
                v[g][k] = vn;
            }
        }
        work
    }
}

/// Identifies a constraint from one step to the next: its interface and slave node (a slave has
/// at most one constraint per interface and pass, the two passes of a pair have different
/// slaves, and a group has one pass). Not the segment: a node resting on a master node may
/// switch between the two segments that share it from one step to the next, and its multiplier
/// carries over.
#[inline]
fn warm_key(c: &Constraint) -> [u32; 2] {
    [c.interface, c.s]
}

#[inline]
fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

#[inline]
fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

#[inline]
fn dist2(a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}
