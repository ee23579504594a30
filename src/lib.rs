//! # ricochet
//!
//! A GPU-accelerated explicit contact-impact simulator for 2D solids.
//!
//! The code reads like the method: a [`scene`] file is meshed ([`mesh`]) into a flat [`model`];
//! a [`plan`] lists the stages the scene needs; the [`step`] module integrates in time with the
//! central-difference method (element forces, node update), on the CPU reference path
//! ([`step::cpu`]) or on the GPU ([`gpu`]); [`run`] drives a solver and writes the [`output`],
//! which [`plot`] draws.

#![warn(missing_docs)]
// Index loops over element corners read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

pub mod bench;
pub mod checkpoint;
pub mod contact;
pub mod error;
pub mod geometry;
pub mod gmsh;
pub mod gpu;
pub mod mesh;
pub mod model;
pub mod output;
pub mod plan;
pub mod plot;
pub mod run;
pub mod scene;
pub mod step;
pub mod verify;

pub use error::{Error, Result};
