//! Device-resident simulation state: the buffers a scene needs (and no others), allocated once in
//! a fixed order, and the bind groups built once on them. By file: this one sizes and allocates
//! the buffers ([`GpuState::new`]) through `src/gpu/alloc.rs` (which records them for the plan
//! report and checkpoints); `binds.rs` builds each kernel's bind group, `record.rs` records a
//! step as labelled dispatches ([`GpuState::record_step`]). The contact stage's buffers are
//! [`super::contact::ContactState`]'s. The CPU reference keeps the same state in host arrays
//! ([`crate::step::cpu::CpuSolver`]).

mod binds;
mod record;

use crate::contact::ContactSet;
use crate::error::{Error, Result};
use crate::model::Model;
use crate::plan::{Plan, Stage};
use crate::step::Schedule;

use super::alloc::Alloc;
use super::contact::{ContactState, Shared};
use super::kernels::Kernels;
use super::layout::*;
use super::{boundary, element, loads, node, reduce};
use binds::Binds;

/// Nodes + elements + constraints up to which a CPU adapter reduces in one workgroup (the
/// control workgroup, instead of a first level over many workgroups and a dispatch of its own).
/// On lavapipe a dispatch costs about 29 us of hand-off to its thread pool, more than the
/// control workgroup takes to reduce these values itself. Measured on the 2-core machine
/// (2026-11-25, f1f92ef, the same scene fused and not, alternated in one process): the 10^4 pile
/// (about 23 000 values) 1 449 -> 1 290-1 350 us a step; at 10^5 (about 210 000 values) the
/// two are within the noise (the pile 10 319 against 10 125 us, the striker 7 674 against 7 446).
pub const FUSED_LIMIT: usize = 1 << 17;

/// Sample instances (one per body, and the elements, constraints, loads) up to which a CPU
/// adapter reduces in one workgroup: the control workgroup sums them one after another on sample
/// steps, each with its barrier tree. The 10^5 pile's 1 026 instances were measured with
/// [`FUSED_LIMIT`]; a scene of more bodies keeps the reduction over many workgroups.
pub const FUSED_INSTANCES: usize = 1 << 11;

/// Workgroups of the sums' second level at most (`sum_instances`; each takes every this-many-th
/// instance beyond): the dispatch limit per dimension.
pub const MAX_INST_GROUPS: u32 = 65535;

/// Most steps recorded per submission (the solver's batches; the history ring holds at least
/// this many rows).
pub const MAX_BATCH: u32 = 1024;

/// Rows the history ring holds between readbacks, at most (fewer when a row is so wide, with many
/// bodies, that the ring would exceed the device's largest storage binding; never fewer than the
/// steps of one submission, [`MAX_BATCH`]).
pub const ROW_CAPACITY: u32 = 4096;

/// The history ring's rows for rows of `stride` words on a device whose largest storage binding
/// is `max_binding` bytes.
pub fn row_capacity(stride: u32, max_binding: u64) -> u32 {
    let fit = max_binding / (4 * stride.max(1) as u64);
    (fit.min(ROW_CAPACITY as u64) as u32).max(MAX_BATCH)
}

/// Buffers and bind groups of one scene on the device.
#[derive(Debug)]
pub struct GpuState {
    /// Sizes and static parameters (as uploaded).
    pub params: Params,
    /// Names and sizes (bytes) of the buffers allocated, for the plan report: every device
    /// buffer of the scene, the host-readable staging buffers of [`super::GpuSolver`] included
    /// (`readback`, `snapshot_readback`, and `search_readback` from the first contact search on).
    pub allocated: Vec<(&'static str, u64)>,
    /// Every buffer of the scene allocated at the start (not the staging buffers), in order: what
    /// a checkpoint saves (the contact candidates' current buffer replaces the first one after
    /// it grew).
    pub(crate) buffers: Vec<(&'static str, wgpu::Buffer)>,
    pub(crate) ctrl: wgpu::Buffer,
    pub(crate) nodes: wgpu::Buffer,
    pub(crate) elem_force: wgpu::Buffer,
    pub(crate) elem_dt: wgpu::Buffer,
    pub(crate) v_prev: wgpu::Buffer,
    pub(crate) u_snap: Option<wgpu::Buffer>,
    /// J2 plastic state per element (scenes with a plastic body only).
    pub(crate) plastic: Option<wgpu::Buffer>,
    /// Erosion state per element: (eroded energy, eroded flag, Johnson-Cook damage, 0) (scenes
    /// with failure only).
    pub(crate) erosion: Option<wgpu::Buffer>,
    /// The elements eroded since the contact surfaces last followed (scenes with failure; one
    /// entry per element with contact, one in all without).
    pub(crate) eroded_list: Option<wgpu::Buffer>,
    /// Whether a body's material has Johnson-Cook damage (snapshots carry the damage).
    pub(crate) damage: bool,
    pub(crate) history: wgpu::Buffer,
    pub(crate) indirect: wgpu::Buffer,
    /// Contact buffers (scenes with contact only).
    pub contact: Option<ContactState>,
    groups: Groups,
    bind: Binds,
}

/// Workgroups of the per-item kernels.
#[derive(Debug, Clone, Copy)]
struct Groups {
    element: u32,
    node: u32,
    boundary: u32,
    pressure: u32,
}

/// The buffers of a scene (those of the kernels it compiles; `None`: a kernel or variant it does
/// not need), in allocation order. Named in `shaders/*.wgsl` by the same names or their own.
struct Buffers {
    params: wgpu::Buffer,
    ctrl: wgpu::Buffer,
    elements: wgpu::Buffer,
    bodies: wgpu::Buffer,
    nodes: wgpu::Buffer,
    inv_mass: wgpu::Buffer,
    offsets: wgpu::Buffer,
    slots: wgpu::Buffer,
    elem_force: wgpu::Buffer,
    pressure: Option<wgpu::Buffer>,
    v_old: Option<wgpu::Buffer>,
    elem_dt: wgpu::Buffer,
    elem_state: Option<wgpu::Buffer>,
    plastic: Option<wgpu::Buffer>,
    failures: Option<wgpu::Buffer>,
    erosion: Option<wgpu::Buffer>,
    eroded_list: Option<wgpu::Buffer>,
    v_prev: wgpu::Buffer,
    u_snap: Option<wgpu::Buffer>,
    curves: Option<wgpu::Buffer>,
    constraints: Option<wgpu::Buffer>,
    sample_src: wgpu::Buffer,
    dt_partial: wgpu::Buffer,
    instances: wgpu::Buffer,
    sum_partial: wgpu::Buffer,
    history: wgpu::Buffer,
    times: wgpu::Buffer,
    inst_res: wgpu::Buffer,
    indirect: wgpu::Buffer,
}

/// Sample or snapshot times k * interval, k = 0.. up to past `end`, in ticks.
fn time_table(interval: f64, end: f64) -> Vec<[u32; 2]> {
    let count = ((end / interval).floor() as usize + 2).min(1 << 22);
    (0..count)
        .map(|k| ticks(k as f64 * interval, end))
        .collect()
}

/// The sample instances (one per body, its nodes; the elements; the constraints; with loads the
/// nodes' load work; with plastic bodies the elements' plastic work; with failure the eroded
/// elements' energy and count) of `nn` nodes, `ne` elements and `nc` constraints, for reductions
/// of `rg` threads, and their first-level workgroups in all.
fn sample_instances(
    model: &Model,
    (nn, ne, nc): (usize, usize, usize),
    (loads, plastic, failure): (bool, bool, bool),
    rg: u32,
) -> (Vec<Instance>, u32) {
    let nl = if loads { nn } else { 0 };
    let mut instances = Vec::new();
    let mut first = 0u32;
    let mut push = |start: usize, count: usize, scale: f32| {
        let groups = reduce::groups(count, rg);
        instances.push(Instance {
            start: start as u32,
            count: count as u32,
            groups,
            first_group: first,
            scale,
            _pad: [0; 3],
        });
        first += groups;
    };
    for b in &model.bodies {
        push(b.nodes.start, b.nodes.len(), (1.0 / b.mass) as f32);
    }
    push(nn, ne, 1.0);
    if nc > 0 {
        push(nn + ne, nc, 1.0);
    }
    if loads {
        push(nn + ne + nc, nl, 1.0);
    }
    // J2 plastic work, one accumulator per element after the loads' (element.wgsl).
    let npl = if plastic { ne } else { 0 };
    if plastic {
        push(nn + ne + nc + nl, ne, 1.0);
    }
    // Eroded energy and count, one entry per element after the plastic work's (element.wgsl).
    if failure {
        push(nn + ne + nc + nl + npl, ne, 1.0);
    }
    (instances, first)
}

impl GpuState {
    /// Uploads a model at t = 0. `fused`: whether the control workgroup reduces directly (see
    /// control.wgsl); `None` decides by adapter and size.
    ///
    /// # Errors
    /// [`Error::Gpu`] when the model exceeds what one dispatch can cover.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        device: &wgpu::Device,
        kernels: &Kernels,
        model: &Model,
        plan: &Plan,
        schedule: &Schedule,
        fused: Option<bool>,
        device_type: wgpu::DeviceType,
        contact: super::contact::ContactOptions,
    ) -> Result<GpuState> {
        let nn = model.node_count();
        let ne = model.element_count();
        let nc = model.constraints.len();
        let nb = model.bodies.len();
        let max_groups = 65_535usize;
        if ne.div_ceil(element::WORKGROUP as usize) > max_groups
            || nn.div_ceil(node::WORKGROUP as usize) > max_groups
        {
            return Err(Error::Gpu(format!(
                "model too large for one dispatch: {ne} elements, {nn} nodes (at most {} each)",
                max_groups * 64
            )));
        }
        use wgpu::BufferUsages as U;
        let storage = U::STORAGE;
        let mut a = Alloc::new(device);

        // Static data.
        let bodies = element::bodies(model);
        let elems = element::elements(model);
        let node_state: Vec<[f32; 4]> = model
            .velocity
            .iter()
            .map(|v| [0.0, 0.0, v[0] as f32, v[1] as f32])
            .collect();
        let inv_mass: Vec<f32> = model.mass.iter().map(|m| (1.0 / m) as f32).collect();
        // Pressure entries (their forces go to slots past the elements' and are gathered after them).
        let press = if plan.has(Stage::Pressure) {
            loads::pressure_entries(model)
        } else {
            Vec::new()
        };
        let np = press.len();
        let press_nodes: Vec<u32> = press.iter().map(|(n, _)| *n).collect();
        let press_data: Vec<loads::GpuPressureEntry> = press.iter().map(|(_, e)| *e).collect();
        let (offsets, slots) = node::adjacency(&model.quads, nn, &press_nodes);
        // Pressure and damping work: one accumulator per node after the constraints' (loads.wgsl).
        let has_loads = kernels.features.loads;
        let nl = if has_loads { nn } else { 0 };
        let plastic = kernels.features.plastic;
        let npl = if plastic { ne } else { 0 };
        let failure = kernels.features.failure;
        let nf = if failure { ne } else { 0 };
        let rg = kernels.features.reduce_group;
        let (instances, first) =
            sample_instances(model, (nn, ne, nc), (has_loads, plastic, failure), rg);
        // Small models on CPU adapters: the control workgroup reduces directly (see control.wgsl).
        let fused = fused.unwrap_or(
            kernels.features.reduce_group == 64
                && nn + ne + nc + nl + npl + nf <= FUSED_LIMIT
                && instances.len() <= FUSED_INSTANCES,
        );
        let sum_groups = if fused { 0 } else { first };

        let contact_set = if plan.has(Stage::Contact) {
            ContactSet::new(model)
        } else {
            None
        };
        let has_fields = plan.has(Stage::Fields);
        let mut times = time_table(schedule.history_interval, schedule.end_time);
        let n_sample_times = times.len() as u32;
        let mut n_snapshot_times = 0;
        if let (true, Some(fi)) = (has_fields, schedule.field_interval) {
            let snaps = time_table(fi, schedule.end_time);
            n_snapshot_times = snaps.len() as u32;
            times.extend(snaps);
        }
        // Time, step, dt, the five energies, the plastic work with a plastic body, the eroded
        // count and energy with failure, then per body.
        let row_stride = 9 + u32::from(plastic) + 2 * u32::from(failure) + 2 * nb as u32;
        let row_cap = row_capacity(row_stride, device.limits().max_storage_buffer_binding_size);
        if ticks_per_end(schedule.end_time) < MIN_TICKS_PER_END {
            return Err(Error::Gpu(format!(
                "run.end_time = {:e} s is too short for the GPU, which keeps time in f32 ticks \
                 (an end time of at least {:e} s); run it with --backend cpu",
                schedule.end_time,
                MIN_TICKS_PER_END / MAX_TICKS_PER_SECOND
            )));
        }
        let [end_lo, end_hi] = ticks(schedule.end_time, schedule.end_time);
        let params = Params {
            n_nodes: nn as u32,
            n_elems: ne as u32,
            n_cons: nc as u32,
            n_bodies: nb as u32,
            scale: schedule.time_step_scale as f32,
            fixed_dt: schedule.time_step.unwrap_or(0.0) as f32,
            end_lo,
            end_hi,
            n_sample_times,
            n_snapshot_times,
            row_stride,
            row_capacity: row_cap,
            dt_groups: if fused { 0 } else { reduce::groups(ne, rg) },
            n_instances: instances.len() as u32,
            sum_groups,
            ticks_per_second: (ticks_per_end(schedule.end_time) / schedule.end_time) as f32,
            penalty_dt: contact_set
                .as_ref()
                .and_then(|c| c.penalty_step())
                .map_or(0.0, |(d, _)| d as f32),
            mass_damping: model.mass_damping as f32,
            gravity_x: model.gravity[0] as f32,
            gravity_y: model.gravity[1] as f32,
            gravity_ramp: model.gravity_ramp as f32,
            one: 1.0,
            failure: u32::from(failure),
            failure_at: if failure {
                (nn + ne + nc + nl + npl) as u32
            } else {
                0
            },
            _pad: 0,
            loads: u32::from(has_loads),
            plastic: u32::from(plastic),
            inst_groups: if fused {
                0
            } else {
                (instances.len() as u32).min(MAX_INST_GROUPS)
            },
        };
        let control = Control {
            flags: FLAG_SAMPLE
                | if n_snapshot_times > 0 {
                    FLAG_SNAPSHOT
                } else {
                    0
                },
            state: STATE_RUNNING,
            dt_min: f32::MAX,
            bad_element: NONE,
            bad_node: NONE,
            ..Default::default()
        };
        // Two vec4 per element, three with axisymmetric bodies (the hoop bulk stress).
        let es_words = if kernels.features.axisymmetric { 3 } else { 2 };
        let indirect_init = [sum_groups, 1, 1, params.inst_groups, 1, 1];
        // (Every buffer is copyable both ways, for readbacks and checkpoints: `Alloc` adds the
        // copy usages.)
        let b = Buffers {
            params: a.init("params", bytemuck::bytes_of(&params), U::UNIFORM),
            ctrl: a.init("control", bytemuck::bytes_of(&control), storage),
            elements: a.init("elements", bytemuck::cast_slice(&elems), storage),
            bodies: a.init("bodies", bytemuck::cast_slice(&bodies), storage),
            nodes: a.init("nodes", bytemuck::cast_slice(&node_state), storage),
            inv_mass: a.init("inv_mass", bytemuck::cast_slice(&inv_mass), storage),
            offsets: a.init("adjacency_offsets", bytemuck::cast_slice(&offsets), storage),
            slots: a.init("adjacency_slots", bytemuck::cast_slice(&slots), storage),
            elem_force: a.zeroed("element_forces", 32 * ne as u64 + 8 * np as u64, storage),
            pressure: (np > 0).then(|| {
                a.init(
                    "pressure_entries",
                    bytemuck::cast_slice(&press_data),
                    storage,
                )
            }),
            v_old: has_loads.then(|| a.zeroed("v_old", 8 * nn as u64, storage)),
            elem_dt: a.zeroed("element_dt", 4 * ne as u64, storage),
            elem_state: plan
                .has_dissipation()
                .then(|| a.zeroed("element_dissipation", 16 * es_words * ne as u64, storage)),
            // J2: C_p^-1 - I and (alpha, plastic work) per element; zero is the virgin state.
            plastic: plastic.then(|| a.zeroed("element_plastic_state", 32 * ne as u64, storage)),
            // Failure: the bodies' criteria, and per element (eroded energy, flag, damage, 0);
            // zero is the intact state.
            failures: failure.then(|| {
                a.init(
                    "body_failure",
                    bytemuck::cast_slice(&element::failures(model)),
                    storage,
                )
            }),
            erosion: failure.then(|| a.zeroed("element_erosion", 16 * ne as u64, storage)),
            eroded_list: failure.then(|| {
                let cap = if plan.has(Stage::Contact) { ne } else { 1 };
                a.zeroed("element_eroded_list", 4 * cap as u64, storage)
            }),
            // v^{n-1/2} per node, then the f32 rounding residuals of each node's last velocity
            // update and of its last displacement update (node.wgsl's compensated sums, joined by
            // the contact's corrections), carried to the next step (and in the checkpoint like
            // every allocated buffer).
            v_prev: a.zeroed("v_prev", 24 * nn as u64, storage),
            u_snap: has_fields.then(|| a.zeroed("u_snapshot", 8 * nn as u64, storage)),
            // Load curves: only for scenes with velocity boundaries or pressure loads (their
            // kernels declare the table), at least one entry.
            curves: (nc > 0 || np > 0).then(|| {
                a.init(
                    "load_curves",
                    bytemuck::cast_slice(&boundary::curve_table(model).0),
                    storage,
                )
            }),
            constraints: (nc > 0).then(|| {
                a.init(
                    "constraints",
                    bytemuck::cast_slice(&boundary::constraints(model)),
                    storage,
                )
            }),
            sample_src: a.zeroed(
                "sample_sources",
                16 * (nn + ne + nc + nl + npl + nf) as u64,
                storage,
            ),
            // First-level reduction results; when the control workgroup reduces directly
            // (`fused`) they are never read or written, and only the minimum size is bound (the
            // kernels declare them).
            dt_partial: a.zeroed(
                "dt_partials",
                if fused {
                    0
                } else {
                    8 * params.dt_groups as u64
                },
                storage,
            ),
            instances: a.init("instances", bytemuck::cast_slice(&instances), storage),
            sum_partial: a.zeroed(
                "sum_partials",
                if fused { 0 } else { 16 * first as u64 },
                storage,
            ),
            history: a.zeroed("history", 4 * (row_cap as u64 * row_stride as u64), storage),
            times: a.init("times", bytemuck::cast_slice(&times), storage),
            inst_res: a.zeroed("instance_sums", 16 * instances.len() as u64, storage),
            indirect: a.init(
                "indirect",
                bytemuck::cast_slice(&indirect_init),
                storage | U::INDIRECT,
            ),
        };

        let contact = match (contact_set, &kernels.contact) {
            (Some(set), Some(p)) => {
                let path = super::contact::Path::choose(
                    &contact,
                    set.tables().nodes.len(),
                    set.slot_count(),
                    device_type,
                )?;
                Some(ContactState::new(
                    device,
                    p,
                    model,
                    set,
                    Shared {
                        ctrl: &b.ctrl,
                        nodes: &b.nodes,
                        v_prev: &b.v_prev,
                        sample_src: &b.sample_src,
                    },
                    row_cap,
                    path,
                    contact.candidate_capacity,
                    &mut a,
                )?)
            }
            _ => None,
        };

        let bind = Binds::new(device, kernels, &b);
        let (allocated, buffers) = a.finish();
        Ok(GpuState {
            params,
            allocated,
            buffers,
            ctrl: b.ctrl,
            nodes: b.nodes,
            elem_force: b.elem_force,
            elem_dt: b.elem_dt,
            v_prev: b.v_prev,
            u_snap: b.u_snap,
            plastic: b.plastic,
            erosion: b.erosion,
            eroded_list: b.eroded_list,
            damage: failure && model.has_damage(),
            history: b.history,
            indirect: b.indirect,
            contact,
            groups: Groups {
                element: (ne as u32).div_ceil(element::WORKGROUP),
                node: (nn as u32).div_ceil(node::WORKGROUP),
                boundary: (nc as u32).div_ceil(boundary::WORKGROUP),
                pressure: (np as u32).div_ceil(loads::WORKGROUP),
            },
            bind,
        })
    }

    /// Total bytes allocated on the device.
    pub fn bytes(&self) -> u64 {
        self.allocated.iter().map(|(_, b)| b).sum()
    }
}
