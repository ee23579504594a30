//! Scenes that differ by one feature each, with the exact stage list each one's plan must have:
//! shared by the CPU plan tests (`tests/core/plan.rs`) and the GPU buffer and kernel tests
//! (`tests/gpu/plan.rs`). A scene pays only for what it uses.
#![allow(dead_code)]

use crate::scene_text::STEEL;
use ricochet::plan::Stage::{self, *};

/// A 4 x 3 steel block, 10 x 7.5 mm, moving and squeezed; `run` is added to `[run]`, `hourglass` is
/// the body's `hourglass` value, `tail` is appended (more bodies and tables).
pub fn block(run: &str, hourglass: &str, tail: &str) -> String {
    format!(
        r#"
[run]
end_time = 1.0e-5
{run}

{STEEL}

[[body]]
name = "block"
material = "steel"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [0.01, 0.0075], cells = [4, 3] }} }}
initial_velocity = [0.0, -1.0]
velocity_gradient = [[-10.0, 0.0], [0.0, 5.0]]
hourglass = {hourglass}
{tail}
"#
    )
}

/// Default hourglass control.
pub const VISCOUS: &str = r#"{ form = "viscous", coefficient = 0.1 }"#;
/// Stiffness hourglass control.
pub const STIFFNESS: &str = r#"{ form = "stiffness", coefficient = 0.1 }"#;
/// No hourglass control.
pub const NONE: &str = r#"{ form = "none" }"#;
/// Viscous form with a zero coefficient: no hourglass control either.
pub const ZERO: &str = r#"{ form = "viscous", coefficient = 0.0 }"#;
/// Bulk viscosity off.
pub const NO_BULK: &str = "bulk_viscosity = { linear = 0.0, quadratic = 0.0 }";
/// Bulk viscosity off and a fixed step (well below the stable step): the bare plan.
pub const BARE_RUN: &str = "bulk_viscosity = { linear = 0.0, quadratic = 0.0 }\ntime_step = 1.0e-8";

/// A second block below the first, touching it, and a contact between them.
pub const PAIR: &str = r#"
[[body]]
name = "base"
material = "steel"
mesh = { rectangle = { origin = [0.0, -0.005], size = [0.01, 0.005], cells = [3, 2] } }
hourglass = { form = "viscous", coefficient = 0.1 }

[[contact]]
bodies = ["block", "base"]
"#;

/// A rigid wall left of every body, 1 mm off.
pub const WALL: &str = r#"
[[rigid_wall]]
point = [-0.001, 0.0]
normal = [1.0, 0.0]
"#;

/// The left edge held in x.
pub const BOUNDARY: &str = r#"
[[boundary]]
body = "block"
region = { min = [-1.0e-9, -1.0], max = [1.0e-9, 1.0] }
velocity = { x = 0.0 }
"#;

/// A ramped pressure on the top edge.
pub const PRESSURE: &str = r#"
[[pressure]]
body = "block"
region = { min = [-0.001, 0.0074], max = [0.011, 0.0076] }
value = 1.0e6
ramp = 1.0e-6
"#;

/// A second block with stiffness hourglass control, apart from the first, no contact.
pub const STIFF_BODY: &str = r#"
[[body]]
name = "other"
material = "steel"
mesh = { rectangle = { origin = [0.1, 0.0], size = [0.01, 0.01], cells = [2, 2] } }
hourglass = { form = "stiffness", coefficient = 0.05 }
"#;

/// (name, scene text, the exact stage list of its plan).
pub fn cases() -> Vec<(&'static str, String, Vec<Stage>)> {
    let base = |extra: &[Stage]| -> Vec<Stage> {
        let mut s = vec![ElementForces, HourglassViscous, BulkViscosity, StableStep];
        s.extend_from_slice(extra);
        s
    };
    vec![
        (
            "no_contact",
            block("", VISCOUS, ""),
            base(&[NodeUpdate, History]),
        ),
        (
            "contact_pair",
            block("", VISCOUS, PAIR),
            base(&[NodeUpdate, Contact, History]),
        ),
        (
            "wall_only",
            block("", VISCOUS, WALL),
            base(&[NodeUpdate, Contact, History]),
        ),
        (
            "viscous_hourglass_no_bulk_viscosity",
            block(NO_BULK, VISCOUS, ""),
            vec![
                ElementForces,
                HourglassViscous,
                StableStep,
                NodeUpdate,
                History,
            ],
        ),
        (
            "stiffness_hourglass",
            block("", STIFFNESS, ""),
            vec![
                ElementForces,
                HourglassStiffness,
                BulkViscosity,
                StableStep,
                NodeUpdate,
                History,
            ],
        ),
        (
            "stiffness_hourglass_no_bulk_viscosity_fixed_step",
            block(BARE_RUN, STIFFNESS, ""),
            vec![ElementForces, HourglassStiffness, NodeUpdate, History],
        ),
        (
            "no_hourglass_no_bulk_viscosity_fixed_step",
            block(BARE_RUN, NONE, ""),
            vec![ElementForces, NodeUpdate, History],
        ),
        (
            "zero_hourglass_coefficient_no_bulk_viscosity_fixed_step",
            block(BARE_RUN, ZERO, ""),
            vec![ElementForces, NodeUpdate, History],
        ),
        (
            "no_hourglass_with_bulk_viscosity",
            block("", NONE, ""),
            vec![
                ElementForces,
                BulkViscosity,
                StableStep,
                NodeUpdate,
                History,
            ],
        ),
        (
            "viscous_and_stiffness_bodies",
            block("", VISCOUS, STIFF_BODY),
            vec![
                ElementForces,
                HourglassViscous,
                HourglassStiffness,
                BulkViscosity,
                StableStep,
                NodeUpdate,
                History,
            ],
        ),
        (
            "boundaries",
            block(BARE_RUN, NONE, BOUNDARY),
            vec![ElementForces, NodeUpdate, VelocityBoundaries, History],
        ),
        (
            "pressure",
            block(BARE_RUN, NONE, PRESSURE),
            vec![ElementForces, Pressure, NodeUpdate, History],
        ),
        (
            "mass_damping",
            block(&format!("{BARE_RUN}\nmass_damping = 1.0e3"), NONE, ""),
            vec![ElementForces, MassDamping, NodeUpdate, History],
        ),
        (
            "fields",
            block(&format!("{BARE_RUN}\nfield_interval = 1.0e-6"), NONE, ""),
            vec![ElementForces, NodeUpdate, History, Fields],
        ),
        (
            "everything",
            block(
                "mass_damping = 1.0e3\nfield_interval = 1.0e-6",
                VISCOUS,
                &format!("{STIFF_BODY}{PAIR}{WALL}{BOUNDARY}{PRESSURE}"),
            ),
            vec![
                ElementForces,
                HourglassViscous,
                HourglassStiffness,
                BulkViscosity,
                Pressure,
                StableStep,
                MassDamping,
                NodeUpdate,
                VelocityBoundaries,
                Contact,
                History,
                Fields,
            ],
        ),
    ]
}

/// `ricochet check`'s plan line for `stages`.
pub fn plan_line(stages: &[Stage]) -> String {
    let names: Vec<&str> = stages.iter().map(|s| s.name()).collect();
    format!("plan       {}", names.join(" -> "))
}
