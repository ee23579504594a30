//! Body surfaces: the boundary edges of a body's mesh, with outward normals, and its boundary
//! nodes, on which the pressure loads act ([`super::PressureLoad`]) and the contacts are built
//! ([`crate::contact`]). Computed once on the CPU; the GPU kernels receive the result as the
//! pressure loads' nodal forces and the contact tables ([`crate::contact::Tables`]).

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

    /// Extracts the surface of body `body`: the edges used by exactly one of its elements.
    pub fn of_body(model: &Model, body: usize) -> Surface {
        let b = &model.bodies[body];
        let mut edges: Vec<([u32; 2], [u32; 2], u32)> = Vec::new();
        for e in b.elements.clone() {
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
            if m - k == 1 {
                segments.push(Segment {
                    nodes: edges[k].1,
                    element: edges[k].2,
                });
            }
            k = m;
        }
        segments.sort_by_key(|s| (s.element, s.nodes));
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

/// Reference length of a segment.
pub fn length(model: &Model, s: &Segment) -> f64 {
    let a = model.position[s.nodes[0] as usize];
    let b = model.position[s.nodes[1] as usize];
    (b[0] - a[0]).hypot(b[1] - a[1])
}
