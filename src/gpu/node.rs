//! Node stage kernel (`shaders/node.wgsl`): gathers nodal forces from the element slots in a fixed
//! order (deterministic, no atomics) and performs the central-difference update. The CPU reference
//! is the node stage of [`crate::step::cpu::CpuSolver`].

use super::shader::{compute_pipeline, Features};

/// WGSL source.
pub const SOURCE: &str = include_str!("../../shaders/node.wgsl");

/// Threads per workgroup.
pub const WORKGROUP: u32 = 64;

pub(crate) fn pipeline(device: &wgpu::Device, features: Features) -> wgpu::ComputePipeline {
    compute_pipeline(device, "node", SOURCE, features, "main", Some(WORKGROUP))
}

/// Node-to-element adjacency: for node i, `slots[offsets[i]..offsets[i+1]]` are the indices
/// `4 e + corner` of the element force slots that act on it, in ascending order, then the slots
/// `4 n_elements + k` of the extra forces `extra[k]` on node i (pressure entries), ascending.
pub fn adjacency(quads: &[[u32; 4]], nodes: usize, extra: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let mut count = vec![0u32; nodes + 1];
    for q in quads {
        for &n in q {
            count[n as usize + 1] += 1;
        }
    }
    for &n in extra {
        count[n as usize + 1] += 1;
    }
    for i in 0..nodes {
        count[i + 1] += count[i];
    }
    let offsets = count.clone();
    let mut fill = count;
    let mut slots = vec![0u32; 4 * quads.len() + extra.len()];
    for (e, q) in quads.iter().enumerate() {
        for (a, &n) in q.iter().enumerate() {
            slots[fill[n as usize] as usize] = (4 * e + a) as u32;
            fill[n as usize] += 1;
        }
    }
    for (k, &n) in extra.iter().enumerate() {
        slots[fill[n as usize] as usize] = (4 * quads.len() + k) as u32;
        fill[n as usize] += 1;
    }
    (offsets, slots)
}
