//! The scene's validator ([`Validator`]) and the checks every table shares: the error of a
//! rejected value (file, dotted key, value, reason), positive, non-negative and finite numbers,
//! unit vectors, keywords, numbers in a TOML value, names as quoted in messages, items by name,
//! and the physical groups of a body's Gmsh file. Each table's own checks are in its file
//! (`run.rs`, `material.rs`, ...), as `impl Validator<'_>` blocks. Host-side only, no GPU twin.

use std::path::Path;

use super::body::Body;
use super::mesh::MeshSpec;
use crate::error::{Error, Result};
use crate::gmsh::NodeGroup;

/// Checks the tables of the scene file `file` (and of a study file: `study::validate` adds its
/// tables' checks to the same type); its errors name that file.
pub(crate) struct Validator<'a> {
    /// The file checked.
    pub(crate) file: &'a Path,
}

/// A number as messages show it (Rust's `{:?}`: `1.0`, `1e-7`, `NaN`).
pub(super) fn fmt_num(x: f64) -> String {
    format!("{x:?}")
}

/// A name as messages show it: quoted, cut to its first 40 characters and then `...`.
pub(super) fn shown_name(name: &str) -> String {
    let shown: String = name.chars().take(40).collect();
    let more = if name.chars().count() > 40 { "..." } else { "" };
    format!("{shown:?}{more}")
}

/// A TOML number (a float, or an integer as f64); `None` for any other value.
pub(super) fn number(v: &toml::Value) -> Option<f64> {
    v.as_float().or(v.as_integer().map(|i| i as f64))
}

impl Validator<'_> {
    /// The error of `value` at `key`: [`Error::Invalid`] in this scene file.
    pub(crate) fn invalid(
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

    /// `x`, positive, finite and of normal size (not subnormal).
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

    /// `x`, finite and >= 0.
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

    /// `x`, finite.
    pub(crate) fn finite(&self, key: &str, x: f64) -> Result<f64> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.invalid(key, fmt_num(x), "must be finite"))
        }
    }

    /// Every one of `xs` finite, in order (the first that is not is reported at `key`).
    pub(super) fn finite_all(&self, key: &str, xs: &[f64]) -> Result<()> {
        xs.iter().try_for_each(|&x| self.finite(key, x).map(drop))
    }

    /// The value of the keyword `word` at `key` among `words` (the first when `word` is absent:
    /// the default); another word is refused with `expected` as the reason.
    pub(crate) fn keyword<T: Copy>(
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

    /// The index of the `what` (a body, a material) called `name` among `names`; an unknown name
    /// is refused at `key`, listing those defined.
    pub(super) fn index_of<'n>(
        &self,
        key: &str,
        name: &str,
        what: &str,
        names: impl Iterator<Item = &'n str> + Clone,
    ) -> Result<usize> {
        names.clone().position(|n| n == name).ok_or_else(|| {
            let known: Vec<&str> = names.collect();
            self.invalid(
                key,
                format!("{name:?}"),
                &format!("no {what} of that name (defined: {known:?})"),
            )
        })
    }

    /// The index of the body called `name` (see [`Validator::index_of`]).
    pub(super) fn body_index(&self, key: &str, name: &str, bodies: &[Body]) -> Result<usize> {
        self.index_of(key, name, "body", bodies.iter().map(|b| b.name.as_str()))
    }

    /// The physical group `name` (a name, or a number as text: `"5"`) of the Gmsh file `body`
    /// was read from, among those whose dimension `dim_ok` accepts, with that file; by name
    /// first, then by number (a curve before a point of the same number); at `key`, a body not
    /// read from a Gmsh file is refused as `by_name` ("a region by name"), an unknown group as
    /// not one of `kind` ("physical curve or point"), listing those there by name and number.
    pub(super) fn mesh_group<'b>(
        &self,
        key: &str,
        name: &str,
        body: &'b Body,
        by_name: &str,
        kind: &str,
        dim_ok: impl Fn(i32) -> bool,
    ) -> Result<(&'b Path, &'b NodeGroup)> {
        let MeshSpec::Gmsh { file, mesh, .. } = &body.mesh else {
            return Err(self.invalid(
                key,
                format!("{name:?}"),
                &format!(
                    "body {:?} is not read from a Gmsh file: {by_name} is a {kind} of the body's \
                     mesh file",
                    body.name
                ),
            ));
        };
        let in_kind = || mesh.groups.iter().filter(|g| dim_ok(g.dim));
        let found = in_kind()
            .find(|g| !g.name.is_empty() && g.name == name)
            .or_else(|| in_kind().find(|g| g.is(name)));
        let Some(g) = found else {
            let known: Vec<String> = in_kind().map(|g| g.label()).collect();
            return Err(self.invalid(
                key,
                format!("{name:?}"),
                &format!(
                    "{} has no {kind} of that name or number on body {:?} (there: {})",
                    file.display(),
                    body.name,
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                ),
            ));
        };
        Ok((file, g))
    }
}
