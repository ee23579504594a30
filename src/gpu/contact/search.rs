//! Contact search on the device (`shaders/contact_search.wgsl`): positions of the step, whether a
//! search is due, the hashed uniform grid over the swept segment boxes, candidate lists per slot,
//! the node adjacency and the Jones-Plassmann colouring of the slots. CPU reference of the
//! candidates: [`crate::contact`]'s parry broad phase (the GPU's candidates are a superset of the
//! pairs it activates; tested); of the colouring: [`coloring_is_proper`].

/// WGSL source.
pub const SOURCE: &str = include_str!("../../../shaders/contact_search.wgsl");

/// Indirect-argument entries of the search kernels, in dispatch order (WGSL `plan`).
pub(crate) const ENTRIES: [&str; 14] = [
    "boxes",
    "seg_count",
    "scan_buckets",
    "seg_fill",
    "slot_count",
    "scan_slots",
    "slot_fill",
    "adj_count",
    "scan_nodes",
    "adj_fill",
    "adj_sort",
    "color_round",
    "list_count",
    "list_fill",
];

/// Whether `color` (one per slot) is a proper colouring of the slots whose touched nodes are
/// `touched` (a slot's slave and its candidates' nodes): no two slots of one colour share a node.
pub fn coloring_is_proper(touched: &[Vec<u32>], color: &[u32]) -> bool {
    let mut seen: std::collections::HashMap<(u32, u32), usize> = std::collections::HashMap::new();
    for (k, set) in touched.iter().enumerate() {
        let mut nodes = set.clone();
        nodes.sort_unstable();
        nodes.dedup();
        for n in nodes {
            if let Some(&other) = seen.get(&(n, color[k])) {
                if other != k {
                    return false;
                }
            }
            seen.insert((n, color[k]), k);
        }
    }
    true
}
