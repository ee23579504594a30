//! Contact narrow phase on the device (`shaders/contact_narrow.wgsl`): one thread per slot picks
//! its constraint among its candidates (or against its wall), with the corner rule, the penalty
//! impulse and the Lagrange warm start; a per-node gather applies the penalty and warm-start
//! impulses in slot order. CPU reference: [`crate::contact::ContactSet::apply`] (its narrow phase
//! and [`crate::contact::narrow`]).

/// WGSL source (also compiled into the solve module, whose re-check calls it).
pub const SOURCE: &str = include_str!("../../../shaders/contact_narrow.wgsl");
