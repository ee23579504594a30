//! Checkpoints that do not belong to their folder or are not whole (issue 40, items 4-8): a
//! `checkpoint.bin` that is a stream, a device or a huge sparse file, one copied from another
//! run's folder, one damaged (a flipped bit, a NaN time, a finished solver state, a changed
//! history offset, a NaN wall time), a mesh file changed since the checkpoint, and a folder whose
//! `history.csv` was resaved with CRLF line ends or cut mid-row, or whose `fields/` was deleted.
//! Each restart exits 2 naming the file and what did not match, bounded in time and memory
//! (`run_bin_bounded`), and leaves the folder's outputs as they were.

use std::path::{Path, PathBuf};

use ricochet::checkpoint::{digest, Checkpoint};

use crate::common::*;

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

/// `ricochet run --restart dir` bounded to 120 s and 4 GiB: (exit code, stderr).
fn restart(dir: &Path) -> (Option<i32>, String) {
    let (o, killed) = run_bin_bounded(&["run", "--restart", dir.to_str().unwrap()], 120);
    assert!(!killed, "the restart of {} hung: {o:?}", dir.display());
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Asserts that the restart of `dir` exits 2 with each of `needles` in its message.
fn refused(dir: &Path, needles: &[&str]) -> String {
    let (code, err) = restart(dir);
    assert_eq!(code, Some(2), "{needles:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{n:?} not in: {err}");
    }
    err
}

/// A finished CPU run of `scene` to `end` with checkpoints every `interval`, in `dir`.
fn run_with_checkpoints(scene: &Path, dir: &Path, end: &str, interval: &str) {
    let o = run_cpu(
        scene,
        dir,
        &["--end-time", end, "--checkpoint-interval", interval],
    );
    assert_eq!(o.status.code(), Some(0), "{o:?}");
}

/// A change to a decoded checkpoint.
type Change = Box<dyn Fn(&mut Checkpoint)>;

/// Writes `c` as `dir/checkpoint.bin` (a whole checkpoint: its checksum matches).
fn rewrite(dir: &Path, c: &Checkpoint) {
    c.write(dir).expect("write the checkpoint");
}

#[test]
fn checkpoints_that_are_streams_devices_or_huge_are_refused_before_they_are_read() {
    // Item 4: the 16 GiB cap was checked after reading, so /dev/zero exhausted memory.
    let base = tmp_dir("checkpoint-streams");
    let a = base.join("a");
    run_with_checkpoints(&asset("pile.toml"), &a, "1e-4", "4e-5");
    let file = a.join("checkpoint.bin");
    let fifo = base.join("fifo");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo");
    assert!(made.success());
    for (target, why) in [
        (Path::new("/dev/zero"), "not a regular file"),
        (Path::new("/dev/urandom"), "not a regular file"),
        (fifo.as_path(), "not a regular file"),
    ] {
        let _ = std::fs::remove_file(&file);
        std::os::unix::fs::symlink(target, &file).unwrap();
        refused(&a, &["checkpoint.bin", why]);
    }
    // Sparse files: one over the cap, one of 5 GiB under it (refused after its header).
    for (len, why) in [
        (17u64 << 30, "more than"),
        (5 << 30, "not a ricochet checkpoint"),
    ] {
        let _ = std::fs::remove_file(&file);
        std::fs::File::create(&file).unwrap().set_len(len).unwrap();
        refused(&a, &["checkpoint.bin", why]);
    }
    // A header announcing far more than the file holds.
    let _ = std::fs::remove_file(&file);
    let mut bytes = ricochet::checkpoint::MAGIC.to_vec();
    bytes.extend((1u64 << 62).to_le_bytes());
    bytes.extend([0u8; 64]);
    std::fs::write(&file, bytes).unwrap();
    refused(&a, &["checkpoint.bin", "cut short or extended"]);
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_checkpoint_from_another_runs_folder_is_refused_and_the_history_kept() {
    // Item 5: another scene's checkpoint was accepted and its rows spliced into history.csv.
    let base = tmp_dir("checkpoint-foreign");
    let (a, b) = (base.join("a"), base.join("b"));
    run_with_checkpoints(&asset("pile.toml"), &a, "1e-4", "4e-5");
    run_with_checkpoints(&asset("disk_wall.toml"), &b, "6e-5", "2.5e-5");
    std::fs::copy(b.join("checkpoint.bin"), a.join("checkpoint.bin")).unwrap();
    let history = std::fs::read(a.join("history.csv")).unwrap();
    // Refused by the first file that is not the checkpoint's: the snapshots the other run wrote
    // (this run has none of its names), or its history.
    let err = refused(&a, &["checkpoint: "]);
    assert!(
        err.contains("history.csv") && err.contains("another run's")
            || err.contains("fields/disk_00000.vtu") && err.contains("missing"),
        "{err}"
    );
    assert_eq!(std::fs::read(a.join("history.csv")).unwrap(), history);
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_damaged_checkpoint_is_refused_naming_what_did_not_match() {
    // Item 6: a flipped bit completed with other results; t = NaN or a finished solver state
    // stepped until killed; a changed history offset wrote a malformed CSV; a NaN wall time
    // wrote "wall_seconds": null.
    let base = tmp_dir("checkpoint-damaged");
    let a = base.join("a");
    run_with_checkpoints(&asset("pile.toml"), &a, "1e-4", "4e-5");
    let file = a.join("checkpoint.bin");
    let good = std::fs::read(&file).unwrap();
    let c = Checkpoint::read(&a).expect("the run's checkpoint");
    // One bit flipped anywhere: in the header, the body (the solver state is most of it), the
    // checksum.
    for at in [
        3,
        12,
        good.len() / 3,
        good.len() / 2,
        good.len() - 20,
        good.len() - 1,
    ] {
        let mut bytes = good.clone();
        bytes[at] ^= 0x10;
        std::fs::write(&file, &bytes).unwrap();
        refused(&a, &["checkpoint.bin"]);
    }
    let mut bytes = good.clone();
    bytes[good.len() / 2] ^= 0x01;
    std::fs::write(&file, &bytes).unwrap();
    refused(&a, &["checkpoint.bin", "checksum"]);
    // Extended by a byte.
    let mut bytes = good.clone();
    bytes.push(0);
    std::fs::write(&file, &bytes).unwrap();
    refused(&a, &["checkpoint.bin", "extended"]);
    // Whole checkpoints (their checksum recomputed) holding values that cannot be restored.
    let cases: Vec<(&str, Change)> = vec![
        ("t = NaN", Box::new(|c| c.time = f64::NAN)),
        ("t = inf", Box::new(|c| c.time = f64::INFINITY)),
        ("not a finite time", Box::new(|c| c.time = -1.0)),
        ("past the run's end time", Box::new(|c| c.time = 1.0)),
        ("wall time", Box::new(|c| c.loop_seconds = f64::NAN)),
        ("history.csv", Box::new(|c| c.history_bytes -= 3)),
        ("history.csv", Box::new(|c| c.history_bytes += 1)),
        ("history.csv", Box::new(|c| c.history_rows += 1)),
        ("step", Box::new(|c| c.steps += 1)),
        (
            "scene text",
            Box::new(|c| c.scene_text = c.scene_text.replace("20.0", "21.0")),
        ),
        (
            "saved state is damaged",
            Box::new(|c| {
                // The CPU state's last field: the solver has finished.
                *c.solver.last_mut().unwrap() = 1;
                c.solver_digest = digest(&c.solver);
            }),
        ),
    ];
    for (needle, change) in &cases {
        let mut d = c.clone();
        change(&mut d);
        rewrite(&a, &d);
        refused(&a, &["checkpoint: ", needle]);
    }
    // The run's own checkpoint still restarts and completes (nothing above changed the folder).
    std::fs::write(&file, &good).unwrap();
    let (code, err) = restart(&a);
    assert_eq!(code, Some(0), "{err}");
    let s = std::fs::read_to_string(a.join("summary.json")).unwrap();
    assert!(s.contains("\"completed\"") && !s.contains("null"), "{s}");
    let (_, rows) = read_csv(&a.join("history.csv"));
    assert!(rows.iter().all(|r| r.iter().all(|x| x.is_finite())));
    let _ = std::fs::remove_dir_all(&base);
}

/// `text` (an ASCII MSH 4.1 file) with every node's coordinates scaled by `k`.
fn scale_nodes(text: &str, k: f64) -> String {
    let mut out = String::new();
    let mut in_nodes = false;
    for line in text.lines() {
        if line == "$Nodes" {
            in_nodes = true;
        } else if line == "$EndNodes" {
            in_nodes = false;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        if in_nodes && words.len() == 3 && line.contains('.') {
            let xs: Vec<String> = words
                .iter()
                .map(|w| format!("{:e}", w.parse::<f64>().unwrap() * k))
                .collect();
            out.push_str(&xs.join(" "));
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    out
}

#[test]
fn a_mesh_file_changed_since_the_checkpoint_is_refused_naming_it() {
    // Item 7: the disk scaled by 0.98 restarted with exit 0 and "completed", kinetic energy
    // 20.45 J instead of 1.21 J.
    let base = tmp_dir("checkpoint-mesh");
    std::fs::create_dir_all(base.join("gmsh")).unwrap();
    let scene = base.join("disk_wall_gmsh.toml");
    std::fs::copy(asset("disk_wall_gmsh.toml"), &scene).unwrap();
    let mesh = base.join("gmsh/disk.msh");
    std::fs::copy(asset("gmsh/disk.msh"), &mesh).unwrap();
    let a = base.join("a");
    run_with_checkpoints(&scene, &a, "3e-5", "1.2e-5");
    let text = std::fs::read_to_string(&mesh).unwrap();
    std::fs::write(&mesh, scale_nodes(&text, 0.98)).unwrap();
    let history = std::fs::read(a.join("history.csv")).unwrap();
    refused(
        &a,
        &["checkpoint.bin", "disk.msh", "changed since the checkpoint"],
    );
    assert_eq!(std::fs::read(a.join("history.csv")).unwrap(), history);
    // Deleted: named too.
    std::fs::remove_file(&mesh).unwrap();
    refused(&a, &["disk.msh"]);
    // Put back as it was: the restart completes.
    std::fs::write(&mesh, &text).unwrap();
    let (code, err) = restart(&a);
    assert_eq!(code, Some(0), "{err}");
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn a_resaved_or_cut_history_and_deleted_fields_are_refused_naming_them() {
    // Item 8: a history.csv resaved with CRLF was cut mid-row and appended to; with fields/
    // deleted, fields.pvd listed files that did not exist.
    let base = tmp_dir("checkpoint-outputs");
    let a = base.join("a");
    run_with_checkpoints(&asset("disk_wall.toml"), &a, "6e-5", "2.5e-5");
    let c = Checkpoint::read(&a).unwrap();
    assert!(!c.snapshots.is_empty());
    let history = std::fs::read_to_string(a.join("history.csv")).unwrap();
    let b = base.join("b");
    // CRLF line ends.
    copy_folder(&a, &b);
    std::fs::write(b.join("history.csv"), history.replace('\n', "\r\n")).unwrap();
    refused(
        &b,
        &[
            "history.csv",
            "not the history the checkpoint was taken after",
        ],
    );
    assert_eq!(
        std::fs::read_to_string(b.join("history.csv")).unwrap(),
        history.replace('\n', "\r\n"),
        "the refused restart changed history.csv"
    );
    // Cut mid-row before the checkpoint's offset.
    let _ = std::fs::remove_dir_all(&b);
    copy_folder(&a, &b);
    let cut = c.history_bytes as usize - 7;
    std::fs::write(b.join("history.csv"), &history.as_bytes()[..cut]).unwrap();
    refused(&b, &["history.csv"]);
    // A row changed (same length) before the offset.
    let _ = std::fs::remove_dir_all(&b);
    copy_folder(&a, &b);
    let mut bytes = history.clone().into_bytes();
    let at = c.history_bytes as usize / 2;
    bytes[at] = if bytes[at] == b'1' { b'2' } else { b'1' };
    std::fs::write(b.join("history.csv"), &bytes).unwrap();
    refused(&b, &["history.csv"]);
    // fields/ deleted.
    let _ = std::fs::remove_dir_all(&b);
    copy_folder(&a, &b);
    std::fs::remove_dir_all(b.join("fields")).unwrap();
    refused(&b, &["checkpoint.bin", "fields", "missing"]);
    assert!(!b.join("fields").exists());
    let _ = std::fs::remove_dir_all(&base);
}

/// Copies the files of `from` (and its sub-folders) into `to`.
fn copy_folder(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let p = e.path();
        if p.is_dir() {
            copy_folder(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).unwrap();
        }
    }
}
