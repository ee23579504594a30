//! Studies: many runs of one scene (README, "Studies"). A study file ([`spec`], its checks in
//! [`validate`]) names a base
//! scene, the scene keys it varies (overridden by [`crate::scene::overrides`]) and the figures
//! to collect; [`cases`] makes its cases (a grid, lists side by side, a seeded Latin hypercube)
//! and writes each one's materialised scene and manifest under `DIR/cases/<id>/`; [`local`] runs
//! them on this machine as child processes of the ricochet binary (one worker per hardware GPU
//! adapter, else per CPU core), [`slurm`] writes and submits a Slurm job array that runs them on
//! a cluster, [`threshold`] searches for the value of one parameter at which a condition flips,
//! and [`collect`](mod@collect) joins every case's parameters, status and figures into `results.csv` and
//! `results.json`. Nothing here prints or exits: the command line (`ricochet study`, `collect`,
//! `check`, `plot`) and the Python binding call these functions. Host-side only, no GPU twin
//! (the cases' runs choose their backend as `ricochet run` does).

pub mod cases;
pub mod collect;
pub mod local;
pub mod plot;
pub mod slurm;
pub mod spec;
pub mod threshold;
pub mod validate;

pub use cases::{Case, Manifest, Record};
pub use collect::{collect, CaseStatus, Results};
pub use local::{Progress, Runner, Worker};
pub use spec::{Kind, Study};
