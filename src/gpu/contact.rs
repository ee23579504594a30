//! Contact kernel (`shaders/contact.wgsl`), compiled, allocated and dispatched only for scenes with
//! contact or rigid walls: narrow phase, penalty impulses and the diagonal-mass Lagrange
//! correction by coloured projected Gauss-Seidel, in one workgroup. The broad phase stays on the
//! host ([`crate::contact::ContactSet::search_tables`], parry's BVH): the kernel stops the run when a
//! contact node has moved more than half the search margin since the last search, and
//! [`ContactState::search`] uploads new candidates and colours. CPU reference:
//! [`crate::contact::ContactSet::apply`].
#![allow(missing_docs)]

use bytemuck::{Pod, Zeroable};

use crate::contact::{ContactSet, SearchTables, MAX_SWEEPS};
use crate::model::Model;

use super::kernels::{compute_pipeline, Features};
use super::state::Alloc;

/// WGSL source.
pub const SOURCE: &str = include_str!("../../shaders/contact.wgsl");

/// Control state set by the contact kernel when a search is due (WGSL `STATE_SEARCH`).
pub const STATE_SEARCH: u32 = 4;

pub(crate) fn pipeline(device: &wgpu::Device, features: Features) -> wgpu::ComputePipeline {
    compute_pipeline(device, "contact", SOURCE, features, "main", None)
}

/// Mirror of WGSL `ContactParams`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct ContactParams {
    pub n_local: u32,
    pub n_slots: u32,
    pub n_ifaces: u32,
    pub n_colors: u32,
    pub margin: f32,
    pub max_sweeps: u32,
    pub searched: u32,
    pub hist_stride: u32,
    pub color_base: u32,
    pub slot_base: u32,
    pub cand_base: u32,
    pub row_capacity: u32,
}

/// Mirror of WGSL `Slot`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSlot {
    pub info: u32,
    pub s: u32,
    pub np: u32,
    pub nn: u32,
    pub normal: [f32; 2],
    pub point: [f32; 2],
    pub k: f32,
    pub _pad: [f32; 3],
}

/// Mirror of WGSL `Segment`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSegment {
    pub a: u32,
    pub b: u32,
    pub k: f32,
    pub _pad: u32,
}

/// Size of WGSL `Cons` (scratch only).
pub const CONS_SIZE: u64 = 48;

const _: () = assert!(std::mem::size_of::<ContactParams>() == 48);
const _: () = assert!(std::mem::size_of::<GpuSlot>() == 48);
const _: () = assert!(std::mem::size_of::<GpuSegment>() == 16);

/// The shared buffers the contact kernel binds.
pub(crate) struct Shared<'a> {
    pub ctrl: &'a wgpu::Buffer,
    pub nodes: &'a wgpu::Buffer,
    pub v_prev: &'a wgpu::Buffer,
    pub sample_src: &'a wgpu::Buffer,
}

/// Contact buffers, bind group and the host side of the search.
#[derive(Debug)]
pub struct ContactState {
    /// Parameters as last uploaded.
    pub params: ContactParams,
    set: ContactSet,
    /// Global index and reference position of each contact node.
    nodes: Vec<u32>,
    reference: Vec<[f64; 2]>,
    /// Interface names (history columns).
    pub names: Vec<String>,
    /// Broad-phase searches so far.
    pub searches: u64,
    params_buf: wgpu::Buffer,
    search_buf: wgpu::Buffer,
    u_search: wgpu::Buffer,
    pub(crate) history: wgpu::Buffer,
    /// (binding, buffer) of the bind group, to rebuild it when the search buffer grows.
    entries: Vec<(u32, wgpu::Buffer)>,
    pub(crate) bind: wgpu::BindGroup,
}

impl ContactState {
    /// Buffers of `set` (the model's contacts); `alloc` records each buffer for the plan report.
    pub(crate) fn new(
        device: &wgpu::Device,
        pipeline: &wgpu::ComputePipeline,
        model: &Model,
        set: ContactSet,
        shared: Shared<'_>,
        row_capacity: u32,
        alloc: &mut Alloc<'_>,
    ) -> ContactState {
        let t = set.tables();
        let nl = t.nodes.len();
        let reference: Vec<[f64; 2]> = t
            .nodes
            .iter()
            .map(|&g| model.position[g as usize])
            .collect();
        let c_ref: Vec<[f32; 4]> = reference
            .iter()
            .zip(&t.inv_mass)
            .map(|(x, im)| [x[0] as f32, x[1] as f32, im[0] as f32, im[1] as f32])
            .collect();
        let node_words: Vec<[u32; 2]> = t
            .nodes
            .iter()
            .zip(&t.mass)
            .map(|(&g, &m)| [g, (m as f32).to_bits()])
            .collect();
        let slots: Vec<GpuSlot> = t
            .slots
            .iter()
            .map(|s| GpuSlot {
                info: s.interface
                    | (u32::from(s.penalty) << 16)
                    | (u32::from(s.wall) << 17)
                    | (u32::from(s.second_is_slave) << 18),
                s: s.node,
                np: s.neighbours[0],
                nn: s.neighbours[1],
                normal: s.normal.map(|x| x as f32),
                point: s.point.map(|x| x as f32),
                k: s.stiffness as f32,
                _pad: [0.0; 3],
            })
            .collect();
        let segs: Vec<GpuSegment> = t
            .segments
            .iter()
            .map(|seg| GpuSegment {
                a: seg.nodes[0],
                b: seg.nodes[1],
                k: seg.stiffness as f32,
                _pad: 0,
            })
            .collect();
        let init_v: Vec<[f32; 2]> = t
            .nodes
            .iter()
            .map(|&g| model.velocity[g as usize].map(|x| x as f32))
            .collect();
        let names = set.names();
        let ni = names.len() as u32;
        let hist_stride = 1 + 4 * ni;
        let params = ContactParams {
            n_local: nl as u32,
            n_slots: slots.len() as u32,
            n_ifaces: ni,
            margin: set.margin() as f32,
            max_sweeps: MAX_SWEEPS as u32,
            hist_stride,
            color_base: slots.len() as u32 + 1,
            row_capacity,
            ..Default::default()
        };
        use wgpu::BufferUsages as U;
        let st = U::STORAGE;
        let params_buf = alloc.init(
            "contact_params",
            bytemuck::bytes_of(&params),
            U::UNIFORM | U::COPY_DST,
        );
        let nodes_buf = alloc.init("contact_nodes", bytemuck::cast_slice(&node_words), st);
        let ref_buf = alloc.init("contact_reference", bytemuck::cast_slice(&c_ref), st);
        let slots_buf = alloc.init("contact_slots", bytemuck::cast_slice(&slots), st);
        let segs_buf = alloc.init("contact_segments", bytemuck::cast_slice(&segs), st);
        let search_len = 2 * slots.len() + 2 + 8 * slots.len();
        let search_buf = alloc.init(
            "contact_search",
            &vec![0u8; 4 * search_len],
            st | U::COPY_DST,
        );
        let u_search = alloc.init("contact_u_search", &vec![0u8; 8 * nl], st | U::COPY_DST);
        let pv = alloc.init("contact_scratch", &vec![0u8; 32 * nl], st);
        let vd: Vec<[f32; 4]> = init_v.iter().map(|v| [v[0], v[1], 0.0, 0.0]).collect();
        let vd = alloc.init("contact_velocities", bytemuck::cast_slice(&vd), st);
        let cons = alloc.init(
            "contact_constraints",
            &vec![0u8; (CONS_SIZE as usize) * slots.len()],
            st,
        );
        let history = alloc.init(
            "contact_history",
            &vec![0u8; 4 * (row_capacity * hist_stride + 4 * (ni + 1)) as usize],
            st | U::COPY_SRC,
        );
        let entries = vec![
            (0, params_buf.clone()),
            (1, shared.ctrl.clone()),
            (2, shared.nodes.clone()),
            (3, shared.v_prev.clone()),
            (4, shared.sample_src.clone()),
            (5, nodes_buf),
            (6, ref_buf),
            (7, slots_buf),
            (8, segs_buf),
            (9, search_buf.clone()),
            (10, u_search.clone()),
            (11, pv),
            (12, vd),
            (13, cons),
            (14, history.clone()),
        ];
        let bind = make_bind(device, pipeline, &entries);
        ContactState {
            params,
            set,
            nodes: t.nodes,
            reference,
            names,
            searches: 0,
            params_buf,
            search_buf,
            u_search,
            history,
            entries,
            bind,
        }
    }

    /// The penalty springs' stable step and what sets it.
    pub fn penalty_step(&self) -> Option<(f64, &str)> {
        self.set.penalty_step()
    }

    /// Global node indices of the contact nodes.
    pub fn nodes(&self) -> &[u32] {
        &self.nodes
    }

    /// Searches again with the contact nodes' state `uv` ((u, v) per contact node, as the kernel
    /// read them), `dt` = dt^{n+1/2} and whether the step is the last (no displacement update):
    /// uploads candidates, colours and the search positions, and marks the step as searched so
    /// that the resumed kernel does not stop again.
    pub(crate) fn search(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pipeline: &wgpu::ComputePipeline,
        uv: &[[f32; 4]],
        dt: f32,
        last: bool,
    ) {
        // The kernel's own f32 arithmetic for u_n and u_n + dt v.
        let mut x_n = Vec::with_capacity(uv.len());
        let mut x_tr = Vec::with_capacity(uv.len());
        let mut u_tr = Vec::with_capacity(uv.len());
        for (s, x) in uv.iter().zip(&self.reference) {
            let (u, v) = ([s[0], s[1]], [s[2], s[3]]);
            let (un, ut) = if last {
                (u, [u[0] + dt * v[0], u[1] + dt * v[1]])
            } else {
                ([u[0] - dt * v[0], u[1] - dt * v[1]], u)
            };
            x_n.push([x[0] + un[0] as f64, x[1] + un[1] as f64]);
            x_tr.push([x[0] + ut[0] as f64, x[1] + ut[1] as f64]);
            u_tr.push(ut);
        }
        let t: SearchTables = self.set.search_tables(&x_n, &x_tr);
        let n_slots = self.params.n_slots as usize;
        let n_colors = t.color_offsets.len().saturating_sub(1);
        let mut words: Vec<u32> =
            Vec::with_capacity(2 * n_slots + n_colors + 2 + t.candidates.len());
        words.extend(&t.candidate_offsets);
        let color_base = words.len() as u32;
        words.extend(&t.color_offsets);
        let slot_base = words.len() as u32;
        words.extend(&t.color_slots);
        let cand_base = words.len() as u32;
        words.extend(&t.candidates);
        let bytes = 4 * words.len() as u64;
        if bytes > self.search_buf.size() {
            self.search_buf = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("contact_search"),
                size: bytes.next_power_of_two(),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            for e in &mut self.entries {
                if e.0 == 9 {
                    e.1 = self.search_buf.clone();
                }
            }
            self.bind = make_bind(device, pipeline, &self.entries);
        }
        queue.write_buffer(&self.search_buf, 0, bytemuck::cast_slice(&words));
        queue.write_buffer(&self.u_search, 0, bytemuck::cast_slice(&u_tr));
        self.params.n_colors = n_colors as u32;
        self.params.color_base = color_base;
        self.params.slot_base = slot_base;
        self.params.cand_base = cand_base;
        self.params.searched = 2;
        queue.write_buffer(&self.params_buf, 0, bytemuck::bytes_of(&self.params));
        self.searches += 1;
    }

    /// After the searched step's tail has been submitted: later steps check the search margin.
    pub(crate) fn resume(&mut self, queue: &wgpu::Queue) {
        self.params.searched = 1;
        queue.write_buffer(&self.params_buf, 0, bytemuck::bytes_of(&self.params));
    }
}

fn make_bind(
    device: &wgpu::Device,
    pipeline: &wgpu::ComputePipeline,
    entries: &[(u32, wgpu::Buffer)],
) -> wgpu::BindGroup {
    let list: Vec<wgpu::BindGroupEntry<'_>> = entries
        .iter()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("contact"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &list,
    })
}
