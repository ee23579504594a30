//! Contact on the device, compiled, allocated and dispatched only for scenes with contact or
//! rigid walls. The step's CONTACT stage, by file (each beside its WGSL kernel, and each owning its
//! pipelines and its dispatches):
//!
//! - [`search`]: positions of the step, whether a search is due, candidates from a hashed uniform
//!   grid, the active slots (those that can touch before the next search: a pass slot with
//!   candidates, a wall slot within the margin of its wall) and a colouring of the slots, all on
//!   the device (no readback of the nodes);
//! - [`narrow`]: each active slot's constraint, the penalty impulses and the Lagrange warm starts;
//! - [`solve`]: the diagonal-mass Lagrange correction (projected Gauss-Seidel by colours, in one
//!   workgroup or one dispatch per colour) and the active-set update; [`colouring`] the
//!   one-workgroup solve's compaction and colouring of its constraints (a stage file of the
//!   solve's modules) and their CPU reference;
//! - [`report`]: corrected velocities, u_{n+1}, the impulses' work and the interface reports;
//! - [`one`]: on CPU adapters with a small contact set, the stage in two one-workgroup dispatches
//!   (before and after the search) instead of eight.
//! - [`erosion`]: in a scene with failure, the fixed candidate lists under a mask and how they
//!   follow the elements that erode (the host, between two halves of the step that eroded them).
//!
//! Beside them, [`kernels`] holds the compiled kernels of every stage and their layouts,
//! [`tables`] the contact set's static tables and [`options`] the choice of path. This file holds what the stages share: the parameters ([`ContactParams`], with the
//! workspace offsets), the contact state ([`ContactState`]: the buffers, the one bind group every
//! contact kernel binds, built once with one explicit layout, and the host's view of the
//! counters) and the order of the stages in a step ([`ContactState::record_parts`]). The host
//! reads back only the contact counters with each batch's control block; a search that needs more
//! candidate room or more colouring rounds stops the step before it changed anything, and
//! `ContactState::grow` enlarges what is needed and resumes the step. CPU reference:
//! [`crate::contact::ContactSet::apply`].

pub mod colouring;
pub mod erosion;
pub mod kernels;
pub mod narrow;
pub mod one;
pub mod options;
pub mod report;
pub mod search;
pub mod solve;
pub mod tables;

pub use crate::gpu::shader::local_constraints;
pub use kernels::{stage_source, ContactKernels, MODULES};
pub(crate) use options::Path;
pub use options::{
    local_sweeps, one_group, pair_blocks, parallel_colouring, ContactOptions, SearchSwitch,
};

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::contact::erosion::Masked;
use crate::contact::ContactSet;
use crate::error::{Error, Result};
use crate::model::Model;

use super::alloc::Alloc;
use tables::{GpuSegment, GpuSlot};

/// Shared WGSL declarations of the contact kernels.
pub const COMMON: &str = include_str!("../../../shaders/contact_common.wgsl");

/// Control state set when a contact buffer must grow (WGSL `STATE_SEARCH_GROW`).
pub const STATE_SEARCH_GROW: u32 = 4;
/// Control state set when elements eroded in a scene with contact (WGSL `STATE_ERODED`): the
/// host moves the surfaces (`ContactState::follow_erosion`) and resumes the step.
pub const STATE_ERODED: u32 = 5;

/// [`ContactState::record_parts`]: the node preparation and the search plan.
pub const PART_PREP: u32 = 1;
/// [`ContactState::record_parts`]: the search kernels (empty dispatches when none is due).
pub const PART_SEARCH: u32 = 2;
/// [`ContactState::record_parts`]: the narrow phase and the gather of the constraints.
pub const PART_NARROW: u32 = 4;
/// [`ContactState::record_parts`]: the Lagrange correction (or the penalty forces).
pub const PART_SOLVE: u32 = 8;
/// [`ContactState::record_parts`]: the finish (node update) and the interface reports.
pub const PART_REPORT: u32 = 16;
/// [`ContactState::record_parts`]: the whole contact stage.
pub const PART_ALL: u32 = 31;
/// Colours at most (WGSL `MAX_COLORS`).
pub const MAX_COLORS: u32 = 64;
/// The most buckets of the search's hash grid (two per segment up to it; more segments share
/// them, which costs time, never candidates). On lavapipe (Mesa 22.3.6, 2026-11-28) a grid of
/// 2^19 buckets or more found no candidate at all, whatever the segments (the 10^4 striker with
/// its grid forced to 2^19: none; the eroding striker of 39 042 slots and 153 600 candidate
/// segments, 2^19 by the rule: none, its projectile through the plate), while 2^18 found them all.
/// The likely cause (found on 2026-11-28): llvmpipe ends a shader invocation's loops after
/// 65 535 iterations in all (`LP_MAX_TGSI_LOOP_ITERATIONS` in Mesa's gallivm, "shared between
/// every loop in a shader"), and the bucket scan's 8 lanes take 2^16 buckets each at 2^19
/// (`scan` in `shaders/contact_search.wgsl`). Tested in `tests/gpu/erosion_contact.rs`.
pub const MAX_BUCKETS: u32 = 1 << 18;
/// Sweep slots of the per-colour path (WGSL `MAX_SWEEP_SLOTS`).
pub const MAX_SWEEP_SLOTS: u32 = 80;
/// Threads per workgroup of the per-item kernels (WGSL `CG`).
pub const CG: u32 = 64;
/// Colouring rounds recorded at first.
pub const FIRST_ROUNDS: u32 = 24;
/// Indirect entry of the first colour's sweep (colour c: `COLOR_ENTRY + c`), after the search
/// kernels' entries; written by the search's `scan_lists`.
pub const COLOR_ENTRY: u32 = search::ENTRIES.len() as u32;
/// Indirect entry of the kernels over the active slots (narrow phase, slot reports; WGSL
/// `ACTIVE_ENTRY`), written at each search after the search kernels' and the colours' entries.
pub const ACTIVE_ENTRY: u32 = COLOR_ENTRY + MAX_COLORS;
/// Stride of the dynamic-offset index entries.
const INDEX_STRIDE: u64 = 256;
/// Index entries: colouring rounds and re-checks first, then (colour, sweep) pairs.
const ROUND_ENTRIES: u64 = MAX_COLORS as u64;

const GROW_CANDIDATES: u32 = 1;
const GROW_COLORS: u32 = 2;
const GROW_ROUNDS: u32 = 4;

/// Mirror of WGSL `ContactParams`: the sizes, offsets and choices every contact stage reads
/// (written by the host, at the start of the contact state `ContactCtl`). The fields without a
/// doc here are documented once, in `shaders/contact_common.wgsl`.
#[allow(missing_docs)]
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct ContactParams {
    pub n_local: u32,
    pub n_slots: u32,
    pub n_segs: u32,
    pub n_ifaces: u32,
    pub margin: f32,
    pub max_sweeps: u32,
    pub multi: u32,
    pub hist_stride: u32,
    pub row_capacity: u32,
    pub n_buckets: u32,
    pub cand_capacity: u32,
    pub adj_capacity: u32,
    pub jp_rounds: u32,
    pub colors_recorded: u32,
    pub tolerance: f32,
    pub friction: u32,
    pub o_bcount: u32,
    pub o_boff: u32,
    pub o_bcur: u32,
    pub o_bent: u32,
    pub o_ccount: u32,
    pub o_coff: u32,
    pub o_ncount: u32,
    pub o_noff: u32,
    pub o_ncur: u32,
    pub o_color: u32,
    pub o_lcount: u32,
    pub o_loff: u32,
    pub o_lcur: u32,
    pub o_list: u32,
    pub o_iface: u32,
    pub o_act: u32,
    pub o_mask: u32,
    pub f_rf: u32,
    /// 1.0, read at run time (the report's compensated work sums; see `Params::one`).
    pub one: f32,
    /// Nodes of the model: `v_prev`'s second third (from this index) holds node.wgsl's velocity
    /// residuals, its last third (from twice this index) the displacement residuals, which the
    /// contact's corrections join.
    pub n_nodes: u32,
    pub f_box: u32,
    pub f_usearch: u32,
    pub f_rp: u32,
    pub f_wp: u32,
    /// ws offsets of the active slots (those that can have a constraint until the next search:
    /// a pass slot with candidates, a wall slot near its wall): a flag per slot, their
    /// exclusive prefix (n_slots + 1 words; the last is the count) and the list in slot order.
    pub o_aflag: u32,
    pub o_aoff: u32,
    pub o_alist: u32,
    /// 1: the one-workgroup solve's active-set re-checks run as their own dispatches over the
    /// active slots (`recheck_active`, many workgroups), between rounds of `solve_one`.
    pub split: u32,
    /// ws offsets of the one-workgroup solve's extrapolation (see
    /// [`crate::contact::extrapolation`]): (lambda, lt) after the last sweep per compacted
    /// constraint (2 words each), the nodes of the constraints, and their dv after the last sweep
    /// (2 words each).
    pub o_lprev: u32,
    pub o_nlist: u32,
    pub o_dvp: u32,
    /// 1: the one-workgroup solve extrapolates between sweeps (0: plain projected Gauss-Seidel;
    /// the per-colour path never does).
    pub extrapolate: u32,
    /// The one-workgroup solve's packed rows (`contact_solve.wgsl`, `pack`): ws offset of the
    /// compacted constraints' node indices into the packed nodes and their partner's packed
    /// index (4 words each), fws offsets of
    /// their rows (2 vec4 each), of their friction rows (1 vec4 each, with friction) and of the
    /// packed nodes (`n_local` + 1 vec4: dv and 1/m, the last one zero for walls).
    pub o_cidx: u32,
    pub f_row: u32,
    pub f_frow: u32,
    pub f_node: u32,
    /// ws offsets of the pairing (with WGSL `PAIR_BLOCKS`,
    /// [`crate::gpu::shader::Features::contact_pair_blocks`]) (`pair_constraints`), a word per slot each: each constraint's
    /// best partner, then its pair code (leader or partner, and the other's compacted index).
    pub o_best: u32,
    pub o_pair: u32,
}

/// Mirror of the first part of WGSL `ContactCtl` after the parameters: the counters the host
/// reads back with each batch (documented in `shaders/contact_common.wgsl`).
#[allow(missing_docs)]
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct ContactCounters {
    pub due: u32,
    pub extent: u32,
    pub n_cand: u32,
    pub need_cand: u32,
    pub n_adj: u32,
    pub searching: u32,
    pub n_colors: u32,
    pub searches: u32,
    pub grow: u32,
    pub lagrange: u32,
    /// Penalty impulses bounded so far (constraint-steps).
    pub bounded: u32,
    pub sweeps: u32,
    pub sweeps_total: u32,
    pub sweeps_max: u32,
    pub solve_steps: u32,
    pub unconverged: u32,
    /// f32 bits: the residual of this step (the largest change of a gap in its last sweep, m).
    pub residual: u32,
    /// f32 bits: the largest residual of a step so far (m).
    pub residual_max: u32,
}

/// Bytes of WGSL `ContactParams`, at the start of `ContactCtl`.
pub const PARAMS_SIZE: u64 = std::mem::size_of::<ContactParams>() as u64;
/// Bytes of WGSL `ContactCtl`: the parameters, the counters, the per-sweep changes, the
/// re-checks' additions and the step's largest penetration.
pub const CTL_SIZE: u64 =
    PARAMS_SIZE + std::mem::size_of::<ContactCounters>() as u64 + 4 * MAX_SWEEP_SLOTS as u64 + 20;

const _: () = assert!(std::mem::size_of::<ContactParams>() == 216);
const _: () = assert!(std::mem::size_of::<ContactCounters>() == 72);

/// What the stages record their dispatches with: the contact bind group (group 0; its dynamic
/// offset selects an index entry), the indirect sizes and the parameters.
pub(crate) struct Dispatch<'a> {
    /// The parameters as last uploaded.
    pub params: &'a ContactParams,
    bind: &'a wgpu::BindGroup,
    ind: &'a wgpu::Buffer,
}

impl Dispatch<'_> {
    /// Binds group 0 with index entry `entry` (every contact pipeline shares its layout, so it
    /// stays bound across pipelines: set again only where the entry changes).
    pub fn bind(&self, pass: &mut wgpu::ComputePass<'_>, entry: u64) {
        pass.set_bind_group(0, self.bind, &[(entry * INDEX_STRIDE) as u32]);
    }

    /// `pipeline` over `n` workgroups.
    pub fn direct(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        pipeline: &wgpu::ComputePipeline,
        n: u32,
    ) {
        pass.set_pipeline(pipeline);
        pass.dispatch_workgroups(n, 1, 1);
    }

    /// The pipeline set last, over the workgroups of indirect entry `entry`.
    pub fn indirect(&self, pass: &mut wgpu::ComputePass<'_>, entry: u64) {
        pass.dispatch_workgroups_indirect(self.ind, 12 * entry);
    }

    /// `pipeline` over the active slots of the last search (indirect entry [`ACTIVE_ENTRY`]).
    pub fn active(&self, pass: &mut wgpu::ComputePass<'_>, pipeline: &wgpu::ComputePipeline) {
        pass.set_pipeline(pipeline);
        self.indirect(pass, ACTIVE_ENTRY as u64);
    }
}

/// Workgroups of [`CG`] threads over `n` items (at least one).
pub(crate) fn groups(n: u32) -> u32 {
    n.div_ceil(CG).max(1)
}

/// The shared buffers the contact kernels bind.
pub(crate) struct Shared<'a> {
    pub ctrl: &'a wgpu::Buffer,
    pub nodes: &'a wgpu::Buffer,
    pub v_prev: &'a wgpu::Buffer,
    pub sample_src: &'a wgpu::Buffer,
}

/// Sizes of the workspace arrays.
struct Workspace {
    words: u32,
    vec4s: u32,
}

/// Lays out the workspace arrays of every stage (`ws`: u32 words, `fws`: vec4) and writes their
/// offsets into `p`.
fn layout_workspace(p: &mut ContactParams) -> Workspace {
    let mut at = 0u32;
    let mut take = |n: u32| {
        let o = at;
        at += n.max(1);
        o
    };
    let (t, ns, nl, nc) = (p.n_buckets, p.n_slots, p.n_local, MAX_COLORS);
    p.o_bcount = take(t);
    p.o_boff = take(t + 1);
    p.o_bcur = take(t);
    p.o_bent = take(4 * p.n_segs);
    p.o_ccount = take(ns);
    p.o_coff = take(ns + 1);
    p.o_ncount = take(nl);
    p.o_noff = take(nl + 1);
    p.o_ncur = take(nl);
    p.o_color = take(ns);
    p.o_lcount = take(nc + 1);
    p.o_loff = take(nc + 2);
    p.o_lcur = take(nc + 1);
    p.o_list = take(ns);
    p.o_iface = take(p.n_ifaces + 1);
    p.o_act = take(ns);
    p.o_mask = take(nl);
    p.o_aflag = take(ns);
    p.o_aoff = take(ns + 1);
    p.o_alist = take(ns);
    p.o_lprev = take(2 * ns);
    p.o_nlist = take(nl);
    p.o_dvp = take(2 * nl);
    // The one-workgroup solve's packed rows (none on the per-colour path).
    let one = p.multi == 0;
    p.o_cidx = if one { take(4 * ns) } else { 0 };
    p.o_best = if one { take(ns) } else { 0 };
    p.o_pair = if one { take(ns) } else { 0 };
    let words = at;
    let mut f = 0u32;
    let mut ftake = |n: u32| {
        let o = f;
        f += n.max(1);
        o
    };
    p.f_box = ftake(p.n_segs);
    p.f_usearch = ftake(nl);
    p.f_rp = ftake(ns);
    p.f_wp = ftake(nl.div_ceil(CG));
    // Friction partials per slot run (force along the tangents, work, its part after t_n).
    p.f_rf = if p.friction != 0 { ftake(ns) } else { 0 };
    p.f_row = if one { ftake(2 * ns) } else { 0 };
    p.f_frow = if one && p.friction != 0 { ftake(ns) } else { 0 };
    p.f_node = if one { ftake(nl + 1) } else { 0 };
    Workspace { words, vec4s: f }
}

/// The index entries (a `vec4<u32>` each, [`INDEX_STRIDE`] bytes apart) that the dynamic offset
/// of group 0 selects: colouring rounds and re-checks r = 0.. ([`ROUND_ENTRIES`] of them), then on
/// the per-colour path one per (colour, sweep).
fn index_entries(multi: bool) -> Vec<u8> {
    let entries_n = ROUND_ENTRIES
        + if multi {
            MAX_SWEEP_SLOTS as u64 * MAX_COLORS as u64
        } else {
            0
        };
    let mut index_bytes = vec![0u8; (entries_n * INDEX_STRIDE) as usize];
    for e in 0..entries_n {
        let v: [u32; 4] = if e < ROUND_ENTRIES {
            [e as u32, 0, 0, 0]
        } else {
            let r = (e - ROUND_ENTRIES) as u32;
            [r % MAX_COLORS, r / MAX_COLORS, 0, 0]
        };
        let at = (e * INDEX_STRIDE) as usize;
        index_bytes[at..at + 16].copy_from_slice(bytemuck::bytes_of(&v));
    }
    index_bytes
}

/// Contact buffers, bind groups and the host's view of the device counters.
#[derive(Debug)]
pub struct ContactState {
    /// Parameters as last uploaded.
    pub params: ContactParams,
    set: ContactSet,
    /// Global index of each contact node.
    nodes: Vec<u32>,
    /// Interface names (history columns).
    pub names: Vec<String>,
    /// Counters as last read back.
    pub counters: ContactCounters,
    pub(crate) ctl: wgpu::Buffer,
    grow_buf: wgpu::Buffer,
    pub(crate) history: wgpu::Buffer,
    ind: wgpu::Buffer,
    _index: wgpu::Buffer,
    /// (binding, buffer) of the bind group, to rebuild it when the candidate buffer grows.
    entries: Vec<(u32, wgpu::Buffer)>,
    bind: wgpu::BindGroup,
    ind_bind: wgpu::BindGroup,
    /// Grow events so far (candidate buffer, colours recorded, colouring rounds).
    pub grows: u32,
    /// The stage in one workgroup before the search and one after it ([`one`]).
    one: bool,
    /// The search in one workgroup ([`search::search_one_path`]; as last switched).
    search_one: bool,
    /// The search's switch between its two ways, if it has one, with the step and the searches
    /// at the start of its window, and the switches so far.
    search_switch: Option<(SearchSwitch, u32, u32)>,
    search_switches: u64,
    /// Eroding contact (a scene with failure): the fixed candidate lists, the model whose
    /// surfaces they follow, and the slots and segments as last written to the device.
    eroding: Option<erosion::Eroding>,
}

fn make_bind(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    entries: &[(u32, wgpu::Buffer)],
) -> wgpu::BindGroup {
    let list: Vec<wgpu::BindGroupEntry<'_>> = entries
        .iter()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: if *binding == 17 {
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(16),
                })
            } else {
                buffer.as_entire_binding()
            },
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("contact"),
        layout,
        entries: &list,
    })
}

impl ContactState {
    /// Buffers of `set` (the model's contacts); `alloc` records each buffer for the plan report.
    /// `path`: the solve path and how the stage is dispatched.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        device: &wgpu::Device,
        kernels: &ContactKernels,
        model: &Model,
        set: ContactSet,
        shared: Shared<'_>,
        row_capacity: u32,
        path: Path,
        candidate_capacity: Option<u32>,
        alloc: &mut Alloc<'_>,
    ) -> Result<ContactState> {
        let Path {
            multi,
            split,
            extrapolate,
            one,
            search_one,
            search_switch,
        } = path;
        let masked = if model.has_erosion() {
            Some(Masked::new(model, &set).ok_or_else(|| erosion::unfollowed("build"))?)
        } else {
            None
        };
        let t = match &masked {
            Some(m) => m
                .tables(&set)
                .ok_or_else(|| erosion::unfollowed("lay out"))?,
            None => set.tables(),
        };
        let nl = t.nodes.len();
        let c_ref = tables::reference(&t);
        let node_words = tables::node_words(&t);
        let slots: Vec<GpuSlot> = t.slots.iter().map(GpuSlot::from).collect();
        let segs: Vec<GpuSegment> = t.segments.iter().map(GpuSegment::from).collect();
        let eroding = match masked {
            Some(masked) => Some(erosion::Eroding {
                on: masked
                    .laid_out(&set)
                    .ok_or_else(|| erosion::unfollowed("lay out"))?,
                masked,
                model: Box::new(model.clone()),
                slots: slots.clone(),
                segments: segs.clone(),
            }),
            None => None,
        };
        let names = set.names();
        let iface = tables::interface_starts(&t, names.len())?;
        let ni = names.len() as u32;
        // Words per history row: the contact energy, with friction the friction work, then per
        // interface fx, fy, the largest penetration, the active nodes and with friction ft.
        let friction = t.slots.iter().any(|s| s.friction > 0.0);
        let hist_stride = if friction { 2 + 5 * ni } else { 1 + 4 * ni };
        let n_slots = slots.len() as u32;
        let n_segs = segs.len() as u32;
        let cand_capacity = candidate_capacity.unwrap_or((4 * n_slots).max(1024)).max(1);
        let mut params = ContactParams {
            n_local: nl as u32,
            n_slots,
            n_segs,
            n_ifaces: ni,
            margin: t.margin as f32,
            max_sweeps: if multi {
                solve::MULTI_SWEEPS
            } else {
                solve::MAX_SWEEPS
            },
            multi: u32::from(multi),
            hist_stride,
            row_capacity,
            n_buckets: (2 * n_segs).max(64).next_power_of_two().min(MAX_BUCKETS),
            cand_capacity,
            adj_capacity: n_slots + 2 * cand_capacity,
            jp_rounds: FIRST_ROUNDS,
            colors_recorded: if multi { 8 } else { 0 },
            one: 1.0,
            n_nodes: model.node_count() as u32,
            tolerance: (solve::TOLERANCE * t.margin) as f32,
            friction: u32::from(friction),
            split: u32::from(split && !multi),
            extrapolate: u32::from(extrapolate && !multi),
            ..Default::default()
        };
        let work = layout_workspace(&mut params);
        let mut ws_init = vec![0u32; work.words as usize];
        ws_init[params.o_iface as usize..params.o_iface as usize + iface.len()]
            .copy_from_slice(&iface);
        // Per node: (u_n, trial u), (v_free, v^{n-1/2}), (v kept for the next step, dv).
        let init_pv: Vec<[f32; 4]> = t
            .nodes
            .iter()
            .flat_map(|&g| {
                let v = model.velocity[g as usize];
                [[0.0; 4], [0.0; 4], [v[0] as f32, v[1] as f32, 0.0, 0.0]]
            })
            .collect();
        use wgpu::BufferUsages as U;
        let st = U::STORAGE;
        let nodes_buf = alloc.init("contact_nodes", bytemuck::cast_slice(&node_words), st);
        let ref_buf = alloc.init("contact_reference", bytemuck::cast_slice(&c_ref), st);
        // Storage bindings may not be empty: a scene without slots (or with walls only, without
        // segments) binds one unused record.
        let slot_words = if slots.is_empty() {
            vec![GpuSlot::default()]
        } else {
            slots
        };
        let slots_buf = alloc.init("contact_slots", bytemuck::cast_slice(&slot_words), st);
        let seg_words = if segs.is_empty() {
            vec![GpuSegment::default()]
        } else {
            segs
        };
        let segs_buf = alloc.init("contact_segments", bytemuck::cast_slice(&seg_words), st);
        let pv = alloc.init("contact_nodal", bytemuck::cast_slice(&init_pv), st);
        let cons = alloc.init(
            "contact_constraints",
            &vec![0u8; (narrow::CONS_SIZE as usize) * (n_slots as usize).max(1)],
            st,
        );
        let mut ctl_init = vec![0u8; CTL_SIZE as usize];
        ctl_init[..PARAMS_SIZE as usize].copy_from_slice(bytemuck::bytes_of(&params));
        let ctl = alloc.init("contact_state", &ctl_init, st | U::COPY_SRC | U::COPY_DST);
        let ws = alloc.init(
            "contact_workspace",
            bytemuck::cast_slice(&ws_init),
            st | U::COPY_SRC,
        );
        let grow_buf = alloc.init(
            "contact_candidates",
            &vec![0u8; 4 * (params.cand_capacity + params.adj_capacity) as usize],
            st | U::COPY_SRC,
        );
        let fws = alloc.init(
            "contact_workspace_f32",
            &vec![0u8; 16 * work.vec4s as usize],
            st,
        );
        let history = alloc.init(
            "contact_history",
            &vec![0u8; 4 * (row_capacity * hist_stride + 4 * (ni + 2)) as usize],
            st | U::COPY_SRC,
        );
        let ind = alloc.init(
            "contact_indirect",
            &vec![0u8; 12 * (ACTIVE_ENTRY as usize + 1)],
            st | U::INDIRECT,
        );
        let index = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("contact_index"),
            contents: &index_entries(multi),
            usage: U::UNIFORM,
        });
        alloc.record("contact_index", index.size());
        let entries = vec![
            (1, shared.ctrl.clone()),
            (2, shared.nodes.clone()),
            (3, shared.v_prev.clone()),
            (4, shared.sample_src.clone()),
            (5, nodes_buf),
            (6, ref_buf),
            (7, slots_buf),
            (8, segs_buf),
            (9, pv),
            (11, cons),
            (12, ctl.clone()),
            (13, ws),
            (14, grow_buf.clone()),
            (15, fws),
            (16, history.clone()),
            (17, index.clone()),
        ];
        let bind = make_bind(device, &kernels.layouts.shared, &entries);
        let ind_bind = search::bind_indirect(device, &kernels.layouts.indirect, &ind);
        Ok(ContactState {
            params,
            set,
            nodes: t.nodes,
            names,
            counters: ContactCounters::default(),
            ctl,
            grow_buf,
            history,
            ind,
            _index: index,
            entries,
            bind,
            ind_bind,
            grows: 0,
            one,
            search_one,
            search_switch: search_switch.map(|s| (s, 0, 0)),
            search_switches: 0,
            eroding,
        })
    }

    /// The penalty springs' stable step and what sets it.
    pub fn penalty_step(&self) -> Option<(f64, &str)> {
        self.set.penalty_step()
    }

    /// Global node indices of the contact nodes.
    pub fn nodes(&self) -> &[u32] {
        &self.nodes
    }

    /// The buffer at `binding` of the contact bind group (test hooks).
    pub(crate) fn binding(&self, binding: u32) -> Option<&wgpu::Buffer> {
        self.entries.iter().find(|e| e.0 == binding).map(|e| &e.1)
    }

    /// Whether the per-colour solve path is in use.
    pub fn multi(&self) -> bool {
        self.params.multi != 0
    }

    /// Whether the stage runs in one workgroup before the search and one after it ([`one`]).
    pub fn one(&self) -> bool {
        self.one
    }

    /// Broad-phase searches so far (as last read back).
    pub fn searches(&self) -> u64 {
        self.counters.searches as u64
    }

    /// Records the contact stage of a step.
    pub fn record(&self, k: &ContactKernels, pass: &mut wgpu::ComputePass<'_>) {
        self.record_parts(k, pass, PART_ALL);
    }

    /// Records the parts of the contact stage named by `parts` (a mask of [`PART_PREP`],
    /// [`PART_SEARCH`], [`PART_NARROW`], [`PART_SOLVE`], [`PART_REPORT`]), in stage order: the
    /// whole stage with [`PART_ALL`]; one part alone only for timing its kernels (the bench's
    /// contact shares), since alone it works on whatever the other parts left. In one
    /// workgroup ([`ContactState::one`]) the narrow part is the whole stage after the search,
    /// and the solve and report parts record nothing.
    pub fn record_parts(&self, k: &ContactKernels, pass: &mut wgpu::ComputePass<'_>, parts: u32) {
        let d = Dispatch {
            params: &self.params,
            bind: &self.bind,
            ind: &self.ind,
        };
        // Group 0 is set once (offset 0) and again only where its index offset changes.
        d.bind(pass, 0);
        pass.set_bind_group(1, &self.ind_bind, &[]);
        let on = |part: u32| parts & part != 0;
        if on(PART_PREP) {
            if self.one {
                k.one.record_prep(&d, pass);
            } else {
                k.search.record_prep(&d, pass);
            }
        }
        if on(PART_SEARCH) {
            if self.search_one {
                k.search.record_one(&d, pass);
            } else {
                k.search.record(&d, pass);
            }
        }
        if self.one {
            // Narrow phase to reports in one dispatch (timed as the narrow part).
            if on(PART_NARROW) {
                k.one.record(&d, pass);
            }
            return;
        }
        if on(PART_NARROW) {
            k.narrow.record(&d, pass);
        }
        if on(PART_SOLVE) {
            k.solve.record(&d, pass);
        }
        if on(PART_REPORT) {
            k.report.record(&d, pass);
        }
    }

    /// Gives the candidate buffer room for `cap` candidates (a new, zeroed buffer, bound in
    /// place of the old one).
    pub(crate) fn resize_candidates(
        &mut self,
        device: &wgpu::Device,
        kernels: &ContactKernels,
        cap: u32,
    ) {
        self.params.cand_capacity = cap;
        self.params.adj_capacity = self.params.n_slots + 2 * cap;
        let bytes = 4 * (cap as u64 + self.params.adj_capacity as u64);
        self.grow_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("contact_candidates"),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        for e in &mut self.entries {
            if e.0 == 14 {
                e.1 = self.grow_buf.clone();
            }
        }
        self.bind = make_bind(device, &kernels.layouts.shared, &self.entries);
    }

    /// The candidate buffer now in use.
    pub(crate) fn candidates_buffer(&self) -> &wgpu::Buffer {
        &self.grow_buf
    }

    /// After a step stopped with [`STATE_SEARCH_GROW`] (`counters` just read back): enlarges what
    /// the search asked for, and marks a search due so that the resumed step searches again.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the colouring needs more than [`MAX_COLORS`] colours.
    pub(crate) fn grow(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &ContactKernels,
    ) -> Result<()> {
        let c = self.counters;
        if c.grow & GROW_CANDIDATES != 0 {
            let need = c.need_cand.max(self.params.cand_capacity + 1);
            let cap = (need + need / 2).next_power_of_two();
            self.resize_candidates(device, kernels, cap);
        }
        if c.grow & GROW_ROUNDS != 0 {
            if self.params.jp_rounds >= MAX_COLORS {
                return Err(Error::Gpu(format!(
                    "contact colouring needs more than {MAX_COLORS} colours: the candidate \
                     pairs are too dense (a node near very many segments)"
                )));
            }
            self.params.jp_rounds = (2 * self.params.jp_rounds).min(MAX_COLORS);
        }
        if c.grow & GROW_COLORS != 0 {
            self.params.colors_recorded = c.n_colors.min(MAX_COLORS);
        }
        self.grows += 1;
        queue.write_buffer(&self.ctl, 0, bytemuck::bytes_of(&self.params));
        // Counters: due = 1 (offset 0), grow = 0 (offset 32).
        queue.write_buffer(&self.ctl, PARAMS_SIZE, bytemuck::bytes_of(&1u32));
        queue.write_buffer(&self.ctl, PARAMS_SIZE + 32, bytemuck::bytes_of(&0u32));
        Ok(())
    }
}
