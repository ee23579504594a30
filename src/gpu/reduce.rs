//! First level of the reductions (`shaders/reduce.wgsl`): the element stable-step minimum with its
//! element, and the sums of the sample instances. Each workgroup reads a strided set that depends
//! only on the sizes, and sums in a fixed tree, so results are bit-reproducible. The sums' second
//! level runs here too (`sum_instances`, one workgroup per instance, the same tree), the stable
//! step's in [`super::control`]. The lanes' shares and the trees are WGSL shared with
//! [`super::control`] (`shaders/reduce_common.wgsl`), the sum tree also with the contact reports
//! ([`TREE`]). CPU reference: [`sum_reference`].

use wgpu::{ComputePipeline, Device};

use super::shader::{compute_pipeline, Features};

/// WGSL source (the sum tree and the parts shared with [`super::control`] first).
pub const SOURCE: &str = concat!(
    include_str!("../../shaders/tree.wgsl"),
    include_str!("../../shaders/reduce_common.wgsl"),
    include_str!("../../shaders/reduce.wgsl")
);

/// The fixed-order sum over a workgroup's lanes (`shaders/tree.wgsl`): compiled before the
/// reductions, the run control and the contact reports, each of which sets its size `TREE`.
pub const TREE: &str = include_str!("../../shaders/tree.wgsl");

/// The pipeline of entry point `entry` (`min_dt`, `sum`, `sum_instances`).
pub(crate) fn pipeline(device: &Device, features: Features, entry: &str) -> ComputePipeline {
    compute_pipeline(device, entry, SOURCE, features, entry, None)
}

/// Workgroups of `rg` threads for a first-level reduction over `n` items (at most one per `rg`
/// items, at most `rg` so that one workgroup finishes the second level).
pub fn groups(n: usize, rg: u32) -> u32 {
    (n.div_ceil(rg as usize)).clamp(1, rg as usize) as u32
}

/// CPU reference of the fixed-order sum: the same strides and tree as the kernels, in f32.
pub fn sum_reference(items: &[[f32; 4]], groups: u32, rg: u32) -> [f32; 4] {
    let rg = rg as usize;
    let g = groups as usize;
    let mut partial = vec![[0f32; 4]; g];
    for (w, p) in partial.iter_mut().enumerate() {
        let mut lanes = vec![[0f32; 4]; rg];
        for (l, lane) in lanes.iter_mut().enumerate() {
            let mut j = w * rg + l;
            while j < items.len() {
                for c in 0..4 {
                    lane[c] += items[j][c];
                }
                j += g * rg;
            }
        }
        *p = tree(lanes);
    }
    let mut lanes = vec![[0f32; 4]; rg];
    lanes[..g].copy_from_slice(&partial);
    tree(lanes)
}

fn tree(mut lanes: Vec<[f32; 4]>) -> [f32; 4] {
    let mut s = lanes.len() / 2;
    while s > 0 {
        for l in 0..s {
            for c in 0..4 {
                lanes[l][c] += lanes[l + s][c];
            }
        }
        s /= 2;
    }
    lanes[0]
}
