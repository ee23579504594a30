//! The general-contact checks shared by the CPU (`tests/core/general_contact.rs`) and GPU
//! (`tests/gpu/general.rs`) tests: the assets they run, the most nodes a contact table had
//! active, and what both backends assert on the pile of sixteen disks in one `bodies = "all"`
//! table (`assets/pile.toml`) and on the ring pressed onto itself (`assets/ring_crush.toml`),
//! each to its own depth.
#![allow(dead_code)]

use ricochet::model::Model;
use ricochet::run::RunResult;

use crate::stress::penetration::{interpenetration, self_penetration};

/// The text of `assets/<name>`.
pub fn asset(name: &str) -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The most nodes the contact table `contact` had active in a history row of `r`.
pub fn most_active(r: &RunResult, contact: usize) -> u32 {
    r.samples
        .iter()
        .map(|(s, _)| s.contacts[contact].active_nodes)
        .max()
        .unwrap_or(0)
}

/// Element size of the pile's disks (radius 5 mm, 4 cells).
pub const PILE_H: f64 = 0.01 / 4.0;

/// Element size across the ring's wall.
pub const RING_T: f64 = 0.002;

/// What the pile of sixteen disks measured at the end of a run.
pub struct Pile {
    /// The largest energy-balance error.
    pub err: f64,
    /// The deepest node inside another disk at the end (m).
    pub deepest: f64,
    /// The most nodes in contact between disks in a history row.
    pub active: u32,
}

/// The pile of sixteen disks after a run on either backend (`r`, the model and the final
/// displacements `u`): the disks met (more than 10 nodes in disk contact), the energy balance
/// holds within 1e-3, and no node lies deeper than `depth` x h inside another disk.
pub fn check_pile(r: &RunResult, model: &Model, u: &[[f64; 2]], depth: f64) -> Pile {
    let p = Pile {
        err: r.summary.max_energy_error,
        deepest: interpenetration(model, u),
        active: most_active(r, 0),
    };
    assert!(p.active > 10, "the disks met");
    assert!(p.err < 1e-3, "energy balance {:e}", p.err);
    assert!(p.deepest < depth * PILE_H, "{:e} m inside", p.deepest);
    p
}

/// What the ring pressed onto itself measured at the end of a run.
pub struct Ring {
    /// The largest energy-balance error.
    pub err: f64,
    /// The deepest node inside its own ring at the end (m).
    pub inside: f64,
    /// The deepest node inside the punch at the end (m).
    pub other: f64,
    /// The most nodes in self-contact in a history row.
    pub active: u32,
}

/// The ring pressed onto itself after a run on either backend: it met itself (more than 5 nodes
/// in self-contact), the energy balance holds within 1e-3, and no node lies deeper than `depth` x
/// the wall's element size inside its own ring or inside the punch.
pub fn check_ring(r: &RunResult, model: &Model, u: &[[f64; 2]], depth: f64) -> Ring {
    let ring = Ring {
        err: r.summary.max_energy_error,
        inside: self_penetration(model, u, 0),
        other: interpenetration(model, u),
        active: most_active(r, 1),
    };
    assert!(ring.active > 5, "the ring met itself");
    assert!(ring.err < 1e-3, "energy balance {:e}", ring.err);
    for (what, depth_m) in [("its own ring", ring.inside), ("the punch", ring.other)] {
        assert!(depth_m < depth * RING_T, "{depth_m:e} m inside {what}");
    }
    ring
}
