//! What the study tests share: the binary, the repository's paths, scratch folders, and running
//! a command with a time limit.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The ricochet binary under test.
pub fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_ricochet"));
    c.env(
        "XDG_RUNTIME_DIR",
        std::env::var("XDG_RUNTIME_DIR").unwrap_or("/tmp".into()),
    );
    c
}

/// A path in the repository.
pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A fresh scratch folder for test `name`.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ricochet-study-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `cmd` and returns its output, printing it when the status is not `expected`.
pub fn run(cmd: &mut Command, expected: i32) -> Output {
    let out = cmd.output().unwrap();
    let code = out.status.code().unwrap_or(-1);
    assert_eq!(
        code,
        expected,
        "{cmd:?}: exit status {code}\nstdout:\n{}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// A study file in `dir` over the shipped `rods_impact.toml` with `body` after its `[study]`
/// header (name, scene, backend cpu).
pub fn study_file(dir: &Path, name: &str, body: &str) -> PathBuf {
    let path = dir.join(format!("{name}.toml"));
    let text = format!(
        "[study]\nname = \"{name}\"\nscene = {:?}\nbackend = \"cpu\"\n{body}",
        repo("assets/rods_impact.toml").display().to_string()
    );
    std::fs::write(&path, text).unwrap();
    path
}

/// The lines of `results.csv` in `dir`.
pub fn results(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("results.csv"))
        .unwrap()
        .lines()
        .map(str::to_string)
        .collect()
}
