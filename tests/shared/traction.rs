//! The consistent boundary forces of a constant stress on a patch, shared by the CPU
//! (`tests/core/patch.rs`) and GPU (`tests/gpu.rs`) patch tests.
#![allow(dead_code)]

use std::collections::HashMap;

use ricochet::model::Model;

/// Number of elements sharing each edge (1 on the boundary); a triangle's collapsed side
/// (`[a, b, c, c]`) is no edge.
pub fn edge_count(model: &Model) -> HashMap<(u32, u32), usize> {
    let mut count: HashMap<(u32, u32), usize> = HashMap::new();
    for q in &model.quads {
        for a in 0..4 {
            let (i, j) = (q[a], q[(a + 1) % 4]);
            if i == j {
                continue;
            }
            *count.entry((i.min(j), i.max(j))).or_default() += 1;
        }
    }
    count
}

/// Expected nodal forces of a constant first Piola-Kirchhoff stress `p` (row-major 2x2) on the
/// reference patch of thickness `t`: on each boundary edge i -> j (counter-clockwise) with
/// outward normal times length N, the traction resultant t p N, split half and half between i
/// and j; the element forces are external minus internal, so minus that. Interior nodes get
/// zero.
pub fn traction_forces(model: &Model, p: [[f64; 2]; 2], t: f64) -> Vec<[f64; 2]> {
    let count = edge_count(model);
    let mut f = vec![[0.0; 2]; model.node_count()];
    for q in &model.quads {
        for a in 0..4 {
            let (i, j) = (q[a], q[(a + 1) % 4]);
            if i == j || count[&(i.min(j), i.max(j))] != 1 {
                continue;
            }
            let (pi, pj) = (model.position[i as usize], model.position[j as usize]);
            let n = [pj[1] - pi[1], -(pj[0] - pi[0])];
            let tr = [
                p[0][0] * n[0] + p[0][1] * n[1],
                p[1][0] * n[0] + p[1][1] * n[1],
            ];
            for k in [i, j] {
                f[k as usize][0] -= 0.5 * t * tr[0];
                f[k as usize][1] -= 0.5 * t * tr[1];
            }
        }
    }
    f
}

/// The nodes on no boundary edge.
pub fn interior(model: &Model) -> Vec<usize> {
    let mut boundary = vec![false; model.node_count()];
    for ((i, j), c) in edge_count(model) {
        if c == 1 {
            boundary[i as usize] = true;
            boundary[j as usize] = true;
        }
    }
    (0..model.node_count()).filter(|&i| !boundary[i]).collect()
}
