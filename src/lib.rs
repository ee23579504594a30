//! # ricochet
//!
//! A GPU-accelerated explicit contact-impact simulator for 2D solids.
//!
//! The code reads like the method: a [`scene`] file is meshed ([`mesh`]) into a flat [`model`];
//! a [`plan`] lists the stages the scene needs; the [`step`] module integrates in time with the
//! central-difference method, on the CPU reference path ([`step::cpu`]: the [`element`] forces,
//! the node update, the [`contact`] correction) or on the GPU ([`gpu`]); [`run`] drives a solver
//! and writes the [`output`] (and the [`checkpoint`]s), which [`plot`] draws; [`verify`] and
//! [`bench`](mod@bench) run whole scenes.
//!
//! ## Layers
//!
//! Each module uses only the modules of the layers above its own, never one of its own layer or
//! below (`tests/core/layout.rs` checks that their dependencies, and those between the modules
//! inside [`step`], [`contact`] and [`gpu`], form no circle):
//!
//! 1. [`error`]; [`geometry`] (the element's geometry, pure functions of its corners);
//!    [`input`] (files read whole within a cap)
//! 2. [`gmsh`] (Gmsh mesh files)
//! 3. [`scene`]
//! 4. [`mesh`] (generated meshes); [`element`] (a body's element parameters, the material
//!    models, one element's forces and stable step)
//! 5. [`model`] (with its bodies' surfaces, [`model::surface`])
//! 6. [`plan`]; [`contact`]
//! 7. [`step`]
//! 8. [`output`]; [`gpu`]
//! 9. [`checkpoint`]; [`plot`]
//! 10. [`run`]
//! 11. [`verify`]; [`bench`](mod@bench); [`study`] (many runs of one scene, here or on Slurm)
//!
//! What two layers share lives in the lower one: the corner geometry that the scene's mesh
//! checks, the model, the contact and the element read is in [`geometry`]; the element is below
//! the model, whose bodies hold its parameters and whose first step is the elements' stable
//! step at t = 0 (which the contact's mass-form penalty also reads); the bodies' surfaces, on
//! which the model resolves pressure loads and the contact builds its passes, are the model's.

#![warn(missing_docs)]
// Index loops over element corners read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

pub mod bench;
pub mod checkpoint;
pub mod contact;
pub mod element;
pub mod error;
pub mod geometry;
pub mod gmsh;
pub mod gpu;
pub mod input;
pub mod mesh;
pub mod model;
pub mod output;
pub mod plan;
pub mod plot;
pub mod run;
pub mod scene;
pub mod step;
pub mod study;
pub mod verify;

pub use error::{Error, Result};
