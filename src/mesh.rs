//! Structured mesh generators: rectangles and O-grid disks of 4-node quads.
//!
//! Quads are numbered counter-clockwise. Node coordinates are relative to the body's origin (the
//! rectangle's lower-left corner or the disk's centre) so that they keep full precision; the
//! origin is stored separately. Explicit and Gmsh meshes come as they are in the scene (checked
//! there, with [`crate::geometry::overlapping_quads`]).

use std::collections::HashMap;

use crate::scene::MeshSpec;

/// A body's mesh: local node coordinates and quad connectivity.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    /// Origin added to every local coordinate.
    pub origin: [f64; 2],
    /// Node coordinates relative to `origin`.
    pub nodes: Vec<[f64; 2]>,
    /// Quads, counter-clockwise node indices; a triangle is the collapsed quad `[a, b, c, c]`
    /// (explicit and Gmsh meshes; see [`crate::geometry::is_triangle`]).
    pub quads: Vec<[u32; 4]>,
}

impl Mesh {
    /// Generates the mesh described by `spec`.
    pub fn generate(spec: &MeshSpec) -> Mesh {
        match *spec {
            MeshSpec::Explicit {
                ref nodes,
                ref quads,
            } => explicit(nodes, quads),
            MeshSpec::Gmsh { ref mesh, .. } => explicit(&mesh.nodes, &mesh.quads),
            MeshSpec::Rectangle {
                origin,
                size,
                cells,
            } => rectangle(origin, size, cells),
            MeshSpec::Disk {
                center,
                radius,
                cells,
                refine,
            } => match refine {
                Some(r) => graded_disk(center, radius, cells, r.toward, r.ratio),
                None => disk(center, radius, cells),
            },
        }
    }

    /// Signed area of quad or triangle `q` (positive when counter-clockwise).
    pub fn quad_area(&self, q: usize) -> f64 {
        let c = self.quads[q].map(|i| self.nodes[i as usize]);
        0.5 * ((c[2][0] - c[0][0]) * (c[3][1] - c[1][1])
            - (c[3][0] - c[1][0]) * (c[2][1] - c[0][1]))
    }
}

/// A user-given mesh, stored relative to its first node.
pub fn explicit(nodes: &[[f64; 2]], quads: &[[u32; 4]]) -> Mesh {
    let origin = nodes.first().copied().unwrap_or([0.0, 0.0]);
    Mesh {
        origin,
        nodes: nodes
            .iter()
            .map(|p| [p[0] - origin[0], p[1] - origin[1]])
            .collect(),
        quads: quads.to_vec(),
    }
}

/// Structured grid over `[origin, origin + size]` with `cells` quads along x and y.
pub fn rectangle(origin: [f64; 2], size: [f64; 2], cells: [usize; 2]) -> Mesh {
    let [nx, ny] = cells;
    let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        for i in 0..=nx {
            nodes.push([
                size[0] * i as f64 / nx as f64,
                size[1] * j as f64 / ny as f64,
            ]);
        }
    }
    let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut quads = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            quads.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Mesh {
        origin,
        nodes,
        quads,
    }
}

/// O-grid disk: a square core of `cells` x `cells` quads and four curved blocks of
/// `cells` (around) x `max(1, cells/2)` (radial) quads. Radial lines are straight, so every quad
/// is convex and none is degenerate.
pub fn disk(center: [f64; 2], radius: f64, cells: usize) -> Mesh {
    graded_disk(center, radius, cells, [1.0, 0.0], 1.0)
}

/// The stretch parameter beta of `sinh(beta s) / sinh(beta)` whose slope at s = 0 is `1 / ratio`
/// (beta = 0: no stretch).
fn stretch(ratio: f64) -> f64 {
    if ratio <= 1.0 {
        return 0.0;
    }
    // beta / sinh(beta) decreases from 1 (beta = 0) to 0: bisection.
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    while hi / hi.sinh() > 1.0 / ratio {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid / mid.sinh() > 1.0 / ratio {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// `sinh(beta s) / sinh(beta)` on [-1, 1] (the identity for beta = 0).
fn stretched(beta: f64, s: f64) -> f64 {
    if beta == 0.0 {
        s
    } else {
        (beta * s).sinh() / beta.sinh()
    }
}

/// O-grid disk refined toward the rim point in direction `toward` (a unit vector) and the point
/// opposite: the spacing along the rim there is `ratio` times finer than uniform, and the
/// element layers under the rim are thinned everywhere so that the elements at that point are
/// about square. `ratio = 1` gives [`disk`].
pub fn graded_disk(
    center: [f64; 2],
    radius: f64,
    cells: usize,
    toward: [f64; 2],
    ratio: f64,
) -> Mesh {
    let n = cells;
    let beta = stretch(ratio);
    // Radial layers: uniform spacing R / n (m = n / 2 layers over R / 2); the rim layer is made
    // as thin as the rim spacing at the focus, (pi R / 2n) / ratio.
    let beta_r = stretch(ratio * 2.0 / std::f64::consts::PI);
    let (fs, fc) = (toward[1].atan2(toward[0])).sin_cos();
    let turn = |p: [f64; 2]| [fc * p[0] - fs * p[1], fs * p[0] + fc * p[1]];
    let m = (n / 2).max(1);
    let a = 0.5 * radius; // core half-width
    let mut nodes: Vec<[f64; 2]> = Vec::new();
    let mut index: HashMap<(i64, i64), u32> = HashMap::new();
    let quantum = radius * 1e-9;
    let mut add = |p: [f64; 2], nodes: &mut Vec<[f64; 2]>| -> u32 {
        let k = (
            (p[0] / quantum).round() as i64,
            (p[1] / quantum).round() as i64,
        );
        *index.entry(k).or_insert_with(|| {
            nodes.push(p);
            (nodes.len() - 1) as u32
        })
    };
    let mut quads = Vec::new();
    // Core.
    let mut core = vec![0u32; (n + 1) * (n + 1)];
    for j in 0..=n {
        for i in 0..=n {
            let x = -a + 2.0 * a * i as f64 / n as f64;
            let y = a * stretched(beta, -1.0 + 2.0 * j as f64 / n as f64);
            core[j * (n + 1) + i] = add([x, y], &mut nodes);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let c = |i: usize, j: usize| core[j * (n + 1) + i];
            quads.push([c(i, j), c(i + 1, j), c(i + 1, j + 1), c(i, j + 1)]);
        }
    }
    // Four curved blocks: the one facing +x, rotated by k * 90 degrees.
    for k in 0..4 {
        let (s, c) = (k as f64 * std::f64::consts::FRAC_PI_2).sin_cos();
        let rot = |p: [f64; 2]| [c * p[0] - s * p[1], s * p[0] + c * p[1]];
        let mut ids = vec![0u32; (n + 1) * (m + 1)];
        for t in 0..=n {
            let uniform = -1.0 + 2.0 * t as f64 / n as f64;
            // The blocks facing +x and -x (of the unturned disk) carry the refinement.
            let eta = if k % 2 == 0 {
                stretched(beta, uniform)
            } else {
                uniform
            };
            let inner = [a, a * eta];
            let theta = eta * std::f64::consts::FRAC_PI_4;
            let outer = [radius * theta.cos(), radius * theta.sin()];
            for r in 0..=m {
                let f = 1.0 - stretched(beta_r, 1.0 - r as f64 / m as f64);
                let p = [
                    inner[0] + f * (outer[0] - inner[0]),
                    inner[1] + f * (outer[1] - inner[1]),
                ];
                ids[t * (m + 1) + r] = add(rot(p), &mut nodes);
            }
        }
        for t in 0..n {
            for r in 0..m {
                let id = |t: usize, r: usize| ids[t * (m + 1) + r];
                // radial (r) then tangential (t) is counter-clockwise for the +x block
                quads.push([id(t, r), id(t, r + 1), id(t + 1, r + 1), id(t + 1, r)]);
            }
        }
    }
    // Turned after merging, so that shared nodes are merged in the unturned frame.
    for p in &mut nodes {
        *p = turn(*p);
    }
    Mesh {
        origin: center,
        nodes,
        quads,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangle_counts_and_area() {
        let m = rectangle([1.0, 2.0], [2.0, 1.0], [4, 3]);
        assert_eq!(m.nodes.len(), 20);
        assert_eq!(m.quads.len(), 12);
        let area: f64 = (0..m.quads.len()).map(|q| m.quad_area(q)).sum();
        assert!((area - 2.0).abs() < 1e-12);
    }

    #[test]
    fn disk_is_valid_and_closed() {
        for n in [2, 3, 8, 16] {
            let r = 0.05;
            let m = disk([0.0, 0.0], r, n);
            let mm = (n / 2).max(1);
            assert_eq!(m.quads.len(), n * n + 4 * n * mm);
            // Euler: V - E + F = 1 for a disk; E = (4F + boundary edges)/2, boundary edges = 4n.
            let edges = (4 * m.quads.len() + 4 * n) / 2;
            assert_eq!(m.nodes.len() + m.quads.len(), edges + 1);
            for q in 0..m.quads.len() {
                assert!(m.quad_area(q) > 0.0, "n={n} quad {q} not counter-clockwise");
            }
            let area: f64 = (0..m.quads.len()).map(|q| m.quad_area(q)).sum();
            // The polygon inscribed in the circle with 4n sides.
            let k = 4 * n;
            let polygon = 0.5 * k as f64 * r * r * (2.0 * std::f64::consts::PI / k as f64).sin();
            assert!((area - polygon).abs() < 1e-12 * r * r, "n={n}");
        }
    }
}
