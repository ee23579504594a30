//! The study file (README, "Studies"): its raw serde tables, the validated [`Study`] and its
//! parts, and the checks of every key, each refusal an [`Error::Invalid`] naming the study file,
//! the key (`parameter[1].range.count`) and the value, as the scene's are. Host-side only, no
//! GPU twin.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use toml::Value;

use crate::error::{Error, Result};
use crate::run::Backend;
use crate::scene::overrides::{shown, KeyPath};
use crate::scene::{toml_message, SCENE_MAX_BYTES};

/// Largest study file read (bytes).
pub const STUDY_MAX_BYTES: u64 = 1 << 20;

/// Most cases a study may have (a grid's product, a list's length, Latin hypercube samples, or a
/// threshold search's runs at most).
pub const MAX_CASES: usize = 100_000;

/// Longest study, parameter or figure name (characters).
pub const NAME_MAX: usize = 64;

/// The numbers of `summary.json` a `[[collect]]` table may name with `summary = "..."`.
pub const SUMMARY_NUMBERS: [&str; 18] = [
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
    "contact_penalty_bounded",
    "history_rows",
];

/// The tables of a study file as written. Unknown keys are errors, as in scene files.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStudy {
    study: RawHeader,
    #[serde(default)]
    parameter: Vec<RawParameter>,
    #[serde(default)]
    collect: Vec<RawCollect>,
    threshold: Option<RawThreshold>,
}

/// `[study]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHeader {
    name: Option<String>,
    scene: String,
    kind: Option<String>,
    samples: Option<i64>,
    seed: Option<i64>,
    backend: Option<String>,
    checkpoint_interval: Option<f64>,
}

/// `[[parameter]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawParameter {
    key: String,
    name: Option<String>,
    values: Option<Vec<Value>>,
    range: Option<RawRange>,
    min: Option<f64>,
    max: Option<f64>,
    log: Option<bool>,
}

/// `[[parameter]] range`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRange {
    from: f64,
    to: f64,
    count: i64,
    #[serde(default)]
    log: bool,
}

/// `[[collect]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCollect {
    name: String,
    summary: Option<String>,
    history: Option<String>,
    reduce: Option<String>,
    time: Option<f64>,
}

/// `[threshold]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawThreshold {
    parameter: Option<String>,
    bracket: [f64; 2],
    tolerance: f64,
    condition: String,
    points_per_round: Option<i64>,
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
    fn parse(text: &str) -> std::result::Result<Self, String> {
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
        let v = Check { file: path };
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

/// Checks the tables of the study file `file`; its errors name that file.
struct Check<'a> {
    file: &'a Path,
}

impl Check<'_> {
    fn invalid(&self, key: impl Into<String>, value: impl Into<String>, reason: &str) -> Error {
        Error::Invalid {
            file: self.file.to_path_buf(),
            key: key.into(),
            value: value.into(),
            reason: reason.to_string(),
        }
    }

    /// A study, parameter or figure name: 1 to [`NAME_MAX`] ASCII letters, digits, `_`, `-`,
    /// `.` or `[`, `]` (key paths as names), not starting with `.` or `-`.
    fn name(&self, key: &str, name: &str) -> Result<String> {
        let ok = !name.is_empty()
            && name.chars().count() <= NAME_MAX
            && !name.starts_with(['.', '-'])
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "_-.[]".contains(c))
            && !(key == "study.name" && name.contains(['[', ']']));
        if ok {
            Ok(name.to_string())
        } else {
            Err(self.invalid(
                key,
                format!("{name:?}"),
                &format!(
                    "must be 1 to {NAME_MAX} ASCII letters, digits, `_`, `-` or `.`, not \
                     starting with `.` or `-`"
                ),
            ))
        }
    }

    fn keyword<T: Copy>(
        &self,
        key: &str,
        word: Option<&str>,
        words: &[(&str, T)],
        expected: &str,
    ) -> Result<T> {
        let found = match word {
            None => words.first(),
            Some(w) => words.iter().find(|(k, _)| *k == w),
        };
        found
            .map(|&(_, t)| t)
            .ok_or_else(|| self.invalid(key, format!("{:?}", word.unwrap_or_default()), expected))
    }

    /// A count in 1..=[`MAX_CASES`] at `key` (required for `kind`).
    fn count(&self, key: &str, n: Option<i64>, kind: &str) -> Result<usize> {
        match n {
            Some(n) if n >= 1 && n as u64 <= MAX_CASES as u64 => Ok(n as usize),
            Some(n) => Err(self.invalid(
                key,
                n.to_string(),
                &format!("must be an integer in 1..={MAX_CASES}"),
            )),
            None => Err(self.invalid(key, "(missing)", &format!("required for kind = {kind:?}"))),
        }
    }

    fn finite(&self, key: &str, x: f64) -> Result<f64> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(key, format!("{x:?}"), "must be a finite number"))
        }
    }

    /// `[[parameter]]` number `i` of a study of kind `kind`.
    fn parameter(&self, i: usize, p: &RawParameter, kind: &str) -> Result<Parameter> {
        let at = |k: &str| format!("parameter[{i}].{k}");
        let key = KeyPath::parse(&p.key)
            .map_err(|reason| self.invalid(at("key"), format!("{:?}", p.key), &reason))?;
        let name = match &p.name {
            Some(n) => self.name(&at("name"), n)?,
            None => self.name(&at("key"), &p.key).map_err(|_| {
                self.invalid(
                    at("name"),
                    "(missing)",
                    &format!(
                        "the key {:?} is longer than {NAME_MAX} characters or has characters a \
                         results.csv column cannot: give the parameter a `name`",
                        p.key
                    ),
                )
            })?,
        };
        let given: Vec<&str> = [
            ("values", p.values.is_some()),
            ("range", p.range.is_some()),
            ("min", p.min.is_some()),
            ("max", p.max.is_some()),
            ("log", p.log.is_some()),
        ]
        .iter()
        .filter(|(_, g)| *g)
        .map(|(k, _)| *k)
        .collect();
        let only = |allowed: &[&str], why: &str| -> Result<()> {
            match given.iter().find(|k| !allowed.contains(k)) {
                Some(k) => Err(self.invalid(at(k), "(given)", why)),
                None => Ok(()),
            }
        };
        let values = match kind {
            "lhs" => {
                only(
                    &["min", "max", "log"],
                    "an lhs parameter is sampled between `min` and `max` (with `log`)",
                )?;
                let (Some(min), Some(max)) = (p.min, p.max) else {
                    return Err(self.invalid(
                        at(if p.min.is_none() { "min" } else { "max" }),
                        "(missing)",
                        "an lhs parameter needs `min` and `max`",
                    ));
                };
                let (min, max) = (self.finite(&at("min"), min)?, self.finite(&at("max"), max)?);
                let log = p.log.unwrap_or(false);
                if max <= min {
                    return Err(self.invalid(at("max"), format!("{max:?}"), "must exceed `min`"));
                }
                if log && min <= 0.0 {
                    return Err(self.invalid(
                        at("min"),
                        format!("{min:?}"),
                        "must be > 0 with `log = true`",
                    ));
                }
                Values::Interval { min, max, log }
            }
            "threshold" if p.values.is_none() && p.range.is_none() => {
                only(
                    &[],
                    "the searched parameter takes its values from [threshold] bracket",
                )?;
                Values::Searched
            }
            _ => {
                only(
                    &["values", "range"],
                    "`min`, `max` and `log` are for kind = \"lhs\"; give `values` or `range`",
                )?;
                match (&p.values, &p.range) {
                    (Some(vals), None) => {
                        if vals.is_empty() || vals.len() > MAX_CASES {
                            return Err(self.invalid(
                                at("values"),
                                format!("({} values)", vals.len()),
                                &format!("must hold 1 to {MAX_CASES} values"),
                            ));
                        }
                        for (k, x) in vals.iter().enumerate() {
                            if let Value::Float(f) = x {
                                if !f.is_finite() {
                                    return Err(self.invalid(
                                        format!("parameter[{i}].values[{k}]"),
                                        shown(x),
                                        "must be a finite number",
                                    ));
                                }
                            }
                        }
                        Values::List(vals.clone())
                    }
                    (None, Some(r)) => Values::List(self.range(i, r)?),
                    (Some(_), Some(_)) => {
                        return Err(self.invalid(
                            at("range"),
                            "(given)",
                            "give `values` or `range`, not both",
                        ))
                    }
                    (None, None) => {
                        return Err(self.invalid(
                            at("values"),
                            "(missing)",
                            "a parameter needs `values = [...]` or `range = { from, to, count }`",
                        ))
                    }
                }
            }
        };
        Ok(Parameter { name, key, values })
    }

    /// `range = { from, to, count, log }` of parameter `i`, expanded: `count` values from `from`
    /// to `to` (both included), evenly spaced (in the logarithm with `log`).
    fn range(&self, i: usize, r: &RawRange) -> Result<Vec<Value>> {
        let at = |k: &str| format!("parameter[{i}].range.{k}");
        let from = self.finite(&at("from"), r.from)?;
        let to = self.finite(&at("to"), r.to)?;
        let count = self.count(&at("count"), Some(r.count), "range")?;
        if r.log && !(from > 0.0 && to > 0.0) {
            return Err(self.invalid(
                at(if from > 0.0 { "to" } else { "from" }),
                format!("{:?}", if from > 0.0 { to } else { from }),
                "must be > 0 with `log = true`",
            ));
        }
        Ok(range_values(from, to, count, r.log)
            .into_iter()
            .map(Value::Float)
            .collect())
    }

    /// `[[collect]]` number `i`.
    fn figure(&self, i: usize, c: &RawCollect) -> Result<Figure> {
        let at = |k: &str| format!("collect[{i}].{k}");
        let name = self.name(&at("name"), &c.name)?;
        let source = match (&c.summary, &c.history) {
            (Some(s), None) => {
                for (k, given) in [("reduce", c.reduce.is_some()), ("time", c.time.is_some())] {
                    if given {
                        return Err(self.invalid(
                            at(k),
                            "(given)",
                            "only with `history` (a summary number is one number)",
                        ));
                    }
                }
                if !SUMMARY_NUMBERS.contains(&s.as_str()) {
                    return Err(self.invalid(
                        at("summary"),
                        format!("{s:?}"),
                        &format!("not a number of summary.json (those: {SUMMARY_NUMBERS:?})"),
                    ));
                }
                Source::Summary(s.clone())
            }
            (None, Some(h)) => {
                if h.is_empty() || h.contains([',', '"', '\n']) {
                    return Err(self.invalid(
                        at("history"),
                        format!("{h:?}"),
                        "must name a column of history.csv (e.g. \"kinetic_energy\", \
                         \"target.vx\")",
                    ));
                }
                let reduce = match c.reduce.as_deref() {
                    Some("final") | None => Reduce::Final,
                    Some("max") => Reduce::Max,
                    Some("min") => Reduce::Min,
                    Some("at") => match c.time {
                        Some(t) if t.is_finite() && t >= 0.0 => Reduce::At(t),
                        Some(t) => {
                            return Err(self.invalid(
                                at("time"),
                                format!("{t:?}"),
                                "must be a finite time >= 0",
                            ))
                        }
                        None => {
                            return Err(self.invalid(
                                at("time"),
                                "(missing)",
                                "reduce = \"at\" needs a `time` (s)",
                            ))
                        }
                    },
                    Some(other) => {
                        return Err(self.invalid(
                            at("reduce"),
                            format!("{other:?}"),
                            "must be \"final\", \"max\", \"min\" or \"at\"",
                        ))
                    }
                };
                if c.time.is_some() && !matches!(reduce, Reduce::At(_)) {
                    return Err(self.invalid(at("time"), "(given)", "only with reduce = \"at\""));
                }
                Source::History {
                    column: h.clone(),
                    reduce,
                }
            }
            _ => {
                return Err(self.invalid(
                    at("summary"),
                    "(missing)",
                    "give `summary = \"<number of summary.json>\"` or `history = \"<column>\"`, \
                     one of the two",
                ))
            }
        };
        Ok(Figure { name, source })
    }

    /// `[threshold]` against the parameters and figures.
    fn threshold(
        &self,
        t: &RawThreshold,
        parameters: &[Parameter],
        figures: &[Figure],
    ) -> Result<Threshold> {
        let searched: Vec<usize> = (0..parameters.len())
            .filter(|&i| parameters[i].values == Values::Searched)
            .collect();
        let parameter = match &t.parameter {
            Some(p) => parameters
                .iter()
                .position(|q| &q.name == p || &q.key.text == p)
                .ok_or_else(|| {
                    let names: Vec<&str> = parameters.iter().map(|q| q.name.as_str()).collect();
                    self.invalid(
                        "threshold.parameter",
                        format!("{p:?}"),
                        &format!("no [[parameter]] of that name or key (names: {names:?})"),
                    )
                })?,
            None => match searched.as_slice() {
                [one] => *one,
                _ => {
                    return Err(self.invalid(
                        "threshold.parameter",
                        "(missing)",
                        "name the [[parameter]] searched (the one without values)",
                    ))
                }
            },
        };
        for (i, p) in parameters.iter().enumerate() {
            let ok = match &p.values {
                Values::Searched => i == parameter,
                Values::List(v) => i != parameter && v.len() == 1,
                Values::Interval { .. } => false,
            };
            if !ok {
                return Err(self.invalid(
                    format!("parameter[{i}]"),
                    format!("{:?}", p.name),
                    "in a threshold study the searched parameter has no values and every other \
                     parameter exactly one (a constant)",
                ));
            }
        }
        let [lo, hi] = t.bracket;
        if !(lo.is_finite() && hi.is_finite() && hi > lo) {
            return Err(self.invalid(
                "threshold.bracket",
                format!("{:?}", t.bracket),
                "must be two finite numbers, the lower first",
            ));
        }
        let width = hi - lo;
        let tolerance = t.tolerance;
        if !(tolerance.is_finite() && tolerance > 0.0 && tolerance < width) {
            return Err(self.invalid(
                "threshold.tolerance",
                format!("{tolerance:?}"),
                "must be a positive number below the bracket's width",
            ));
        }
        // Bisection would need more rounds than f64 has digits for.
        if (width / tolerance).log2() > 60.0 || tolerance < 1e-12 * lo.abs().max(hi.abs()) {
            return Err(self.invalid(
                "threshold.tolerance",
                format!("{tolerance:?}"),
                "is below the resolution of the bracket's numbers (1e-12 of them)",
            ));
        }
        let condition = Condition::parse(&t.condition)
            .map_err(|r| self.invalid("threshold.condition", format!("{:?}", t.condition), &r))?;
        if !figures.iter().any(|f| f.name == condition.figure) {
            let names: Vec<&str> = figures.iter().map(|f| f.name.as_str()).collect();
            return Err(self.invalid(
                "threshold.condition",
                format!("{:?}", t.condition),
                &format!(
                    "{:?} is not a collected figure (those: {names:?})",
                    condition.figure
                ),
            ));
        }
        let points_per_round = match t.points_per_round {
            Some(n) if (1..=64).contains(&n) => Some(n as usize),
            Some(n) => {
                return Err(self.invalid(
                    "threshold.points_per_round",
                    n.to_string(),
                    "must be an integer in 1..=64",
                ))
            }
            None => None,
        };
        Ok(Threshold {
            parameter,
            bracket: [lo, hi],
            tolerance,
            condition,
            points_per_round,
        })
    }

    /// The number of cases of `study`, within [`MAX_CASES`]; zip lists of one length.
    fn sizes(&self, study: &Study) -> Result<()> {
        let lens: Vec<usize> = study
            .parameters
            .iter()
            .map(|p| match &p.values {
                Values::List(v) => v.len(),
                _ => 1,
            })
            .collect();
        match &study.kind {
            Kind::Grid => {
                let n = lens
                    .iter()
                    .try_fold(1usize, |acc, &l| acc.checked_mul(l))
                    .filter(|&n| n <= MAX_CASES);
                if n.is_none() {
                    return Err(self.invalid(
                        "parameter",
                        format!("{lens:?} values"),
                        &format!("the grid has more than {MAX_CASES} cases"),
                    ));
                }
            }
            Kind::Zip => {
                if let Some(i) = lens.iter().position(|&l| l != lens[0]) {
                    return Err(self.invalid(
                        format!("parameter[{i}].values"),
                        format!("({} values)", lens[i]),
                        &format!(
                            "a zip study takes the i-th value of every parameter: parameter[0] \
                             has {}",
                            lens[0]
                        ),
                    ));
                }
            }
            Kind::Lhs { .. } | Kind::Threshold(_) => {}
        }
        Ok(())
    }
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
