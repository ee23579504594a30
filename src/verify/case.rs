//! Verification cases as data: a TOML file under `assets/verification/` holds a scene template,
//! the refinement ladder, the contact methods, and the metrics with their references and pass
//! bounds. Adding a case is adding a file.
//!
//! The template (`[template] scene = '''...'''`) is a scene file in which `${expr}` is replaced, per run, by the value of `expr`:
//! arithmetic (`+ - * / ^`, parentheses, `sqrt`, `ln`, `exp`, `abs`, `pi`) over the case's `[vars]`, the
//! level's variables, and `method` (the contact method, as text); `${method_keys}` is replaced by
//! the method's entry of the `[method_keys]` table (extra scene lines, e.g. a penalty scale).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Error, Result};

/// A verification case, as read from its file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// What the case is and where its reference comes from.
    pub case: CaseInfo,
    /// Named constants available to the template and the metrics' expressions.
    #[serde(default)]
    pub vars: BTreeMap<String, f64>,
    /// The refinement ladders: `quick` (a few levels, for the test suite) and `full`.
    pub levels: Levels,
    /// The quantities measured, each with its reference and pass bound.
    pub metric: Vec<Metric>,
    /// Extra scene lines per method (`${method_keys}` in the template), e.g. a penalty scale.
    #[serde(default)]
    pub method_keys: BTreeMap<String, String>,
    /// The scene template.
    pub template: Template,
    /// The file the case came from (set when read).
    #[serde(skip)]
    pub file: PathBuf,
}

/// The `[template]` table.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Template {
    /// The scene file, with `${expr}` placeholders.
    pub scene: String,
}

/// The `[case]` table.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseInfo {
    /// Short name (file names, CSV).
    pub name: String,
    /// One-line description for the report.
    pub title: String,
    /// Where the reference values come from.
    pub reference: String,
    /// Contact methods to run (`${method}` in the template); `["none"]` for a case without contact.
    #[serde(default = "default_methods")]
    pub methods: Vec<String>,
    /// The level variable that measures the refinement (elements across the characteristic length).
    pub size: String,
    /// Exponent k of the cost: wall time ~ size^k (2 for a strip of elements, 3 for a 2D mesh);
    /// the plot's reference slopes are -p / k for convergence orders p = 1 and 2.
    pub cost_exponent: f64,
    /// The metric drawn in the plot (default: the first).
    #[serde(default)]
    pub plot: Option<String>,
    /// The backends that run the case (default both): `["cpu"]` for a case whose model the GPU
    /// backend does not run yet (the report says so).
    #[serde(default)]
    pub backends: Option<Vec<String>>,
}

impl CaseInfo {
    /// Whether `backend` ("cpu" or "gpu") runs the case.
    pub fn runs_on(&self, backend: &str) -> bool {
        self.backends
            .as_ref()
            .is_none_or(|b| b.iter().any(|x| x == backend))
    }
}

fn default_methods() -> Vec<String> {
    vec!["none".to_string()]
}

/// The refinement ladders: each level is a table of variables.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Levels {
    /// A short ladder (minutes in all on a 2-core machine); empty for a case too costly for the
    /// test suite (`verify --quick` leaves it out and the report says so).
    pub quick: Vec<BTreeMap<String, f64>>,
    /// The full ladder.
    pub full: Vec<BTreeMap<String, f64>>,
}

/// What a metric measures (the extractors are in [`super::metric`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MetricKind {
    /// Contact duration of `contact`: from the start of the first history interval with a force
    /// to the end of the last (s).
    ContactDuration,
    /// Median |force| of `contact` along `component` over the contact duration (N or N/m).
    PlateauForce,
    /// Largest |force| of `contact` along `component` (N or N/m).
    PeakForce,
    /// Rigid-body velocity of `body` along `component` at the end (m/s).
    BodyVelocity,
    /// -v_end / v_start of `body` along `component`.
    Restitution,
    /// The residual velocity of a projectile `body` along `component` (m/s): its speed at the
    /// end in the direction it started in, 0 when it stopped or turned back (it did not
    /// perforate the target).
    ResidualVelocity,
    /// Contact energy at the end over the initial energy, times `factor`.
    ContactEnergyRatio,
    /// Largest |kinetic + internal + hourglass - E0| / E0 over the run (a conservative run).
    EnergyDrift,
    /// Largest energy-balance error of the run's audit (relative to the largest energy).
    EnergyBalance,
    /// Largest |sigma - sigma_ref| over all elements at the end (sigma_ref = `stress`), in Pa.
    StressError,
    /// Kinetic over internal (strain) energy at the end: how static a dynamic-relaxation run
    /// ended.
    KineticRatio,
    /// |force| of `contact` along `component` in the last history interval (N or N/m): the
    /// resultant a (near-)static run transmits.
    FinalForce,
    /// Largest penetration of `contact` in the last history row (`max_penetration`, m): what a
    /// (near-)static run leaves of its springs' penetration.
    FinalPenetration,
    /// Largest nodal contact pressure between `body` and the rigid wall `contact` at the end (Pa),
    /// from the static nodal balance (see [`super::metric::contact_pressures`]).
    PeakPressure,
    /// Half the length of the loaded part of the surface of `body` on the rigid wall `contact` at
    /// the end (m): half the sum of the tributary lengths (along the wall) of the nodes that touch
    /// it with a positive pressure (see [`super::metric::contact_pressures`]). A node carries its
    /// whole tributary length, so the estimate is within about half an element of the edge.
    ContactHalfWidth,
    /// The error of that half-width against `half_width`, in elements: (a - a_ref) / h, with h
    /// the mean length along the wall of the two surface segments that straddle the edges of the
    /// loaded zone (from the outermost loaded node to the next surface node).
    EdgeError,
    /// Extent of `body` along `component` at the end: largest minus smallest current coordinate
    /// of its nodes (m; the final length of a Taylor bar).
    Extent,
    /// Largest current coordinate of the nodes of `body` along `component` at the end (m; the
    /// impact-face radius of a Taylor bar).
    MaxCoordinate,
    /// Largest equivalent plastic strain of the elements of `body` at the end.
    PeakPlasticStrain,
    /// Thick cylinder under internal pressure (`lame = [a, b, p]`): the largest error of the
    /// radial and hoop stress at the element centres of `body` at the end against the closed form
    /// at the centres' reference radii (Pa; REFERENCES.md section 9).
    LameStressError,
    /// The same for the radial displacement of the nodes (m).
    LameDisplacementError,
    /// Uniaxial plane strain of a J2 body along y (REFERENCES.md section 10): the largest
    /// |sigma_vm - closed form| over the elements of `body` at the end (Pa), at the strain
    /// 1 - (extent along y) / (reference extent).
    UniaxialJ2Error,
    /// When the velocity of `body` along `component` reaches 0 (s): the zero of the
    /// least-squares line through the rows whose velocity lies between 10 % and 90 % of the
    /// initial one (the sliding phase of a block that decelerates uniformly; the vibrations of
    /// an elastic body average out, and its last creep before it sticks does not count).
    StopTime,
    /// The mass-weighted mean displacement of the nodes of `body` along `component` at the end
    /// (m): how far its centre of mass moved.
    Displacement,
    /// The work dissipated by friction at the end (`friction_work`, J or J/m).
    FrictionWork,
    /// The least-squares slope of the velocity of `body` along `component` over the history
    /// rows (m/s^2): a constant acceleration.
    Acceleration,
    /// When the first element eroded (s): the time of the first history row whose
    /// `eroded_elements` is not 0 (with a row every step, the t_n of the step whose state met
    /// the failure criterion).
    ErosionTime,
    /// Johnson-Cook thermal softening with adiabatic heating (REFERENCES.md section 11): the
    /// largest |T* - (1 - exp(-k W0(eps_p)))| over the elements of `body` at the end, T* their
    /// homologous temperature and eps_p their equivalent plastic strain, W0 the work of the
    /// room-temperature flow stress to eps_p and k = beta / (rho c_p (T_m - T_r)): the exact
    /// coupled adiabatic solution for m = 1 without the rate term (c = 0).
    ThermalSofteningError,
}

/// A value of a metric (its bound, reference or scale): a number, or an expression over the
/// run's variables (e.g. `"0.9 / n"`).
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum BoundValue {
    /// A number.
    Number(f64),
    /// An expression.
    Expr(String),
}

impl BoundValue {
    /// The value for a run's variables.
    ///
    /// # Errors
    /// A message when the expression cannot be evaluated.
    pub fn value(&self, vars: &BTreeMap<String, f64>) -> std::result::Result<f64, String> {
        match self {
            BoundValue::Number(x) => Ok(*x),
            BoundValue::Expr(e) => eval(e, vars),
        }
    }
}

impl std::fmt::Display for BoundValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BoundValue::Number(x) => write!(f, "{x:.1e}"),
            BoundValue::Expr(e) => write!(f, "{e}"),
        }
    }
}

/// A bound: one for all runs, or a table keyed by `method.backend`, `method` or `backend`
/// (looked up in that order; runs with no entry are reported, not judged).
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum Bound {
    /// The same bound for every run.
    All(BoundValue),
    /// Bounds by method and backend.
    Keyed(BTreeMap<String, BoundValue>),
}

impl Bound {
    /// The bound of a run, if it is judged.
    ///
    /// # Errors
    /// A message when the bound's expression cannot be evaluated.
    pub fn get(
        &self,
        method: &str,
        backend: &str,
        vars: &BTreeMap<String, f64>,
    ) -> Option<std::result::Result<f64, String>> {
        let v = match self {
            Bound::All(b) => Some(b),
            Bound::Keyed(m) => m
                .get(&format!("{method}.{backend}"))
                .or_else(|| m.get(method))
                .or_else(|| m.get(backend)),
        };
        v.map(|b| b.value(vars))
    }
}

impl std::fmt::Display for Bound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Bound::All(b) => write!(f, "{b}"),
            Bound::Keyed(m) => {
                let parts: Vec<String> = m.iter().map(|(k, v)| format!("{k}: {v}")).collect();
                write!(f, "{}", parts.join(", "))
            }
        }
    }
}

/// One `[[metric]]` table.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Metric {
    /// Name in the CSV and report.
    pub name: String,
    /// What is measured.
    pub kind: MetricKind,
    /// The reference value: a number, or an expression over the run's variables (a reference
    /// that depends on a level's variables, e.g. a residual velocity on the striking velocity).
    pub reference: BoundValue,
    /// The error is |value - reference| / scale (default: |reference|, or 1 when it is 0); a
    /// number or an expression, > 0.
    #[serde(default)]
    pub scale: Option<BoundValue>,
    /// Pass bound on that error at the finest level (every level with `every_level`); absent:
    /// reported, not judged.
    #[serde(default)]
    pub bound: Option<Bound>,
    /// Judge every level, not only the finest.
    #[serde(default)]
    pub every_level: bool,
    /// Only for these methods (default: all).
    #[serde(default)]
    pub methods: Option<Vec<String>>,
    /// The contact or wall (by name) for force and duration metrics.
    #[serde(default)]
    pub contact: Option<String>,
    /// The body for velocity and contact-pressure metrics.
    #[serde(default)]
    pub body: Option<String>,
    /// "x" or "y" (default "x").
    #[serde(default)]
    pub component: Option<String>,
    /// Multiplier (an expression over the variables) for `contact_energy_ratio`.
    #[serde(default)]
    pub factor: Option<String>,
    /// Reference stress [xx, yy, xy] (Pa) for `stress_error`.
    #[serde(default)]
    pub stress: Option<[f64; 3]>,
    /// Reference contact half-width (m) for `edge_error`.
    #[serde(default)]
    pub half_width: Option<f64>,
    /// Inner radius, outer radius and internal pressure [a, b, p] (m, m, Pa) for the Lame
    /// metrics.
    #[serde(default)]
    pub lame: Option<[f64; 3]>,
}

impl Metric {
    /// Whether the metric applies to `method`.
    pub fn applies(&self, method: &str) -> bool {
        self.methods
            .as_ref()
            .is_none_or(|m| m.iter().any(|x| x == method))
    }

    /// The component index (0 = x, 1 = y).
    pub fn component_index(&self) -> usize {
        usize::from(self.component.as_deref() == Some("y"))
    }
}

impl Case {
    /// Reads and checks a case file.
    ///
    /// # Errors
    /// [`Error::Parse`] when the file cannot be read (missing, not a regular file, over
    /// [`crate::scene::SCENE_MAX_BYTES`]) or parsed, [`Error::Invalid`] naming the file and key.
    pub fn read(path: &Path) -> Result<Case> {
        let parse = |message: String| Error::Parse {
            file: path.to_path_buf(),
            message,
        };
        let bytes =
            crate::input::read_capped(path, crate::scene::SCENE_MAX_BYTES).map_err(parse)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            parse(format!(
                "not UTF-8 text (byte {})",
                e.utf8_error().valid_up_to()
            ))
        })?;
        Self::parse(&text, path)
    }

    /// Parses and checks a case (the template is expanded once per level to catch bad expressions).
    ///
    /// # Errors
    /// [`Error::Parse`] or [`Error::Invalid`] naming the file and key.
    pub fn parse(text: &str, path: &Path) -> Result<Case> {
        let mut case: Case = toml::from_str(text).map_err(|e| Error::Parse {
            file: path.to_path_buf(),
            message: crate::scene::toml_message(text, &e),
        })?;
        case.file = path.to_path_buf();
        let invalid = |key: &str, value: String, reason: &str| Error::Invalid {
            file: path.to_path_buf(),
            key: key.to_string(),
            value,
            reason: reason.to_string(),
        };
        if case.levels.full.is_empty() {
            return Err(invalid(
                "levels.full",
                "[]".into(),
                "needs at least one level",
            ));
        }
        if case.case.methods.is_empty() {
            return Err(invalid(
                "case.methods",
                "[]".into(),
                "needs at least one method",
            ));
        }
        if case.case.cost_exponent.is_nan() || case.case.cost_exponent <= 0.0 {
            return Err(invalid(
                "case.cost_exponent",
                case.case.cost_exponent.to_string(),
                "must be > 0",
            ));
        }
        if case.metric.is_empty() {
            return Err(invalid("metric", "[]".into(), "needs at least one metric"));
        }
        if let Some(p) = &case.case.plot {
            if !case.metric.iter().any(|m| &m.name == p) {
                return Err(invalid("case.plot", p.clone(), "names no metric"));
            }
        }
        for (k, m) in case.metric.iter().enumerate() {
            let need = |what: &str, ok: bool| {
                if ok {
                    Ok(())
                } else {
                    Err(invalid(
                        &format!("metric[{k}].{what}"),
                        "(missing)".into(),
                        &format!("required for kind {:?}", m.kind),
                    ))
                }
            };
            use MetricKind as K;
            match m.kind {
                K::ContactDuration
                | K::PlateauForce
                | K::PeakForce
                | K::FinalForce
                | K::FinalPenetration => need("contact", m.contact.is_some())?,
                K::BodyVelocity | K::Restitution | K::ResidualVelocity => {
                    need("body", m.body.is_some())?
                }
                K::PeakPressure | K::ContactHalfWidth | K::EdgeError => {
                    need("body", m.body.is_some())?;
                    need("contact", m.contact.is_some())?;
                    if m.kind == K::EdgeError {
                        need("half_width", m.half_width.is_some())?
                    }
                }
                K::StressError => need("stress", m.stress.is_some())?,
                K::Extent
                | K::MaxCoordinate
                | K::PeakPlasticStrain
                | K::UniaxialJ2Error
                | K::ThermalSofteningError
                | K::StopTime
                | K::Displacement
                | K::Acceleration => need("body", m.body.is_some())?,
                K::LameStressError | K::LameDisplacementError => {
                    need("body", m.body.is_some())?;
                    need("lame", m.lame.is_some())?
                }
                K::ContactEnergyRatio
                | K::EnergyDrift
                | K::EnergyBalance
                | K::KineticRatio
                | K::FrictionWork
                | K::ErosionTime => {}
            }
            if let Some(c) = &m.component {
                if c != "x" && c != "y" {
                    return Err(invalid(
                        &format!("metric[{k}].component"),
                        format!("{c:?}"),
                        "must be \"x\" or \"y\"",
                    ));
                }
            }
            if let Some(BoundValue::Number(s)) = m.scale {
                if s.is_nan() || s <= 0.0 {
                    return Err(invalid(
                        &format!("metric[{k}].scale"),
                        s.to_string(),
                        "must be > 0",
                    ));
                }
            }
        }
        for (ladder, levels) in [("quick", &case.levels.quick), ("full", &case.levels.full)] {
            for (i, level) in levels.iter().enumerate() {
                if !level.contains_key(&case.case.size) {
                    return Err(invalid(
                        &format!("levels.{ladder}[{i}]"),
                        format!("{level:?}"),
                        &format!("has no `{}` (case.size)", case.case.size),
                    ));
                }
                for method in &case.case.methods {
                    case.expand(level, method).map_err(|reason| {
                        invalid(&format!("scene (levels.{ladder}[{i}])"), reason, "")
                    })?;
                    let vars = case.variables(level);
                    for (k, m) in case.metric.iter().enumerate() {
                        for backend in ["cpu", "gpu"] {
                            let b = m.bound.as_ref().and_then(|b| b.get(method, backend, &vars));
                            if let Some(Err(reason)) = b {
                                return Err(invalid(
                                    &format!("metric[{k}].bound"),
                                    format!("{:?}", m.bound),
                                    &reason,
                                ));
                            }
                        }
                        if let Some(f) = &m.factor {
                            eval(f, &vars).map_err(|reason| {
                                invalid(&format!("metric[{k}].factor"), f.clone(), &reason)
                            })?;
                        }
                        for (key, v) in [
                            ("reference", Some(&m.reference)),
                            ("scale", m.scale.as_ref()),
                        ] {
                            if let Some(BoundValue::Expr(e)) = v {
                                eval(e, &vars).map_err(|reason| {
                                    invalid(&format!("metric[{k}].{key}"), e.clone(), &reason)
                                })?;
                            }
                        }
                    }
                }
            }
        }
        Ok(case)
    }

    /// The variables of one run: the case's, then the level's.
    pub fn variables(&self, level: &BTreeMap<String, f64>) -> BTreeMap<String, f64> {
        let mut v = self.vars.clone();
        v.extend(level.iter().map(|(k, x)| (k.clone(), *x)));
        v
    }

    /// The scene text of one run.
    ///
    /// # Errors
    /// A message naming the bad placeholder.
    pub fn expand(
        &self,
        level: &BTreeMap<String, f64>,
        method: &str,
    ) -> std::result::Result<String, String> {
        let vars = self.variables(level);
        let keys = self.method_keys.get(method).map_or("", String::as_str);
        let scene = self.template.scene.replace("${method_keys}", keys);
        let mut out = String::with_capacity(scene.len());
        let mut rest = scene.as_str();
        while let Some(i) = rest.find("${") {
            out.push_str(&rest[..i]);
            let after = &rest[i + 2..];
            let j = after.find('}').ok_or_else(|| {
                format!("unclosed `${{` in {:?}", &rest[i..rest.len().min(i + 30)])
            })?;
            let expr = after[..j].trim();
            if expr == "method" {
                out.push_str(method);
            } else {
                let x = eval(expr, &vars).map_err(|e| format!("`${{{expr}}}`: {e}"))?;
                out.push_str(&number(x));
            }
            rest = &after[j + 1..];
        }
        out.push_str(rest);
        Ok(out)
    }
}

/// A number as TOML: integers without a fraction, others in exponent form.
fn number(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        format!("{x:e}")
    }
}

/// Evaluates an arithmetic expression over `vars`.
///
/// # Errors
/// A message naming the unknown variable or the syntax error.
pub fn eval(expr: &str, vars: &BTreeMap<String, f64>) -> std::result::Result<f64, String> {
    let tokens = tokenize(expr)?;
    let mut p = Parser {
        tokens,
        pos: 0,
        vars,
    };
    let x = p.sum()?;
    if p.pos != p.tokens.len() {
        return Err(format!("unexpected {:?}", p.tokens[p.pos]));
    }
    if !x.is_finite() {
        return Err(format!("not finite ({x})"));
    }
    Ok(x)
}

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Num(f64),
    Name(String),
    Op(char),
}

fn tokenize(s: &str) -> std::result::Result<Vec<Token>, String> {
    let mut out = Vec::new();
    let b: Vec<char> = s.chars().collect();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || c == '.' {
            let start = i;
            while i < b.len()
                && (b[i].is_ascii_digit()
                    || b[i] == '.'
                    || ((b[i] == 'e' || b[i] == 'E') && i > start)
                    || ((b[i] == '-' || b[i] == '+') && (b[i - 1] == 'e' || b[i - 1] == 'E')))
            {
                i += 1;
            }
            let t: String = b[start..i].iter().collect();
            out.push(Token::Num(
                t.parse().map_err(|_| format!("bad number {t:?}"))?,
            ));
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < b.len() && (b[i].is_alphanumeric() || b[i] == '_') {
                i += 1;
            }
            out.push(Token::Name(b[start..i].iter().collect()));
        } else if "+-*/^()".contains(c) {
            out.push(Token::Op(c));
            i += 1;
        } else {
            return Err(format!("unexpected character {c:?}"));
        }
    }
    Ok(out)
}

struct Parser<'a> {
    tokens: Vec<Token>,
    pos: usize,
    vars: &'a BTreeMap<String, f64>,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Token> {
        self.tokens.get(self.pos)
    }

    fn op(&mut self, c: char) -> bool {
        if self.peek() == Some(&Token::Op(c)) {
            self.pos += 1;
            true
        } else {
            false
        }
    }

    fn sum(&mut self) -> std::result::Result<f64, String> {
        let mut x = self.product()?;
        loop {
            if self.op('+') {
                x += self.product()?;
            } else if self.op('-') {
                x -= self.product()?;
            } else {
                return Ok(x);
            }
        }
    }

    fn product(&mut self) -> std::result::Result<f64, String> {
        let mut x = self.power()?;
        loop {
            if self.op('*') {
                x *= self.power()?;
            } else if self.op('/') {
                x /= self.power()?;
            } else {
                return Ok(x);
            }
        }
    }

    fn power(&mut self) -> std::result::Result<f64, String> {
        let x = self.unary()?;
        if self.op('^') {
            Ok(x.powf(self.power()?))
        } else {
            Ok(x)
        }
    }

    fn unary(&mut self) -> std::result::Result<f64, String> {
        if self.op('-') {
            return Ok(-self.unary()?);
        }
        if self.op('+') {
            return self.unary();
        }
        self.atom()
    }

    fn atom(&mut self) -> std::result::Result<f64, String> {
        match self.tokens.get(self.pos).cloned() {
            Some(Token::Num(x)) => {
                self.pos += 1;
                Ok(x)
            }
            Some(Token::Op('(')) => {
                self.pos += 1;
                let x = self.sum()?;
                if !self.op(')') {
                    return Err("missing `)`".into());
                }
                Ok(x)
            }
            Some(Token::Name(n)) => {
                self.pos += 1;
                if self.op('(') {
                    let x = self.sum()?;
                    if !self.op(')') {
                        return Err("missing `)`".into());
                    }
                    return match n.as_str() {
                        "sqrt" => Ok(x.sqrt()),
                        "ln" => Ok(x.ln()),
                        "exp" => Ok(x.exp()),
                        "abs" => Ok(x.abs()),
                        _ => Err(format!("unknown function `{n}`")),
                    };
                }
                if n == "pi" {
                    return Ok(std::f64::consts::PI);
                }
                self.vars
                    .get(&n)
                    .copied()
                    .ok_or_else(|| format!("unknown variable `{n}`"))
            }
            other => Err(format!("expected a value, found {other:?}")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expressions_evaluate_with_precedence_and_variables() {
        let mut v = BTreeMap::new();
        v.insert("n".to_string(), 20.0);
        v.insert("L".to_string(), 1.0);
        assert_eq!(eval("1 + 2 * 3", &v), Ok(7.0));
        assert_eq!(eval("(1 + 2) * 3", &v), Ok(9.0));
        assert_eq!(eval("2 ^ 3 ^ 2", &v), Ok(512.0));
        assert_eq!(eval("-L / n", &v), Ok(-0.05));
        assert_eq!(eval("4 * n", &v), Ok(80.0));
        assert_eq!(eval("sqrt(16) + 1e-1", &v), Ok(4.1));
        assert_eq!(eval("2.5E2", &v), Ok(250.0));
        assert!(eval("m + 1", &v)
            .unwrap_err()
            .contains("unknown variable `m`"));
        assert!(eval("1 / 0", &v).is_err());
        assert!(eval("(1", &v).is_err());
        assert_eq!(number(40.0), "40");
        assert_eq!(number(3.5e-4), "3.5e-4");
    }
}
