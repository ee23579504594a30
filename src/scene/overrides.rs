//! Overrides of a scene's keys by their path (`body[striker].initial_velocity[1]`,
//! `material[steel].yield_stress`, `run.end_time`, `contact[0].friction`): what a study varies
//! from case to case. A [`KeyPath`] is parsed from its text; [`apply`] sets its value in the
//! scene's TOML tree; [`materialise`] applies a list of [`Override`]s to scene text and writes the
//! whole scene back as TOML, with the paths of Gmsh meshes made absolute so that the scene can
//! be read from another folder. The text that comes out goes through [`super::Scene::parse`] like
//! any scene file, so that every check of the scene applies to the overridden values
//! ([`super::Scene::parse_with`] does both). Host-side only, no GPU twin.
//!
//! Paths: keys joined by `.`; a key may be followed by selectors in brackets: on an array of
//! tables (`[[body]]`, `[[material]]`, `[[contact]]`, ...) a selector is the `name` of the table
//! (`body[striker]`; quoted as `body["1"]` for a name that is all digits) or its index
//! (`contact[0]`); on an array of values, an index (`initial_velocity[1]`). Every key on the way
//! must exist, except that the last key may be one the table does not give yet (a default,
//! such as `contact[0].friction`); a key the scene format does not know is then refused by the
//! scene's own check (unknown keys are errors).

use std::fmt;
use std::path::Path;

use toml::{Table, Value};

use crate::error::{Error, Result};

/// One step of a [`KeyPath`]: a key, or a selector in brackets after it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Segment {
    /// A key of a table (`run`, `end_time`).
    Key(String),
    /// An element of an array by its index (`[1]`).
    Index(usize),
    /// A table of an array of tables by its `name` (`[striker]`, `["1"]`).
    Name(String),
}

/// The path of a key in a scene, as a study names it: `body[striker].initial_velocity[1]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KeyPath {
    /// The path as written.
    pub text: String,
    /// Its steps, in order; the first is always a key.
    pub segments: Vec<Segment>,
}

/// Longest key path accepted (characters).
pub const KEY_PATH_MAX: usize = 1000;

impl KeyPath {
    /// Parses `text`: keys (`[A-Za-z_][A-Za-z0-9_]*`) joined by `.`, each followed by any number
    /// of selectors `[0]`, `[name]` or `["name"]`.
    ///
    /// # Errors
    /// A reason, naming the position, when `text` is not such a path.
    ///
    /// ```
    /// use ricochet::scene::overrides::{KeyPath, Segment};
    /// let p = KeyPath::parse("body[striker].initial_velocity[1]").unwrap();
    /// assert_eq!(
    ///     p.segments,
    ///     vec![
    ///         Segment::Key("body".into()),
    ///         Segment::Name("striker".into()),
    ///         Segment::Key("initial_velocity".into()),
    ///         Segment::Index(1),
    ///     ]
    /// );
    /// assert!(KeyPath::parse("body[striker").is_err());
    /// ```
    pub fn parse(text: &str) -> std::result::Result<Self, String> {
        if text.chars().count() > KEY_PATH_MAX {
            return Err(format!("longer than {KEY_PATH_MAX} characters"));
        }
        let chars: Vec<char> = text.chars().collect();
        let mut segments = Vec::new();
        let mut i = 0;
        let at = |i: usize| format!("at character {}", i + 1);
        loop {
            // A key.
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            if i == start || chars[start].is_ascii_digit() {
                return Err(format!(
                    "expected a key (letters, digits and `_`, not starting with a digit) {}",
                    at(start)
                ));
            }
            segments.push(Segment::Key(chars[start..i].iter().collect()));
            // Its selectors.
            while i < chars.len() && chars[i] == '[' {
                i += 1;
                let (segment, next) = if chars.get(i) == Some(&'"') {
                    let close = chars[i + 1..]
                        .iter()
                        .position(|&c| c == '"')
                        .map(|p| p + i + 1)
                        .ok_or_else(|| format!("unclosed quote {}", at(i)))?;
                    let name: String = chars[i + 1..close].iter().collect();
                    (Segment::Name(name), close + 1)
                } else {
                    let close = chars[i..]
                        .iter()
                        .position(|&c| c == ']')
                        .map(|p| p + i)
                        .ok_or_else(|| format!("unclosed `[` {}", at(i - 1)))?;
                    let inner: String = chars[i..close].iter().collect();
                    let inner = inner.trim();
                    if inner.is_empty() {
                        return Err(format!("empty selector `[]` {}", at(i - 1)));
                    }
                    let segment = if inner.chars().all(|c| c.is_ascii_digit()) {
                        Segment::Index(
                            inner
                                .parse()
                                .map_err(|_| format!("index {inner} too large {}", at(i)))?,
                        )
                    } else {
                        Segment::Name(inner.to_string())
                    };
                    (segment, close)
                };
                if chars.get(next) != Some(&']') {
                    return Err(format!("expected `]` {}", at(next)));
                }
                segments.push(segment);
                i = next + 1;
            }
            match chars.get(i) {
                None => break,
                Some('.') => i += 1,
                Some(c) => return Err(format!("unexpected {c:?} {}", at(i))),
            }
        }
        Ok(Self {
            text: text.to_string(),
            segments,
        })
    }
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

/// A scene key set to a value.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// The key.
    pub key: KeyPath,
    /// Its value (a number, string, boolean, array or table, as TOML has them).
    pub value: Value,
}

/// A TOML value as messages show it: numbers as Rust's `{:?}` writes floats (`1e300`, `NaN`),
/// the rest as inline TOML.
pub fn shown(value: &Value) -> String {
    match value {
        Value::Float(x) => format!("{x:?}"),
        other => other.to_string(),
    }
}

/// Sets the key at `path` of the scene tree `root` to `value`, and returns the path with each
/// selector by name replaced by its index (`body[1].initial_velocity[0]`: how the scene's own
/// messages name the key). An integer value for a key whose value is a float becomes a float, and
/// a float with an integral value for a key whose value is an integer (`cells`) an integer.
///
/// # Errors
/// The reason when a key on the way does not exist, a selector finds no table of that name or an
/// index is past the end of its array, or a step does not fit the value there (a selector on a
/// table, a key on an array).
pub fn apply(
    root: &mut Table,
    path: &KeyPath,
    value: Value,
) -> std::result::Result<String, String> {
    let mut resolved = String::new();
    let mut here: &mut Value = {
        let Some(Segment::Key(first)) = path.segments.first() else {
            return Err("an empty key".into());
        };
        resolved.push_str(first);
        if path.segments.len() == 1 {
            let slot = root.get_mut(first.as_str());
            let coerced = coerce(slot.as_deref(), value);
            root.insert(first.clone(), coerced);
            return Ok(resolved);
        }
        root.get_mut(first.as_str())
            .ok_or_else(|| format!("the scene has no `{first}`"))?
    };
    let last = path.segments.len() - 1;
    for (k, segment) in path.segments.iter().enumerate().skip(1) {
        let is_last = k == last;
        match segment {
            Segment::Key(key) => {
                let Value::Table(table) = here else {
                    return Err(format!(
                        "`{resolved}` is {}, not a table: it has no key `{key}`",
                        kind(here)
                    ));
                };
                resolved.push('.');
                resolved.push_str(key);
                if is_last {
                    let coerced = coerce(table.get(key.as_str()), value);
                    table.insert(key.clone(), coerced);
                    return Ok(resolved);
                }
                here = table
                    .get_mut(key.as_str())
                    .ok_or_else(|| format!("`{resolved}` is not in the scene"))?;
            }
            Segment::Index(i) => {
                let Value::Array(items) = here else {
                    return Err(format!(
                        "`{resolved}` is {}, not an array: no element [{i}]",
                        kind(here)
                    ));
                };
                let n = items.len();
                let slot = items.get_mut(*i).ok_or_else(|| {
                    format!("`{resolved}` has {n} elements: [{i}] is past its end")
                })?;
                resolved.push_str(&format!("[{i}]"));
                if is_last {
                    *slot = coerce(Some(slot), value);
                    return Ok(resolved);
                }
                here = slot;
            }
            Segment::Name(name) => {
                let Value::Array(items) = here else {
                    return Err(format!(
                        "`{resolved}` is {}, not an array of tables: no [{name}]",
                        kind(here)
                    ));
                };
                let names: Vec<String> = items
                    .iter()
                    .filter_map(|t| t.get("name").and_then(Value::as_str))
                    .map(str::to_string)
                    .collect();
                let Some(i) = items
                    .iter()
                    .position(|t| t.get("name").and_then(Value::as_str) == Some(name.as_str()))
                else {
                    return Err(format!(
                        "no `{resolved}` table is named {name:?} (names: {names:?}; or select \
                         by index, `{resolved}[0]`)"
                    ));
                };
                resolved.push_str(&format!("[{i}]"));
                if is_last {
                    return Err(format!(
                        "`{resolved}` is a whole table: name one of its keys \
                         (`{}[{name}].key`)",
                        path_head(&resolved)
                    ));
                }
                here = &mut items[i];
            }
        }
    }
    // The loop returns at the last segment.
    Err("an empty key".into())
}

/// `a.b[1]` -> `a.b`: the resolved path without its last selector.
fn path_head(resolved: &str) -> &str {
    resolved.rsplit_once('[').map_or(resolved, |(h, _)| h)
}

/// What a TOML value is, for messages.
fn kind(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "a string",
        Value::Integer(_) => "an integer",
        Value::Float(_) => "a number",
        Value::Boolean(_) => "a boolean",
        Value::Datetime(_) => "a date",
        Value::Array(_) => "an array",
        Value::Table(_) => "a table",
    }
}

/// `value` in the type of the value it replaces where only the form of a number differs.
fn coerce(old: Option<&Value>, value: Value) -> Value {
    match (old, value) {
        (Some(Value::Float(_)), Value::Integer(i)) => Value::Float(i as f64),
        (Some(Value::Integer(_)), Value::Float(x))
            if x.fract() == 0.0 && x.abs() < 9.0e15 && x.is_finite() =>
        {
            Value::Integer(x as i64)
        }
        (_, v) => v,
    }
}

/// The scene text `text` (of the scene file `path`) with `overrides` applied, in order, written
/// back as TOML (comments dropped), and every relative `mesh.gmsh` path of a body made absolute
/// (relative to `path`'s folder, as the scene reads it), so that the text can be saved in another
/// folder and read from there.
///
/// # Errors
/// [`Error::Parse`] when `text` is not TOML (naming `path`, with the line); [`Error::Invalid`]
/// naming `path`, the override's key and value and the reason when a key cannot be set.
pub fn materialise(text: &str, path: &Path, overrides: &[Override]) -> Result<String> {
    let mut table: Table = toml::from_str(text).map_err(|e| Error::Parse {
        file: path.to_path_buf(),
        message: super::toml_message(text, &e),
    })?;
    for o in overrides {
        apply(&mut table, &o.key, o.value.clone()).map_err(|reason| Error::Invalid {
            file: path.to_path_buf(),
            key: o.key.text.clone(),
            value: shown(&o.value),
            reason,
        })?;
    }
    absolute_meshes(&mut table, path);
    toml::to_string(&table).map_err(|e| Error::Parse {
        file: path.to_path_buf(),
        message: format!("cannot write the scene back as TOML: {e}"),
    })
}

/// Every `body[i].mesh.gmsh` that is a relative path, made absolute against the folder of the
/// scene file `path` (itself made absolute against the working folder).
fn absolute_meshes(table: &mut Table, path: &Path) {
    let folder = path.parent().unwrap_or(Path::new(""));
    let folder = std::fs::canonicalize(folder).unwrap_or_else(|_| {
        std::env::current_dir()
            .map(|d| d.join(folder))
            .unwrap_or_else(|_| folder.to_path_buf())
    });
    let Some(Value::Array(bodies)) = table.get_mut("body") else {
        return;
    };
    for body in bodies {
        let Some(Value::String(file)) = body
            .get_mut("mesh")
            .and_then(|m| m.as_table_mut())
            .and_then(|m| m.get_mut("gmsh"))
        else {
            continue;
        };
        if !Path::new(file.as_str()).is_absolute() {
            *file = folder.join(file.as_str()).to_string_lossy().into_owned();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = r#"
[run]
end_time = 1.0e-4

[[material]]
name = "steel"
model = "linear_elastic"
density = 7850.0
youngs_modulus = 2.1e11
poisson_ratio = 0.3

[[body]]
name = "striker"
material = "steel"
mesh = { rectangle = { origin = [0.0, 0.0], size = [0.1, 0.01], cells = [40, 4] } }
initial_velocity = [10.0, 0.0]

[[body]]
name = "1"
material = "steel"
mesh = { gmsh = "part.msh", group = "part" }
"#;

    fn tree() -> Table {
        toml::from_str(SCENE).unwrap()
    }

    fn set(t: &mut Table, key: &str, v: Value) -> std::result::Result<String, String> {
        apply(t, &KeyPath::parse(key).unwrap(), v)
    }

    #[test]
    fn paths_parse_with_names_indices_and_quotes() {
        let p = KeyPath::parse("body[\"1\"].mesh.rectangle.cells[0]").unwrap();
        assert_eq!(p.segments[1], Segment::Name("1".into()));
        assert_eq!(p.segments.last(), Some(&Segment::Index(0)));
        assert_eq!(
            KeyPath::parse("run.end_time").unwrap().segments,
            vec![Segment::Key("run".into()), Segment::Key("end_time".into())]
        );
        for bad in [
            "", ".a", "a.", "a..b", "1a", "a[", "a[]", "a[0", "a[0]b", "a b", "a[\"x]",
        ] {
            assert!(KeyPath::parse(bad).is_err(), "{bad:?} parsed");
        }
    }

    #[test]
    fn values_are_set_by_name_index_and_key() {
        let mut t = tree();
        assert_eq!(
            set(
                &mut t,
                "body[striker].initial_velocity[1]",
                Value::Float(-3.0)
            )
            .unwrap(),
            "body[0].initial_velocity[1]"
        );
        assert_eq!(
            set(&mut t, "material[steel].yield_stress", Value::Float(3e8)).unwrap(),
            "material[0].yield_stress"
        );
        set(&mut t, "run.end_time", Value::Integer(2)).unwrap();
        set(
            &mut t,
            "body[0].mesh.rectangle.cells[0]",
            Value::Float(80.0),
        )
        .unwrap();
        set(&mut t, "body[\"1\"].thickness", Value::Float(0.5)).unwrap();
        assert_eq!(
            t["body"][0]["initial_velocity"],
            Value::Array(vec![Value::Float(10.0), Value::Float(-3.0)])
        );
        assert_eq!(t["material"][0]["yield_stress"], Value::Float(3e8));
        // An integer for a float key becomes a float, an integral float for an integer an integer.
        assert_eq!(t["run"]["end_time"], Value::Float(2.0));
        assert_eq!(
            t["body"][0]["mesh"]["rectangle"]["cells"][0],
            Value::Integer(80)
        );
        assert_eq!(t["body"][1]["thickness"], Value::Float(0.5));
    }

    #[test]
    fn missing_keys_names_and_indices_are_refused_with_the_reason() {
        let mut t = tree();
        let e = set(&mut t, "body[stiker].thickness", Value::Float(1.0)).unwrap_err();
        assert!(e.contains("\"stiker\"") && e.contains("striker"), "{e}");
        let e = set(&mut t, "body[0].initial_velocity[2]", Value::Float(1.0)).unwrap_err();
        assert!(e.contains("2 elements"), "{e}");
        let e = set(&mut t, "contact[0].friction", Value::Float(0.1)).unwrap_err();
        assert!(e.contains("no `contact`"), "{e}");
        let e = set(&mut t, "run[0]", Value::Float(0.1)).unwrap_err();
        assert!(e.contains("not an array"), "{e}");
        let e = set(&mut t, "body[striker]", Value::Float(0.1)).unwrap_err();
        assert!(e.contains("whole table"), "{e}");
        let e = set(&mut t, "body[1].initial_velocity[0]", Value::Float(0.1)).unwrap_err();
        assert!(e.contains("not in the scene"), "{e}");
    }

    #[test]
    fn materialised_text_keeps_the_values_and_makes_mesh_paths_absolute() {
        let path = Path::new("/some/where/scene.toml");
        let overrides = [Override {
            key: KeyPath::parse("body[striker].initial_velocity[0]").unwrap(),
            value: Value::Float(4.350184725e-6),
        }];
        let text = materialise(SCENE, path, &overrides).unwrap();
        let back: Table = toml::from_str(&text).unwrap();
        assert_eq!(
            back["body"][0]["initial_velocity"][0],
            Value::Float(4.350184725e-6)
        );
        assert_eq!(back["run"]["end_time"], Value::Float(1.0e-4));
        let mesh = back["body"][1]["mesh"]["gmsh"].as_str().unwrap();
        assert!(
            Path::new(mesh).is_absolute() && mesh.ends_with("part.msh"),
            "{mesh}"
        );
        let e = materialise(
            SCENE,
            path,
            &[Override {
                key: KeyPath::parse("material[iron].density").unwrap(),
                value: Value::Float(1.0),
            }],
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("material[iron].density") && e.contains("scene.toml"),
            "{e}"
        );
    }
}
