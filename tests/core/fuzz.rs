//! Fuzz: [`N_MUTANTS`] mutated scenes, made deterministically from the scenes of `assets/`, go
//! through the whole load path and a short CPU run, in process; a sample also goes through
//! `ricochet check`.
//!
//! **Generator.** The base scenes are every `*.toml` of `assets/`, `assets/stress/`,
//! `assets/verification/` and `assets/bench/`, taken in turn (sorted by path). Each mutant is
//! its base scene parsed into a `toml::Value` tree, changed by 1 to 3 operators, written back with
//! `toml::to_string`; one in ten then also gets a byte-level change. All choices come from one
//! splitmix64 generator seeded with [`SEED`], so every run makes the same mutants (a failure
//! prints the case's number, base, operators and full text). The operators, on a node reached by
//! a random walk from the root (a random key at each table, a random element at each array, so
//! that a long explicit mesh does not swamp the rest):
//!
//! - a number replaced by 0, -1, -0.0, +-1e300, 5e-324, 1e-300, 1e-30, NaN, +-inf, 2^53,
//!   i64::MAX, i64::MIN, x * 1e6, x * 1e-6, -x, or, half of the time (to keep enough scenes
//!   valid), x * 2, x / 2, x * 1.1, x * 0.9, x * 10, x * 100, x + 1;
//! - a string replaced by "", "../../fuzz-escaped", a deeper `..` path, "/tmp/fuzz-escaped-abs",
//!   "a,b", a string of 300 or 100 000 characters, "näme", "\u{0}", another string of the same
//!   scene (names swapped so that references dangle or repeat), or a valid keyword of another key
//!   ("all", "penalty", "neo_hookean", "plane_stress", "stiffness", "ascii", ...);
//! - a type change: number to string or boolean, string to number, boolean to number, array to
//!   table or string, table to number or array;
//! - on an array: a copy of an element appended, an element removed, all removed, a third
//!   coordinate appended;
//! - a key deleted, an unknown key inserted;
//! - an entry of an array of tables (`[[body]]`, `[[contact]]`, `[[rigid_wall]]`, ...) duplicated,
//!   half of the time with `_2` appended to its name;
//! - byte level (10 %): the text cut at a random byte, or a random byte (valid UTF-8 or not)
//!   inserted or replaced.
//!
//! A mutant that `toml::to_string` cannot write is skipped and counted; mutants are made until
//! [`N_MUTANTS`] have been checked.
//!
//! **Each case** runs in its own folder of a sandbox, `<sandbox>/cases/<case>/scene.toml` with the
//! run's outputs in `<sandbox>/cases/<case>/out/`, inside `catch_unwind`, through the binary's load path:
//! `Scene::load`, `run::check_memory`, `run::model`, `run::check_limits`, `Plan::new`, then, for a
//! scene of at most [`MAX_RUN_ELEMENTS`] elements and [`MAX_RUN_BYTES`] of estimated memory (the
//! others are counted as skipped for size), `run::run` on the CPU reference with `run.end_time`
//! cut to its first steps (1000 on small meshes, fewer on large ones: about [`STEP_BUDGET`]
//! element-steps per case, at least 20 steps). It asserts:
//!
//! - no panic anywhere on that path;
//! - a refused scene's error names the scene file and is shorter than [`MAX_MESSAGE`] bytes;
//! - a run ends with status "completed" or "failed" (with a message), never an I/O error; a
//!   "completed" run has only finite numbers in `summary.json` (serde_json writes a non-finite
//!   number as `null`) and in `history.csv`;
//! - nothing is written outside `out/`: after each case the sandbox holds only the case's
//!   `scene.toml` and what is under its `out/`, and no new entry whose name carries the
//!   escape marker appeared in the system temporary folder, `/tmp` or the working folder (names
//!   such as "../../fuzz-escaped" or "/tmp/fuzz-escaped-abs" must not leave `out/`; the marker
//!   keeps the check blind to other tests' folders written at the same time);
//! - no hang: a watchdog thread prints the case and aborts the process when one case takes more
//!   than [`CASE_LIMIT`] (so CI fails instead of hanging); the slowest case is printed;
//! - bounded memory: the peak resident size of the process (`VmHWM` of `/proc/self/status`, read
//!   after every case) stays below [`PEAK_RSS_LIMIT`] (it includes tests that run beside this one);
//! - every [`BINARY_EVERY`]-th case (at or below the size cap) also goes through
//!   `ricochet check`: exit status 0 or 2 only (never a panic's 101, another status or a signal),
//!   2 whenever the in-process load refused the scene, and on 2 stderr names the file;
//! - at the end: at least [`N_MUTANTS`] mutants checked and at least [`MIN_RUN`] of them run, so
//!   that the fuzz reaches the solver and not only the TOML parser.
//!
//! Budget: about 25 s in release mode on the 2-core machine, most of it in the runs.

use std::cell::RefCell;
use std::collections::BTreeSet;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use ricochet::plan::Plan;
use ricochet::scene::Scene;
use ricochet::step::cpu::CpuSolver;
use toml::{Table, Value};

use crate::common::*;

/// Seed of the generator.
const SEED: u64 = 0x0016_F022_5EED_2024;
/// Mutants checked.
const N_MUTANTS: usize = 2000;
/// Longest time one case may take before the watchdog aborts the process.
const CASE_LIMIT: Duration = Duration::from_secs(20);
/// Largest scene (elements) that is run; larger accepted scenes are counted as skipped.
const MAX_RUN_ELEMENTS: u64 = 200_000;
/// Largest estimated memory (`run::memory_estimate`) of a scene that is run.
const MAX_RUN_BYTES: u64 = 256 << 20;
/// Element-steps per run (the step count is this over the elements, between 20 and 1000).
const STEP_BUDGET: f64 = 1.5e6;
/// Longest error message of a refused scene (bytes).
const MAX_MESSAGE: usize = 4096;
/// Largest peak resident size of the process (bytes).
const PEAK_RSS_LIMIT: u64 = 3 << 30;
/// Every this many cases, also `ricochet check`.
const BINARY_EVERY: usize = 40;
/// Fewest mutants that must have been accepted and run.
const MIN_RUN: usize = 300;
/// Marker in every path-like string the generator writes, looked for outside the sandbox.
const ESCAPE_MARK: &str = "fuzz-esc";

// ---------------------------------------------------------------------------------------------
// Generator.
// ---------------------------------------------------------------------------------------------

/// splitmix64.
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in 0..n (n > 0).
    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// True with probability p.
    pub(crate) fn chance(&mut self, p: f64) -> bool {
        ((self.next() >> 11) as f64 / (1u64 << 53) as f64) < p
    }
}

#[derive(Clone, Debug)]
enum Seg {
    Key(String),
    Index(usize),
}

fn show_path(path: &[Seg]) -> String {
    let mut s = String::new();
    for p in path {
        match p {
            Seg::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Seg::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    if s.is_empty() {
        "(root)".into()
    } else {
        s
    }
}

fn get_mut<'a>(v: &'a mut Value, path: &[Seg]) -> &'a mut Value {
    path.iter().fold(v, |v, seg| match (seg, v) {
        (Seg::Key(k), Value::Table(t)) => t.get_mut(k).expect("path key"),
        (Seg::Index(i), Value::Array(a)) => &mut a[*i],
        _ => panic!("bad path"),
    })
}

fn children(v: &Value) -> Vec<(Seg, &Value)> {
    match v {
        Value::Table(t) => t.iter().map(|(k, c)| (Seg::Key(k.clone()), c)).collect(),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .map(|(i, c)| (Seg::Index(i), c))
            .collect(),
        _ => Vec::new(),
    }
}

fn any(v: &Value, want: &dyn Fn(&Value) -> bool) -> bool {
    want(v) || children(v).iter().any(|(_, c)| any(c, want))
}

/// A random node for which `want` holds (never the root unless `root`): a walk from the root
/// that picks a random child (among those whose subtree has such a node) at each level and
/// stops at a wanted node with probability 0.4 (always where it cannot go on).
fn pick(
    rng: &mut Rng,
    root: &Value,
    want: &dyn Fn(&Value) -> bool,
    root_ok: bool,
) -> Option<Vec<Seg>> {
    let mut path = Vec::new();
    let mut v = root;
    loop {
        let here = want(v) && (root_ok || !path.is_empty());
        let next: Vec<(Seg, &Value)> = children(v)
            .into_iter()
            .filter(|(_, c)| any(c, want))
            .collect();
        if next.is_empty() || (here && rng.chance(0.4)) {
            return here.then_some(path);
        }
        let k = rng.below(next.len());
        let (seg, c) = next.into_iter().nth(k).expect("a child");
        path.push(seg);
        v = c;
    }
}

fn is_number(v: &Value) -> bool {
    matches!(v, Value::Integer(_) | Value::Float(_))
}

/// A value as in a message: floats by `{:?}` (`1e300`, not 301 digits), strings cut at 40
/// characters.
fn short(v: &Value) -> String {
    match v {
        Value::Float(f) => format!("{f:?}"),
        Value::String(s) if s.chars().count() > 40 => {
            format!(
                "{:?}... ({} characters)",
                s.chars().take(40).collect::<String>(),
                s.chars().count()
            )
        }
        other => other.to_string(),
    }
}

fn strings(v: &Value, out: &mut Vec<String>) {
    if let Value::String(s) = v {
        out.push(s.clone());
    }
    for (_, c) in children(v) {
        strings(c, out);
    }
}

fn number(rng: &mut Rng, old: &Value) -> Value {
    let x = match old {
        Value::Integer(i) => *i as f64,
        Value::Float(f) => *f,
        _ => 1.0,
    };
    let int = matches!(old, Value::Integer(_));
    let f = Value::Float;
    // Half of the time a mild change, to keep enough scenes valid.
    if rng.chance(0.5) {
        return match (rng.below(6), old) {
            (0, Value::Integer(i)) => Value::Integer(i.saturating_mul(2)),
            (1, Value::Integer(i)) => Value::Integer(i / 2),
            (2, Value::Integer(i)) if rng.chance(0.2) => Value::Integer(i.saturating_mul(100)),
            (_, Value::Integer(i)) => Value::Integer(i.saturating_add(1)),
            (0, _) => f(2.0 * x),
            (1, _) => f(0.5 * x),
            (2, _) => f(1.1 * x),
            (3, _) => f(0.9 * x),
            (4, _) => f(10.0 * x),
            (5, Value::Float(_)) if rng.chance(0.2) => f(100.0 * x),
            _ => f(x + 1.0),
        };
    }
    match rng.below(17) {
        0 => Value::Integer(0),
        1 => Value::Integer(-1),
        2 => f(-0.0),
        3 => f(1e300),
        4 => f(-1e300),
        5 => f(5e-324),
        6 => f(1e-300),
        7 => f(1e-30),
        8 => f(f64::NAN),
        9 => f(f64::INFINITY),
        10 => f(f64::NEG_INFINITY),
        11 => {
            if int {
                Value::Integer(1 << 53)
            } else {
                f(9007199254740992.0)
            }
        }
        12 => Value::Integer(i64::MAX),
        13 => Value::Integer(i64::MIN),
        14 => match old {
            Value::Integer(i) => Value::Integer(i.saturating_mul(1_000_000)),
            _ => f(x * 1e6),
        },
        15 => match old {
            Value::Integer(i) if rng.chance(0.5) => Value::Integer(i / 1_000_000),
            _ => f(x * 1e-6),
        },
        _ => match old {
            Value::Integer(i) => Value::Integer(i.wrapping_neg()),
            _ => f(-x),
        },
    }
}

const KEYWORDS: [&str; 14] = [
    "all",
    "lagrange",
    "penalty",
    "linear_elastic",
    "neo_hookean",
    "plane_strain",
    "plane_stress",
    "viscous",
    "stiffness",
    "none",
    "binary",
    "binary64",
    "ascii",
    "Part_2-a.v1",
];

fn string(rng: &mut Rng, scene: &[String]) -> Value {
    let s = match rng.below(10) {
        0 => String::new(),
        1 => format!("../../{ESCAPE_MARK}aped"),
        2 => format!("../../../../../../../../../../{ESCAPE_MARK}aped-deep"),
        3 => format!("/tmp/{ESCAPE_MARK}aped-abs"),
        4 => "a,b".into(),
        5 => "n".repeat(if rng.chance(0.5) { 300 } else { 100_000 }),
        6 => "näme".into(),
        7 => "\u{0}".into(),
        8 if !scene.is_empty() => scene[rng.below(scene.len())].clone(),
        _ => KEYWORDS[rng.below(KEYWORDS.len())].into(),
    };
    Value::String(s)
}

fn retype(rng: &mut Rng, old: &Value) -> Value {
    match old {
        Value::Integer(_) | Value::Float(_) => {
            if rng.chance(0.5) {
                Value::String(old.to_string())
            } else {
                Value::Boolean(true)
            }
        }
        Value::String(_) => {
            if rng.chance(0.5) {
                Value::Integer(1)
            } else {
                Value::Float(0.5)
            }
        }
        Value::Boolean(_) => Value::Float(1.0),
        Value::Array(a) => {
            if rng.chance(0.5) || a.is_empty() {
                Value::String("[1.0, 2.0]".into())
            } else {
                let mut t = Table::new();
                t.insert("0".into(), a[0].clone());
                Value::Table(t)
            }
        }
        Value::Table(_) => {
            if rng.chance(0.5) {
                Value::Integer(1)
            } else {
                Value::Array(vec![old.clone()])
            }
        }
        Value::Datetime(_) => Value::Integer(0),
    }
}

/// Applies one random operator to `root`; returns what it did, or None when it found nothing to
/// apply to (then another is drawn).
fn mutate(rng: &mut Rng, root: &mut Value) -> Option<String> {
    let op = rng.below(100);
    if op < 40 {
        let path = pick(rng, root, &is_number, false)?;
        let v = get_mut(root, &path);
        let new = number(rng, v);
        let what = format!(
            "number {} = {} -> {}",
            show_path(&path),
            short(v),
            short(&new)
        );
        *v = new;
        Some(what)
    } else if op < 55 {
        let path = pick(rng, root, &|v| matches!(v, Value::String(_)), false)?;
        let mut all = Vec::new();
        strings(root, &mut all);
        let v = get_mut(root, &path);
        let new = string(rng, &all);
        let what = format!(
            "string {} = {} -> {}",
            show_path(&path),
            short(v),
            short(&new)
        );
        *v = new;
        Some(what)
    } else if op < 63 {
        let path = pick(rng, root, &|_| true, false)?;
        let v = get_mut(root, &path);
        let new = retype(rng, v);
        let what = format!("type {} -> {}", show_path(&path), short(&new));
        *v = new;
        Some(what)
    } else if op < 75 {
        let path = pick(rng, root, &|v| matches!(v, Value::Array(_)), false)?;
        let Value::Array(a) = get_mut(root, &path) else {
            unreachable!()
        };
        let p = show_path(&path);
        match rng.below(4) {
            0 if !a.is_empty() => {
                let i = rng.below(a.len());
                a.push(a[i].clone());
                Some(format!("array {p}: [{i}] appended again"))
            }
            1 if !a.is_empty() => {
                let i = rng.below(a.len());
                a.remove(i);
                Some(format!("array {p}: [{i}] removed"))
            }
            2 => {
                a.clear();
                Some(format!("array {p}: emptied"))
            }
            _ => {
                let third = match a.first() {
                    Some(Value::Integer(_)) => Value::Integer(0),
                    _ => Value::Float(0.0),
                };
                a.push(third);
                Some(format!("array {p}: third coordinate appended"))
            }
        }
    } else if op < 83 {
        let path = pick(
            rng,
            root,
            &|v| matches!(v, Value::Table(t) if !t.is_empty()),
            true,
        )?;
        let Value::Table(t) = get_mut(root, &path) else {
            unreachable!()
        };
        let keys: Vec<String> = t.keys().cloned().collect();
        let k = &keys[rng.below(keys.len())];
        t.remove(k);
        Some(format!("key {}.{k} deleted", show_path(&path)))
    } else if op < 88 {
        let path = pick(rng, root, &|v| matches!(v, Value::Table(_)), true)?;
        let Value::Table(t) = get_mut(root, &path) else {
            unreachable!()
        };
        let k = ["fuzz_unknown", "", "näme", "a.b"][rng.below(4)];
        t.insert(k.into(), Value::Integer(1));
        Some(format!("key {}.{k:?} inserted", show_path(&path)))
    } else {
        let Value::Table(t) = root else {
            unreachable!()
        };
        let lists: Vec<String> = t
            .iter()
            .filter(|(_, v)| matches!(v, Value::Array(a) if a.iter().any(|e| e.is_table())))
            .map(|(k, _)| k.clone())
            .collect();
        if lists.is_empty() {
            return None;
        }
        let k = &lists[rng.below(lists.len())];
        let Some(Value::Array(a)) = t.get_mut(k) else {
            unreachable!()
        };
        let i = rng.below(a.len());
        let mut copy = a[i].clone();
        let mut what = format!("[[{k}]] {i} duplicated");
        if rng.chance(0.5) {
            if let Some(Value::String(name)) = copy.as_table_mut().and_then(|c| c.get_mut("name")) {
                name.push_str("_2");
                what.push_str(" with name _2");
            }
        }
        a.push(copy);
        Some(what)
    }
}

/// A byte-level change of `bytes`.
pub(crate) fn mutate_bytes(rng: &mut Rng, bytes: &mut Vec<u8>) -> String {
    let at = rng.below(bytes.len() + 1);
    let b = rng.next() as u8;
    match rng.below(3) {
        0 => {
            bytes.truncate(at);
            format!("bytes: cut at {at}")
        }
        1 => {
            bytes.insert(at, b);
            format!("bytes: {b:#04x} inserted at {at}")
        }
        _ => {
            if at < bytes.len() {
                bytes[at] = b;
            } else {
                bytes.push(b);
            }
            format!("bytes: {b:#04x} written at {at}")
        }
    }
}

/// A mutant: its base scene, what was done and the file's bytes.
struct Mutant {
    base: String,
    ops: Vec<String>,
    bytes: Vec<u8>,
}

impl Mutant {
    /// The case as printed: base, operators and text (lines cut to 1000 characters).
    fn describe(&self, case: usize) -> String {
        let text: Vec<String> = String::from_utf8_lossy(&self.bytes)
            .lines()
            .map(|l| match l.char_indices().nth(1000) {
                Some((i, _)) => format!("{}... (line cut here)", &l[..i]),
                None => l.to_string(),
            })
            .collect();
        format!(
            "case {case} (base {}, {}):\n----\n{}\n----",
            self.base,
            self.ops.join("; "),
            text.join("\n")
        )
    }
}

/// The base scenes, sorted by path: (name, parsed tree). A verification case (a template) gives
/// one scene per method, at its first quick level.
fn bases() -> Vec<(String, Value)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in [
        "assets",
        "assets/stress",
        "assets/verification",
        "assets/bench",
    ] {
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "toml") {
                files.push(p);
            }
        }
    }
    files.sort();
    let mut out = Vec::new();
    for p in files {
        let rel = p.strip_prefix(root).unwrap().display().to_string();
        let texts: Vec<(String, String)> = if rel.starts_with("assets/verification/") {
            let case = ricochet::verify::case::Case::read(&p).unwrap();
            // The first level of the quick ladder. A case with none (the full ladder only) is
            // too costly a base: a run of perforation_blunt's coarsest level to the step budget
            // took 7-15 s, and the mutants of a base run about ten times. Its keys are those of
            // the failure and thermal cases and the perforation assets, which are bases.
            let Some(level) = case.levels.quick.first() else {
                continue;
            };
            case.case
                .methods
                .iter()
                .map(|m| {
                    let text = case.expand(level, m).unwrap();
                    (format!("{rel} ({m}, {level:?})"), text)
                })
                .collect()
        } else {
            vec![(rel, std::fs::read_to_string(&p).unwrap())]
        };
        for (name, text) in texts {
            let table: Table = toml::from_str(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
            out.push((name, Value::Table(table)));
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// One case.
// ---------------------------------------------------------------------------------------------

/// How a case ended (when it broke no rule).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Outcome {
    /// `Scene::load` refused it (read, TOML or shape).
    Parse,
    /// `Scene::load` refused a value.
    Validation,
    /// `run::check_memory` refused it.
    Memory,
    /// `run::model` refused it (mesh, boundary, pressure, overlap).
    Model,
    /// `run::check_limits` refused it.
    Limits,
    /// Accepted, not run: above the size cap.
    SkippedForSize,
    /// Run: completed.
    Completed,
    /// Run: failed (instability), with a message.
    Failed,
}

impl Outcome {
    pub(crate) fn refused(self) -> bool {
        self <= Outcome::Limits
    }
}

/// Checks a refusal's message: names the file (the scene, or the mesh file `mesh` it reads),
/// not empty, not too long.
fn refused(
    outcome: Outcome,
    e: ricochet::Error,
    file: &Path,
    mesh: Option<&Path>,
) -> Result<Outcome, String> {
    let msg = e.to_string();
    let name = file.display().to_string();
    let named = msg.contains(&name) || mesh.is_some_and(|m| msg.contains(&*m.to_string_lossy()));
    if msg.trim().is_empty() || !named || msg.len() > MAX_MESSAGE {
        let shown: String = msg.chars().take(2000).collect();
        return Err(format!(
            "{outcome:?} refusal with a bad message ({} bytes; must name {name} and have at most \
             {MAX_MESSAGE}): {shown}",
            msg.len()
        ));
    }
    Ok(outcome)
}

/// The numbers of a JSON value that are not finite (`null`, as serde_json writes them).
pub(crate) fn json_nulls(v: &serde_json::Value, path: &str, out: &mut Vec<String>) {
    match v {
        serde_json::Value::Null => out.push(path.to_string()),
        serde_json::Value::Number(n) if !n.as_f64().is_some_and(f64::is_finite) => {
            out.push(path.to_string())
        }
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                json_nulls(x, &format!("{path}[{i}]"), out);
            }
        }
        serde_json::Value::Object(o) => {
            for (k, x) in o {
                json_nulls(x, &format!("{path}.{k}"), out);
            }
        }
        _ => {}
    }
}

/// The binary's load path and a short CPU run of the scene `file` (whose refusal may name the
/// mesh file `mesh` instead).
pub(crate) fn run_case(file: &Path, mesh: Option<&Path>, out: &Path) -> Result<Outcome, String> {
    let mut scene = match Scene::load(file) {
        Ok(s) => s,
        Err(e @ ricochet::Error::Invalid { .. }) => {
            return refused(Outcome::Validation, e, file, mesh)
        }
        Err(e) => return refused(Outcome::Parse, e, file, mesh),
    };
    if let Err(e) = ricochet::run::check_memory(&scene) {
        return refused(Outcome::Memory, e, file, mesh);
    }
    let elements: u64 = ricochet::run::element_counts(&scene).iter().sum();
    if elements > MAX_RUN_ELEMENTS || ricochet::run::memory_estimate(&scene) > MAX_RUN_BYTES {
        return Ok(Outcome::SkippedForSize);
    }
    let model = match ricochet::run::model(&scene) {
        Ok(m) => m,
        Err(e) => return refused(Outcome::Model, e, file, mesh),
    };
    if let Err(e) = ricochet::run::check_limits(&scene, &model) {
        return refused(Outcome::Limits, e, file, mesh);
    }
    let plan = Plan::new(&scene, &model);
    let steps = (STEP_BUDGET / elements.max(1) as f64).clamp(20.0, 1000.0);
    let dt = ricochet::run::first_step(&scene, &model).0;
    scene.run.end_time = scene.run.end_time.min(steps * dt);
    let mut solver = CpuSolver::new(model.clone(), plan.clone(), ricochet::run::schedule(&scene));
    let result = ricochet::run::run(&scene, &model, &plan, &mut solver, out, None)
        .map_err(|e| format!("run error: {e}"))?;
    let text = std::fs::read_to_string(out.join("summary.json"))
        .map_err(|e| format!("summary.json: {e}"))?;
    let summary: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("summary.json is not JSON: {e}"))?;
    let status = summary["status"].as_str().unwrap_or("(none)");
    if status != result.summary.status {
        return Err(format!(
            "summary.json says {status:?}, the run {:?}",
            result.summary.status
        ));
    }
    match status {
        "completed" => {
            let mut bad = Vec::new();
            json_nulls(&summary, "summary", &mut bad);
            if !bad.is_empty() {
                return Err(format!(
                    "completed run with non-finite numbers in summary.json at {bad:?}:\n{text}"
                ));
            }
            let history = std::fs::read_to_string(out.join("history.csv"))
                .map_err(|e| format!("history.csv: {e}"))?;
            // The header, after the comment lines (`#`: the axisymmetric note), is not numbers.
            let comments = history.lines().take_while(|l| l.starts_with('#')).count();
            for (i, line) in history.lines().enumerate().skip(comments + 1) {
                for x in line.split(',') {
                    if !x.parse::<f64>().is_ok_and(f64::is_finite) {
                        return Err(format!(
                            "completed run with {x:?} in history.csv line {}: {line}",
                            i + 1
                        ));
                    }
                }
            }
            Ok(Outcome::Completed)
        }
        "failed" if !result.summary.message.trim().is_empty() => Ok(Outcome::Failed),
        other => Err(format!(
            "run ended with status {other:?} and message {:?}",
            result.summary.message
        )),
    }
}

/// Entries of `dir` whose name has the escape marker.
fn marked(dir: &Path) -> BTreeSet<PathBuf> {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .filter(|e| e.file_name().to_string_lossy().contains(ESCAPE_MARK))
                .map(|e| e.path())
                .collect()
        })
        .unwrap_or_default()
}

/// What the sandbox holds besides `root/cases/<case>/scene.toml` and `root/cases/<case>/out/`
/// (with anything under `out/`), `case` being the one case folder there.
fn strays(root: &Path, case: &Path) -> Vec<PathBuf> {
    let entries = |d: &Path| -> Vec<PathBuf> {
        std::fs::read_dir(d)
            .map(|rd| rd.filter_map(|e| e.ok()).map(|e| e.path()).collect())
            .unwrap_or_default()
    };
    let real_dir = |p: &Path| p.is_dir() && !p.is_symlink();
    let mut bad = Vec::new();
    let cases = root.join("cases");
    for p in entries(root) {
        if !(p == cases && real_dir(&p)) {
            bad.push(p);
        }
    }
    for p in entries(&cases) {
        if !(p == case && real_dir(&p)) {
            bad.push(p);
        }
    }
    for p in entries(case) {
        let ok = (p == case.join("scene.toml") && p.is_file() && !p.is_symlink())
            || (p == case.join("out") && real_dir(&p));
        if !ok {
            bad.push(p);
        }
    }
    bad
}

/// Peak resident size of this process (bytes), from `VmHWM` of `/proc/self/status`.
pub(crate) fn peak_rss() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("VmHWM:"))?.to_string();
            line.split_whitespace().nth(1)?.parse::<u64>().ok()
        })
        .map_or(0, |kb| kb * 1024)
}

thread_local! {
    /// The last panic of this thread, with its location (set by the hook of [`install_hook`]).
    pub(crate) static LAST_PANIC: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// A panic hook that records each panic's message and location for this thread, then calls
/// the hook that was there before (so other tests' panics print as usual).
pub(crate) fn install_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let prev = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            LAST_PANIC.with(|p| *p.borrow_mut() = Some(info.to_string()));
            prev(info);
        }));
    });
}

/// A thread that aborts the process when the current case runs longer than [`CASE_LIMIT`].
pub(crate) struct Watchdog {
    current: Arc<Mutex<Option<(Instant, String)>>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Watchdog {
    pub(crate) fn start() -> Self {
        let current: Arc<Mutex<Option<(Instant, String)>>> = Arc::new(Mutex::new(None));
        let stop = Arc::new(AtomicBool::new(false));
        let (c, s) = (Arc::clone(&current), Arc::clone(&stop));
        let thread = std::thread::spawn(move || {
            while !s.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(100));
                let guard = c.lock().unwrap_or_else(|e| e.into_inner());
                if let Some((t0, what)) = guard.as_ref() {
                    if t0.elapsed() > CASE_LIMIT {
                        // Straight to stderr: the test harness's capture of `eprintln!` would
                        // be lost with the process.
                        use std::io::Write as _;
                        let _ = writeln!(
                            std::io::stderr(),
                            "fuzz: HANG: a case has run for more than {CASE_LIMIT:?}; aborting.\n{what}"
                        );
                        std::process::abort();
                    }
                }
            }
        });
        Self {
            current,
            stop,
            thread: Some(thread),
        }
    }

    pub(crate) fn watch(&self, what: Option<String>) {
        *self.current.lock().unwrap_or_else(|e| e.into_inner()) = what.map(|w| (Instant::now(), w));
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The test.
// ---------------------------------------------------------------------------------------------

#[test]
fn mutated_scenes_never_panic_hang_escape_or_complete_with_non_finite_numbers() {
    let t_start = Instant::now();
    install_hook();
    let bases = bases();
    assert!(bases.len() >= 20, "only {} base scenes", bases.len());
    let root = tmp_dir("fuzz");
    let sandbox = root.join("cases");
    std::fs::create_dir_all(&sandbox).unwrap();
    let cwd = std::env::current_dir().unwrap();
    let outside: Vec<PathBuf> = vec![
        std::env::temp_dir(),
        PathBuf::from("/tmp"),
        cwd,
        root.clone(),
        root.parent().unwrap().to_path_buf(),
    ];
    let before: Vec<BTreeSet<PathBuf>> = outside.iter().map(|d| marked(d)).collect();

    let failures =
        std::env::temp_dir().join(format!("ricochet-fuzz-failures-{}", std::process::id()));
    let watchdog = Watchdog::start();
    // Deeper local runs: RICOCHET_FUZZ_SEED and RICOCHET_FUZZ_MUTANTS (CI uses the constants).
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    let seed = env("RICOCHET_FUZZ_SEED").unwrap_or(SEED);
    let n_mutants = env("RICOCHET_FUZZ_MUTANTS").map_or(N_MUTANTS, |n| n as usize);
    let mut rng = Rng(seed);
    let mut made = 0usize;
    let mut unwritable = 0usize;
    let mut counts = std::collections::BTreeMap::<Outcome, usize>::new();
    let mut violations: Vec<String> = Vec::new();
    let mut binary_runs = 0usize;
    let mut slowest = (0.0f64, String::new());
    let mut peak = 0u64;
    let mut checked = 0usize;
    while checked < n_mutants {
        let (base, tree) = &bases[made % bases.len()];
        made += 1;
        let mut tree = tree.clone();
        let mut ops = Vec::new();
        // 1 operator (60 %), 2 (25 %) or 3 (15 %).
        let n_ops = [1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 3, 3, 3][rng.below(20)];
        while ops.len() < n_ops {
            if let Some(op) = mutate(&mut rng, &mut tree) {
                ops.push(op);
            }
        }
        let Ok(text) = toml::to_string(&tree) else {
            unwritable += 1;
            continue;
        };
        let mut bytes = text.into_bytes();
        if rng.chance(0.1) {
            ops.push(mutate_bytes(&mut rng, &mut bytes));
        }
        let mutant = Mutant {
            base: base.clone(),
            ops,
            bytes,
        };
        let case = checked;
        checked += 1;

        let dir = sandbox.join(format!("{case:04}"));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("scene.toml");
        std::fs::write(&file, &mutant.bytes).unwrap();
        let out = dir.join("out");
        watchdog.watch(Some(mutant.describe(case)));
        let t0 = Instant::now();
        let result = catch_unwind(AssertUnwindSafe(|| run_case(&file, None, &out)));
        let result = match result {
            Ok(r) => r,
            Err(payload) => {
                let msg = payload
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                let at = LAST_PANIC.with(|p| p.borrow_mut().take()).unwrap_or(msg);
                Err(format!("PANIC: {at}"))
            }
        };
        // A broken rule: the case is printed at the end and its file kept in `failures`.
        let mut fail = |why: String| {
            let why: String = why.chars().take(3000).collect();
            std::fs::create_dir_all(&failures).unwrap();
            let kept = failures.join(format!("case_{case:04}.toml"));
            std::fs::write(&kept, &mutant.bytes).unwrap();
            violations.push(format!(
                "{why}\n(scene kept as {})\n{}",
                kept.display(),
                mutant.describe(case)
            ));
        };
        let outcome = match result {
            Ok(o) => {
                *counts.entry(o).or_default() += 1;
                Some(o)
            }
            Err(why) => {
                fail(why);
                None
            }
        };
        // A sample through the binary (not the scenes above the size cap: `check` meshes them).
        if case.is_multiple_of(BINARY_EVERY) && outcome != Some(Outcome::SkippedForSize) {
            binary_runs += 1;
            let name = file.to_str().unwrap();
            let o = run_bin(&["check", name]);
            let err = String::from_utf8_lossy(&o.stderr);
            match o.status.code() {
                Some(0) if !outcome.is_some_and(Outcome::refused) => {}
                Some(2) if err.contains(name) && !err.contains("panicked") => {}
                code => fail(format!(
                    "`ricochet check` exited with {code:?} ({:?}; in process: {outcome:?}); \
                     stderr:\n{err}",
                    o.status
                )),
            }
        }
        let seconds = t0.elapsed().as_secs_f64();
        watchdog.watch(None);
        if seconds > slowest.0 {
            slowest = (seconds, format!("case {case} (base {})", mutant.base));
        }
        // Nothing outside `out/`.
        let strays = strays(&root, &dir);
        if !strays.is_empty() {
            fail(format!("files outside out/: {strays:?}"));
        }
        for (d, b) in outside.iter().zip(&before) {
            let new: Vec<PathBuf> = marked(d).difference(b).cloned().collect();
            if !new.is_empty() {
                fail(format!("files outside the sandbox: {new:?}"));
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
        peak = peak.max(peak_rss());
    }
    drop(watchdog);
    let _ = std::fs::remove_dir_all(&root);

    let count = |o: Outcome| counts.get(&o).copied().unwrap_or(0);
    let ran = count(Outcome::Completed) + count(Outcome::Failed);
    let total = t_start.elapsed().as_secs_f64();
    // Straight to stderr, past the harness's capture: the counts belong in the CI log.
    use std::io::Write as _;
    let _ = writeln!(
        std::io::stderr(),
        "fuzz: seed {seed:#x}: {checked} mutants checked of {made} made ({unwritable} not writable as TOML) from \
         {} base scenes: refused at parse {} and validation {}, by memory {}, model {} and limits \
         {}; skipped for size {}; run {ran}: completed {}, failed {}; {} rule violations; \
         `ricochet check` on {binary_runs}; slowest case {:.3} s ({}); peak RSS {:.1} MiB; {total:.1} s \
         in all",
        bases.len(),
        count(Outcome::Parse),
        count(Outcome::Validation),
        count(Outcome::Memory),
        count(Outcome::Model),
        count(Outcome::Limits),
        count(Outcome::SkippedForSize),
        count(Outcome::Completed),
        count(Outcome::Failed),
        violations.len(),
        slowest.0,
        slowest.1,
        peak as f64 / 1048576.0,
    );
    for v in violations.iter().take(5) {
        eprintln!("fuzz: VIOLATION: {v}\n");
    }
    assert!(
        violations.is_empty(),
        "{} fuzz cases broke a rule (the first 5 above)",
        violations.len()
    );
    assert!(checked >= N_MUTANTS.min(n_mutants));
    let min_run = MIN_RUN.min(MIN_RUN * n_mutants / N_MUTANTS);
    assert!(
        ran >= min_run,
        "only {ran} mutants were run (at least {min_run} wanted)"
    );
    assert!(
        peak < PEAK_RSS_LIMIT,
        "peak RSS {:.1} MiB, above {} MiB",
        peak as f64 / 1048576.0,
        PEAK_RSS_LIMIT >> 20
    );
}
