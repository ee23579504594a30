//! Fuzz of the files a run reads besides its scene (issue 40): mutated Gmsh mesh files,
//! mutated checkpoints and mutated output folders, made deterministically from one splitmix64
//! generator ([`SEED`], or `RICOCHET_FUZZ_SEED`; the counts [`MESH_MUTANTS`] and
//! [`CHECKPOINT_MUTANTS`], or `RICOCHET_FUZZ_FILE_MUTANTS` for each, for a campaign by hand).
//!
//! **Mesh files.** The shipped meshes (`gmsh/disk.msh` and `gmsh/notched_plate.msh`, ASCII, and
//! `gmsh/notched_plate_binary.msh`), each with the scene that reads it, changed by one or two of:
//! bytes flipped, the file cut at a byte, a section (`$Nodes`, `$Elements`, `$Entities`,
//! `$PhysicalNames`, `$MeshFormat`) cut out or duplicated, a number of a section's or a block's
//! header changed (0, -1, 2^32 - 1, 2^64 - 1, n +- 1, 10^9), node tags swapped, repeated, 0 or
//! past the range, the format's binary flag or data size changed. Each goes through the
//! scene-fuzz's load path and a short CPU run ([`super::fuzz::run_case`]: no panic, a refusal
//! naming the scene or mesh file, a completed run with finite numbers), and every
//! [`BINARY_EVERY`]-th through `ricochet check` bounded in time and memory (exit 0 or 2, 2 when
//! refused in process, the file named).
//!
//! **Checkpoints and output folders.** Finished CPU runs with checkpoints (the pile, and the
//! disk of `disk_wall_gmsh.toml` with its mesh and fields), copied per case and changed by one
//! of: bytes of `checkpoint.bin` flipped, the file cut or extended, a field of the decoded
//! checkpoint changed and written back whole (time, steps, history offset and rows, wall time,
//! interval, backend, scene text, mesh digests, snapshot names, the solver state), the
//! checkpoint of another run's folder, the mesh or the scene file changed after the run,
//! `history.csv` resaved with CRLF, cut at a byte or replaced by `/dev/zero`, `fields/` deleted,
//! the folder made read-only. The restart runs in process (`run::execute`). A change that must
//! be refused (every byte change, every value that cannot be restored, a foreign checkpoint, a
//! changed mesh, CRLF, a history cut before the checkpoint's offset, deleted fields) must exit
//! as bad input naming a file of the folder or the mesh; a change that must not matter (the
//! scene file edited after the run: the checkpoint keeps its text; a history cut after the
//! offset) must give the same `history.csv` as the untouched folder's restart; any other must be
//! refused as bad input or end with a whole history (every row of the header's width, as many
//! as `summary.json` says), finite numbers in `summary.json` and snapshot files that exist.
//! Every [`BINARY_EVERY`]-th case also runs `ricochet run --restart` on a copy: exit 2 exactly
//! when refused in process.
//!
//! A watchdog aborts the process when one case takes longer than the scene fuzz's limit.
//! Budget: about 11 s in release mode on the 2-core machine (2026-11-27).

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

use ricochet::checkpoint::{digest, Checkpoint};
use ricochet::run::{execute, Ending, Interrupt, RunRequest};

use super::fuzz::{
    install_hook, json_nulls, mutate_bytes, run_case, Outcome, Rng, Watchdog, LAST_PANIC,
};
use crate::common::*;

/// Seed of the generator.
const SEED: u64 = 0x0040_F11E_5EED_2026;
/// Mesh-file mutants checked in CI.
const MESH_MUTANTS: usize = 45;
/// Checkpoint and output-folder mutants checked in CI.
const CHECKPOINT_MUTANTS: usize = 36;
/// Every this many cases, also the binary.
const BINARY_EVERY: usize = 9;

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

/// The message of a caught panic.
fn panic_message(payload: Box<dyn std::any::Any + Send>) -> String {
    let msg = payload
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_default();
    LAST_PANIC.with(|p| p.borrow_mut().take()).unwrap_or(msg)
}

// ---------------------------------------------------------------------------------------------
// Mesh files.
// ---------------------------------------------------------------------------------------------

/// The byte range of section `$name` (from its first line to the end of `$Endname`).
fn section(bytes: &[u8], name: &str) -> Option<(usize, usize)> {
    let find = |pat: &[u8], from: usize| {
        bytes[from..]
            .windows(pat.len())
            .position(|w| w == pat)
            .map(|i| i + from)
    };
    let start = find(format!("${name}\n").as_bytes(), 0)?;
    let end_tag = format!("$End{name}\n");
    let end = find(end_tag.as_bytes(), start)? + end_tag.len();
    Some((start, end))
}

const SECTIONS: [&str; 5] = [
    "MeshFormat",
    "PhysicalNames",
    "Entities",
    "Nodes",
    "Elements",
];

/// Lines of `bytes` as byte ranges (without their `\n`).
fn lines(bytes: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = 0;
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'\n' {
            out.push((start, i));
            start = i + 1;
        }
    }
    if start < bytes.len() {
        out.push((start, bytes.len()));
    }
    out
}

/// Replaces the line `(a, b)` of `bytes` with `new`.
fn set_line(bytes: &mut Vec<u8>, (a, b): (usize, usize), new: &str) {
    bytes.splice(a..b, new.bytes());
}

/// Node-tag lines of an ASCII file's `$Nodes` (single integers after a block header).
fn tag_lines(bytes: &[u8]) -> Vec<(usize, usize)> {
    let Some((s, e)) = section(bytes, "Nodes") else {
        return Vec::new();
    };
    lines(&bytes[s..e])
        .into_iter()
        .skip(2)
        .map(|(a, b)| (a + s, b + s))
        .filter(|&(a, b)| {
            let t = &bytes[a..b];
            !t.is_empty() && t.iter().all(u8::is_ascii_digit)
        })
        .collect()
}

/// One change to a mesh file: a sentence saying what it was.
fn mutate_mesh(rng: &mut Rng, bytes: &mut Vec<u8>, binary: bool) -> String {
    let op = rng.below(if binary { 7 } else { 9 });
    match op {
        0 => {
            let n = 1 + rng.below(4);
            let mut at = Vec::new();
            for _ in 0..n {
                let i = rng.below(bytes.len());
                bytes[i] ^= 1 << rng.below(8);
                at.push(i);
            }
            format!("bits flipped at {at:?}")
        }
        1 => mutate_bytes(rng, bytes),
        2 | 3 => {
            let name = SECTIONS[rng.below(SECTIONS.len())];
            let Some((s, e)) = section(bytes, name) else {
                return format!("no ${name} to change");
            };
            if op == 2 {
                bytes.drain(s..e);
                format!("${name} cut out")
            } else {
                let copy = bytes[s..e].to_vec();
                let at = if rng.chance(0.5) { e } else { bytes.len() };
                bytes.splice(at..at, copy);
                format!("${name} duplicated")
            }
        }
        4 => {
            // The format line: binary flag or data size.
            let Some((s, _)) = section(bytes, "MeshFormat") else {
                return "no $MeshFormat".into();
            };
            let ls = lines(&bytes[s..]);
            let (a, b) = (ls[1].0 + s, ls[1].1 + s);
            let new = match rng.below(3) {
                0 => format!("4.1 {} 8", if binary { 0 } else { 1 }),
                1 => format!("4.1 {} {}", u8::from(binary), rng.below(17)),
                _ => [
                    "2.2 0 8",
                    "4.0 0 8",
                    "4.1 0 8 extra",
                    "4.1 -1 8",
                    "4.1 1 99999999999",
                ][rng.below(5)]
                .to_string(),
            };
            set_line(bytes, (a, b), &new);
            format!("format line set to {new:?}")
        }
        5 | 6 => {
            // A number of a section's header (binary: the header is binary too, so bytes
            // near the section's start).
            let name = ["Nodes", "Elements", "Entities", "PhysicalNames"][rng.below(4)];
            let Some((s, e)) = section(bytes, name) else {
                return format!("no ${name}");
            };
            if binary && name != "PhysicalNames" {
                let at = s + name.len() + 2 + rng.below(48.min(e - s - name.len() - 2));
                let v = [0u8, 0xff, 0x7f, 0x80][rng.below(4)];
                bytes[at] = v;
                return format!("${name} header byte {at} set to {v:#04x}");
            }
            // ASCII: the section's first header or a block header (lines of 4 numbers).
            let ls: Vec<(usize, usize)> = lines(&bytes[s..e])
                .into_iter()
                .map(|(a, b)| (a + s, b + s))
                .filter(|&(a, b)| {
                    let w: Vec<&[u8]> = bytes[a..b].split(|&c| c == b' ').collect();
                    (w.len() == 4 || w.len() == 1)
                        && w.iter()
                            .all(|x| !x.is_empty() && x.iter().all(u8::is_ascii_digit))
                })
                .collect();
            let pick = if rng.chance(0.5) || ls.len() < 2 {
                0
            } else {
                rng.below(ls.len().min(40))
            };
            let Some(&(a, b)) = ls.get(pick) else {
                return format!("no header in ${name}");
            };
            let text = String::from_utf8_lossy(&bytes[a..b]).into_owned();
            let mut words: Vec<String> = text.split(' ').map(String::from).collect();
            let k = rng.below(words.len());
            let old: i128 = words[k].parse().unwrap_or(0);
            words[k] = match rng.below(7) {
                0 => "0".into(),
                1 => "-1".into(),
                2 => "4294967295".into(),
                3 => "18446744073709551615".into(),
                4 => (old + 1).to_string(),
                5 => (old - 1).to_string(),
                _ => "1000000000".into(),
            };
            let new = words.join(" ");
            set_line(bytes, (a, b), &new);
            format!("${name} header {text:?} set to {new:?}")
        }
        _ => {
            // Node tags (ASCII): swapped, repeated, 0, past the range.
            let tags = tag_lines(bytes);
            if tags.len() < 2 {
                return "no node tags".into();
            }
            let i = rng.below(tags.len());
            let j = rng.below(tags.len());
            let (ti, tj) = (
                String::from_utf8_lossy(&bytes[tags[i].0..tags[i].1]).into_owned(),
                String::from_utf8_lossy(&bytes[tags[j].0..tags[j].1]).into_owned(),
            );
            match rng.below(4) {
                0 => {
                    // Swapped: written from the later line back so the earlier stays in place.
                    let (first, second) = if i < j { (i, j) } else { (j, i) };
                    let (tf, ts) = if i < j { (&ti, &tj) } else { (&tj, &ti) };
                    set_line(bytes, tags[second], tf);
                    set_line(bytes, tags[first], ts);
                    format!("node tags {ti} and {tj} swapped")
                }
                1 => {
                    set_line(bytes, tags[i], &tj);
                    format!("node tag {ti} set to {tj} (repeated)")
                }
                2 => {
                    set_line(bytes, tags[i], "0");
                    format!("node tag {ti} set to 0")
                }
                _ => {
                    let big = (tags.len() + 1 + rng.below(1000)).to_string();
                    set_line(bytes, tags[i], &big);
                    format!("node tag {ti} set to {big} (past the range)")
                }
            }
        }
    }
}

/// (scene file, mesh file, binary) of the mesh bases.
const MESH_BASES: [(&str, &str, bool); 3] = [
    ("disk_wall_gmsh.toml", "gmsh/disk.msh", false),
    ("notched_plate.toml", "gmsh/notched_plate.msh", false),
    ("notched_plate.toml", "gmsh/notched_plate_binary.msh", true),
];

fn env(k: &str) -> Option<u64> {
    std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok())
}

#[test]
fn mutated_mesh_files_are_refused_naming_them_or_run_cleanly() {
    install_hook();
    let t_start = Instant::now();
    let seed = env("RICOCHET_FUZZ_SEED").unwrap_or(SEED);
    let n = env("RICOCHET_FUZZ_FILE_MUTANTS").map_or(MESH_MUTANTS, |n| n as usize);
    let mut rng = Rng(seed ^ 0x6d65_7368);
    let root = tmp_dir("fuzz-mesh");
    let bases: Vec<(String, Vec<u8>, bool)> = MESH_BASES
        .iter()
        .map(|(scene, mesh, binary)| {
            let text = std::fs::read_to_string(asset(scene)).unwrap();
            let text = text.replace(
                &format!("\"{}\"", &mesh.replace("_binary", "")),
                "\"mesh.msh\"",
            );
            assert!(text.contains("\"mesh.msh\""), "{scene}");
            (text, std::fs::read(asset(mesh)).unwrap(), *binary)
        })
        .collect();
    let watchdog = Watchdog::start();
    let mut violations = Vec::new();
    let mut counts = std::collections::BTreeMap::<Outcome, usize>::new();
    let (mut binary_runs, mut peak) = (0usize, 0u64);
    for case in 0..n {
        let b = case % bases.len();
        let (scene_text, mesh, binary) = &bases[b];
        let mut bytes = mesh.clone();
        let mut ops = vec![mutate_mesh(&mut rng, &mut bytes, *binary)];
        if rng.chance(0.3) {
            ops.push(mutate_mesh(&mut rng, &mut bytes, *binary));
        }
        let what = format!(
            "mesh case {case} (base {}): {}",
            MESH_BASES[b].1,
            ops.join("; ")
        );
        let dir = root.join(format!("{case:04}"));
        std::fs::create_dir_all(&dir).unwrap();
        let (scene, mesh_file) = (dir.join("scene.toml"), dir.join("mesh.msh"));
        std::fs::write(&scene, scene_text).unwrap();
        std::fs::write(&mesh_file, &bytes).unwrap();
        watchdog.watch(Some(what.clone()));
        let result = catch_unwind(AssertUnwindSafe(|| {
            run_case(&scene, Some(&mesh_file), &dir.join("out"))
        }))
        .unwrap_or_else(|p| Err(format!("PANIC: {}", panic_message(p))));
        let outcome = match result {
            Ok(o) => {
                *counts.entry(o).or_default() += 1;
                Some(o)
            }
            Err(why) => {
                violations.push(format!("{what}: {why}"));
                None
            }
        };
        if case % BINARY_EVERY == 0 {
            binary_runs += 1;
            let (o, killed) = run_bin_bounded(&["check", scene.to_str().unwrap()], 60);
            let err = String::from_utf8_lossy(&o.stderr);
            let named = err.contains(&*scene.to_string_lossy())
                || err.contains(&*mesh_file.to_string_lossy());
            match o.status.code() {
                _ if killed => violations.push(format!("{what}: `ricochet check` hung")),
                Some(0) if !outcome.is_some_and(Outcome::refused) => {}
                Some(2) if named && !err.contains("panicked") => {}
                code => violations.push(format!(
                    "{what}: `ricochet check` exited with {code:?} (in process: {outcome:?}): \
                     {err}"
                )),
            }
        }
        watchdog.watch(None);
        let _ = std::fs::remove_dir_all(&dir);
        peak = peak.max(super::fuzz::peak_rss());
    }
    drop(watchdog);
    let _ = std::fs::remove_dir_all(&root);
    use std::io::Write as _;
    let _ = writeln!(
        std::io::stderr(),
        "fuzz (mesh files): seed {seed:#x}: {n} mutants: {counts:?}; `ricochet check` on \
         {binary_runs}; {} rule violations; peak RSS {:.1} MiB; {:.1} s",
        violations.len(),
        peak as f64 / 1048576.0,
        t_start.elapsed().as_secs_f64()
    );
    for v in violations.iter().take(5) {
        eprintln!("fuzz (mesh files): VIOLATION: {v}\n");
    }
    assert!(
        violations.is_empty(),
        "{} mesh cases broke a rule",
        violations.len()
    );
}

// ---------------------------------------------------------------------------------------------
// Checkpoints and output folders.
// ---------------------------------------------------------------------------------------------

/// What a change must give.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Expect {
    /// Refused as bad input, naming a file.
    Refused,
    /// The same `history.csv` as the untouched folder's restart.
    Same,
    /// Refused as bad input, or a whole history.
    Either,
}

/// A finished run folder to mutate: its folder, the mesh file it reads, its restart's history.
struct Base {
    dir: PathBuf,
    mesh: Option<PathBuf>,
    scene: PathBuf,
    history: Vec<u8>,
}

/// Copies the files of `from` (and its sub-folders) into `to`; links are copied as links.
fn copy_folder(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let p = e.path();
        let kind = std::fs::symlink_metadata(&p).unwrap().file_type();
        if kind.is_symlink() {
            let target = std::fs::read_link(&p).unwrap();
            std::os::unix::fs::symlink(target, to.join(e.file_name())).unwrap();
        } else if kind.is_dir() {
            copy_folder(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).unwrap();
        }
    }
}

/// A CPU run of `scene` to `end` with checkpoints every `interval` into `dir`.
fn finished_run(scene: &Path, dir: &Path, end: &str, interval: &str) {
    let o = run_cpu(
        scene,
        dir,
        &["--end-time", end, "--checkpoint-interval", interval],
    );
    assert_eq!(o.status.code(), Some(0), "{o:?}");
}

/// How a restart in process ended.
#[derive(Debug)]
enum Restart {
    /// Refused as bad input (exit 2), the message naming one of the names given.
    Refused,
    /// An output file could not be written (exit 1), the message naming the folder: a
    /// read-only folder for a user other than root.
    Unwritable,
    /// It ran.
    Ran(Ending),
}

/// The restart of `dir` in process; Err for a panic, an error that is not bad input, or a
/// message that does not name one of `names`.
fn restart(dir: &Path, names: &[String]) -> Result<Restart, String> {
    let r = catch_unwind(AssertUnwindSafe(|| {
        execute(
            &RunRequest::restart(dir),
            &Interrupt::new(),
            &mut |_| {},
            &mut |_, _, _| {},
        )
    }))
    .map_err(|p| format!("PANIC: {}", panic_message(p)))?;
    match r {
        Ok(o) => Ok(Restart::Ran(o.ending)),
        Err(
            e @ (ricochet::Error::Checkpoint(_)
            | ricochet::Error::Read { .. }
            | ricochet::Error::Parse { .. }
            | ricochet::Error::Invalid { .. }),
        ) => {
            let msg = e.to_string();
            if names.iter().any(|n| msg.contains(n.as_str())) && msg.len() < 4096 {
                Ok(Restart::Refused)
            } else {
                Err(format!("refused without naming one of {names:?}: {msg}"))
            }
        }
        Err(e @ ricochet::Error::Write { .. })
            if e.to_string().contains(&*dir.to_string_lossy()) =>
        {
            Ok(Restart::Unwritable)
        }
        Err(e) => Err(format!("error that is not bad input: {e}")),
    }
}

/// The checks of a restart that ran: a whole history, finite numbers, snapshots that exist.
fn whole(dir: &Path, ending: &Ending) -> Result<(), String> {
    let text = std::fs::read_to_string(dir.join("summary.json")).map_err(|e| e.to_string())?;
    let summary: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    if matches!(ending, Ending::Completed) {
        let mut bad = Vec::new();
        json_nulls(&summary, "summary", &mut bad);
        if !bad.is_empty() {
            return Err(format!("completed with non-finite numbers at {bad:?}"));
        }
    }
    let history = std::fs::read_to_string(dir.join("history.csv")).map_err(|e| e.to_string())?;
    if !history.ends_with('\n') || history.contains('\r') {
        return Err("history.csv does not end with a whole row, or has CR".into());
    }
    let mut lines = history.lines().skip_while(|l| l.starts_with('#'));
    let width = lines.next().map_or(0, |h| h.split(',').count());
    let mut rows = 0;
    for l in lines {
        rows += 1;
        let ok = l.split(',').count() == width
            && l.split(',')
                .all(|x| x.parse::<f64>().is_ok_and(f64::is_finite));
        if !ok && matches!(ending, Ending::Completed) {
            return Err(format!("history.csv row {rows} is not whole: {l}"));
        }
    }
    if summary["history_rows"].as_u64() != Some(rows) {
        return Err(format!(
            "history.csv has {rows} rows, summary.json says {}",
            summary["history_rows"]
        ));
    }
    if let Ok(pvd) = std::fs::read_to_string(dir.join("fields.pvd")) {
        for part in pvd.split("file=\"").skip(1) {
            let f = part.split('"').next().unwrap_or("");
            if !dir.join(f).is_file() {
                return Err(format!("fields.pvd lists {f}, which does not exist"));
            }
        }
    }
    Ok(())
}

/// One change to the folder `dir` (a copy of `base`): what it was and what it must give.
fn mutate_folder(rng: &mut Rng, dir: &Path, base: &Base, other: &Path) -> (String, Expect) {
    let file = dir.join("checkpoint.bin");
    let mut bytes = std::fs::read(&file).unwrap();
    let c = Checkpoint::read(dir).unwrap();
    let rewrite = |d: &Checkpoint| d.write(dir).unwrap();
    match rng.below(10) {
        0 => {
            let n = 1 + rng.below(3);
            let mut at = Vec::new();
            for _ in 0..n {
                let i = rng.below(bytes.len());
                bytes[i] ^= 1 << rng.below(8);
                at.push(i);
            }
            std::fs::write(&file, &bytes).unwrap();
            (
                format!("checkpoint bits flipped at {at:?}"),
                Expect::Refused,
            )
        }
        1 => {
            let n = rng.below(bytes.len());
            bytes.truncate(n);
            std::fs::write(&file, &bytes).unwrap();
            (format!("checkpoint cut to {n} bytes"), Expect::Refused)
        }
        2 => {
            let n = 1 + rng.below(64);
            for _ in 0..n {
                bytes.push(rng.next() as u8);
            }
            std::fs::write(&file, &bytes).unwrap();
            (format!("checkpoint extended by {n} bytes"), Expect::Refused)
        }
        3 | 4 => {
            let mut d = c.clone();
            let bad = [f64::NAN, f64::INFINITY, -1.0, 1.0, f64::MIN_POSITIVE][rng.below(5)];
            let (what, expect) = match rng.below(14) {
                0 => {
                    d.time = bad;
                    (format!("time = {bad:e}"), Expect::Refused)
                }
                1 => {
                    d.steps = [0, d.steps + 1, d.steps.saturating_sub(1), u64::MAX][rng.below(4)];
                    (format!("steps = {}", d.steps), Expect::Refused)
                }
                2 => {
                    let k = 1 + rng.below(40) as u64;
                    d.history_bytes = if rng.chance(0.5) {
                        d.history_bytes.saturating_sub(k)
                    } else {
                        d.history_bytes + k
                    };
                    (
                        format!("history_bytes = {}", d.history_bytes),
                        Expect::Refused,
                    )
                }
                3 => {
                    d.history_rows =
                        [0, d.history_rows + 1, d.history_rows.saturating_sub(1)][rng.below(3)];
                    (
                        format!("history_rows = {}", d.history_rows),
                        Expect::Refused,
                    )
                }
                4 => {
                    d.loop_seconds = [f64::NAN, f64::INFINITY, -1.0][rng.below(3)];
                    (format!("wall time = {:e}", d.loop_seconds), Expect::Refused)
                }
                5 => {
                    d.interval = [f64::NAN, 0.0, -1.0, f64::INFINITY][rng.below(4)];
                    (format!("interval = {:e}", d.interval), Expect::Refused)
                }
                6 => {
                    d.backend = ["", "cpu2", "GPU"][rng.below(3)].into();
                    (format!("backend = {:?}", d.backend), Expect::Refused)
                }
                7 => {
                    d.scene_text.push_str("\n# changed\n");
                    ("scene text changed".into(), Expect::Refused)
                }
                8 => {
                    d.end_time_override = Some([f64::NAN, 0.0, -1.0][rng.below(3)]);
                    (
                        "--end-time not finite or not positive".into(),
                        Expect::Refused,
                    )
                }
                9 if !d.meshes.is_empty() => {
                    d.meshes[0].digest ^= 1;
                    ("mesh digest changed".into(), Expect::Refused)
                }
                10 if !d.snapshots.is_empty() => {
                    let k = rng.below(d.snapshots.len());
                    d.snapshots[k].2 =
                        ["fields/../../x.vtu", "", "fields/missing.vtu"][rng.below(3)].into();
                    (
                        format!("snapshot {k} renamed {:?}", d.snapshots[k].2),
                        Expect::Refused,
                    )
                }
                11 => {
                    let i = rng.below(d.solver.len());
                    d.solver[i] ^= 1 << rng.below(8);
                    d.solver_digest = digest(&d.solver);
                    (
                        format!("solver state bit {i} flipped, its digest recomputed"),
                        Expect::Either,
                    )
                }
                12 => {
                    d.audit = Default::default();
                    ("energy audit reset".into(), Expect::Either)
                }
                _ => {
                    d.loop_seconds = rng.below(1000) as f64;
                    (format!("wall time = {:e}", d.loop_seconds), Expect::Either)
                }
            };
            rewrite(&d);
            (what, expect)
        }
        5 => {
            std::fs::copy(other.join("checkpoint.bin"), &file).unwrap();
            ("checkpoint of another run's folder".into(), Expect::Refused)
        }
        6 => match &base.mesh {
            Some(m) => {
                let mut mesh = std::fs::read(m).unwrap();
                let i = mesh.len() / 2 + rng.below(mesh.len() / 4);
                mesh[i] = if mesh[i] == b'1' { b'2' } else { b'1' };
                std::fs::write(dir.parent().unwrap().join("mesh.msh"), &mesh).unwrap();
                (
                    "the mesh file changed after the run".into(),
                    Expect::Refused,
                )
            }
            None => {
                let mut scene = std::fs::read_to_string(&base.scene).unwrap();
                scene.push_str("\n# edited after the run\n");
                std::fs::write(dir.parent().unwrap().join("scene.toml"), scene).unwrap();
                ("the scene file changed after the run".into(), Expect::Same)
            }
        },
        7 => {
            let h = dir.join("history.csv");
            let text = std::fs::read_to_string(&h).unwrap();
            match rng.below(3) {
                0 => {
                    std::fs::write(&h, text.replace('\n', "\r\n")).unwrap();
                    ("history.csv resaved with CRLF".into(), Expect::Refused)
                }
                1 => {
                    let n = rng.below(text.len());
                    std::fs::write(&h, &text.as_bytes()[..n]).unwrap();
                    let e = if (n as u64) < c.history_bytes {
                        Expect::Refused
                    } else {
                        Expect::Same
                    };
                    (format!("history.csv cut at byte {n}"), e)
                }
                _ => {
                    std::fs::remove_file(&h).unwrap();
                    std::os::unix::fs::symlink("/dev/zero", &h).unwrap();
                    ("history.csv a link to /dev/zero".into(), Expect::Refused)
                }
            }
        }
        8 if dir.join("fields").is_dir() => {
            std::fs::remove_dir_all(dir.join("fields")).unwrap();
            ("fields/ deleted".into(), Expect::Refused)
        }
        _ => {
            use std::os::unix::fs::PermissionsExt as _;
            std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o555)).unwrap();
            // Root writes anyway; others are refused (an output error names the folder).
            ("the folder made read-only".into(), Expect::Either)
        }
    }
}

#[test]
fn mutated_checkpoints_and_output_folders_are_refused_or_restart_whole() {
    install_hook();
    let t_start = Instant::now();
    let seed = env("RICOCHET_FUZZ_SEED").unwrap_or(SEED);
    let n = env("RICOCHET_FUZZ_FILE_MUTANTS").map_or(CHECKPOINT_MUTANTS, |n| n as usize);
    let mut rng = Rng(seed ^ 0x6368_6b70);
    let root = tmp_dir("fuzz-checkpoint");
    // The bases: each scene (and mesh) copied into the sandbox so that a case may change them.
    let mut bases = Vec::new();
    for (scene, mesh, end, interval) in [
        ("pile.toml", None, "1e-4", "4e-5"),
        (
            "disk_wall_gmsh.toml",
            Some("gmsh/disk.msh"),
            "3e-5",
            "1.2e-5",
        ),
    ] {
        let b = root.join(format!("base-{scene}"));
        std::fs::create_dir_all(&b).unwrap();
        let mut text = std::fs::read_to_string(asset(scene)).unwrap();
        let mesh = mesh.map(|m| {
            text = text.replace(&format!("\"{m}\""), "\"mesh.msh\"");
            std::fs::copy(asset(m), b.join("mesh.msh")).unwrap();
            b.join("mesh.msh")
        });
        let scene_file = b.join("scene.toml");
        std::fs::write(&scene_file, &text).unwrap();
        let dir = b.join("out");
        finished_run(&scene_file, &dir, end, interval);
        let copy = b.join("restarted");
        copy_folder(&dir, &copy);
        match restart(&copy, &[]) {
            Ok(Restart::Ran(Ending::Completed)) => {}
            other => panic!("the untouched {scene} folder restarts: {other:?}"),
        }
        let history = std::fs::read(copy.join("history.csv")).unwrap();
        bases.push(Base {
            dir,
            mesh,
            scene: scene_file,
            history,
        });
    }
    let watchdog = Watchdog::start();
    let mut violations = Vec::new();
    let mut counts = std::collections::BTreeMap::<String, usize>::new();
    let mut binary_runs = 0usize;
    for case in 0..n {
        let k = case % bases.len();
        let base = &bases[k];
        let other = &bases[1 - k].dir;
        // The folder and what it reads, as the base's: out/ beside scene.toml and mesh.msh.
        let case_root = root.join(format!("{case:04}"));
        let dir = case_root.join("out");
        copy_folder(base.dir.parent().unwrap(), &case_root);
        let _ = std::fs::remove_dir_all(case_root.join("restarted"));
        // The checkpoint names the base's scene and mesh files: the case's copies go there
        // after the change (a changed mesh or scene is copied over the base's, and put back).
        let (what, expect) = mutate_folder(&mut rng, &dir, base, other);
        let what = format!(
            "checkpoint case {case} (base {}): {what}",
            base.scene.display()
        );
        let changed_input = ["mesh.msh", "scene.toml"]
            .iter()
            .map(|f| (base.dir.parent().unwrap().join(f), case_root.join(f)))
            .filter(|(a, b)| std::fs::read(a).ok() != std::fs::read(b).ok())
            .collect::<Vec<_>>();
        let saved: Vec<(PathBuf, Vec<u8>)> = changed_input
            .iter()
            .map(|(a, b)| {
                let old = std::fs::read(a).unwrap();
                std::fs::copy(b, a).unwrap();
                (a.clone(), old)
            })
            .collect();
        let copy = (case % BINARY_EVERY == 0).then(|| {
            let c = case_root.join("binary");
            copy_folder(&dir, &c);
            c
        });
        let mut names: Vec<String> = ["checkpoint.bin", "history.csv", "fields", "mesh.msh"]
            .iter()
            .map(|f| f.to_string())
            .collect();
        names.push(dir.display().to_string());
        watchdog.watch(Some(what.clone()));
        let r = restart(&dir, &names);
        let verdict = match (&r, expect) {
            (Err(why), _) => Err(why.clone()),
            (Ok(Restart::Refused), Expect::Refused | Expect::Either) => Ok("refused"),
            (Ok(Restart::Unwritable), Expect::Either) => Ok("unwritable"),
            (Ok(Restart::Unwritable), _) => Err("an output error instead of bad input".into()),
            (Ok(Restart::Ran(e)), Expect::Either) => whole(&dir, e).map(|_| "ran"),
            (Ok(Restart::Ran(e)), Expect::Same) => whole(&dir, e).and_then(|_| {
                if std::fs::read(dir.join("history.csv")).unwrap() == base.history {
                    Ok("ran the same")
                } else {
                    Err("history.csv differs from the untouched folder's restart".into())
                }
            }),
            (Ok(Restart::Ran(e)), Expect::Refused) => Err(format!("accepted (ended {e:?})")),
            (Ok(Restart::Refused), Expect::Same) => {
                Err("refused a change that must not matter".into())
            }
        };
        match verdict {
            Ok(v) => *counts.entry(v.to_string()).or_default() += 1,
            Err(why) => violations.push(format!("{what}: {why}")),
        }
        if let Some(c) = copy {
            binary_runs += 1;
            let (o, killed) = run_bin_bounded(&["run", "--restart", c.to_str().unwrap()], 120);
            let code = o.status.code();
            let want = match &r {
                Ok(Restart::Refused) => Some(2),
                Ok(Restart::Unwritable) => Some(1),
                Ok(Restart::Ran(Ending::Completed)) => Some(0),
                Ok(Restart::Ran(Ending::Failed(_))) => Some(3),
                _ => code,
            };
            if killed || code != want {
                violations.push(format!(
                    "{what}: `ricochet run --restart` exited with {code:?} (killed: {killed}), \
                     in process {r:?}: {}",
                    String::from_utf8_lossy(&o.stderr)
                ));
            }
        }
        watchdog.watch(None);
        for (a, old) in saved {
            std::fs::write(a, old).unwrap();
        }
        use std::os::unix::fs::PermissionsExt as _;
        let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755));
        let _ = std::fs::remove_dir_all(&case_root);
    }
    drop(watchdog);
    let _ = std::fs::remove_dir_all(&root);
    use std::io::Write as _;
    let _ = writeln!(
        std::io::stderr(),
        "fuzz (checkpoints): seed {seed:#x}: {n} mutants: {counts:?}; `ricochet run --restart` \
         on {binary_runs}; {} rule violations; {:.1} s",
        violations.len(),
        t_start.elapsed().as_secs_f64()
    );
    for v in violations.iter().take(5) {
        eprintln!("fuzz (checkpoints): VIOLATION: {v}\n");
    }
    assert!(
        violations.is_empty(),
        "{} checkpoint cases broke a rule",
        violations.len()
    );
}
