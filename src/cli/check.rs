//! `ricochet check SCENE`: validates a scene without running it (the library's
//! [`ricochet::run::load`]) and prints its plan: the model and its bodies, the stable step, the
//! contact tables and how they enforce contact, the loads, the memory estimate, the outputs and
//! the stages that will run. A study file (one with a `[study]` table) is checked case by case
//! ([`ricochet::study::Study::check`]).

use std::process::ExitCode;

use ricochet::contact::ContactSet;
use ricochet::model::Model;
use ricochet::plan::Plan;
use ricochet::scene::Scene;
use ricochet::step::cpu::CpuSolver;

use super::args::CheckArgs;

/// `ricochet check SCENE` (or a study file: every case's scene checked).
pub fn check(args: CheckArgs) -> anyhow::Result<ExitCode> {
    if ricochet::study::spec::is_study_file(&args.scene) {
        let study = ricochet::study::Study::load(&args.scene)?;
        let root = std::path::PathBuf::from("out").join(&study.name);
        let cases = study.check(&root)?;
        println!(
            "study {} ({}): {} {} cases of {} checked{}",
            study.name,
            study.file.display(),
            cases.len(),
            study.kind.keyword(),
            study.scene.display(),
            if matches!(study.kind, ricochet::study::Kind::Threshold(_)) {
                " (the two ends of the bracket)"
            } else {
                ""
            }
        );
        return Ok(ExitCode::SUCCESS);
    }
    let (scene, model, plan) = ricochet::run::load(&args.scene, None)?;
    print_plan(&scene, model, &plan)?;
    Ok(ExitCode::SUCCESS)
}

/// Prints the plan of a loaded scene; an error for a fixed `run.time_step` above the stable
/// step.
fn print_plan(scene: &Scene, model: Model, plan: &Plan) -> anyhow::Result<()> {
    let schedule = ricochet::run::schedule(scene);
    let mut contact = ContactSet::new(&model);
    let solver = CpuSolver::new(model, plan.clone(), schedule);
    let model = solver.model();
    let (dt_element, e) = solver.stable_step();
    let (dt, step) = ricochet::run::checked_step(scene, (dt_element, e), contact.as_ref())?;
    let steps = (scene.run.end_time / step).ceil() as u64;
    println!("scene      {} ({})", scene.name, scene.file.display());
    println!(
        "model      {} nodes, {} elements, {} bodies, {} constrained nodes",
        plan.nodes,
        plan.elements,
        model.bodies.len(),
        plan.constrained_nodes
    );
    print_bodies(scene, model);
    println!(
        "time step  stable {dt:.4e} s (element {e}); step {step:.4e} s; about {steps} steps to {:e} s",
        scene.run.end_time
    );
    if let Some(c) = contact.as_mut() {
        print_contact(scene, model, plan, c, dt, dt_element);
    }
    print_faces(model);
    print_loads(scene, model);
    print_outputs(scene, plan);
    Ok(())
}

/// Each body: nodes, elements, mass, wave speed, hourglass form; its Gmsh mesh, formulation and
/// plasticity.
fn print_bodies(scene: &Scene, model: &Model) {
    for b in &model.bodies {
        println!(
            "  body     {:<16} {} nodes, {} elements, mass {:.6e} kg, c_d {:.1} m/s, hourglass {:?}",
            b.name,
            b.nodes.len(),
            b.elements.len(),
            b.mass,
            b.params.dilatational_speed(),
            b.params.hourglass
        );
        if let Some(ricochet::scene::MeshSpec::Gmsh { file, group, mesh }) = scene
            .bodies
            .iter()
            .find(|sb| sb.name == b.name)
            .map(|sb| &sb.mesh)
        {
            let tris = mesh.triangles();
            println!(
                "           Gmsh {} group `{group}`: {} quads (4-node), {tris} triangles (3-node), {} nodes{}",
                file.display(),
                mesh.quads.len() - tris,
                mesh.nodes.len(),
                if mesh.reoriented > 0 {
                    format!(", {} turned counter-clockwise", mesh.reoriented)
                } else {
                    String::new()
                }
            );
            if let Some((i, area, edge)) = mesh.smallest() {
                println!(
                    "           smallest element: Gmsh tag {}, area {area:.4e} m^2, shortest edge {edge:.4e} m",
                    mesh.element_tags[i]
                );
            }
        }
        if b.params.formulation == ricochet::scene::Formulation::Axisymmetric {
            println!("           axisymmetric (x = r; masses, forces and energies per radian)");
        }
        if b.params.model == ricochet::scene::MaterialModel::J2Plastic {
            let p = &b.params;
            if p.jc_b != 0.0 || p.jc_c != 0.0 {
                println!(
                    "           J2 plastic, Johnson-Cook: a {:e} Pa, b {:e} Pa, n {}, c {}, reference strain rate {:e} 1/s",
                    p.yield_stress, p.jc_b, p.jc_n, p.jc_c, p.jc_rate0
                );
            } else {
                println!(
                    "           J2 plastic: yield stress {:e} Pa, hardening modulus {:e} Pa",
                    p.yield_stress, p.hardening
                );
            }
        }
        if let Some(t) = scene
            .bodies
            .iter()
            .find(|sb| sb.name == b.name)
            .and_then(|sb| scene.materials.get(sb.material))
            .and_then(|m| m.plasticity?.johnson_cook?.thermal)
        {
            println!(
                "           {}; the temperature T per element from room temperature, T* = (T - T_r) / (T_m - T_r) in [0, 1]",
                t.describe()
            );
        }
        if let Some(f) = &b.params.failure {
            println!(
                "           failure: {}; a failed element erodes at once (its mass stays on its nodes)",
                f.describe()
            );
        }
    }
}

/// The contact tables and walls: counts, margin, methods, augmentation, what sets the step,
/// friction and the overlaps at t = 0.
fn print_contact(
    scene: &Scene,
    model: &Model,
    plan: &Plan,
    c: &mut ContactSet,
    dt: f64,
    dt_element: f64,
) {
    let groups: Vec<&ricochet::scene::Contact> =
        model.contacts.iter().filter(|c| c.group).collect();
    let mut group_bodies: Vec<usize> = groups.iter().flat_map(|c| c.bodies.clone()).collect();
    group_bodies.sort_unstable();
    group_bodies.dedup();
    let self_bodies: usize = groups
        .iter()
        .filter(|c| c.self_contact)
        .map(|c| c.bodies.len())
        .sum();
    let names = c.names();
    println!(
        "contact    {} contact tables ({} pairs, {} groups over {} bodies, self-contact on {}), \
         {} walls{}; search margin {:.4e} m",
        plan.contacts,
        plan.contacts - groups.len(),
        groups.len(),
        group_bodies.len(),
        self_bodies,
        plan.walls,
        if names.len() <= 8 {
            format!(": {}", names.join(", "))
        } else {
            String::new()
        },
        c.margin()
    );
    // How the tables and walls enforce contact (counts per method, in the scene's words).
    let mut methods: Vec<(&str, usize)> = Vec::new();
    for m in model
        .contacts
        .iter()
        .map(|c| c.method)
        .chain(model.walls.iter().map(|w| w.method))
    {
        match methods.iter_mut().find(|(w, _)| *w == m.word()) {
            Some((_, n)) => *n += 1,
            None => methods.push((m.word(), 1)),
        }
    }
    let methods: Vec<String> = methods.iter().map(|(w, n)| format!("{w} {n}")).collect();
    println!("  methods  {}", methods.join(", "));
    let rates: Vec<String> = model
        .contacts
        .iter()
        .map(|c| (&c.name, c.method, c.augmentation_rate))
        .chain(
            model
                .walls
                .iter()
                .map(|w| (&w.name, w.method, w.augmentation_rate)),
        )
        .filter(|(_, m, _)| *m == ricochet::scene::ContactMethod::AugmentedLagrange)
        .map(|(n, _, r)| format!("{n} {r} /s"))
        .collect();
    if !rates.is_empty() {
        println!(
            "  augment  {} (the multipliers' update rate, below run.mass_damping = {} /s)",
            rates.join(", "),
            scene.run.mass_damping
        );
    }
    match c.penalty_step() {
        Some((dp, what)) => println!(
            "  penalty  {what} alone allows {dp:.4e} s; with the elements {dt:.4e} s: {}",
            if dt < 0.99 * dt_element {
                format!("it controls dt (element step {dt_element:.4e} s)")
            } else {
                "the elements control dt".to_string()
            }
        ),
        None => {
            let mass_form = model
                .contacts
                .iter()
                .map(|c| (c.method, c.penalty_form))
                .chain(model.walls.iter().map(|w| (w.method, w.penalty_form)))
                .any(|(m, f)| m.has_springs() && f == ricochet::scene::PenaltyForm::Mass);
            if mass_form {
                println!(
                    "  penalty  mass form k = s m* / dt^2 at dt = {:.4e} s: no effect on the stable step",
                    model.initial_step()
                );
            } else {
                println!("  lagrange no effect on the stable step");
            }
        }
    }
    let friction: Vec<String> = model
        .contacts
        .iter()
        .map(|c| (&c.name, c.friction, c.method, c.friction_stiffness))
        .chain(
            model
                .walls
                .iter()
                .map(|w| (&w.name, w.friction, w.method, w.friction_stiffness)),
        )
        .filter(|(_, mu, _, _)| *mu > 0.0)
        .map(|(n, mu, m, kt)| {
            let how = match m {
                ricochet::scene::ContactMethod::Lagrange => "lagrange".to_string(),
                ricochet::scene::ContactMethod::Penalty => {
                    format!("penalty, regularized, k_t = {kt} k")
                }
                // Refused by the scene reader (normal multipliers only).
                m @ (ricochet::scene::ContactMethod::PerturbedLagrange
                | ricochet::scene::ContactMethod::AugmentedLagrange) => m.word().to_string(),
            };
            format!("{n} mu = {mu} ({how})")
        })
        .collect();
    if !friction.is_empty() {
        println!("  friction Coulomb: {}", friction.join(", "));
    }
    let overlaps = &model.initial_overlaps;
    if overlaps.is_empty() {
        println!("  overlaps none at t = 0");
    }
    for o in overlaps.iter().take(20) {
        println!(
            "  overlap  {}: node {} penetrated {:.4e} m at t = 0; moved onto the surface (no strain)",
            o.interface, o.node, o.depth
        );
    }
    if overlaps.len() > 20 {
        println!("  overlap  ... {} in all", overlaps.len());
    }
}

/// The named faces of the contacts between surfaces.
fn print_faces(model: &Model) {
    for c in model.contacts.iter().filter(|c| c.surfaces.is_some()) {
        if let Some(faces) = &c.surfaces {
            let named: Vec<String> = faces
                .iter()
                .zip(&c.bodies)
                .map(|((name, edges), &b)| {
                    format!(
                        "`{name}` of {} ({} edges)",
                        model.bodies[b].name,
                        edges.len()
                    )
                })
                .collect();
            println!("  faces    {}: {}", c.name, named.join(" against "));
        }
    }
}

/// Boundaries with groups or load curves, pressure loads, gravity and mass damping.
fn print_loads(scene: &Scene, model: &Model) {
    for b in &scene.boundaries {
        let curve = |c: &Option<ricochet::scene::LoadCurve>, axis: &str| {
            c.as_ref().map(|c| {
                let last = c.points.last().copied().unwrap_or([0.0; 2]);
                format!(
                    ", v{axis} a load curve of {} points ({:e} m/s from {:e} s)",
                    c.points.len(),
                    last[1],
                    last[0]
                )
            })
        };
        let curves = [curve(&b.curve_x, "x"), curve(&b.curve_y, "y")]
            .into_iter()
            .flatten()
            .collect::<String>();
        let group = b
            .group
            .as_ref()
            .map(|g| format!(" on group `{}` ({} nodes)", g.name, g.nodes.len()));
        if group.is_some() || !curves.is_empty() {
            println!("boundary   {}{}{curves}", b.key, group.unwrap_or_default());
        }
    }
    for (i, p) in model.pressures.iter().enumerate() {
        let ramp = match (&p.curve, p.ramp) {
            (Some(c), _) => format!(
                ", a load curve of {} points ({:e} Pa from {:e} s)",
                c.points.len(),
                c.points.last().map_or(0.0, |q| q[1]),
                c.points.last().map_or(0.0, |q| q[0])
            ),
            (None, Some(r)) => format!(", ramped over {r:e} s"),
            (None, None) => String::new(),
        };
        println!(
            "pressure   pressure[{i}]: {:e} Pa on {} edges ({} nodes){ramp}",
            p.value,
            p.edges,
            p.nodes.len()
        );
    }
    if model.gravity != [0.0; 2] {
        println!(
            "gravity    [{:e}, {:e}] m/s^2 on every node{}",
            model.gravity[0],
            model.gravity[1],
            if model.gravity_ramp > 0.0 {
                format!(", ramped in over {:e} s", model.gravity_ramp)
            } else {
                String::new()
            }
        );
    }
    if model.mass_damping > 0.0 {
        println!(
            "damping    mass-proportional, alpha = {:e} 1/s (critical for the mode omega = {:e} rad/s)",
            model.mass_damping,
            0.5 * model.mass_damping
        );
    }
}

/// The memory estimate, the outputs and the plan's stages.
fn print_outputs(scene: &Scene, plan: &Plan) {
    let bytes_cpu = ricochet::run::memory_estimate(scene);
    let have = ricochet::run::available_memory()
        .map(|b| format!(" of {:.1} MiB available", b as f64 / 1048576.0))
        .unwrap_or_default();
    println!(
        "memory     about {:.1} MiB (CPU reference peak, from {} + {} bytes per element with \
         fields){have}",
        bytes_cpu as f64 / 1048576.0,
        ricochet::run::BYTES_PER_ELEMENT,
        ricochet::run::FIELD_BYTES_PER_ELEMENT
    );
    let r = &scene.run;
    let mut outputs = format!(
        "history every {:e} s (about {:.0} rows)",
        r.history_interval,
        (r.end_time / r.history_interval).floor() + 1.0
    );
    if let Some(f) = r.field_interval {
        let format = match r.field_format {
            ricochet::scene::FieldFormat::Binary => "binary VTU, Float32, zlib",
            ricochet::scene::FieldFormat::Binary64 => "binary VTU, Float64, zlib",
            ricochet::scene::FieldFormat::Ascii => "ASCII VTU",
        };
        outputs.push_str(&format!(
            ", fields every {f:e} s (about {:.0} snapshots, {format})",
            (r.end_time / f).floor() + 1.0
        ));
    }
    if let Some(c) = r.checkpoint_interval {
        outputs.push_str(&format!(", a checkpoint every {c:e} s"));
    }
    println!("outputs    {outputs}");
    println!("plan       {plan}");
    if scene.run.erode_inverted {
        println!(
            "erosion    an element about to invert erodes (run.erosion.inverted) instead of stopping the run"
        );
    }
    if let Some(s) = scene.run.erode_min_time_step {
        println!(
            "erosion    an element whose stable step times time_step_scale falls below {s:e} s \
             erodes (run.erosion.min_time_step) instead of shrinking the run's step"
        );
    }
}
