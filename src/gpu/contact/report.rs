//! The end of the contact step on the device (`shaders/contact_report.wgsl`): corrected velocities
//! and u_{n+1}, the work of the impulses, and the interface reports (impulse on the first body,
//! active slaves, largest penetration) by fixed-order reductions. CPU reference: the end of
//! [`crate::contact::ContactSet::apply`] and [`crate::contact::ContactSet::sample`].

/// WGSL source.
pub const SOURCE: &str = include_str!("../../../shaders/contact_report.wgsl");
