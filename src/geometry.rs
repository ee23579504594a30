//! Element geometry, pure functions of the corners: the quad's centre gradients and hourglass
//! vector ([`quad_geometry`]), the triangle as a collapsed quad (`[a, b, c, c]`, [`is_triangle`]),
//! the element's centre, its characteristic length for the stable step, its corner check, its
//! lumped masses, and the overlap check of an explicit mesh ([`overlapping_quads`]).
//!
//! The lowest layer of the crate, with [`crate::error`]: the scene's mesh checks, the model's
//! assembly, the contact and the element ([`crate::element`]) all read it. The GPU's element
//! kernel computes the same quantities from the model's reference corners in
//! `shaders/element.wgsl`; the f64 functions here are their reference.

use std::collections::HashMap;

/// The sign vector of the hourglass mode of a 4-node quad.
pub const HOURGLASS_BASE: [f64; 4] = [1.0, -1.0, 1.0, -1.0];

/// sqrt(8/3): the stable-step length of a triangle is this times area / longest side (see
/// [`characteristic_length`]).
pub const TRIANGLE_LENGTH: f64 = 1.632_993_161_855_452;

/// Whether the element with nodes `q` is a triangle (a collapsed quad `[a, b, c, c]`).
#[inline]
pub fn is_triangle(q: &[u32; 4]) -> bool {
    q[2] == q[3]
}

/// Whether the corners `x` are those of a triangle (the last repeats the third).
#[inline]
pub fn is_triangle_geometry(x: &[[f64; 2]; 4]) -> bool {
    x[2] == x[3]
}

/// Weights of the corners at the element's centre: 1/4 each for a quad, 1/3 on the three
/// corners of a triangle (its centroid; the repeated corner gets 0).
#[inline]
pub fn centre_weights(triangle: bool) -> [f64; 4] {
    if triangle {
        [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 0.0]
    } else {
        [0.25; 4]
    }
}

/// The centre of the element with corners `x` (the centroid of a triangle).
#[inline]
pub fn element_centre(x: &[[f64; 2]; 4]) -> [f64; 2] {
    let w = centre_weights(is_triangle_geometry(x));
    let mut c = [0.0; 2];
    for a in 0..4 {
        c[0] += w[a] * x[a][0];
        c[1] += w[a] * x[a][1];
    }
    c
}

/// Reference geometry of a quad at its centre: area and shape-function gradients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadGeometry {
    /// Area.
    pub area: f64,
    /// dN_a/dX at the centre, per node.
    pub bx: [f64; 4],
    /// dN_a/dY at the centre, per node.
    pub by: [f64; 4],
    /// Flanagan-Belytschko hourglass vector gamma_a.
    pub gamma: [f64; 4],
    /// 1 / area.
    pub inv_area: f64,
    /// (b . b) / (gamma . gamma): geometry factor of the stiffness hourglass coefficient.
    pub hourglass_stiffness: f64,
    /// sqrt(b . b) / (gamma . gamma): geometry factor of the viscous hourglass coefficient.
    pub hourglass_viscous: f64,
    /// Reference radius of the centre (axisymmetric elements; 0 otherwise, see
    /// [`crate::model::Model::geometry`]).
    pub radius: f64,
    /// A triangle (collapsed quad): no hourglass mode, so `gamma` and the hourglass factors are 0.
    pub triangle: bool,
}

/// Centre gradients and hourglass vector of the quad with corners `x` (counter-clockwise).
#[inline]
pub fn quad_geometry(x: &[[f64; 2]; 4]) -> QuadGeometry {
    let (x1, x2, x3, x4) = (x[0][0], x[1][0], x[2][0], x[3][0]);
    let (y1, y2, y3, y4) = (x[0][1], x[1][1], x[2][1], x[3][1]);
    let area = 0.5 * ((x3 - x1) * (y4 - y2) - (x4 - x2) * (y3 - y1));
    let s = 0.5 / area;
    let bx = [s * (y2 - y4), s * (y3 - y1), s * (y4 - y2), s * (y1 - y3)];
    let by = [s * (x4 - x2), s * (x1 - x3), s * (x2 - x4), s * (x3 - x1)];
    let h = HOURGLASS_BASE;
    let hx = h[0] * x1 + h[1] * x2 + h[2] * x3 + h[3] * x4;
    let hy = h[0] * y1 + h[1] * y2 + h[2] * y3 + h[3] * y4;
    let gamma = [
        h[0] - hx * bx[0] - hy * by[0],
        h[1] - hx * bx[1] - hy * by[1],
        h[2] - hx * bx[2] - hy * by[2],
        h[3] - hx * bx[3] - hy * by[3],
    ];
    let bb: f64 = (0..4).map(|a| bx[a] * bx[a] + by[a] * by[a]).sum();
    let gg: f64 = gamma.iter().map(|x| x * x).sum();
    if is_triangle_geometry(x) {
        return QuadGeometry {
            area,
            inv_area: 1.0 / area,
            hourglass_stiffness: 0.0,
            hourglass_viscous: 0.0,
            radius: 0.0,
            bx,
            by,
            gamma: [0.0; 4],
            triangle: true,
        };
    }
    QuadGeometry {
        area,
        inv_area: 1.0 / area,
        hourglass_stiffness: bb / gg,
        hourglass_viscous: bb.sqrt() / gg,
        radius: 0.0,
        bx,
        by,
        gamma,
        triangle: false,
    }
}

/// Characteristic length of a quad: area over max(longest side, longest diagonal / sqrt 2).
/// Equal to the side for a square, to the short side for a thin rectangle.
///
/// A triangle (collapsed quad, whose longest side is then the maximum) gets [`TRIANGLE_LENGTH`]
/// times that, sqrt(2/3) of its smallest altitude: with lumped masses A/3, the largest
/// eigenfrequency of a constant-strain triangle is at most 2 c / (sqrt(2/3) h_min), for
/// c^2 = (lambda + 2 mu + max(lambda, 0)) / rho, on every shape and Poisson ratio (the bound is
/// reached by slender isosceles triangles at nu = 0; a unit test of [`crate::element::forces`]
/// checks it against the element's eigenvalues).
#[inline]
pub fn characteristic_length(x: &[[f64; 2]; 4], area: f64) -> f64 {
    let d = |a: usize, b: usize| {
        let dx = x[b][0] - x[a][0];
        let dy = x[b][1] - x[a][1];
        dx * dx + dy * dy
    };
    let side = d(0, 1).max(d(1, 2)).max(d(2, 3)).max(d(3, 0));
    let diag = 0.5 * d(0, 2).max(d(1, 3));
    let l = area / side.max(diag).sqrt();
    if is_triangle_geometry(x) {
        TRIANGLE_LENGTH * l
    } else {
        l
    }
}

/// Smallest corner cross product of `x` (twice the area of the corner's triangle). A triangle
/// has one: its corners 0 and 1 (corners 2 and 3 meet a zero-length side).
#[inline]
pub fn min_corner_cross(x: &[[f64; 2]; 4]) -> f64 {
    let corners = if is_triangle_geometry(x) { 1 } else { 4 };
    let mut m = f64::INFINITY;
    for a in 0..corners {
        let p = x[(a + 3) % 4];
        let c = x[a];
        let n = x[(a + 1) % 4];
        m = m.min((n[0] - c[0]) * (p[1] - c[1]) - (n[1] - c[1]) * (p[0] - c[0]));
    }
    m
}

/// Smallest corner Jacobian of `x`, relative to the quad's area (1 for a parallelogram, 2 for a
/// triangle).
#[inline]
pub fn min_corner_ratio(x: &[[f64; 2]; 4], area: f64) -> f64 {
    let m = min_corner_cross(x);
    if area.abs() > 0.0 {
        m / area.abs()
    } else {
        m
    }
}

/// Row-sum lumped masses per radian of an axisymmetric bilinear quad: `rho * integral of N_a r`
/// by 2x2 Gauss quadrature, r = `x0` + x (`x` relative to the mesh origin `x0`).
pub fn lumped_mass_axisymmetric(x: &[[f64; 2]; 4], rho: f64, x0: f64) -> [f64; 4] {
    lumped_mass_weighted(x, rho, Some(x0))
}

/// Row-sum lumped masses of a bilinear quad: `rho_t * integral of N_a`, by 2x2 Gauss quadrature;
/// of a triangle (collapsed quad, see [`is_triangle`]): `rho_t A / 3` on its three
/// nodes (the repeated corner gets 0).
pub fn lumped_mass(x: &[[f64; 2]; 4], rho_t: f64) -> [f64; 4] {
    lumped_mass_weighted(x, rho_t, None)
}

fn lumped_mass_weighted(x: &[[f64; 2]; 4], rho_t: f64, x0: Option<f64>) -> [f64; 4] {
    if is_triangle_geometry(x) {
        // Triangle: rho_t integral of N_a = rho_t A / 3; axisymmetric, with r = sum N_b r_b and
        // integral of N_a N_b = A (1 + delta_ab) / 12: rho A (2 r_a + r_b + r_c) / 12.
        let area = 0.5
            * ((x[1][0] - x[0][0]) * (x[2][1] - x[0][1])
                - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]));
        let m: [f64; 3] = match x0 {
            None => [rho_t * area / 3.0; 3],
            Some(x0) => {
                let r = [x0 + x[0][0], x0 + x[1][0], x0 + x[2][0]];
                let sum = r[0] + r[1] + r[2];
                r.map(|ra| rho_t * area * (ra + sum) / 12.0)
            }
        };
        return [m[0], m[1], m[2], 0.0];
    }
    let g = 1.0 / 3f64.sqrt();
    let mut m = [0.0; 4];
    let xi_a = [-1.0, 1.0, 1.0, -1.0];
    let eta_a = [-1.0, -1.0, 1.0, 1.0];
    for (xi, eta) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
        // Jacobian of the bilinear map.
        let mut j = [0.0; 4];
        for a in 0..4 {
            let dxi = 0.25 * xi_a[a] * (1.0 + eta_a[a] * eta);
            let deta = 0.25 * eta_a[a] * (1.0 + xi_a[a] * xi);
            j[0] += dxi * x[a][0];
            j[1] += deta * x[a][0];
            j[2] += dxi * x[a][1];
            j[3] += deta * x[a][1];
        }
        let det = j[0] * j[3] - j[1] * j[2];
        let n: [f64; 4] =
            std::array::from_fn(|a| 0.25 * (1.0 + xi_a[a] * xi) * (1.0 + eta_a[a] * eta));
        let r = match x0 {
            Some(x0) => x0 + (0..4).map(|a| n[a] * x[a][0]).sum::<f64>(),
            None => 1.0,
        };
        for a in 0..4 {
            m[a] += rho_t * n[a] * det * r;
        }
    }
    m
}

/// Whether quad `q` of `nodes` is strictly convex and counter-clockwise (a triangle
/// `[a, b, c, c]`: counter-clockwise with positive area).
fn convex_ccw(nodes: &[[f64; 2]], q: &[u32; 4]) -> bool {
    let p = q.map(|i| nodes[i as usize]);
    let corners = if is_triangle(q) {
        if q[0] == q[1] || q[1] == q[2] || q[0] == q[2] {
            return false;
        }
        1
    } else {
        4
    };
    (0..corners).all(|a| {
        let (o, s, t) = (p[a], p[(a + 1) % 4], p[(a + 2) % 4]);
        (s[0] - o[0]) * (t[1] - s[1]) - (s[1] - o[1]) * (t[0] - s[0]) > 0.0
    })
}

/// Whether the convex counter-clockwise quads `a` and `b` overlap by more than `tol` (a length):
/// no edge normal of either separates them (separating axes). Quads that share an edge or a
/// corner touch without overlapping.
fn quads_overlap(a: &[[f64; 2]; 4], b: &[[f64; 2]; 4], tol: f64) -> bool {
    for (p, q) in [(a, b), (b, a)] {
        for k in 0..4 {
            let (s, t) = (p[k], p[(k + 1) % 4]);
            // Outward normal of edge s -> t of a counter-clockwise quad, unit length.
            let n = [t[1] - s[1], s[0] - t[0]];
            let len = n[0].hypot(n[1]);
            if len == 0.0 {
                continue;
            }
            let n = [n[0] / len, n[1] / len];
            let d = |x: &[f64; 2]| (x[0] - s[0]) * n[0] + (x[1] - s[1]) * n[1];
            // p lies at d <= 0; q is separated when all its corners lie at d >= -tol.
            if q.iter().all(|x| d(x) >= -tol) {
                return false;
            }
        }
    }
    true
}

/// The first pair (i < j) of quads of an explicit mesh whose interiors overlap (by more than
/// 10^-9 of the smaller quad's size), if any; quads that are not strictly convex and
/// counter-clockwise are skipped (the mesh check refuses them by name). Candidate pairs come from
/// a uniform grid of the quads' bounding boxes, cells of the median quad size, so the check costs
/// about one pass over the quads.
pub fn overlapping_quads(nodes: &[[f64; 2]], quads: &[[u32; 4]]) -> Option<(usize, usize)> {
    let corners: Vec<[[f64; 2]; 4]> = quads.iter().map(|q| q.map(|i| nodes[i as usize])).collect();
    let boxes: Vec<[f64; 4]> = corners
        .iter()
        .map(|c| {
            c.iter().fold(
                [
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                ],
                |b, p| {
                    [
                        b[0].min(p[0]),
                        b[1].min(p[1]),
                        b[2].max(p[0]),
                        b[3].max(p[1]),
                    ]
                },
            )
        })
        .collect();
    let ok: Vec<bool> = quads.iter().map(|q| convex_ccw(nodes, q)).collect();
    let mut sizes: Vec<f64> = boxes
        .iter()
        .zip(&ok)
        .filter(|(_, &k)| k)
        .map(|(b, _)| (b[2] - b[0]).max(b[3] - b[1]))
        .collect();
    if sizes.is_empty() {
        return None;
    }
    let mid = sizes.len() / 2;
    let cell = *sizes.select_nth_unstable_by(mid, f64::total_cmp).1;
    if !(cell.is_finite() && cell > 0.0) {
        return None;
    }
    let key = |x: f64| (x / cell).floor() as i64;
    // Cells a box spans, in f64: with coordinates far beyond the cell size (1e300 in a fuzzed
    // mesh) the i64 keys saturate and their differences would overflow.
    let large = |b: &[f64; 4]| {
        let span = (((b[2] / cell).floor() - (b[0] / cell).floor()) + 1.0)
            * (((b[3] / cell).floor() - (b[1] / cell).floor()) + 1.0);
        span.is_nan() || span > 4096.0
    };
    let mut grid: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
    for (i, b) in boxes.iter().enumerate() {
        if !ok[i] {
            continue;
        }
        // A quad far larger than the median spans at most 64 x 64 cells here; larger ones are
        // compared against the others directly below.
        if large(b) {
            continue;
        }
        let (x0, y0, x1, y1) = (key(b[0]), key(b[1]), key(b[2]), key(b[3]));
        for gx in x0..=x1 {
            for gy in y0..=y1 {
                grid.entry((gx, gy)).or_default().push(i as u32);
            }
        }
    }
    let size = |i: usize| (boxes[i][2] - boxes[i][0]).max(boxes[i][3] - boxes[i][1]);
    let test = |i: usize, j: usize| {
        let (a, b) = (&boxes[i], &boxes[j]);
        let tol = 1e-9 * size(i).min(size(j));
        a[0] < b[2] - tol
            && b[0] < a[2] - tol
            && a[1] < b[3] - tol
            && b[1] < a[3] - tol
            && quads_overlap(&corners[i], &corners[j], tol)
    };
    let mut best: Option<(usize, usize)> = None;
    let mut keep = |i: usize, j: usize| {
        let pair = (i.min(j), i.max(j));
        if best.is_none_or(|b| pair < b) {
            best = Some(pair);
        }
    };
    let mut cells: Vec<_> = grid.iter().collect();
    cells.sort_unstable_by_key(|(k, _)| **k);
    for (_, list) in cells {
        for (a, &i) in list.iter().enumerate() {
            for &j in &list[a + 1..] {
                if test(i as usize, j as usize) {
                    keep(i as usize, j as usize);
                }
            }
        }
    }
    // The few very large quads, against every other.
    for i in 0..quads.len() {
        let b = &boxes[i];
        if ok[i] && large(b) {
            for j in 0..quads.len() {
                if j != i && ok[j] && test(i, j) {
                    keep(i, j);
                }
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_is_orthogonal_to_linear_fields() {
        let x = [[0.0, 0.0], [2.0, 0.1], [2.3, 1.7], [-0.2, 1.1]];
        let g = quad_geometry(&x);
        let sx: f64 = (0..4).map(|a| g.gamma[a] * x[a][0]).sum();
        let sy: f64 = (0..4).map(|a| g.gamma[a] * x[a][1]).sum();
        let s1: f64 = g.gamma.iter().sum();
        assert!(sx.abs() < 1e-12 && sy.abs() < 1e-12 && s1.abs() < 1e-12);
        // b reproduces the gradient of linear fields
        let gx: f64 = (0..4).map(|a| g.bx[a] * x[a][0]).sum();
        let gy: f64 = (0..4).map(|a| g.by[a] * x[a][0]).sum();
        assert!((gx - 1.0).abs() < 1e-12 && gy.abs() < 1e-12);
    }

    #[test]
    fn lumped_mass_sums_to_element_mass() {
        let x = [[0.0, 0.0], [2.0, 0.1], [2.3, 1.7], [-0.2, 1.1]];
        let m = lumped_mass(&x, 3.0);
        let area = quad_geometry(&x).area;
        let total: f64 = m.iter().sum();
        assert!((total - 3.0 * area).abs() < 1e-12 * total);
        assert!(m.iter().all(|&w| w > 0.0));
    }
    #[test]
    fn lumped_mass_of_a_triangle_is_a_third_each_and_its_axisymmetric_mass_is_exact() {
        let t = [[0.3, 0.1], [1.2, 0.4], [0.5, 1.1]];
        let x = [t[0], t[1], t[2], t[2]];
        let area = quad_geometry(&x).area;
        let m = lumped_mass(&x, 3.0);
        assert_eq!(m[3], 0.0);
        for w in &m[..3] {
            assert!((w - area).abs() < 1e-15, "{w} vs {}", area);
        }
        // Per radian: rho times the integral of r over the triangle, A (r_a + r_b + r_c) / 3,
        // with the origin at x0 = 0.7.
        let m = lumped_mass_axisymmetric(&x, 2.0, 0.7);
        let total: f64 = m.iter().sum();
        let exact = 2.0 * area * (2.1 + t[0][0] + t[1][0] + t[2][0]) / 3.0;
        assert!((total - exact).abs() < 1e-14 * exact, "{total} vs {exact}");
        // The node farther from the axis carries more.
        assert!(m[1] > m[2] && m[2] > m[0]);
    }
}
