//! The bytes each GPU kernel of a step moves, by buffer: the element stage
//! (`shaders/element.wgsl`), the stable-step reduction (`reduce.wgsl`'s `min_dt`), the control
//! kernels (`control.wgsl`) and the node stage (`node.wgsl`), as their Rust rooms in
//! [`crate::gpu`] bind them. [`traffic`] lists them for a set of compiled features,
//! [`bytes_per_element_cycle`] adds them up, [`bound`] turns a bandwidth into the throughput it
//! allows, and [`table`] prints the bench block's list as the Markdown table of BENCHMARKS.md.
//! The record sizes come from the `#[repr(C)]` mirrors of [`crate::gpu::layout`]; the tests keep
//! the buffers and their access true to the kernels (naga's analysis of each entry point's
//! globals) and the committed table true to [`table`]. The CPU reference moves no bytes of its
//! own: this is the GPU's account only.
//!
//! The model counts what reaches memory once per step: a record read by several threads (the
//! node record gathered by the four elements around it, the uniform parameters, the body
//! table, the control block) is counted once, as the caches serve the others when the threads
//! that share it run close together (the generated meshes number their elements and nodes row
//! by row). A sample step (a history row due) moves more: the `sample_src` writes and the sums'
//! kernels, which run with no workgroups on the other steps.

use std::mem::size_of;

use crate::gpu::element::{GpuBody, GpuElement};
use crate::gpu::layout::{Control, Params};
use crate::gpu::shader::Features;

/// One buffer as one kernel of a step touches it.
#[derive(Debug, Clone, PartialEq)]
pub struct Traffic {
    /// The kernel (entry point) of the step: `element`, `min_dt`, `control_dt`, `node`,
    /// `control_end`.
    pub kernel: &'static str,
    /// The buffer's name in the kernel's WGSL.
    pub buffer: &'static str,
    /// The WGSL type of one record, with its size.
    pub record: String,
    /// The kernel reads it.
    pub reads: bool,
    /// The kernel writes it (atomics included).
    pub writes: bool,
    /// Bytes per element per step that reach memory (reads and writes together).
    pub per_element: u64,
    /// Bytes per node per step that reach memory.
    pub per_node: u64,
    /// How the figure is counted.
    pub note: &'static str,
}

/// The kernels of a step that [`traffic`] covers, in step order: (kernel, WGSL source, entry
/// point). The sums (`reduce.wgsl`'s `sum` and `sum_instances`) run on sample steps only.
pub const KERNELS: [(&str, &str, &str); 5] = [
    ("element", crate::gpu::element::SOURCE, "main"),
    ("min_dt", crate::gpu::reduce::SOURCE, "min_dt"),
    ("control_dt", crate::gpu::control::SOURCE, "control_dt"),
    ("node", crate::gpu::node::SOURCE, "main"),
    ("control_end", crate::gpu::control::SOURCE, "control_end"),
];

/// The features the bench block compiles ([`super::scene`]: linear elastic, plane strain,
/// viscous hourglass control and bulk viscosity, no loads, fields, plasticity or contact), on a
/// GPU (reductions of 256 threads).
pub fn block_features() -> Features {
    Features {
        dissipation: true,
        linear_elastic: true,
        neo_hookean: false,
        plane_stress: false,
        hourglass_stiffness: false,
        contact_springs: false,
        contact_friction: false,
        ..Features::default()
    }
}

const VEC4: u64 = size_of::<[f32; 4]>() as u64;
const VEC2: u64 = size_of::<[f32; 2]>() as u64;
const WORD: u64 = size_of::<f32>() as u64;

/// The buffers of every kernel of a (non-sample) step compiled with `features`, and the bytes
/// each moves per element and per node.
pub fn traffic(features: &Features) -> Vec<Traffic> {
    let element = size_of::<GpuElement>() as u64;
    // Dissipative state words (vec4) per element: WGSL `ES`.
    let es: u64 = if features.axisymmetric { 3 } else { 2 };
    let t = |kernel, buffer, record: String, rw: (bool, bool), per: (u64, u64), note| Traffic {
        kernel,
        buffer,
        record,
        reads: rw.0,
        writes: rw.1,
        per_element: per.0,
        per_node: per.1,
        note,
    };
    let params = || format!("Params ({} B)", size_of::<Params>());
    let ctrl = || format!("Control ({} B)", size_of::<Control>());
    let v4 = || format!("vec4<f32> ({VEC4} B)");
    let v2 = || format!("vec2<f32> ({VEC2} B)");
    let word = |ty: &str| format!("{ty} ({WORD} B)");
    const R: (bool, bool) = (true, false);
    const W: (bool, bool) = (false, true);
    const RW: (bool, bool) = (true, true);
    let mut v = vec![
        t(
            "element",
            "params",
            params(),
            R,
            (0, 0),
            "uniform: once a step",
        ),
        t(
            "element",
            "elems",
            format!("Element ({element} B)"),
            R,
            (element, 0),
            "the element's corners, nodes, body",
        ),
        t(
            "element",
            "bodies",
            format!("Body ({} B)", size_of::<GpuBody>()),
            R,
            (0, 0),
            "one per body: cached",
        ),
        t(
            "element",
            "nodes",
            v4(),
            R,
            (0, VEC4),
            "(u, v) of the 4 corners: each node once",
        ),
        t(
            "element",
            "v_prev",
            v2(),
            R,
            (0, 2 * VEC2),
            "the corners' velocity and displacement residuals",
        ),
    ];
    if features.dissipation {
        v.push(t(
            "element",
            "elem_state",
            v4(),
            RW,
            (2 * es * VEC4, 0),
            if features.axisymmetric {
                "3 vec4 read and written (hoop bulk stress)"
            } else {
                "2 vec4 read and written: (Q, works), bulk P"
            },
        ));
    }
    if features.plastic {
        v.push(t(
            "element",
            "plastic_state",
            v4(),
            RW,
            (2 * VEC4, 0),
            "2 vec4 read (J2 bodies); written only where it yields",
        ));
    }
    v.extend([
        t(
            "element",
            "elem_force",
            v2(),
            W,
            (4 * VEC2, 0),
            "the 4 corner forces",
        ),
        t(
            "element",
            "elem_dt",
            word("f32"),
            W,
            (WORD, 0),
            "stable step",
        ),
        t(
            "element",
            "ctrl",
            ctrl(),
            RW,
            (0, 0),
            "state, flags, dt; atomicMin on an inverted element",
        ),
        t(
            "element",
            "sample_src",
            v4(),
            W,
            (0, 0),
            "sample steps only (16 B per element)",
        ),
        t("min_dt", "params", params(), R, (0, 0), "uniform"),
        t(
            "min_dt",
            "elem_dt",
            word("f32"),
            R,
            (WORD, 0),
            "every element's step",
        ),
        t(
            "min_dt",
            "dt_partial",
            format!("vec2<u32> ({VEC2} B)"),
            W,
            (0, 0),
            "one per workgroup (at most 256)",
        ),
        t("control_dt", "params", params(), R, (0, 0), "uniform"),
        t("control_dt", "ctrl", ctrl(), RW, (0, 0), "one workgroup"),
        t(
            "control_dt",
            "dt_partial",
            format!("vec2<u32> ({VEC2} B)"),
            R,
            (0, 0),
            "at most 2 KiB a step",
        ),
        t(
            "control_dt",
            "elem_dt",
            word("f32"),
            R,
            (0, 0),
            "only where small models reduce here (CPU adapters)",
        ),
        t("node", "params", params(), R, (0, 0), "uniform"),
        t(
            "node",
            "nodes",
            v4(),
            RW,
            (0, 2 * VEC4),
            "(u, v) read and written",
        ),
        t("node", "inv_mass", word("f32"), R, (0, WORD), "1 / m"),
        t(
            "node",
            "adj_offsets",
            word("u32"),
            R,
            (0, WORD),
            "n_nodes + 1 offsets, each read by two threads",
        ),
        t(
            "node",
            "adj_slots",
            word("u32"),
            R,
            (4 * WORD, 0),
            "one slot per element corner",
        ),
        t(
            "node",
            "elem_force",
            v2(),
            R,
            (4 * VEC2, 0),
            "gathered through the slots, each once",
        ),
        t(
            "node",
            "v_prev",
            v2(),
            RW,
            (0, 4 * VEC2),
            "both residuals read and written (v^{n-1/2} on sample steps)",
        ),
        t(
            "node",
            "ctrl",
            ctrl(),
            RW,
            (0, 0),
            "dt, flags; atomicMin on a non-finite node",
        ),
        t(
            "node",
            "sample_src",
            v4(),
            W,
            (0, 0),
            "sample steps only (16 B per node)",
        ),
    ]);
    if features.fields {
        v.push(t(
            "node",
            "u_snap",
            v2(),
            W,
            (0, 0),
            "snapshot steps only (8 B per node)",
        ));
    }
    if features.loads {
        v.push(t(
            "node",
            "v_old",
            v2(),
            W,
            (0, VEC2),
            "v^{n-1/2} for the loads' work",
        ));
    }
    v.extend([
        t("control_end", "params", params(), R, (0, 0), "uniform"),
        t("control_end", "ctrl", ctrl(), RW, (0, 0), "one workgroup"),
        t(
            "control_end",
            "instances",
            "Instance (32 B)".into(),
            R,
            (0, 0),
            "sample steps only",
        ),
        t(
            "control_end",
            "history",
            word("f32"),
            W,
            (0, 0),
            "one row on sample steps",
        ),
        t(
            "control_end",
            "times",
            format!("vec2<u32> ({VEC2} B)"),
            R,
            (0, 0),
            "the next sample and snapshot times",
        ),
        t(
            "control_end",
            "indirect",
            word("u32"),
            W,
            (0, 0),
            "the sums' 24 B dispatch sizes",
        ),
        t(
            "control_end",
            "sample_src",
            v4(),
            R,
            (0, 0),
            "only where small models sum here (CPU adapters)",
        ),
        t(
            "control_end",
            "inst_res",
            v4(),
            RW,
            (0, 0),
            "sample steps only",
        ),
    ]);
    v
}

/// Bytes per element-cycle of `traffic` on a mesh of `nodes_per_element` nodes per element
/// (1 on a large block: (N + 1)^2 / N^2).
pub fn bytes_per_element_cycle(traffic: &[Traffic], nodes_per_element: f64) -> f64 {
    traffic
        .iter()
        .map(|t| t.per_element as f64 + t.per_node as f64 * nodes_per_element)
        .sum()
}

/// Bytes per step of the `kernels` of `traffic` on a mesh of `elements` elements and `nodes`
/// nodes.
pub fn bytes_per_step(traffic: &[Traffic], kernels: &[&str], elements: usize, nodes: usize) -> f64 {
    traffic
        .iter()
        .filter(|t| kernels.contains(&t.kernel))
        .map(|t| (t.per_element * elements as u64 + t.per_node * nodes as u64) as f64)
        .sum()
}

/// The bench block's bytes per element-cycle, nodes = elements (a large block).
pub fn block_bytes_per_element_cycle() -> f64 {
    bytes_per_element_cycle(&traffic(&block_features()), 1.0)
}

/// Element-cycles per second that `gb_per_s` (1e9 B/s) allows at `bytes` per element-cycle.
pub fn bound(gb_per_s: f64, bytes: f64) -> f64 {
    gb_per_s * 1e9 / bytes
}

/// The bench block's traffic as the Markdown table of BENCHMARKS.md: a row per kernel and
/// buffer, then each kernel's total per element-cycle (nodes = elements) and the step's.
pub fn table() -> String {
    let traffic = traffic(&block_features());
    let mut s = String::from(
        "| kernel | buffer | record | access | B / element | B / node | counted |\n\
         | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let access = |t: &Traffic| match (t.reads, t.writes) {
        (true, true) => "read, write",
        (true, false) => "read",
        _ => "write",
    };
    for t in &traffic {
        s.push_str(&format!(
            "| {} | `{}` | {} | {} | {} | {} | {} |\n",
            t.kernel,
            t.buffer,
            t.record,
            access(t),
            t.per_element,
            t.per_node,
            t.note
        ));
    }
    let mut kernels: Vec<&str> = Vec::new();
    for t in &traffic {
        if !kernels.contains(&t.kernel) {
            kernels.push(t.kernel);
        }
    }
    for k in kernels {
        let mine: Vec<Traffic> = traffic.iter().filter(|t| t.kernel == k).cloned().collect();
        let e: u64 = mine.iter().map(|t| t.per_element).sum();
        let n: u64 = mine.iter().map(|t| t.per_node).sum();
        s.push_str(&format!(
            "| **{k}** | | | | **{e}** | **{n}** | {} B per element-cycle |\n",
            bytes_per_element_cycle(&mine, 1.0)
        ));
    }
    s.push_str(&format!(
        "| **step** | | | | **{}** | **{}** | **{} B per element-cycle** |\n",
        traffic.iter().map(|t| t.per_element).sum::<u64>(),
        traffic.iter().map(|t| t.per_node).sum::<u64>(),
        bytes_per_element_cycle(&traffic, 1.0)
    ));
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;
    use std::path::Path;

    /// The storage and uniform buffers that entry point `entry` of `source` (compiled with
    /// `features`) uses, by name: (reads, writes), from naga's analysis.
    fn uses(source: &str, features: Features, entry: &str) -> BTreeMap<String, (bool, bool)> {
        use naga::valid::GlobalUse;
        let wgsl = crate::gpu::shader::source(source, features);
        let module = naga::front::wgsl::parse_str(&wgsl).expect("parses");
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .expect("validates");
        let index = module
            .entry_points
            .iter()
            .position(|e| e.name == entry)
            .unwrap_or_else(|| panic!("no entry point {entry}"));
        let function = info.get_entry_point(index);
        let mut out = BTreeMap::new();
        for (handle, global) in module.global_variables.iter() {
            let buffer = matches!(
                global.space,
                naga::AddressSpace::Uniform | naga::AddressSpace::Storage { .. }
            );
            let used = function[handle];
            if buffer && !used.is_empty() {
                let name = global.name.clone().unwrap_or_default();
                let writes = used.intersects(GlobalUse::WRITE | GlobalUse::ATOMIC);
                out.insert(name, (used.contains(GlobalUse::READ), writes));
            }
        }
        out
    }

    /// Every buffer that each kernel of the step uses is in the table with the access the
    /// kernel has, and nothing else is, for the block's features and the others'.
    #[test]
    fn the_traffic_lists_every_buffer_each_kernel_binds() {
        let block = block_features();
        for features in [
            block,
            Features {
                axisymmetric: true,
                plastic: true,
                ..block
            },
            Features {
                loads: true,
                fields: true,
                ..block
            },
            Features {
                dissipation: false,
                ..block
            },
        ] {
            let traffic = traffic(&features);
            for (kernel, source, entry) in KERNELS {
                let listed: BTreeMap<String, (bool, bool)> = traffic
                    .iter()
                    .filter(|t| t.kernel == kernel)
                    .map(|t| (t.buffer.to_string(), (t.reads, t.writes)))
                    .collect();
                let used = uses(source, features, entry);
                assert_eq!(listed, used, "{kernel} with {features:?}");
            }
        }
    }

    /// The per-element records are the mirrors' sizes, and the dissipative state's words the
    /// element kernel's `ES`.
    #[test]
    fn records_are_the_mirrors_sizes() {
        let traffic = traffic(&block_features());
        let get = |k: &str, b: &str| {
            traffic
                .iter()
                .find(|t| t.kernel == k && t.buffer == b)
                .unwrap_or_else(|| panic!("{k} {b}"))
                .clone()
        };
        assert_eq!(get("element", "elems").per_element, 64);
        assert_eq!(
            get("element", "elems").per_element,
            size_of::<GpuElement>() as u64
        );
        assert_eq!(get("element", "elem_state").per_element, 2 * 2 * 16);
        let wgsl = crate::gpu::shader::source(crate::gpu::element::SOURCE, block_features());
        assert!(wgsl.contains("const ES: u32 = 2u;"));
        let axi = crate::gpu::shader::source(
            crate::gpu::element::SOURCE,
            Features {
                axisymmetric: true,
                ..block_features()
            },
        );
        assert!(axi.contains("const ES: u32 = 3u;"));
        assert_eq!(block_bytes_per_element_cycle(), 320.0);
        assert_eq!(
            bytes_per_step(&traffic, &["element"], 10, 0),
            10.0 * (64 + 64 + 32 + 4) as f64
        );
        assert!((bound(3350.0, 320.0) - 1.046875e10).abs() < 1.0);
    }

    /// The bench block compiles the features of [`block_features`].
    #[test]
    fn the_block_compiles_the_block_features() {
        let scene = super::super::scene(4).expect("scene");
        let (model, plan) = super::super::scenes::build(&scene).expect("model");
        use crate::plan::Stage;
        use crate::scene::{Formulation, HourglassForm, MaterialModel};
        let f = block_features();
        assert_eq!(plan.has_dissipation(), f.dissipation);
        assert_eq!(plan.has(Stage::Fields), f.fields);
        assert!(!plan.has(Stage::Pressure) && !plan.has(Stage::MassDamping));
        assert!(!plan.has(Stage::Gravity) && !f.loads);
        assert_eq!(model.has_plasticity(), f.plastic);
        for b in &model.bodies {
            assert_eq!(b.params.model, MaterialModel::LinearElastic);
            assert_eq!(b.params.formulation, Formulation::PlaneStrain);
            assert_eq!(b.params.hourglass, HourglassForm::Viscous);
        }
        assert!(model.contacts.is_empty() && model.walls.is_empty());
    }

    /// BENCHMARKS.md holds the table that [`table`] prints.
    #[test]
    fn benchmarks_md_holds_the_table() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("BENCHMARKS.md");
        let text = std::fs::read_to_string(path).expect("BENCHMARKS.md");
        let table = table();
        assert!(
            text.contains(&table),
            "BENCHMARKS.md lacks the bytes table; it is now:\n{table}"
        );
    }
}
