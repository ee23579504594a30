//! Recording a step into a compute pass: the stages in step order, each a kernel of
//! [`super::super::kernels::Kernels`] with its bind group of [`super::GpuState`] (built once), and
//! parts of a step alone for the kernel tests, the resumed step after a contact search and the
//! bench's timings. The CPU reference takes the same stages in the same order
//! ([`crate::step::cpu::CpuSolver`]).

use super::GpuState;
use crate::gpu::kernels::Kernels;

/// `pipeline` with `bind` as group 0 over `groups` workgroups.
fn dispatch(
    pass: &mut wgpu::ComputePass<'_>,
    pipeline: &wgpu::ComputePipeline,
    bind: &wgpu::BindGroup,
    groups: u32,
) {
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind, &[]);
    pass.dispatch_workgroups(groups, 1, 1);
}

/// [`dispatch`] of a kernel the scene may not have (`None`: it has not, nor its bind group).
fn dispatch_if(
    pass: &mut wgpu::ComputePass<'_>,
    pipeline: &Option<wgpu::ComputePipeline>,
    bind: &Option<wgpu::BindGroup>,
    groups: u32,
) {
    if let (Some(p), Some(b)) = (pipeline, bind) {
        dispatch(pass, p, b, groups);
    }
}

impl GpuState {
    /// Records one step into `pass`: element, stable step, node update, boundaries, samples, control.
    pub fn record_step(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        self.record_forces(kernels, pass);
        self.record_update(kernels, pass);
        self.record_tail(kernels, pass);
    }

    /// Records the first part of a step: element forces, the stable step and its control.
    pub fn record_forces(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        self.record_element(kernels, pass);
        self.record_dt(kernels, pass);
    }

    /// Records the uncoupled update of a step: pressure loads, the node update, boundaries.
    pub fn record_update(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        let (b, g) = (&self.bind, &self.groups);
        dispatch_if(pass, &kernels.pressure, &b.pressure, g.pressure);
        self.record_node(kernels, pass);
        dispatch_if(pass, &kernels.boundary, &b.boundary, g.boundary);
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
        dispatch_if(pass, &kernels.load_work, &b.load_work, self.groups.node);
        if self.params.sum_groups > 0 {
            pass.set_pipeline(&kernels.sum);
            pass.set_bind_group(0, &b.sum, &[]);
            pass.dispatch_workgroups_indirect(&self.indirect, 0);
            pass.set_pipeline(&kernels.sum_instances);
            pass.set_bind_group(0, &b.sum_instances, &[]);
            pass.dispatch_workgroups_indirect(&self.indirect, 12);
        }
        dispatch(pass, &kernels.control_end, &b.control_end, 1);
    }

    /// Records only the element stage (for kernel tests and stage timing).
    pub fn record_element(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        dispatch(
            pass,
            &kernels.element,
            &self.bind.element,
            self.groups.element,
        );
    }

    /// Records only the node stage (for stage timing).
    pub fn record_node(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        dispatch(pass, &kernels.node, &self.bind.node, self.groups.node);
    }

    /// Records the stable step: its first-level reduction (unless the control workgroup reduces
    /// directly) and its control.
    fn record_dt(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        if self.params.dt_groups > 0 {
            dispatch(
                pass,
                &kernels.min_dt,
                &self.bind.min_dt,
                self.params.dt_groups,
            );
        }
        dispatch(pass, &kernels.control_dt, &self.bind.control_dt, 1);
    }

    /// Records only the stable-step reduction and control (for stage timing).
    pub fn record_control(&self, kernels: &Kernels, pass: &mut wgpu::ComputePass<'_>) {
        self.record_dt(kernels, pass);
        dispatch(pass, &kernels.control_end, &self.bind.control_end, 1);
    }
}
