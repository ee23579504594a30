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

mod block;
mod contact;
mod scenes;
mod table;
mod timing;

pub use block::{cpu, gpu};
pub use contact::{both_contact, cpu_contact, gpu_contact, ContactTiming, DEFAULT_WARMUP};
pub use scenes::{
    bench_schedule, block_text, contact_scene, contact_text, disk_elements, pile_scene, pile_text,
    scene, striker_scene, striker_text, with_friction, ContactScene, PileContact, PILE_DISK_CELLS,
    PILE_RADIUS, PILE_VELOCITY, STRIKER_SIDE, STRIKER_VELOCITY,
};
pub use table::{contact_table, summary, table, BenchRow, ContactRow};
pub use timing::DEFAULT_ROUNDS;
