//! How far two runs of the same scene lie apart (another solver path or option against the
//! default): shared by the CPU and GPU test crates.

use ricochet::run::RunResult;

/// The largest distance between the two runs' displacements of the same node, and the largest
/// displacement of the first (the scale).
pub fn displacement_difference(a: &[[f64; 2]], b: &[[f64; 2]]) -> (f64, f64) {
    let du = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x[0] - y[0]).hypot(x[1] - y[1]))
        .fold(0.0, f64::max);
    let umax = a.iter().map(|x| x[0].hypot(x[1])).fold(0.0, f64::max);
    (du, umax)
}

/// The largest difference of the kinetic, internal or contact energy over the history rows the
/// two runs share, and the first run's kinetic energy at the start (the scale).
pub fn energy_difference(a: &RunResult, b: &RunResult) -> (f64, f64) {
    let de = a
        .samples
        .iter()
        .zip(&b.samples)
        .map(|((x, _), (y, _))| {
            (x.contact - y.contact)
                .abs()
                .max((x.kinetic - y.kinetic).abs())
                .max((x.internal - y.internal).abs())
        })
        .fold(0.0, f64::max);
    (de, a.samples[0].0.kinetic)
}
