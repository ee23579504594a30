//! `ricochet bench`: the block table and the contact scenes' table. The timing is the library's
//! ([`ricochet::bench`]); here are the options read into scenes, sizes and backends, sizes beyond
//! the machine's memory refused before anything runs, the order of the runs (both backends of a
//! contact scene in the same rounds where the GPU can run it), and the tables printed and
//! written as JSON. The choice of runs and the memory refusal would serve another front end as
//! well from [`ricochet::bench`]. With `--probe` or `--profile` (the device check,
//! `benches/device.sh`), the GPU's probe or per-stage profile instead of the tables.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::Context;
use clap::Args;

use ricochet::bench::{
    BenchRow, ContactRow, ContactScene, ContactTiming, PileContact, ProfileReport, ProfileScene,
};
use ricochet::gpu::GpuContext;
use ricochet::scene::Scene;

use super::args::{
    BenchArgs, BenchBackend, BenchColouring, BenchContactStage, BenchPairBlocks, BenchScene,
    BenchSearch, BenchSweepMemory,
};

/// The options of `ricochet bench` for the device check (`benches/device.sh`).
#[derive(Args)]
pub struct DeviceArgs {
    /// Instead of the tables, probe the GPU: the bandwidth of a vec4<f32> copy between two
    /// buffers and the dispatch floor (dispatches that do nothing, in one pass), each timed
    /// --rounds times (medians), and the bound that bandwidth puts on the block's throughput.
    #[arg(long, conflicts_with = "profile")]
    pub probe: bool,
    /// MiB of each buffer of the probe's copy (at most the adapter's largest storage binding).
    #[arg(long, default_value_t = 512, value_name = "MIB")]
    pub probe_mib: u64,
    /// Dispatches in the probe's one pass.
    #[arg(long, default_value_t = ricochet::gpu::probe::DEFAULT_DISPATCHES)]
    pub probe_dispatches: u32,
    /// Instead of the tables, profile the GPU: each scene (the block of each --cells, the
    /// contact scenes of each --elements, with their contact) runs --warmup steps, then --steps
    /// steps with each part of a step between timestamp queries: device us per step by part.
    #[arg(long)]
    pub profile: bool,
}

/// `ricochet bench`.
pub fn bench(args: BenchArgs) -> anyhow::Result<ExitCode> {
    let BenchArgs {
        backend,
        scene,
        cells,
        elements,
        pile_pairs,
        friction,
        failure,
        steps,
        rounds,
        warmup,
        plain_sweeps,
        pair_blocks,
        colouring,
        sweep_memory,
        no_record_ahead,
        search,
        contact_group,
        contact_stage,
        json,
        adapter,
        device,
    } = args;
    let one = contact_stage.map(|s| s == BenchContactStage::One);
    let parallel_colouring = colouring.map(|c| c == BenchColouring::Parallel);
    let local_sweeps = sweep_memory.map(|m| m == BenchSweepMemory::Workgroup);
    let pair_blocks = pair_blocks.map(|p| p == BenchPairBlocks::On);
    let search_one = search.map(|s| s == BenchSearch::One);
    if rounds == 0 || steps == 0 {
        anyhow::bail!("--steps and --rounds must be positive");
    }
    if (device.probe || device.profile) && backend == BenchBackend::Cpu {
        anyhow::bail!("--probe and --profile time a GPU: not with --backend cpu");
    }
    if device.probe {
        let ctx = GpuContext::new(adapter.as_deref())?;
        return probe(&ctx, &device, rounds, json.as_deref());
    }
    let all = scene.contains(&BenchScene::All);
    let block = all || scene.contains(&BenchScene::Block);
    let contact_scenes: Vec<ContactScene> = ContactScene::ALL
        .into_iter()
        .filter(|c| {
            all || scene.contains(&match c {
                ContactScene::Pair => BenchScene::Pair,
                ContactScene::Striker => BenchScene::Striker,
                ContactScene::Pile => BenchScene::Pile,
            })
        })
        .collect();
    if let Some(mu) = friction.filter(|mu| !(mu.is_finite() && *mu > 0.0)) {
        anyhow::bail!("--friction {mu}: must be a finite positive Coulomb coefficient");
    }
    if let Some(e) = failure.filter(|e| !(e.is_finite() && *e > 0.0)) {
        anyhow::bail!("--failure {e}: must be a finite positive principal strain");
    }
    if block && cells.contains(&0) {
        anyhow::bail!("--cells must be positive");
    }
    if !contact_scenes.is_empty() && elements.contains(&0) {
        anyhow::bail!("--elements must be positive");
    }
    if block {
        for &n in &cells {
            refuse_beyond_memory("--cells", n, ricochet::bench::contact_scene(n, true))?;
        }
    }
    for &which in &contact_scenes {
        for &target in &elements {
            let scene = which.scene(which.size_for(target), true, PileContact::All);
            refuse_beyond_memory("--elements", target, scene)?;
        }
    }
    if device.profile {
        let ctx = Arc::new(GpuContext::new(adapter.as_deref())?);
        let scenes: Vec<(ProfileScene, Vec<usize>)> = block
            .then(|| (ProfileScene::Block, cells.clone()))
            .into_iter()
            .chain(
                contact_scenes
                    .iter()
                    .map(|&c| (ProfileScene::Contact(c), elements.clone())),
            )
            .collect();
        return profile(
            &ctx,
            &scenes,
            (warmup, steps),
            ricochet::bench::contact_options(&ContactTiming {
                pair_blocks,
                parallel_colouring,
                local_sweeps,
                search_one,
                group: contact_group,
                one,
                ..ContactTiming::new(steps, rounds)
            }),
            json.as_deref(),
        );
    }
    let ctx = match backend {
        BenchBackend::Cpu => None,
        BenchBackend::Auto => GpuContext::new(adapter.as_deref()).ok().map(Arc::new),
        BenchBackend::Gpu | BenchBackend::Both => {
            Some(Arc::new(GpuContext::new(adapter.as_deref())?))
        }
    };
    let run_cpu = matches!(
        backend,
        BenchBackend::Cpu | BenchBackend::Both | BenchBackend::Auto
    );
    let rows = if block {
        block_rows(&cells, steps, rounds, run_cpu, ctx.as_ref())?
    } else {
        Vec::new()
    };
    let timing = ContactTiming {
        steps,
        rounds,
        warmup,
        pile: if pile_pairs {
            PileContact::Pairs
        } else {
            PileContact::All
        },
        friction,
        failure,
        plain_sweeps,
        pair_blocks,
        parallel_colouring,
        local_sweeps,
        search_one,
        group: contact_group,
        one,
        record_ahead: no_record_ahead.then_some(false),
    };
    let contact_rows = contact_rows(&contact_scenes, &elements, &timing, run_cpu, ctx.as_ref());
    if block {
        println!("{}", ricochet::bench::table(&rows));
        print!("{}", ricochet::bench::summary(&rows));
    }
    if !contact_rows.is_empty() {
        if block {
            println!();
        }
        print!("{}", ricochet::bench::contact_table(&contact_rows));
    }
    if let Some(path) = json {
        let text = if contact_scenes.is_empty() {
            serde_json::to_string_pretty(&rows)?
        } else {
            serde_json::to_string_pretty(
                &serde_json::json!({ "block": rows, "contact": contact_rows }),
            )?
        };
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(ExitCode::SUCCESS)
}

/// A generated scene beyond the machine's memory, refused before anything runs, naming the
/// option (`key` = `value`) that asked for it.
fn refuse_beyond_memory(
    key: &str,
    value: usize,
    scene: ricochet::Result<Scene>,
) -> ricochet::Result<()> {
    match scene.and_then(|s| ricochet::run::check_memory(&s)) {
        Err(ricochet::Error::Invalid {
            key: inner,
            value: v,
            reason,
            ..
        }) => Err(ricochet::Error::Invalid {
            file: PathBuf::from("ricochet bench"),
            key: key.into(),
            value: value.to_string(),
            reason: format!("the generated scene's `{inner}` = {v}: {reason}"),
        }),
        other => other,
    }
}

/// The block's rows: each size on the CPU (when `run_cpu`) and on `ctx`'s GPU, each printed to
/// stderr as it is timed.
fn block_rows(
    cells: &[usize],
    steps: u64,
    rounds: u32,
    run_cpu: bool,
    ctx: Option<&Arc<GpuContext>>,
) -> anyhow::Result<Vec<BenchRow>> {
    let mut rows = Vec::new();
    for &n in cells {
        if run_cpu {
            rows.push(ricochet::bench::cpu(n, steps, rounds)?);
            eprint!("{}", ricochet::bench::table(&rows[rows.len() - 1..]));
        }
        if let Some(ctx) = ctx {
            rows.push(ricochet::bench::gpu(ctx.clone(), n, steps, rounds)?);
            eprint!("{}", ricochet::bench::table(&rows[rows.len() - 1..]));
        }
    }
    Ok(rows)
}

/// The contact scenes' rows, each printed to stderr as it is timed: with both backends, in the
/// same alternating rounds (the GPU row's ratio to the CPU's), and where that fails (a scene
/// the GPU cannot run) apart; a scene a backend cannot run is reported and skipped.
fn contact_rows(
    scenes: &[ContactScene],
    elements: &[usize],
    timing: &ContactTiming,
    run_cpu: bool,
    ctx: Option<&Arc<GpuContext>>,
) -> Vec<ContactRow> {
    let mut contact_rows = Vec::new();
    let mut push = |what: String, row: ricochet::Result<ContactRow>| {
        match row {
            Ok(row) => {
                eprint!(
                    "{}",
                    ricochet::bench::contact_table(std::slice::from_ref(&row))
                );
                contact_rows.push(row);
            }
            // A scene a backend cannot run (the GPU's body limit, `bodies = "all"` where
            // it does not parse) is reported and skipped; the others go on.
            Err(e) => eprintln!("{what}: skipped: {e}"),
        }
    };
    for &which in scenes {
        for &target in elements {
            let size = which.size_for(target);
            let what = |backend: &str| {
                format!(
                    "{} {backend} {} elements",
                    which.name(),
                    which.elements(size)
                )
            };
            if let (true, Some(ctx)) = (run_cpu, ctx) {
                // Both backends in the same alternating rounds (the GPU row's ratio to
                // the CPU's); where that fails (a scene the GPU cannot run), apart.
                match ricochet::bench::both_contact(ctx.clone(), which, size, timing) {
                    Ok(rows) => {
                        for row in rows {
                            let backend = row.backend.clone();
                            push(what(&backend), Ok(row));
                        }
                        continue;
                    }
                    Err(e) => {
                        eprintln!("{}: the CPU and GPU apart: {e}", what("cpu and gpu"))
                    }
                }
            }
            if run_cpu {
                let row = ricochet::bench::cpu_contact(which, size, timing);
                push(what("cpu"), row);
            }
            if let Some(ctx) = ctx {
                let row = ricochet::bench::gpu_contact(ctx.clone(), which, size, timing);
                push(what("gpu"), row);
            }
        }
    }
    contact_rows
}

/// `ricochet bench --probe`: the report printed, and written to `json` when given; an error
/// when the copy did not copy.
fn probe(
    ctx: &GpuContext,
    device: &DeviceArgs,
    rounds: u32,
    json: Option<&Path>,
) -> anyhow::Result<ExitCode> {
    let bytes = device
        .probe_mib
        .checked_mul(1 << 20)
        .filter(|b| *b > 0)
        .context("--probe-mib must be positive and below 2^44")?;
    let report = ricochet::bench::probe(ctx, bytes, device.probe_dispatches, rounds)?;
    print!("{}", ricochet::bench::probe_summary(&report));
    if let Some(path) = json {
        let text = serde_json::to_string_pretty(&report)?;
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    if !report.bandwidth.verified {
        anyhow::bail!("the probe's copy wrote something else than its source");
    }
    Ok(ExitCode::SUCCESS)
}

/// `ricochet bench --profile`: each scene at each size profiled on `ctx` (`scenes`: the scene
/// and its sizes: the block's cells, the contact scenes' element targets), each row printed to
/// stderr as it is measured, the table printed and the report written to `json` when given. An
/// adapter without timestamp queries gives a notice and no rows; a scene that fails is
/// reported and skipped.
fn profile(
    ctx: &Arc<GpuContext>,
    scenes: &[(ProfileScene, Vec<usize>)],
    (warmup, steps): (u64, u64),
    options: ricochet::gpu::contact::ContactOptions,
    json: Option<&Path>,
) -> anyhow::Result<ExitCode> {
    let mut report = ProfileReport {
        adapter: ctx.adapter_name(),
        timestamps: ctx.timestamps,
        notice: None,
        rows: Vec::new(),
    };
    if ctx.timestamps {
        for (which, sizes) in scenes {
            for &n in sizes {
                let size = match which {
                    ProfileScene::Block => n,
                    ProfileScene::Contact(c) => c.size_for(n),
                };
                match ricochet::bench::profile(ctx.clone(), *which, size, (warmup, steps), options)
                {
                    Ok(Some(row)) => {
                        eprint!(
                            "{}",
                            ricochet::bench::profile_table(std::slice::from_ref(&row))
                        );
                        report.rows.push(row);
                    }
                    Ok(None) => {}
                    Err(e) => eprintln!("{} of size {size}: skipped: {e}", which.name()),
                }
            }
        }
        print!("{}", ricochet::bench::profile_table(&report.rows));
    } else {
        let notice = ricochet::bench::no_timestamps(ctx);
        println!("{notice}");
        report.notice = Some(notice);
    }
    if let Some(path) = json {
        let text = serde_json::to_string_pretty(&report)?;
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(ExitCode::SUCCESS)
}
