//! The GPU backend: WGSL compute kernels through wgpu, headless.
//!
//! Kernels (one `.wgsl` in `shaders/` beside each `.rs` here): [`element`] (stress and forces per
//! element), [`reduce`] (stable-step minimum, sample sums), [`control`] (step control on the GPU),
//! [`node`] (gather, central-difference update, energies on sample steps), [`boundary`]
//! (prescribed velocities), [`loads`] (pressure loads, mass-damping work), [`contact`] (the
//! contact stage by file: search, narrow phase, the Lagrange correction, reports). What several
//! kernels share is WGSL concatenated before them ([`shader`]: `common.wgsl`; `curve.wgsl`,
//! `tree.wgsl`, `reduce_common.wgsl`, `contact_common.wgsl`). [`kernels::Kernels`] holds the
//! compiled pipelines, [`state::GpuState`] the buffers (allocated through `alloc.rs`),
//! [`solver::GpuSolver`] drives them in batches of steps; [`context`] opens the adapter that
//! [`choice`] picks (by index, PCI bus id or name, within `CUDA_VISIBLE_DEVICES` /
//! `ROCR_VISIBLE_DEVICES`). All sums are gathers or fixed-order trees: the same scene on the same
//! adapter gives the same bits.

mod alloc;
pub mod boundary;
mod checkpoint;
pub mod choice;
pub mod contact;
pub mod context;
pub mod control;
pub mod element;
pub mod kernels;
pub mod layout;
pub mod loads;
pub mod node;
pub mod probe;
pub mod reduce;
pub mod shader;
pub mod solver;
pub mod state;

pub use context::{GpuContext, KernelCache, KernelKey};
pub use solver::{AheadCounts, GpuSolver};
