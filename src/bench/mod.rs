//! Throughput benchmark: a generated impact-like block of N x N quads (no contact), run for a
//! fixed number of steps on the CPU reference or the GPU, reported as element-cycles per second.
//!
//! In the same run, alternating in rounds (medians reported), it also measures what the step costs
//! beyond the bare element-and-update loop (the full step over the bare loop: a scene without
//! contact should run as fast as the bare loop), and what a contact pair adds per step: the block
//! resting on a base, with and without a `[[contact]]` between them. A second table times contact
//! scenes (the block pressed into its base, a striker into a plate, a pile of disks on a wall) with
//! and without their contact.
//!
//! The scenes are generated in `scenes`, timed by `block` (the first table) and `contact` (the
//! second) with the rounds, the bare loop and the CPU and GPU solvers of `timing`, and printed by
//! `table`. Each bench times the CPU reference ([`crate::step::cpu`]) or its GPU twin
//! ([`crate::gpu`]), or both.
//!
//! For the device check (`benches/device.sh`), GPU only: [`probe`](mod@probe) reports what the
//! adapter reaches (a copy's bandwidth, the dispatch floor; kernels in [`crate::gpu::probe`]),
//! [`profile`](mod@profile) where a step's device time goes by part, and [`bytes`] the bytes
//! each kernel of a step moves (BENCHMARKS.md's traffic table).

mod block;
pub mod bytes;
mod contact;
pub mod probe;
pub mod profile;
mod scenes;
mod table;
mod timing;

pub use block::{cpu, gpu};
pub use bytes::block_bytes_per_element_cycle;
pub use contact::{
    both_contact, contact_options, cpu_contact, gpu_contact, ContactTiming, DEFAULT_WARMUP,
};
pub use probe::{probe, probe_summary, ProbeReport};
pub use profile::{no_timestamps, profile, profile_table, ProfileReport, ProfileRow, ProfileScene};
pub use scenes::{
    bench_schedule, block_text, contact_scene, contact_text, disk_elements, pile_scene, pile_text,
    scene, striker_scene, striker_text, with_failure, with_friction, ContactScene, PileContact,
    FAILURE_STRAIN, PILE_DISK_CELLS, PILE_RADIUS, PILE_VELOCITY, STRIKER_SIDE, STRIKER_VELOCITY,
};
pub use table::{contact_table, summary, table, BenchRow, ContactRow};
pub use timing::DEFAULT_ROUNDS;
