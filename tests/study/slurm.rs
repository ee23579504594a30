//! Studies through `--slurm` on a one-node Slurm cluster that the tests start
//! (`tests/slurm/start.sh`: munged, slurmctld and slurmd with their state under a temporary
//! folder and their ports on 127.0.0.1, stopped by pid when the test process ends). Without
//! `sbatch` on PATH the tests fail when `CI` is set and print a skip notice otherwise.

use std::path::PathBuf;
use std::process::Command;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use crate::common::{bin, repo, results, run, scratch, study_file};

/// The test cluster's `slurm.conf`, started once for the test process; `None` (after a notice)
/// where Slurm is not installed and `CI` is not set.
fn cluster() -> Option<&'static PathBuf> {
    static CONF: OnceLock<Option<PathBuf>> = OnceLock::new();
    CONF.get_or_init(|| {
        let installed = ["sbatch", "slurmctld", "slurmd", "munged"].iter().all(|p| {
            Command::new("sh")
                .args(["-c", &format!("command -v {p} || test -x /usr/sbin/{p}")])
                .output()
                .is_ok_and(|o| o.status.success())
        });
        if !installed {
            assert!(
                std::env::var_os("CI").is_none(),
                "CI is set but Slurm is not installed (sbatch, slurmctld, slurmd, munged): \
                 .ci/run installs the Debian packages slurm-wlm and munge"
            );
            eprintln!(
                "SKIPPED: the Slurm tests (sbatch, slurmctld, slurmd or munged not found; \
                 apt-get install slurm-wlm munge to run them)"
            );
            return None;
        }
        let free_port = || {
            std::net::TcpListener::bind("127.0.0.1:0")
                .unwrap()
                .local_addr()
                .unwrap()
                .port()
        };
        let dir = std::env::temp_dir().join(format!("ricochet-slurm-{}", std::process::id()));
        let out = Command::new("bash")
            .arg(repo("tests/slurm/start.sh"))
            .arg(&dir)
            .arg(free_port().to_string())
            .arg(free_port().to_string())
            .arg(std::process::id().to_string())
            .env(
                "PATH",
                format!(
                    "{}:/usr/sbin:/sbin",
                    std::env::var("PATH").unwrap_or_default()
                ),
            )
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "the test cluster did not start:\n{}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        Some(dir.join("slurm.conf"))
    })
    .as_ref()
}

/// The binary with the test cluster's configuration.
fn on(conf: &PathBuf) -> Command {
    let mut c = bin();
    c.env("SLURM_CONF", conf);
    c
}

/// The 12-case grid of `assets/studies/rods_grid.toml` through `--slurm` (two tasks at a time,
/// `--wait` until the collect job has run) gives the same `results.csv`, byte for byte, as the
/// study run here.
#[test]
fn the_grid_through_slurm_gives_the_local_table() {
    let Some(conf) = cluster() else { return };
    let dir = scratch("slurm-grid");
    let study = repo("assets/studies/rods_grid.toml");
    let started = Instant::now();
    let o = run(
        on(conf)
            .arg("study")
            .arg(&study)
            .arg("--out")
            .arg(dir.join("slurm"))
            .args([
                "--backend",
                "cpu",
                "--slurm",
                "--max-parallel",
                "2",
                "--time",
                "10",
                "--wait",
            ]),
        0,
    );
    let took = started.elapsed();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("submitted: job array"), "{stdout}");
    assert!(stdout.contains("12 completed"), "{stdout}");
    let script = std::fs::read_to_string(dir.join("slurm/slurm/array.sh")).unwrap();
    for line in [
        "#SBATCH --array=0-11%2",
        "#SBATCH --requeue",
        "#SBATCH --time=10",
    ] {
        assert!(script.contains(line), "{script}");
    }
    // The collect job wrote the table.
    assert!(
        std::fs::read_to_string(dir.join("slurm/slurm/logs/collect.out"))
            .unwrap()
            .contains("12 completed")
    );
    run(
        bin()
            .arg("study")
            .arg(&study)
            .arg("--out")
            .arg(dir.join("local"))
            .args(["--backend", "cpu"]),
        0,
    );
    assert_eq!(results(&dir.join("slurm")), results(&dir.join("local")));
    eprintln!("the 12-case grid through Slurm took {took:.1?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 6-case study through `--slurm` whose second task is sent SIGTERM mid-run (as
/// `--signal=B:TERM@S` does before a time limit): its run checkpoints, the task requeues itself,
/// and the requeued task continues from the checkpoint; the table equals the local run's.
#[test]
fn a_stopped_task_is_requeued_and_restarts_from_its_checkpoint() {
    let Some(conf) = cluster() else { return };
    let dir = scratch("slurm-requeue");
    let body = r#"
[[parameter]]
name = "v0"
key = "body[striker].initial_velocity[0]"
values = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]

[[parameter]]
key = "run.end_time"
values = [0.2]

[[collect]]
name = "target_v"
history = "target.vx"

[[collect]]
name = "steps"
summary = "steps"
"#;
    let study = study_file(&dir, "requeue", body);
    let out = dir.join("slurm");
    let o = run(
        on(conf)
            .arg("study")
            .arg(&study)
            .arg("--out")
            .arg(&out)
            .args(["--slurm", "--max-parallel", "2"]),
        0,
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    let array = stdout
        .split("job array ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap()
        .to_string();
    let collect = stdout
        .split("collect job ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .unwrap()
        .to_string();
    // Wait until case 0001's run is under way, then signal its task's shell.
    let history = out.join("cases/0001/out/history.csv");
    let started = Instant::now();
    while !history.exists() {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "case 0001 never started"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(200));
    let job = Command::new("squeue")
        .env("SLURM_CONF", conf)
        .args(["-h", "-o", "%A", "-j", &format!("{array}_1")])
        .output()
        .unwrap();
    let job = String::from_utf8_lossy(&job.stdout).trim().to_string();
    assert!(!job.is_empty(), "task {array}_1 is not in the queue");
    // scancel retries while the job is being requeued: not waited for.
    let mut scancel = Command::new("scancel")
        .env("SLURM_CONF", conf)
        .args(["--signal=TERM", "--batch", &job])
        .spawn()
        .unwrap();
    // The collect job ends after every task (the requeued one included).
    let started = Instant::now();
    loop {
        let q = Command::new("squeue")
            .env("SLURM_CONF", conf)
            .args(["-h", "-j", &collect])
            .output()
            .unwrap();
        if String::from_utf8_lossy(&q.stdout).trim().is_empty() {
            break;
        }
        assert!(
            started.elapsed() < Duration::from_secs(180),
            "the collect job never ran"
        );
        std::thread::sleep(Duration::from_millis(250));
    }
    let _ = scancel.kill();
    let _ = scancel.wait();
    let log = std::fs::read_to_string(out.join("cases/0001/run.log")).unwrap();
    assert!(log.contains("interrupted by SIGTERM"), "{log}");
    assert!(log.contains("from its checkpoint"), "{log}");
    let task_log = std::fs::read_to_string(out.join("slurm/logs/1.out")).unwrap();
    assert!(task_log.contains("requeueing its task"), "{task_log}");
    assert!(task_log.contains("restart count 1"), "{task_log}");
    let rows = results(&out);
    assert_eq!(rows.len(), 7);
    assert!(
        rows[1..].iter().all(|r| r.contains(",completed,")),
        "{rows:#?}"
    );
    // Every other case ran once.
    for id in ["0000", "0002", "0003", "0004", "0005"] {
        let log = std::fs::read_to_string(out.join(format!("cases/{id}/run.log"))).unwrap();
        assert_eq!(log.matches("$ ricochet").count(), 1, "case {id}: {log}");
    }
    let local = dir.join("local");
    run(bin().arg("study").arg(&study).arg("--out").arg(&local), 0);
    assert_eq!(rows, results(&local));
    let _ = std::fs::remove_dir_all(&dir);
}
