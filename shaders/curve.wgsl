// Load curves (prepended to boundary.wgsl and loads.wgsl, which declare `curves`): curve k's
// header at curves[k] = (first point, point count) as bitcast u32, its (time, value) points from
// there; piecewise linear, held at the first value before the first time and at the last after.
// CPU reference: scene::LoadCurve::at.

fn curve_at(k: u32, t: f32) -> f32 {
    let h = curves[k];
    let start = bitcast<u32>(h.x);
    let n = bitcast<u32>(h.y);
    let first = curves[start];
    if (t <= first.x || n < 2u) {
        return first.y;
    }
    let last = curves[start + n - 1u];
    if (t > last.x) {
        return last.y;
    }
    // The piece x_lo < t <= x_hi.
    var lo = 0u;
    var hi = n - 1u;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (curves[start + mid].x < t) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let a = curves[start + lo];
    let b = curves[start + hi];
    return a.y + (b.y - a.y) * ((t - a.x) / (b.x - a.x));
}

// t_n in seconds (from the 64-bit tick count).
fn time_now() -> f32 {
    return (f32(ctrl.t_hi) * 4294967296.0 + f32(ctrl.t_lo)) / params.ticks_per_second;
}
