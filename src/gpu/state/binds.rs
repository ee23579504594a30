//! The bind groups of a scene's kernels, built once from its buffers ([`super::Buffers`]): one per
//! kernel, its entries the bindings its `shaders/*.wgsl` declares (the optional ones only where
//! the scene has their buffers). The contact stage's are the contact state's
//! ([`crate::gpu::contact::ContactState`]).

use super::Buffers;
use crate::gpu::kernels::Kernels;

/// The bind group of each kernel (group 0), in step order (`None`: a kernel the scene does not
/// compile).
#[derive(Debug)]
pub(super) struct Binds {
    pub(super) element: wgpu::BindGroup,
    pub(super) min_dt: wgpu::BindGroup,
    pub(super) control_dt: wgpu::BindGroup,
    pub(super) pressure: Option<wgpu::BindGroup>,
    pub(super) node: wgpu::BindGroup,
    pub(super) boundary: Option<wgpu::BindGroup>,
    pub(super) load_work: Option<wgpu::BindGroup>,
    pub(super) sum: wgpu::BindGroup,
    pub(super) sum_instances: wgpu::BindGroup,
    pub(super) control_end: wgpu::BindGroup,
}

/// The bind group `label` of `pipeline`'s group 0 (its layout derived from the WGSL): the
/// buffers of `list` at their bindings, and of `optional` those present.
fn bind(
    device: &wgpu::Device,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    list: &[(u32, &wgpu::Buffer)],
    optional: &[(u32, Option<&wgpu::Buffer>)],
) -> wgpu::BindGroup {
    let present = optional.iter().filter_map(|&(i, b)| b.map(|b| (i, b)));
    let entries: Vec<wgpu::BindGroupEntry<'_>> = list
        .iter()
        .copied()
        .chain(present)
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    })
}

impl Binds {
    /// The bind groups of `kernels` on the buffers `b`.
    pub(super) fn new(device: &wgpu::Device, kernels: &Kernels, b: &Buffers) -> Binds {
        let element = bind(
            device,
            "element",
            &kernels.element,
            &[
                (0, &b.params),
                (1, &b.elements),
                (2, &b.bodies),
                (3, &b.nodes),
                (4, &b.elem_force),
                (5, &b.elem_dt),
                (6, &b.ctrl),
                (7, &b.sample_src),
                (10, &b.v_prev),
            ],
            &[
                (8, b.elem_state.as_ref()),
                (9, b.plastic.as_ref()),
                (11, b.failures.as_ref()),
                (12, b.erosion.as_ref()),
                (13, b.eroded_list.as_ref()),
            ],
        );
        let node = bind(
            device,
            "node",
            &kernels.node,
            &[
                (0, &b.params),
                (1, &b.nodes),
                (2, &b.inv_mass),
                (3, &b.offsets),
                (4, &b.slots),
                (5, &b.elem_force),
                (6, &b.v_prev),
                (7, &b.ctrl),
                (8, &b.sample_src),
            ],
            &[(9, b.u_snap.as_ref()), (10, b.v_old.as_ref())],
        );
        let boundary = match (&kernels.boundary, &b.constraints, &b.curves) {
            (Some(p), Some(c), Some(cv)) => Some(bind(
                device,
                "boundary",
                p,
                &[
                    (0, &b.params),
                    (1, c),
                    (2, &b.nodes),
                    (3, &b.v_prev),
                    (4, &b.sample_src),
                    (5, &b.ctrl),
                    (6, cv),
                ],
                &[],
            )),
            _ => None,
        };
        let pressure = match (&kernels.pressure, &b.pressure, &b.curves) {
            (Some(p), Some(e), Some(cv)) => Some(bind(
                device,
                "pressure_force",
                p,
                &[
                    (0, &b.params),
                    (1, &b.ctrl),
                    (2, e),
                    (3, &b.elem_force),
                    (10, cv),
                ],
                &[],
            )),
            _ => None,
        };
        let load_work = match (&kernels.load_work, &b.v_old) {
            (Some(p), Some(vo)) => Some(bind(
                device,
                "load_work",
                p,
                &[
                    (0, &b.params),
                    (1, &b.ctrl),
                    (3, &b.elem_force),
                    (4, &b.nodes),
                    (5, &b.inv_mass),
                    (6, &b.offsets),
                    (7, &b.slots),
                    (8, vo),
                    (9, &b.sample_src),
                ],
                &[],
            )),
            _ => None,
        };
        Binds {
            element,
            min_dt: bind(
                device,
                "min_dt",
                &kernels.min_dt,
                &[(0, &b.params), (1, &b.elem_dt), (2, &b.dt_partial)],
                &[],
            ),
            control_dt: bind(
                device,
                "control_dt",
                &kernels.control_dt,
                &[
                    (0, &b.params),
                    (1, &b.ctrl),
                    (2, &b.dt_partial),
                    (8, &b.elem_dt),
                ],
                &[],
            ),
            node,
            boundary,
            pressure,
            load_work,
            sum: bind(
                device,
                "sum",
                &kernels.sum,
                &[
                    (0, &b.params),
                    (3, &b.instances),
                    (4, &b.sample_src),
                    (5, &b.sum_partial),
                ],
                &[],
            ),
            sum_instances: bind(
                device,
                "sum_instances",
                &kernels.sum_instances,
                &[
                    (0, &b.params),
                    (3, &b.instances),
                    (5, &b.sum_partial),
                    (6, &b.inst_res),
                ],
                &[],
            ),
            control_end: bind(
                device,
                "control_end",
                &kernels.control_end,
                &[
                    (0, &b.params),
                    (1, &b.ctrl),
                    (3, &b.instances),
                    (5, &b.history),
                    (6, &b.times),
                    (7, &b.indirect),
                    (9, &b.sample_src),
                    (10, &b.inst_res),
                ],
                &[],
            ),
        }
    }
}
