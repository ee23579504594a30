//! The tests of studies (`ricochet study`, `collect`, `check` and `plot` on a study folder),
//! through the binary, on the CPU reference (a study's runs are child processes of the binary):
//!
//! - [`local`]: the 12-case grid of `assets/studies/rods_grid.toml` run here, rerun without
//!   recomputing a case, interrupted and continued, a failing case reported in `results.csv`,
//!   the threshold search against its closed form, `plot --figure --against`;
//! - [`bad_study`]: bad study files exit 2 naming the file, the key and the value, and a fuzz of
//!   study files (numbers, strings, keys, types, paths) that never panics or hangs;
//! - [`slurm`]: the same grid and a 6-case study whose task is stopped mid-run, through
//!   `--slurm` on a one-node Slurm cluster started for the tests (`tests/slurm/start.sh`): the
//!   requeued task restarts from its checkpoint, and `results.csv` equals the local run's.
//!   Without Slurm (`sbatch` not on PATH) these fail when `CI` is set and are skipped with a
//!   notice otherwise.

#[path = "study/common.rs"]
mod common;

#[path = "study/bad_study.rs"]
mod bad_study;
#[path = "study/local.rs"]
mod local;
#[path = "study/slurm.rs"]
mod slurm;
