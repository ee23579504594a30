//! The device probe's report (`ricochet bench --probe`): the adapter, the streaming bandwidth
//! of a `vec4<f32>` copy and the dispatch floor measured by [`crate::gpu::probe`], and the bound
//! that bandwidth puts on the bench block's throughput at the bytes per element-cycle of
//! [`super::bytes`]. GPU only: the probe times a device.

use serde::Serialize;

use super::bytes::{block_bytes_per_element_cycle, bound};
use crate::error::Result;
use crate::gpu::probe::{bandwidth, dispatch_floor, Bandwidth, DispatchFloor, ProbeKernels};
use crate::gpu::GpuContext;

/// What `ricochet bench --probe` measures and reports.
#[derive(Debug, Clone, Serialize)]
pub struct ProbeReport {
    /// The adapter, as the bench tables name it.
    pub adapter: String,
    /// The adapter's own name.
    pub name: String,
    /// Its driver.
    pub driver: String,
    /// What the driver says of its version.
    pub driver_info: String,
    /// Whether the device times below come from timestamp queries.
    pub timestamps: bool,
    /// The copy.
    pub bandwidth: Bandwidth,
    /// The dispatch floor.
    pub dispatch: DispatchFloor,
    /// The bench block's bytes per element-cycle (BENCHMARKS.md's traffic table).
    pub block_bytes_per_element_cycle: f64,
    /// The block's element-cycles per second at the copy's median bandwidth, if every byte
    /// of the table moved at that speed and nothing else took time.
    pub block_bound_element_cycles_per_second: f64,
}

/// Runs the probes on `ctx`: a copy of `bytes` bytes (at most the adapter's largest storage
/// binding) and `dispatches` dispatches in one pass, each `repeats` times.
///
/// # Errors
/// [`crate::Error::Gpu`] when the device is lost.
pub fn probe(ctx: &GpuContext, bytes: u64, dispatches: u32, repeats: u32) -> Result<ProbeReport> {
    let kernels = ProbeKernels::new(&ctx.device);
    let bandwidth = bandwidth(ctx, &kernels, bytes, repeats)?;
    let dispatch = dispatch_floor(ctx, &kernels, dispatches, repeats)?;
    let per = block_bytes_per_element_cycle();
    Ok(ProbeReport {
        adapter: ctx.adapter_name(),
        name: ctx.info.name.clone(),
        driver: ctx.info.driver.clone(),
        driver_info: ctx.info.driver_info.clone(),
        timestamps: ctx.timestamps,
        block_bytes_per_element_cycle: per,
        block_bound_element_cycles_per_second: bound(bandwidth.gb_per_s, per),
        bandwidth,
        dispatch,
    })
}

/// The report in words, a line per measure.
pub fn probe_summary(r: &ProbeReport) -> String {
    let b = &r.bandwidth;
    let d = &r.dispatch;
    format!(
        "adapter: {}\n\
         driver: {} {}\n\
         copy: {:.1} GB/s median, {:.1} best ({} copies of {} MiB read and {} MiB written, {}; \
         the copy {})\n\
         dispatch floor: {:.2} us per dispatch with a barrier between them, {:.2} us without \
         ({} dispatches in one pass, median of {}, {}); wall clock {:.2} and {:.2} us\n\
         bench block: {} B per element-cycle, so at most {:.3e} element-cycles/s at {:.1} GB/s\n",
        r.adapter,
        r.driver,
        r.driver_info,
        b.gb_per_s,
        b.gb_per_s_best,
        b.repeats,
        b.bytes >> 20,
        b.bytes >> 20,
        b.timer,
        if b.verified {
            "checked"
        } else {
            "WRONG: the destination differs from the source"
        },
        d.chained_us,
        d.empty_us,
        d.dispatches,
        d.repeats,
        d.timer,
        d.chained_wall_us,
        d.empty_wall_us,
        r.block_bytes_per_element_cycle,
        r.block_bound_element_cycles_per_second,
        b.gb_per_s
    )
}
