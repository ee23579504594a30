//! Pure element geometry: tests on the corners of quads and triangles that need no mesh, model
//! or solver (the overlap check of explicit meshes, run when a scene is read).
//!
//! A CPU-only module with no GPU twin; the scene reader ([`crate::scene`]) and the mesh
//! generators ([`crate::mesh`], which re-exports [`overlapping_quads`]) call it.

use std::collections::HashMap;

/// Whether quad `q` of `nodes` is strictly convex and counter-clockwise (a triangle
/// `[a, b, c, c]`: counter-clockwise with positive area).
fn convex_ccw(nodes: &[[f64; 2]], q: &[u32; 4]) -> bool {
    let p = q.map(|i| nodes[i as usize]);
    let corners = if crate::step::element::is_triangle(q) {
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
