//! Overlaps at t = 0: slave nodes that start behind a contact surface or a wall are moved onto
//! it in the reference configuration (so without strain, and so without energy) before the run;
//! overlaps deeper than half a contact segment are refused.

use super::rules::project;
use super::{broad, ContactSet};
use crate::error::Result;
use crate::geometry::{element_centre, min_corner_ratio, quad_geometry};
use crate::model::surface::Surface;
use crate::model::{Model, Overlap};
use crate::scene::{self, Scene};

impl ContactSet {
    /// Whether pass `p` is a group's.
    fn is_group(&self, p: usize) -> bool {
        self.passes.get(p).is_some_and(|p| p.group)
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
                let mut worst: Option<(f64, [f64; 2], u32)> = None;
                while k < p.candidates.len() && p.candidates[k].0 == si {
                    let j = p.candidates[k].1 as usize;
                    let [a, b] = p.segments[j];
                    let x = &self.x_n;
                    if let Some(pr) = project(
                        x[s as usize],
                        x[a as usize],
                        x[b as usize],
                        self.on_axis([a, b]),
                    ) {
                        if pr.gap < 0.0
                            && pr.gap > -0.5 * pr.length
                            && worst.is_none_or(|w| pr.gap > w.0)
                        {
                            worst = Some((pr.gap, pr.normal, p.segment_body[j]));
                        }
                    }
                    k += 1;
                }
                if let Some((g, normal, master)) = worst {
                    out.push(Overlap {
                        interface: self.interfaces[p.interface].name.clone(),
                        node: self.nodes[s as usize],
                        depth: -g,
                        normal,
                        pass: Some(pi),
                        bodies: Some([p.slave_body[si as usize], master]),
                    });
                }
            }
        }
        for w in &self.walls {
            for &l in &w.nodes {
                let g = super::dot(super::sub(self.x_n[l as usize], w.point), w.normal);
                if g < 0.0 {
                    out.push(Overlap {
                        interface: self.interfaces[w.interface].name.clone(),
                        node: self.nodes[l as usize],
                        depth: -g,
                        normal: w.normal,
                        pass: None,
                        bodies: None,
                    });
                }
            }
        }
        self.searched = false;
        out
    }
}

/// Moves the slave nodes of `model` that start behind a contact surface or a wall onto it, in the
/// reference configuration, and records what was moved in [`Model::initial_overlaps`] (touching
/// bodies at rest then stay at rest; nodal masses are kept, the moves being small against the
/// elements); then refuses overlaps deeper than half a contact segment. Call once, on the model
/// of a run, before anything else reads its positions (see [`crate::run::model`]).
///
/// # Errors
/// [`crate::Error::Invalid`] naming the element a move would invert, or the node left inside
/// another body's element.
pub fn resolve(model: &mut Model, scene: &Scene) -> Result<()> {
    if !model.has_contact() {
        return Ok(());
    }
    let moved_any = remove(model, scene)?;
    if moved_any {
        // The pressure loads act on the moved reference edges.
        model.load_pressures(scene)?;
    }
    refuse_deep(model, scene)
}

/// Moves slave nodes that start behind a contact surface or a wall onto it, in the reference
/// configuration (so without strain, and so without energy), and records what was moved in
/// [`Model::initial_overlaps`]. Touching bodies at rest then stay at rest. Nodal masses are
/// kept (the moves are small against the elements).
fn remove(model: &mut Model, scene: &Scene) -> Result<bool> {
    let mut moved_any = false;
    // Moving one body's nodes can uncover another's (two-pass): a few rounds.
    for _ in 0..4 {
        let Some(mut set) = ContactSet::new(model) else {
            return Ok(moved_any);
        };
        let found = set.initial_overlaps(model);
        if found.is_empty() {
            break;
        }
        // Walls, and one contact pass per round: the reverse pass of a two-pass contact
        // then finds its nodes on the moved surface instead of moving them apart again. A
        // group's pass is both directions at once: its nodes of a later body behind an earlier
        // body's surface first (and self-contact), then the others.
        let round = |o: &Overlap| {
            o.pass.map(|p| {
                let later_first = o.bodies.is_some_and(|[s, m]| s < m);
                (p, set.is_group(p) && later_first)
            })
        };
        let first = found.iter().filter_map(round).min();
        let found: Vec<Overlap> = found
            .into_iter()
            .filter(|o| o.pass.is_none() || round(o) == first)
            .collect();
        let mut moved = vec![false; model.position.len()];
        for o in &found {
            let i = o.node as usize;
            if moved[i] {
                continue;
            }
            moved[i] = true;
            moved_any = true;
            let p = &mut model.position[i];
            p[0] += o.depth * o.normal[0];
            p[1] += o.depth * o.normal[1];
        }
        for (e, q) in model.quads.iter().enumerate() {
            if !q.iter().any(|&n| moved[n as usize]) {
                continue;
            }
            let x = q.map(|n| model.position[n as usize]);
            let g = quad_geometry(&x);
            if !(g.area > 0.0 && min_corner_ratio(&x, g.area) > 1e-8) {
                let b = model.element_body[e] as usize;
                return Err(scene::invalid(
                    scene,
                    format!("body[{b}].mesh"),
                    format!("element {}", e - model.bodies[b].elements.start),
                    "moving the nodes that overlap a contact surface at t = 0 onto it inverts this element: separate the bodies",
                ));
            }
            let [cx, cy] = element_centre(&x);
            model.corners[e] = x.map(|p| [p[0] - cx, p[1] - cy]);
        }
        model.initial_overlaps.extend(found);
    }
    Ok(moved_any)
}

/// After the overlap removal: a slave node still inside an element of its master body is
/// deeper than half a contact segment (the contact cannot tell from which side it came, and
/// would leave it there for the whole run, reporting no penetration): an error naming it.
fn refuse_deep(model: &Model, scene: &Scene) -> Result<()> {
    for (ci, c) in model.contacts.iter().enumerate() {
        // (slave bodies, master bodies) per direction; within a group every body against the
        // others (a node inside its own body's element is not an overlap).
        let dirs: Vec<(Vec<usize>, Vec<usize>)> = if c.group {
            vec![(c.bodies.clone(), c.bodies.clone())]
        } else {
            let mut d = vec![(vec![c.bodies[0]], vec![c.bodies[1]])];
            if c.two_pass {
                d.push((vec![c.bodies[1]], vec![c.bodies[0]]));
            }
            d
        };
        for (slaves, masters) in dirs {
            let mut nodes: Vec<(u32, usize)> = Vec::new();
            for &b in &slaves {
                nodes.extend(Surface::of_body(model, b).nodes.into_iter().map(|n| (n, b)));
            }
            let elements: Vec<(usize, usize)> = masters
                .iter()
                .flat_map(|&b| model.bodies[b].elements.clone().map(move |e| (e, b)))
                .collect();
            let corners: Vec<[[f64; 2]; 4]> = elements
                .iter()
                .map(|&(e, _)| model.quads[e].map(|n| model.position[n as usize]))
                .collect();
            let points: Vec<[f64; 2]> = nodes
                .iter()
                .map(|&(n, _)| model.position[n as usize])
                .collect();
            for (k, local) in broad::points_in_boxes(&points, &corners) {
                let ((n, slave), (e, master)) = (nodes[k], elements[local]);
                if slave == master {
                    continue;
                }
                let x = corners[local];
                // Inside by more than round-off: the moved nodes lie on the surface.
                let tol = 1e-6 * quad_geometry(&x).area.abs().sqrt();
                let depth = inside_depth(&x, model.position[n as usize]);
                if depth > tol {
                    let (sb, mb) = (&model.bodies[slave], &model.bodies[master]);
                    return Err(scene::invalid(
                        scene,
                        format!("contact[{ci}]"),
                        format!("{:?}", c.name),
                        &format!(
                            "at t = 0, node {} of body {:?} lies inside element {} of body {:?} \
                             (at least {depth:.3e} m from that element's sides), deeper than half \
                             a contact segment: such an overlap is not removed and contact \
                             would leave the node inside for the whole run; separate the bodies",
                            n as usize - sb.nodes.start,
                            sb.name,
                            e - mb.elements.start,
                            mb.name
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// How far `p` lies inside the convex counter-clockwise quad `x`: the smallest distance to the
/// lines of its sides (negative or zero outside or on the boundary).
fn inside_depth(x: &[[f64; 2]; 4], p: [f64; 2]) -> f64 {
    let mut depth = f64::INFINITY;
    for a in 0..4 {
        let (s, t) = (x[a], x[(a + 1) % 4]);
        let d = [t[0] - s[0], t[1] - s[1]];
        let l = d[0].hypot(d[1]);
        if l > 0.0 {
            // Left of s -> t is inside.
            depth = depth.min((d[0] * (p[1] - s[1]) - d[1] * (p[0] - s[0])) / l);
        }
    }
    depth
}
