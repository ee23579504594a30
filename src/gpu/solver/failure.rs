//! The messages of a run that stopped on the device (the failure codes of `shaders/control.wgsl`
//! and `shaders/node.wgsl`), naming the bodies, elements and nodes of the model; the same failures
//! as the CPU reference's ([`crate::step::cpu::CpuSolver`]).

use std::ops::Range;

use crate::gpu::layout::Control;
use crate::model::Model;
use crate::step::Schedule;

/// What failure messages need of the model.
#[derive(Debug, Clone)]
pub(super) struct Names {
    /// Per body its name, nodes and elements.
    bodies: Vec<(String, Range<usize>, Range<usize>)>,
    /// Nodes of the model.
    pub nodes: usize,
    /// What sets the penalty springs' step, if any.
    penalty: Option<String>,
}

impl Names {
    /// The names of `model`'s bodies; `penalty`: what sets the penalty springs' step.
    pub fn new(model: &Model, penalty: Option<String>) -> Self {
        Names {
            bodies: model
                .bodies
                .iter()
                .map(|b| (b.name.clone(), b.nodes.clone(), b.elements.clone()))
                .collect(),
            nodes: model.node_count(),
            penalty,
        }
    }

    /// Bodies of the model.
    pub fn body_count(&self) -> usize {
        self.bodies.len()
    }

    fn element(&self, e: usize) -> String {
        match self.bodies.iter().find(|b| b.2.contains(&e)) {
            Some(b) => format!(
                "element {e} (body {:?}, local element {})",
                b.0,
                e - b.2.start
            ),
            None => format!("element {e}"),
        }
    }

    fn node(&self, i: usize) -> String {
        match self.bodies.iter().find(|b| b.1.contains(&i)) {
            Some(b) => format!("node {i} (body {:?}, local node {})", b.0, i - b.1.start),
            None => format!("node {i}"),
        }
    }

    /// The message of the failure that `ctrl` reports (its code, index and value) in a run of
    /// `schedule`.
    pub fn failure(&self, ctrl: &Control, schedule: &Schedule) -> String {
        let i = ctrl.fail_index as usize;
        match ctrl.fail_code {
            1 => format!(
                "{} inverted: a corner Jacobian is not positive; reduce time_step_scale, \
                 refine the mesh or raise the hourglass coefficient",
                self.element(i)
            ),
            2 => format!(
                "velocity of {} is not finite: the run went unstable",
                if i < self.nodes {
                    self.node(i)
                } else {
                    format!("node {i}")
                }
            ),
            3 => format!(
                "the fixed time_step {:e} exceeds the stable step {:e} of {}{}",
                schedule.time_step.unwrap_or(0.0),
                ctrl.fail_value,
                self.element(i),
                self.penalty.as_deref().map_or(String::new(), |w| format!(
                    " and the penalty springs of {w}"
                ))
            ),
            4 => format!(
                "the stable step collapsed to {:e} (first step {:e}) at {}",
                ctrl.fail_value,
                ctrl.dt_first,
                self.element(i)
            ),
            _ => format!(
                "stable step is {:e} at {}: the element is degenerate or its state is not finite",
                ctrl.fail_value,
                self.element(i)
            ),
        }
    }
}
