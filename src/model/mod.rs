//! The model: a scene turned into flat arrays (nodes, elements, bodies, constraints), and the
//! boundary of each body ([`surface`]), on which pressure loads and contacts act.
//!
//! Reference coordinates are kept apart from displacements: every element stores its corners
//! relative to its own centre, so that f32 keeps full precision far from the origin. The GPU
//! solver uploads these arrays as they are (in f32, [`crate::gpu::state`]).

pub mod surface;

use std::ops::Range;

use crate::element::plastic::PlasticState;
use crate::element::{evaluate_state, evaluate_with, Dissipation, ElementOut, ElementParams};
use crate::error::Result;
use crate::geometry::{
    element_centre, is_triangle, is_triangle_geometry, lumped_mass, lumped_mass_axisymmetric,
    min_corner_ratio, quad_geometry, QuadGeometry,
};
use crate::mesh::Mesh;
use crate::scene::{self, Scene};
use surface::Surface;

/// One body's slice of the model.
#[derive(Debug, Clone)]
pub struct BodyModel {
    /// Name.
    pub name: String,
    /// Its nodes, a contiguous range of global node indices.
    pub nodes: Range<usize>,
    /// Its elements, a contiguous range of global element indices.
    pub elements: Range<usize>,
    /// Element parameters.
    pub params: ElementParams,
    /// Total mass.
    pub mass: f64,
    /// For an axisymmetric body, the largest |x| of a node on the axis (x = r = 0, to round-off
    /// of the body's size): such nodes keep u_r = 0 and the edges between two of them are not
    /// part of its surface ([`surface`]). `None` for a plane body.
    pub axis_tolerance: Option<f64>,
}

impl BodyModel {
    /// Whether the point `p` (reference coordinates) lies on the axis of this axisymmetric body
    /// (never for a plane body).
    pub fn on_axis(&self, p: [f64; 2]) -> bool {
        self.axis_tolerance.is_some_and(|tol| p[0].abs() <= tol)
    }
}

/// A velocity constraint on one node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeConstraint {
    /// Global node index.
    pub node: u32,
    /// Prescribed x velocity, if any.
    pub vx: Option<f64>,
    /// Prescribed y velocity, if any (with `cy`, its value at t = 0).
    pub vy: Option<f64>,
    /// Index into [`Model::curves`] of the x velocity's load curve (`None`: constant `vx`).
    pub cx: Option<u32>,
    /// Index into [`Model::curves`] of the y velocity's load curve (`None`: constant `vy`).
    pub cy: Option<u32>,
}

impl NodeConstraint {
    /// Node `node` with no component prescribed yet.
    pub fn free(node: u32) -> Self {
        Self {
            node,
            vx: None,
            vy: None,
            cx: None,
            cy: None,
        }
    }

    /// The prescribed (x, y) velocity at time `t` of `curves` (the model's).
    pub fn velocity_at(&self, curves: &[crate::scene::LoadCurve], t: f64) -> [Option<f64>; 2] {
        let at = |v: Option<f64>, c: Option<u32>| match c {
            Some(k) => Some(curves[k as usize].at(t)),
            None => v,
        };
        [at(self.vx, self.cx), at(self.vy, self.cy)]
    }
}

/// A pressure load resolved to nodal forces.
///
/// The consistent nodal forces of a uniform pressure on the loaded edges, per unit pressure:
/// p L t / 2 on each edge node along the inward normal of the reference edge (a nominal,
/// dead-direction load, exact for the geometrically linear material).
#[derive(Debug, Clone, PartialEq)]
pub struct PressureLoad {
    /// Pressure (Pa), positive compressive.
    pub value: f64,
    /// Duration of the linear ramp (s), if any.
    pub ramp: Option<f64>,
    /// The load curve, when the pressure is one (`value` is then its value at t = 0).
    pub curve: Option<crate::scene::LoadCurve>,
    /// Loaded nodes (global indices, ascending) and their force per unit pressure (N/Pa).
    pub nodes: Vec<(u32, [f64; 2])>,
    /// Number of loaded edges.
    pub edges: usize,
}

impl PressureLoad {
    /// The pressure at time `t`: its load curve's value, or `value`, scaled by `min(t / ramp, 1)`
    /// with a ramp.
    pub fn at(&self, t: f64) -> f64 {
        if let Some(c) = &self.curve {
            return c.at(t);
        }
        match self.ramp {
            Some(r) => self.value * (t / r).clamp(0.0, 1.0),
            None => self.value,
        }
    }
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
    /// The bodies of the node and of the surface it is behind (`None` for a wall).
    pub bodies: Option<[u32; 2]>,
}

/// The whole model as flat arrays.
#[derive(Debug, Clone)]
pub struct Model {
    /// Absolute reference coordinates of the nodes.
    pub position: Vec<[f64; 2]>,
    /// Lumped nodal masses.
    pub mass: Vec<f64>,
    /// Initial velocities.
    pub velocity: Vec<[f64; 2]>,
    /// Element connectivity (global node indices, counter-clockwise).
    pub quads: Vec<[u32; 4]>,
    /// Reference corner coordinates of each element relative to the element's centre.
    pub corners: Vec<[[f64; 2]; 4]>,
    /// Reference radius (x) of each element's centre, for axisymmetric bodies (empty when the
    /// model has none; 0 for the elements of other bodies).
    pub radius: Vec<f64>,
    /// Slave nodes that started behind a contact surface or wall and were moved onto it
    /// ([`crate::contact::overlap::resolve`]).
    pub initial_overlaps: Vec<Overlap>,
    /// Body of each element.
    pub element_body: Vec<u32>,
    /// Bodies.
    pub bodies: Vec<BodyModel>,
    /// Velocity constraints, sorted by node.
    pub constraints: Vec<NodeConstraint>,
    /// The load curves of the velocity boundaries ([`NodeConstraint::cx`], `cy`).
    pub curves: Vec<crate::scene::LoadCurve>,
    /// Contacts between bodies (as in the scene).
    pub contacts: Vec<scene::Contact>,
    /// Rigid walls (as in the scene).
    pub walls: Vec<scene::RigidWall>,
    /// Pressure loads.
    pub pressures: Vec<PressureLoad>,
    /// Mass-proportional damping coefficient alpha (1/s), 0 for none.
    pub mass_damping: f64,
    /// Gravity (m/s^2), [0, 0] for none.
    pub gravity: [f64; 2],
    /// Duration of its linear ramp from 0 (s; 0: none).
    pub gravity_ramp: f64,
    /// The run's fixed step, if any (as in the scene).
    pub time_step: Option<f64>,
    /// The run's safety factor on the stable step (as in the scene).
    pub time_step_scale: f64,
    /// `run.erosion.inverted`: an element about to invert erodes instead of stopping the run.
    pub erode_inverted: bool,
    /// `run.erosion.min_time_step` over `time_step_scale`: an element whose stable step falls
    /// below it erodes (0: never).
    pub erode_min_dt: f64,
}

impl Model {
    /// Assembles the model of `scene`: meshes each body, lumps the mass, applies initial
    /// velocities, collects the velocity constraints and resolves the pressure loads. Contact
    /// overlaps at t = 0 are not resolved here: a run's model comes from [`crate::run::model`],
    /// which also calls [`crate::contact::overlap::resolve`].
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] for a mesh with an inverted, zero-area or non-convex element, or a
    /// boundary box that selects no node.
    pub fn assemble(scene: &Scene) -> Result<Model> {
        let mut m = Model {
            position: Vec::new(),
            mass: Vec::new(),
            velocity: Vec::new(),
            quads: Vec::new(),
            corners: Vec::new(),
            radius: Vec::new(),
            element_body: Vec::new(),
            bodies: Vec::new(),
            constraints: Vec::new(),
            curves: Vec::new(),
            contacts: scene.contacts.clone(),
            walls: scene.walls.clone(),
            initial_overlaps: Vec::new(),
            pressures: Vec::new(),
            mass_damping: scene.run.mass_damping,
            gravity: scene.run.gravity,
            gravity_ramp: scene.run.gravity_ramp,
            time_step: scene.run.time_step,
            time_step_scale: scene.run.time_step_scale,
            erode_inverted: scene.run.erode_inverted,
            erode_min_dt: scene
                .run
                .erode_min_time_step
                .map_or(0.0, |s| s / scene.run.time_step_scale),
        };
        let any_axi = scene
            .bodies
            .iter()
            .any(|b| b.formulation == scene::Formulation::Axisymmetric);
        for (bi, body) in scene.bodies.iter().enumerate() {
            let mesh = Mesh::generate(&body.mesh);
            let axi = body.formulation == scene::Formulation::Axisymmetric;
            if axi {
                // Every node at x = r >= 0 (to round-off of the body's size).
                let size = mesh
                    .nodes
                    .iter()
                    .fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()))
                    + mesh.origin[0].abs();
                if let Some((i, p)) = mesh
                    .nodes
                    .iter()
                    .enumerate()
                    .find(|(_, p)| mesh.origin[0] + p[0] < -1e-12 * size)
                {
                    return Err(scene::invalid(
                        scene,
                        format!("body[{bi}].mesh"),
                        format!("node {i} at x = {:e}", mesh.origin[0] + p[0]),
                        "an axisymmetric body lies at x = r >= 0 (the axis is x = 0)",
                    ));
                }
            }
            let material = &scene.materials[body.material];
            let params = ElementParams::new(
                material,
                body.formulation,
                body.thickness,
                body.hourglass.form,
                body.hourglass.coefficient,
                (scene.run.bulk_linear, scene.run.bulk_quadratic),
            );
            let n0 = m.position.len();
            let e0 = m.quads.len();
            let mut mass = vec![0.0; mesh.nodes.len()];
            for (qi, q) in mesh.quads.iter().enumerate() {
                let x: [[f64; 2]; 4] = q.map(|i| mesh.nodes[i as usize]);
                let tri = is_triangle(q);
                if tri && (q[0] == q[1] || q[1] == q[2] || q[2] == q[0])
                    || tri != is_triangle_geometry(&x)
                {
                    return Err(scene::invalid(
                        scene,
                        format!("body[{bi}].mesh"),
                        format!("element {qi} = {q:?}"),
                        "two corners of the element are the same node or the same point (a triangle \
                         is [a, b, c] or [a, b, c, c] with a, b, c distinct)",
                    ));
                }
                let g = quad_geometry(&x);
                let corner = min_corner_ratio(&x, g.area);
                if !(g.area > 0.0 && corner > 1e-8) {
                    return Err(scene::invalid(
                        scene,
                        format!("body[{bi}].mesh"),
                        format!("{} {qi} = {q:?}, area {:e}", if tri { "triangle" } else { "quad" }, g.area),
                        "inverted, zero-area or non-convex element (elements must be convex and counter-clockwise)",
                    ));
                }
                let lumped = if axi {
                    lumped_mass_axisymmetric(&x, params.density, mesh.origin[0])
                } else {
                    lumped_mass(&x, params.density * params.thickness)
                };
                for a in 0..4 {
                    mass[q[a] as usize] += lumped[a];
                }
                let [cx, cy] = element_centre(&x);
                m.corners.push(x.map(|p| [p[0] - cx, p[1] - cy]));
                if any_axi {
                    m.radius.push(if axi { mesh.origin[0] + cx } else { 0.0 });
                }
                m.quads.push(q.map(|i| i + n0 as u32));
                m.element_body.push(bi as u32);
            }
            let mut used = vec![false; mesh.nodes.len()];
            for q in &mesh.quads {
                for &i in q {
                    used[i as usize] = true;
                }
            }
            if let Some(i) = used.iter().position(|&u| !u) {
                return Err(scene::invalid(
                    scene,
                    format!("body[{bi}].mesh"),
                    format!("node {i}"),
                    "node belongs to no element",
                ));
            }
            if let Some(i) = mass.iter().position(|&x| !(x.is_normal() && x > 0.0)) {
                return Err(scene::invalid(
                    scene,
                    format!("material[{}].density", body.material),
                    format!("{:e}", material.density),
                    &format!(
                        "the mass of node {i} of body {:?} is {:e} kg: density x thickness x \
                         element area underflows (below {:e})",
                        body.name,
                        mass[i],
                        f64::MIN_POSITIVE
                    ),
                ));
            }
            let total: f64 = mass.iter().sum();
            // Centroid for the angular velocity.
            let (mut cx, mut cy) = (0.0, 0.0);
            for (p, w) in mesh.nodes.iter().zip(&mass) {
                cx += w * p[0];
                cy += w * p[1];
            }
            cx /= total;
            cy /= total;
            for (p, w) in mesh.nodes.iter().zip(&mass) {
                m.position
                    .push([mesh.origin[0] + p[0], mesh.origin[1] + p[1]]);
                m.mass.push(*w);
                let om = body.angular_velocity;
                let g = body.velocity_gradient;
                let (rx, ry) = (p[0] - cx, p[1] - cy);
                m.velocity.push([
                    body.initial_velocity[0] - om * ry + g[0][0] * rx + g[0][1] * ry,
                    body.initial_velocity[1] + om * rx + g[1][0] * rx + g[1][1] * ry,
                ]);
            }
            m.bodies.push(BodyModel {
                name: body.name.clone(),
                nodes: n0..m.position.len(),
                elements: e0..m.quads.len(),
                params,
                mass: total,
                axis_tolerance: None,
            });
        }
        // Velocity constraints: later boundaries override earlier ones component-wise.
        let mut cons: Vec<Option<NodeConstraint>> = vec![None; m.position.len()];
        for b in &scene.boundaries {
            let range = m.bodies[b.body].nodes.clone();
            let mut curve = |c: &Option<crate::scene::LoadCurve>| {
                c.as_ref().map(|c| {
                    m.curves.push(c.clone());
                    (m.curves.len() - 1) as u32
                })
            };
            let (cx, cy) = (curve(&b.curve_x), curve(&b.curve_y));
            let named: Option<std::collections::HashSet<usize>> = b
                .group
                .as_ref()
                .map(|g| g.nodes.iter().map(|&i| range.start + i as usize).collect());
            let mut hit = 0;
            for n in range {
                let p = m.position[n];
                let selected = match &named {
                    Some(set) => set.contains(&n),
                    None => {
                        p[0] >= b.min[0] && p[0] <= b.max[0] && p[1] >= b.min[1] && p[1] <= b.max[1]
                    }
                };
                if selected {
                    hit += 1;
                    let c = cons[n].get_or_insert(NodeConstraint::free(n as u32));
                    if b.vx.is_some() {
                        c.vx = b.vx;
                        c.cx = cx;
                    }
                    if b.vy.is_some() {
                        c.vy = b.vy;
                        c.cy = cy;
                    }
                }
            }
            if hit == 0 {
                return Err(scene::invalid(
                    scene,
                    format!("{}.region", b.key),
                    format!("{{ min = {:?}, max = {:?} }}", b.min, b.max),
                    &format!(
                        "the box selects no node of body {:?}",
                        scene.bodies[b.body].name
                    ),
                ));
            }
        }
        // Axisymmetric bodies: the nodes on the axis keep u_r = 0 (whatever the boundaries say).
        for (bi, body) in scene.bodies.iter().enumerate() {
            if body.formulation != scene::Formulation::Axisymmetric {
                continue;
            }
            let nodes = m.bodies[bi].nodes.clone();
            let size = nodes.clone().fold(0.0f64, |s, n| {
                s.max(m.position[n][0].abs()).max(m.position[n][1].abs())
            });
            m.bodies[bi].axis_tolerance = Some(1e-12 * size);
            for n in nodes {
                if m.bodies[bi].on_axis(m.position[n]) {
                    let c = cons[n].get_or_insert(NodeConstraint::free(n as u32));
                    c.vx = Some(0.0);
                    c.cx = None;
                }
            }
        }
        m.constraints = cons.into_iter().flatten().collect();
        for c in &m.constraints {
            let v = &mut m.velocity[c.node as usize];
            if let Some(x) = c.vx {
                v[0] = x;
            }
            if let Some(y) = c.vy {
                v[1] = y;
            }
        }
        m.load_pressures(scene)?;
        // Contacts limited to named faces: each face must reach the body's boundary.
        for (i, c) in scene.contacts.iter().enumerate() {
            let Some(faces) = &c.surfaces else { continue };
            for (k, ((name, edges), &b)) in faces.iter().zip(&c.bodies).enumerate() {
                if Surface::of_body(&m, b)
                    .restricted(&m.global_edges(b, edges))
                    .segments
                    .is_empty()
                {
                    return Err(scene::invalid(
                        scene,
                        format!("contact[{i}].surfaces[{k}]"),
                        format!("{name:?}"),
                        &format!(
                            "none of the curve's edges is on the boundary of body {:?}",
                            scene.bodies[b].name
                        ),
                    ));
                }
            }
        }
        Ok(m)
    }

    /// Resolves the pressure loads of `scene` on the current reference positions (again after
    /// [`crate::contact::overlap::resolve`] moved nodes).
    ///
    /// # Errors
    /// [`crate::Error::Invalid`] when a load's box selects no boundary edge.
    pub fn load_pressures(&mut self, scene: &Scene) -> Result<()> {
        let m = self;
        m.pressures.clear();
        for p in &scene.pressures {
            let load = m.pressure_load(p, &scene.bodies[p.body]);
            if load.edges == 0 {
                let body = &scene.bodies[p.body].name;
                return Err(match &p.group {
                    Some(g) => scene::invalid(
                        scene,
                        format!("{}.region.group", p.key),
                        format!("{:?}", g.name),
                        &format!("none of the curve's edges is on the boundary of body {body:?}"),
                    ),
                    None => scene::invalid(
                        scene,
                        format!("{}.region", p.key),
                        format!("{{ min = {:?}, max = {:?} }}", p.min, p.max),
                        &format!(
                            "the box selects no boundary edge of body {body:?} (both end nodes \
                             of an edge must lie in the box)"
                        ),
                    ),
                });
            }
            m.pressures.push(load);
        }
        Ok(())
    }

    /// The nodal forces per unit pressure of `p`: on every boundary edge of its body whose two
    /// nodes lie in its box (reference coordinates, bounds included), `L t / 2` on each node along
    /// the edge's inward normal.
    fn pressure_load(&self, p: &scene::Pressure, body: &scene::Body) -> PressureLoad {
        let axi = body.formulation == scene::Formulation::Axisymmetric;
        // A named curve: the boundary segments among its own line elements.
        let surface = match &p.group {
            Some(g) => {
                Surface::of_body(self, p.body).restricted(&self.global_edges(p.body, &g.edges))
            }
            None => Surface::of_body(self, p.body),
        };
        let inside = |n: u32| {
            let x = self.position[n as usize];
            x[0] >= p.min[0] && x[0] <= p.max[0] && x[1] >= p.min[1] && x[1] <= p.max[1]
        };
        let mut force: std::collections::BTreeMap<u32, [f64; 2]> = Default::default();
        let mut edges = 0;
        for seg in &surface.segments {
            let [a, b] = seg.nodes;
            if !(inside(a) && inside(b)) {
                continue;
            }
            edges += 1;
            // Outward normal times length: (t_y, -t_x) with t = b - a (body on the left).
            let (xa, xb) = (self.position[a as usize], self.position[b as usize]);
            let t = [xb[0] - xa[0], xb[1] - xa[1]];
            // Per node: t / 2 (planar), or the integral of N r along the edge per radian,
            // (2 r_a + r_b) / 6 and (r_a + 2 r_b) / 6 (axisymmetric).
            let weights = if axi {
                [(2.0 * xa[0] + xb[0]) / 6.0, (xa[0] + 2.0 * xb[0]) / 6.0]
            } else {
                [0.5 * body.thickness; 2]
            };
            for (n, w) in [a, b].into_iter().zip(weights) {
                let e = force.entry(n).or_insert([0.0; 2]);
                e[0] -= w * t[1];
                e[1] += w * t[0];
            }
        }
        PressureLoad {
            value: p.value,
            ramp: p.ramp,
            curve: p.curve.clone(),
            nodes: force.into_iter().collect(),
            edges,
        }
    }

    /// Body `body`'s node pairs `edges` (indices within the body) in global node numbers.
    pub fn global_edges(&self, body: usize, edges: &[[u32; 2]]) -> Vec<[u32; 2]> {
        let start = self.bodies[body].nodes.start as u32;
        edges.iter().map(|e| [start + e[0], start + e[1]]).collect()
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.position.len()
    }

    /// Number of elements.
    pub fn element_count(&self) -> usize {
        self.quads.len()
    }

    /// The names of the contacts, then of the rigid walls: the interfaces in the order of the
    /// history's contact columns.
    pub fn interface_names(&self) -> Vec<String> {
        self.contacts
            .iter()
            .map(|c| c.name.clone())
            .chain(self.walls.iter().map(|w| w.name.clone()))
            .collect()
    }

    /// Whether the model has any contact or rigid wall.
    pub fn has_contact(&self) -> bool {
        !self.contacts.is_empty() || !self.walls.is_empty()
    }

    /// Parameters of element `e`.
    pub fn params(&self, e: usize) -> &ElementParams {
        &self.bodies[self.element_body[e] as usize].params
    }

    /// Reference geometry of element `e`, with its centre's radius for an axisymmetric body.
    pub fn geometry(&self, e: usize) -> QuadGeometry {
        let mut g = quad_geometry(&self.corners[e]);
        if let Some(&r) = self.radius.get(e) {
            g.radius = r;
        }
        g
    }

    /// The out-of-plane extent of element `e`: its body's thickness, or its centre's radius for
    /// an axisymmetric body (whose quantities are per radian).
    pub fn thickness(&self, e: usize) -> f64 {
        let p = self.params(e);
        if p.formulation == scene::Formulation::Axisymmetric {
            self.radius[e]
        } else {
            p.thickness
        }
    }

    /// Element `e` evaluated at rest at the nodal displacements `u` (no velocity, no step before)
    /// from the plastic state `plastic`: its static forces and stress.
    pub fn element_at(&self, e: usize, u: &[[f64; 2]], plastic: &PlasticState) -> ElementOut {
        evaluate_state(
            self.params(e),
            &self.geometry(e),
            &self.corners[e],
            &self.quads[e].map(|i| u[i as usize]),
            &[[0.0; 2]; 4],
            &Dissipation::default(),
            0.0,
            plastic,
        )
    }

    /// The elements' stable step at t = 0 (undeformed, at the initial velocities; without the
    /// safety factor) and the element that sets it; a NaN step (a degenerate element) is kept
    /// as the answer.
    pub fn initial_stable_step(&self) -> (f64, usize) {
        let mut best = (f64::INFINITY, 0);
        for e in 0..self.element_count() {
            let q = self.quads[e];
            let out = evaluate_with(
                self.params(e),
                &self.geometry(e),
                &self.corners[e],
                &[[0.0; 2]; 4],
                &q.map(|i| self.velocity[i as usize]),
                &Dissipation::default(),
                0.0,
            );
            if out.dt.is_nan() || out.dt < best.0 {
                best = (out.dt, e);
            }
        }
        best
    }

    /// The run's first step: the fixed step, else the safety factor times
    /// [`Model::initial_stable_step`] (the mass form of the penalty stiffness is set by it).
    pub fn initial_step(&self) -> f64 {
        self.time_step
            .unwrap_or_else(|| self.time_step_scale * self.initial_stable_step().0)
    }

    /// Gravity at time `t`: [`Model::gravity`] times min(t / ramp, 1).
    pub fn gravity_at(&self, t: f64) -> [f64; 2] {
        let f = if self.gravity_ramp > 0.0 {
            (t / self.gravity_ramp).clamp(0.0, 1.0)
        } else {
            1.0
        };
        [f * self.gravity[0], f * self.gravity[1]]
    }

    /// Whether a contact or rigid wall has friction (the history then has `friction_work` and
    /// the contacts' `.ft` columns).
    pub fn has_friction(&self) -> bool {
        self.contacts.iter().any(|c| c.friction > 0.0)
            || self.walls.iter().any(|w| w.friction > 0.0)
    }

    /// Whether a body is of a J2 plastic material (the solvers then keep a plastic state per
    /// element).
    pub fn has_plasticity(&self) -> bool {
        self.bodies
            .iter()
            .any(|b| b.params.model == crate::scene::MaterialModel::J2Plastic)
    }

    /// Whether a body's material has failure criteria (its elements may erode).
    pub fn has_failure(&self) -> bool {
        self.bodies.iter().any(|b| b.params.failure.is_some())
    }

    /// Whether elements may erode: a material with failure criteria, `run.erosion.inverted` or
    /// `run.erosion.min_time_step` (the plan's failure stage and the erosion state).
    pub fn has_erosion(&self) -> bool {
        self.has_failure() || self.erode_inverted || self.erode_min_dt > 0.0
    }

    /// Whether a body's material has Johnson-Cook damage (kept per element between steps).
    pub fn has_damage(&self) -> bool {
        self.bodies
            .iter()
            .any(|b| b.params.failure.is_some_and(|f| f.johnson_cook.is_some()))
    }
}
