//! The checks of a study file's tables (added to the scene's `Validator`, whose errors, keywords and
//! finite numbers they use): names, keywords, counts, each
//! `[[parameter]]`, `[[collect]]` and `[threshold]` against the others, and the number of cases;
//! each refusal an [`crate::error::Error::Invalid`] naming the study file, the key and the value. What
//! [`super::spec::Study::parse`] calls. Host-side only, no GPU twin.

use toml::Value;

use super::spec::{
    range_values, Condition, Figure, Kind, Parameter, RawCollect, RawParameter, RawRange,
    RawThreshold, Reduce, Source, Study, Threshold, Values, MAX_CASES, NAME_MAX, SUMMARY_NUMBERS,
};
use crate::error::Result;
use crate::scene::overrides::{shown, KeyPath};
use crate::scene::validate::Validator;

impl Validator<'_> {
    /// A study, parameter or figure name: 1 to [`NAME_MAX`] ASCII letters, digits, `_`, `-`,
    /// `.` or `[`, `]` (key paths as names), not starting with `.` or `-`.
    pub(super) fn name(&self, key: &str, name: &str) -> Result<String> {
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

    /// A count in 1..=[`MAX_CASES`] at `key` (required for `kind`).
    pub(super) fn count(&self, key: &str, n: Option<i64>, kind: &str) -> Result<usize> {
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

    /// `[[parameter]]` number `i` of a study of kind `kind`.
    pub(super) fn parameter(&self, i: usize, p: &RawParameter, kind: &str) -> Result<Parameter> {
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
    pub(super) fn range(&self, i: usize, r: &RawRange) -> Result<Vec<Value>> {
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
    pub(super) fn figure(&self, i: usize, c: &RawCollect) -> Result<Figure> {
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
    pub(super) fn threshold(
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
    pub(super) fn sizes(&self, study: &Study) -> Result<()> {
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
