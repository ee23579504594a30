//! Device-resident simulation state: the buffers a scene needs (and no others) and the bind groups,
//! built once; [`GpuState::record_step`] records one step as labelled dispatches.

use crate::error::{Error, Result};
use crate::model::Model;
use crate::plan::{Plan, Stage};
use crate::scene::{Formulation, HourglassForm, MaterialModel};
use crate::step::Schedule;

use super::alloc::Alloc;
use super::contact::{ContactState, Shared};
use super::kernels::Kernels;
use super::layout::*;
use super::{boundary, element, loads, node, reduce};
use crate::contact::ContactSet;

/// Nodes + elements + constraints up to which a CPU adapter reduces in one workgroup (the
/// control workgroup, instead of a first level over many workgroups and a dispatch of its own).
/// On lavapipe a dispatch costs about 29 us of hand-off to its thread pool, more than the
/// control workgroup takes to reduce these values itself. Measured on the 2-core machine
/// (session 19, the same scene fused and not, alternated in one process): the 10^4 pile
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
    pub(crate) history: wgpu::Buffer,
    pub(crate) indirect: wgpu::Buffer,
    /// Contact buffers (scenes with contact only).
    pub contact: Option<ContactState>,
    groups: Groups,
    bind: Binds,
}

#[derive(Debug, Clone, Copy)]
struct Groups {
    element: u32,
    node: u32,
    boundary: u32,
    pressure: u32,
}

#[derive(Debug)]
struct Binds {
    element: wgpu::BindGroup,
    min_dt: wgpu::BindGroup,
    control_dt: wgpu::BindGroup,
    node: wgpu::BindGroup,
    boundary: Option<wgpu::BindGroup>,
    pressure: Option<wgpu::BindGroup>,
    load_work: Option<wgpu::BindGroup>,
    sum: wgpu::BindGroup,
    sum_instances: wgpu::BindGroup,
    control_end: wgpu::BindGroup,
}

fn entries<'a>(list: &[(u32, &'a wgpu::Buffer)]) -> Vec<wgpu::BindGroupEntry<'a>> {
    list.iter()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: buffer.as_entire_binding(),
        })
        .collect()
}

fn bind(
    device: &wgpu::Device,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    list: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries(list),
    })
}

/// Sample or snapshot times k * interval, k = 0.. up to past `end`, in ticks.
fn time_table(interval: f64, end: f64) -> Vec<[u32; 2]> {
    let count = ((end / interval).floor() as usize + 2).min(1 << 22);
    (0..count)
        .map(|k| ticks(k as f64 * interval, end))
        .collect()
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
        let mut a = Alloc {
            device,
            list: Vec::new(),
            buffers: Vec::new(),
        };

        // Static data.
        let bodies: Vec<GpuBody> = model
            .bodies
            .iter()
            .map(|b| {
                let p = &b.params;
                GpuBody {
                    model: match p.model {
                        MaterialModel::LinearElastic => 0,
                        MaterialModel::NeoHookean => 1,
                        MaterialModel::J2Plastic => 2,
                    },
                    formulation: match p.formulation {
                        Formulation::PlaneStrain => 0,
                        Formulation::PlaneStress => 1,
                        Formulation::Axisymmetric => 2,
                    },
                    hourglass: match p.hourglass {
                        HourglassForm::None => 0,
                        HourglassForm::Viscous => 1,
                        HourglassForm::Stiffness => 2,
                    },
                    density: p.density as f32,
                    thickness: p.thickness as f32,
                    lambda: p.lambda as f32,
                    mu: p.mu as f32,
                    lambda_plane: p.lambda_plane as f32,
                    wave_modulus: p.wave_modulus as f32,
                    hourglass_coefficient: p.hourglass_coefficient as f32,
                    bulk_linear: p.bulk_linear as f32,
                    bulk_quadratic: p.bulk_quadratic as f32,
                    mass: b.mass as f32,
                    yield_stress: p.yield_stress.min(f32::MAX as f64) as f32,
                    hardening: p.hardening as f32,
                    jc_b: p.jc_b as f32,
                    jc_n: p.jc_n as f32,
                    jc_c: p.jc_c as f32,
                    jc_rate0: p.jc_rate0 as f32,
                    ..Default::default()
                }
            })
            .collect();
        let elems: Vec<GpuElement> = (0..ne)
            .map(|e| {
                let c = model.corners[e];
                GpuElement {
                    c01: [
                        c[0][0] as f32,
                        c[0][1] as f32,
                        c[1][0] as f32,
                        c[1][1] as f32,
                    ],
                    c23: [
                        c[2][0] as f32,
                        c[2][1] as f32,
                        c[3][0] as f32,
                        c[3][1] as f32,
                    ],
                    nodes: model.quads[e],
                    body: model.element_body[e],
                    radius: model.radius.get(e).copied().unwrap_or(0.0) as f32,
                    _pad: [0; 2],
                }
            })
            .collect();
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

        // Sample instances: one per body (its nodes), the elements, the constraints.
        let rg = kernels.features.reduce_group;
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
        if has_loads {
            push(nn + ne + nc, nl, 1.0);
        }
        // J2 plastic work, one accumulator per element after the loads' (element.wgsl).
        let plastic = kernels.features.plastic;
        let npl = if plastic { ne } else { 0 };
        if plastic {
            push(nn + ne + nc + nl, npl, 1.0);
        }
        // Small models on CPU adapters: the control workgroup reduces directly (see control.wgsl).
        let fused = fused.unwrap_or(
            kernels.features.reduce_group == 64
                && nn + ne + nc + nl + npl <= FUSED_LIMIT
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
        // Time, step, dt, the five energies, the plastic work with a plastic body, then per body.
        let row_stride = 9 + u32::from(plastic) + 2 * nb as u32;
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
            _pad: [0; 3],
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

        let params_buf = a.init("params", bytemuck::bytes_of(&params), U::UNIFORM);
        let ctrl = a.init(
            "control",
            bytemuck::bytes_of(&control),
            storage | U::COPY_SRC | U::COPY_DST,
        );
        let elems_buf = a.init("elements", bytemuck::cast_slice(&elems), storage);
        let bodies_buf = a.init("bodies", bytemuck::cast_slice(&bodies), storage);
        let nodes = a.init(
            "nodes",
            bytemuck::cast_slice(&node_state),
            storage | U::COPY_SRC | U::COPY_DST,
        );
        let inv_mass_buf = a.init("inv_mass", bytemuck::cast_slice(&inv_mass), storage);
        let offsets_buf = a.init("adjacency_offsets", bytemuck::cast_slice(&offsets), storage);
        let slots_buf = a.init("adjacency_slots", bytemuck::cast_slice(&slots), storage);
        let elem_force = a.zeroed(
            "element_forces",
            32 * ne as u64 + 8 * np as u64,
            storage | U::COPY_SRC,
        );
        let press_buf = (np > 0).then(|| {
            a.init(
                "pressure_entries",
                bytemuck::cast_slice(&press_data),
                storage,
            )
        });
        let v_old = has_loads.then(|| a.zeroed("v_old", 8 * nn as u64, storage));
        let elem_dt = a.zeroed("element_dt", 4 * ne as u64, storage | U::COPY_SRC);
        // Two vec4 per element, three with axisymmetric bodies (the hoop bulk stress).
        let es_words = if kernels.features.axisymmetric { 3 } else { 2 };
        let elem_state = plan
            .has_dissipation()
            .then(|| a.zeroed("element_dissipation", 16 * es_words * ne as u64, storage));
        // J2: C_p^-1 - I and (alpha, plastic work) per element; zero is the virgin state.
        let plastic_buf = plastic.then(|| {
            a.zeroed(
                "element_plastic_state",
                32 * ne as u64,
                storage | U::COPY_SRC | U::COPY_DST,
            )
        });
        // v^{n-1/2} per node, then the f32 rounding residuals of each node's last velocity update
        // and of its last displacement update (node.wgsl's compensated sums, joined by the
        // contact's corrections), carried to the next step (and in the checkpoint like every
        // allocated buffer).
        let v_prev = a.zeroed("v_prev", 24 * nn as u64, storage | U::COPY_SRC);
        let u_snap =
            has_fields.then(|| a.zeroed("u_snapshot", 8 * nn as u64, storage | U::COPY_SRC));
        let cons: Vec<GpuConstraint> = model
            .constraints
            .iter()
            .map(|c| GpuConstraint {
                node: c.node,
                mask: u32::from(c.vx.is_some()) | (u32::from(c.vy.is_some()) << 1),
                vx: c.vx.unwrap_or(0.0) as f32,
                vy: c.vy.unwrap_or(0.0) as f32,
                mass: model.mass[c.node as usize] as f32,
                curve_x: c.cx.unwrap_or(u32::MAX),
                curve_y: c.cy.unwrap_or(u32::MAX),
                _pad: 0.0,
            })
            .collect();
        // Load curves: only for scenes with velocity boundaries or pressure loads (their kernels
        // declare the table), at least one entry.
        let curves_buf = (nc > 0 || np > 0).then(|| {
            a.init(
                "load_curves",
                bytemuck::cast_slice(&boundary::curve_table(model).0),
                storage,
            )
        });
        let cons_buf =
            (nc > 0).then(|| a.init("constraints", bytemuck::cast_slice(&cons), storage));
        let sample_src = a.zeroed(
            "sample_sources",
            16 * (nn + ne + nc + nl + npl) as u64,
            storage,
        );
        // First-level reduction results; when the control workgroup reduces directly (`fused`)
        // they are never read or written, and only the minimum size is bound (the kernels
        // declare them).
        let dt_partial = a.zeroed(
            "dt_partials",
            if fused {
                0
            } else {
                8 * params.dt_groups as u64
            },
            storage,
        );
        let instances_buf = a.init("instances", bytemuck::cast_slice(&instances), storage);
        let sum_partial = a.zeroed(
            "sum_partials",
            if fused { 0 } else { 16 * first as u64 },
            storage,
        );
        let history = a.zeroed(
            "history",
            4 * (row_cap as u64 * row_stride as u64),
            storage | U::COPY_SRC,
        );
        let times_buf = a.init("times", bytemuck::cast_slice(&times), storage);
        let inst_res = a.zeroed("instance_sums", 16 * instances.len() as u64, storage);
        let indirect_init = [sum_groups, 1, 1, params.inst_groups, 1, 1];
        let indirect = a.init(
            "indirect",
            bytemuck::cast_slice(&indirect_init),
            storage | U::INDIRECT,
        );

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
                        ctrl: &ctrl,
                        nodes: &nodes,
                        v_prev: &v_prev,
                        sample_src: &sample_src,
                    },
                    row_cap,
                    path,
                    contact.candidate_capacity,
                    &mut a,
                )?)
            }
            _ => None,
        };

        // Bind groups, once.
        let mut el: Vec<(u32, &wgpu::Buffer)> = vec![
            (0, &params_buf),
            (1, &elems_buf),
            (2, &bodies_buf),
            (3, &nodes),
            (4, &elem_force),
            (5, &elem_dt),
            (6, &ctrl),
            (7, &sample_src),
            (10, &v_prev),
        ];
        if let Some(s) = &elem_state {
            el.push((8, s));
        }
        if let Some(s) = &plastic_buf {
            el.push((9, s));
        }
        let mut nd: Vec<(u32, &wgpu::Buffer)> = vec![
            (0, &params_buf),
            (1, &nodes),
            (2, &inv_mass_buf),
            (3, &offsets_buf),
            (4, &slots_buf),
            (5, &elem_force),
            (6, &v_prev),
            (7, &ctrl),
            (8, &sample_src),
        ];
        if let Some(s) = &u_snap {
            nd.push((9, s));
        }
        if let Some(s) = &v_old {
            nd.push((10, s));
        }
        let bind = Binds {
            element: bind(device, "element", &kernels.element, &el),
            min_dt: bind(
                device,
                "min_dt",
                &kernels.min_dt,
                &[(0, &params_buf), (1, &elem_dt), (2, &dt_partial)],
            ),
            control_dt: bind(
                device,
                "control_dt",
                &kernels.control_dt,
                &[
                    (0, &params_buf),
                    (1, &ctrl),
                    (2, &dt_partial),
                    (8, &elem_dt),
                ],
            ),
            node: bind(device, "node", &kernels.node, &nd),
            boundary: match (&kernels.boundary, &cons_buf, &curves_buf) {
                (Some(p), Some(c), Some(cv)) => Some(bind(
                    device,
                    "boundary",
                    p,
                    &[
                        (0, &params_buf),
                        (1, c),
                        (2, &nodes),
                        (3, &v_prev),
                        (4, &sample_src),
                        (5, &ctrl),
                        (6, cv),
                    ],
                )),
                _ => None,
            },
            pressure: match (&kernels.pressure, &press_buf, &curves_buf) {
                (Some(p), Some(e), Some(cv)) => Some(bind(
                    device,
                    "pressure_force",
                    p,
                    &[
                        (0, &params_buf),
                        (1, &ctrl),
                        (2, e),
                        (3, &elem_force),
                        (10, cv),
                    ],
                )),
                _ => None,
            },
            load_work: match (&kernels.load_work, &v_old) {
                (Some(p), Some(vo)) => Some(bind(
                    device,
                    "load_work",
                    p,
                    &[
                        (0, &params_buf),
                        (1, &ctrl),
                        (3, &elem_force),
                        (4, &nodes),
                        (5, &inv_mass_buf),
                        (6, &offsets_buf),
                        (7, &slots_buf),
                        (8, vo),
                        (9, &sample_src),
                    ],
                )),
                _ => None,
            },
            sum: bind(
                device,
                "sum",
                &kernels.sum,
                &[
                    (0, &params_buf),
                    (3, &instances_buf),
                    (4, &sample_src),
                    (5, &sum_partial),
                ],
            ),
            sum_instances: bind(
                device,
                "sum_instances",
                &kernels.sum_instances,
                &[
                    (0, &params_buf),
                    (3, &instances_buf),
                    (5, &sum_partial),
                    (6, &inst_res),
                ],
            ),
            control_end: bind(
                device,
                "control_end",
                &kernels.control_end,
                &[
                    (0, &params_buf),
                    (1, &ctrl),
                    (3, &instances_buf),
                    (5, &history),
                    (6, &times_buf),
                    (7, &indirect),
                    (9, &sample_src),
                    (10, &inst_res),
                ],
            ),
        };
        Ok(GpuState {
            params,
            allocated: a.list,
            buffers: a.buffers,
            ctrl,
            nodes,
            elem_force,
            elem_dt,
            v_prev,
            u_snap,
            plastic: plastic_buf,
            history,
            indirect,
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

    /// Records one step into `pass`: element, stable step, node update, boundaries, samples, control.
    pub fn record_step(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        self.record_forces(kernels, pass);
        self.record_update(kernels, pass);
        self.record_tail(kernels, pass);
    }

    /// Records the first part of a step: element forces, the stable step and its control.
    pub fn record_forces(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        let b = &self.bind;
        pass.set_pipeline(&kernels.element);
        pass.set_bind_group(0, &b.element, &[]);
        pass.dispatch_workgroups(self.groups.element, 1, 1);
        if self.params.dt_groups > 0 {
            pass.set_pipeline(&kernels.min_dt);
            pass.set_bind_group(0, &b.min_dt, &[]);
            pass.dispatch_workgroups(self.params.dt_groups, 1, 1);
        }
        pass.set_pipeline(&kernels.control_dt);
        pass.set_bind_group(0, &b.control_dt, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }

    /// Records the uncoupled update of a step: pressure loads, the node update, boundaries.
    pub fn record_update(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        let b = &self.bind;
        if let (Some(p), Some(bg)) = (&kernels.pressure, &b.pressure) {
            pass.set_pipeline(p);
            pass.set_bind_group(0, bg, &[]);
            pass.dispatch_workgroups(self.groups.pressure, 1, 1);
        }
        pass.set_pipeline(&kernels.node);
        pass.set_bind_group(0, &b.node, &[]);
        pass.dispatch_workgroups(self.groups.node, 1, 1);
        if let (Some(p), Some(bg)) = (&kernels.boundary, &b.boundary) {
            pass.set_pipeline(p);
            pass.set_bind_group(0, bg, &[]);
            pass.dispatch_workgroups(self.groups.boundary, 1, 1);
        }
    }

    /// Records the end of a step from the contact stage on: contact, load work, sample sums, control.
    /// (After a search stopped a step in its contact stage, the host resumes it with this.)
    pub fn record_tail(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        if let (Some(k), Some(c)) = (&kernels.contact, &self.contact) {
            c.record(k, pass);
        }
        self.record_end(kernels, pass);
    }

    /// Records the last part of a step: load work, sample sums, the history row and control.
    pub fn record_end(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        let b = &self.bind;
        if let (Some(p), Some(bg)) = (&kernels.load_work, &b.load_work) {
            pass.set_pipeline(p);
            pass.set_bind_group(0, bg, &[]);
            pass.dispatch_workgroups(self.groups.node, 1, 1);
        }
        if self.params.sum_groups > 0 {
            pass.set_pipeline(&kernels.sum);
            pass.set_bind_group(0, &b.sum, &[]);
            pass.dispatch_workgroups_indirect(&self.indirect, 0);
            pass.set_pipeline(&kernels.sum_instances);
            pass.set_bind_group(0, &b.sum_instances, &[]);
            pass.dispatch_workgroups_indirect(&self.indirect, 12);
        }
        pass.set_pipeline(&kernels.control_end);
        pass.set_bind_group(0, &b.control_end, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }

    /// Records only the element stage (for kernel tests and stage timing).
    pub fn record_element(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        pass.set_pipeline(&kernels.element);
        pass.set_bind_group(0, &self.bind.element, &[]);
        pass.dispatch_workgroups(self.groups.element, 1, 1);
    }

    /// Records only the node stage (for stage timing).
    pub fn record_node(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        pass.set_pipeline(&kernels.node);
        pass.set_bind_group(0, &self.bind.node, &[]);
        pass.dispatch_workgroups(self.groups.node, 1, 1);
    }

    /// Records only the stable-step reduction and control (for stage timing).
    pub fn record_control(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        let b = &self.bind;
        if self.params.dt_groups > 0 {
            pass.set_pipeline(&kernels.min_dt);
            pass.set_bind_group(0, &b.min_dt, &[]);
            pass.dispatch_workgroups(self.params.dt_groups, 1, 1);
        }
        pass.set_pipeline(&kernels.control_dt);
        pass.set_bind_group(0, &b.control_dt, &[]);
        pass.dispatch_workgroups(1, 1, 1);
        pass.set_pipeline(&kernels.control_end);
        pass.set_bind_group(0, &b.control_end, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }

    /// Total bytes allocated on the device.
    pub fn bytes(&self) -> u64 {
        self.allocated.iter().map(|(_, b)| b).sum()
    }
}
