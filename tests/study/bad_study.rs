//! Bad study files: each refusal exits 2 and names the file, the key and the value; and a fuzz of
//! the shipped study files.

use std::path::Path;
use std::time::{Duration, Instant};

use toml::Value;

use crate::common::{bin, repo, run, scratch, study_file};

/// The parameters of a valid study, for the refusals below to break one thing at a time.
const GOOD: &str = r#"
[[parameter]]
name = "v0"
key = "body[striker].initial_velocity[0]"
values = [5.0, 10.0]

[[collect]]
name = "target_v"
history = "target.vx"
"#;

/// Each bad study: `ricochet check` and `ricochet study` exit 2, and stderr names the file, the
/// key and the value (and the case, for an override the scene refuses).
#[test]
fn bad_study_files_exit_2_naming_the_file_key_and_value() {
    let dir = scratch("bad");
    let cases: [(&str, String, &[&str]); 11] = [
        ("unknown_key", format!("{GOOD}\n[[parameter]]\nkey = \"run.end_time\"\nvalues = [1e-4]\nstep = 2\n"), &["unknown field `step`"]),
        ("unknown_body", GOOD.replace("body[striker]", "body[stiker]"), &["body[stiker].initial_velocity[0]", "5.0", "case 0000", "\"stiker\""]),
        ("past_the_end", GOOD.replace("initial_velocity[0]", "initial_velocity[2]"), &["initial_velocity[2]", "case 0000"]),
        ("bad_path", GOOD.replace("].initial_velocity", "].initial velocity"), &["parameter[0].key", "initial velocity", "character 22"]),
        ("out_of_range", format!("{GOOD}\n[[parameter]]\nkey = \"material[steel].density\"\nvalues = [7850.0, -1.0]\n"), &["material[steel].density", "-1.0", "case 0001"]),
        ("unknown_scene_key", format!("{GOOD}\n[[parameter]]\nkey = \"run.end_tme\"\nvalues = [1e-4]\n"), &["run.end_tme", "0.0001"]),
        ("bad_reduce", GOOD.replace("history = \"target.vx\"", "history = \"target.vx\"\nreduce = \"mean\""), &["collect[0].reduce", "\"mean\""]),
        ("zero_count", GOOD.replace("values = [5.0, 10.0]", "range = { from = 1.0, to = 2.0, count = 0 }"), &["parameter[0].range.count", "0"]),
        ("bad_summary", GOOD.replace("history = \"target.vx\"", "summary = \"speed\""), &["collect[0].summary", "\"speed\""]),
        ("nan_value", GOOD.replace("values = [5.0, 10.0]", "values = [5.0, nan]"), &["parameter[0].values[1]", "NaN"]),
        ("no_parameter", "[[collect]]\nname = \"x\"\nsummary = \"steps\"\n".to_string(), &["parameter", "at least one"]),
    ];
    for (name, body, words) in &cases {
        let path = study_file(&dir, name, body);
        for command in ["check", "study"] {
            let mut cmd = bin();
            cmd.arg(command).arg(&path);
            if command == "study" {
                cmd.arg("--out").arg(dir.join("out"));
            }
            let o = run(&mut cmd, 2);
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(
                err.contains(&format!("{name}.toml")),
                "{name} {command}: {err}"
            );
            for w in *words {
                assert!(err.contains(w), "{name} {command}: no {w:?} in {err}");
            }
        }
    }
    // A bad kind, named with its value.
    let path = dir.join("bad_kind.toml");
    std::fs::write(
        &path,
        format!(
            "[study]\nscene = {:?}\nkind = \"cube\"\n{GOOD}",
            repo("assets/rods_impact.toml").display().to_string()
        ),
    )
    .unwrap();
    let o = run(bin().arg("check").arg(&path), 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad_kind.toml") && err.contains("study.kind") && err.contains("\"cube\""),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// splitmix64, the fuzz's generator (fixed seed: every run makes the same mutants).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// Mutants of the study files made by the fuzz.
const N_MUTANTS: usize = 400;
/// Every this many mutants also goes through `ricochet check`.
const BINARY_EVERY: usize = 20;
/// Longest time one mutant may take in process.
const CASE_LIMIT: Duration = Duration::from_secs(20);

/// One random change to `v`: a number, a string (paths among them), a key, or a type.
fn mutate(v: &mut Value, rng: &mut Rng, strings: &[String]) {
    match v {
        Value::Table(t) if !t.is_empty() && rng.below(4) > 0 => {
            let keys: Vec<String> = t.keys().cloned().collect();
            let k = &keys[rng.below(keys.len())];
            match rng.below(8) {
                0 => {
                    t.remove(k);
                }
                1 => {
                    t.insert("fuzz_unknown".into(), Value::Integer(1));
                }
                _ => mutate(t.get_mut(k).unwrap(), rng, strings),
            }
        }
        Value::Array(a) if !a.is_empty() && rng.below(4) > 0 => match rng.below(6) {
            0 => a.clear(),
            1 => {
                let x = a[rng.below(a.len())].clone();
                a.push(x);
            }
            _ => {
                let i = rng.below(a.len());
                mutate(&mut a[i], rng, strings)
            }
        },
        Value::Float(x) => {
            let choices = [
                0.0,
                -1.0,
                -0.0,
                1e300,
                -1e300,
                5e-324,
                f64::NAN,
                f64::INFINITY,
                *x * 1e6,
                -*x,
                *x * 2.0,
                *x * 0.5,
                1e-30,
            ];
            *x = choices[rng.below(choices.len())];
        }
        Value::Integer(i) => {
            let choices = [
                0,
                -1,
                1,
                2,
                1_000_000,
                i64::MAX,
                i64::MIN,
                *i * 1000,
                100_001,
            ];
            *i = choices[rng.below(choices.len())];
        }
        Value::String(s) => {
            let fixed = [
                String::new(),
                "../../fuzz-escaped".into(),
                "/tmp/fuzz-escaped-abs.toml".into(),
                "a,b".into(),
                "x".repeat(300),
                "body[".into(),
                "body[striker].initial_velocity[99]".into(),
                "material[0]".into(),
                "run".into(),
                "kinetic0 >= nan".into(),
                "lhs".into(),
                "threshold".into(),
                "at".into(),
                "\u{0}".into(),
            ];
            *s = if rng.below(3) == 0 && !strings.is_empty() {
                strings[rng.below(strings.len())].clone()
            } else {
                fixed[rng.below(fixed.len())].clone()
            };
        }
        other => {
            *other = match rng.below(4) {
                0 => Value::String("fuzz".into()),
                1 => Value::Boolean(true),
                2 => Value::Array(vec![]),
                _ => Value::Float(1.5),
            };
        }
    }
}

/// Every string of `v`.
fn strings(v: &Value, out: &mut Vec<String>) {
    match v {
        Value::String(s) => out.push(s.clone()),
        Value::Array(a) => a.iter().for_each(|x| strings(x, out)),
        Value::Table(t) => t.values().for_each(|x| strings(x, out)),
        _ => {}
    }
}

/// [`N_MUTANTS`] mutants of the study files of `assets/studies/` (1 to 3 changes each, or a cut
/// of the text) go through `Study::parse` and, when valid with at most 50 cases,
/// `Study::check` of every case, in process: no panic, no mutant over [`CASE_LIMIT`], every
/// refusal naming the study file (or the base scene it reads); every [`BINARY_EVERY`]-th also
/// through `ricochet check`, which exits 0 or 2 only, 2 exactly when the library refused it.
#[test]
fn fuzzed_study_files_are_refused_cleanly() {
    let dir = scratch("fuzz");
    let studies = repo("assets/studies");
    let mut bases: Vec<(String, Value)> = std::fs::read_dir(&studies)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| {
            let mut v: Value = toml::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
            // The base scene by its absolute path: the mutants live in the scratch folder.
            v["study"]["scene"] =
                Value::String(repo("assets/rods_impact.toml").display().to_string());
            (p.file_name().unwrap().to_string_lossy().into_owned(), v)
        })
        .collect();
    bases.sort_by(|a, b| a.0.cmp(&b.0));
    assert!(bases.len() >= 3);
    let mut rng = Rng(0x5eed_0038);
    let (mut refused, mut valid) = (0, 0);
    for n in 0..N_MUTANTS {
        let (base, tree) = &bases[n % bases.len()];
        let mut all = Vec::new();
        strings(tree, &mut all);
        let mut v = tree.clone();
        for _ in 0..1 + rng.below(3) {
            mutate(&mut v, &mut rng, &all);
        }
        let Ok(mut text) = toml::to_string(&v) else {
            continue;
        };
        if rng.below(10) == 0 {
            let mut cut = rng.below(text.len().max(1));
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            text.truncate(cut);
        }
        let path = dir.join(format!("mutant_{n:04}.toml"));
        std::fs::write(&path, &text).unwrap();
        let started = Instant::now();
        let outcome = std::panic::catch_unwind(|| {
            ricochet::study::Study::parse(&text, &path).and_then(|s| {
                let n = s.cases().len();
                if n <= 50 {
                    s.check(&dir.join("out")).map(|_| ())
                } else {
                    Ok(())
                }
            })
        });
        let took = started.elapsed();
        let outcome = outcome.unwrap_or_else(|_| panic!("mutant {n} of {base} panicked:\n{text}"));
        assert!(
            took < CASE_LIMIT,
            "mutant {n} of {base} took {took:?}:\n{text}"
        );
        match &outcome {
            Ok(()) => valid += 1,
            Err(e) => {
                refused += 1;
                let m = e.to_string();
                assert!(
                    m.contains(&format!("mutant_{n:04}.toml")) || m.contains("rods_impact.toml"),
                    "mutant {n} of {base}: the message names neither file: {m}\n{text}"
                );
                assert!(m.len() < 4000, "mutant {n}: a message of {} bytes", m.len());
            }
        }
        if n % BINARY_EVERY == 0 {
            let o = bin().arg("check").arg(&path).output().unwrap();
            let code = o.status.code();
            let expected = if outcome.is_ok() { 0 } else { 2 };
            assert_eq!(
                code,
                Some(expected),
                "mutant {n} of {base}: `ricochet check` exit {code:?}:\n{}\n{text}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
        let _ = std::fs::remove_file(&path);
    }
    // Some mutants cannot be written back as TOML (a table turned into a value before other
    // values): skipped, as the scene fuzz skips them.
    assert!(
        refused + valid >= N_MUTANTS / 2,
        "{refused} refused, {valid} valid"
    );
    assert!(
        refused >= N_MUTANTS / 4 && valid >= 10,
        "{refused} refused, {valid} valid"
    );
    assert!(!Path::new("/tmp/fuzz-escaped-abs.toml").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
