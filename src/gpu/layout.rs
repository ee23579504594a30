//! `#[repr(C)]` mirrors of the structs in `shaders/common.wgsl` (the parameters, the run control
//! and the sample instances every kernel shares; each kernel's own structs are mirrored beside it,
//! in its `.rs`), with their sizes asserted against the WGSL layout, and the time in ticks. Field
//! meanings are documented once, in the WGSL declarations.
#![allow(missing_docs)]

use bytemuck::{Pod, Zeroable};

/// Mirror of WGSL `Params` (uniform): sizes and static run parameters.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct Params {
    pub n_nodes: u32,
    pub n_elems: u32,
    pub n_cons: u32,
    pub n_bodies: u32,
    pub scale: f32,
    pub fixed_dt: f32,
    pub end_lo: u32,
    pub end_hi: u32,
    pub n_sample_times: u32,
    pub n_snapshot_times: u32,
    pub row_stride: u32,
    pub row_capacity: u32,
    pub dt_groups: u32,
    pub n_instances: u32,
    pub sum_groups: u32,
    pub ticks_per_second: f32,
    pub penalty_dt: f32,
    pub mass_damping: f32,
    pub loads: u32,
    pub plastic: u32,
    pub inst_groups: u32,
    pub gravity_x: f32,
    pub gravity_y: f32,
    pub gravity_ramp: f32,
    /// 1.0, read at run time: node.wgsl's compensated sum subtracts v * one so that a compiler
    /// that reassociates floating point (Mesa's NIR, a driver's) cannot fold (v + y) - v to y.
    pub one: f32,
    pub failure: u32,
    pub failure_at: u32,
    pub _pad: u32,
}

/// Mirror of WGSL `Control`: the run state advanced on the GPU.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct Control {
    pub t_lo: u32,
    pub t_hi: u32,
    pub dt_prev: f32,
    pub dt_next: f32,
    pub dt_node: f32,
    pub dt_first: f32,
    pub dt_min: f32,
    pub dt_max: f32,
    pub step: u32,
    pub flags: u32,
    pub state: u32,
    pub rows: u32,
    pub next_sample: u32,
    pub next_snapshot: u32,
    pub fail_code: u32,
    pub fail_index: u32,
    pub fail_value: f32,
    pub dt_elem: u32,
    pub bad_element: u32,
    pub bad_node: u32,
    pub damp_c: f32,
    /// Elements eroded since the contact surfaces last followed erosion (element.wgsl; the host
    /// clears it when it moves them: [`crate::gpu::contact::STATE_ERODED`]).
    pub eroded: u32,
}

/// Byte offset of `Control::eroded`, for clearing it with a 4-byte write.
pub const CONTROL_ERODED_OFFSET: u64 = 84;

/// Byte offset of `Control::state`, for un-pausing with a 4-byte write.
pub const CONTROL_STATE_OFFSET: u64 = 40;

/// Mirror of WGSL `Instance`: one range summed on sample steps.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Pod, Zeroable)]
pub struct Instance {
    pub start: u32,
    pub count: u32,
    pub groups: u32,
    pub first_group: u32,
    pub scale: f32,
    pub _pad: [u32; 3],
}

/// Control flags (WGSL `FLAG_*`).
pub const FLAG_SAMPLE: u32 = 1;
/// Snapshot due this step.
pub const FLAG_SNAPSHOT: u32 = 2;
/// Last step.
pub const FLAG_END: u32 = 4;
/// Control states (WGSL `STATE_*`).
pub const STATE_RUNNING: u32 = 0;
/// Paused after a snapshot step until the host has read it.
pub const STATE_PAUSED: u32 = 1;
/// End reached.
pub const STATE_DONE: u32 = 2;
/// Unstable.
pub const STATE_FAILED: u32 = 3;
/// "No index" marker.
pub const NONE: u32 = u32::MAX;

const _: () = assert!(std::mem::size_of::<Params>() == 112);
const _: () = assert!(std::mem::size_of::<Control>() == 88);
const _: () = assert!(std::mem::size_of::<Instance>() == 32);
const _: () = assert!(std::mem::offset_of!(Control, state) as u64 == CONTROL_STATE_OFFSET);
const _: () = assert!(std::mem::offset_of!(Control, eroded) as u64 == CONTROL_ERODED_OFFSET);

/// Ticks per end time: the GPU keeps time as a 64-bit count of `end_time / 2^40` (fewer ticks
/// for an end time so short that `2^40 / end_time` ticks per second overflows `f32`, see
/// [`ticks_per_end`]).
pub const TICKS_PER_END: f64 = (1u64 << 40) as f64;

/// The most ticks per second the kernels are given (`Params::ticks_per_second`, an `f32`): 2^120,
/// which leaves a step of up to 2^8 s room before `dt * ticks_per_second` overflows.
pub const MAX_TICKS_PER_SECOND: f64 = 1.329_227_995_784_916e36;

/// The fewest ticks per end time a run may have ([`ticks_per_end`]): 2^20, a millionth of the
/// run, within which the kernels' 1 % rules (the last step's clip, a sample's slack) still hold.
pub const MIN_TICKS_PER_END: f64 = (1u64 << 20) as f64;

/// Ticks per end time of a run ending at `end_time`: [`TICKS_PER_END`], or for an end time
/// below about 1e-24 s the largest power of two that keeps the ticks per second within an
/// `f32` (2^40 / 1e-28 s overflowed to infinity, and the run stood still at t = 0).
pub fn ticks_per_end(end_time: f64) -> f64 {
    let mut n = TICKS_PER_END;
    while n > 1.0 && n / end_time > MAX_TICKS_PER_SECOND {
        n *= 0.5;
    }
    n
}

/// A time in ticks as (lo, hi).
pub fn ticks(t: f64, end_time: f64) -> [u32; 2] {
    let n = (t / end_time * ticks_per_end(end_time)).round().max(0.0) as u64;
    [n as u32, (n >> 32) as u32]
}

/// Seconds of a tick count (lo, hi).
pub fn seconds(lo: u32, hi: u32, end_time: f64) -> f64 {
    ((hi as u64) << 32 | lo as u64) as f64 * end_time / ticks_per_end(end_time)
}
