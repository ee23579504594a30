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
    (0..4)
        .map(|a| {
            let (s, t) = (x[a], x[(a + 1) % 4]);
            let d = [t[0] - s[0], t[1] - s[1]];
            (d[0] * (p[1] - s[1]) - d[1] * (p[0] - s[0])) / d[0].hypot(d[1])
        })
        .fold(f64::INFINITY, f64::min)
}

/// The deepest any node of one body lies inside an element of another (deformed), over all
/// ordered pairs of bodies.
pub fn interpenetration(model: &Model, u: &[[f64; 2]]) -> f64 {
    let mut worst: f64 = 0.0;
    for a in &model.bodies {
        for b in &model.bodies {
            if a.name == b.name {
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
