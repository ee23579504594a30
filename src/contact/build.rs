//! Building a [`ContactSet`] from a model: the passes of each `[[contact]]` table (a pair's one or
//! two directions, or a group's one symmetric pass), the walls, the local nodes and masses; and
//! the same passes and walls again on the surfaces left after erosion ([`rebuild`], called by
//! [`super::erosion`]), in the local numbering of the first build, and on every candidate that
//! erosion may expose ([`every_candidate`], the GPU's fixed lists).

use std::collections::BTreeMap;

use super::report::Interface;
use super::{ContactSet, Law, Pass, Wall};
use crate::geometry::quad_geometry;
use crate::model::surface::{self, EdgeCandidates, Exposure, Surface};
use crate::model::Model;
use crate::scene::{Contact, PenaltyForm};

/// A contact's or wall's penalty stiffness settings.
#[derive(Clone, Copy)]
struct Spring {
    scale: f64,
    form: PenaltyForm,
}

/// 2D bulk modulus used by the penalty stiffness: lambda (of the formulation) + mu.
/// Whether each of the global nodes `nodes` lies on the axis of an axisymmetric body (empty when
/// no body is axisymmetric).
fn on_axis(model: &Model, nodes: &[u32]) -> Vec<bool> {
    if model.bodies.iter().all(|b| b.axis_tolerance.is_none()) {
        return Vec::new();
    }
    nodes
        .iter()
        .map(|&g| {
            let g = g as usize;
            let b = model.bodies.partition_point(|b| b.nodes.end <= g);
            model
                .bodies
                .get(b)
                .is_some_and(|b| b.on_axis(model.position[g]))
        })
        .collect()
}

fn bulk_modulus(model: &Model, body: usize) -> f64 {
    let p = &model.bodies[body].params;
    p.lambda_plane + p.mu
}

fn element_area(model: &Model, e: u32) -> f64 {
    quad_geometry(&model.corners[e as usize]).area
}

/// The surfaces an erosion rebuild reuses ([`rebuild`]): per body its candidate edges and its
/// surface as meshed, once computed (they depend only on the mesh), and per erodible body its
/// exposure under the flags of the last rebuild (`eroded`), which the next one brings up to date
/// in the size of what changed ([`EdgeCandidates::update`]).
#[derive(Debug, Clone, Default)]
pub(super) struct Cache {
    candidates: Vec<Option<EdgeCandidates>>,
    initial: Vec<Option<Surface>>,
    exposure: Vec<Option<Exposure>>,
    eroded: Vec<bool>,
}

/// Surfaces and local node numbering while the set is built.
struct Builder<'m> {
    model: &'m Model,
    /// Per global element, whether it eroded (empty: none has).
    eroded: &'m [bool],
    /// The erodible bodies' surfaces are every candidate edge, their free nodes every node
    /// ([`every_candidate`]).
    every: bool,
    /// The surfaces of the bodies now (those of `initial` while nothing has eroded).
    surfaces: Vec<Option<Surface>>,
    /// The surfaces of the mesh as meshed.
    initial: Vec<Option<Surface>>,
    /// The candidate edges of the bodies that can erode, when first needed.
    candidates: Vec<Option<EdgeCandidates>>,
    /// The erodible bodies' exposures under `eroded` (a rebuild's: [`Cache`]), when first needed.
    exposure: Vec<Option<Exposure>>,
    local: Vec<u32>,
    nodes: Vec<u32>,
    min_length: f64,
    /// The run's first step (the mass form's dt), computed when first needed.
    step: Option<f64>,
}

impl<'m> Builder<'m> {
    fn new(model: &'m Model, eroded: &'m [bool]) -> Self {
        let nb = model.bodies.len();
        Builder {
            model,
            eroded,
            every: false,
            surfaces: vec![None; nb],
            initial: vec![None; nb],
            candidates: vec![None; nb],
            exposure: vec![None; nb],
            local: vec![u32::MAX; model.node_count()],
            nodes: Vec::new(),
            min_length: f64::INFINITY,
            step: None,
        }
    }

    /// Whether body `b`'s elements can fail (its surface follows erosion).
    fn erodible(&self, b: usize) -> bool {
        self.model.bodies[b].params.failure.is_some()
    }

    /// Body `b`'s candidate edges (an erodible body).
    fn candidates(&mut self, b: usize) -> &EdgeCandidates {
        let model = self.model;
        self.candidates[b].get_or_insert_with(|| EdgeCandidates::of_body(model, b))
    }

    /// Body `b`'s surface as meshed.
    fn initial_surface(&mut self, b: usize) -> Surface {
        let model = self.model;
        self.initial[b]
            .get_or_insert_with(|| Surface::of_body(model, b))
            .clone()
    }

    /// Body `b`'s surface now: as meshed, or the exposed candidate edges after erosion.
    fn surface(&mut self, b: usize) -> Surface {
        if self.every && self.erodible(b) {
            let edges = self.candidates(b).edges.clone();
            let mut nodes: Vec<u32> = edges.iter().flat_map(|s| s.nodes).collect();
            nodes.sort_unstable();
            nodes.dedup();
            return Surface {
                body: b,
                nodes,
                segments: edges,
            };
        }
        if self.eroded.is_empty() || !self.erodible(b) {
            return self.initial_surface(b);
        }
        if let Some(s) = &self.surfaces[b] {
            return s.clone();
        }
        self.exposure(b);
        let s = match (&self.candidates[b], &self.exposure[b]) {
            (Some(c), Some(x)) => c.surface_of(x),
            _ => return self.initial_surface(b),
        };
        self.surfaces[b] = Some(s.clone());
        s
    }

    /// Makes body `b`'s exposure under `eroded` (an erodible body, `eroded` not empty).
    fn exposure(&mut self, b: usize) {
        if self.exposure[b].is_none() {
            let eroded = self.eroded;
            let x = self.candidates(b).exposure(eroded);
            self.exposure[b] = Some(x);
        }
    }

    /// Body `b`'s free nodes (of eroded elements only), within the nodes of `only` (global node
    /// pairs) if given.
    fn free_nodes(&mut self, b: usize, only: Option<&[[u32; 2]]>) -> Vec<u32> {
        if !self.erodible(b) || (self.eroded.is_empty() && !self.every) {
            return Vec::new();
        }
        let mut free = if self.every {
            let all = vec![true; self.model.quads.len()];
            self.candidates(b).free_nodes(&all)
        } else {
            self.exposure(b);
            match (&self.candidates[b], &self.exposure[b]) {
                (Some(c), Some(x)) => c.free_of(x),
                _ => Vec::new(),
            }
        };
        if let Some(edges) = only {
            let set: std::collections::HashSet<u32> = edges.iter().flatten().copied().collect();
            free.retain(|g| set.contains(g));
        }
        free
    }

    /// Adds every node of the erodible bodies of the contacts and walls to the local numbering
    /// (after the surface nodes, whose numbers stay), and every candidate edge to the shortest
    /// segment: the surfaces erosion exposes need no new local node, and the margin holds.
    fn erodible_nodes(&mut self) {
        let model = self.model;
        let mut bodies: Vec<usize> = model
            .contacts
            .iter()
            .flat_map(|c| c.bodies.iter().copied())
            .chain(model.walls.iter().flat_map(|w| w.bodies.iter().copied()))
            .filter(|&b| self.erodible(b))
            .collect();
        bodies.sort_unstable();
        bodies.dedup();
        for b in bodies {
            for g in model.bodies[b].nodes.clone() {
                self.add(g as u32);
            }
            let shortest = self
                .candidates(b)
                .edges
                .iter()
                .map(|s| surface::length(model, s))
                .fold(f64::INFINITY, f64::min);
            self.min_length = self.min_length.min(shortest);
        }
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
    /// among them and their nodes (a contact limited to named faces), with its free nodes.
    fn surface_of(&mut self, b: usize, only: Option<&[[u32; 2]]>) -> (Surface, Vec<u32>) {
        let s = self.surface(b);
        let free = self.free_nodes(b, only);
        match only {
            Some(edges) => (s.restricted(edges), free),
            None => (s, free),
        }
    }

    /// Body `b`'s surface as meshed, or the part of it on `only`.
    fn initial_of(&mut self, b: usize, only: Option<&[[u32; 2]]>) -> Surface {
        let s = self.initial_surface(b);
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

    /// Adds the nodes of `ss` (body `b`'s surface) and its free nodes `free` to `p` as slaves.
    fn slaves(&mut self, p: &mut Pass, b: usize, ss: &Surface, free: &[u32]) {
        for (g, [pg, ng]) in side_nodes(ss, free) {
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
                let (ss, free) = self.surface_of(b, None);
                let initial = self.initial_surface(b);
                slave_mass = slave_mass.min(self.min_mass(&initial));
                self.slaves(&mut p, b, &ss, &free);
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
        // The mass form's slave mass: of the surfaces as meshed, whatever erodes.
        let initial_mass = [
            {
                let s = self.initial_of(first, faces[0].as_deref());
                self.min_mass(&s)
            },
            {
                let s = self.initial_of(second, faces[1].as_deref());
                self.min_mass(&s)
            },
        ];
        let mut dirs = vec![(first, second, 0, 1, true)];
        if c.two_pass {
            dirs.push((second, first, 1, 0, false));
        }
        // Two passes act on the same node pairs: each carries half the interface stiffness.
        let share = if c.two_pass { 0.5 } else { 1.0 };
        for (slave, master, ks, km, slave_is_first) in dirs {
            let mut p = empty(slave_is_first);
            let slave_mass = initial_mass[ks];
            self.masters(&mut p, master, &surf[km].0, share, spring, slave_mass);
            self.slaves(&mut p, slave, &surf[ks].0, &surf[ks].1);
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
            let (s, free) = self.surface_of(b, None);
            let mut adjacent: BTreeMap<u32, Vec<surface::Segment>> = BTreeMap::new();
            for seg in &s.segments {
                for g in seg.nodes {
                    adjacent.entry(g).or_default().push(*seg);
                }
            }
            let side = side_nodes(&s, &free);
            for &(g, _) in &side {
                // The node's stiffest adjacent boundary segment (modulus form), or its mass; a
                // free node's, of the edges of its (eroded) elements.
                let mut k = 0.0f64;
                let m = self.model.mass[g as usize];
                let segs = match adjacent.get(&g) {
                    Some(segs) => segs.clone(),
                    None => self.element_edges(b, g),
                };
                for seg in &segs {
                    let l = surface::length(self.model, seg);
                    self.min_length = self.min_length.min(l);
                    k = k.max(self.stiffness(spring, b, seg.element, l, m, f64::INFINITY));
                }
                nodes.push(self.add(g));
                body.push(b as u32);
                stiffness.push(k);
            }
            // (After the nodes, so that the local numbering stays that of the nodes.)
            for (_, nb) in side {
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

impl Builder<'_> {
    /// The edges at node `g` of its elements in body `b` (an erodible body's candidates).
    fn element_edges(&mut self, b: usize, g: u32) -> Vec<surface::Segment> {
        let model = self.model;
        let cand = self.candidates(b);
        let mut out = Vec::new();
        for &e in cand.elements_of(g) {
            let q = model.quads[e as usize];
            for a in 0..4 {
                let (i, j) = (q[a], q[(a + 1) % 4]);
                if i != j && (i == g || j == g) {
                    out.push(surface::Segment {
                        nodes: [i, j],
                        element: e,
                    });
                }
            }
        }
        out
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
        let mut bld = Builder::new(model, &[]);
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
        if model.has_erosion() {
            bld.erodible_nodes();
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
            axis: on_axis(model, &nodes),
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
            surfaces: Cache::default(),
        };
        set.penalty_step = set.compute_penalty_step();
        Some(set)
    }
}

/// The passes and walls of `model` on the surfaces left where `eroded` (per global element) have
/// eroded, in the local numbering `nodes` of the first build ([`ContactSet::new`], which holds
/// every node of an erodible body); `None` if they need a node outside it.
/// `cache` keeps the bodies' candidate edges and initial surfaces from one rebuild to the next.
pub(super) fn rebuild(
    model: &Model,
    eroded: &[bool],
    nodes: &[u32],
    cache: &mut Cache,
) -> Option<(Vec<Pass>, Vec<Wall>)> {
    let mut bld = Builder::new(model, eroded);
    let nb = model.bodies.len();
    if cache.candidates.len() == nb && cache.initial.len() == nb {
        bld.candidates = std::mem::take(&mut cache.candidates);
        bld.initial = std::mem::take(&mut cache.initial);
    }
    if cache.exposure.len() == nb && cache.eroded.len() == eroded.len() {
        // The exposures of the last rebuild, brought to `eroded`: the elements whose flag
        // changed, body by body (elements are numbered body after body).
        let changed: Vec<u32> = (0..eroded.len())
            .filter(|&e| eroded[e] != cache.eroded[e])
            .map(|e| e as u32)
            .collect();
        let mut exposure = std::mem::take(&mut cache.exposure);
        for (b, x) in exposure.iter_mut().enumerate() {
            match (x.as_mut(), bld.candidates[b].as_ref()) {
                (Some(ex), Some(c)) => {
                    let r = &model.bodies[b].elements;
                    let from = changed.partition_point(|&e| (e as usize) < r.start);
                    let to = changed.partition_point(|&e| (e as usize) < r.end);
                    c.update(ex, &changed[from..to], eroded, &model.quads);
                }
                // No candidates kept: the exposure is made again when needed.
                _ => *x = None,
            }
        }
        bld.exposure = exposure;
    }
    let (out, bld) = build_kept(bld, nodes);
    cache.candidates = bld.candidates;
    cache.initial = bld.initial;
    cache.exposure = bld.exposure;
    cache.eroded = eroded.to_vec();
    out
}

/// The passes and walls of `model` with every slave node and master segment that erosion may
/// bring onto them: on an erodible body, every edge of its elements is a segment and every node
/// a slave (the slaves' neighbours and the walls' stiffness are not those of any surface), in the
/// local numbering `nodes` of the first build; `None` as [`rebuild`]. The GPU keeps these lists
/// fixed under a mask ([`super::erosion::Masked`]).
pub(super) fn every_candidate(model: &Model, nodes: &[u32]) -> Option<(Vec<Pass>, Vec<Wall>)> {
    let mut bld = Builder::new(model, &[]);
    bld.every = true;
    build_on(bld, nodes)
}

/// The passes and walls `bld` builds, in the local numbering `nodes`.
fn build_on(bld: Builder<'_>, nodes: &[u32]) -> Option<(Vec<Pass>, Vec<Wall>)> {
    build_kept(bld, nodes).0
}

/// [`build_on`], giving the builder back (with the surfaces it computed).
#[allow(clippy::type_complexity)]
fn build_kept<'m>(
    mut bld: Builder<'m>,
    nodes: &[u32],
) -> (Option<(Vec<Pass>, Vec<Wall>)>, Builder<'m>) {
    let model = bld.model;
    for (l, &g) in nodes.iter().enumerate() {
        bld.local[g as usize] = l as u32;
    }
    bld.nodes = nodes.to_vec();
    let mut passes = Vec::new();
    for (iface, c) in model.contacts.iter().enumerate() {
        bld.contact(c, iface, &mut passes);
    }
    for p in &mut passes {
        p.link_neighbours();
    }
    let walls = model
        .walls
        .iter()
        .enumerate()
        .map(|(k, w)| bld.wall(w, model.contacts.len() + k))
        .collect();
    let out = (bld.nodes.len() == nodes.len()).then_some((passes, walls));
    (out, bld)
}

/// The nodes of a side of a contact: those of `ss` and the free nodes `free`, ascending, each
/// with its neighbours along the surface (previous, next; global indices; the node itself where
/// it has none, as a free node).
fn side_nodes(ss: &Surface, free: &[u32]) -> Vec<(u32, [u32; 2])> {
    let mut out: Vec<(u32, [u32; 2])> = ss
        .nodes
        .iter()
        .copied()
        .zip(surface_neighbours(ss))
        .collect();
    if !free.is_empty() {
        out.extend(free.iter().map(|&g| (g, [g, g])));
        out.sort_by_key(|x| x.0);
        out.dedup_by_key(|x| x.0);
    }
    out
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
