//! A study's cases on a Slurm cluster: `DIR/slurm/array.sh`, a job array with one case per array
//! task (throttled by `%K`, a GPU per task when asked), and `DIR/slurm/collect.sh`, a job that
//! runs `ricochet collect DIR` once every task of the array has ended
//! (`--dependency=afterany:<array id>`); [`submit`] hands both to `sbatch --parsable`.
//!
//! Each array task runs its case as the local runner does ([`super::local`]): a case whose run
//! ended (completed or failed in its `summary.json`) is left alone, one with a checkpoint
//! continues from it (`ricochet run --restart`), any other runs from the start; the output goes to
//! the case's `run.log` and the exit status to its `exit` file, so that [`super::collect()`] reads
//! the same folder whichever ran it. `--signal=B:TERM@S` has Slurm send SIGTERM to the task's
//! shell S seconds before its time limit; the shell passes it to the run, which writes its
//! checkpoint and stops, and the task then requeues itself (`scontrol requeue`, allowed by
//! `--requeue`): the requeued task restarts from the checkpoint. A task that Slurm itself
//! requeues or that is killed (`scontrol requeue`, a node failure) does the same on its next
//! start. Nothing here prints. Host-side only, no GPU twin.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::cases::write_file;
use super::collect::{EXIT_FILE, LOG_FILE};
use crate::error::{Error, Result};
use crate::run::Backend;

/// What the scripts ask of Slurm.
#[derive(Debug, Clone, PartialEq)]
pub struct SlurmOptions {
    /// The ricochet binary the tasks run (an absolute path the compute nodes can reach).
    pub program: PathBuf,
    /// The runs' backend (`--backend`).
    pub backend: Backend,
    /// `--partition`.
    pub partition: Option<String>,
    /// The throttle: at most this many array tasks at once (`--array=...%K`).
    pub max_parallel: Option<usize>,
    /// `--gpus-per-task`.
    pub gpus_per_task: Option<u32>,
    /// `--cpus-per-task`.
    pub cpus_per_task: Option<u32>,
    /// `--time` of each task (Slurm's forms: `MM`, `HH:MM:SS`, `D-HH`, ...).
    pub time: Option<String>,
    /// Seconds before the time limit at which the task is told to checkpoint and stop
    /// (`--signal=B:TERM@S`).
    pub signal_seconds: u32,
    /// `--account`.
    pub account: Option<String>,
    /// Further `#SBATCH` options of both scripts, each as written on sbatch's command line
    /// (`--mem=4G`, `--qos=short`).
    pub extra: Vec<String>,
}

impl SlurmOptions {
    /// Options for `program` on `backend`, every other one Slurm's default; the signal 120 s
    /// before the time limit.
    pub fn new(program: PathBuf, backend: Backend) -> Self {
        Self {
            program,
            backend,
            partition: None,
            max_parallel: None,
            gpus_per_task: None,
            cpus_per_task: None,
            time: None,
            signal_seconds: 120,
            account: None,
            extra: Vec::new(),
        }
    }

    /// The `#SBATCH` lines the two scripts share.
    fn common(&self) -> Vec<String> {
        let mut lines = Vec::new();
        if let Some(p) = &self.partition {
            lines.push(format!("--partition={p}"));
        }
        if let Some(a) = &self.account {
            lines.push(format!("--account={a}"));
        }
        lines.extend(self.extra.iter().cloned());
        lines
    }
}

/// The paths of a study's Slurm scripts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Scripts {
    /// `DIR/slurm/array.sh`.
    pub array: PathBuf,
    /// `DIR/slurm/collect.sh`.
    pub collect: PathBuf,
}

/// The ids of the submitted jobs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Submitted {
    /// The job array's id.
    pub array: String,
    /// The collect job's id.
    pub collect: String,
}

/// A value quoted for bash (single quotes).
fn quoted(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// A path quoted for bash.
fn quoted_path(p: &Path) -> String {
    quoted(&p.to_string_lossy())
}

/// Checks an option that goes on an `#SBATCH` line: one line, no `#`-comment breaking it.
fn sbatch_safe(what: &str, value: &str) -> Result<()> {
    if value.is_empty() || value.contains(['\n', '\r']) || value.trim() != value {
        return Err(Error::Study(format!(
            "{what} {value:?} cannot go on an #SBATCH line (empty, spaces around it, or a \
             line break)"
        )));
    }
    Ok(())
}

/// The text of `array.sh` for the study folder `root` (absolute) and its case ids `ids`.
///
/// # Errors
/// [`Error::Study`] for an option that cannot go on an `#SBATCH` line, or no cases.
pub fn array_script(
    name: &str,
    root: &Path,
    ids: &[String],
    opts: &SlurmOptions,
) -> Result<String> {
    if ids.is_empty() {
        return Err(Error::Study("the study has no cases to run".into()));
    }
    let mut sbatch = vec![
        format!("--job-name=ricochet-{name}"),
        format!(
            "--array=0-{}{}",
            ids.len() - 1,
            opts.max_parallel
                .map(|k| format!("%{k}"))
                .unwrap_or_default()
        ),
        format!("--output={}/slurm/logs/%a.out", root.display()),
        "--open-mode=append".into(),
        "--requeue".into(),
        format!("--signal=B:TERM@{}", opts.signal_seconds),
        "--ntasks=1".into(),
        format!("--cpus-per-task={}", opts.cpus_per_task.unwrap_or(1)),
    ];
    if let Some(t) = &opts.time {
        sbatch.push(format!("--time={t}"));
    }
    if let Some(g) = opts.gpus_per_task {
        sbatch.push(format!("--gpus-per-task={g}"));
    }
    sbatch.extend(opts.common());
    for s in &sbatch {
        sbatch_safe("the option", s)?;
    }
    let backend = match opts.backend {
        Backend::Auto => "auto",
        Backend::Cpu => "cpu",
        Backend::Gpu => "gpu",
    };
    let mut text = String::from("#!/bin/bash\n");
    text.push_str(&format!(
        "# The cases of the study {name:?} as a Slurm job array (written by `ricochet study \
         --slurm`):\n# one case per array task. Submit with `sbatch --parsable {}`, then\n# \
         `sbatch --dependency=afterany:<array id> {}`.\n",
        root.join("slurm/array.sh").display(),
        root.join("slurm/collect.sh").display()
    ));
    for s in &sbatch {
        text.push_str(&format!("#SBATCH {s}\n"));
    }
    let list: Vec<String> = ids.iter().map(|id| quoted(id)).collect();
    text.push_str(&format!(
        r#"set -u
ricochet={program}
root={root}
ids=({ids})
id=${{ids[$SLURM_ARRAY_TASK_ID]}}
dir="$root/cases/$id"
log="$dir/{log}"
echo "case $id: array task ${{SLURM_ARRAY_JOB_ID:-?}}_${{SLURM_ARRAY_TASK_ID}} on $(hostname), restart count ${{SLURM_RESTART_COUNT:-0}}"
# A run that ended (completed or failed) is not run again.
if grep -Eq '"status": *"(completed|failed)"' "$dir/out/summary.json" 2>/dev/null; then
  echo "case $id: its run has ended; nothing to do"
  exit 0
fi
if [ -f "$dir/out/checkpoint.bin" ]; then
  args=(run --restart "$dir/out")
else
  rm -rf "$dir/out"
  args=(run "$dir/scene.toml" --out "$dir/out")
fi
args+=(--backend {backend})
rm -f "$dir/{exit}"
echo "\$ ricochet ${{args[*]}}" >> "$log"
# SIGTERM (the --signal before the time limit, scancel --signal=TERM, a requeue) goes to the run,
# which writes its checkpoint and stops.
child=
stop() {{ [ -n "$child" ] && kill -TERM "$child" 2>/dev/null; }}
trap stop TERM INT
"$ricochet" "${{args[@]}}" >> "$log" 2>&1 &
child=$!
while :; do
  wait "$child"
  code=$?
  kill -0 "$child" 2>/dev/null || break
done
echo "$code" > "$dir/{exit}"
echo "case $id: exit status $code"
# Stopped with a checkpoint: requeue this task; it restarts from the checkpoint.
if [ "$code" = 130 ] || [ "$code" = 143 ]; then
  if [ -f "$dir/out/checkpoint.bin" ]; then
    echo "case $id: interrupted with a checkpoint; requeueing its task"
    scontrol requeue "${{SLURM_ARRAY_JOB_ID}}_${{SLURM_ARRAY_TASK_ID}}"
  fi
fi
exit 0
"#,
        program = quoted_path(&opts.program),
        root = quoted_path(root),
        ids = list.join(" "),
        log = LOG_FILE,
        exit = EXIT_FILE,
    ));
    Ok(text)
}

/// The text of `collect.sh` for the study folder `root` (absolute).
///
/// # Errors
/// [`Error::Study`] for an option that cannot go on an `#SBATCH` line.
pub fn collect_script(name: &str, root: &Path, opts: &SlurmOptions) -> Result<String> {
    let mut sbatch = vec![
        format!("--job-name=ricochet-{name}-collect"),
        format!("--output={}/slurm/logs/collect.out", root.display()),
        "--ntasks=1".into(),
        "--cpus-per-task=1".into(),
    ];
    sbatch.extend(opts.common());
    for s in &sbatch {
        sbatch_safe("the option", s)?;
    }
    let mut text = String::from("#!/bin/bash\n");
    text.push_str(&format!(
        "# Collects the study {name:?} (results.csv, results.json) once its job array has \
         ended:\n# `sbatch --dependency=afterany:<array id> {}`.\n",
        root.join("slurm/collect.sh").display()
    ));
    for s in &sbatch {
        text.push_str(&format!("#SBATCH {s}\n"));
    }
    text.push_str(&format!(
        "exec {} collect {}\n",
        quoted_path(&opts.program),
        quoted_path(root)
    ));
    Ok(text)
}

/// Writes `root/slurm/array.sh` and `root/slurm/collect.sh` (executable) and the folder of the
/// tasks' logs, `root/slurm/logs/`, for the study `name` whose cases are `ids`.
///
/// # Errors
/// As [`array_script`]; [`Error::Write`] when a file cannot be written.
pub fn write_scripts(
    name: &str,
    root: &Path,
    ids: &[String],
    opts: &SlurmOptions,
) -> Result<Scripts> {
    let root = std::fs::canonicalize(root).map_err(|source| Error::Write {
        path: root.to_path_buf(),
        source,
    })?;
    let dir = root.join("slurm");
    crate::output::create_dir(&dir.join("logs"))?;
    let scripts = Scripts {
        array: dir.join("array.sh"),
        collect: dir.join("collect.sh"),
    };
    write_file(&scripts.array, &array_script(name, &root, ids, opts)?)?;
    write_file(&scripts.collect, &collect_script(name, &root, opts)?)?;
    #[cfg(unix)]
    for p in [&scripts.array, &scripts.collect] {
        use std::os::unix::fs::PermissionsExt as _;
        std::fs::set_permissions(p, std::fs::Permissions::from_mode(0o755)).map_err(|source| {
            Error::Write {
                path: p.clone(),
                source,
            }
        })?;
    }
    Ok(scripts)
}

/// Runs `sbatch --parsable ARGS SCRIPT` and returns the job id it printed (the part before a `;`
/// cluster name).
fn sbatch(args: &[String], script: &Path) -> Result<String> {
    let out = Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .arg(script)
        .output()
        .map_err(|e| {
            Error::Study(format!(
                "cannot run sbatch ({e}): is Slurm installed here (sbatch on PATH)?"
            ))
        })?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(Error::Study(format!(
            "sbatch {} failed ({}): {}",
            script.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    let id = stdout
        .lines()
        .next()
        .unwrap_or("")
        .split(';')
        .next()
        .unwrap_or("")
        .trim()
        .to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(Error::Study(format!(
            "sbatch {} printed no job id: {stdout:?}",
            script.display()
        )));
    }
    Ok(id)
}

/// Submits `scripts`: the array, then the collect job dependent on it
/// (`--dependency=afterany:<array id>`).
///
/// # Errors
/// [`Error::Study`] when sbatch cannot be run, fails, or prints no job id.
pub fn submit(scripts: &Scripts) -> Result<Submitted> {
    let array = sbatch(&[], &scripts.array)?;
    let collect = sbatch(
        &[format!("--dependency=afterany:{array}")],
        &scripts.collect,
    )?;
    Ok(Submitted { array, collect })
}

/// Whether the job `id` is still known to the scheduler as pending or running (`squeue`).
///
/// # Errors
/// [`Error::Study`] when squeue cannot be run.
pub fn queued(id: &str) -> Result<bool> {
    let out = Command::new("squeue")
        .args(["-h", "-o", "%T", "-j", id])
        .output()
        .map_err(|e| Error::Study(format!("cannot run squeue: {e}")))?;
    // squeue fails for a job it has already forgotten: no longer queued.
    Ok(out.status.success() && !String::from_utf8_lossy(&out.stdout).trim().is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_array_script_throttles_signals_and_requeues() {
        let mut opts = SlurmOptions::new(PathBuf::from("/opt/ricochet"), Backend::Cpu);
        opts.max_parallel = Some(2);
        opts.gpus_per_task = Some(1);
        opts.time = Some("00:10:00".into());
        opts.partition = Some("gpu".into());
        let ids: Vec<String> = (0..6).map(|i| format!("{i:04}")).collect();
        let s = array_script("grid", Path::new("/s/it's"), &ids, &opts).unwrap();
        for line in [
            "#SBATCH --array=0-5%2",
            "#SBATCH --requeue",
            "#SBATCH --signal=B:TERM@120",
            "#SBATCH --gpus-per-task=1",
            "#SBATCH --time=00:10:00",
            "#SBATCH --partition=gpu",
            "ids=('0000' '0001' '0002' '0003' '0004' '0005')",
            "root='/s/it'\\''s'",
            "scontrol requeue",
            "args=(run --restart \"$dir/out\")",
        ] {
            assert!(s.contains(line), "no {line:?} in\n{s}");
        }
        let c = collect_script("grid", Path::new("/s"), &opts).unwrap();
        assert!(c.contains("exec '/opt/ricochet' collect '/s'"), "{c}");
        opts.partition = Some("a\nb".into());
        assert!(array_script("grid", Path::new("/s"), &ids, &opts).is_err());
        assert!(array_script("grid", Path::new("/s"), &[], &opts).is_err());
    }
}
