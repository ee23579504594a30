//! The bench's rows and tables: a [`BenchRow`] per backend of the block bench (its throughput,
//! the full step over the bare loop, what a contact pair adds) printed by [`table`] and
//! [`summary`], and a [`ContactRow`] per backend and contact scene printed by [`contact_table`].

use serde::Serialize;

use super::scenes::ContactScene;

/// One row of the bench table.
#[derive(Debug, Clone, Serialize)]
pub struct BenchRow {
    /// "cpu" or "gpu".
    pub backend: String,
    /// Adapter or processor.
    pub adapter: String,
    /// Cells per side.
    pub cells: usize,
    /// Elements.
    pub elements: usize,
    /// Steps timed (of the full step; the same number of each other variant).
    pub steps: u64,
    /// Wall seconds of the timed steps.
    pub wall_seconds: f64,
    /// Elements x steps / wall seconds.
    pub element_cycles_per_second: f64,
    /// Steps per second.
    pub steps_per_second: f64,
    /// GPU: share of the step per stage (each stage timed alone over the same steps).
    pub stage_shares: Vec<(String, f64)>,
    /// Rounds: each variant timed `steps / rounds` steps per round, in alternation.
    pub rounds: u32,
    /// Wall seconds of the bare loop (element forces and node update only) over `steps` steps.
    pub bare_seconds: f64,
    /// Median over the rounds of (full step time) / (bare loop time), same steps, same run.
    pub full_over_bare: f64,
    /// Elements of the contact comparison (the block and its base).
    pub contact_elements: usize,
    /// Median over the rounds of the extra wall seconds per step of the block on its base with a
    /// `[[contact]]` over the same two bodies without it.
    pub contact_seconds_per_step: f64,
    /// Median over the rounds of that extra time as a share of the step with contact.
    pub contact_share: f64,
    /// Broad-phase searches of the contact run.
    pub contact_searches: u64,
}

/// A row of the block bench with its throughput from `steps` steps in `wall` seconds; the
/// columns of the rounds and of the contact pair are left to fill (NaN or 0).
pub(super) fn row(
    backend: &str,
    adapter: String,
    cells: usize,
    elements: usize,
    steps: u64,
    wall: f64,
    stage_shares: Vec<(String, f64)>,
) -> BenchRow {
    BenchRow {
        backend: backend.to_string(),
        adapter,
        cells,
        elements,
        steps,
        wall_seconds: wall,
        element_cycles_per_second: elements as f64 * steps as f64 / wall,
        steps_per_second: steps as f64 / wall,
        stage_shares,
        rounds: 1,
        bare_seconds: f64::NAN,
        full_over_bare: f64::NAN,
        contact_elements: 0,
        contact_seconds_per_step: f64::NAN,
        contact_share: f64::NAN,
        contact_searches: 0,
    }
}

/// The adapter column of the CPU reference's rows.
pub(super) fn solver_adapter() -> String {
    "CPU reference (f64, 1 thread)".to_string()
}

/// Formats rows as a table.
pub fn table(rows: &[BenchRow]) -> String {
    let mut s = format!(
        "{:<7} {:>9} {:>7} {:>10} {:>12} {:>12} {:>9} {:>12} {:>8}  {}\n",
        "backend",
        "elements",
        "steps",
        "wall [s]",
        "elem-cyc/s",
        "steps/s",
        "full/bare",
        "contact [us]",
        "contact",
        "stage shares"
    );
    for r in rows {
        let shares: Vec<String> = r
            .stage_shares
            .iter()
            .map(|(n, x)| format!("{n} {:.0}%", 100.0 * x))
            .collect();
        s.push_str(&format!(
            "{:<7} {:>9} {:>7} {:>10.3} {:>12.3e} {:>12.1} {:>9.3} {:>12.2} {:>7.1}%  {}\n",
            r.backend,
            r.elements,
            r.steps,
            r.wall_seconds,
            r.element_cycles_per_second,
            r.steps_per_second,
            r.full_over_bare,
            1e6 * r.contact_seconds_per_step,
            100.0 * r.contact_share,
            shares.join(", ")
        ));
    }
    s
}

/// The ratios of each row in words: the full step over the bare loop, and what the contact pair
/// adds per step.
pub fn summary(rows: &[BenchRow]) -> String {
    let mut s = String::new();
    for r in rows {
        s.push_str(&format!(
            "{} {} elements: full step / bare element+update loop = {:.3} (median of {} rounds); \
             a contact pair (block on a base, {} elements, {} searches) adds {:.2} us per step, \
             {:.1} % of the step with contact\n",
            r.backend,
            r.elements,
            r.full_over_bare,
            r.rounds,
            r.contact_elements,
            r.contact_searches,
            1e6 * r.contact_seconds_per_step,
            100.0 * r.contact_share
        ));
    }
    s
}

/// One row of the contact-scene table.
#[derive(Debug, Clone, Serialize)]
pub struct ContactRow {
    /// The scene.
    pub scene: ContactScene,
    /// "cpu" or "gpu".
    pub backend: String,
    /// Adapter or processor.
    pub adapter: String,
    /// Size parameter of the scene (see [`ContactScene`]).
    pub size: usize,
    /// Elements.
    pub elements: usize,
    /// Bodies.
    pub bodies: usize,
    /// Steps timed of each variant (with and without contact).
    pub steps: u64,
    /// Rounds the steps were split into, the two variants timed in alternation.
    pub rounds: u32,
    /// Steps each variant ran before the timed ones.
    pub warmup: u64,
    /// Plain projected Gauss-Seidel sweeps (not extrapolated).
    pub plain_sweeps: bool,
    /// Whether the solve swept 2 x 2 blocks of node pairs: the GPU's one-workgroup solve
    /// ([`crate::gpu::contact::ContactOptions::pair_blocks`]; GPUs by default, not CPU
    /// adapters); the CPU reference always does.
    pub pair_blocks: bool,
    /// Wall seconds of the timed steps with contact.
    pub wall_seconds: f64,
    /// Steps per second with contact.
    pub steps_per_second: f64,
    /// Wall seconds of the same steps without the scene's `[[contact]]` (walls kept).
    pub free_seconds: f64,
    /// Median over the rounds of (with - without) / with: the contact share of the step.
    pub contact_share: f64,
    /// With `--friction`: the Coulomb coefficient of the third variant (the contacts and walls
    /// with friction), else `None`.
    pub friction: Option<f64>,
    /// With `--friction`: steps per second of the variant with friction.
    pub friction_steps_per_second: Option<f64>,
    /// With `--friction`: median over the rounds of (with friction - with) / steps, in
    /// microseconds: what friction adds to a contact step.
    pub friction_us_per_step: Option<f64>,
    /// Lagrange contact: the solver's sweeps per step with constraints, mean over the run so
    /// far (0 without Lagrange constraints).
    pub sweeps_mean: f64,
    /// With `--friction`: the same for the variant with friction.
    pub friction_sweeps_mean: Option<f64>,
    /// With `--failure`: the principal-strain limit of the variant with failure (every
    /// material erodes at it, and elements about to invert erode), else `None`.
    pub failure: Option<f64>,
    /// With `--failure`: steps per second of the variant with failure.
    pub failure_steps_per_second: Option<f64>,
    /// With `--failure`: median over the rounds of (with failure - with) / steps, in
    /// microseconds: what eroding elements (and the contact surfaces that follow them) add to a
    /// contact step.
    pub failure_us_per_step: Option<f64>,
    /// With `--failure`: elements the variant with failure eroded by the end of its timed steps.
    pub failure_eroded: Option<u64>,
    /// With `--failure`: times the variant's contact surfaces followed erosion during its timed
    /// steps ([`crate::step::Counters::erosion_follows`]).
    pub failure_follows: Option<u64>,
    /// With `--failure`: the host's mean wall time per follow in those steps, in microseconds
    /// (GPU: the eroded elements' readback, the host's follow and the writes; the forced search
    /// runs on the device and is in `failure_us_per_step`, not here; 0 without a follow).
    pub failure_follow_us: Option<f64>,
    /// Broad-phase searches during the timed steps with contact.
    pub searches: u64,
    /// Searches per 100 timed steps.
    pub searches_per_100_steps: f64,
    /// Bytes read back from the device per timed step with contact (0 on the CPU).
    pub bytes_read_back_per_step: f64,
    /// The host's time recording the GPU's batches per timed step with contact, in
    /// microseconds ([`crate::step::Counters::record_seconds`]; 0 on the CPU). Recorded ahead
    /// (the default), it overlaps the device's run of the batch before.
    pub record_us_per_step: f64,
    /// Timed against the CPU reference in the same rounds (`--backend both`): the median over
    /// the rounds of the CPU reference's time for the steps with contact over this backend's,
    /// i.e. this backend's speed as a multiple of the CPU's. `None` on the CPU's own row and
    /// where the CPU reference was not timed alongside.
    pub vs_cpu: Option<f64>,
}

/// Formats contact rows as a table; with a GPU row, the host's time recording its batches per
/// step ([`ContactRow::record_us_per_step`]).
/// With `--friction`, three more columns: the steps per second with friction, what friction
/// adds to a step (microseconds) and its sweeps; with `--failure`, five more: the steps per
/// second with failure, what it adds to a step, the elements eroded, the follows of erosion in
/// the timed steps and the host's mean time per follow (microseconds); with `--plain-sweeps`,
/// a line saying so under it.
pub fn contact_table(rows: &[ContactRow]) -> String {
    let rough = rows.iter().any(|r| r.friction.is_some());
    let failing = rows.iter().any(|r| r.failure.is_some());
    let mut s = format!(
        "{:<8} {:<7} {:>9} {:>6} {:>7} {:>10} {:>8} {:>15} {:>16}",
        "scene",
        "backend",
        "elements",
        "bodies",
        "steps",
        "steps/s",
        "contact",
        "searches/100 st",
        "read back [B/st]"
    );
    s.push_str(&format!(" {:>6}", "sweeps"));
    let gpu = rows.iter().any(|r| r.backend == "gpu");
    if gpu {
        s.push_str(&format!(" {:>14}", "record [us/st]"));
    }
    let versus = rows.iter().any(|r| r.vs_cpu.is_some());
    if versus {
        s.push_str(&format!(" {:>7}", "vs CPU"));
    }
    if rough {
        s.push_str(&format!(
            " {:>16} {:>18} {:>15}",
            "friction steps/s", "friction [us/st]", "friction sweeps"
        ));
    }
    if failing {
        s.push_str(&format!(
            " {:>15} {:>17} {:>7} {:>7} {:>11}",
            "failure steps/s", "failure [us/st]", "eroded", "follows", "follow [us]"
        ));
    }
    s.push('\n');
    for r in rows {
        s.push_str(&format!(
            "{:<8} {:<7} {:>9} {:>6} {:>7} {:>10.1} {:>7.1}% {:>15.1} {:>16.0}",
            r.scene.name(),
            r.backend,
            r.elements,
            r.bodies,
            r.steps,
            r.steps_per_second,
            100.0 * r.contact_share,
            r.searches_per_100_steps,
            r.bytes_read_back_per_step
        ));
        s.push_str(&format!(" {:>6.1}", r.sweeps_mean));
        if gpu {
            s.push_str(&format!(" {:>14.2}", r.record_us_per_step));
        }
        if versus {
            match r.vs_cpu {
                Some(v) => s.push_str(&format!(" {v:>7.2}")),
                None => s.push_str(&format!(" {:>7}", "-")),
            }
        }
        if rough {
            match (
                r.friction_steps_per_second,
                r.friction_us_per_step,
                r.friction_sweeps_mean,
            ) {
                (Some(f), Some(us), Some(sw)) => {
                    s.push_str(&format!(" {f:>16.1} {us:>18.2} {sw:>15.1}"))
                }
                _ => s.push_str(&format!(" {:>16} {:>18} {:>15}", "-", "-", "-")),
            }
        }
        if failing {
            match (
                r.failure_steps_per_second,
                r.failure_us_per_step,
                r.failure_eroded,
            ) {
                (Some(f), Some(us), Some(n)) => {
                    s.push_str(&format!(" {f:>15.1} {us:>17.2} {n:>7}"))
                }
                _ => s.push_str(&format!(" {:>15} {:>17} {:>7}", "-", "-", "-")),
            }
            match (r.failure_follows, r.failure_follow_us) {
                (Some(n), Some(us)) => s.push_str(&format!(" {n:>7} {us:>11.1}")),
                _ => s.push_str(&format!(" {:>7} {:>11}", "-", "-")),
            }
        }
        s.push('\n');
    }
    if rows.iter().any(|r| r.plain_sweeps) {
        s.push_str("(plain projected Gauss-Seidel sweeps, not extrapolated)\n");
    }
    if rows.iter().any(|r| r.backend == "gpu" && r.pair_blocks) {
        s.push_str("(the GPU's solve with 2 x 2 blocks of node pairs)\n");
    }
    if versus {
        s.push_str(
            "(vs CPU: the steps with contact, CPU reference time over this backend's, median over \
             rounds timed in alternation with the CPU's)\n",
        );
    }
    s
}
