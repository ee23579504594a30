//! The step plan: which stages a scene needs. A scene pays only for what it uses.

use std::fmt;

use crate::model::Model;
use crate::scene::{HourglassForm, Scene};

/// A stage of the step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Stage {
    /// Stress, nodal forces and stable step of every element.
    ElementForces,
    /// J2 plastic return and plastic work of the elements of plastic bodies (per-element plastic
    /// state kept between steps).
    Plasticity,
    /// Failure criteria after the element evaluation, and erosion of the elements that fail
    /// (bodies whose material has `failure`) or, with `run.erosion.inverted`, are about to
    /// invert; per-element eroded flag and damage kept between steps.
    Failure,
    /// Viscous hourglass forces (bodies with the viscous form).
    HourglassViscous,
    /// Stiffness hourglass forces (bodies with the stiffness form).
    HourglassStiffness,
    /// Bulk viscosity in compression.
    BulkViscosity,
    /// Pressure loads: their consistent nodal forces added to f_n (scenes with `[[pressure]]`).
    Pressure,
    /// Minimum reduction of the element stable steps.
    StableStep,
    /// Mass-proportional damping in the velocity update, and its work (`run.mass_damping` > 0).
    MassDamping,
    /// Gravity: the body force m g on every node, and its work (`run.gravity` not zero).
    Gravity,
    /// Central-difference velocity and displacement update.
    NodeUpdate,
    /// Prescribed velocities.
    VelocityBoundaries,
    /// Broad phase (when due), narrow phase and contact correction.
    Contact,
    /// Energy audit and body velocities at history times.
    History,
    /// Field snapshots at field times.
    Fields,
}

impl Stage {
    /// Short name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            Stage::ElementForces => "element_forces",
            Stage::Plasticity => "plasticity",
            Stage::Failure => "failure",
            Stage::HourglassViscous => "hourglass_viscous",
            Stage::HourglassStiffness => "hourglass_stiffness",
            Stage::BulkViscosity => "bulk_viscosity",
            Stage::Pressure => "pressure",
            Stage::StableStep => "stable_step",
            Stage::MassDamping => "mass_damping",
            Stage::Gravity => "gravity",
            Stage::NodeUpdate => "node_update",
            Stage::VelocityBoundaries => "velocity_boundaries",
            Stage::Contact => "contact",
            Stage::History => "history",
            Stage::Fields => "fields",
        }
    }
}

/// The stages a scene needs, and the sizes that decide cost.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Stages in execution order.
    pub stages: Vec<Stage>,
    /// Nodes.
    pub nodes: usize,
    /// Elements.
    pub elements: usize,
    /// Elements of bodies with viscous hourglass control (coefficient > 0).
    pub viscous_hourglass_elements: usize,
    /// Elements of bodies with stiffness hourglass control (coefficient > 0).
    pub stiffness_hourglass_elements: usize,
    /// Constrained nodes.
    pub constrained_nodes: usize,
    /// Contacts between bodies.
    pub contacts: usize,
    /// Rigid walls.
    pub walls: usize,
    /// Nodes loaded by pressure (summed over the loads).
    pub pressure_nodes: usize,
}

impl Plan {
    /// Builds the plan of a scene's model.
    pub fn new(scene: &Scene, model: &Model) -> Plan {
        // A coefficient of 0 means no hourglass control (README), whatever the form.
        let count = |form| {
            model
                .bodies
                .iter()
                .filter(|b| b.params.hourglass == form && b.params.hourglass_coefficient > 0.0)
                .map(|b| b.elements.len())
                .sum::<usize>()
        };
        let viscous = count(HourglassForm::Viscous);
        let stiffness = count(HourglassForm::Stiffness);
        let mut stages = vec![Stage::ElementForces];
        if model.has_plasticity() {
            stages.push(Stage::Plasticity);
        }
        if model.has_erosion() {
            stages.push(Stage::Failure);
        }
        if viscous > 0 {
            stages.push(Stage::HourglassViscous);
        }
        if stiffness > 0 {
            stages.push(Stage::HourglassStiffness);
        }
        if model.bodies.iter().any(|b| b.params.has_bulk_viscosity()) {
            stages.push(Stage::BulkViscosity);
        }
        if !model.pressures.is_empty() {
            stages.push(Stage::Pressure);
        }
        if scene.run.time_step.is_none() {
            stages.push(Stage::StableStep);
        }
        if model.mass_damping > 0.0 {
            stages.push(Stage::MassDamping);
        }
        if model.gravity != [0.0; 2] {
            stages.push(Stage::Gravity);
        }
        stages.push(Stage::NodeUpdate);
        if !model.constraints.is_empty() {
            stages.push(Stage::VelocityBoundaries);
        }
        if model.has_contact() {
            stages.push(Stage::Contact);
        }
        stages.push(Stage::History);
        if scene.run.field_interval.is_some() {
            stages.push(Stage::Fields);
        }
        Plan {
            stages,
            nodes: model.node_count(),
            elements: model.element_count(),
            viscous_hourglass_elements: viscous,
            stiffness_hourglass_elements: stiffness,
            constrained_nodes: model.constraints.len(),
            contacts: model.contacts.len(),
            walls: model.walls.len(),
            pressure_nodes: model.pressures.iter().map(|p| p.nodes.len()).sum(),
        }
    }

    /// Whether the plan has `stage`.
    pub fn has(&self, stage: Stage) -> bool {
        self.stages.contains(&stage)
    }

    /// Whether any element keeps dissipative state between steps (viscous hourglass or bulk viscosity).
    pub fn has_dissipation(&self) -> bool {
        self.has(Stage::HourglassViscous) || self.has(Stage::BulkViscosity)
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.stages.iter().map(|s| s.name()).collect();
        write!(f, "{}", names.join(" -> "))
    }
}
