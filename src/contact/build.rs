//! Building a [`ContactSet`] from a model: the passes of each `[[contact]]` table (a pair's one or
//! two directions, or a group's one symmetric pass), the walls, the local nodes and masses.

use std::collections::BTreeMap;

use super::report::Interface;
use super::{ContactSet, Law, Pass, Wall};
use crate::geometry::quad_geometry;
use crate::model::surface::{self, Surface};
use crate::model::Model;
use crate::scene::{Contact, PenaltyForm};

/// A contact's or wall's penalty stiffness settings.
#[derive(Clone, Copy)]
struct Spring {
    scale: f64,
    form: PenaltyForm,
}

/// 2D bulk modulus used by the penalty stiffness: lambda (of the formulation) + mu.
fn bulk_modulus(model: &Model, body: usize) -> f64 {
    let p = &model.bodies[body].params;
    p.lambda_plane + p.mu
}

fn element_area(model: &Model, e: u32) -> f64 {
    quad_geometry(&model.corners[e as usize]).area
}

/// Surfaces and local node numbering while the set is built.
struct Builder<'m> {
    model: &'m Model,
    surfaces: Vec<Option<Surface>>,
    local: Vec<u32>,
    nodes: Vec<u32>,
    min_length: f64,
    /// The run's first step (the mass form's dt), computed when first needed.
    step: Option<f64>,
}

impl Builder<'_> {
    fn surface(&mut self, b: usize) -> Surface {
        let model = self.model;
        self.surfaces[b]
            .get_or_insert_with(|| Surface::of_body(model, b))
            .clone()
    }

    /// The local index of global node `g`.
    fn add(&mut self, g: u32) -> u32 {
        if self.local[g as usize] == u32::MAX {
            self.local[g as usize] = self.nodes.len() as u32;
            self.nodes.push(g);
        }
        self.local[g as usize]
    }

    /// Body `b`'s surface, or with `only` (global node pairs, either direction) the segments
    /// among them and their nodes (a contact limited to named faces).
    fn surface_of(&mut self, b: usize, only: Option<&[[u32; 2]]>) -> Surface {
        let s = self.surface(b);
        match only {
            Some(edges) => s.restricted(edges),
            None => s,
        }
    }

    /// The run's first step (see [`Model::initial_step`]).
    fn step(&mut self) -> f64 {
        let model = self.model;
        *self.step.get_or_insert_with(|| model.initial_step())
    }

    /// Penalty stiffness of a spring: the modulus form `scale` K t L^2 / A (body `b`, a segment
    /// of length `l` of element `e`), or the mass form `scale` m* / dt^2 with the reduced mass
    /// m* of masses `m1` and `m2` (`m2` infinite: a wall).
    fn stiffness(&mut self, spring: Spring, b: usize, e: u32, l: f64, m1: f64, m2: f64) -> f64 {
        match spring.form {
            PenaltyForm::Modulus => {
                let t = self.model.thickness(e as usize);
                spring.scale * bulk_modulus(self.model, b) * t * l * l / element_area(self.model, e)
            }
            PenaltyForm::Mass => {
                let m = if m2.is_finite() {
                    m1 * m2 / (m1 + m2)
                } else {
                    m1
                };
                let dt = self.step();
                spring.scale * m / (dt * dt)
            }
        }
    }

    /// The smallest node mass of `s`.
    fn min_mass(&self, s: &Surface) -> f64 {
        s.nodes
            .iter()
            .map(|&g| self.model.mass[g as usize])
            .fold(f64::INFINITY, f64::min)
    }

    /// Adds the nodes of `ss` (body `b`'s surface) to `p` as slaves.
    fn slaves(&mut self, p: &mut Pass, b: usize, ss: &Surface) {
        for (&g, [pg, ng]) in ss.nodes.iter().zip(surface_neighbours(ss)) {
            let s = self.add(g);
            let nb = [self.add(pg), self.add(ng)];
            p.slaves.push(s);
            p.slave_body.push(b as u32);
            p.neighbours.push(nb);
        }
    }

    /// Adds the segments of `ms` (body `b`'s surface) to `p` as masters, with `share` of the
    /// contact's penalty stiffness (the mass form against slave nodes of at least `slave_mass`).
    fn masters(
        &mut self,
        p: &mut Pass,
        b: usize,
        ms: &Surface,
        share: f64,
        spring: Spring,
        slave_mass: f64,
    ) {
        for s in &ms.segments {
            let l = surface::length(self.model, s);
            self.min_length = self.min_length.min(l);
            let mm = s
                .nodes
                .iter()
                .map(|&g| self.model.mass[g as usize])
                .fold(f64::INFINITY, f64::min);
            let k = self.stiffness(spring, b, s.element, l, slave_mass, mm);
            p.stiffness.push(share * k);
            let ab = s.nodes.map(|g| self.add(g));
            p.segments.push(ab);
            p.segment_body.push(b as u32);
        }
    }

    /// The passes of contact `c` (interface `iface`).
    fn contact(&mut self, c: &Contact, iface: usize, passes: &mut Vec<Pass>) {
        let empty = |slave_is_first: bool| Pass {
            interface: iface,
            method: c.method,
            slave_is_first,
            two_pass: c.two_pass || c.group,
            group: c.group,
            self_contact: c.self_contact,
            slaves: Vec::new(),
            slave_body: Vec::new(),
            neighbours: Vec::new(),
            neighbour_slaves: Vec::new(),
            segments: Vec::new(),
            segment_body: Vec::new(),
            stiffness: Vec::new(),
            law: Law::new(
                c.friction,
                c.friction_stiffness,
                c.penalty_form,
                c.augmentation_rate,
            ),
            candidates: Vec::new(),
        };
        let spring = Spring {
            scale: c.penalty_scale,
            form: c.penalty_form,
        };
        if c.group {
            // One symmetric pass: every node pair is met from both sides, each side with half
            // the stiffness (as a two-pass contact).
            let mut p = empty(true);
            let mut slave_mass = f64::INFINITY;
            for &b in &c.bodies {
                let ss = self.surface(b);
                slave_mass = slave_mass.min(self.min_mass(&ss));
                self.slaves(&mut p, b, &ss);
            }
            for &b in &c.bodies {
                let ms = self.surface(b);
                self.masters(&mut p, b, &ms, 0.5, spring, slave_mass);
            }
            passes.push(p);
            return;
        }
        let (first, second) = (c.bodies[0], c.bodies[1]);
        // Named faces: each body's curve edges in global node numbers.
        let faces: Vec<Option<Vec<[u32; 2]>>> = (0..2)
            .map(|k| {
                c.surfaces
                    .as_ref()
                    .map(|s| self.model.global_edges(c.bodies[k], &s[k].1))
            })
            .collect();
        let surf = [
            self.surface_of(first, faces[0].as_deref()),
            self.surface_of(second, faces[1].as_deref()),
        ];
        let mut dirs = vec![(first, second, 0, 1, true)];
        if c.two_pass {
            dirs.push((second, first, 1, 0, false));
        }
        // Two passes act on the same node pairs: each carries half the interface stiffness.
        let share = if c.two_pass { 0.5 } else { 1.0 };
        for (slave, master, ks, km, slave_is_first) in dirs {
            let mut p = empty(slave_is_first);
            let slave_mass = self.min_mass(&surf[ks]);
            self.masters(&mut p, master, &surf[km], share, spring, slave_mass);
            self.slaves(&mut p, slave, &surf[ks]);
            passes.push(p);
        }
    }

    /// Wall `w`'s nodes (every surface node of its bodies) and their penalty stiffness.
    fn wall(&mut self, w: &crate::scene::RigidWall, iface: usize) -> Wall {
        let mut nodes = Vec::new();
        let mut body = Vec::new();
        let mut stiffness = Vec::new();
        let spring = Spring {
            scale: w.penalty_scale,
            form: w.penalty_form,
        };
        let mut neighbours = Vec::new();
        for &b in &w.bodies {
            let s = self.surface(b);
            for &g in &s.nodes {
                // The node's stiffest adjacent boundary segment (modulus form), or its mass.
                let mut k = 0.0f64;
                let m = self.model.mass[g as usize];
                for seg in s.segments.iter().filter(|seg| seg.nodes.contains(&g)) {
                    let l = surface::length(self.model, seg);
                    self.min_length = self.min_length.min(l);
                    k = k.max(self.stiffness(spring, b, seg.element, l, m, f64::INFINITY));
                }
                nodes.push(self.add(g));
                body.push(b as u32);
                stiffness.push(k);
            }
            // (After the nodes, so that the local numbering stays that of the nodes.)
            for nb in surface_neighbours(&s) {
                neighbours.push(nb.map(|g| self.add(g)));
            }
        }
        Wall {
            interface: iface,
            method: w.method,
            point: w.point,
            normal: w.normal,
            nodes,
            body,
            neighbours,
            stiffness,
            law: Law::new(
                w.friction,
                w.friction_stiffness,
                w.penalty_form,
                w.augmentation_rate,
            ),
        }
    }
}

impl Law {
    /// The law of a contact's or wall's keys.
    fn new(friction: f64, friction_stiffness: f64, form: PenaltyForm, augmentation: f64) -> Self {
        Self {
            friction,
            friction_stiffness,
            mass_form: form == PenaltyForm::Mass,
            augmentation,
        }
    }
}

impl ContactSet {
    /// The contact state of `model`; `None` when it has no contact or wall.
    pub fn new(model: &Model) -> Option<ContactSet> {
        if !model.has_contact() {
            return None;
        }
        let mut bld = Builder {
            model,
            surfaces: vec![None; model.bodies.len()],
            local: vec![u32::MAX; model.node_count()],
            nodes: Vec::new(),
            min_length: f64::INFINITY,
            step: None,
        };
        let mut interfaces = Vec::new();
        let mut passes = Vec::new();
        let mut walls = Vec::new();
        for c in &model.contacts {
            let iface = interfaces.len();
            interfaces.push(Interface::new(&c.name));
            bld.contact(c, iface, &mut passes);
        }
        for p in &mut passes {
            p.link_neighbours();
        }
        for w in &model.walls {
            let iface = interfaces.len();
            interfaces.push(Interface::new(&w.name));
            walls.push(bld.wall(w, iface));
        }
        let Builder {
            nodes, min_length, ..
        } = bld;
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
        let n = nodes.len();
        let mut set = ContactSet {
            interfaces,
            passes,
            walls,
            reference: nodes.iter().map(|&g| model.position[g as usize]).collect(),
            inv_mass,
            mass,
            inv_mass_scale: 1.0,
            warm: Vec::new(),
            warm_dt: 0.0,
            v_old: vec![[0.0; 2]; n],
            x_ref: vec![[0.0; 2]; n],
            x_n: vec![[0.0; 2]; n],
            x_tr: vec![[0.0; 2]; n],
            x_c: vec![[0.0; 2]; n],
            done: Vec::new(),
            dt: 0.0,
            v_free: vec![[0.0; 2]; n],
            dv: vec![[0.0; 2]; n],
            pen_ft: Vec::new(),
            pen_ft_next: Vec::new(),
            dvt: if model.contacts.iter().any(|c| c.friction > 0.0)
                || model.walls.iter().any(|w| w.friction > 0.0)
            {
                vec![[0.0; 2]; n]
            } else {
                Vec::new()
            },
            nodes,
            searched: false,
            margin: if min_length.is_finite() {
                0.5 * min_length
            } else {
                0.0
            },
            searches: 0,
            sweep_stats: Default::default(),
            penalty_step: None,
            penalty_bounded: 0,
            cons: Vec::new(),
            plain_sweeps: false,
            last_lambda: Vec::new(),
            last_dv: Vec::new(),
            touched: Vec::new(),
            partner: Vec::new(),
            by_slave: Vec::new(),
            pairs: Vec::new(),
            mark: Vec::new(),
        };
        set.penalty_step = set.compute_penalty_step();
        Some(set)
    }
}

/// Each node of `ss` (in its order): its neighbours along the surface (previous, next; global
/// indices; the node itself where it has none).
fn surface_neighbours(ss: &Surface) -> Vec<[u32; 2]> {
    let mut prev = BTreeMap::new();
    let mut next = BTreeMap::new();
    for seg in &ss.segments {
        next.insert(seg.nodes[0], seg.nodes[1]);
        prev.insert(seg.nodes[1], seg.nodes[0]);
    }
    ss.nodes
        .iter()
        .map(|&g| {
            [
                prev.get(&g).copied().unwrap_or(g),
                next.get(&g).copied().unwrap_or(g),
            ]
        })
        .collect()
}
