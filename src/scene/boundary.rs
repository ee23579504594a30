//! `[[boundary]]` and `[[pressure]]`: prescribed velocities and pressure loads (README, "Scene
//! format", `[[boundary]]` and `[[pressure]]`): the raw tables, [`Boundary`], [`Pressure`], their
//! regions (a box or a Gmsh group, [`RegionGroup`]) and values (a number or a [`LoadCurve`]), and
//! their validation. Host-side only, no GPU twin.

use serde::Deserialize;

use super::body::Body;
use super::fixed;
use super::validate::{fmt_num, Validator};
use crate::error::Result;

/// A `[[pressure]]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPressure {
    body: String,
    region: RawRegion,
    value: RawValue,
    ramp: Option<f64>,
}

/// A `[[boundary]]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBoundary {
    body: String,
    region: RawRegion,
    velocity: RawVelocity,
}

/// The `region` of a boundary or pressure: a box, or a Gmsh group.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRegion {
    #[serde(default, deserialize_with = "fixed::option")]
    min: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "fixed::option")]
    max: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "fixed::group")]
    group: Option<String>,
}

/// The `velocity` of a boundary.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawVelocity {
    x: Option<RawValue>,
    y: Option<RawValue>,
}

/// A number, or a load curve: a table of `[time, value]` pairs.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum RawValue {
    Constant(f64),
    Table(Vec<Vec<f64>>),
}

/// Points of a load curve at most (a bound on what one scene key can allocate).
pub const MAX_CURVE_POINTS: usize = 100_000;

/// A value prescribed in time: piecewise linear through its `[time, value]` points (times
/// strictly increasing), held at the first value before the first time and at the last after
/// the last. A constant is one point.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadCurve {
    /// The `[time (s), value]` points.
    pub points: Vec<[f64; 2]>,
}

impl LoadCurve {
    /// The constant `v`.
    pub fn constant(v: f64) -> Self {
        Self {
            points: vec![[0.0, v]],
        }
    }

    /// The value at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        let p = &self.points;
        let Some(first) = p.first() else {
            return 0.0;
        };
        if t <= first[0] {
            return first[1];
        }
        for w in p.windows(2) {
            let (a, b) = (w[0], w[1]);
            if t <= b[0] {
                return a[1] + (b[1] - a[1]) * ((t - a[0]) / (b[0] - a[0]));
            }
        }
        p[p.len() - 1][1]
    }

    /// Whether it is one value for all time.
    pub fn is_constant(&self) -> bool {
        self.points.windows(2).all(|w| w[0][1] == w[1][1])
    }
}

/// A prescribed velocity on the nodes of a body inside a box.
#[derive(Debug, Clone)]
pub struct Boundary {
    /// Index into [`Scene::bodies`](super::Scene::bodies).
    pub body: usize,
    /// Box lower corner.
    pub min: [f64; 2],
    /// Box upper corner.
    pub max: [f64; 2],
    /// Prescribed x velocity, if any.
    pub vx: Option<f64>,
    /// Prescribed y velocity, if any.
    pub vy: Option<f64>,
    /// The x velocity's load curve, when it is one (`vx` is then its value at t = 0).
    pub curve_x: Option<LoadCurve>,
    /// The y velocity's load curve, when it is one (`vy` is then its value at t = 0).
    pub curve_y: Option<LoadCurve>,
    /// The physical curve or point of the body's mesh file that selects the nodes instead of
    /// the box (`region = { group = "..." }`).
    pub group: Option<RegionGroup>,
    /// Key prefix used in messages (`boundary[i]`).
    pub key: String,
}

/// A region given by name: a physical curve or point of the body's Gmsh file, as that body's
/// nodes and edges.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionGroup {
    /// The group's name.
    pub name: String,
    /// Node indices within the body (its mesh's numbering), ascending.
    pub nodes: Vec<u32>,
    /// The curve's line elements within the body, as pairs of body node indices.
    pub edges: Vec<[u32; 2]>,
}

/// A pressure (traction) load on the boundary edges of a body inside a box.
#[derive(Debug, Clone)]
pub struct Pressure {
    /// Index into [`Scene::bodies`](super::Scene::bodies).
    pub body: usize,
    /// Box lower corner.
    pub min: [f64; 2],
    /// Box upper corner.
    pub max: [f64; 2],
    /// Pressure (Pa), acting against the outward normal (positive: compressive).
    pub value: f64,
    /// Duration of the linear ramp from 0 (s), if any; constant afterwards.
    pub ramp: Option<f64>,
    /// The pressure's load curve, when `value` is a table (`value` is then its value at t = 0).
    pub curve: Option<LoadCurve>,
    /// The physical curve of the body's mesh file whose boundary edges are loaded, instead of
    /// the box (`region = { group = "..." }`).
    pub group: Option<RegionGroup>,
    /// Key prefix used in messages (`pressure[i]`).
    pub key: String,
}

impl Validator<'_> {
    /// The `[[boundary]]` tables, in order.
    pub(super) fn boundaries(&self, raw: &[RawBoundary], bodies: &[Body]) -> Result<Vec<Boundary>> {
        raw.iter()
            .enumerate()
            .map(|(i, b)| self.boundary(&format!("boundary[{i}]"), b, bodies))
            .collect()
    }

    /// The `[[pressure]]` tables, in order.
    pub(super) fn pressures(&self, raw: &[RawPressure], bodies: &[Body]) -> Result<Vec<Pressure>> {
        raw.iter()
            .enumerate()
            .map(|(i, p)| self.pressure(&format!("pressure[{i}]"), p, bodies))
            .collect()
    }

    fn boundary(&self, key: &str, b: &RawBoundary, bodies: &[Body]) -> Result<Boundary> {
        let body = self.body_index(&format!("{key}.body"), &b.body, bodies)?;
        let (min, max, group) = self.region(key, &b.region, &bodies[body], 0)?;
        if b.velocity.x.is_none() && b.velocity.y.is_none() {
            return Err(self.invalid(
                format!("{key}.velocity"),
                "{}",
                "prescribe at least one of `x` or `y`",
            ));
        }
        let vx = b
            .velocity
            .x
            .as_ref()
            .map(|v| self.value(&format!("{key}.velocity.x"), v))
            .transpose()?;
        let vy = b
            .velocity
            .y
            .as_ref()
            .map(|v| self.value(&format!("{key}.velocity.y"), v))
            .transpose()?;
        let split = |c: Option<LoadCurve>| match c {
            Some(c) if c.points.len() > 1 => (Some(c.at(0.0)), Some(c)),
            Some(c) => (Some(c.at(0.0)), None),
            None => (None, None),
        };
        let ((vx, curve_x), (vy, curve_y)) = (split(vx), split(vy));
        Ok(Boundary {
            body,
            min,
            max,
            vx,
            vy,
            curve_x,
            curve_y,
            group,
            key: key.to_string(),
        })
    }

    /// A constant or a load curve `[[t0, v0], [t1, v1], ...]`: finite, at least one point of two
    /// numbers, times at least 0 and strictly increasing, at most [`MAX_CURVE_POINTS`] points.
    fn value(&self, key: &str, v: &RawValue) -> Result<LoadCurve> {
        let rows = match v {
            RawValue::Constant(x) => return Ok(LoadCurve::constant(self.finite(key, *x)?)),
            RawValue::Table(rows) => rows,
        };
        let shown = || {
            let s = format!("{rows:?}");
            s.chars().take(80).collect::<String>()
        };
        if rows.is_empty() || rows.len() > MAX_CURVE_POINTS {
            return Err(self.invalid(
                key,
                shown(),
                &format!("a load curve needs 1 to {MAX_CURVE_POINTS} [time, value] points"),
            ));
        }
        let mut points = Vec::with_capacity(rows.len());
        for (i, r) in rows.iter().enumerate() {
            let ([t, x], true) = (
                [
                    r.first().copied().unwrap_or(f64::NAN),
                    r.get(1).copied().unwrap_or(f64::NAN),
                ],
                r.len() == 2,
            ) else {
                return Err(self.invalid(
                    format!("{key}[{i}]"),
                    format!("{r:?}"),
                    "each point is [time, value]",
                ));
            };
            if !(t.is_finite() && x.is_finite() && t >= 0.0) {
                return Err(self.invalid(
                    format!("{key}[{i}]"),
                    format!("{r:?}"),
                    "time and value must be finite, the time at least 0",
                ));
            }
            if let Some(prev) = points.last().map(|p: &[f64; 2]| p[0]) {
                if t <= prev {
                    return Err(self.invalid(
                        format!("{key}[{i}]"),
                        format!("{r:?}"),
                        &format!("times must increase (the point before is at {prev:e} s)"),
                    ));
                }
            }
            points.push([t, x]);
        }
        Ok(LoadCurve { points })
    }

    /// A box `{ min, max }` (finite, min <= max component-wise), or `{ group = "name" }`: a
    /// physical curve (or, where `min_dim` is 0, a point) of the Gmsh file `body` was read from,
    /// as that body's nodes and edges. Returns the box (unbounded for a group) and the group.
    fn region(
        &self,
        key: &str,
        r: &RawRegion,
        body: &Body,
        min_dim: i32,
    ) -> Result<([f64; 2], [f64; 2], Option<RegionGroup>)> {
        let rk = format!("{key}.region");
        if let Some(name) = &r.group {
            if r.min.is_some() || r.max.is_some() {
                return Err(self.invalid(
                    rk,
                    format!("{{ group = {name:?}, ... }}"),
                    "give either `group` or `min` and `max`, not both",
                ));
            }
            let gk = format!("{rk}.group");
            let (file, g) = self.mesh_group(
                &gk,
                name,
                body,
                "a region by name",
                "physical curve or point",
                |_| true,
            )?;
            if g.dim < min_dim {
                return Err(self.invalid(
                    gk,
                    format!("{name:?}"),
                    &format!(
                        "{}: group `{name}` is a physical point; a pressure needs a physical curve",
                        file.display()
                    ),
                ));
            }
            let group = RegionGroup {
                name: name.clone(),
                nodes: g.nodes.clone(),
                edges: g.edges.clone(),
            };
            return Ok(([f64::NEG_INFINITY; 2], [f64::INFINITY; 2], Some(group)));
        }
        let (Some(min), Some(max)) = (r.min, r.max) else {
            return Err(self.invalid(
                rk,
                "{...}",
                "give `min = [x, y]` and `max = [x, y]` (a box), or `group = \"name\"` (a physical \
                 curve or point of the body's Gmsh file)",
            ));
        };
        for i in 0..2 {
            self.finite(&format!("{rk}.min"), min[i])?;
            self.finite(&format!("{rk}.max"), max[i])?;
            if min[i] > max[i] {
                return Err(self.invalid(
                    rk,
                    format!("min = {min:?}, max = {max:?}"),
                    "min must not exceed max",
                ));
            }
        }
        Ok((min, max, None))
    }

    fn pressure(&self, key: &str, p: &RawPressure, bodies: &[Body]) -> Result<Pressure> {
        let body = self.body_index(&format!("{key}.body"), &p.body, bodies)?;
        let (min, max, group) = self.region(key, &p.region, &bodies[body], 1)?;
        let curve = self.value(&format!("{key}.value"), &p.value)?;
        let value = curve.at(0.0);
        let curve = (curve.points.len() > 1).then_some(curve);
        let ramp = p
            .ramp
            .map(|r| self.positive(&format!("{key}.ramp"), r))
            .transpose()?;
        if ramp.is_some() && curve.is_some() {
            return Err(self.invalid(
                format!("{key}.ramp"),
                fmt_num(ramp.unwrap_or(0.0)),
                "a load curve (`value = [[t, p], ...]`) gives its own ramp: drop `ramp`",
            ));
        }
        Ok(Pressure {
            body,
            min,
            max,
            value,
            ramp,
            curve,
            group,
            key: key.to_string(),
        })
    }
}
