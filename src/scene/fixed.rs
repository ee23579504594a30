//! Fixed-length arrays of the scene file, read strictly: serde's own `[T; N]` takes the first N
//! values of a longer TOML array and drops the rest (a quad with 5 node indices, a node
//! `[x, y, z]`, `cells = [2, 2, 0]` were accepted). Used by the tables' raw structs through
//! `#[serde(deserialize_with = "fixed::...")]`. Host-side only.

use serde::de::{Deserialize, Deserializer, Error};

fn exact<'de, D: Deserializer<'de>, T, const N: usize>(v: Vec<T>) -> Result<[T; N], D::Error> {
    let len = v.len();
    v.try_into().map_err(|_| {
        D::Error::invalid_length(len, &format!("an array of exactly {N} values").as_str())
    })
}

/// `[T; N]`.
pub fn array<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    exact::<D, T, N>(Vec::deserialize(d)?)
}

/// `Option<[T; N]>` (with `#[serde(default)]`).
pub fn option<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    Option::<Vec<T>>::deserialize(d)?
        .map(exact::<D, T, N>)
        .transpose()
}

/// `Option<Vec<[T; N]>>` (with `#[serde(default)]`).
pub fn list<'de, D, T, const N: usize>(d: D) -> Result<Option<Vec<[T; N]>>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    Option::<Vec<Vec<T>>>::deserialize(d)?
        .map(|rows| rows.into_iter().map(exact::<D, T, N>).collect())
        .transpose()
}

/// `Option<Vec<[i64; 4]>>` of quads `[a, b, c, d]` and triangles `[a, b, c]` (with
/// `#[serde(default)]`): a triangle becomes the collapsed quad `[a, b, c, c]`.
pub fn elements<'de, D>(d: D) -> Result<Option<Vec<[i64; 4]>>, D::Error>
where
    D: Deserializer<'de>,
{
    Option::<Vec<Vec<i64>>>::deserialize(d)?
        .map(|rows| {
            rows.into_iter()
                .map(|r| match r[..] {
                    [a, b, c] => Ok([a, b, c, c]),
                    [a, b, c, e] => Ok([a, b, c, e]),
                    _ => Err(D::Error::invalid_length(
                        r.len(),
                        &"exactly 3 node indices (a triangle) or 4 (a quad)",
                    )),
                })
                .collect()
        })
        .transpose()
}

/// `Option<[[f64; 2]; 2]>` (with `#[serde(default)]`).
pub fn matrix<'de, D>(d: D) -> Result<Option<[[f64; 2]; 2]>, D::Error>
where
    D: Deserializer<'de>,
{
    Option::<Vec<Vec<f64>>>::deserialize(d)?
        .map(|rows| {
            let rows: Vec<[f64; 2]> = rows
                .into_iter()
                .map(exact::<D, f64, 2>)
                .collect::<Result<_, _>>()?;
            exact::<D, [f64; 2], 2>(rows)
        })
        .transpose()
}

/// A physical group of a Gmsh file as written: a name (`"clamp"`) or a number (`5` or `"5"`;
/// Gmsh's tutorials number groups without naming them), as text.
struct Group(String);

impl<'de> Deserialize<'de> for Group {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Group;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a physical group's name (a string) or number (an integer)")
            }
            fn visit_str<E: Error>(self, s: &str) -> Result<Group, E> {
                Ok(Group(s.to_string()))
            }
            fn visit_i64<E: Error>(self, n: i64) -> Result<Group, E> {
                Ok(Group(n.to_string()))
            }
            fn visit_u64<E: Error>(self, n: u64) -> Result<Group, E> {
                Ok(Group(n.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

/// `Option<String>` of a group name or number (with `#[serde(default)]`).
pub fn group<'de, D>(d: D) -> Result<Option<String>, D::Error>
where
    D: Deserializer<'de>,
{
    Ok(Option::<Group>::deserialize(d)?.map(|g| g.0))
}

/// `Option<Vec<String>>` of group names or numbers (with `#[serde(default)]`).
pub fn groups<'de, D>(d: D) -> Result<Option<Vec<String>>, D::Error>
where
    D: Deserializer<'de>,
{
    Ok(Option::<Vec<Group>>::deserialize(d)?.map(|v| v.into_iter().map(|g| g.0).collect()))
}
