//! The study file (README, "Studies"): its raw serde tables, the validated [`Study`] and its
//! parts, and [`Study::parse`], which has every key checked by [`super::validate`], each refusal
//! an [`Error::Invalid`] naming the study file, the key (`parameter[1].range.count`) and the
//! value, as the scene's are. Host-side only, no GPU twin.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use toml::Value;

use crate::error::{Error, Result};
use crate::run::Backend;
use crate::scene::overrides::KeyPath;
use crate::scene::validate::Validator;
use crate::scene::{toml_message, SCENE_MAX_BYTES};

/// Largest study file read (bytes).
pub const STUDY_MAX_BYTES: u64 = 1 << 20;

/// Most cases a study may have (a grid's product, a list's length, Latin hypercube samples, or a
/// threshold search's runs at most).
pub const MAX_CASES: usize = 100_000;

/// Longest study, parameter or figure name (characters).
pub const NAME_MAX: usize = 64;

/// The numbers of `summary.json` a `[[collect]]` table may name with `summary = "..."`.
pub const SUMMARY_NUMBERS: [&str; 19] = [
    "nodes",
    "elements",
    "steps",
    "end_time",
    "wall_seconds",
    "element_cycles_per_second",
    "dt_min",
    "dt_max",
    "max_energy_error",
    "gpu_submissions",
    "gpu_readbacks",
    "contact_searches",
    "bytes_read_back",
    "contact_sweeps_mean",
    "contact_sweeps_max",
    "contact_unconverged",
    "contact_residual_max",
    "contact_penalty_bounded",
    "history_rows",
];

/// The tables of a study file as written. Unknown keys are errors, as in scene files.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStudy {
    pub(super) study: RawHeader,
    #[serde(default)]
    pub(super) parameter: Vec<RawParameter>,
    #[serde(default)]
    pub(super) collect: Vec<RawCollect>,
    pub(super) threshold: Option<RawThreshold>,
}

/// `[study]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawHeader {
    pub(super) name: Option<String>,
    pub(super) scene: String,
    pub(super) kind: Option<String>,
    pub(super) samples: Option<i64>,
    pub(super) seed: Option<i64>,
    pub(super) backend: Option<String>,
    pub(super) checkpoint_interval: Option<f64>,
}

/// `[[parameter]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawParameter {
    pub(super) key: String,
    pub(super) name: Option<String>,
    pub(super) values: Option<Vec<Value>>,
    pub(super) range: Option<RawRange>,
    pub(super) min: Option<f64>,
    pub(super) max: Option<f64>,
    pub(super) log: Option<bool>,
}

/// `[[parameter]] range`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRange {
    pub(super) from: f64,
    pub(super) to: f64,
    pub(super) count: i64,
    #[serde(default)]
    pub(super) log: bool,
}

/// `[[collect]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCollect {
    pub(super) name: String,
    pub(super) summary: Option<String>,
    pub(super) history: Option<String>,
    pub(super) reduce: Option<String>,
    pub(super) time: Option<f64>,
}

/// `[threshold]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawThreshold {
    pub(super) parameter: Option<String>,
    pub(super) bracket: [f64; 2],
    pub(super) tolerance: f64,
    pub(super) condition: String,
    pub(super) points_per_round: Option<i64>,
}

/// How a study makes its cases.
#[derive(Debug, Clone, PartialEq)]
pub enum Kind {
    /// Every combination of the parameters' values (the last parameter varies fastest).
    Grid,
    /// The parameters' value lists side by side: case i takes the i-th value of each (`kind =
    /// "zip"` or `"list"`).
    Zip,
    /// A seeded Latin hypercube of `samples` points over the parameters' `min`..`max`.
    Lhs {
        /// Cases.
        samples: usize,
        /// The generator's seed.
        seed: u64,
    },
    /// A search for the value of one parameter at which a condition flips.
    Threshold(Threshold),
}

impl Kind {
    /// The keyword of the study file.
    pub fn keyword(&self) -> &'static str {
        match self {
            Kind::Grid => "grid",
            Kind::Zip => "zip",
            Kind::Lhs { .. } => "lhs",
            Kind::Threshold(_) => "threshold",
        }
    }
}

/// The values a parameter takes.
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    /// These values (`values = [...]`, or a `range` expanded).
    List(Vec<Value>),
    /// An interval sampled by the Latin hypercube (`min`, `max`, `log`).
    Interval {
        /// Lower end.
        min: f64,
        /// Upper end.
        max: f64,
        /// Sampled uniformly in the logarithm.
        log: bool,
    },
    /// The parameter a threshold search varies (its values come from the search).
    Searched,
}

/// A scene key that the study varies.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// Its name in `results.csv` (`name`, or the key's text).
    pub name: String,
    /// The key.
    pub key: KeyPath,
    /// Its values.
    pub values: Values,
}

/// How a history column becomes one figure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reduce {
    /// The last row's value.
    Final,
    /// The largest value.
    Max,
    /// The smallest value.
    Min,
    /// The value at this time, interpolated linearly between the rows around it.
    At(f64),
}

/// Where a figure comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// A number of `summary.json`.
    Summary(String),
    /// A column of `history.csv`, reduced.
    History {
        /// The column.
        column: String,
        /// The reduction.
        reduce: Reduce,
    },
}

/// A figure collected from every case (`[[collect]]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Figure {
    /// Its name (a column of `results.csv`).
    pub name: String,
    /// Where it comes from.
    pub source: Source,
}

/// A comparison of a condition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    /// `<`
    Less,
    /// `<=`
    LessEqual,
    /// `>`
    Greater,
    /// `>=`
    GreaterEqual,
}

/// A condition on a collected figure: `figure op value` (`loss >= 0.1`).
#[derive(Debug, Clone, PartialEq)]
pub struct Condition {
    /// The figure's name.
    pub figure: String,
    /// The comparison.
    pub op: Op,
    /// The number compared with.
    pub value: f64,
    /// The condition as written.
    pub text: String,
}

impl Condition {
    /// Whether the condition holds for the figure's value `x` (false for NaN).
    pub fn holds(&self, x: f64) -> bool {
        match self.op {
            Op::Less => x < self.value,
            Op::LessEqual => x <= self.value,
            Op::Greater => x > self.value,
            Op::GreaterEqual => x >= self.value,
        }
    }

    /// Parses `figure op number` with op one of `<`, `<=`, `>`, `>=`.
    ///
    /// # Errors
    /// The reason when `text` has no operator or its number is not a finite number.
    pub fn parse(text: &str) -> std::result::Result<Self, String> {
        let ops = [
            ("<=", Op::LessEqual),
            (">=", Op::GreaterEqual),
            ("<", Op::Less),
            (">", Op::Greater),
        ];
        let Some((at, len, op)) = ops
            .iter()
            .filter_map(|&(s, op)| text.find(s).map(|i| (i, s.len(), op)))
            .min_by_key(|&(i, len, _)| (i, usize::MAX - len))
        else {
            return Err("expected `figure op number` with op one of <, <=, >, >=".into());
        };
        let figure = text[..at].trim();
        let number = text[at + len..].trim();
        let value: f64 = number
            .parse()
            .map_err(|_| format!("{number:?} is not a number"))?;
        if !value.is_finite() {
            return Err(format!("{number:?} is not a finite number"));
        }
        Ok(Self {
            figure: figure.to_string(),
            op,
            value,
            text: text.trim().to_string(),
        })
    }
}

/// A threshold search (`[threshold]`).
#[derive(Debug, Clone, PartialEq)]
pub struct Threshold {
    /// The parameter searched (an index into [`Study::parameters`]).
    pub parameter: usize,
    /// The interval searched, lower end first.
    pub bracket: [f64; 2],
    /// The search stops when the bracket is at most this wide.
    pub tolerance: f64,
    /// The condition that flips inside the bracket.
    pub condition: Condition,
    /// Points run (in parallel) per round; `None`: one per worker.
    pub points_per_round: Option<usize>,
}

/// A validated study.
#[derive(Debug, Clone)]
pub struct Study {
    /// The study file.
    pub file: PathBuf,
    /// Its text.
    pub text: String,
    /// The study's name (`[study] name`, or the file's stem): the default output folder is
    /// `out/<name>`.
    pub name: String,
    /// The base scene (`[study] scene`, relative to the study file's folder).
    pub scene: PathBuf,
    /// The base scene's text.
    pub scene_text: String,
    /// How the cases are made.
    pub kind: Kind,
    /// The parameters, in order.
    pub parameters: Vec<Parameter>,
    /// The figures collected, in order.
    pub figures: Vec<Figure>,
    /// The backend of the runs (`[study] backend`; the command line's `--backend` wins).
    pub backend: Backend,
    /// `run.checkpoint_interval` of every case (`[study] checkpoint_interval`); `None`: the
    /// scene's, or a tenth of the case's end time.
    pub checkpoint_interval: Option<f64>,
}

impl Study {
    /// Reads and validates a study file, and reads its base scene.
    ///
    /// # Errors
    /// [`Error::Read`] when the file cannot be read, [`Error::Parse`] for TOML and shape errors
    /// (unknown keys included), [`Error::Invalid`] naming the file, the key and the value for a
    /// value out of range or a base scene that cannot be read.
    pub fn load(path: &Path) -> Result<Self> {
        let text = read_text(path, STUDY_MAX_BYTES, "study")?;
        Self::parse(&text, path)
    }

    /// Parses and validates study text of the file `path` (the base scene is read relative to
    /// its folder).
    ///
    /// # Errors
    /// As [`Study::load`], without the read error.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let raw: RawStudy = toml::from_str(text).map_err(|e| Error::Parse {
            file: path.to_path_buf(),
            message: toml_message(text, &e),
        })?;
        let v = Validator { file: path };
        let h = &raw.study;
        let name = match &h.name {
            Some(n) => v.name("study.name", n)?,
            None => {
                let stem = path
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                v.name("study.name", &stem).map_err(|_| {
                    v.invalid(
                        "study.name",
                        format!("{stem:?}"),
                        "is missing, and the file's name is not a valid study name: give \
                         `name` (1 to 64 ASCII letters, digits, `_`, `-` or `.`)",
                    )
                })?
            }
        };
        let scene = path
            .parent()
            .unwrap_or(Path::new(""))
            .join(if h.scene.is_empty() { "." } else { &h.scene });
        let scene_text = read_text(&scene, SCENE_MAX_BYTES, "scene").map_err(|e| {
            v.invalid(
                "study.scene",
                format!("{:?}", h.scene),
                &format!("the base scene cannot be read: {e}"),
            )
        })?;
        let backend = v.keyword(
            "study.backend",
            h.backend.as_deref(),
            &[
                ("auto", Backend::Auto),
                ("cpu", Backend::Cpu),
                ("gpu", Backend::Gpu),
            ],
            "must be \"auto\", \"cpu\" or \"gpu\"",
        )?;
        let checkpoint_interval = match h.checkpoint_interval {
            Some(t) if t.is_finite() && t > 0.0 => Some(t),
            Some(t) => {
                return Err(v.invalid(
                    "study.checkpoint_interval",
                    format!("{t:?}"),
                    "must be a positive finite number of seconds",
                ))
            }
            None => None,
        };
        let kind_word = h.kind.as_deref().unwrap_or("grid");
        let mut parameters = Vec::with_capacity(raw.parameter.len());
        for (i, p) in raw.parameter.iter().enumerate() {
            parameters.push(v.parameter(i, p, kind_word)?);
        }
        if parameters.is_empty() {
            return Err(v.invalid(
                "parameter",
                "[]",
                "a study needs at least one [[parameter]] table (key and values)",
            ));
        }
        for (i, p) in parameters.iter().enumerate() {
            if let Some(j) = parameters[..i].iter().position(|q| q.name == p.name) {
                return Err(v.invalid(
                    format!("parameter[{i}].name"),
                    format!("{:?}", p.name),
                    &format!("parameter[{j}] has the same name (names head results.csv columns)"),
                ));
            }
        }
        let mut figures = Vec::with_capacity(raw.collect.len());
        for (i, c) in raw.collect.iter().enumerate() {
            let f = v.figure(i, c)?;
            let clash = parameters.iter().any(|p| p.name == f.name)
                || figures.iter().any(|g: &Figure| g.name == f.name)
                || ["id", "status"].contains(&f.name.as_str());
            if clash {
                return Err(v.invalid(
                    format!("collect[{i}].name"),
                    format!("{:?}", f.name),
                    "is already a column of results.csv (id, status, a parameter or another \
                     figure)",
                ));
            }
            figures.push(f);
        }
        let kind = match kind_word {
            "grid" => Kind::Grid,
            "zip" | "list" => Kind::Zip,
            "lhs" => Kind::Lhs {
                samples: v.count("study.samples", h.samples, "lhs")?,
                seed: match h.seed {
                    Some(s) if s >= 0 => s as u64,
                    Some(s) => return Err(v.invalid("study.seed", s.to_string(), "must be >= 0")),
                    None => {
                        return Err(v.invalid(
                            "study.seed",
                            "(missing)",
                            "an lhs study needs a seed (an integer >= 0), so that a rerun \
                             makes the same samples",
                        ))
                    }
                },
            },
            "threshold" => {
                let Some(t) = &raw.threshold else {
                    return Err(v.invalid(
                        "threshold",
                        "(missing)",
                        "a threshold study needs a [threshold] table (bracket, tolerance, \
                         condition)",
                    ));
                };
                Kind::Threshold(v.threshold(t, &parameters, &figures)?)
            }
            other => {
                return Err(v.invalid(
                    "study.kind",
                    format!("{other:?}"),
                    "must be \"grid\", \"zip\" (or \"list\"), \"lhs\" or \"threshold\"",
                ))
            }
        };
        if !matches!(kind, Kind::Lhs { .. }) {
            for (key, given) in [("study.samples", h.samples), ("study.seed", h.seed)] {
                if let Some(x) = given {
                    return Err(v.invalid(key, x.to_string(), "only for kind = \"lhs\""));
                }
            }
        }
        if raw.threshold.is_some() && !matches!(kind, Kind::Threshold(_)) {
            return Err(v.invalid(
                "threshold",
                "{...}",
                &format!("only for kind = \"threshold\" (this study is {kind_word:?})"),
            ));
        }
        let study = Study {
            file: path.to_path_buf(),
            text: text.to_string(),
            name,
            scene,
            scene_text,
            kind,
            parameters,
            figures,
            backend,
            checkpoint_interval,
        };
        v.sizes(&study)?;
        Ok(study)
    }
}

/// Whether the file `path` is a study file: TOML with a top-level `[study]` table (a scene has
/// none). False when it cannot be read or is not TOML (the scene's reader then says why).
pub fn is_study_file(path: &Path) -> bool {
    read_text(path, STUDY_MAX_BYTES, "study")
        .ok()
        .and_then(|t| toml::from_str::<toml::Table>(&t).ok())
        .is_some_and(|t| t.get("study").is_some_and(Value::is_table))
}

/// The text of the file `path`, at most `max` bytes of UTF-8.
fn read_text(path: &Path, max: u64, what: &str) -> Result<String> {
    use std::io::Read as _;
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(max + 1).read_to_end(&mut bytes))
        .map_err(|source| Error::Read {
            file: path.to_path_buf(),
            source,
        })?;
    if bytes.len() as u64 > max {
        return Err(Error::Parse {
            file: path.to_path_buf(),
            message: format!("larger than {} KiB: not a {what} file", max >> 10),
        });
    }
    String::from_utf8(bytes).map_err(|e| Error::Parse {
        file: path.to_path_buf(),
        message: format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
    })
}

/// `count` numbers from `from` to `to` (both included; `from` alone when `count` is 1), evenly
/// spaced, or evenly spaced in the logarithm with `log`. The ends are exact.
pub fn range_values(from: f64, to: f64, count: usize, log: bool) -> Vec<f64> {
    (0..count)
        .map(|k| {
            if k == 0 {
                from
            } else if k + 1 == count {
                to
            } else {
                let t = k as f64 / (count - 1) as f64;
                if log {
                    (from.ln() + t * (to.ln() - from.ln())).exp()
                } else {
                    from + t * (to - from)
                }
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conditions_parse_with_their_operator() {
        let c = Condition::parse("loss >= 0.1").unwrap();
        assert_eq!(
            (c.figure.as_str(), c.op, c.value),
            ("loss", Op::GreaterEqual, 0.1)
        );
        assert!(c.holds(0.1) && !c.holds(0.0999));
        let c = Condition::parse("target.vx<-1e-3").unwrap();
        assert_eq!(
            (c.figure.as_str(), c.op, c.value),
            ("target.vx", Op::Less, -1e-3)
        );
        assert!(!c.holds(f64::NAN));
        for bad in ["loss", "loss >= x", "loss >= nan", "loss = 1"] {
            assert!(Condition::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn ranges_include_both_ends() {
        assert_eq!(range_values(1.0, 2.0, 3, false), [1.0, 1.5, 2.0]);
        assert_eq!(range_values(5.0, 9.0, 1, false), [5.0]);
        let r = range_values(1.0, 100.0, 3, true);
        assert_eq!((r[0], r[2]), (1.0, 100.0));
        assert!((r[1] - 10.0).abs() < 1e-12);
    }
}
