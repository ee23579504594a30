//! Contact: node-to-segment contact between bodies and planar rigid walls, enforced after the
//! uncoupled update of all bodies (the CONTACT step of the explicit flowchart, Belytschko X.6).
//!
//! - Surfaces ([`surface`]): boundary edges of each body with outward normals, and boundary nodes.
//! - Broad phase ([`broad`]): a `parry2d` BVH over the master segments, inflated by a search margin;
//!   searched again only when some contact node has moved more than half the margin since the last
//!   search (swept: the boxes cover the node's whole path over the step).
//! - Narrow phase ([`narrow`]): each slave node's penetrated candidate segment, its parameter xi,
//!   normal and gap.
//! - Lagrange multipliers with the diagonal mass: an impulse lambda >= 0 per active constraint closes
//!   the gap at u_{n+1} exactly (the plastic-impact velocity correction); constraints coupled through
//!   shared nodes are solved by projected Gauss-Seidel sweeps in a fixed order.
//! - Penalty: p = k (-g) at u_n, k = s K t L^2 / A, the impulse bounded by the perfectly plastic
//!   one, and the stable step reduced for the springs.
//!
//! The work the contact impulses do is accounted for in the conserved form of the energy audit:
//! an impulse J_n at step n does the work J_n (v^{n-1/2} + v^{n+1/2}) / 2, half of it after t_n.

pub mod broad;
pub mod narrow;
pub mod surface;

use crate::model::Model;
use crate::scene::ContactMethod;

use narrow::{penetrates, project};
use surface::{Segment, Surface};

/// Projected Gauss-Seidel sweeps at most per step.
pub const MAX_SWEEPS: usize = 500;
/// Sweeps stop when no gap changes by more than this fraction of the search margin.
pub const SWEEP_TOLERANCE: f64 = 1e-13;
/// Rounds of the Lagrange active-set update per step (re-checks of the free nodes at the
/// corrected positions, each followed by sweeps when it adds constraints).
pub const ACTIVE_SET_ROUNDS: usize = 4;

/// What a contact or wall reports at a history sample.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactSample {
    /// Contact force on the first body (or on the wall's bodies), averaged over the interval since
    /// the previous sample.
    pub force: [f64; 2],
    /// Largest penetration at the sample step (after the correction, for Lagrange).
    pub max_penetration: f64,
    /// Slave nodes with a non-zero impulse at the sample step.
    pub active_nodes: u32,
}

/// A contact or wall as the history sees it.
#[derive(Debug, Clone)]
struct Interface {
    name: String,
    /// Impulse on the first body since the last sample.
    impulse: [f64; 2],
    /// Impulse on the first body at the last step.
    step_impulse: [f64; 2],
    /// Force-weighting time since the last sample.
    elapsed: f64,
    active: u32,
    max_penetration: f64,
}

/// One pass: slave nodes of one body against master segments of another.
#[derive(Debug, Clone)]
struct Pass {
    interface: usize,
    method: ContactMethod,
    /// Whether the slave body is the interface's first body.
    slave_is_first: bool,
    /// Slave and master bodies.
    bodies: [u32; 2],
    /// Whether the contact has the reverse pass too.
    two_pass: bool,
    /// Slave nodes (local indices).
    slaves: Vec<u32>,
    /// Each slave node's neighbours along its own surface (previous, next; local indices): its
    /// outward normal is the perpendicular of next - previous.
    neighbours: Vec<[u32; 2]>,
    /// Master segments (local node indices a -> b).
    segments: Vec<[u32; 2]>,
    /// Penalty stiffness of each segment.
    stiffness: Vec<f64>,
    /// Candidate (position in `slaves`, segment) pairs from the last search, sorted.
    candidates: Vec<(u32, u32)>,
}

/// A rigid wall.
#[derive(Debug, Clone)]
struct Wall {
    interface: usize,
    method: ContactMethod,
    point: [f64; 2],
    normal: [f64; 2],
    /// Nodes (local indices).
    nodes: Vec<u32>,
    /// Penalty stiffness of each node.
    stiffness: Vec<f64>,
}

/// An active constraint of the step.
#[derive(Debug, Clone, Copy)]
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
    /// dt (1/m_s + (1-xi)^2/m_a + xi^2/m_b) along n.
    w: f64,
    lambda: f64,
    /// Impulse on the first body = sign * lambda * n.
    sign: f64,
    /// Penetration reported for it.
    penetration: f64,
}

/// A slave node behind a master surface or a wall at t = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Overlap {
    /// Contact or wall name.
    pub interface: String,
    /// Global node index.
    pub node: u32,
    /// Penetration depth (m).
    pub depth: f64,
    /// Unit normal of the surface it is behind (moving the node by `depth` along it removes it).
    pub normal: [f64; 2],
    /// The contact pass that found it (`None` for a wall).
    pub pass: Option<usize>,
}

/// Result of the contact step.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepWork {
    /// Work of the step's contact impulses, J (v^{n-1/2} + v^{n+1/2}) / 2.
    pub work: f64,
    /// The part of it after t_n, J v^{n+1/2} / 2.
    pub after: f64,
}

/// Contact state of a model on the CPU.
#[derive(Debug, Clone)]
pub struct ContactSet {
    interfaces: Vec<Interface>,
    passes: Vec<Pass>,
    walls: Vec<Wall>,
    /// Global index of each local contact node.
    nodes: Vec<u32>,
    /// Inverse mass per local node and direction (0 on a velocity-constrained direction).
    inv_mass: Vec<[f64; 2]>,
    mass: Vec<f64>,
    /// 1 / the factor on the masses of the step's velocity update (1 without damping).
    inv_mass_scale: f64,
    /// The Lagrange multipliers of the last step by constraint (interface, slave node), sorted,
    /// and that step's dt_n: the next step's projected Gauss-Seidel starts from them.
    warm: Vec<([u32; 2], f64)>,
    warm_dt: f64,
    /// v^{n-1/2} of the local nodes.
    v_old: Vec<[f64; 2]>,
    /// Positions at the last search.
    x_ref: Vec<[f64; 2]>,
    searched: bool,
    margin: f64,
    searches: u64,
    penalty_step: Option<(f64, String)>,
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
    cons: Vec<Constraint>,
}

/// 2D bulk modulus used by the penalty stiffness: lambda (of the formulation) + mu.
fn bulk_modulus(model: &Model, body: usize) -> f64 {
    let p = &model.bodies[body].params;
    p.lambda_plane + p.mu
}

fn element_area(model: &Model, e: u32) -> f64 {
    crate::step::element::quad_geometry(&model.corners[e as usize]).area
}

impl ContactSet {
    /// The contact state of `scene`'s model; `None` when the scene has no contact or wall.
    pub fn new(model: &Model) -> Option<ContactSet> {
        if !model.has_contact() {
            return None;
        }
        let nb = model.bodies.len();
        let mut surfaces: Vec<Option<Surface>> = vec![None; nb];
        let mut surface = |b: usize| -> Surface {
            surfaces[b]
                .get_or_insert_with(|| Surface::of_body(model, b))
                .clone()
        };
        let mut local = vec![u32::MAX; model.node_count()];
        let mut nodes: Vec<u32> = Vec::new();
        let mut add = |g: u32, nodes: &mut Vec<u32>| -> u32 {
            if local[g as usize] == u32::MAX {
                local[g as usize] = nodes.len() as u32;
                nodes.push(g);
            }
            local[g as usize]
        };
        let mut interfaces = Vec::new();
        let mut passes = Vec::new();
        let mut walls = Vec::new();
        let mut min_length = f64::INFINITY;
        for c in &model.contacts {
            let iface = interfaces.len();
            interfaces.push(Interface::new(&c.name));
            let mut dirs = vec![(c.bodies[0], c.bodies[1], true)];
            if c.two_pass {
                dirs.push((c.bodies[1], c.bodies[0], false));
            }
            // Two passes act on the same node pairs: each carries half the interface stiffness.
            let share = if c.two_pass { 0.5 } else { 1.0 };
            for (slave, master, slave_is_first) in dirs {
                let ss = surface(slave);
                let ms = surface(master);
                let k_body = bulk_modulus(model, master) * model.bodies[master].params.thickness;
                let mut segments = Vec::new();
                let mut stiffness = Vec::new();
                for s in &ms.segments {
                    let l = surface::length(model, s);
                    min_length = min_length.min(l);
                    stiffness.push(
                        share * c.penalty_scale * k_body * l * l / element_area(model, s.element),
                    );
                    segments.push(s.nodes.map(|g| add(g, &mut nodes)));
                }
                let mut prev = std::collections::BTreeMap::new();
                let mut next = std::collections::BTreeMap::new();
                for seg in &ss.segments {
                    next.insert(seg.nodes[0], seg.nodes[1]);
                    prev.insert(seg.nodes[1], seg.nodes[0]);
                }
                let slaves: Vec<u32> = ss.nodes.iter().map(|&g| add(g, &mut nodes)).collect();
                let neighbours = ss
                    .nodes
                    .iter()
                    .map(|g| {
                        let p = prev.get(g).copied().unwrap_or(*g);
                        let n = next.get(g).copied().unwrap_or(*g);
                        [add(p, &mut nodes), add(n, &mut nodes)]
                    })
                    .collect();
                passes.push(Pass {
                    interface: iface,
                    method: c.method,
                    slave_is_first,
                    bodies: [slave as u32, master as u32],
                    two_pass: c.two_pass,
                    slaves,
                    neighbours,
                    segments,
                    stiffness,
                    candidates: Vec::new(),
                });
            }
        }
        for w in &model.walls {
            let iface = interfaces.len();
            interfaces.push(Interface::new(&w.name));
            let mut wn = Vec::new();
            let mut stiffness = Vec::new();
            for &b in &w.bodies {
                let s = surface(b);
                let k_body = bulk_modulus(model, b) * model.bodies[b].params.thickness;
                for &g in &s.nodes {
                    // The node's stiffest adjacent boundary segment.
                    let k = s
                        .segments
                        .iter()
                        .filter(|seg| seg.nodes.contains(&g))
                        .map(|seg: &Segment| {
                            let l = surface::length(model, seg);
                            min_length = min_length.min(l);
                            l * l / element_area(model, seg.element)
                        })
                        .fold(0.0f64, f64::max);
                    wn.push(add(g, &mut nodes));
                    stiffness.push(w.penalty_scale * k_body * k);
                }
            }
            walls.push(Wall {
                interface: iface,
                method: w.method,
                point: w.point,
                normal: w.normal,
                nodes: wn,
                stiffness,
            });
        }
        let mut constrained = vec![[false; 2]; model.node_count()];
        for c in &model.constraints {
            constrained[c.node as usize] = [c.vx.is_some(), c.vy.is_some()];
        }
        let mass: Vec<f64> = nodes.iter().map(|&g| model.mass[g as usize]).collect();
        let inv_mass = nodes
            .iter()
            .zip(&mass)
            .map(|(&g, m)| constrained[g as usize].map(|c| if c { 0.0 } else { 1.0 / m }))
            .collect();
        let mut set = ContactSet {
            interfaces,
            passes,
            walls,
            inv_mass,
            mass,
            inv_mass_scale: 1.0,
            warm: Vec::new(),
            warm_dt: 0.0,
            v_old: vec![[0.0; 2]; nodes.len()],
            x_ref: vec![[0.0; 2]; nodes.len()],
            x_n: vec![[0.0; 2]; nodes.len()],
            x_tr: vec![[0.0; 2]; nodes.len()],
            x_c: vec![[0.0; 2]; nodes.len()],
            done: Vec::new(),
            dt: 0.0,
            v_free: vec![[0.0; 2]; nodes.len()],
            dv: vec![[0.0; 2]; nodes.len()],
            nodes,
            searched: false,
            margin: if min_length.is_finite() {
                0.5 * min_length
            } else {
                0.0
            },
            searches: 0,
            penalty_step: None,
            cons: Vec::new(),
        };
        set.penalty_step = set.compute_penalty_step();
        Some(set)
    }

    /// Slots of the GPU tables: every pass's slave nodes and every wall's nodes.
    pub fn slot_count(&self) -> usize {
        self.passes.iter().map(|p| p.slaves.len()).sum::<usize>()
            + self.walls.iter().map(|w| w.nodes.len()).sum::<usize>()
    }

    /// Names of the contacts and walls, in history-column order.
    pub fn names(&self) -> Vec<String> {
        self.interfaces.iter().map(|i| i.name.clone()).collect()
    }

    /// Search margin (half the shortest segment).
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// Broad-phase searches so far.
    pub fn searches(&self) -> u64 {
        self.searches
    }

    /// The stable step the penalty springs alone allow, 2 / omega with
    /// omega^2 = k (1/m_slave + 1/m_master), and what sets it; `None` without penalty contact.
    pub fn penalty_step(&self) -> Option<(f64, &str)> {
        self.penalty_step.as_ref().map(|(d, s)| (*d, s.as_str()))
    }

    fn compute_penalty_step(&self) -> Option<(f64, String)> {
        let mut best: Option<(f64, String)> = None;
        let mut consider = |omega2: f64, name: &str| {
            if omega2 > 0.0 {
                let dt = 2.0 / omega2.sqrt();
                if best.as_ref().is_none_or(|b| dt < b.0) {
                    best = Some((dt, name.to_string()));
                }
            }
        };
        for p in self
            .passes
            .iter()
            .filter(|p| p.method == ContactMethod::Penalty)
        {
            let ms = p
                .slaves
                .iter()
                .map(|&l| self.mass[l as usize])
                .fold(f64::INFINITY, f64::min);
            let mm = p
                .segments
                .iter()
                .flatten()
                .map(|&l| self.mass[l as usize])
                .fold(f64::INFINITY, f64::min);
            // A node of a two-pass contact is slave in one pass and master in the other: both
            // springs act on it.
            let passes = if p.two_pass { 2.0 } else { 1.0 };
            let k = passes * p.stiffness.iter().copied().fold(0.0f64, f64::max);
            consider(
                k * (1.0 / ms + 1.0 / mm),
                &format!("contact {:?}", self.interfaces[p.interface].name),
            );
        }
        for w in self
            .walls
            .iter()
            .filter(|w| w.method == ContactMethod::Penalty)
        {
            let omega2 = w
                .nodes
                .iter()
                .zip(&w.stiffness)
                .map(|(&l, k)| k / self.mass[l as usize])
                .fold(0.0f64, f64::max);
            consider(
                omega2,
                &format!("rigid wall {:?}", self.interfaces[w.interface].name),
            );
        }
        best
    }

    /// Combines the element stable step with the penalty springs':
    /// 1 / dt^2 = 1 / dt_element^2 + 1 / dt_penalty^2 (dt0 / sqrt(1 + k_p / k_e) for a node on a mesh).
    pub fn limit_step(&self, dt_element: f64) -> f64 {
        match self.penalty_step {
            Some((dp, _)) => 1.0 / (1.0 / (dt_element * dt_element) + 1.0 / (dp * dp)).sqrt(),
            None => dt_element,
        }
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

    /// Slave nodes that penetrate a master segment or a wall in the reference configuration.
    pub fn initial_overlaps(&mut self, model: &Model) -> Vec<Overlap> {
        let u = vec![[0.0; 2]; model.node_count()];
        let v = u.clone();
        self.positions(model, &u, &v, 0.0);
        self.search();
        let mut out = Vec::new();
        for (pi, p) in self.passes.iter().enumerate() {
            let mut k = 0;
            while k < p.candidates.len() {
                let si = p.candidates[k].0;
                let s = p.slaves[si as usize];
                // The closest surface the node is behind.
                let mut worst: Option<(f64, [f64; 2])> = None;
                while k < p.candidates.len() && p.candidates[k].0 == si {
                    let [a, b] = p.segments[p.candidates[k].1 as usize];
                    let x = &self.x_n;
                    if let Some(pr) = project(x[s as usize], x[a as usize], x[b as usize]) {
                        if pr.gap < 0.0
                            && pr.gap > -0.5 * pr.length
                            && worst.is_none_or(|w| pr.gap > w.0)
                        {
                            worst = Some((pr.gap, pr.normal));
                        }
                    }
                    k += 1;
                }
                if let Some((g, normal)) = worst {
                    out.push(Overlap {
                        interface: self.interfaces[p.interface].name.clone(),
                        node: self.nodes[s as usize],
                        depth: -g,
                        normal,
                        pass: Some(pi),
                    });
                }
            }
        }
        for w in &self.walls {
            for &l in &w.nodes {
                let g = dot(sub(self.x_n[l as usize], w.point), w.normal);
                if g < 0.0 {
                    out.push(Overlap {
                        interface: self.interfaces[w.interface].name.clone(),
                        node: self.nodes[l as usize],
                        depth: -g,
                        normal: w.normal,
                        pass: None,
                    });
                }
            }
        }
        self.searched = false;
        out
    }

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

    fn search_due(&self) -> bool {
        if !self.searched {
            return true;
        }
        let h2 = 0.25 * self.margin * self.margin;
        self.x_ref
            .iter()
            .zip(self.x_n.iter().zip(&self.x_tr))
            .any(|(r, (a, b))| dist2(*r, *a) > h2 || dist2(*r, *b) > h2)
    }

    fn search(&mut self) {
        for p in &mut self.passes {
            p.candidates =
                broad::candidates(&p.slaves, &p.segments, &self.x_n, &self.x_tr, self.margin);
        }
        self.x_ref.copy_from_slice(&self.x_tr);
        self.searched = true;
        self.searches += 1;
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
        if self.search_due() {
            self.search();
        }
        self.cons.clear();
        for d in &mut self.dv {
            *d = [0.0; 2];
        }
        self.dt = dt;
        self.collect_passes(dt, dt_n, None);
        self.collect_walls(dt, dt_n, None);
        // Penalty impulses (marked by w < 0, impulse in lambda): fixed, applied first.
        let n_pen = self.cons.iter().filter(|c| c.w < 0.0).count();
        for k in 0..self.cons.len() {
            let c = self.cons[k];
            if c.w < 0.0 {
                self.impulse(&c, c.lambda);
            }
        }
        // Lagrange: projected Gauss-Seidel in the fixed constraint order, warm-started from the
        // multipliers of the previous step (the same slave node of the same interface), scaled by
        // the ratio of the steps. In a persistent contact (a pressure carried across an
        // interface) the sweeps then continue where they stopped instead of starting from zero
        // each step: with the redundant constraints of two passes on non-matching meshes a cold
        // start leaves a residual of about 1e-5 of the load after MAX_SWEEPS sweeps.
        if !self.warm.is_empty() && self.warm_dt > 0.0 {
            let ratio = dt_n / self.warm_dt;
            for k in 0..self.cons.len() {
                let c = self.cons[k];
                if c.w < 0.0 {
                    continue;
                }
                if let Ok(i) = self.warm.binary_search_by_key(&warm_key(&c), |w| w.0) {
                    let lambda = self.warm[i].1 * ratio;
                    if lambda > 0.0 {
                        self.impulse(&c, lambda);
                        self.cons[k].lambda = lambda;
                    }
                }
            }
        }
        if self.cons.len() > n_pen {
            self.sweep();
            // Active-set update: the sweeps move master nodes, which can carry a segment onto
            // a slave node that was free at the trial positions (a node beside a dent, or at
            // a kink, whose neighbours are pushed back). Such a node would end the step inside
            // the other body, unconstrained. Check the free nodes again at the corrected
            // positions and sweep again with any that penetrate, a few rounds at most.
            for _ in 0..ACTIVE_SET_ROUNDS {
                let before = self.cons.len();
                self.recheck(dt, dt_n);
                if self.cons.len() == before {
                    break;
                }
                self.sweep();
            }
        }
        self.warm.clear();
        for c in &self.cons {
            if c.w >= 0.0 && c.lambda > 0.0 {
                self.warm.push((warm_key(c), c.lambda));
            }
        }
        self.warm.sort_unstable_by_key(|w| w.0);
        self.warm_dt = dt_n;
        // Reports.
        for i in &mut self.interfaces {
            i.step_impulse = [0.0; 2];
            i.active = 0;
            i.max_penetration = 0.0;
            i.elapsed += dt_n;
        }
        let mut last_slave = (u32::MAX, u32::MAX);
        for k in 0..self.cons.len() {
            let c = self.cons[k];
            let pen = if c.w < 0.0 {
                c.penetration
            } else {
                -(c.g0 + dt * self.relative(&c))
            };
            let i = &mut self.interfaces[c.interface as usize];
            if c.lambda > 0.0 {
                i.step_impulse[0] += c.sign * c.lambda * c.n[0];
                i.step_impulse[1] += c.sign * c.lambda * c.n[1];
                if last_slave != (c.interface, c.s) {
                    i.active += 1;
                    last_slave = (c.interface, c.s);
                }
            }
            i.max_penetration = i.max_penetration.max(pen);
        }
        for i in &mut self.interfaces {
            i.impulse[0] += i.step_impulse[0];
            i.impulse[1] += i.step_impulse[1];
        }
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
            for k in 0..2 {
                let vn = v[g][k] + d[k];
                let j = m * d[k];
                work.work += 0.5 * j * (self.v_old[l][k] + vn);
                work.after += 0.5 * j * vn;
                v[g][k] = vn;
            }
        }
        work
    }

    /// Projected Gauss-Seidel sweeps over the Lagrange constraints, in their fixed order, until
    /// the largest change of a gap is below [`SWEEP_TOLERANCE`] x margin or [`MAX_SWEEPS`].
    fn sweep(&mut self) {
        let tol = SWEEP_TOLERANCE * self.margin.max(f64::MIN_POSITIVE);
        let dt = self.dt;
        for _ in 0..MAX_SWEEPS {
            let mut change: f64 = 0.0;
            for k in 0..self.cons.len() {
                let c = self.cons[k];
                if c.w < 0.0 {
                    continue;
                }
                let g = c.g0 + dt * self.relative(&c);
                let lambda = (c.lambda - g / c.w).max(0.0);
                let d = lambda - c.lambda;
                if d != 0.0 {
                    self.impulse(&c, d);
                    self.cons[k].lambda = lambda;
                    change = change.max((d * c.w).abs());
                }
            }
            if change <= tol {
                break;
            }
        }
    }

    /// Adds the Lagrange constraints of the slave and wall nodes without one that penetrate at
    /// the corrected positions x_tr + dt dv (see `apply`). Their gaps are stored at the free
    /// trial positions, as for every constraint, so that the sweeps treat them alike.
    fn recheck(&mut self, dt: f64, dt_n: f64) {
        let mut done = std::mem::take(&mut self.done);
        done.clear();
        done.extend(self.cons.iter().map(warm_key));
        done.sort_unstable();
        for l in 0..self.x_tr.len() {
            let (x, d) = (self.x_tr[l], self.dv[l]);
            self.x_c[l] = [x[0] + dt * d[0], x[1] + dt * d[1]];
        }
        std::mem::swap(&mut self.x_tr, &mut self.x_c);
        let first = self.cons.len();
        self.collect_passes(dt, dt_n, Some(&done));
        self.collect_walls(dt, dt_n, Some(&done));
        std::mem::swap(&mut self.x_tr, &mut self.x_c);
        for k in first..self.cons.len() {
            let c = self.cons[k];
            self.cons[k].g0 = c.g0 - dt * self.relative(&c);
        }
        self.done = done;
    }

    /// Relative normal velocity change of constraint `c` from the impulses so far.
    #[inline]
    fn relative(&self, c: &Constraint) -> f64 {
        let ds = self.dv[c.s as usize];
        let mut r = ds[0] * c.n[0] + ds[1] * c.n[1];
        if c.a != u32::MAX {
            let da = self.dv[c.a as usize];
            let db = self.dv[c.b as usize];
            r -= (1.0 - c.xi) * (da[0] * c.n[0] + da[1] * c.n[1])
                + c.xi * (db[0] * c.n[0] + db[1] * c.n[1]);
        }
        r
    }

    /// Applies impulse `lambda` along `c.n` (slave) and its reaction (master nodes).
    #[inline]
    fn impulse(&mut self, c: &Constraint, lambda: f64) {
        let sc = self.inv_mass_scale;
        let im = self.inv_mass[c.s as usize].map(|x| x * sc);
        let d = &mut self.dv[c.s as usize];
        d[0] += lambda * c.n[0] * im[0];
        d[1] += lambda * c.n[1] * im[1];
        if c.a != u32::MAX {
            for (node, share) in [(c.a, 1.0 - c.xi), (c.b, c.xi)] {
                let im = self.inv_mass[node as usize].map(|x| x * sc);
                let d = &mut self.dv[node as usize];
                d[0] -= share * lambda * c.n[0] * im[0];
                d[1] -= share * lambda * c.n[1] * im[1];
            }
        }
    }

    /// dt (1/m_s + (1-xi)^2/m_a + xi^2/m_b) along n (per direction, constrained directions rigid).
    fn weight(&self, s: u32, ab: Option<(u32, u32)>, xi: f64, n: [f64; 2], dt: f64) -> f64 {
        let along = |l: u32| {
            let im = self.inv_mass[l as usize];
            n[0] * n[0] * im[0] + n[1] * n[1] * im[1]
        };
        let mut w = along(s);
        if let Some((a, b)) = ab {
            w += (1.0 - xi) * (1.0 - xi) * along(a) + xi * xi * along(b);
        }
        dt * w * self.inv_mass_scale
    }

    fn free_relative(&self, s: u32, ab: Option<(u32, u32)>, xi: f64, n: [f64; 2]) -> f64 {
        let vs = self.v_free[s as usize];
        let mut r = dot(vs, n);
        if let Some((a, b)) = ab {
            r -=
                (1.0 - xi) * dot(self.v_free[a as usize], n) + xi * dot(self.v_free[b as usize], n);
        }
        r
    }

    /// Whether slave `s` (own outward normal `own`) is in contact with segment `j` of pass `p`,
    /// and if so its selection key (larger is better) and projection.
    ///
    /// Lagrange: projection at the trial positions; the node penetrates and came from the
    /// segment's front (see [`penetrates`]); key (gap before the step clamped at 0, trial gap):
    /// the segment the node came from the front of, then the closest. Penalty: projection at
    /// u_n, penetrating by less than half the segment; key (gap, 0).
    fn qualify(
        &self,
        p: &Pass,
        s: u32,
        own: [f64; 2],
        j: usize,
    ) -> Option<((f64, f64), narrow::Projection)> {
        let [a, b] = p.segments[j];
        let (sl, al, bl) = (s as usize, a as usize, b as usize);
        // Only segments that face the node's own surface: at a corner shared by two segments
        // this keeps the face the node meets, not the edge it touches end-on.
        let seg_t = sub(self.x_n[bl], self.x_n[al]);
        if dot(own, [seg_t[1], -seg_t[0]]) >= 0.0 {
            return None;
        }
        match p.method {
            ContactMethod::Lagrange => {
                let pr = project(self.x_tr[sl], self.x_tr[al], self.x_tr[bl])?;
                // Gap before the step, to the segment's line at u_n.
                let before = line_gap(self.x_n[sl], self.x_n[al], self.x_n[bl]);
                penetrates(pr.gap, before, pr.length).then_some(((before.min(0.0), pr.gap), pr))
            }
            ContactMethod::Penalty => {
                let pr = project(self.x_n[sl], self.x_n[al], self.x_n[bl])?;
                (pr.gap < 0.0 && pr.gap > -0.5 * pr.length).then_some(((pr.gap, 0.0), pr))
            }
        }
    }

    /// The constraints of the passes' slave nodes; with `skip` (a re-check, see `recheck`),
    /// Lagrange passes only, and not the nodes that have one (sorted `warm_key`s).
    fn collect_passes(&mut self, dt: f64, dt_n: f64, skip: Option<&[[u32; 2]]>) {
        for pi in 0..self.passes.len() {
            let p = &self.passes[pi];
            if skip.is_some() && p.method != ContactMethod::Lagrange {
                continue;
            }
            let sign = if p.slave_is_first { 1.0 } else { -1.0 };
            let mut k = 0;
            while k < p.candidates.len() {
                let si = p.candidates[k].0;
                let s = p.slaves[si as usize];
                // The slave node's own outward normal (unnormalised), at u_n.
                let [np, nn] = p.neighbours[si as usize];
                let t = sub(self.x_n[nn as usize], self.x_n[np as usize]);
                let own = [t[1], -t[0]];
                let first = k;
                while k < p.candidates.len() && p.candidates[k].0 == si {
                    k += 1;
                }
                let range = &p.candidates[first..k];
                if skip.is_some_and(|d| d.binary_search(&[p.interface as u32, s]).is_ok()) {
                    continue;
                }
                // (key, segment, projection) of the best candidate.
                let mut best: Option<((f64, f64), usize, narrow::Projection)> = None;
                for &(_, j) in range {
                    let j = j as usize;
                    if let Some((key, pr)) = self.qualify(p, s, own, j) {
                        if best.is_none_or(|(bk, _, _)| key > bk) {
                            best = Some((key, j, pr));
                        }
                    }
                }
                let Some((key, j, mut pr)) = best else {
                    continue;
                };
                let [a, b] = p.segments[j];
                // A tie with the neighbouring segment at a shared master node: the node meets
                // that master node (a corner met end-on, e.g. corner to corner), not either
                // face. Contact with the node itself along its averaged normal, so that the
                // choice does not fall to round-off (which breaks symmetry).
                for &(_, j2) in range {
                    let j2 = j2 as usize;
                    let [a2, b2] = p.segments[j2];
                    let m = if a2 == b && b2 != a {
                        b
                    } else if b2 == a && a2 != b {
                        a
                    } else {
                        continue;
                    };
                    let Some((key2, pr2)) = self.qualify(p, s, own, j2) else {
                        continue;
                    };
                    if !narrow::ties(key, key2, pr.length) {
                        continue;
                    }
                    let x = if p.method == ContactMethod::Lagrange {
                        &self.x_tr
                    } else {
                        &self.x_n
                    };
                    if let Some(v) =
                        narrow::vertex(x[s as usize], x[m as usize], pr.normal, pr2.normal)
                    {
                        pr.normal = v.normal;
                        pr.gap = v.gap;
                        pr.xi = if m == b { 1.0 } else { 0.0 };
                    }
                    break;
                }
                let w = self.weight(s, Some((a, b)), pr.xi, pr.normal, dt);
                if w.is_nan() || w <= 0.0 {
                    continue;
                }
                let mut c = Constraint {
                    interface: p.interface as u32,
                    s,
                    a,
                    b,
                    xi: pr.xi,
                    n: pr.normal,
                    g0: pr.gap,
                    w,
                    lambda: 0.0,
                    sign,
                    penetration: 0.0,
                };
                if p.method == ContactMethod::Penalty {
                    let rate = self.free_relative(s, Some((a, b)), pr.xi, pr.normal);
                    let g_trial = pr.gap + dt * rate;
                    c.lambda = penalty_impulse(p.stiffness[j], pr.gap, rate, g_trial, w, dt, dt_n);
                    c.penetration = -pr.gap;
                    c.w = -w;
                }
                self.cons.push(c);
            }
        }
    }

    /// The constraints of the walls' nodes; `skip` as for [`Self::collect_passes`].
    fn collect_walls(&mut self, dt: f64, dt_n: f64, skip: Option<&[[u32; 2]]>) {
        for wi in 0..self.walls.len() {
            let w = &self.walls[wi];
            if skip.is_some() && w.method != ContactMethod::Lagrange {
                continue;
            }
            for (idx, &l) in w.nodes.iter().enumerate() {
                if skip.is_some_and(|d| d.binary_search(&[w.interface as u32, l]).is_ok()) {
                    continue;
                }
                let n = w.normal;
                let (g, g_tr) = (
                    dot(sub(self.x_n[l as usize], w.point), n),
                    dot(sub(self.x_tr[l as usize], w.point), n),
                );
                let weight = self.weight(l, None, 0.0, n, dt);
                if weight.is_nan() || weight <= 0.0 {
                    continue;
                }
                let mut c = Constraint {
                    interface: w.interface as u32,
                    s: l,
                    a: u32::MAX,
                    b: u32::MAX,
                    xi: 0.0,
                    n,
                    g0: g_tr,
                    w: weight,
                    lambda: 0.0,
                    sign: 1.0,
                    penetration: 0.0,
                };
                match w.method {
                    ContactMethod::Lagrange => {
                        if g_tr >= 0.0 {
                            continue;
                        }
                    }
                    ContactMethod::Penalty => {
                        if g >= 0.0 {
                            continue;
                        }
                        let rate = dot(self.v_free[l as usize], n);
                        c.lambda =
                            penalty_impulse(w.stiffness[idx], g, rate, g_tr, weight, dt, dt_n);
                        c.penetration = -g;
                        c.w = -weight;
                    }
                }
                self.cons.push(c);
            }
        }
    }

    /// The contacts' history values at a sample; resets the interval averages.
    pub fn sample(&mut self) -> Vec<ContactSample> {
        self.interfaces
            .iter_mut()
            .map(|i| {
                let force = if i.elapsed > 0.0 {
                    [i.impulse[0] / i.elapsed, i.impulse[1] / i.elapsed]
                } else {
                    [0.0; 2]
                };
                i.impulse = [0.0; 2];
                i.elapsed = 0.0;
                ContactSample {
                    force,
                    max_penetration: i.max_penetration,
                    active_nodes: i.active,
                }
            })
            .collect()
    }
}

/// Penalty impulse over the step for a spring of stiffness `k` at gap `g` (< 0), bounded so that
/// one step never does more than the perfectly plastic impulse (Belytschko X.6):
/// - while the free update approaches (`rate` < 0, the relative normal velocity), at most the
///   impulse that stops the approach: no release within the impact step, no velocity reversal;
/// - while it separates, at most the impulse that brings the node back onto the surface by
///   u_{n+1} (the gap `g_trial` of the free update closed), so a spring never throws it off.
///
/// For omega dt well below 1 neither bound is active and the spring acts unchanged; for a stiff
/// spring the bounds keep the run from gaining energy. `w` is dt (1/m_s + ...).
#[inline]
pub fn penalty_impulse(k: f64, g: f64, rate: f64, g_trial: f64, w: f64, dt: f64, dt_n: f64) -> f64 {
    let spring = dt_n * k * (-g).max(0.0);
    let bound = if rate < 0.0 {
        -rate * dt / w
    } else {
        (-g_trial / w).max(0.0)
    };
    spring.min(bound)
}

impl Interface {
    fn new(name: &str) -> Self {
        Interface {
            name: name.to_string(),
            impulse: [0.0; 2],
            step_impulse: [0.0; 2],
            elapsed: 0.0,
            active: 0,
            max_penetration: 0.0,
        }
    }
}

/// Identifies a constraint from one step to the next: its interface and slave node (a slave has
/// at most one constraint per interface and pass, and the two passes have different slaves). Not
/// the segment: a node resting on a master node may switch between the two segments that share
/// it from one step to the next, and its multiplier carries over.
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

/// Signed distance of `p` to the line of `a -> b` (outward normal side positive).
#[inline]
fn line_gap(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let t = sub(b, a);
    let l = t[0].hypot(t[1]);
    if l > 0.0 {
        dot(sub(p, a), [t[1] / l, -t[0] / l])
    } else {
        0.0
    }
}

/// A slot of the GPU contact kernel: one pass's slave node or one wall's node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlotTable {
    /// Interface (contact or wall) index.
    pub interface: u32,
    /// Penalty (else Lagrange).
    pub penalty: bool,
    /// A wall's node (else a pass's slave node).
    pub wall: bool,
    /// The slave body is the interface's second body (its impulse counts negative).
    pub second_is_slave: bool,
    /// Slave node (local index).
    pub node: u32,
    /// Neighbours along the slave's surface (passes).
    pub neighbours: [u32; 2],
    /// Wall normal and point.
    pub normal: [f64; 2],
    /// A point of the wall.
    pub point: [f64; 2],
    /// Wall penalty stiffness of the node.
    pub stiffness: f64,
    /// The pass (`u32::MAX` for a wall).
    pub pass: u32,
    /// The slave node's body.
    pub body: u32,
    /// A group pass: the impulse's sign on the first body follows the body order.
    pub group: bool,
    /// The pass admits segments of the slave's own body.
    pub self_contact: bool,
}

/// A master segment of the GPU tables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentTable {
    /// Local nodes a -> b.
    pub nodes: [u32; 2],
    /// Penalty stiffness.
    pub stiffness: f64,
    /// Its pass.
    pub pass: u32,
    /// Its body.
    pub body: u32,
}

/// The flat, static tables of a contact set, for the GPU kernel.
#[derive(Debug, Clone)]
pub struct Tables {
    /// Global index of each local contact node.
    pub nodes: Vec<u32>,
    /// Inverse mass per local node and direction (0 on a constrained direction).
    pub inv_mass: Vec<[f64; 2]>,
    /// Mass per local node.
    pub mass: Vec<f64>,
    /// Slots: every pass's slave nodes in order, then every wall's nodes.
    pub slots: Vec<SlotTable>,
    /// Master segments of all passes.
    pub segments: Vec<SegmentTable>,
    /// Reference positions of the local nodes.
    pub reference: Vec<[f64; 2]>,
    /// Search margin.
    pub margin: f64,
}

/// The result of a search in slot form: candidate segments per slot (CSR) and a colouring of the
/// slots such that slots of one colour share no node (through any candidate).
#[derive(Debug, Clone, Default)]
pub struct SearchTables {
    /// Candidate offsets per slot (slots + 1).
    pub candidate_offsets: Vec<u32>,
    /// Candidate segments (indices into [`Tables::segments`]).
    pub candidates: Vec<u32>,
    /// Slot offsets per colour (colours + 1).
    pub color_offsets: Vec<u32>,
    /// Slots in colour order (ascending within a colour).
    pub color_slots: Vec<u32>,
}

impl ContactSet {
    /// The static tables of the GPU kernel.
    pub fn tables(&self, model: &Model) -> Tables {
        let mut slots = Vec::new();
        let mut segments = Vec::new();
        for (pi, p) in self.passes.iter().enumerate() {
            for (si, &s) in p.slaves.iter().enumerate() {
                slots.push(SlotTable {
                    interface: p.interface as u32,
                    penalty: p.method == ContactMethod::Penalty,
                    wall: false,
                    second_is_slave: !p.slave_is_first,
                    node: s,
                    neighbours: p.neighbours[si],
                    normal: [0.0; 2],
                    point: [0.0; 2],
                    stiffness: 0.0,
                    pass: pi as u32,
                    body: p.bodies[0],
                    group: false,
                    self_contact: false,
                });
            }
            segments.extend(
                p.segments
                    .iter()
                    .zip(&p.stiffness)
                    .map(|(&nodes, &stiffness)| SegmentTable {
                        nodes,
                        stiffness,
                        pass: pi as u32,
                        body: p.bodies[1],
                    }),
            );
        }
        for w in &self.walls {
            for (idx, &l) in w.nodes.iter().enumerate() {
                slots.push(SlotTable {
                    interface: w.interface as u32,
                    penalty: w.method == ContactMethod::Penalty,
                    wall: true,
                    second_is_slave: false,
                    node: l,
                    neighbours: [l, l],
                    normal: w.normal,
                    point: w.point,
                    stiffness: w.stiffness[idx],
                    pass: u32::MAX,
                    body: u32::MAX,
                    group: false,
                    self_contact: false,
                });
            }
        }
        Tables {
            nodes: self.nodes.clone(),
            inv_mass: self.inv_mass.clone(),
            mass: self.mass.clone(),
            slots,
            segments,
            reference: self
                .nodes
                .iter()
                .map(|&g| model.position[g as usize])
                .collect(),
            margin: self.margin,
        }
    }

    /// Searches with the local nodes at `x_n` (start of the step) and `x_tr` (the free update's
    /// end), the GPU's way: candidates per slot and a colouring (greedy, in slot order).
    pub fn search_tables(&mut self, x_n: &[[f64; 2]], x_tr: &[[f64; 2]]) -> SearchTables {
        self.x_n.copy_from_slice(x_n);
        self.x_tr.copy_from_slice(x_tr);
        self.search();
        let mut t = SearchTables::default();
        t.candidate_offsets.push(0);
        // Node sets per slot, for the colouring.
        let mut touched: Vec<Vec<u32>> = Vec::new();
        let mut seg_base = 0u32;
        for p in &self.passes {
            let mut k = 0;
            for si in 0..p.slaves.len() as u32 {
                let mut set = vec![p.slaves[si as usize]];
                while k < p.candidates.len() && p.candidates[k].0 == si {
                    let j = p.candidates[k].1;
                    t.candidates.push(seg_base + j);
                    set.extend(p.segments[j as usize]);
                    k += 1;
                }
                t.candidate_offsets.push(t.candidates.len() as u32);
                touched.push(set);
            }
            seg_base += p.segments.len() as u32;
        }
        for w in &self.walls {
            for &l in &w.nodes {
                t.candidate_offsets.push(t.candidates.len() as u32);
                touched.push(vec![l]);
            }
        }
        // Greedy colouring: the lowest colour no slot sharing a node has taken.
        let mut used: Vec<Vec<u32>> = vec![Vec::new(); self.nodes.len()];
        let mut color = vec![0u32; touched.len()];
        let mut colors = 0u32;
        for (k, set) in touched.iter().enumerate() {
            let mut c = 0u32;
            while set.iter().any(|&n| used[n as usize].contains(&c)) {
                c += 1;
            }
            for &n in set {
                used[n as usize].push(c);
            }
            color[k] = c;
            colors = colors.max(c + 1);
        }
        t.color_offsets.push(0);
        for c in 0..colors {
            t.color_slots.extend(
                color
                    .iter()
                    .enumerate()
                    .filter(|(_, &x)| x == c)
                    .map(|(k, _)| k as u32),
            );
            t.color_offsets.push(t.color_slots.len() as u32);
        }
        t
    }
}
