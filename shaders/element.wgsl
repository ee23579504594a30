// Element stage: one-point 4-node quad, total Lagrangian, one thread per element.
// Mirrors ricochet::step::element::evaluate (the f64 CPU reference) line by line in f32.

struct Body {
    model: u32,           // 0 linear elastic, 1 neo-Hookean
    formulation: u32,     // 0 plane strain, 1 plane stress
    hourglass: u32,       // 0 none, 1 viscous, 2 stiffness
    _pad0: u32,
    density: f32,
    thickness: f32,
    lambda: f32,
    mu: f32,
    lambda_plane: f32,
    wave_modulus: f32,
    hourglass_coefficient: f32,
    bulk_linear: f32,
    bulk_quadratic: f32,
    mass: f32,
    _pad1: f32,
    _pad2: f32,
}

struct Element {
    c01: vec4<f32>,       // reference corners 0,1 relative to the element centre
    c23: vec4<f32>,       // corners 2,3
    nodes: vec4<u32>,
    body: u32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
}

override WG: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> elems: array<Element>;
@group(0) @binding(2) var<storage, read> bodies: array<Body>;
@group(0) @binding(3) var<storage, read> nodes: array<vec4<f32>>;        // (u, v)
@group(0) @binding(4) var<storage, read_write> elem_force: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read_write> elem_dt: array<f32>;
@group(0) @binding(6) var<storage, read_write> ctrl: Control;
@group(0) @binding(7) var<storage, read_write> sample_src: array<vec4<f32>>;
//#if dissipation
// (Q_x, Q_y, hourglass work, bulk work), (bulk P xx xy yx yy) per element
@group(0) @binding(8) var<storage, read_write> elem_state: array<vec4<f32>>;
//#endif

// x - ln(1 + x), accurate for small x.
fn x_minus_log1p(x: f32) -> f32 {
    if (abs(x) < 1e-2) {
        return x * x * (0.5 - x * (1.0 / 3.0 - x * (0.25 - x * (0.2 - x / 6.0))));
    }
    return x - log(1.0 + x);
}

fn log1p(x: f32) -> f32 {
    return x - x_minus_log1p(x);
}

@compute @workgroup_size(WG)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    if (e >= params.n_elems) {
        return;
    }
    if (ctrl.state != STATE_RUNNING) {
        return;
    }
    let el = elems[e];
    let b = bodies[el.body];
    let x = array<vec2<f32>, 4>(el.c01.xy, el.c01.zw, el.c23.xy, el.c23.zw);
    let s0 = nodes[el.nodes.x];
    let s1 = nodes[el.nodes.y];
    let s2 = nodes[el.nodes.z];
    let s3 = nodes[el.nodes.w];
    let u = array<vec2<f32>, 4>(s0.xy, s1.xy, s2.xy, s3.xy);
    let v = array<vec2<f32>, 4>(s0.zw, s1.zw, s2.zw, s3.zw);

    // Reference geometry at the centre.
    let area0 = 0.5 * ((x[2].x - x[0].x) * (x[3].y - x[1].y) - (x[3].x - x[1].x) * (x[2].y - x[0].y));
    let sc = 0.5 / area0;
    let bx = array<f32, 4>(sc * (x[1].y - x[3].y), sc * (x[2].y - x[0].y), sc * (x[3].y - x[1].y), sc * (x[0].y - x[2].y));
    let by = array<f32, 4>(sc * (x[3].x - x[1].x), sc * (x[0].x - x[2].x), sc * (x[1].x - x[3].x), sc * (x[2].x - x[0].x));
    let hx = x[0].x - x[1].x + x[2].x - x[3].x;
    let hy = x[0].y - x[1].y + x[2].y - x[3].y;
    let gamma = array<f32, 4>(
        1.0 - hx * bx[0] - hy * by[0],
        -1.0 - hx * bx[1] - hy * by[1],
        1.0 - hx * bx[2] - hy * by[2],
        -1.0 - hx * bx[3] - hy * by[3],
    );
    let a0t = area0 * b.thickness;

    // Displacement gradient H = F - I and its rate.
    var h = vec4<f32>(0.0);   // xx xy yx yy
    var fd = vec4<f32>(0.0);
    for (var a = 0; a < 4; a++) {
        h += vec4<f32>(u[a].x * bx[a], u[a].x * by[a], u[a].y * bx[a], u[a].y * by[a]);
        fd += vec4<f32>(v[a].x * bx[a], v[a].x * by[a], v[a].y * bx[a], v[a].y * by[a]);
    }
    let f = h + vec4<f32>(1.0, 0.0, 0.0, 1.0);
    let jm1 = h.x + h.w + h.x * h.w - h.y * h.z;   // J - 1 without cancellation
    let j = 1.0 + jm1;

    // Stress (first Piola-Kirchhoff) and strain energy density.
    var pk: vec4<f32>;
    var w: f32;
    if (b.model == 0u) {
        let exy = 0.5 * (h.y + h.z);
        let tr = h.x + h.w;
        let sxx = b.lambda_plane * tr + 2.0 * b.mu * h.x;
        let syy = b.lambda_plane * tr + 2.0 * b.mu * h.w;
        let sxy = 2.0 * b.mu * exy;
        pk = vec4<f32>(sxx, sxy, sxy, syy);
        w = 0.5 * (sxx * h.x + syy * h.w + 2.0 * sxy * exy);
    } else {
        // Out-of-plane stretch z = F33 (plane stress: mu (z^2 - 1) + lambda ln(J2 z) = 0).
        var zm1 = 0.0;
        if (b.formulation == 1u) {
            let ln_j2 = log1p(jm1);
            var z = max(1.0 - b.lambda * ln_j2 / (2.0 * b.mu + b.lambda), 0.1);
            for (var it = 0; it < 6; it++) {
                let g = b.mu * (z * z - 1.0) + b.lambda * (ln_j2 + log(z));
                let dg = 2.0 * b.mu * z + b.lambda / z;
                z -= g / dg;
            }
            zm1 = z - 1.0;
        }
        let ln_j = log1p(jm1) + log1p(zm1);
        // mu (F - F^-T) = mu (J F - cof F) / J, with the diagonal free of cancellation.
        let jf_cof = vec4<f32>(jm1 + j * h.x - h.w, j * f.y + f.z, j * f.z + f.y, jm1 + j * h.w - h.x);
        let fit = vec4<f32>(f.w, -f.z, -f.y, f.x) / j;
        pk = b.mu * jf_cof / j + b.lambda * ln_j * fit;
        // mu/2 (I1 - 3 - 2 ln J) + lambda/2 ln^2 J, I1 - 3 - 2 ln J written without cancellation:
        // 2 (trH - ln J2) + |H|^2 + (z^2 - 1 - 2 ln z); trH - ln J2 = -det H + (jm1 - ln(1 + jm1)).
        let hh = dot(h, h);
        let i1_term = 2.0 * (-(h.x * h.w - h.y * h.z) + x_minus_log1p(jm1)) + hh + zm1 * zm1 + 2.0 * x_minus_log1p(zm1);
        w = 0.5 * b.mu * i1_term + 0.5 * b.lambda * ln_j * ln_j;
    }

    // Current geometry.
    var xc: array<vec2<f32>, 4>;
    for (var a = 0; a < 4; a++) {
        xc[a] = x[a] + u[a];
    }
    let area = 0.5 * ((xc[2].x - xc[0].x) * (xc[3].y - xc[1].y) - (xc[3].x - xc[1].x) * (xc[2].y - xc[0].y));
    var min_corner = 3.0e38;
    for (var a = 0; a < 4; a++) {
        let p = xc[(a + 3) % 4];
        let c = xc[a];
        let n = xc[(a + 1) % 4];
        min_corner = min(min_corner, (n.x - c.x) * (p.y - c.y) - (n.y - c.y) * (p.x - c.x));
    }
    if (!(min_corner > 0.0)) {
        atomicMin(&ctrl.bad_element, e);
    }
    let d01 = xc[1] - xc[0];
    let d12 = xc[2] - xc[1];
    let d23 = xc[3] - xc[2];
    let d30 = xc[0] - xc[3];
    let d02 = xc[2] - xc[0];
    let d13 = xc[3] - xc[1];
    let side = max(max(dot(d01, d01), dot(d12, d12)), max(dot(d23, d23), dot(d30, d30)));
    let diag = 0.5 * max(dot(d02, d02), dot(d13, d13));
    let aa = abs(area);
    let length = aa / sqrt(max(side, diag));
    let rho = b.density * area0 / max(aa, 1e-37);
    let c = sqrt(b.wave_modulus / rho);

    var force: array<vec2<f32>, 4>;
    for (var a = 0; a < 4; a++) {
        force[a] = -a0t * vec2<f32>(pk.x * bx[a] + pk.y * by[a], pk.z * bx[a] + pk.w * by[a]);
    }

    // Hourglass control.
    var bb = 0.0;
    var gg = 0.0;
    for (var a = 0; a < 4; a++) {
        bb += bx[a] * bx[a] + by[a] * by[a];
        gg += gamma[a] * gamma[a];
    }
    var hg_stored = 0.0;
    var hg_q = vec2<f32>(0.0);
    var hg_rate = vec2<f32>(0.0);
    if (b.hourglass == 2u) {
        // Scaled with the shear modulus 2 mu (see ElementParams::hourglass_modulus).
        let k = b.hourglass_coefficient * 2.0 * b.mu * a0t * bb / gg;
        var q = vec2<f32>(0.0);
        for (var a = 0; a < 4; a++) {
            q += gamma[a] * u[a];
        }
        for (var a = 0; a < 4; a++) {
            force[a] -= k * gamma[a] * q;
        }
        hg_stored = 0.5 * k * dot(q, q);
    } else if (b.hourglass == 1u) {
        let rho_c = sqrt(2.0 * b.mu * b.density);
        let damp = b.hourglass_coefficient * rho_c * a0t * sqrt(bb) / gg;
        for (var a = 0; a < 4; a++) {
            hg_rate += gamma[a] * v[a];
        }
        hg_q = damp * hg_rate;
        for (var a = 0; a < 4; a++) {
            force[a] -= gamma[a] * hg_q;
        }
    }

    // Bulk viscosity.
    var dt = length / c;
    var bulk_p = vec4<f32>(0.0);
    if (b.bulk_linear > 0.0 || b.bulk_quadratic > 0.0) {
        var rate = fd.x + fd.w;
        if (b.model == 1u) {
            rate = (fd.x * f.w - fd.y * f.z - fd.z * f.y + fd.w * f.x) / j;
        }
        if (rate * length < -1e-9 * c) {
            let q = rho * length * (b.bulk_quadratic * length * rate * rate - b.bulk_linear * c * rate);
            if (b.model == 0u) {
                bulk_p = vec4<f32>(-q, 0.0, 0.0, -q);
            } else {
                bulk_p = vec4<f32>(-q * f.w, q * f.z, q * f.y, -q * f.x);
            }
        }
        // Linear part always (no jump in dt between compression and expansion), quadratic in compression.
        let qs = b.bulk_linear * c + b.bulk_quadratic * length * max(-rate, 0.0);
        dt = length / (qs + sqrt(qs * qs + c * c));
        for (var a = 0; a < 4; a++) {
            force[a] -= a0t * vec2<f32>(bulk_p.x * bx[a] + bulk_p.y * by[a], bulk_p.z * bx[a] + bulk_p.w * by[a]);
        }
    }

    var works = vec2<f32>(0.0);
//#if dissipation
    {
        let s0 = elem_state[2u * e];
        let p0 = elem_state[2u * e + 1u];
        let dtp = ctrl.dt_prev;
        let hg_work = 0.5 * dtp * dot(hg_rate, s0.xy + hg_q);
        let bulk_work = 0.5 * a0t * dtp * dot(p0 + bulk_p, fd);
        works = s0.zw + vec2<f32>(hg_work, bulk_work);
        elem_state[2u * e] = vec4<f32>(hg_q, works);
        elem_state[2u * e + 1u] = bulk_p;
    }
//#endif

    for (var a = 0u; a < 4u; a++) {
        elem_force[4u * e + a] = force[a];
    }
    elem_dt[e] = dt;
    if ((ctrl.flags & FLAG_SAMPLE) != 0u) {
        sample_src[params.n_nodes + e] = vec4<f32>(w * a0t, hg_stored, works);
    }
}
