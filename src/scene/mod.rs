//! Scene files: the TOML format users write, and its validation into a [`Scene`].
//!
//! Every rejected value is reported as [`Error::Invalid`] with the file, the dotted key and the value.
//!
//! One file per table family of the format (README, "Scene format"), each holding the table's raw
//! serde struct, its public types and its own checks (an `impl Validator<'_>` block): `run.rs`
//! (`[run]`), `material.rs` (`[[material]]`), `body.rs` (`[[body]]`) and `mesh.rs` (its
//! `mesh`), `boundary.rs` (`[[boundary]]`, `[[pressure]]`, regions and load curves),
//! `contact.rs` (`[[contact]]`, `[[rigid_wall]]`). `validate.rs` holds the validator and the
//! checks the tables share, `fixed.rs` the strict fixed-length arrays; [`overrides`] sets keys
//! by their path before the tables are decoded (what a study varies). This module reads the
//! file, decodes its tables, has them validated in order and assembles the [`Scene`]; every
//! public type is re-exported here. Host-side only, no GPU twin: the GPU reads the model built
//! from a scene ([`crate::model`]).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Error, Result};

mod body;
mod boundary;
mod contact;
mod fixed;
mod material;
mod mesh;
pub mod overrides;
mod run;
pub(crate) mod validate;

pub use body::{
    Body, Formulation, Hourglass, HourglassForm, DEFAULT_HOURGLASS_COEFFICIENT, NAME_MAX,
};
pub use boundary::{Boundary, LoadCurve, Pressure, RegionGroup, MAX_CURVE_POINTS};
pub use contact::{
    Contact, ContactMethod, PenaltyForm, RigidWall, CONTACT_NAME_MAX, DEFAULT_AUGMENTATION,
    DEFAULT_MASS_PENALTY_SCALE, DEFAULT_PENALTY_FORM, DEFAULT_PENALTY_SCALE,
};
pub use material::{
    FailureCriteria, JohnsonCook, JohnsonCookDamage, Material, MaterialModel, Plasticity,
    ThermalSoftening,
};
pub use mesh::{DiskRefinement, MeshSpec};
pub use run::{
    FieldFormat, RunSettings, BULK_QUADRATIC_MAX, DEFAULT_BULK_LINEAR, DEFAULT_BULK_QUADRATIC,
    DEFAULT_ENERGY_ERROR_LIMIT, DEFAULT_TIME_STEP_SCALE,
};

use body::RawBody;
use boundary::{RawBoundary, RawPressure};
use contact::{RawContact, RawWall};
use material::RawMaterial;
use run::RawRun;
use validate::Validator;

/// Largest scene file read (bytes).
pub const SCENE_MAX_BYTES: u64 = 64 << 20;

/// The tables of a scene file as written (serde), each table's struct in its file. Unknown keys
/// are errors so that typos are caught.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    run: RawRun,
    #[serde(default)]
    material: Vec<RawMaterial>,
    #[serde(default)]
    body: Vec<RawBody>,
    #[serde(default)]
    boundary: Vec<RawBoundary>,
    #[serde(default)]
    contact: Vec<RawContact>,
    #[serde(default)]
    rigid_wall: Vec<RawWall>,
    #[serde(default)]
    pressure: Vec<RawPressure>,
}

/// A validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Scene name (file stem).
    pub name: String,
    /// Source file.
    pub file: PathBuf,
    /// Run control.
    pub run: RunSettings,
    /// Materials.
    pub materials: Vec<Material>,
    /// Bodies.
    pub bodies: Vec<Body>,
    /// Velocity boundary conditions.
    pub boundaries: Vec<Boundary>,
    /// Contacts between bodies.
    pub contacts: Vec<Contact>,
    /// Rigid walls.
    pub walls: Vec<RigidWall>,
    /// Pressure loads.
    pub pressures: Vec<Pressure>,
}

impl Scene {
    /// Whether the scene has any contact or rigid wall.
    pub fn has_contact(&self) -> bool {
        !self.contacts.is_empty() || !self.walls.is_empty()
    }
}

impl Scene {
    /// Reads and validates a scene file ([`Scene::read_text`], then [`Scene::parse`]).
    ///
    /// # Errors
    /// [`Error::Read`] when the file cannot be read, [`Error::Parse`] for TOML and shape errors
    /// (unknown keys included), [`Error::Invalid`] for values that are out of range.
    pub fn load(path: &Path) -> Result<Self> {
        Self::parse(&Self::read_text(path)?, path)
    }

    /// The text of a scene file, at most [`SCENE_MAX_BYTES`] of it (a stream such as
    /// `/dev/zero`, or a runaway file, is refused when the cap is reached, not read until memory
    /// runs out; a pipe is read as a scene).
    ///
    /// # Errors
    /// [`Error::Read`] when the file cannot be read, [`Error::Parse`] when it is larger than the
    /// cap or not UTF-8 text.
    pub fn read_text(path: &Path) -> Result<String> {
        use std::io::Read as _;
        let read_err = |source| Error::Read {
            file: path.to_path_buf(),
            source,
        };
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(SCENE_MAX_BYTES + 1).read_to_end(&mut bytes))
            .map_err(read_err)?;
        if bytes.len() as u64 > SCENE_MAX_BYTES {
            return Err(Error::Parse {
                file: path.to_path_buf(),
                message: format!(
                    "larger than {} MiB: not a scene file (meshes this large belong in a mesh file)",
                    SCENE_MAX_BYTES >> 20
                ),
            });
        }
        String::from_utf8(bytes).map_err(|e| Error::Parse {
            file: path.to_path_buf(),
            message: format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        })
    }

    /// Parses and validates scene text; `path` is used for the name and in messages.
    ///
    /// # Errors
    /// As [`Scene::load`], without the read error.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let raw = decode(text, path)?;
        Validator { file: path }.scene(raw)
    }

    /// Parses and validates scene text with keys overridden by their path
    /// ([`overrides::materialise`], then [`Scene::parse`] of the text that gives): every check of
    /// the scene applies to the overridden values. Without overrides, [`Scene::parse`].
    ///
    /// # Errors
    /// As [`Scene::parse`], and [`Error::Invalid`] naming an override's key and value when it
    /// cannot be set.
    pub fn parse_with(text: &str, path: &Path, overrides: &[overrides::Override]) -> Result<Self> {
        if overrides.is_empty() {
            return Self::parse(text, path);
        }
        let text = overrides::materialise(text, path, overrides)?;
        Self::parse(&text, path)
    }
}

/// The tables of scene text `text` (from `path`), decoded: TOML syntax, the tables' shapes and
/// unknown keys checked, an error quoting its line ([`toml_message`]). Every scene passes here
/// before its values are validated: a step that edits the tables first (a key overridden by its
/// path) belongs here.
fn decode(text: &str, path: &Path) -> Result<RawScene> {
    toml::from_str(text).map_err(|e| Error::Parse {
        file: path.to_path_buf(),
        message: toml_message(text, &e),
    })
}

/// Characters of the offending line quoted on either side of a TOML error's column.
const QUOTE_CHARS: usize = 60;

/// Longest parser message quoted (characters).
const MESSAGE_CHARS: usize = 1000;

/// A TOML error as the parser renders it (line, column, the line with a caret under the column,
/// the message), with the quoted line cut to `QUOTE_CHARS` (60) characters either side of the column
/// and the message to `MESSAGE_CHARS` (1 000): the parser quotes the whole line and the whole value,
/// and one line can hold a whole mesh (the nodes of `assets/ring_crush.toml` are one line of
/// 16 KB), so a typo there gave a message the size of the file.
pub fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let cut = |s: &str, n: usize| -> String {
        match s.char_indices().nth(n) {
            Some((i, _)) => format!("{}...", &s[..i]),
            None => s.to_string(),
        }
    };
    let message = cut(e.message().trim_end(), MESSAGE_CHARS);
    let Some(span) = e.span() else {
        return cut(e.to_string().trim_end(), MESSAGE_CHARS);
    };
    let mut start = span.start.min(text.len());
    while !text.is_char_boundary(start) {
        start -= 1;
    }
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let line_no = text[..line_start].matches('\n').count() + 1;
    let content = text[line_start..].split('\n').next().unwrap_or("");
    let content = content.strip_suffix('\r').unwrap_or(content);
    let chars: Vec<char> = content.chars().collect();
    let column = text[line_start..start].chars().count();
    let from = column.saturating_sub(QUOTE_CHARS);
    let to = (column + QUOTE_CHARS + 1).min(chars.len());
    let mut quoted: String = if from > 0 {
        "...".into()
    } else {
        String::new()
    };
    let caret_at = column - from + quoted.len();
    quoted.extend(&chars[from.min(to)..to]);
    if to < chars.len() {
        quoted.push_str("...");
    }
    let width = text
        .get(start..span.end.min(text.len()))
        .map_or(1, |s| s.chars().take_while(|&c| c != '\n').count())
        .clamp(1, QUOTE_CHARS);
    let gutter = " ".repeat(line_no.to_string().len() + 1);
    format!(
        "TOML parse error at line {line_no}, column {}\n{gutter}|\n{line_no} | {quoted}\n{gutter}| {}{}\n{message}",
        column + 1,
        " ".repeat(caret_at),
        "^".repeat(width)
    )
}

impl Validator<'_> {
    /// The scene of the raw tables, validated table by table in the order of the format.
    fn scene(&self, raw: RawScene) -> Result<Scene> {
        let run = self.run(&raw.run)?;
        let materials = self.materials(&raw.material)?;
        let bodies = self.bodies(&raw.body, &materials)?;
        let boundaries = self.boundaries(&raw.boundary, &bodies)?;
        let contacts = self.contacts(&raw.contact, &bodies, run.mass_damping)?;
        let walls = self.walls(&raw.rigid_wall, &bodies, &contacts, run.mass_damping)?;
        let pressures = self.pressures(&raw.pressure, &bodies)?;
        let name = self
            .file
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".to_string());
        Ok(Scene {
            name,
            file: self.file.to_path_buf(),
            run,
            materials,
            bodies,
            boundaries,
            contacts,
            walls,
            pressures,
        })
    }
}

/// Builds an [`Error::Invalid`] for `scene` (used by later validation stages such as meshing).
pub fn invalid(
    scene: &Scene,
    key: impl Into<String>,
    value: impl Into<String>,
    reason: &str,
) -> Error {
    Validator { file: &scene.file }.invalid(key, value, reason)
}
