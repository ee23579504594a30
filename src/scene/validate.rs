//! The scene's validator ([`Validator`]) and the checks every table shares: the error of a
//! rejected value (file, dotted key, value, reason), positive, non-negative and finite numbers,
//! unit vectors, and bodies by name. Each table's own checks are in its file (`run.rs`,
//! `material.rs`, ...), as `impl Validator<'_>` blocks. Host-side only, no GPU twin.

use std::path::Path;

use super::body::Body;
use crate::error::{Error, Result};

pub(super) struct Validator<'a> {
    pub(super) file: &'a Path,
}

pub(super) fn fmt_num(x: f64) -> String {
    format!("{x:?}")
}

impl Validator<'_> {
    pub(super) fn invalid(
        &self,
        key: impl Into<String>,
        value: impl Into<String>,
        reason: &str,
    ) -> Error {
        Error::Invalid {
            file: self.file.to_path_buf(),
            key: key.into(),
            value: value.into(),
            reason: reason.to_string(),
        }
    }

    pub(super) fn positive(&self, key: &str, x: f64) -> Result<f64> {
        if x.is_normal() && x > 0.0 {
            Ok(x)
        } else if x > 0.0 && x.is_finite() {
            Err(self.invalid(
                key,
                fmt_num(x),
                &format!(
                    "is below the smallest normal number {:e} (subnormal): use a positive finite \
                     number of normal size",
                    f64::MIN_POSITIVE
                ),
            ))
        } else {
            Err(self.invalid(key, fmt_num(x), "must be a positive finite number"))
        }
    }

    pub(super) fn non_negative(&self, key: &str, x: f64) -> Result<f64> {
        if x.is_finite() && x >= 0.0 {
            Ok(x)
        } else {
            Err(self.invalid(key, fmt_num(x), "must be a finite number >= 0"))
        }
    }

    /// A non-zero finite vector, normalised: `v` over its length, scaled first by its largest component so that no finite vector
    /// overflows (`[-1.5e308, -1.5e308]` is the direction (-1, -1) / sqrt 2).
    pub(super) fn unit(&self, key: &str, v: [f64; 2]) -> Result<[f64; 2]> {
        let m = v[0].abs().max(v[1].abs());
        if !(m.is_finite() && m > 0.0) {
            return Err(self.invalid(key, format!("{v:?}"), "must be a finite non-zero vector"));
        }
        let w = [v[0] / m, v[1] / m];
        let len = w[0].hypot(w[1]);
        Ok([w[0] / len, w[1] / len])
    }

    pub(super) fn finite(&self, key: &str, x: f64) -> Result<f64> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(key, fmt_num(x), "must be finite"))
        }
    }

    pub(super) fn body_index(&self, key: &str, name: &str, bodies: &[Body]) -> Result<usize> {
        bodies.iter().position(|b| b.name == name).ok_or_else(|| {
            let known: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).collect();
            self.invalid(
                key,
                format!("{name:?}"),
                &format!("no body of that name (defined: {known:?})"),
            )
        })
    }
}
