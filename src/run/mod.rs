//! Running a scene: the limits checked before a run starts ([`check_memory`],
//! [`check_gpu_limits`], [`check_limits`]), the time loop that drives a solver of either backend
//! and writes the outputs ([`run`], [`run_with`]), and a whole run as `ricochet run` makes it,
//! for any front end ([`RunRequest`], [`Prepared`], [`execute`]), stopped by an [`Interrupt`].
//!
//! - `limits.rs`: memory, GPU buffer and schedule limits;
//! - `driver.rs`: the time loop, checkpoints and `summary.json`;
//! - `launch.rs`: requests, backend choice and outcomes;
//! - `interrupt.rs`: the stop flags.
//!
//! The loop is the same for the CPU reference ([`crate::step::cpu`]) and the GPU
//! ([`crate::gpu`]): both are driven through [`crate::step::Solver`].

mod driver;
mod interrupt;
mod launch;
mod limits;
mod warnings;

pub use driver::{run, run_with, Progress, RunOptions, RunResult};
pub use interrupt::Interrupt;
pub use launch::{
    choose_solver, execute, load, model_and_plan, Backend, Ending, Prepared, RunOutcome,
    RunRequest, Start,
};
pub use limits::{
    available_memory, check_gpu_limits, check_limits, check_memory, checked_step, element_counts,
    first_step, memory_estimate, BYTES_PER_ELEMENT, FIELD_BYTES_PER_ELEMENT, GPU_BYTES_PER_ELEMENT,
    GPU_SAMPLE_BYTES, MAX_HISTORY_ROWS, MAX_SNAPSHOTS, MAX_STEPS, PLASTIC_BYTES_PER_ELEMENT,
};
pub use warnings::convergence_warning;

use crate::error::Result;
use crate::model::Model;
use crate::scene::Scene;
use crate::step::Schedule;

/// The schedule of a scene's run.
pub fn schedule(scene: &Scene) -> Schedule {
    Schedule {
        end_time: scene.run.end_time,
        history_interval: scene.run.history_interval,
        field_interval: scene.run.field_interval,
        time_step_scale: scene.run.time_step_scale,
        time_step: scene.run.time_step,
    }
}

/// The model of a run of `scene`: [`Model::assemble`], then the contact overlaps at t = 0
/// moved onto their surfaces ([`crate::contact::overlap::resolve`]).
///
/// # Errors
/// [`crate::Error::Invalid`] for an invalid mesh, boundary or pressure box, or an overlap at t = 0
/// that cannot be resolved.
pub fn model(scene: &Scene) -> Result<Model> {
    let mut model = Model::assemble(scene)?;
    crate::contact::overlap::resolve(&mut model, scene)?;
    Ok(model)
}
