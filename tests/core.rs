//! The core test suite of ricochet: the CPU reference path against analytic values.
//!
//! One test binary (to keep link time down) with one module per topic under `tests/core/`:
//!
//! - [`patch`]: constant-strain patch tests (single quad, distorted patches, a Gmsh mesh), exact stress;
//! - [`gmsh`]: the shipped Gmsh MSH 4.1 meshes (counts, ASCII against binary, orientation);
//! - [`mesh_files`]: hostile and unusual mesh files: any binary data size, streams and FIFOs,
//!   nodes found by their tags (permuted, repeated, 0, out of range), numbered physical groups;
//! - [`rigid`]: rigid translation and (large) rotation of neo-Hookean elements, spinning disk;
//! - [`hourglass`]: hourglass modes, their control (stiffness, viscous) and reported energy;
//! - [`load_curve`]: velocities and pressures as tables of (time, value), the pulled bar's closed form;
//! - [`mass`]: lumped mass and momentum conservation;
//! - [`wave`]: 1D waves in a rod strip against the dispersion table of `REFERENCES.md` section 2;
//! - [`energy`]: the energy audit of a free-vibrating block (conservative and dissipative), of a
//!   pressure load and of mass damping;
//! - [`failure`]: material failure and erosion: a single element eroding at the step its
//!   plastic strain reaches the limit, Johnson-Cook damage at zero triaxiality against its closed
//!   form, the energy audit with `eroded_energy`, free nodes, the plan, the outputs;
//! - [`erosion_contact`]: eroding contact: the masked candidate edges against the boundary of
//!   the remaining elements, two-body, group, self-contact and wall surfaces following erosion, a
//!   projectile perforating a plate, a long rod penetrating a thick target, free nodes stopping
//!   on a wall;
//! - [`friction`]: Coulomb friction with Lagrange contact: a block sliding on a floor and on a
//!   clamped block decelerates at mu g, its friction work and force;
//! - [`gravity`]: gravity as a body force: exact free fall and its work, a block resting on a wall;
//! - [`patch_contact`]: the contact patch test (two blocks, non-matching meshes, pressure load,
//!   mass damping): two-pass Lagrange exact, one pass failing as it should;
//! - [`general_contact`]: contact groups (`bodies = "all"`, lists) and self-contact: the scene
//!   forms, the GPU tables, a pile of 16 disks and a ring pressed onto itself;
//! - [`perturbed`]: the perturbed Lagrangian's consistent H against the node-by-node penalty;
//! - [`augmented`]: the augmented Lagrangian leaving no penetration in a persistent contact, and
//!   the keys it refuses;
//! - [`contact`]: rod impact (Lagrange, penalty, rigid wall, impedance mismatch), corner-first
//!   square on a wall, the contact plan and history columns;
//! - [`stress`]: the stiff and extreme cases of `assets/stress/` (REFERENCES.md section 6): stiff
//!   penalty, mass and element-size ratios, impacts up to 0.3 c, a thin plate crossed within a
//!   step, nu = 0.499, initial overlaps, corner impacts, time_step_scale 1.0 and 1.2;
//! - [`axisymmetric`]: the axisymmetric formulation: hoop-strain patch test, masses per radian,
//!   the axis held at u_r = 0, refused inputs;
//! - [`plastic`]: J2 plasticity: the plastic patch test of REFERENCES.md section 10 against the
//!   closed form, its energy audit with `plastic_work`, objectivity under rigid rotations;
//! - [`plan`]: a scene pays only for what it uses: the exact stages of the plan, `ricochet check`
//!   printing it, no contact state without contact, and `ricochet bench` reporting its ratios;
//! - [`bad_input`]: every rejected scene exits with status 2 and names the file, key and value;
//! - [`fuzz`]: 2000 mutants of the scenes of `assets/` through the load path and a short CPU run
//!   (and a sample through `ricochet check`): no panic, hang, escaped file, unbounded memory or
//!   non-finite number in a completed run;
//! - [`fuzz_files`]: mutated mesh files, checkpoints and output folders: refused naming the
//!   file, or run to a whole history; nothing hangs;
//! - [`outputs`]: `history.csv`, `summary.json`, VTU fields (read back with meshio), unstable runs;
//! - [`plot`]: `ricochet plot` and `run --plots`: every picture at its size, identical bytes twice,
//!   GIF frames, the colour of the patch test's uniform stress, the window around the cells
//!   drawn, refused folders and fields;
//! - [`restart`]: checkpoints and `run --restart` give the outputs of the run never stopped, bit
//!   for bit, after a crash and after an interruption, with contact; bad checkpoints exit 2;
//! - [`checkpoint_checks`]: checkpoints that are streams or huge, another run's, damaged, or
//!   whose mesh, `history.csv` or `fields/` changed since: exit 2 naming the file;
//! - [`output_lock`]: a second run or restart into an output folder in use exits 2 naming the
//!   folder and the process; a lock left by a process that ended does not block;
//! - [`run_library`]: the run as a library call (`run::execute`): progress reported, an interrupt
//!   flag giving an `interrupted` outcome and summary, and a restart through the same call;
//! - [`verify_cases`]: the verification cases as data, and `verify`'s exit status on a missed bound;
//! - [`layout`]: the library's modules depend on each other one way (no circle between the
//!   top-level modules, nor inside `step`, `contact` and `gpu`).

#[macro_use]
#[path = "shared/scene_text.rs"]
mod scene_text;

#[path = "core/common.rs"]
mod common;

#[path = "core/augmented.rs"]
mod augmented;
#[path = "core/axisymmetric.rs"]
mod axisymmetric;
#[path = "core/bad_input.rs"]
mod bad_input;
#[path = "core/checkpoint_checks.rs"]
mod checkpoint_checks;
#[path = "core/contact.rs"]
mod contact;
#[path = "core/energy.rs"]
mod energy;
#[path = "core/erosion_contact.rs"]
mod erosion_contact;
#[path = "core/failure.rs"]
mod failure;
#[path = "core/friction.rs"]
mod friction;
#[path = "core/fuzz.rs"]
mod fuzz;
#[path = "core/fuzz_files.rs"]
mod fuzz_files;
#[path = "core/general_contact.rs"]
mod general_contact;
#[path = "core/gmsh.rs"]
mod gmsh;
#[path = "core/gravity.rs"]
mod gravity;
#[path = "core/hourglass.rs"]
mod hourglass;
#[path = "core/layout.rs"]
mod layout;
#[path = "core/load_curve.rs"]
mod load_curve;
#[path = "core/mass.rs"]
mod mass;
#[path = "core/mesh_files.rs"]
mod mesh_files;
#[path = "core/output_lock.rs"]
mod output_lock;
#[path = "core/outputs.rs"]
mod outputs;
#[path = "core/patch.rs"]
mod patch;
#[path = "core/patch_contact.rs"]
mod patch_contact;
#[path = "core/perturbed.rs"]
mod perturbed;
#[path = "core/plan.rs"]
mod plan;
#[path = "core/plastic.rs"]
mod plastic;
#[path = "core/plot.rs"]
mod plot;
#[path = "core/restart.rs"]
mod restart;
#[path = "core/rigid.rs"]
mod rigid;
#[path = "core/run_library.rs"]
mod run_library;
#[path = "core/stress.rs"]
mod stress;
#[path = "core/verify_cases.rs"]
mod verify_cases;
#[path = "core/wave.rs"]
mod wave;
