//! Device probes (`shaders/probe.wgsl`), no part of a step: what a kernel reaches through wgpu on
//! this adapter. [`bandwidth`] times a `vec4<f32>` copy between two buffers (512 MiB each by
//! default, or the adapter's largest storage binding): the streaming bandwidth that the element
//! and node kernels could reach. [`dispatch_floor`] times many dispatches that do nothing in one
//! pass: what a dispatch costs before any work. Both time the device with timestamp queries
//! where the adapter has them, and the wall clock always. The CPU reference of the copy is
//! [`pattern`]: after `fill` and `copy` the destination holds it ([`copied`];
//! `tests/gpu/device.rs` compares the two). `ricochet bench --probe` reports them
//! ([`crate::bench::probe()`]).

use std::time::Instant;

use serde::Serialize;

use super::context::GpuContext;
use super::shader::{compute_pipeline, Features};
use crate::error::{Error, Result};

/// WGSL source.
pub const SOURCE: &str = include_str!("../../shaders/probe.wgsl");

/// Threads per workgroup of `fill` and `copy` (WGSL `WG`).
pub const WORKGROUP: u32 = 256;

/// Bytes of one element of the copied buffers (WGSL `vec4<f32>`).
pub const ELEMENT_BYTES: u64 = std::mem::size_of::<[f32; 4]>() as u64;
const _: () = assert!(ELEMENT_BYTES == 16);

/// Bytes of each of the two buffers of [`bandwidth`] unless asked otherwise (512 MiB).
pub const DEFAULT_BYTES: u64 = 512 << 20;

/// Dispatches in the one pass of [`dispatch_floor`] unless asked otherwise.
pub const DEFAULT_DISPATCHES: u32 = 1000;

/// Timed repetitions of each probe unless asked otherwise (medians reported).
pub const DEFAULT_REPEATS: u32 = 10;

/// Workgroups per dimension of the copy's grid at most (WebGPU's default limit).
pub const MAX_GROUPS_PER_DIMENSION: u32 = 65_535;

/// The pattern that `fill` writes at element `i` (the CPU reference): exact in f32.
pub fn pattern(i: u32) -> [f32; 4] {
    [(i & 0xffff) as f32, (i >> 16) as f32, 1.0, -1.0]
}

/// The 2D grid (x, y) of workgroups that covers `groups` workgroups with at most `max_dim` per
/// dimension: y rows of x, x y - groups < y spare ones (their threads return at once).
pub fn grid(groups: u32, max_dim: u32) -> (u32, u32) {
    let max_dim = max_dim.max(1);
    let y = groups.div_ceil(max_dim).max(1);
    (groups.div_ceil(y).max(1), y)
}

/// The probe's pipelines, compiled once.
#[derive(Debug)]
pub struct ProbeKernels {
    fill: wgpu::ComputePipeline,
    copy: wgpu::ComputePipeline,
    chained: wgpu::ComputePipeline,
    empty: wgpu::ComputePipeline,
}

impl ProbeKernels {
    /// Compiles the probe kernels.
    pub fn new(device: &wgpu::Device) -> Self {
        let f = Features::default();
        let wg = Some(WORKGROUP);
        Self {
            fill: compute_pipeline(device, "probe_fill", SOURCE, f, "fill", wg),
            copy: compute_pipeline(device, "probe_copy", SOURCE, f, "copy", wg),
            chained: compute_pipeline(device, "probe_chained", SOURCE, f, "chained", None),
            empty: compute_pipeline(device, "probe_empty", SOURCE, f, "empty", None),
        }
    }
}

/// The copy probe's result.
#[derive(Debug, Clone, Serialize)]
pub struct Bandwidth {
    /// Bytes of each buffer (the source read, the destination written).
    pub bytes: u64,
    /// Copies timed, one submission each, after one untimed.
    pub repeats: u32,
    /// Workgroups of the copy's grid (x, y) of [`WORKGROUP`] threads.
    pub grid: (u32, u32),
    /// "timestamps" when [`Bandwidth::seconds`] are device times, else "wall clock".
    pub timer: String,
    /// Seconds of each copy: the device's time between its pass's timestamps, or else the
    /// wall time of its submission until the device is idle.
    pub seconds: Vec<f64>,
    /// Wall seconds of each copy's submission until the device is idle.
    pub wall_seconds: Vec<f64>,
    /// Median over the copies of (bytes read + bytes written) / seconds, in GB/s (1e9 B/s).
    pub gb_per_s: f64,
    /// The same for the fastest copy.
    pub gb_per_s_best: f64,
    /// The destination's first and last elements read back equal [`pattern`].
    pub verified: bool,
}

/// The dispatch probe's result.
#[derive(Debug, Clone, Serialize)]
pub struct DispatchFloor {
    /// Dispatches of one workgroup in the one pass.
    pub dispatches: u32,
    /// Passes timed of each kind, one submission each, after one untimed.
    pub repeats: u32,
    /// "timestamps" when the `*_us` figures are device times, else "wall clock".
    pub timer: String,
    /// Median microseconds per dispatch of `chained` (a read-write binding: wgpu puts a barrier
    /// between two of them, as between the dependent dispatches of a step).
    pub chained_us: f64,
    /// Median microseconds per dispatch of `empty` (nothing bound, no barrier between them).
    pub empty_us: f64,
    /// Median wall microseconds per dispatch of `chained`, the submission and wait included.
    pub chained_wall_us: f64,
    /// The same for `empty`.
    pub empty_wall_us: f64,
}

/// Timestamp pairs of passes, resolved and read back after a submission.
struct Stamps {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    staging: wgpu::Buffer,
}

impl Stamps {
    /// Room for `pairs` passes (`None` without timestamp queries).
    fn new(ctx: &GpuContext, pairs: u32) -> Option<Stamps> {
        if !ctx.timestamps {
            return None;
        }
        let device = &ctx.device;
        let bytes = 16 * u64::from(pairs);
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        Some(Stamps {
            set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("probe"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * pairs,
            }),
            resolve: buffer(
                "probe_resolve",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            staging: buffer(
                "probe_staging",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
        })
    }

    /// The timestamp writes of pair `k`.
    fn writes(&self, k: u32) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * k),
            end_of_pass_write_index: Some(2 * k + 1),
        }
    }

    /// Device seconds of the first `pairs` pairs (after their submissions finished), resolved
    /// and read back in one submission.
    fn seconds(&self, ctx: &GpuContext, pairs: u32) -> Result<Vec<f64>> {
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("probe_resolve"),
            });
        let bytes = 16 * u64::from(pairs);
        enc.resolve_query_set(&self.set, 0..2 * pairs, &self.resolve, 0);
        enc.copy_buffer_to_buffer(&self.resolve, 0, &self.staging, 0, bytes);
        ctx.queue.submit([enc.finish()]);
        let bytes = read(ctx, &self.staging, bytes)?;
        let stamps: Vec<u64> = bytemuck::pod_collect_to_vec(&bytes);
        let period = f64::from(ctx.queue.get_timestamp_period()) * 1e-9;
        Ok(stamps
            .chunks_exact(2)
            .map(|p| p[1].saturating_sub(p[0]) as f64 * period)
            .collect())
    }
}

/// Waits until the device is idle.
fn wait(ctx: &GpuContext) -> Result<()> {
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map(|_| ())
        .map_err(|e| Error::Gpu(format!("device lost while waiting: {e}")))
}

/// The first `len` bytes of the mappable `buffer`.
fn read(ctx: &GpuContext, buffer: &wgpu::Buffer, len: u64) -> Result<Vec<u8>> {
    let slice = buffer.slice(..len);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    wait(ctx)?;
    let bytes = slice
        .get_mapped_range()
        .map_err(|e| Error::Gpu(format!("cannot map the probe's readback: {e:?}")))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// The median of `x` (NaN when empty); also the bench's.
pub fn median(mut x: Vec<f64>) -> f64 {
    if x.is_empty() {
        return f64::NAN;
    }
    x.sort_by(f64::total_cmp);
    let n = x.len();
    if n % 2 == 1 {
        x[n / 2]
    } else {
        0.5 * (x[n / 2 - 1] + x[n / 2])
    }
}

/// The two buffers of the copy, filled, with their bind groups and grid.
struct CopyBuffers {
    /// Kept alive with the bind group that reads it.
    _src: wgpu::Buffer,
    dst: wgpu::Buffer,
    bind: wgpu::BindGroup,
    grid: (u32, u32),
    elements: u64,
}

impl CopyBuffers {
    /// Buffers of `elements` vec4s; the source filled with [`pattern`] by `fill` (on the device,
    /// submitted and finished); a grid of at most `max_dim` workgroups per dimension.
    fn new(ctx: &GpuContext, k: &ProbeKernels, elements: u64, max_dim: u32) -> Result<CopyBuffers> {
        let device = &ctx.device;
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: elements * ELEMENT_BYTES,
                usage: wgpu::BufferUsages::STORAGE | usage,
                mapped_at_creation: false,
            })
        };
        let src = buffer("probe_src", wgpu::BufferUsages::empty());
        let dst = buffer("probe_dst", wgpu::BufferUsages::COPY_SRC);
        let groups = u32::try_from(elements.div_ceil(u64::from(WORKGROUP)))
            .map_err(|_| Error::Gpu(format!("probe: {elements} elements are too many")))?;
        let max_dim = max_dim
            .min(device.limits().max_compute_workgroups_per_dimension)
            .min(MAX_GROUPS_PER_DIMENSION);
        let grid = grid(groups, max_dim);
        let fill = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("probe_fill"),
            layout: &k.fill.get_bind_group_layout(0),
            entries: &[entry(1, &src)],
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("probe_copy"),
            layout: &k.copy.get_bind_group_layout(0),
            entries: &[entry(0, &src), entry(1, &dst)],
        });
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("probe_fill"),
        });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("probe_fill"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&k.fill);
            pass.set_bind_group(0, &fill, &[]);
            pass.dispatch_workgroups(grid.0, grid.1, 1);
        }
        ctx.queue.submit([enc.finish()]);
        wait(ctx)?;
        Ok(CopyBuffers {
            _src: src,
            dst,
            bind,
            grid,
            elements,
        })
    }

    /// Submits one copy (its pass between the timestamps of pair `k` of `stamps`, when given)
    /// and waits for it; the wall seconds.
    fn run(
        &self,
        ctx: &GpuContext,
        kernels: &ProbeKernels,
        stamps: Option<(&Stamps, u32)>,
    ) -> Result<f64> {
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("probe_copy"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("probe_copy"),
                timestamp_writes: stamps.map(|(s, k)| s.writes(k)),
            });
            pass.set_pipeline(&kernels.copy);
            pass.set_bind_group(0, &self.bind, &[]);
            pass.dispatch_workgroups(self.grid.0, self.grid.1, 1);
        }
        let t0 = Instant::now();
        ctx.queue.submit([enc.finish()]);
        wait(ctx)?;
        Ok(t0.elapsed().as_secs_f64())
    }

    /// Elements `first..first + count` of the destination.
    fn read_dst(&self, ctx: &GpuContext, first: u64, count: u64) -> Result<Vec<[f32; 4]>> {
        let bytes = count * ELEMENT_BYTES;
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probe_readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("probe_readback"),
            });
        enc.copy_buffer_to_buffer(&self.dst, first * ELEMENT_BYTES, &staging, 0, bytes);
        ctx.queue.submit([enc.finish()]);
        Ok(bytemuck::pod_collect_to_vec(&read(ctx, &staging, bytes)?))
    }

    /// Whether the first and last (up to 4096) elements of the destination equal [`pattern`].
    fn verify(&self, ctx: &GpuContext) -> Result<bool> {
        let n = self.elements;
        let k = n.min(4096);
        for first in [0, n - k] {
            let got = self.read_dst(ctx, first, k)?;
            let ok = got
                .iter()
                .zip(first..)
                .all(|(g, i)| *g == pattern(i as u32));
            if !ok {
                return Ok(false);
            }
        }
        Ok(true)
    }
}

/// The bind group entry of `buffer` at `binding`.
fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

/// The largest buffer the probe may bind on `ctx`, in whole elements, at most `bytes`.
fn elements_for(ctx: &GpuContext, bytes: u64) -> u64 {
    let limits = ctx.device.limits();
    let max = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    (bytes.min(max) / ELEMENT_BYTES).max(1)
}

/// Times `repeats` `vec4<f32>` copies of `bytes` bytes (at most the adapter's largest storage
/// binding; each copy reads that many and writes that many), one submission each after an
/// untimed one, and checks what the last one wrote.
///
/// # Errors
/// [`Error::Gpu`] when the device is lost.
pub fn bandwidth(
    ctx: &GpuContext,
    kernels: &ProbeKernels,
    bytes: u64,
    repeats: u32,
) -> Result<Bandwidth> {
    let repeats = repeats.max(1);
    let copy = CopyBuffers::new(
        ctx,
        kernels,
        elements_for(ctx, bytes),
        MAX_GROUPS_PER_DIMENSION,
    )?;
    copy.run(ctx, kernels, None)?;
    let stamps = Stamps::new(ctx, repeats);
    let mut wall = Vec::new();
    for k in 0..repeats {
        wall.push(copy.run(ctx, kernels, stamps.as_ref().map(|s| (s, k)))?);
    }
    let (timer, seconds) = match &stamps {
        Some(s) => ("timestamps", s.seconds(ctx, repeats)?),
        None => ("wall clock", wall.clone()),
    };
    let bytes = copy.elements * ELEMENT_BYTES;
    let rate = |t: f64| 2.0 * bytes as f64 / t / 1e9;
    let best = seconds.iter().copied().fold(f64::INFINITY, f64::min);
    Ok(Bandwidth {
        bytes,
        repeats,
        grid: copy.grid,
        timer: timer.to_string(),
        gb_per_s: rate(median(seconds.clone())),
        gb_per_s_best: rate(best),
        seconds,
        wall_seconds: wall,
        verified: copy.verify(ctx)?,
    })
}

/// `fill` and one `copy` of `elements` vec4s over a grid of at most `max_dim` workgroups per
/// dimension (a small `max_dim` takes the 2D path on a small buffer); the destination read back,
/// to compare with [`pattern`].
///
/// # Errors
/// [`Error::Gpu`] when the device is lost.
pub fn copied(
    ctx: &GpuContext,
    kernels: &ProbeKernels,
    elements: u64,
    max_dim: u32,
) -> Result<Vec<[f32; 4]>> {
    let copy = CopyBuffers::new(ctx, kernels, elements.max(1), max_dim)?;
    copy.run(ctx, kernels, None)?;
    copy.read_dst(ctx, 0, copy.elements)
}

/// Times `dispatches` dispatches of one workgroup that do nothing, in one pass, `repeats` times
/// for each of `chained` (a barrier between two) and `empty` (none), one submission each after
/// an untimed one.
///
/// # Errors
/// [`Error::Gpu`] when the device is lost.
pub fn dispatch_floor(
    ctx: &GpuContext,
    kernels: &ProbeKernels,
    dispatches: u32,
    repeats: u32,
) -> Result<DispatchFloor> {
    let dispatches = dispatches.max(1);
    let repeats = repeats.max(1);
    let device = &ctx.device;
    let flag = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe_flag"),
        size: 16,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("probe_chained"),
        layout: &kernels.chained.get_bind_group_layout(0),
        entries: &[entry(2, &flag)],
    });
    let stamps = Stamps::new(ctx, 2 * repeats);
    let run = |chained: bool, pair: Option<u32>| -> Result<f64> {
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("probe_dispatch"),
        });
        let writes = stamps.as_ref().zip(pair);
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("probe_dispatch"),
                timestamp_writes: writes.map(|(s, k)| s.writes(k)),
            });
            if chained {
                pass.set_pipeline(&kernels.chained);
                pass.set_bind_group(0, &bind, &[]);
            } else {
                pass.set_pipeline(&kernels.empty);
            }
            for _ in 0..dispatches {
                pass.dispatch_workgroups(1, 1, 1);
            }
        }
        let t0 = Instant::now();
        ctx.queue.submit([enc.finish()]);
        wait(ctx)?;
        Ok(t0.elapsed().as_secs_f64())
    };
    run(true, None)?;
    run(false, None)?;
    let (mut wall_chained, mut wall_empty) = (Vec::new(), Vec::new());
    for k in 0..repeats {
        // Alternated, so that a drift of the machine's speed falls on both alike.
        wall_chained.push(run(true, Some(2 * k))?);
        wall_empty.push(run(false, Some(2 * k + 1))?);
    }
    let per = |t: Vec<f64>| 1e6 * median(t) / f64::from(dispatches);
    let (timer, chained, empty) = match &stamps {
        Some(s) => {
            let t = s.seconds(ctx, 2 * repeats)?;
            (
                "timestamps",
                t.iter().step_by(2).copied().collect(),
                t.iter().skip(1).step_by(2).copied().collect(),
            )
        }
        None => ("wall clock", wall_chained.clone(), wall_empty.clone()),
    };
    Ok(DispatchFloor {
        dispatches,
        repeats,
        timer: timer.to_string(),
        chained_us: per(chained),
        empty_us: per(empty),
        chained_wall_us: per(wall_chained),
        empty_wall_us: per(wall_empty),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_probe_shader_validates_with_naga() {
        let wgsl = super::super::shader::source(SOURCE, Features::default());
        super::super::shader::validate("probe", &wgsl).expect("probe.wgsl validates");
    }

    #[test]
    fn the_grid_covers_every_workgroup_with_few_spare() {
        for groups in [1, 2, 255, 65_535, 65_536, 131_072, 131_073, 2_097_152] {
            for max_dim in [1, 7, 256, 65_535] {
                let (x, y) = grid(groups, max_dim);
                assert!(x <= max_dim && x >= 1, "{groups} {max_dim}: x = {x}");
                assert!(x * y >= groups, "{groups} {max_dim}: {x} x {y}");
                assert!(x * y - groups < y, "{groups} {max_dim}: {x} x {y}");
            }
        }
        assert_eq!(grid(131_072, 65_535), (43_691, 3));
    }

    #[test]
    fn the_pattern_is_exact_and_distinct() {
        assert_eq!(pattern(0), [0.0, 0.0, 1.0, -1.0]);
        assert_eq!(pattern(0x0001_0002), [2.0, 1.0, 1.0, -1.0]);
        assert_eq!(pattern(u32::MAX), [65_535.0, 65_535.0, 1.0, -1.0]);
        assert_ne!(pattern(65_536), pattern(1));
    }

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
    }
}
