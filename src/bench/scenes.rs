//! The bench's generated scenes: the block of the throughput table and, for the contact table,
//! the block pressed into its base ([`ContactScene::Pair`]), a striker into a plate and a pile of
//! disks on a wall, as scene text (the committed `assets/bench/*.toml` are their output) and
//! parsed; [`with_friction`] and [`with_failure`] for the contact table's variants with friction
//! and with failure.

use std::path::Path;

use serde::Serialize;

use crate::error::Result;
use crate::model::Model;
use crate::plan::Plan;
use crate::scene::Scene;

/// The text of the block of [`scene`]: `cells` x `cells` quads, 0.1 m wide.
pub fn block_text(cells: usize) -> String {
    format!(
        r#"
[run]
end_time = 1.0e3
history_interval = 1.0e3
{steel}
[[body]]
name = "block"
material = "steel"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [0.1, 0.1], cells = [{cells}, {cells}] }} }}
velocity_gradient = [[-100.0, 0.0], [0.0, 30.0]]
"#,
        steel = steel("linear_elastic"),
    )
}

/// The `[[material]]` table of the bench scenes' steel, with the material model `model`.
fn steel(model: &str) -> String {
    format!(
        "\n[[material]]\nname = \"steel\"\nmodel = \"{model}\"\ndensity = 7850.0\n\
         youngs_modulus = 2.1e11\npoisson_ratio = 0.3\n"
    )
}

/// The bench scene: a steel block of `cells` x `cells` plane-strain quads, 0.1 m wide, squeezed by
/// an initial velocity field (compression along x, like the first microseconds of an impact), with
/// the default viscous hourglass control and bulk viscosity.
///
/// # Errors
/// None in practice (the text is generated); scene errors otherwise.
pub fn scene(cells: usize) -> Result<Scene> {
    Scene::parse(&block_text(cells), Path::new("bench.toml"))
}

/// The text of [`contact_scene`].
pub fn contact_text(cells: usize, contact: bool) -> String {
    let ny = (cells / 8).max(1);
    let h = 0.1 / cells as f64;
    let mut text = block_text(cells);
    text.push_str(&format!(
        r#"
[[body]]
name = "base"
material = "steel"
mesh = {{ rectangle = {{ origin = [0.0, {y0:e}], size = [0.1, {height:e}], cells = [{cells}, {ny}] }} }}
"#,
        y0 = -(ny as f64) * h,
        height = ny as f64 * h,
    ));
    if contact {
        text.push_str("\n[[contact]]\nbodies = [\"block\", \"base\"]\n");
    }
    text
}

/// The contact bench scene: the block of [`scene`] resting on a base of `cells` x max(1, cells / 8)
/// square elements of the same size (matching nodes along the interface), at rest. The block's
/// velocity field moves its bottom face down into the base (1.5 m/s), so the contact is active on
/// every interface node. With `contact`, a `[[contact]]` with the defaults (Lagrange, two passes)
/// between them; without, the same two bodies pass through each other (the bench's steps move
/// them by a fraction of an element).
///
/// # Errors
/// None in practice (the text is generated); scene errors otherwise.
pub fn contact_scene(cells: usize, contact: bool) -> Result<Scene> {
    Scene::parse(
        &contact_text(cells, contact),
        Path::new("bench_contact.toml"),
    )
}

/// Striker side \[m\] of [`striker_text`] (the plate is 5 x 1 of it).
pub const STRIKER_SIDE: f64 = 0.01;
/// Impact velocity \[m/s\] of [`striker_text`]: v0 / c = 0.05 for steel (c about 6000 m/s).
pub const STRIKER_VELOCITY: f64 = 300.0;
/// O-grid cells of each disk of [`pile_text`] (3 x 6^2 = 108 elements per disk).
pub const PILE_DISK_CELLS: usize = 6;
/// Disk radius \[m\] of [`pile_text`].
pub const PILE_RADIUS: f64 = 0.005;
/// Fall velocity \[m/s\] of [`pile_text`].
pub const PILE_VELOCITY: f64 = 20.0;

/// How [`pile_text`] puts its disks in contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PileContact {
    /// One `[[contact]]` with `bodies = "all"` (the default).
    All,
    /// One `[[contact]]` per pair of disks (`side^2 (side^2 - 1) / 2` of them): a fallback for
    /// builds whose scene parser does not know `bodies = "all"`; for small piles only.
    Pairs,
}

/// The run settings of a generated contact scene (`ricochet run` of the committed files); the
/// bench replaces the end time and the output intervals (see [`bench_schedule`]).
fn run_header(comment: &str, end_time: f64, history: f64, fields: f64) -> String {
    let mut s = String::new();
    for line in comment.lines() {
        s.push_str("# ");
        s.push_str(line);
        s.push('\n');
    }
    s.push_str(&format!(
        "\n[run]\nend_time = {end_time:e}\nhistory_interval = {history:e}\nfield_interval = {fields:e}\n"
    ));
    s
}

/// The striker scene of `n`: a steel striker of n x n quads (10 mm square) hitting a steel plate
/// of 5n x n quads (50 x 10 mm, its bottom edge fixed by a `[[boundary]]`) at
/// [`STRIKER_VELOCITY`] (v0 / c = 0.05, so that the contact search is due every few steps),
/// plane strain, neo-Hookean, with the default bulk viscosity and viscous hourglass control. The
/// striker starts half an element above the plate, centred, shifted by a quarter element so that
/// the nodes do not match, and the contact starts within the first steps. 6 n^2 elements
/// (n = 41, 129, 408 for about 1e4, 1e5, 1e6). With `contact`, one Lagrange `[[contact]]`
/// between the two bodies; without, the striker passes into the plate.
pub fn striker_text(n: usize, contact: bool) -> String {
    let n = n.max(1);
    let s = STRIKER_SIDE;
    let h = s / n as f64;
    let mut text = run_header(
        &format!(
            "Contact bench scene (ricochet bench --scene striker), generated by\n\
             ricochet::bench::striker_text({n}, {contact}): {e} elements.\n\
             A steel striker ({n} x {n} quads, 10 mm) hits a plate ({p} x {n} quads, 50 x 10 mm,\n\
             bottom edge fixed) at {v} m/s (v0 / c = 0.05), neo-Hookean, Lagrange contact.",
            e = 6 * n * n,
            p = 5 * n,
            v = STRIKER_VELOCITY,
        ),
        2.0e-5,
        2.0e-7,
        4.0e-6,
    );
    text.push_str(&steel("neo_hookean"));
    text.push_str(&format!(
        r#"
[[body]]
name = "striker"
material = "steel"
mesh = {{ rectangle = {{ origin = [{sx:e}, {sy:e}], size = [{s:e}, {s:e}], cells = [{n}, {n}] }} }}
initial_velocity = [0.0, {vy:?}]

[[body]]
name = "plate"
material = "steel"
mesh = {{ rectangle = {{ origin = [0.0, 0.0], size = [{pw:e}, {s:e}], cells = [{pn}, {n}] }} }}

[[boundary]]
body = "plate"
region = {{ min = [{lo:e}, {lo:e}], max = [{hi:e}, {top:e}] }}
velocity = {{ x = 0.0, y = 0.0 }}
"#,
        sx = 2.0 * s + 0.25 * h,
        sy = s + 0.5 * h,
        vy = -STRIKER_VELOCITY,
        pw = 5.0 * s,
        pn = 5 * n,
        lo = -0.5 * h,
        hi = 5.0 * s + 0.5 * h,
        top = 0.5 * h,
    ));
    if contact {
        text.push_str("\n[[contact]]\nbodies = [\"striker\", \"plate\"]\nmethod = \"lagrange\"\n");
    }
    text
}

/// The striker scene of [`striker_text`], parsed.
///
/// # Errors
/// None in practice (the text is generated); scene errors otherwise.
pub fn striker_scene(n: usize, contact: bool) -> Result<Scene> {
    Scene::parse(&striker_text(n, contact), Path::new("bench_striker.toml"))
}

/// Elements of one disk of `cells` O-grid cells (see [`crate::mesh::disk`]).
pub fn disk_elements(cells: usize) -> usize {
    cells * cells + 4 * cells * (cells / 2).max(1)
}

/// The pile scene of `side`: side x side steel disks ([`PILE_RADIUS`], [`PILE_DISK_CELLS`]
/// cells, 108 elements each) on a grid with gaps of a tenth of the radius, every other row
/// shifted by a quarter of the pitch, falling at about [`PILE_VELOCITY`] (each disk's velocity
/// perturbed by up to 1 m/s in x and y, deterministically, so that they do not fall as rigid
/// columns) onto a rigid wall (Lagrange) a tenth of the radius below the lowest row; plane
/// strain, linear elastic. `side` = 10, 32, 100 for about 1e4, 1e5, 1e6 elements (108 side^2).
/// `contact`: `None` for the run without contact (the disks pass through each other, the wall
/// stays), else the disks' `[[contact]]` (see [`PileContact`]).
pub fn pile_text(side: usize, contact: Option<PileContact>) -> String {
    let side = side.max(1);
    let disks = side * side;
    let r = PILE_RADIUS;
    let gap = 0.1 * r;
    let pitch = 2.0 * r + gap;
    let how = match contact {
        None => "no contact between the disks",
        Some(PileContact::All) => "one [[contact]] over all bodies",
        Some(PileContact::Pairs) => "one [[contact]] per pair of disks",
    };
    let mut text = run_header(
        &format!(
            "Contact bench scene (ricochet bench --scene pile), generated by\n\
             ricochet::bench::pile_text({side}, {contact:?}): {e} elements.\n\
             {disks} steel disks ({side} x {side}, R = 5 mm, {c} cells, {d} elements each) fall at\n\
             about {v} m/s onto a rigid wall; {how}.",
            e = disks * disk_elements(PILE_DISK_CELLS),
            c = PILE_DISK_CELLS,
            d = disk_elements(PILE_DISK_CELLS),
            v = PILE_VELOCITY,
        ),
        1.0e-3,
        1.0e-5,
        1.0e-4,
    );
    text.push_str(&steel("linear_elastic"));
    for j in 0..side {
        for i in 0..side {
            let shift = if j % 2 == 1 { 0.25 } else { 0.0 };
            let x = (i as f64 + 0.5 + shift) * pitch;
            let y = gap + r + j as f64 * pitch;
            let vx = 0.5 * ((i * 7 + j * 3) % 5) as f64 - 1.0;
            let vy = -PILE_VELOCITY + 0.5 * ((i * 3 + j * 5 + 2) % 5) as f64 - 1.0;
            text.push_str(&format!(
                r#"
[[body]]
name = "d{k}"
material = "steel"
mesh = {{ disk = {{ center = [{x:e}, {y:e}], radius = {r:e}, cells = {c} }} }}
initial_velocity = [{vx:?}, {vy:?}]
"#,
                k = j * side + i,
                c = PILE_DISK_CELLS,
            ));
        }
    }
    text.push_str(
        "\n[[rigid_wall]]\nname = \"floor\"\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\n\
         method = \"lagrange\"\n",
    );
    match contact {
        None => {}
        Some(PileContact::All) => text
            .push_str("\n[[contact]]\nname = \"pile\"\nbodies = \"all\"\nmethod = \"lagrange\"\n"),
        Some(PileContact::Pairs) => {
            for a in 0..disks {
                for b in a + 1..disks {
                    text.push_str(&format!(
                        "\n[[contact]]\nbodies = [\"d{a}\", \"d{b}\"]\nmethod = \"lagrange\"\n"
                    ));
                }
            }
        }
    }
    text
}

/// The pile scene of [`pile_text`], parsed.
///
/// # Errors
/// Scene errors: `PileContact::All` where `bodies = "all"` is not supported yet.
pub fn pile_scene(side: usize, contact: Option<PileContact>) -> Result<Scene> {
    Scene::parse(&pile_text(side, contact), Path::new("bench_pile.toml"))
}

/// The contact scenes of the second bench table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactScene {
    /// The block pressed into its base ([`contact_scene`]); size: cells per side of the block.
    Pair,
    /// A striker into a plate at v0 / c = 0.05 ([`striker_text`]); size: striker cells per side.
    Striker,
    /// A pile of disks dropped onto a rigid wall ([`pile_text`]); size: disks per side.
    Pile,
}

impl ContactScene {
    /// All contact scenes, in table order.
    pub const ALL: [ContactScene; 3] = [
        ContactScene::Pair,
        ContactScene::Striker,
        ContactScene::Pile,
    ];

    /// The scene's name in the table and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ContactScene::Pair => "pair",
            ContactScene::Striker => "striker",
            ContactScene::Pile => "pile",
        }
    }

    /// Elements of the scene of `size`.
    pub fn elements(self, size: usize) -> usize {
        let size = size.max(1);
        match self {
            ContactScene::Pair => size * size + size * (size / 8).max(1),
            ContactScene::Striker => 6 * size * size,
            ContactScene::Pile => size * size * disk_elements(PILE_DISK_CELLS),
        }
    }

    /// The size whose scene has about `elements` elements (at least 1): the block's cells per
    /// side (elements / 1.125), the striker's n (elements / 6; 41, 129, 408 for 1e4, 1e5, 1e6),
    /// the pile's disks per side (about 100 elements per disk; 10, 32, 100).
    pub fn size_for(self, elements: usize) -> usize {
        let per = match self {
            ContactScene::Pair => 1.125,
            ContactScene::Striker => 6.0,
            ContactScene::Pile => 100.0,
        };
        ((elements as f64 / per).sqrt().round() as usize).max(1)
    }

    /// The scene text of `size`, with or without its contact (`pile`: how the pile's disks are
    /// put in contact).
    pub fn text(self, size: usize, contact: bool, pile: PileContact) -> String {
        match self {
            ContactScene::Pair => contact_text(size, contact),
            ContactScene::Striker => striker_text(size, contact),
            ContactScene::Pile => pile_text(size, contact.then_some(pile)),
        }
    }

    /// The parsed scene of [`ContactScene::text`].
    ///
    /// # Errors
    /// Scene errors (the pile's `bodies = "all"` where it is not supported yet).
    pub fn scene(self, size: usize, contact: bool, pile: PileContact) -> Result<Scene> {
        let name = format!("bench_{}.toml", self.name());
        Scene::parse(&self.text(size, contact, pile), Path::new(&name))
    }
}

/// The schedule of a bench run of `scene`: its own step control, but no end (1e3 s) and no
/// outputs due during the bench (history every 1e3 s, no fields).
pub fn bench_schedule(scene: &Scene) -> crate::step::Schedule {
    let mut s = crate::run::schedule(scene);
    s.end_time = 1.0e3;
    s.history_interval = 1.0e3;
    s.field_interval = None;
    s
}

/// `text` with `friction = mu` in every `[[contact]]` and `[[rigid_wall]]` table (the line goes
/// right under the table's header, so the tables keep their other keys).
pub fn with_friction(text: &str, mu: f64) -> String {
    let mut s = String::with_capacity(text.len() + 64);
    for line in text.lines() {
        s.push_str(line);
        s.push('\n');
        if matches!(line.trim(), "[[contact]]" | "[[rigid_wall]]") {
            s.push_str(&format!("friction = {mu:?}\n"));
        }
    }
    s
}

/// Principal-strain limit of the contact table's variant with failure when `--failure` gives
/// none: in the striker at 10^4 elements the first elements erode within 60 steps of the start
/// and about 1.3 a step erode over the first 500 (CPU reference, 2026-11-28).
pub const FAILURE_STRAIN: f64 = 0.03;

/// `text` with `failure = { principal_strain = strain }` in every `[[material]]` (under its
/// `model` line) and `erosion = { inverted = true }` in `[run]`: every body's elements erode at
/// that largest principal strain, and an element about to invert erodes instead of stopping the
/// run, so that a bench scene erodes steadily while it is timed.
pub fn with_failure(text: &str, strain: f64) -> String {
    let mut s = String::with_capacity(text.len() + 128);
    let mut material = false;
    for line in text.lines() {
        s.push_str(line);
        s.push('\n');
        let t = line.trim();
        if t.starts_with("[[") || t.starts_with('[') {
            material = t == "[[material]]";
        }
        if t == "[run]" {
            s.push_str("erosion = { inverted = true }\n");
        }
        if material && t.starts_with("model =") {
            s.push_str(&format!("failure = {{ principal_strain = {strain:?} }}\n"));
        }
    }
    s
}

/// The model and plan of a bench scene, after checking that its size fits the machine's memory.
pub(super) fn build(scene: &Scene) -> Result<(Model, Plan)> {
    // Before meshing: a size beyond the machine's memory is refused, not allocated.
    crate::run::check_memory(scene)?;
    let model = crate::run::model(scene)?;
    let plan = Plan::new(scene, &model);
    Ok((model, plan))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_scene_has_the_pair_only_when_asked() {
        let (m, p) = build(&contact_scene(8, true).expect("scene")).expect("model");
        assert_eq!((m.bodies.len(), p.contacts), (2, 1));
        assert_eq!(m.element_count(), 64 + 8);
        let (_, p) = build(&contact_scene(8, false).expect("scene")).expect("model");
        assert_eq!(p.contacts, 0);
    }
    /// The committed scene files of assets/bench/ are the generators' output (set
    /// `RICOCHET_BLESS=1` to rewrite them).
    #[test]
    fn committed_bench_scenes_are_the_generators_output() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bench");
        for (file, text) in [
            ("striker_1e4.toml", striker_text(41, true)),
            ("pile_1e4.toml", pile_text(10, Some(PileContact::All))),
        ] {
            let path = dir.join(file);
            if std::env::var_os("RICOCHET_BLESS").is_some() {
                std::fs::create_dir_all(&dir).expect("assets/bench");
                std::fs::write(&path, &text).expect("write");
            }
            let committed = std::fs::read_to_string(&path).expect("committed scene");
            assert!(
                committed == text,
                "{file} differs from the generator (RICOCHET_BLESS=1)"
            );
        }
    }

    #[test]
    fn sizes_map_to_the_element_targets() {
        let sizes = |s: ContactScene| [10_000, 100_000, 1_000_000].map(|e| s.size_for(e));
        assert_eq!(sizes(ContactScene::Striker), [41, 129, 408]);
        assert_eq!(sizes(ContactScene::Pile), [10, 32, 100]);
        assert_eq!(ContactScene::Pile.elements(32), 110_592);
        assert_eq!(ContactScene::Striker.elements(41), 10_086);
        assert_eq!(disk_elements(4), 48);
    }

    #[test]
    fn generated_contact_scenes_parse_with_the_expected_counts() {
        let (m, p) = build(&striker_scene(4, true).expect("striker")).expect("model");
        assert_eq!(m.element_count(), ContactScene::Striker.elements(4));
        assert_eq!((m.bodies.len(), p.contacts), (2, 1));
        let scene = striker_scene(4, false).expect("striker");
        assert_eq!((scene.boundaries.len(), scene.contacts.len()), (1, 0));
        // The pile with `bodies = "all"`, or with explicit pairs where that does not parse yet.
        let (scene, pairs) = match pile_scene(3, Some(PileContact::All)) {
            Ok(s) => (s, false),
            Err(_) => (pile_scene(3, Some(PileContact::Pairs)).expect("pile"), true),
        };
        let (m, _) = build(&scene).expect("model");
        assert_eq!(m.element_count(), ContactScene::Pile.elements(3));
        assert_eq!((m.bodies.len(), scene.walls.len()), (9, 1));
        assert_eq!(scene.contacts.len(), if pairs { 36 } else { 1 });
        let scene = pile_scene(3, None).expect("pile");
        assert_eq!((scene.contacts.len(), scene.walls.len()), (0, 1));
        for which in ContactScene::ALL {
            let s = which.scene(8, true, PileContact::Pairs).expect("scene");
            let (m, _) = build(&s).expect("model");
            assert_eq!(m.element_count(), which.elements(8), "{}", which.name());
        }
    }
}
