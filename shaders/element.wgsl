// Element stage: one-point 4-node quad, total Lagrangian, one thread per element.
// Mirrors ricochet::step::element::evaluate (the f64 CPU reference) in f32, its loops over the
// corners as vec4 operations.
// A triangle is a collapsed quad (nodes.z == nodes.w): no hourglass control, centroid weights
// 1/3, one corner to check, the triangle's stable-step length (see the CPU module's notes).
// Each material model, plane stress's out-of-plane Newton iteration, the axisymmetric terms and
// the stiffness hourglass form are compiled only for scenes that have them (`//#if`): lavapipe
// runs a branch that its lanes do not take under a mask, and the 10^4-element pile's linear
// elastic step cost about 100 us more with the neo-Hookean branch in it.
// Material failure (`//#if failure`, scenes with a material's `failure` only): the criteria of
// ricochet::element::failure checked after the stress update, in the CPU's order and with its
// floors; an element that fails erodes at once (ricochet::step::cpu's element stage): no force,
// no stable step and no inversion check from that step on, its mass left on its nodes; with
// run.erosion.inverted (which compiles the failure part too) an element about to invert erodes
// the same way instead of stopping the run.
// Johnson-Cook thermal softening with adiabatic heating (`//#if thermal`, scenes with a material's
// `m` only): the temperature rise in the plastic state's third word of its second vec4, the flow
// stress times 1 - T*^m at the start of the step's temperature (held through the return), the
// rise raised by heating x the step's plastic work per unit reference volume (CPU:
// ricochet::element::evaluate_state), and T* at the end of the step in the damage's d5 term.

struct Body {
    model: u32,           // 0 linear elastic, 1 neo-Hookean, 2 J2 plastic
    formulation: u32,     // 0 plane strain, 1 plane stress, 2 axisymmetric
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
    yield_stress: f32,    // J2: sigma_y (Johnson-Cook: A)
    hardening: f32,       // J2: H (Johnson-Cook: 0)
    jc_b: f32,            // Johnson-Cook B, n, C, reference rate (0, 1, 0, 1 without)
    jc_n: f32,
    jc_c: f32,
    jc_rate0: f32,
    jc_m: f32,            // Johnson-Cook thermal softening m (0: none), T_m - T_r (1 without),
    melt_rise: f32,
    heating: f32,         // taylor_quinney / (density specific_heat) (0 without)
    _pad1: u32,
}

//#if failure
// A body's failure criteria (ricochet::scene::FailureCriteria; Rust mirror gpu::element::GpuFailure).
struct Failure {
    flags: u32,           // FAIL_*: the criteria the material has (0: none)
    plastic_strain: f32,  // equivalent plastic strain at failure
    principal_strain: f32, // largest principal logarithmic strain at failure
    tensile_pressure: f32, // mean stress (tension positive) at failure
    d1: f32,              // Johnson-Cook damage d1..d5 and the rate term's reference rate
    d2: f32,
    d3: f32,
    d4: f32,
    d5: f32,
    rate0: f32,
    inverted: u32,        // 1: an element about to invert erodes (run.erosion.inverted; every body)
    min_dt: f32,          // run.erosion.min_time_step / time_step_scale: a smaller stable step erodes (0: never)
}

const FAIL_PLASTIC: u32 = 1u;
const FAIL_JOHNSON_COOK: u32 = 2u;
const FAIL_PRINCIPAL: u32 = 4u;
const FAIL_TENSILE: u32 = 8u;
// ricochet::element::failure::MIN_FAILURE_STRAIN.
const MIN_FAILURE_STRAIN: f32 = 1e-3;
// The stable step of an eroded element: larger than any element's, below control.wgsl's empty
// minimum (3e38), so that a step whose elements have all eroded is recognised.
const ERODED_DT: f32 = 2.9e38;
//#endif

struct Element {
    c01: vec4<f32>,       // reference corners 0,1 relative to the element centre
    c23: vec4<f32>,       // corners 2,3
    nodes: vec4<u32>,
    body: u32,
    radius: f32,          // axisymmetric: reference radius of the centre
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
// v^{n-1/2}, the velocity residuals, then the displacement residuals (node.wgsl): each node's
// velocity is v + its residual (v_prev[n_nodes + i]) and its displacement u + its residual
// (v_prev[2 n_nodes + i]), to about eps_f32^2 of them.
@group(0) @binding(10) var<storage, read> v_prev: array<vec2<f32>>;
//#if dissipation
// (Q_x, Q_y, hourglass work, bulk work), (bulk P xx xy yx yy) per element, and with the
// axisymmetric variant (bulk P_33, 0, 0, 0)
@group(0) @binding(8) var<storage, read_write> elem_state: array<vec4<f32>>;
//#endif
//#if plastic
// J2: (C_p^-1 - I: xx, yy, xy, zz), (alpha, plastic work so far, temperature rise (thermal
// softening; 0 otherwise), 0) per element
@group(0) @binding(9) var<storage, read_write> plastic_state: array<vec4<f32>>;
//#endif
//#if failure
@group(0) @binding(11) var<storage, read> failures: array<Failure>;   // per body
// Per element: (eroded energy, 1 once eroded, Johnson-Cook damage, 1 if eroded about to invert).
@group(0) @binding(12) var<storage, read_write> erosion: array<vec4<f32>>;
// The elements eroded since the contact surfaces last followed, in the order they eroded (the
// host reads the first ctrl.eroded of them instead of every element's flag; one entry, never
// read, in a scene without contact).
@group(0) @binding(13) var<storage, read_write> eroded_list: array<u32>;
//#endif

// Words per element of the dissipative state.
//#if axisymmetric
const ES: u32 = 3u;
//#else
const ES: u32 = 2u;
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

// exp(x) - 1, accurate for small x.
fn expm1(x: f32) -> f32 {
    if (abs(x) < 1e-2) {
        return x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x * (1.0 / 24.0 + x / 120.0))));
    }
    return exp(x) - 1.0;
}

// J2 plasticity at finite strain (CPU reference: ricochet::step::plastic): Hencky elasticity on
// b_e = F C_p^-1 F^T, radial return in logarithmic strain on its principal axes, yield on the
// Cauchy stress. Kept as deviations from I (b_e - I, C_p^-1 - I, F - I) so that f32 keeps the
// small strains.
struct J2 {
    pk: vec4<f32>,        // first Piola-Kirchhoff xx xy yx yy
    p33: f32,
    cauchy: vec4<f32>,    // xx yy xy zz
    stored: f32,          // per reference volume
    dev: vec4<f32>,       // C_p^-1 - I after the step (xx yy xy zz)
    alpha: f32,
    yielded: bool,
}

// Symmetric (xx, yy, xy) with principal values a, b on the axes (c, s).
fn compose(a: f32, b: f32, c: f32, s: f32) -> vec3<f32> {
    return vec3<f32>(a * c * c + b * s * s, a * s * s + b * c * c, (a - b) * c * s);
}

// (sigma_y + H alpha + B alpha^n)(1 + C ln(max(rate / rate0, 1))).
fn flow_stress(bd: Body, alpha: f32, rate: f32) -> f32 {
    let hard = bd.yield_stress + bd.hardening * alpha + bd.jc_b * pow(max(alpha, 0.0), bd.jc_n);
    return hard * (1.0 + bd.jc_c * log(max(rate / bd.jc_rate0, 1.0)));
}

// The increment of alpha of the return (CPU: plastic::return_increment): closed form for linear
// hardening, else Newton's method kept inside the bracket (0, q / 3 mu).
fn return_increment(bd: Body, q: f32, j: f32, alpha: f32, dt: f32) -> f32 {
    let mu = bd.mu;
    if (bd.jc_b == 0.0 && bd.jc_c == 0.0) {
        return (q - j * (bd.yield_stress + bd.hardening * alpha)) / (3.0 * mu + j * bd.hardening);
    }
    var lo = 0.0;
    var hi = q / (3.0 * mu);
    var x = 0.5 * hi;
    for (var it = 0; it < 60; it++) {
        var rate = 0.0;
        if (dt > 0.0) {
            rate = x / dt;
        }
        let gx = q - 3.0 * mu * x - j * flow_stress(bd, alpha + x, rate);
        if (gx > 0.0) {
            lo = x;
        } else {
            hi = x;
        }
        let a = alpha + x;
        let r = rate / bd.jc_rate0;
        let rate_factor = 1.0 + bd.jc_c * log(max(r, 1.0));
        let hard = bd.yield_stress + bd.hardening * a + bd.jc_b * pow(a, bd.jc_n);
        let d_hard = bd.hardening + bd.jc_b * bd.jc_n * pow(a, bd.jc_n - 1.0);
        var d_rate = 0.0;
        if (r > 1.0) {
            d_rate = bd.jc_c / x;
        }
        let dg = -3.0 * mu - j * (d_hard * rate_factor + hard * d_rate);
        var next = x - gx / dg;
        if (!(next > lo && next < hi)) {
            next = 0.5 * (lo + hi);
        }
        if (abs(next - x) <= 1e-7 * (hi + lo) || hi - lo <= 1e-7 * hi) {
            return next;
        }
        x = next;
    }
    return x;
}

// h = F - I (xx xy yx yy), jm1 = det F - 1 (in plane), zm1 = F_33 - 1, d = C_p^-1 - I; dt the
// step that led here (the Johnson-Cook rate; 0: none); soft the thermal softening factor
// 1 - T*^m of the start of the step (1 without).
fn j2_update(bd: Body, h: vec4<f32>, jm1: f32, zm1: f32, d: vec4<f32>, alpha: f32, allow: bool, dt: f32, soft: f32) -> J2 {
    let f = h + vec4<f32>(1.0, 0.0, 0.0, 1.0);
    // b - I = (F F^T - I) + F D F^T.
    let fd00 = f.x * d.x + f.y * d.z;
    let fd01 = f.x * d.z + f.y * d.y;
    let fd10 = f.z * d.x + f.w * d.z;
    let fd11 = f.z * d.z + f.w * d.y;
    let bxx = 2.0 * h.x + h.x * h.x + h.y * h.y + fd00 * f.x + fd01 * f.y;
    let byy = 2.0 * h.w + h.z * h.z + h.w * h.w + fd10 * f.z + fd11 * f.w;
    let bxy = h.z + h.y + h.x * h.z + h.y * h.w + fd00 * f.z + fd01 * f.w;
    let m = 0.5 * (bxx + byy);
    let dd = 0.5 * (bxx - byy);
    let r = sqrt(dd * dd + bxy * bxy);
    let theta = 0.5 * atan2(bxy, dd);
    let cs = cos(theta);
    let sn = sin(theta);
    let eps = vec3<f32>(0.5 * log1p(m + r), 0.5 * log1p(m - r), 0.5 * log1p(d.w) + log1p(zm1));
    let ev = eps.x + eps.y + eps.z;
    var e = eps - vec3<f32>(ev / 3.0);
    let e2_trial = dot(e, e);
    let mu = bd.mu;
    let q = 2.0 * mu * sqrt(1.5 * e2_trial);
    let j = (1.0 + jm1) * (1.0 + zm1);
//#if thermal
    let flow = flow_stress(bd, alpha, 0.0) * soft;
//#else
    let flow = flow_stress(bd, alpha, 0.0);
//#endif
    var out: J2;
    out.dev = d;
    out.alpha = alpha;
    out.yielded = false;
    if (allow && q > j * flow) {
//#if thermal
        let d_alpha = return_increment(bd, q, j * soft, alpha, dt);
//#else
        let d_alpha = return_increment(bd, q, j, alpha, dt);
//#endif
        e *= 1.0 - 3.0 * mu * d_alpha / q;
        out.alpha = alpha + d_alpha;
        out.yielded = true;
        // b - I = expm1(2 eps) on the same axes; C_p^-1 - I = F^-1 (b - I) F^-T + (C^-1 - I).
        let nb = compose(expm1(2.0 * (e.x + ev / 3.0)), expm1(2.0 * (e.y + ev / 3.0)), cs, sn);
        let dj = 1.0 + jm1;
        let i00 = f.w / dj;
        let i01 = -f.y / dj;
        let i10 = -f.z / dj;
        let i11 = f.x / dj;
        let t00 = i00 * nb.x + i01 * nb.z;
        let t01 = i00 * nb.z + i01 * nb.y;
        let t10 = i10 * nb.x + i11 * nb.z;
        let t11 = i10 * nb.z + i11 * nb.y;
        // C - I = H + H^T + H^T H; C^-1 - I = -C^-1 (C - I).
        let exx = 2.0 * h.x + h.x * h.x + h.z * h.z;
        let eyy = 2.0 * h.w + h.y * h.y + h.w * h.w;
        let exy = h.y + h.z + h.x * h.y + h.z * h.w;
        let cxx = 1.0 + exx;
        let cyy = 1.0 + eyy;
        let det_c = dj * dj;
        let ci_xx = -(cyy * exx - exy * exy) / det_c;
        let ci_yy = -(cxx * eyy - exy * exy) / det_c;
        let ci_xy = -(cyy * exy - exy * eyy) / det_c;
        out.dev = vec4<f32>(
            t00 * i00 + t01 * i01 + ci_xx,
            t10 * i10 + t11 * i11 + ci_yy,
            t00 * i10 + t01 * i11 + ci_xy,
            expm1(2.0 * (e.z + ev / 3.0) - 2.0 * log1p(zm1)),
        );
    }
    let k = bd.lambda + 2.0 * mu / 3.0;
    out.stored = 0.5 * k * ev * ev + mu * dot(e, e);
    let tau = 2.0 * mu * e + vec3<f32>(k * ev);
    let t = compose(tau.x, tau.y, cs, sn);
    // P = tau F^-T, F^-T = [f.w -f.z; -f.y f.x] / det F in plane.
    let dj = 1.0 + jm1;
    let m00 = f.w / dj;
    let m01 = -f.z / dj;
    let m10 = -f.y / dj;
    let m11 = f.x / dj;
    out.pk = vec4<f32>(t.x * m00 + t.z * m10, t.x * m01 + t.z * m11, t.z * m00 + t.y * m10, t.z * m01 + t.y * m11);
    out.p33 = tau.z / (1.0 + zm1);
    out.cauchy = vec4<f32>(t.x, t.y, t.z, tau.z) / j;
    return out;
}

//#if failure
// The failure check of an element after its stress update (CPU: element::failure::check): its
// Cauchy stress `s` (xx yy xy zz), deformation gradient `f` (xx xy yx yy) and hoop stretch
// `f33`, equivalent plastic strain before and after the step, the step `dt` that led here (0 on
// the first), its damage before the step and its homologous temperature T* after the step (0
// without thermal softening). Returns (damage after the step, 1 if it failed).
fn failure_check(fp: Failure, s: vec4<f32>, f: vec4<f32>, f33: f32, alpha_old: f32, alpha: f32, dt: f32, damage_old: f32, t_star: f32) -> vec2<f32> {
    var failed = false;
    var damage = damage_old;
    if ((fp.flags & FAIL_PLASTIC) != 0u) {
        failed = failed || alpha >= fp.plastic_strain;
    }
    let mean = (s.x + s.y + s.w) / 3.0;
    let a = s.x - s.y;
    let b = s.y - s.w;
    let c = s.w - s.x;
    let vm = sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * s.z * s.z);
    if ((fp.flags & FAIL_JOHNSON_COOK) != 0u) {
        let d_alpha = alpha - alpha_old;
        if (d_alpha > 0.0 && vm > 0.0) {
            var rate = 0.0;
            if (dt > 0.0) {
                rate = d_alpha / dt;
            }
            let tri = mean / vm;
            // No damage below sigma* = -1/3, nor where eps_f is not finite (an overflow).
            if (tri >= -1.0 / 3.0) {
                let rate_term = 1.0 + fp.d4 * log(max(rate / fp.rate0, 1.0));
//#if thermal
                let eps = (fp.d1 + fp.d2 * exp(fp.d3 * tri)) * rate_term * (1.0 + fp.d5 * t_star);
//#else
                // Without thermal softening T* is 0: the d5 term is 1.
                let eps = (fp.d1 + fp.d2 * exp(fp.d3 * tri)) * rate_term;
//#endif
                // NaN or +inf (by bit pattern): no damage; -inf takes the floor, as on the CPU.
                let bits = bitcast<u32>(eps);
                if (!((bits & 0x7fffffffu) > 0x7f800000u || bits == 0x7f800000u)) {
                    damage += d_alpha / max(eps, MIN_FAILURE_STRAIN);
                }
            }
        }
        failed = failed || damage >= 1.0;
    }
    if ((fp.flags & FAIL_PRINCIPAL) != 0u) {
        // C = F^T F in plane; its largest eigenvalue is lambda_max^2.
        let c11 = f.x * f.x + f.z * f.z;
        let c22 = f.y * f.y + f.w * f.w;
        let c12 = f.x * f.y + f.z * f.w;
        let m = 0.5 * (c11 + c22);
        let r = length(vec2<f32>(0.5 * (c11 - c22), c12));
        failed = failed || max(0.5 * log(m + r), log(f33)) >= fp.principal_strain;
    }
    if ((fp.flags & FAIL_TENSILE) != 0u) {
        failed = failed || mean >= fp.tensile_pressure;
    }
    return vec2<f32>(damage, select(0.0, 1.0, failed));
}
//#endif

@compute @workgroup_size(WG)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    // The step's control words, read before any lane returns (lavapipe loads an address that
    // every lane shares once while no lane has left; after that, lane by lane).
    let state = ctrl.state;
    let flags = ctrl.flags;
    let dt_prev = ctrl.dt_prev;
    if (e >= params.n_elems || state != STATE_RUNNING) {
        return;
    }
//#if failure
    let eroding = erosion[e];
    if (eroding.y != 0.0) {
        // Eroded: its force (zero), stable step and sample sums were written when it eroded.
        return;
    }
//#endif
    let el = elems[e];
    let b = bodies[el.body];
    // Per-corner quantities as vec4s over the corners (x components, y components): every loop
    // over the corners is a vector operation, with no array indexed in a loop (lavapipe kept
    // such arrays in memory, per lane).
    let xs = vec4<f32>(el.c01.x, el.c01.z, el.c23.x, el.c23.z);
    let ys = vec4<f32>(el.c01.y, el.c01.w, el.c23.y, el.c23.w);
    let s0 = nodes[el.nodes.x];
    let s1 = nodes[el.nodes.y];
    let s2 = nodes[el.nodes.z];
    let s3 = nodes[el.nodes.w];
    let ux = vec4<f32>(s0.x, s1.x, s2.x, s3.x);
    let uy = vec4<f32>(s0.y, s1.y, s2.y, s3.y);
    let vx = vec4<f32>(s0.z, s1.z, s2.z, s3.z);
    let vy = vec4<f32>(s0.w, s1.w, s2.w, s3.w);
    let ur = 2u * params.n_nodes;
    let vr = params.n_nodes;
    let vl0 = v_prev[vr + el.nodes.x];
    let vl1 = v_prev[vr + el.nodes.y];
    let vl2 = v_prev[vr + el.nodes.z];
    let vl3 = v_prev[vr + el.nodes.w];
    let ul0 = v_prev[ur + el.nodes.x];
    let ul1 = v_prev[ur + el.nodes.y];
    let ul2 = v_prev[ur + el.nodes.z];
    let ul3 = v_prev[ur + el.nodes.w];
    let tri = el.nodes.z == el.nodes.w;
    // Corner weights at the centre: 1/4 each, or 1/3 on a triangle's three corners.
    let wc = select(vec4<f32>(0.25), vec4<f32>(1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 0.0), tri);

    // Reference geometry at the centre.
    let area0 = 0.5 * ((xs.z - xs.x) * (ys.w - ys.y) - (xs.w - xs.y) * (ys.z - ys.x));
    let sc = 0.5 / area0;
    // b_a = dN_a/dX at the centre: (y_{a+1} - y_{a-1}, x_{a-1} - x_{a+1}) / (2 A0).
    let bx = sc * (ys.yzwx - ys.wxyz);
    let by = sc * (xs.wxyz - xs.yzwx);
    let hx = xs.x - xs.y + xs.z - xs.w;
    let hy = ys.x - ys.y + ys.z - ys.w;
    let gamma = vec4<f32>(1.0, -1.0, 1.0, -1.0) - hx * bx - hy * by;
    // Axisymmetric: F_33 = r / R at the centre, its rate, the volume per radian A0 R.
//#if axisymmetric
    let axi = b.formulation == 2u;
//#else
    let axi = false;
//#endif
    var zm1 = 0.0;
    var f33d = 0.0;
    var a0t = area0 * b.thickness;
    if (axi) {
        let rr = el.radius;
        zm1 = dot(wc, ux) / rr;
        f33d = dot(wc, vx) / rr;
        a0t = area0 * rr;
    }
    // The hoop stretch r / R (1 off axisymmetric bodies; plane stress's F_33 is not it).
    let hoop_stretch = 1.0 + zm1;

    // Displacement gradient H = F - I and its rate, from the corners' displacements and
    // velocities relative to corner 0 (the same in exact arithmetic, since sum_a b_a = 0): in f32
    // a rigid translation then gives no strain at all, where the absolute u (a body slid by many
    // element sizes) would leave eps_f32 u / h of it, random per element and step. Each corner's
    // u carries its own rounding (node.wgsl's compensated update), up to half an ulp of u apart
    // between corners: that much strain noise (as large as the strain of a block resting under
    // gravity once it has slid a few mm) drove the elements like a random load, so the difference
    // adds the corners' residuals (the low parts of their displacements), and the same for the
    // velocities (a body sliding at 1 m/s: half an ulp is 6e-8 m/s).
    // (Corner 0's differences are 0, so the dot products sum corners 1 to 3.)
    let ulx = vec4<f32>(ul0.x, ul1.x, ul2.x, ul3.x);
    let uly = vec4<f32>(ul0.y, ul1.y, ul2.y, ul3.y);
    let vlx = vec4<f32>(vl0.x, vl1.x, vl2.x, vl3.x);
    let vly = vec4<f32>(vl0.y, vl1.y, vl2.y, vl3.y);
    let dux = (ux - ux.x) + (ulx - ulx.x);
    let duy = (uy - uy.x) + (uly - uly.x);
    let dwx = (vx - vx.x) + (vlx - vlx.x);
    let dwy = (vy - vy.x) + (vly - vly.x);
    let h = vec4<f32>(dot(dux, bx), dot(dux, by), dot(duy, bx), dot(duy, by));   // xx xy yx yy
    let fd = vec4<f32>(dot(dwx, bx), dot(dwx, by), dot(dwy, bx), dot(dwy, by));
    let f = h + vec4<f32>(1.0, 0.0, 0.0, 1.0);
    let jm1 = h.x + h.w + h.x * h.w - h.y * h.z;   // J - 1 without cancellation
    let j = 1.0 + jm1;

    // Stress (first Piola-Kirchhoff) and strain energy density.
    var pk: vec4<f32>;
    var p33 = 0.0;
    var w: f32;
    var plastic_work = 0.0;
    // The Cauchy stress (xx yy xy zz) and equivalent plastic strain before and after the step,
    // for the failure check.
    var cauchy = vec4<f32>(0.0);
    var alpha_old = 0.0;
    var alpha_new = 0.0;
    // The homologous temperature after the step (thermal softening; 0 otherwise).
    var t_star = 0.0;
    if (b.model == 0u) {
//#if linear_elastic
        let exy = 0.5 * (h.y + h.z);
        // zm1: the hoop strain u_r / R (axisymmetric; 0 otherwise).
        let tr = h.x + h.w + zm1;
        let sxx = b.lambda_plane * tr + 2.0 * b.mu * h.x;
        let syy = b.lambda_plane * tr + 2.0 * b.mu * h.w;
        let sxy = 2.0 * b.mu * exy;
        p33 = b.lambda * tr + 2.0 * b.mu * zm1;
        pk = vec4<f32>(sxx, sxy, sxy, syy);
        w = 0.5 * (sxx * h.x + syy * h.w + 2.0 * sxy * exy + p33 * zm1);
//#if failure
        cauchy = vec4<f32>(sxx, syy, sxy, select(p33, 0.0, b.formulation == 1u));
//#endif
//#endif
    } else if (b.model == 2u) {
//#if plastic
        let ps0 = plastic_state[2u * e];
        let ps1 = plastic_state[2u * e + 1u];
        // Thermal softening at the temperature of the start of the step.
        var soft = 1.0;
        var heat = 0.0;
//#if thermal
        heat = ps1.z;
        if (b.jc_m > 0.0) {
            let ts = clamp(heat / b.melt_rise, 0.0, 1.0);
            if (ts > 0.0) {
                soft = 1.0 - pow(ts, b.jc_m);
            }
        }
//#endif
        let s = j2_update(b, h, jm1, zm1, ps0, ps1.x, true, dt_prev, soft);
        pk = s.pk;
        p33 = s.p33;
        w = s.stored;
        cauchy = s.cauchy;
        alpha_old = ps1.x;
        alpha_new = s.alpha;
        var acc = ps1.y;
        if (s.yielded) {
            let dtp = dt_prev;
            if (dtp > 0.0) {
                // The start of the step that yielded, from the old state, no return.
                let ho = h - dtp * fd;
                let jo = ho.x + ho.w + ho.x * ho.w - ho.y * ho.z;
                let so = j2_update(b, ho, jo, zm1 - dtp * f33d, ps0, ps1.x, false, 0.0, soft);
                plastic_work = 0.5 * dtp * (dot(so.pk + s.pk, fd) + (so.p33 + s.p33) * f33d) - (s.stored - so.stored);
            }
            acc += plastic_work * a0t;
//#if thermal
            // Adiabatic heating of the step's plastic work (never negative).
            heat += b.heating * max(plastic_work, 0.0);
//#endif
            plastic_state[2u * e] = s.dev;
            plastic_state[2u * e + 1u] = vec4<f32>(s.alpha, acc, heat, 0.0);
        }
//#if thermal
        if (b.jc_m > 0.0) {
            t_star = clamp(heat / b.melt_rise, 0.0, 1.0);
        }
//#endif
        if ((flags & FLAG_SAMPLE) != 0u) {
            var off = params.n_nodes + params.n_elems + params.n_cons;
            if (params.loads != 0u) {
                off += params.n_nodes;
            }
            sample_src[off + e] = vec4<f32>(acc, 0.0, 0.0, 0.0);
        }
//#endif
    } else {
//#if neo_hookean
        // Out-of-plane stretch z = F33 (plane stress: mu (z^2 - 1) + lambda ln(J2 z) = 0;
        // axisymmetric: r / R, above).
//#if plane_stress
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
//#endif
        let ln_j = log1p(jm1) + log1p(zm1);
        // mu (F - F^-T) = mu (J F - cof F) / J, with the diagonal free of cancellation.
        let jf_cof = vec4<f32>(jm1 + j * h.x - h.w, j * f.y + f.z, j * f.z + f.y, jm1 + j * h.w - h.x);
        let fit = vec4<f32>(f.w, -f.z, -f.y, f.x) / j;
        pk = b.mu * jf_cof / j + b.lambda * ln_j * fit;
        if (b.formulation != 1u) {
            // P_33 = mu (F_33 - 1 / F_33) + lambda ln J / F_33.
            p33 = (b.mu * zm1 * (2.0 + zm1) + b.lambda * ln_j) / (1.0 + zm1);
        }
        // mu/2 (I1 - 3 - 2 ln J) + lambda/2 ln^2 J, I1 - 3 - 2 ln J written without cancellation:
        // 2 (trH - ln J2) + |H|^2 + (z^2 - 1 - 2 ln z); trH - ln J2 = -det H + (jm1 - ln(1 + jm1)).
        let hh = dot(h, h);
        let i1_term = 2.0 * (-(h.x * h.w - h.y * h.z) + x_minus_log1p(jm1)) + hh + zm1 * zm1 + 2.0 * x_minus_log1p(zm1);
        w = 0.5 * b.mu * i1_term + 0.5 * b.lambda * ln_j * ln_j;
//#if failure
        // Cauchy = P F^T / J, sigma_33 = P_33 F_33 / J.
        let jj = j * (1.0 + zm1);
        cauchy = vec4<f32>(
            (pk.x * f.x + pk.y * f.y) / jj,
            (pk.z * f.z + pk.w * f.w) / jj,
            (pk.x * f.z + pk.y * f.w) / jj,
            p33 * (1.0 + zm1) / jj,
        );
//#endif
//#endif
    }

    // Current geometry.
    let cx = xs + ux;
    let cy = ys + uy;
    let area = 0.5 * ((cx.z - cx.x) * (cy.w - cy.y) - (cx.w - cx.y) * (cy.z - cy.x));
    // Each corner's turn (next - corner) x (previous - corner); a triangle checks corner 0 only.
    let turn = (cx.yzwx - cx) * (cy.wxyz - cy) - (cy.yzwx - cy) * (cx.wxyz - cx);
    let first = min(3.0e38, turn.x);
    let min_corner = select(min(min(min(first, turn.y), turn.z), turn.w), first, tri);
    // Sides (corner a to a + 1) and the two diagonals, squared.
    let sx = cx.yzwx - cx;
    let sy = cy.yzwx - cy;
    let sides = sx * sx + sy * sy;
    let side = max(max(sides.x, sides.y), max(sides.z, sides.w));
    let gx = cx.zw - cx.xy;
    let gy = cy.zw - cy.xy;
    let diags = gx * gx + gy * gy;
    let diag = 0.5 * max(diags.x, diags.y);
    let aa = abs(area);
    // A triangle: sqrt(8/3) area / longest side (CPU: TRIANGLE_LENGTH).
    let length = aa / sqrt(max(side, diag)) * select(1.0, 1.6329932, tri);
    let rho = b.density * area0 / max(aa, 1e-37);
    let c = sqrt(b.wave_modulus / rho);

    // The corners' forces (x components, y components).
    var fx = -a0t * (pk.x * bx + pk.y * by);
    var fy = -a0t * (pk.z * bx + pk.w * by);
    if (axi) {
        // The hoop stress on u_r: dF_33 / du_r,a = N_a / R.
        let hoop = a0t * p33 / el.radius;
        fx -= wc * hoop;
    }

    // Hourglass control.
    let bb = dot(bx, bx) + dot(by, by);
    let gg = dot(gamma, gamma);
    var hg_stored = 0.0;
    var hg_q = vec2<f32>(0.0);
    var hg_rate = vec2<f32>(0.0);
//#if hourglass_stiffness
    let stiffness = b.hourglass == 2u;
//#else
    let stiffness = false;
//#endif
    if (stiffness && !tri) {
        // Scaled with the shear modulus 2 mu (see ElementParams::hourglass_modulus).
        let k = b.hourglass_coefficient * 2.0 * b.mu * a0t * bb / gg;
        let q = vec2<f32>(dot(gamma, dux), dot(gamma, duy));
        fx -= k * gamma * q.x;
        fy -= k * gamma * q.y;
        hg_stored = 0.5 * k * dot(q, q);
    } else if (b.hourglass == 1u && !tri) {
        let rho_c = sqrt(2.0 * b.mu * b.density);
        let damp = b.hourglass_coefficient * rho_c * a0t * sqrt(bb) / gg;
        hg_rate = vec2<f32>(dot(gamma, vx - vx.x), dot(gamma, vy - vy.x));
        hg_q = damp * hg_rate;
        fx -= gamma * hg_q.x;
        fy -= gamma * hg_q.y;
    }

    // Bulk viscosity.
    var dt = length / c;
    var bulk_p = vec4<f32>(0.0);
    var bulk_hoop = 0.0;
    if (b.bulk_linear > 0.0 || b.bulk_quadratic > 0.0) {
        var rate = fd.x + fd.w + f33d;
        if (b.model != 0u) {
            rate = (fd.x * f.w - fd.y * f.z - fd.z * f.y + fd.w * f.x) / j + f33d / (1.0 + zm1);
        }
        if (rate * length < -1e-9 * c) {
            let q = rho * length * (b.bulk_quadratic * length * rate * rate - b.bulk_linear * c * rate);
            if (b.model == 0u) {
                bulk_p = vec4<f32>(-q, 0.0, 0.0, -q);
                if (axi) {
                    bulk_hoop = -q;
                }
            } else {
                // -q J F^-T: in plane -q F_33 cof(F), hoop -q det F.
                let z = select(1.0, 1.0 + zm1, axi);
                bulk_p = vec4<f32>(-q * z * f.w, q * z * f.z, q * z * f.y, -q * z * f.x);
                if (axi) {
                    bulk_hoop = -q * j;
                }
            }
        }
        // Linear part always (no jump in dt between compression and expansion), quadratic in compression.
        let qs = b.bulk_linear * c + b.bulk_quadratic * length * max(-rate, 0.0);
        dt = length / (qs + sqrt(qs * qs + c * c));
        fx -= a0t * (bulk_p.x * bx + bulk_p.y * by);
        fy -= a0t * (bulk_p.z * bx + bulk_p.w * by);
        if (axi) {
            let hoop = a0t * bulk_hoop / el.radius;
            fx -= wc * hoop;
        }
    }

    var works = vec2<f32>(0.0);
//#if dissipation
    {
        let s0 = elem_state[ES * e];
        let p0 = elem_state[ES * e + 1u];
        let dtp = dt_prev;
        let hg_work = 0.5 * dtp * dot(hg_rate, s0.xy + hg_q);
        var bulk_work = 0.5 * a0t * dtp * dot(p0 + bulk_p, fd);
//#if axisymmetric
        bulk_work += 0.5 * a0t * dtp * (elem_state[ES * e + 2u].x + bulk_hoop) * f33d;
        elem_state[ES * e + 2u] = vec4<f32>(bulk_hoop, 0.0, 0.0, 0.0);
//#endif
        works = s0.zw + vec2<f32>(hg_work, bulk_work);
        elem_state[ES * e] = vec4<f32>(hg_q, works);
        elem_state[ES * e + 1u] = bulk_p;
    }
//#endif

//#if failure
    let fp = failures[el.body];
    var damage = eroding.z;
    var failed = false;
    if (fp.flags != 0u) {
        let check = failure_check(fp, cauchy, f, hoop_stretch, alpha_old, alpha_new, dt_prev, eroding.z, t_star);
        damage = check.x;
        failed = check.y != 0.0;
    }
    // run.erosion.inverted: an element about to invert erodes instead of stopping the run;
    // run.erosion.min_time_step: so does one whose stable step falls below the limit (each
    // counted apart: the fourth word of its erosion state, 1 and 2; ricochet::gpu::element).
    let inverted = !failed && fp.inverted != 0u && !(min_corner > 0.0);
    let small_step = !failed && min_corner > 0.0 && dt < fp.min_dt;
    {
        if (failed || inverted || small_step) {
            // Eroded at once (CPU: step::cpu's element stage): no force and no stable step from
            // now on, no inversion check. Its strain and stored hourglass energy leave with it,
            // less the half-step work of its unapplied forces (dot(f_n, v^{n-1/2}) dt / 2); its
            // viscous and plastic work of the step are done, its dissipative state cleared.
            let half_work = 0.5 * dt_prev * (dot(fx, vx) + dot(fy, vy));
            let energy = w * a0t + hg_stored + half_work;
            erosion[e] = vec4<f32>(energy, 1.0, damage, select(select(0.0, 2.0, small_step), 1.0, inverted));
            // For the contact surfaces to follow (an integer count, and a list whose order the
            // host does not use: no order dependence).
            let at = atomicAdd(&ctrl.eroded, 1u);
            if (at < arrayLength(&eroded_list)) {
                eroded_list[at] = e;
            }
            elem_force[4u * e] = vec2<f32>(0.0);
            elem_force[4u * e + 1u] = vec2<f32>(0.0);
            elem_force[4u * e + 2u] = vec2<f32>(0.0);
            elem_force[4u * e + 3u] = vec2<f32>(0.0);
            elem_dt[e] = ERODED_DT;
//#if dissipation
            elem_state[ES * e] = vec4<f32>(0.0, 0.0, works);
            elem_state[ES * e + 1u] = vec4<f32>(0.0);
//#if axisymmetric
            elem_state[ES * e + 2u] = vec4<f32>(0.0);
//#endif
//#endif
            // The sample sums it keeps from now on (written once: it never runs again).
            sample_src[params.n_nodes + e] = vec4<f32>(0.0, 0.0, works);
            sample_src[params.failure_at + e] = vec4<f32>(energy, 1.0, 0.0, 0.0);
//#if plastic
            if (params.plastic != 0u) {
                var off = params.n_nodes + params.n_elems + params.n_cons;
                if (params.loads != 0u) {
                    off += params.n_nodes;
                }
                sample_src[off + e] = vec4<f32>(plastic_state[2u * e + 1u].y, 0.0, 0.0, 0.0);
            }
//#endif
            return;
        }
        if (fp.flags != 0u) {
            erosion[e] = vec4<f32>(0.0, 0.0, damage, 0.0);
        }
    }
//#endif
    if (!(min_corner > 0.0)) {
        atomicMin(&ctrl.bad_element, e);
    }
    elem_force[4u * e] = vec2<f32>(fx.x, fy.x);
    elem_force[4u * e + 1u] = vec2<f32>(fx.y, fy.y);
    elem_force[4u * e + 2u] = vec2<f32>(fx.z, fy.z);
    elem_force[4u * e + 3u] = vec2<f32>(fx.w, fy.w);
    elem_dt[e] = dt;
    if ((flags & FLAG_SAMPLE) != 0u) {
        sample_src[params.n_nodes + e] = vec4<f32>(w * a0t, hg_stored, works);
    }
}
