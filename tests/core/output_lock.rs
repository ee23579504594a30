//! The lock of an output folder in use (issue 40, item 10): two runs into the same `--out` at
//! once wrote 1 734 malformed rows of 1 825 and both exited 0. A run (or restart) into a folder
//! whose `ricochet.lock` another process holds exits 2 naming the folder and that process; a
//! lock file left by a process that ended (a crash) does not block; `ricochet plot` reads a
//! finished folder without the lock.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use ricochet::output::lock::{OutputLock, FILE};

use crate::common::*;

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

#[test]
fn a_second_run_into_a_folder_in_use_exits_2_naming_the_folder_and_the_process() {
    let base = tmp_dir("output-lock");
    let out = base.join("out");
    std::fs::create_dir_all(&out).unwrap();
    // Held by this process, as a run would hold it.
    let lock = OutputLock::acquire(&out).expect("the lock of a free folder");
    assert_eq!(
        std::fs::read_to_string(out.join(FILE)).unwrap().trim(),
        std::process::id().to_string()
    );
    let o = run_cpu(&asset("pile.toml"), &out, &["--end-time", "2e-5"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&out.display().to_string())
            && err.contains(&format!("process {}", std::process::id()))
            && err.contains("in use"),
        "{err}"
    );
    assert!(!out.join("history.csv").exists(), "the refused run wrote");
    drop(lock);
    assert!(
        !out.join(FILE).exists(),
        "the lock file stays after the run"
    );
    // Free again: the run writes, and leaves no lock behind.
    let o = run_cpu(
        &asset("disk_wall.toml"),
        &out,
        &["--end-time", "6e-5", "--checkpoint-interval", "2.5e-5"],
    );
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    assert!(!out.join(FILE).exists());
    // A restart into a folder in use is refused the same way, before anything is changed.
    let history = std::fs::read(out.join("history.csv")).unwrap();
    let lock = OutputLock::acquire(&out).unwrap();
    let o = run_bin(&["run", "--restart", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("in use"), "{err}");
    assert_eq!(std::fs::read(out.join("history.csv")).unwrap(), history);
    // `plot` reads a finished folder while it is locked.
    let o = run_bin(&["plot", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    drop(lock);
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn two_runs_at_once_into_one_folder_leave_one_whole_history() {
    // A run held in the folder by a long run; the second of two started together is refused.
    let base = tmp_dir("output-lock-two");
    let out = base.join("out");
    let out_s = out.to_string_lossy().into_owned();
    let scene = asset("pile.toml");
    let first = Command::new(bin())
        .args([
            "run",
            scene.to_str().unwrap(),
            "--backend",
            "cpu",
            "--out",
            &out_s,
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start the first run");
    let t0 = Instant::now();
    while !out.join(FILE).exists() && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(10));
    }
    let second = run_cpu(&asset("disk_wall.toml"), &out, &[]);
    let first = first.wait_with_output().unwrap();
    assert_eq!(first.status.code(), Some(0), "{first:?}");
    let err = String::from_utf8_lossy(&second.stderr);
    // The first run may have ended before the second started: then the second ran alone.
    if second.status.code() == Some(2) {
        assert!(
            err.contains("in use") && err.contains(&out_s),
            "the second run: {err}"
        );
        let (header, rows) = read_csv(&out.join("history.csv"));
        assert!(!rows.is_empty());
        assert!(rows.iter().all(|r| r.len() == header.len()));
    } else {
        assert_eq!(second.status.code(), Some(0), "{err}");
        println!("the first run ended before the second started: not compared");
    }
    assert!(!out.join(FILE).exists());
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_lock_file_left_by_a_process_that_ended_does_not_block() {
    let base = tmp_dir("output-lock-stale");
    let out = base.join("out");
    std::fs::create_dir_all(&out).unwrap();
    // As a run killed with SIGKILL leaves it: the file with its pid, no lock held.
    std::fs::write(out.join(FILE), "4194000\n").unwrap();
    let o = run_cpu(&asset("pile.toml"), &out, &["--end-time", "2e-5"]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    assert!(!out.join(FILE).exists());
    // And a run killed mid-way: the next run takes the folder.
    let mut child = Command::new(bin())
        .args([
            "run",
            asset("pile.toml").to_str().unwrap(),
            "--backend",
            "cpu",
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !out.join(FILE).exists() && t0.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let o = run_cpu(&asset("pile.toml"), &out, &["--end-time", "2e-5"]);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let _ = std::fs::remove_dir_all(&base);
}
