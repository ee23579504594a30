//! How deep a node of one body lies inside another body's (deformed) elements: the check of the
//! stress cases that no node went through a surface, shared by the CPU and GPU tests.

use ricochet::model::Model;

/// Deformed corners of element `e`.
fn corners(model: &Model, u: &[[f64; 2]], e: usize) -> [[f64; 2]; 4] {
    model.quads[e].map(|n| {
        let (p, d) = (model.position[n as usize], u[n as usize]);
        [p[0] + d[0], p[1] + d[1]]
    })
}

/// How far `p` lies inside the convex quad `x` (counter-clockwise): the smallest distance to
/// the lines of its sides (<= 0 outside).
fn inside_depth(x: &[[f64; 2]; 4], p: [f64; 2]) -> f64 {
    // Outside the quad's bounding box: outside the quad (a quick rejection: the scans below test
    // every node against every element).
    let (lo, hi) = bounds(x.iter().copied());
    if p[0] <= lo[0] || p[0] >= hi[0] || p[1] <= lo[1] || p[1] >= hi[1] {
        return 0.0;
    }
    (0..4)
        .map(|a| {
            let (s, t) = (x[a], x[(a + 1) % 4]);
            let d = [t[0] - s[0], t[1] - s[1]];
            (d[0] * (p[1] - s[1]) - d[1] * (p[0] - s[0])) / d[0].hypot(d[1])
        })
        .fold(f64::INFINITY, f64::min)
}

/// The bounding box (lower and upper corners) of `points`.
fn bounds(points: impl Iterator<Item = [f64; 2]>) -> ([f64; 2], [f64; 2]) {
    points.fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), c| {
            (
                [lo[0].min(c[0]), lo[1].min(c[1])],
                [hi[0].max(c[0]), hi[1].max(c[1])],
            )
        },
    )
}

/// The deepest any node of one body lies inside an element of another (deformed), over all
/// ordered pairs of bodies (those whose bounding boxes overlap).
pub fn interpenetration(model: &Model, u: &[[f64; 2]]) -> f64 {
    let boxes: Vec<([f64; 2], [f64; 2])> = model
        .bodies
        .iter()
        .map(|b| {
            bounds(b.nodes.clone().map(|n| {
                [
                    model.position[n][0] + u[n][0],
                    model.position[n][1] + u[n][1],
                ]
            }))
        })
        .collect();
    let apart = |i: usize, j: usize| {
        let ((alo, ahi), (blo, bhi)) = (boxes[i], boxes[j]);
        alo[0] > bhi[0] || blo[0] > ahi[0] || alo[1] > bhi[1] || blo[1] > ahi[1]
    };
    let mut worst: f64 = 0.0;
    for (i, a) in model.bodies.iter().enumerate() {
        for (j, b) in model.bodies.iter().enumerate() {
            if a.name == b.name || apart(i, j) {
                continue;
            }
            for e in b.elements.clone() {
                let x = corners(model, u, e);
                for n in a.nodes.clone() {
                    let p = [
                        model.position[n][0] + u[n][0],
                        model.position[n][1] + u[n][1],
                    ];
                    worst = worst.max(inside_depth(&x, p));
                }
            }
        }
    }
    worst
}

/// The deepest any node of body `body` lies inside one of that body's own elements that does not
/// hold it (deformed): a surface passed through itself.
#[allow(dead_code)]
pub fn self_penetration(model: &Model, u: &[[f64; 2]], body: usize) -> f64 {
    let b = &model.bodies[body];
    let mut worst: f64 = 0.0;
    for e in b.elements.clone() {
        let x = corners(model, u, e);
        for n in b.nodes.clone() {
            if model.quads[e].contains(&(n as u32)) {
                continue;
            }
            let p = [
                model.position[n][0] + u[n][0],
                model.position[n][1] + u[n][1],
            ];
            worst = worst.max(inside_depth(&x, p));
        }
    }
    worst
}
