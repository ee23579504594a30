//! The element, CPU reference: the one-point 4-node quad in total-Lagrangian form, its material
//! models, hourglass control and bulk viscosity. Its GPU twin is [`crate::gpu::element`]
//! (`shaders/element.wgsl`), which follows [`evaluate_state`] line by line in f32.
//!
//! A 3-node triangle is a collapsed quad: its last corner repeats its third (`[a, b, c, c]`),
//! which [`crate::geometry::is_triangle`] and [`crate::geometry::QuadGeometry::triangle`]
//! recognise. The quad's uniform gradients then equal the constant-strain triangle's exactly (the
//! repeated corner's two columns sum to the triangle's third), every nodal displacement of a
//! triangle is a linear field, to which the hourglass vector is orthogonal, so there is no
//! hourglass mode and no hourglass force; what differs is kept apart: no hourglass control (not
//! even its round-off), the centroid weights 1/3 (axisymmetric hoop terms), the corner check on
//! the one real corner set and the stable-step length of the triangle
//! ([`crate::geometry::characteristic_length`]). One kernel, one connectivity layout and one
//! node gather serve both kinds.
//!
//! For each element, from its reference node offsets `dx`, displacements `u` and the lagged
//! half-step velocities `v` (v^{n-1/2}), [`evaluate`] computes
//! - the nodal forces (`f = -A0 t P b0` for the stress, plus hourglass and bulk-viscosity forces),
//! - the stable step of the element from the current geometry,
//! - the strain energy and stored hourglass energy (conservative parts),
//! - the increments of dissipated work of the viscous parts, with the trapezoidal pairing that
//!   makes the discrete energy balance close exactly for fixed steps (see [`ElementOut`]).
//!
//! By file: [`params`] (a body's constitutive and control parameters, from its material),
//! [`stress`] (the stress of the material models), [`plastic`] (J2 plasticity at finite
//! strain), [`failure`] (the failure criteria and Johnson-Cook damage), [`hourglass`] (Flanagan-Belytschko hourglass control) and [`forces`] (one element's
//! evaluation: deformation, forces, bulk viscosity, stable step, energies). The element sits
//! below the model, whose bodies hold their [`ElementParams`] and whose first step is the
//! elements' stable step at t = 0; it reads the pure geometry of [`crate::geometry`].

pub mod failure;
pub mod forces;
pub mod hourglass;
pub mod params;
pub mod plastic;
pub mod stress;

pub use forces::{evaluate, evaluate_state, evaluate_with, Dissipation, ElementOut};
pub use params::ElementParams;
