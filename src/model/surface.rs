//! Body surfaces: the boundary edges of a body's mesh, with outward normals, and its boundary
//! nodes, on which the pressure loads act ([`super::PressureLoad`]) and the contacts are built
//! ([`crate::contact`]). Computed once on the CPU; the GPU kernels receive the result as the
//! pressure loads' nodal forces and the contact tables ([`crate::contact::Tables`]).
//!
//! A body whose elements can fail has a surface that changes as they erode: [`EdgeCandidates`]
//! holds every edge of its elements once, in a fixed order, with the element across it, so that
//! the surface at any time is that list under a mask (an edge is exposed when its element
//! remains and the one across it does not), the form a GPU twin keeps
//! ([`crate::contact::erosion`] says how). [`Surface::of_remaining`] is the same surface computed
//! from scratch, against which it is tested.
//!
//! The edges on the axis of an axisymmetric body (both nodes at r = 0) are not part of its
//! surface: nothing reaches them from the other side (r >= 0), and a node on the axis would find
//! such an edge at zero distance along the one direction it cannot move (u_r = 0), so that it
//! took no constraint from the segments beside it and could pass into the body.

use super::Model;

/// A boundary edge of a body, oriented so that the body lies on its left (the counter-clockwise
/// order of its quad): the outward normal of `a -> b` is `(t_y, -t_x) / |t|` with `t = b - a`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Global node indices (a, b).
    pub nodes: [u32; 2],
    /// The element the edge belongs to.
    pub element: u32,
}

/// One body's contact surface.
#[derive(Debug, Clone)]
pub struct Surface {
    /// The body.
    pub body: usize,
    /// Boundary nodes (global indices, ascending).
    pub nodes: Vec<u32>,
    /// Boundary edges, in element order.
    pub segments: Vec<Segment>,
}

impl Surface {
    /// The part of this surface on `edges` (global node pairs, either direction): the segments
    /// among them and their nodes (a named face of a Gmsh body).
    pub fn restricted(mut self, edges: &[[u32; 2]]) -> Surface {
        let set: std::collections::HashSet<(u32, u32)> = edges
            .iter()
            .flat_map(|e| [(e[0], e[1]), (e[1], e[0])])
            .collect();
        self.segments
            .retain(|seg| set.contains(&(seg.nodes[0], seg.nodes[1])));
        let mut nodes: Vec<u32> = self.segments.iter().flat_map(|seg| seg.nodes).collect();
        nodes.sort_unstable();
        nodes.dedup();
        self.nodes = nodes;
        self
    }

    /// Extracts the surface of body `body`: the edges used by exactly one of its elements (less
    /// those on the axis of an axisymmetric body).
    pub fn of_body(model: &Model, body: usize) -> Surface {
        Surface::of_remaining(model, body, &[])
    }

    /// The surface of body `body`'s elements that have not eroded (`eroded`: per global
    /// element; empty, or shorter than the elements, for none), from scratch: the edges used by
    /// exactly one of them (less those on the axis of an axisymmetric body).
    pub fn of_remaining(model: &Model, body: usize, eroded: &[bool]) -> Surface {
        let b = &model.bodies[body];
        let axial = |i: u32, j: u32| on_axis(model, body, [i, j]);
        let mut edges: Vec<([u32; 2], [u32; 2], u32)> = Vec::new();
        for e in b.elements.clone() {
            if eroded.get(e) == Some(&true) {
                continue;
            }
            let q = model.quads[e];
            for a in 0..4 {
                let (i, j) = (q[a], q[(a + 1) % 4]);
                if i == j {
                    // The collapsed side of a triangle.
                    continue;
                }
                edges.push(([i.min(j), i.max(j)], [i, j], e as u32));
            }
        }
        edges.sort_by_key(|x| x.0);
        let mut segments = Vec::new();
        let mut k = 0;
        while k < edges.len() {
            let mut m = k + 1;
            while m < edges.len() && edges[m].0 == edges[k].0 {
                m += 1;
            }
            if m - k == 1 && !axial(edges[k].1[0], edges[k].1[1]) {
                segments.push(Segment {
                    nodes: edges[k].1,
                    element: edges[k].2,
                });
            }
            k = m;
        }
        segments.sort_by_key(|s| (s.element, s.nodes));
        Surface::of_segments(body, segments)
    }

    /// The surface of body `body` made of `segments` (in their order), with their nodes.
    fn of_segments(body: usize, segments: Vec<Segment>) -> Surface {
        let mut nodes: Vec<u32> = segments.iter().flat_map(|s| s.nodes).collect();
        nodes.sort_unstable();
        nodes.dedup();
        Surface {
            body,
            nodes,
            segments,
        }
    }
}

/// No element across an edge (a boundary edge of the mesh), in [`EdgeCandidates::across`].
pub const NONE: u32 = u32::MAX;

/// Every edge of a body's elements, once per element that has it: the fixed candidate list of
/// its surface while its elements erode ([`EdgeCandidates::exposed`] is the mask).
#[derive(Debug, Clone)]
pub struct EdgeCandidates {
    /// The body.
    pub body: usize,
    /// Every element edge, oriented as in its element (the element on its left), sorted by
    /// element and nodes as [`Surface::segments`]; the collapsed side of a triangle and the
    /// edges on the axis of an axisymmetric body (never exposed) left out.
    pub edges: Vec<Segment>,
    /// The element across each edge ([`NONE`]: none, an edge of the mesh's boundary).
    pub across: Vec<u32>,
    /// The candidate of the element across with the same two nodes ([`NONE`]: none).
    twin: Vec<u32>,
    /// Per node of the body (from `nodes.start`): the range of its elements in `node_elements`.
    node_start: Vec<u32>,
    /// The elements of each node, node after node.
    node_elements: Vec<u32>,
    /// The body's first global node.
    first_node: u32,
}

impl EdgeCandidates {
    /// The candidate edges of body `body` of `model`.
    pub fn of_body(model: &Model, body: usize) -> EdgeCandidates {
        let b = &model.bodies[body];
        let mut edges: Vec<([u32; 2], Segment)> = Vec::new();
        let nn = b.nodes.len();
        let mut count = vec![0u32; nn + 1];
        for e in b.elements.clone() {
            let q = model.quads[e];
            let mut seen: Vec<u32> = Vec::with_capacity(4);
            for a in 0..4 {
                let (i, j) = (q[a], q[(a + 1) % 4]);
                if !seen.contains(&i) {
                    seen.push(i);
                    count[i as usize - b.nodes.start + 1] += 1;
                }
                if i == j || on_axis(model, body, [i, j]) {
                    continue;
                }
                let seg = Segment {
                    nodes: [i, j],
                    element: e as u32,
                };
                edges.push(([i.min(j), i.max(j)], seg));
            }
        }
        // Elements by node (compressed rows).
        for k in 0..nn {
            count[k + 1] += count[k];
        }
        let node_start = count.clone();
        let mut node_elements = vec![0u32; count[nn] as usize];
        let mut fill = count;
        for e in b.elements.clone() {
            let q = model.quads[e];
            let mut seen: Vec<u32> = Vec::with_capacity(4);
            for &i in &q {
                if !seen.contains(&i) {
                    seen.push(i);
                    let k = i as usize - b.nodes.start;
                    node_elements[fill[k] as usize] = e as u32;
                    fill[k] += 1;
                }
            }
        }
        // The element across each edge: the other element with the same node pair.
        edges.sort_by_key(|x| (x.0, x.1.element));
        let mut across = vec![NONE; edges.len()];
        let mut k = 0;
        while k < edges.len() {
            let mut m = k + 1;
            while m < edges.len() && edges[m].0 == edges[k].0 {
                m += 1;
            }
            if m - k == 2 {
                across[k] = edges[k + 1].1.element;
                across[k + 1] = edges[k].1.element;
            }
            k = m;
        }
        let mut order: Vec<usize> = (0..edges.len()).collect();
        order.sort_by_key(|&i| (edges[i].1.element, edges[i].1.nodes));
        // Each edge's twin (same node pair, the element across), in the final order.
        let mut position = vec![0u32; edges.len()];
        for (new, &old) in order.iter().enumerate() {
            position[old] = new as u32;
        }
        let mut twin = vec![NONE; edges.len()];
        let mut k = 0;
        while k + 1 < edges.len() {
            if edges[k].0 == edges[k + 1].0 && across[k] != NONE {
                twin[position[k] as usize] = position[k + 1];
                twin[position[k + 1] as usize] = position[k];
                k += 2;
            } else {
                k += 1;
            }
        }
        EdgeCandidates {
            body,
            edges: order.iter().map(|&i| edges[i].1).collect(),
            across: order.iter().map(|&i| across[i]).collect(),
            twin,
            node_start,
            node_elements,
            first_node: b.nodes.start as u32,
        }
    }

    /// The mask: whether candidate `k` lies on the surface when the elements flagged in
    /// `eroded` (per global element) have eroded: its element remains and the one across it
    /// does not (or there is none).
    #[inline]
    pub fn exposed(&self, k: usize, eroded: &[bool]) -> bool {
        let gone = |e: u32| eroded.get(e as usize) == Some(&true);
        let a = self.across[k];
        !gone(self.edges[k].element) && (a == NONE || gone(a))
    }

    /// The surface under the mask: the exposed candidates in their order, and their nodes.
    pub fn surface(&self, eroded: &[bool]) -> Surface {
        let segments: Vec<Segment> = (0..self.edges.len())
            .filter(|&k| self.exposed(k, eroded))
            .map(|k| self.edges[k])
            .collect();
        Surface::of_segments(self.body, segments)
    }

    /// The elements of global node `g` (none where `g` is not a node of the body).
    pub fn elements_of(&self, g: u32) -> &[u32] {
        let Some(k) = g.checked_sub(self.first_node).map(|k| k as usize) else {
            return &[];
        };
        match (self.node_start.get(k), self.node_start.get(k + 1)) {
            (Some(&a), Some(&b)) => &self.node_elements[a as usize..b as usize],
            _ => &[],
        }
    }

    /// The body's free nodes (ascending): nodes of elements that have all eroded, left as free
    /// masses.
    pub fn free_nodes(&self, eroded: &[bool]) -> Vec<u32> {
        (0..self.node_start.len() - 1)
            .map(|k| self.first_node + k as u32)
            .filter(|&g| {
                let els = self.elements_of(g);
                !els.is_empty() && els.iter().all(|&e| eroded.get(e as usize) == Some(&true))
            })
            .collect()
    }
}

/// The surface and free nodes of an erodible body under a mask that changes a few elements at a
/// time: [`EdgeCandidates::surface`] and [`EdgeCandidates::free_nodes`] kept up to date by
/// [`EdgeCandidates::update`] in the size of the change, not of the body.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Exposure {
    /// The exposed candidates (indices into [`EdgeCandidates::edges`]).
    exposed: std::collections::BTreeSet<u32>,
    /// The free nodes (global).
    free: std::collections::BTreeSet<u32>,
}

impl EdgeCandidates {
    /// The exposure under `eroded` (per global element), from scratch.
    pub fn exposure(&self, eroded: &[bool]) -> Exposure {
        Exposure {
            exposed: (0..self.edges.len())
                .filter(|&k| self.exposed(k, eroded))
                .map(|k| k as u32)
                .collect(),
            free: self.free_nodes(eroded).into_iter().collect(),
        }
    }

    /// Brings `x` to `eroded` after the elements `changed` (global; those of other bodies are
    /// passed over) changed their flag: their edges and the twins of them are masked again,
    /// their nodes (corners `quads`) checked for freedom again.
    pub fn update(&self, x: &mut Exposure, changed: &[u32], eroded: &[bool], quads: &[[u32; 4]]) {
        for &e in changed {
            let from = self.edges.partition_point(|s| s.element < e);
            let to = self.edges.partition_point(|s| s.element <= e);
            for k in from..to {
                for j in [k as u32, self.twin[k]] {
                    if j == NONE {
                        continue;
                    }
                    if self.exposed(j as usize, eroded) {
                        x.exposed.insert(j);
                    } else {
                        x.exposed.remove(&j);
                    }
                }
            }
            if from == to && self.elements_of(quads[e as usize][0]).is_empty() {
                // Not an element of this body.
                continue;
            }
            for &g in &quads[e as usize] {
                let els = self.elements_of(g);
                if !els.is_empty() && els.iter().all(|&f| eroded.get(f as usize) == Some(&true)) {
                    x.free.insert(g);
                } else {
                    x.free.remove(&g);
                }
            }
        }
    }

    /// The surface of `x`: as [`EdgeCandidates::surface`] under its mask.
    pub fn surface_of(&self, x: &Exposure) -> Surface {
        let segments = x.exposed.iter().map(|&k| self.edges[k as usize]).collect();
        Surface::of_segments(self.body, segments)
    }

    /// The free nodes of `x` (ascending): as [`EdgeCandidates::free_nodes`].
    pub fn free_of(&self, x: &Exposure) -> Vec<u32> {
        x.free.iter().copied().collect()
    }
}

/// Whether the edge between the global nodes `nodes` of body `body` lies on the axis of an
/// axisymmetric body (both ends at r = 0).
fn on_axis(model: &Model, body: usize, nodes: [u32; 2]) -> bool {
    let b = &model.bodies[body];
    nodes.iter().all(|&n| b.on_axis(model.position[n as usize]))
}

/// Reference length of a segment.
pub fn length(model: &Model, s: &Segment) -> f64 {
    let a = model.position[s.nodes[0] as usize];
    let b = model.position[s.nodes[1] as usize];
    (b[0] - a[0]).hypot(b[1] - a[1])
}
