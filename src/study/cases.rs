//! A study's cases: their parameter values (a grid, lists side by side, a seeded Latin
//! hypercube; a threshold search adds its own), each case's scene materialised from the base
//! scene with its overrides ([`crate::scene::overrides`]) and checked as `ricochet check` checks a
//! scene, and the study's folder: `DIR/study.json` (what `collect` reads), and per case
//! `DIR/cases/<id>/scene.toml` and `manifest.json`. A rerun of a study into its folder keeps the
//! cases that are unchanged and refuses a study whose cases changed. Host-side only, no GPU twin.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use toml::Value;

use super::spec::{Figure, Kind, Study, Values, MAX_CASES};
use crate::error::{Error, Result};
use crate::scene::overrides::{self, shown, Override};
use crate::scene::Scene;

/// One run of a study: its parameters' values.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Its position in the study (the Slurm array index).
    pub index: usize,
    /// Its folder's name under `DIR/cases/` (`0003`).
    pub id: String,
    /// One value per parameter of the study, in order.
    pub values: Vec<Value>,
}

/// Digits of case ids: 4, or more for studies of more than 10^4 cases.
pub fn id_width(cases: usize) -> usize {
    cases.saturating_sub(1).to_string().len().max(4)
}

/// The id of case `index` at `width` digits.
pub fn case_id(index: usize, width: usize) -> String {
    format!("{index:0width$}")
}

/// splitmix64: the generator of the Latin hypercube (documented so that a sample can be
/// reproduced elsewhere).
#[derive(Debug, Clone)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) (53 bits).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// A Latin hypercube of `samples` points in `dims` dimensions on [0, 1): for each dimension in
/// turn, a random permutation of the strata 0..samples (Fisher-Yates from the top), then for each
/// sample a point uniform in its stratum, (k + u) / samples; all draws from one
/// [`SplitMix64`] seeded with `seed`. `points[i][d]` is sample i's coordinate d.
pub fn latin_hypercube(samples: usize, dims: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = SplitMix64(seed);
    let mut points = vec![vec![0.0; dims]; samples];
    for d in 0..dims {
        let mut strata: Vec<usize> = (0..samples).collect();
        for i in (1..samples).rev() {
            let j = rng.below(i + 1);
            strata.swap(i, j);
        }
        for (i, p) in points.iter_mut().enumerate() {
            p[d] = (strata[i] as f64 + rng.unit()) / samples as f64;
        }
    }
    points
}

impl Study {
    /// The cases of a grid, zip or Latin hypercube study, in order (none for a threshold
    /// search, whose cases come from [`super::threshold`]).
    pub fn cases(&self) -> Vec<Case> {
        let lists: Vec<&[Value]> = self
            .parameters
            .iter()
            .map(|p| match &p.values {
                Values::List(v) => v.as_slice(),
                _ => &[],
            })
            .collect();
        let values: Vec<Vec<Value>> = match &self.kind {
            Kind::Grid => {
                let n: usize = lists.iter().map(|l| l.len()).product();
                (0..n)
                    .map(|mut i| {
                        let mut row = vec![Value::Integer(0); lists.len()];
                        for (d, l) in lists.iter().enumerate().rev() {
                            row[d] = l[i % l.len()].clone();
                            i /= l.len();
                        }
                        row
                    })
                    .collect()
            }
            Kind::Zip => (0..lists[0].len())
                .map(|i| lists.iter().map(|l| l[i].clone()).collect())
                .collect(),
            Kind::Lhs { samples, seed } => latin_hypercube(*samples, self.parameters.len(), *seed)
                .into_iter()
                .map(|point| {
                    point
                        .iter()
                        .zip(&self.parameters)
                        .map(|(&u, p)| match p.values {
                            Values::Interval {
                                min,
                                max,
                                log: false,
                            } => Value::Float(min + u * (max - min)),
                            Values::Interval {
                                min,
                                max,
                                log: true,
                            } => Value::Float((min.ln() + u * (max.ln() - min.ln())).exp()),
                            _ => Value::Float(f64::NAN),
                        })
                        .collect()
                })
                .collect(),
            Kind::Threshold(_) => Vec::new(),
        };
        let width = self.id_width();
        values
            .into_iter()
            .enumerate()
            .map(|(index, values)| Case {
                index,
                id: case_id(index, width),
                values,
            })
            .collect()
    }

    /// Digits of this study's case ids (a threshold search's cases are at most [`MAX_CASES`]).
    pub fn id_width(&self) -> usize {
        let n = match &self.kind {
            Kind::Grid => self
                .parameters
                .iter()
                .map(|p| match &p.values {
                    Values::List(v) => v.len(),
                    _ => 1,
                })
                .product(),
            Kind::Zip => match &self.parameters[0].values {
                Values::List(v) => v.len(),
                _ => 1,
            },
            Kind::Lhs { samples, .. } => *samples,
            Kind::Threshold(_) => 1,
        };
        id_width(n.min(MAX_CASES))
    }

    /// The overrides of `case`: each parameter's key set to the case's value.
    pub fn overrides(&self, case: &Case) -> Vec<Override> {
        self.parameters
            .iter()
            .zip(&case.values)
            .map(|(p, v)| Override {
                key: p.key.clone(),
                value: v.clone(),
            })
            .collect()
    }

    /// The scene of `case`, materialised: the base scene with the case's overrides
    /// ([`overrides::materialise`]: written back as TOML, Gmsh paths absolute), and
    /// `run.checkpoint_interval` set (the study's, else the scene's, else a tenth of the case's
    /// `run.end_time`) so that an interrupted or requeued case continues from its checkpoint.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the study file, the override's key and value, and the case,
    /// when a key cannot be set; [`Error::Parse`] for a base scene that is not TOML.
    pub fn materialise(&self, case: &Case) -> Result<String> {
        let overrides = self.overrides(case);
        let text = overrides::materialise(&self.scene_text, &self.scene, &overrides)
            .map_err(|e| self.case_error(case, &overrides, e))?;
        let mut table: toml::Table = toml::from_str(&text).map_err(|e| Error::Parse {
            file: self.scene.clone(),
            message: e.to_string(),
        })?;
        if let Some(Value::Table(run)) = table.get_mut("run") {
            let end = run
                .get("end_time")
                .and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)));
            let interval = self
                .checkpoint_interval
                .or_else(|| run.get("checkpoint_interval").and_then(Value::as_float))
                .or_else(|| end.filter(|t| t.is_finite() && *t > 0.0).map(|t| t / 10.0));
            if let Some(t) = interval {
                run.insert("checkpoint_interval".into(), Value::Float(t));
            }
        }
        toml::to_string(&table).map_err(|e| Error::Parse {
            file: self.scene.clone(),
            message: format!("cannot write case {}'s scene back as TOML: {e}", case.id),
        })
    }

    /// Checks the materialised scene `text` of `case` (to be read as `path`) as `ricochet
    /// check` checks a scene: the scene's validation, its memory, model and limits
    /// ([`crate::run::model_and_plan`]).
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the study file, the key and value of the override the scene
    /// refused (or every override of the case when the refusal names none of them), and in its
    /// reason the case and the scene's own message.
    pub fn check_case(&self, case: &Case, text: &str, path: &Path) -> Result<()> {
        let checked =
            Scene::parse(text, path).and_then(|scene| crate::run::model_and_plan(&scene).map(drop));
        checked.map_err(|e| self.case_error(case, &self.overrides(case), e))
    }

    /// `e`, an error of case `case`'s scene, as the study's: naming the study file, the
    /// override the error is about (the one whose key the scene's message names, or all of
    /// them) and the case.
    fn case_error(&self, case: &Case, overrides: &[Override], e: Error) -> Error {
        // Each override's key as the scene names it (`body[0].initial_velocity[0]`).
        let mut tree: toml::Table = toml::from_str(&self.scene_text).unwrap_or_default();
        let resolved: Vec<Option<String>> = overrides
            .iter()
            .map(|o| overrides::apply(&mut tree, &o.key, o.value.clone()).ok())
            .collect();
        let about = match &e {
            Error::Invalid { key, .. } => overrides.iter().zip(&resolved).position(|(o, r)| {
                key == &o.key.text
                    || r.as_ref().is_some_and(|r| {
                        key == r || key.starts_with(&format!("{r}.")) || r.starts_with(key)
                    })
            }),
            Error::Parse { message, .. } => overrides.iter().position(|o| {
                matches!(o.key.segments.last(), Some(overrides::Segment::Key(k))
                    if message.contains(&format!("`{k}`")))
            }),
            _ => None,
        };
        let (key, value) = match about {
            Some(i) => (overrides[i].key.text.clone(), shown(&overrides[i].value)),
            None => (
                overrides
                    .iter()
                    .map(|o| o.key.text.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                overrides
                    .iter()
                    .map(|o| shown(&o.value))
                    .collect::<Vec<_>>()
                    .join(", "),
            ),
        };
        let reason = match e {
            // The override's own refusal already names the key and value.
            Error::Invalid {
                file,
                key: k,
                reason,
                ..
            } if file == self.scene && k == key => format!("case {}: {reason}", case.id),
            other => format!("case {}: {other}", case.id),
        };
        Error::Invalid {
            file: self.file.clone(),
            key,
            value,
            reason,
        }
    }

    /// Every case materialised and checked ([`Study::materialise`], [`Study::check_case`]), as if
    /// in the folder `root`: what `ricochet check STUDY` does. For a threshold search, the two
    /// ends of its bracket.
    ///
    /// # Errors
    /// The first case's error, naming the case, the key and the value.
    pub fn check(&self, root: &Path) -> Result<Vec<Case>> {
        let cases = match &self.kind {
            Kind::Threshold(t) => {
                let width = self.id_width();
                t.bracket
                    .iter()
                    .enumerate()
                    .map(|(index, &x)| self.case_at(index, width, t.parameter, x))
                    .collect()
            }
            _ => self.cases(),
        };
        for case in &cases {
            let text = self.materialise(case)?;
            self.check_case(case, &text, &case_scene(root, &case.id))?;
        }
        Ok(cases)
    }

    /// A case of a threshold search: parameter `searched` at `x`, the others at their one value.
    pub fn case_at(&self, index: usize, width: usize, searched: usize, x: f64) -> Case {
        let values = self
            .parameters
            .iter()
            .enumerate()
            .map(|(i, p)| match &p.values {
                _ if i == searched => Value::Float(x),
                Values::List(v) => v[0].clone(),
                _ => Value::Float(x),
            })
            .collect();
        Case {
            index,
            id: case_id(index, width),
            values,
        }
    }
}

/// The folder of case `id` in the study folder `root`.
pub fn case_dir(root: &Path, id: &str) -> PathBuf {
    root.join("cases").join(id)
}

/// The materialised scene of case `id`.
pub fn case_scene(root: &Path, id: &str) -> PathBuf {
    case_dir(root, id).join("scene.toml")
}

/// The run's output folder of case `id`.
pub fn case_out(root: &Path, id: &str) -> PathBuf {
    case_dir(root, id).join("out")
}

/// `manifest.json` of a case: the study, the case and its parameters.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Manifest {
    /// The study's name.
    pub study: String,
    /// The case's id.
    pub id: String,
    /// Its index in the study.
    pub index: usize,
    /// Each parameter: name, key, value.
    pub parameters: Vec<ManifestParameter>,
}

/// One parameter of a [`Manifest`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ManifestParameter {
    /// Its name.
    pub name: String,
    /// The scene key it overrides.
    pub key: String,
    /// The case's value.
    pub value: serde_json::Value,
}

/// `DIR/study.json`: what `collect`, `plot` and the Slurm script read of a study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// The study's name.
    pub name: String,
    /// The study file (absolute).
    pub study_file: PathBuf,
    /// The base scene (absolute).
    pub scene: PathBuf,
    /// The study's kind (`grid`, `zip`, `lhs`, `threshold`).
    pub kind: String,
    /// The parameters: (name, key).
    pub parameters: Vec<(String, String)>,
    /// The figures collected.
    pub figures: Vec<Figure>,
    /// Digits of the case ids.
    pub id_width: usize,
    /// The cases in order: (id, one value per parameter).
    pub cases: Vec<(String, Vec<serde_json::Value>)>,
}

/// A TOML value as JSON (numbers, strings, booleans, arrays, tables; dates as strings).
pub fn json_value(v: &Value) -> serde_json::Value {
    match v {
        Value::String(s) => serde_json::Value::String(s.clone()),
        Value::Integer(i) => serde_json::Value::from(*i),
        Value::Float(x) => serde_json::Number::from_f64(*x)
            .map_or(serde_json::Value::Null, serde_json::Value::Number),
        Value::Boolean(b) => serde_json::Value::Bool(*b),
        Value::Datetime(d) => serde_json::Value::String(d.to_string()),
        Value::Array(a) => serde_json::Value::Array(a.iter().map(json_value).collect()),
        Value::Table(t) => {
            serde_json::Value::Object(t.iter().map(|(k, v)| (k.clone(), json_value(v))).collect())
        }
    }
}

/// `value` written to `path` as pretty JSON, through a temporary file and a rename.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    })?;
    write_file(path, &(text + "\n"))
}

/// `text` written to `path` through a temporary file and a rename (a crash leaves the old file
/// or the new one, whole).
pub fn write_file(path: &Path, text: &str) -> Result<()> {
    let tmp = path.with_extension("tmp");
    let err = |source| Error::Write {
        path: path.to_path_buf(),
        source,
    };
    std::fs::write(&tmp, text).map_err(err)?;
    std::fs::rename(&tmp, path).map_err(err)
}

/// The study's folder `root` prepared for `cases`: `root/study.json` written, and each case's
/// `scene.toml` and `manifest.json` written unless the case's folder already holds the same
/// scene (a rerun). Returns the cases whose folders were written.
///
/// # Errors
/// [`Error::Invalid`] naming the study file when a case's folder holds another scene than the
/// one the study now makes for it, or a folder under `root/cases/` is not one of the study's
/// cases (the study changed: use another folder, or remove the old one); [`Error::Write`] when a
/// file cannot be written; a case's own errors ([`Study::materialise`], [`Study::check_case`]).
pub fn prepare(study: &Study, root: &Path, cases: &[Case]) -> Result<Vec<String>> {
    let mut texts = Vec::with_capacity(cases.len());
    for case in cases {
        let text = study.materialise(case)?;
        let scene = case_scene(root, &case.id);
        match std::fs::read_to_string(&scene) {
            Ok(old) if old == text => texts.push((case, text, false)),
            Ok(_) => {
                return Err(changed(
                    study,
                    root,
                    &format!(
                        "case {}'s scene.toml differs from the one the study makes now",
                        case.id
                    ),
                ))
            }
            Err(_) => {
                study.check_case(case, &text, &scene)?;
                texts.push((case, text, true));
            }
        }
    }
    if matches!(study.kind, Kind::Grid | Kind::Zip | Kind::Lhs { .. }) {
        if let Ok(entries) = std::fs::read_dir(root.join("cases")) {
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                if !cases.iter().any(|c| c.id == name) {
                    return Err(changed(
                        study,
                        root,
                        &format!("cases/{name} is not one of its {} cases", cases.len()),
                    ));
                }
            }
        }
    }
    crate::output::create_dir(&root.join("cases"))?;
    let mut written = Vec::new();
    for (case, text, new) in texts {
        if !new {
            continue;
        }
        let dir = case_dir(root, &case.id);
        crate::output::create_dir(&dir)?;
        write_file(&dir.join("scene.toml"), &text)?;
        let manifest = Manifest {
            study: study.name.clone(),
            id: case.id.clone(),
            index: case.index,
            parameters: study
                .parameters
                .iter()
                .zip(&case.values)
                .map(|(p, v)| ManifestParameter {
                    name: p.name.clone(),
                    key: p.key.text.clone(),
                    value: json_value(v),
                })
                .collect(),
        };
        write_json(&dir.join("manifest.json"), &manifest)?;
        written.push(case.id.clone());
    }
    Ok(written)
}

/// The refusal of a study whose cases changed in the folder `root`.
fn changed(study: &Study, root: &Path, what: &str) -> Error {
    Error::Invalid {
        file: study.file.clone(),
        key: "study".into(),
        value: format!("{:?}", study.name),
        reason: format!(
            "{} already holds another version of this study ({what}): completed cases are \
             reused only when unchanged; write the changed study to another folder (--out) or \
             remove that one",
            root.display()
        ),
    }
}

/// `root/study.json` for `cases` (in order).
///
/// # Errors
/// [`Error::Write`] when it cannot be written.
pub fn write_record(study: &Study, root: &Path, cases: &[Case]) -> Result<()> {
    let absolute = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    let record = Record {
        name: study.name.clone(),
        study_file: absolute(&study.file),
        scene: absolute(&study.scene),
        kind: study.kind.keyword().into(),
        parameters: study
            .parameters
            .iter()
            .map(|p| (p.name.clone(), p.key.text.clone()))
            .collect(),
        figures: study.figures.clone(),
        id_width: study.id_width(),
        cases: cases
            .iter()
            .map(|c| (c.id.clone(), c.values.iter().map(json_value).collect()))
            .collect(),
    };
    crate::output::create_dir(root)?;
    write_json(&root.join("study.json"), &record)
}

/// `root/study.json`.
///
/// # Errors
/// [`Error::Read`] when it cannot be read (not a study's folder), [`Error::Parse`] when it is
/// not a study record.
pub fn read_record(root: &Path) -> Result<Record> {
    let path = root.join("study.json");
    let text = std::fs::read_to_string(&path).map_err(|source| Error::Read {
        file: path.clone(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|e| Error::Parse {
        file: path,
        message: format!("not a study record (written by `ricochet study`): {e}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latin_hypercube_puts_one_sample_in_each_stratum() {
        let p = latin_hypercube(7, 3, 42);
        for d in 0..3 {
            let mut strata: Vec<usize> = p.iter().map(|x| (x[d] * 7.0) as usize).collect();
            strata.sort_unstable();
            assert_eq!(strata, (0..7).collect::<Vec<_>>());
        }
        assert_eq!(p, latin_hypercube(7, 3, 42));
        assert_ne!(p, latin_hypercube(7, 3, 43));
    }

    #[test]
    fn ids_have_four_digits_or_more() {
        assert_eq!(case_id(3, id_width(12)), "0003");
        assert_eq!(case_id(3, id_width(12_001)), "00003");
        assert_eq!(id_width(10_000), 4);
    }
}
