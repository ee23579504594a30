//! `[run]`: run control (README, "Scene format", `[run]`): the raw table, [`RunSettings`] with
//! its defaults and [`FieldFormat`], and their validation (bulk viscosity, mass damping, gravity,
//! erosion).
//! Host-side only, no GPU twin.

use serde::Deserialize;

use super::validate::{fmt_num, number, Validator};
use crate::error::Result;

/// Default safety factor on the stable time step.
pub const DEFAULT_TIME_STEP_SCALE: f64 = 0.9;

/// Default linear bulk-viscosity coefficient (as in common explicit codes).
pub const DEFAULT_BULK_LINEAR: f64 = 0.06;

/// Default quadratic bulk-viscosity coefficient.
pub const DEFAULT_BULK_QUADRATIC: f64 = 1.5;

/// Largest quadratic bulk-viscosity coefficient.
pub const BULK_QUADRATIC_MAX: f64 = 10.0;

/// Default bound on the relative energy-balance error before a run is stopped.
pub const DEFAULT_ENERGY_ERROR_LIMIT: f64 = 0.05;

/// The `[run]` table as written (`gravity` kept as a TOML value, its shape checked below).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawRun {
    end_time: f64,
    time_step_scale: Option<f64>,
    time_step: Option<f64>,
    history_interval: Option<f64>,
    field_interval: Option<f64>,
    field_format: Option<String>,
    checkpoint_interval: Option<f64>,
    energy_error_limit: Option<f64>,
    bulk_viscosity: Option<RawBulk>,
    mass_damping: Option<f64>,
    gravity: Option<toml::Value>,
    gravity_ramp: Option<f64>,
    erosion: Option<toml::Value>,
}

/// The `bulk_viscosity` table of `[run]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBulk {
    linear: Option<f64>,
    quadratic: Option<f64>,
}

/// Encoding of the VTU field files (`run.field_format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FieldFormat {
    /// Raw appended binary data, zlib-compressed, real numbers in single precision (`"binary"`,
    /// the default).
    #[default]
    Binary,
    /// As [`FieldFormat::Binary`] with real numbers in double precision (`"binary64"`).
    Binary64,
    /// Human-readable text (`"ascii"`), several times larger and slower to write.
    Ascii,
}

/// Run control, validated.
#[derive(Debug, Clone)]
pub struct RunSettings {
    /// Simulated end time (s).
    pub end_time: f64,
    /// Safety factor on the stable step.
    pub time_step_scale: f64,
    /// Fixed step, if given.
    pub time_step: Option<f64>,
    /// Time between history rows.
    pub history_interval: f64,
    /// Time between field snapshots, if any.
    pub field_interval: Option<f64>,
    /// Encoding of the field files.
    pub field_format: FieldFormat,
    /// Simulated time between checkpoints (`checkpoint.bin` in the output folder), if any.
    pub checkpoint_interval: Option<f64>,
    /// Relative energy-balance error that stops the run.
    pub energy_error_limit: f64,
    /// Linear bulk-viscosity coefficient.
    pub bulk_linear: f64,
    /// Quadratic bulk-viscosity coefficient.
    pub bulk_quadratic: f64,
    /// Mass-proportional damping coefficient alpha (1/s): a force -alpha m v on every node
    /// (0: none).
    pub mass_damping: f64,
    /// Gravity (m/s^2): a body force m g on every node ([0, 0]: none).
    pub gravity: [f64; 2],
    /// Duration of a linear ramp of gravity from 0 (s; 0: gravity in full from t = 0).
    pub gravity_ramp: f64,
    /// `erosion = { inverted = true }`: an element about to invert erodes (as a failed element,
    /// counted apart) instead of stopping the run (false: the run stops naming it).
    pub erode_inverted: bool,
    /// `erosion = { min_time_step = s }`: an element whose stable step, times
    /// `time_step_scale`, falls below `s` seconds erodes (as a failed element, counted apart)
    /// instead of shrinking the run's step (none: no such limit).
    pub erode_min_time_step: Option<f64>,
}

impl Validator<'_> {
    /// The `[run]` table.
    pub(super) fn run(&self, r: &RawRun) -> Result<RunSettings> {
        let end_time = self.positive("run.end_time", r.end_time)?;
        let time_step_scale = match r.time_step_scale {
            Some(s) => {
                let s = self.positive("run.time_step_scale", s)?;
                // Above 1 the step exceeds the stable step: in a rod (1D, where the estimate is
                // exact) the shortest mode grows within a few steps; in 2D, where the element
                // estimate has some reserve, a run may go on for a while and then diverge.
                if s > 1.0 {
                    return Err(self.invalid(
                        "run.time_step_scale",
                        fmt_num(s),
                        "must not exceed 1.0: it multiplies the stable step, and above 1 the \
                         central-difference step is unstable (1.0 is the stability limit itself, \
                         not a production setting; the default is 0.9)",
                    ));
                }
                s
            }
            None => DEFAULT_TIME_STEP_SCALE,
        };
        let time_step = r
            .time_step
            .map(|s| self.positive("run.time_step", s))
            .transpose()?;
        let history_interval = match r.history_interval {
            Some(h) => self.positive("run.history_interval", h)?,
            None => end_time / 1000.0,
        };
        let field_interval = r
            .field_interval
            .map(|f| self.positive("run.field_interval", f))
            .transpose()?;
        let field_format = self.keyword(
            "run.field_format",
            r.field_format.as_deref(),
            &[
                ("binary", FieldFormat::Binary),
                ("binary64", FieldFormat::Binary64),
                ("ascii", FieldFormat::Ascii),
            ],
            "expected \"binary\" (zlib-compressed, single precision, the default), \"binary64\" \
             (the same in double precision) or \"ascii\"",
        )?;
        let checkpoint_interval = r
            .checkpoint_interval
            .map(|c| self.positive("run.checkpoint_interval", c))
            .transpose()?;
        let energy_error_limit = match r.energy_error_limit {
            Some(e) => self.positive("run.energy_error_limit", e)?,
            None => DEFAULT_ENERGY_ERROR_LIMIT,
        };
        let (bulk_linear, bulk_quadratic) = match &r.bulk_viscosity {
            Some(b) => (
                match b.linear {
                    Some(x) => self.non_negative("run.bulk_viscosity.linear", x)?,
                    None => DEFAULT_BULK_LINEAR,
                },
                match b.quadratic {
                    Some(x) => {
                        let x = self.non_negative("run.bulk_viscosity.quadratic", x)?;
                        // The quadratic part shortens the stable step in compression, after
                        // t = 0 (out of reach of the first-step check of `run::check_limits`) and
                        // in proportion to the coefficient: at 9.2e18 the round-off strain rates
                        // of disks in free fall cut the step 350-fold and a run to 1 ms would
                        // take hours.
                        if x > BULK_QUADRATIC_MAX {
                            return Err(self.invalid(
                                "run.bulk_viscosity.quadratic",
                                fmt_num(x),
                                &format!(
                                    "must not exceed {BULK_QUADRATIC_MAX:?} (typical values \
                                     1.0-2.0; it shortens the stable step in compression in \
                                     proportion)"
                                ),
                            ));
                        }
                        x
                    }
                    None => DEFAULT_BULK_QUADRATIC,
                },
            ),
            None => (DEFAULT_BULK_LINEAR, DEFAULT_BULK_QUADRATIC),
        };
        let mass_damping = match r.mass_damping {
            Some(a) => self.non_negative("run.mass_damping", a)?,
            None => 0.0,
        };
        let gravity = match &r.gravity {
            None => [0.0; 2],
            Some(v) => {
                let pair = v.as_array().and_then(|a| match a.as_slice() {
                    [x, y] => Some([number(x)?, number(y)?]),
                    _ => None,
                });
                let Some(g) = pair else {
                    return Err(self.invalid(
                        "run.gravity",
                        v.to_string(),
                        "must be a 2-vector [gx, gy] in m/s^2, e.g. [0.0, -9.81]",
                    ));
                };
                if !(g[0].is_finite() && g[1].is_finite()) {
                    return Err(self.invalid("run.gravity", format!("{g:?}"), "must be finite"));
                }
                g
            }
        };
        let gravity_ramp = match r.gravity_ramp {
            None => 0.0,
            Some(t) => {
                if r.gravity.is_none() {
                    return Err(self.invalid(
                        "run.gravity_ramp",
                        fmt_num(t),
                        "ramps gravity, but the scene has no `gravity`",
                    ));
                }
                self.positive("run.gravity_ramp", t)?
            }
        };
        let (erode_inverted, erode_min_time_step) = match &r.erosion {
            None => (false, None),
            Some(v) => {
                let expected =
                    "expected a table { inverted = true or false, min_time_step = seconds }";
                let Some(t) = v.as_table() else {
                    return Err(self.invalid("run.erosion", v.to_string(), expected));
                };
                if let Some(k) = t
                    .keys()
                    .find(|k| !matches!(k.as_str(), "inverted" | "min_time_step"))
                {
                    return Err(self.invalid(
                        format!("run.erosion.{k}"),
                        t[k].to_string(),
                        "unknown key (expected inverted or min_time_step)",
                    ));
                }
                if t.is_empty() {
                    return Err(self.invalid("run.erosion", "{}", expected));
                }
                let inverted = match t.get("inverted") {
                    None => false,
                    Some(toml::Value::Boolean(b)) => *b,
                    Some(x) => {
                        return Err(self.invalid(
                            "run.erosion.inverted",
                            x.to_string(),
                            "expected true or false",
                        ))
                    }
                };
                let min_time_step = match t.get("min_time_step") {
                    None => None,
                    Some(x) => {
                        let Some(s) = x.as_float().or(x.as_integer().map(|i| i as f64)) else {
                            return Err(self.invalid(
                                "run.erosion.min_time_step",
                                x.to_string(),
                                "expected a time step in seconds",
                            ));
                        };
                        Some(self.positive("run.erosion.min_time_step", s)?)
                    }
                };
                (inverted, min_time_step)
            }
        };
        Ok(RunSettings {
            end_time,
            time_step_scale,
            time_step,
            history_interval,
            field_interval,
            field_format,
            checkpoint_interval,
            energy_error_limit,
            bulk_linear,
            bulk_quadratic,
            mass_damping,
            gravity,
            gravity_ramp,
            erode_inverted,
            erode_min_time_step,
        })
    }
}
