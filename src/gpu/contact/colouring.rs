//! The one-workgroup solve's compaction and colouring of its constraints on the device
//! (`shaders/contact_colour.wgsl`, `compact`, compiled into the solve's modules: [`SOURCE`]) and
//! its CPU reference: the step's Lagrange constraints coloured greedily in a hashed order of their slots
//! (on GPUs) or in slot order (on CPU adapters), each the first colour that its neighbours (the
//! constraints sharing a node with it) earlier in that order left free. The device computes the
//! first in Jones-Plassmann rounds, the second in one invocation, each in workgroup memory or
//! through storage; `tests/gpu/colouring.rs` compares all four with this.

use std::collections::HashMap;

/// WGSL source (compiled after [`super::narrow::SOURCE`], before [`super::solve::SOURCE`]).
pub const SOURCE: &str = include_str!("../../../shaders/contact_colour.wgsl");

/// The serial colour (WGSL `SERIAL`): a constraint that finds colours 0 to 31 taken.
pub const SERIAL: u32 = 32;
/// Where the partners of the 2 x 2 blocks are listed (WGSL `PARTNER`): after the serial colour,
/// each swept with its leader, never on its own.
pub const PARTNER: u32 = SERIAL + 1;
/// Pair code of a leader (WGSL `PAIR_LEADER`, per slot in the workspace): its partner's index
/// in the compacted list in the low bits ([`PAIR_INDEX`]).
pub const PAIR_LEADER: u32 = 0x8000_0000;
/// The low bits of a pair code: the other constraint's index in the compacted list.
pub const PAIR_INDEX: u32 = 0x3fff_ffff;

/// The hashed priority of slot `k` (WGSL `priority`, `shaders/contact_common.wgsl`: PCG's output
/// permutation), the order of the search's and the solve's colourings.
pub fn priority(k: u32) -> u32 {
    let mut x = k.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    x = ((x >> ((x >> 28) + 4)) ^ x).wrapping_mul(277_803_737);
    (x >> 22) ^ x
}

/// Whether slot `a` is coloured before slot `b` (WGSL `coloured_before`): the larger high 20
/// bits of its priority first, then the lower slot.
pub fn coloured_before(a: u32, b: u32) -> bool {
    let (ra, rb) = (priority(a) & 0xffff_f000, priority(b) & 0xffff_f000);
    ra > rb || (ra == rb && a < b)
}

/// The colours of `constraints`, each its slot and its nodes (slave, segment ends; `u32::MAX`
/// for a wall's missing segment), in the device's rule: in the order of [`coloured_before`]
/// (`hashed`, the parallel colouring) or of the slots, the first colour that none of its
/// neighbours coloured before it holds, [`SERIAL`] when colours 0 to 31 are all taken (a serial
/// constraint marks its nodes with colour 31).
pub fn colours(constraints: &[(u32, [u32; 3])], hashed: bool) -> Vec<u32> {
    colours_paired(constraints, &[], hashed)
}

/// [`colours`] with the 2 x 2 blocks `pairs` (leader's slot, partner's slot): a leader is
/// coloured as one constraint on the nodes of both, in its own place in the order, and its
/// partner takes [`PARTNER`].
pub fn colours_paired(
    constraints: &[(u32, [u32; 3])],
    pairs: &[(u32, u32)],
    hashed: bool,
) -> Vec<u32> {
    let index: HashMap<u32, usize> = constraints
        .iter()
        .enumerate()
        .map(|(i, c)| (c.0, i))
        .collect();
    let partner: HashMap<u32, u32> = pairs.iter().copied().collect();
    let partners: std::collections::HashSet<u32> = pairs.iter().map(|p| p.1).collect();
    let mut order: Vec<usize> = (0..constraints.len())
        .filter(|&i| !partners.contains(&constraints[i].0))
        .collect();
    order.sort_by(|&i, &j| {
        let (a, b) = (constraints[i].0, constraints[j].0);
        if a == b {
            std::cmp::Ordering::Equal
        } else if (hashed && coloured_before(a, b)) || (!hashed && a < b) {
            std::cmp::Ordering::Less
        } else {
            std::cmp::Ordering::Greater
        }
    });
    let mut masks: HashMap<u32, u32> = HashMap::new();
    let mut colour = vec![PARTNER; constraints.len()];
    for i in order {
        let mut unit = constraints[i].1.to_vec();
        if let Some(j) = partner.get(&constraints[i].0).and_then(|p| index.get(p)) {
            unit.extend_from_slice(&constraints[*j].1);
        }
        let nodes = unit.iter().filter(|&&n| n != u32::MAX);
        let used = nodes
            .clone()
            .fold(0u32, |m, n| m | masks.get(n).copied().unwrap_or(0));
        let c = if used == u32::MAX {
            SERIAL
        } else {
            (!used).trailing_zeros()
        };
        for &n in nodes {
            *masks.entry(n).or_insert(0) |= 1 << c.min(31);
        }
        colour[i] = c;
    }
    colour
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of constraints, each sharing a node with the next, and a wall constraint on a
    /// node of its own: a proper colouring (neighbours differ), the first free colour in the
    /// hashed order, the wall's constraint colour 0.
    #[test]
    fn a_chain_is_coloured_properly_in_the_hashed_order() {
        let chain: Vec<(u32, [u32; 3])> = (0..64u32)
            .map(|k| (k, [100 + k, k, k + 1]))
            .chain(std::iter::once((64, [500, u32::MAX, u32::MAX])))
            .collect();
        let c = colours(&chain, true);
        for k in 0..63 {
            assert_ne!(
                c[k],
                c[k + 1],
                "constraints {k} and {} share node {}",
                k + 1,
                k + 1
            );
        }
        assert_eq!(c[64], 0);
        assert!(
            c.iter().all(|&x| x < 3),
            "a path needs at most 3 colours: {c:?}"
        );
        // The first in the hashed order takes colour 0.
        let first = (0..64u32)
            .reduce(|a, b| if coloured_before(a, b) { a } else { b })
            .unwrap();
        assert_eq!(c[first as usize], 0);
    }

    /// 33 constraints on one node: colours 0 to 31, then the serial colour (in slot order, the
    /// slots' colours in turn).
    #[test]
    fn the_33rd_constraint_on_a_node_is_serial() {
        let star: Vec<(u32, [u32; 3])> = (0..33u32).map(|k| (k, [7, 100 + k, 200 + k])).collect();
        let expected: Vec<u32> = (0..32).chain(std::iter::once(SERIAL)).collect();
        assert_eq!(colours(&star, false), expected);
        let mut c = colours(&star, true);
        c.sort_unstable();
        assert_eq!(c, expected);
    }
}
