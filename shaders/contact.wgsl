// CONTACT step, one workgroup, after the uncoupled update (node and boundary kernels): narrow phase
// of every slot (a pass's slave node or a wall's node) against its candidate segments from the
// host's broad phase, penalty impulses, then the diagonal-mass Lagrange correction by projected
// Gauss-Seidel sweeps over colours (slots of one colour share no node, so each colour is updated in
// parallel with the result of a sequential sweep: deterministic), and the corrected velocities,
// u_{n+1}, energies and interface reports. Mirrors crate::contact::ContactSet::apply.
// When a contact node has moved more than half the search margin since the last search, the kernel
// stops the run (STATE_SEARCH) before changing anything; the host searches again and resumes the step.

const RG: u32 = 256u;
const STATE_SEARCH: u32 = 4u;
const KIND_NONE: u32 = 0u;
const KIND_LAGRANGE: u32 = 1u;
const KIND_PENALTY: u32 = 2u;
const XI_TOLERANCE: f32 = 1e-6;
const TIE_TOLERANCE: f32 = 1e-4;      // crate::contact::narrow::TIE_TOLERANCE
const ACTIVE_SET_ROUNDS: u32 = 4u;    // crate::contact::ACTIVE_SET_ROUNDS

struct ContactParams {
    n_local: u32,         // contact nodes
    n_slots: u32,
    n_ifaces: u32,
    n_colors: u32,        // colours of the last search
    margin: f32,
    max_sweeps: u32,
    searched: u32,        // 0 until the first search
    hist_stride: u32,     // f32 words per contact history row: 1 + 4 n_ifaces
    color_base: u32,      // offset of the colour offsets in `search` (the candidate offsets are at 0)
    slot_base: u32,       // offset of the slots in colour order
    cand_base: u32,       // offset of the candidate segments
    row_capacity: u32,
}

struct Slot {
    info: u32,            // interface (bits 0-15), penalty (bit 16), wall (bit 17), second body is slave (bit 18)
    s: u32,               // slave (local node)
    np: u32,              // the slave's neighbours along its own surface (passes)
    nn: u32,
    normal: vec2<f32>,    // walls: unit normal and a point
    point: vec2<f32>,
    k: f32,               // walls: penalty stiffness of the node
    _p0: f32,
    _p1: f32,
    _p2: f32,
}

struct Segment {
    a: u32,
    b: u32,
    k: f32,               // penalty stiffness
    _p0: u32,
}

struct Cons {
    kind: u32,
    a: u32,
    b: u32,
    _p0: u32,
    n: vec2<f32>,
    xi: f32,
    g0: f32,              // gap at u_{n+1} of the free update
    w: f32,               // dt (1/m_s + (1-xi)^2/m_a + xi^2/m_b) along n
    lambda: f32,
    pen: f32,             // penalty: penetration at u_n
    dt_warm: f32,         // dt_n of the step that found lambda (Lagrange: the next step's warm start)
}

@group(0) @binding(0) var<uniform> cp: ContactParams;
@group(0) @binding(1) var<storage, read_write> ctrl: Control;
@group(0) @binding(2) var<storage, read_write> nodes: array<vec4<f32>>;   // (u, v)
@group(0) @binding(3) var<storage, read> v_prev: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read_write> sample_src: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> c_nodes: array<vec2<u32>>;       // (global index, mass bits)
@group(0) @binding(6) var<storage, read> c_ref: array<vec4<f32>>;         // (X, 1/m along x, y)
@group(0) @binding(7) var<storage, read> slots: array<Slot>;
@group(0) @binding(8) var<storage, read> segs: array<Segment>;
@group(0) @binding(9) var<storage, read> search: array<u32>;
@group(0) @binding(10) var<storage, read_write> u_search: array<vec2<f32>>; // u at the last search
@group(0) @binding(11) var<storage, read_write> c_pv: array<vec4<f32>>;     // 2i: (u_n, u_n + dt v_free), 2i+1: (v_free, v^{n-1/2})
@group(0) @binding(12) var<storage, read_write> c_vd: array<vec4<f32>>;     // (v^{n+1/2} kept for the next step, dv)
@group(0) @binding(13) var<storage, read_write> cons: array<Cons>;
// History rows (1 + 4 n_ifaces words each, row_capacity rows), then per interface the impulse and
// time since the last sample, then (work, this step's part after t_n).
@group(0) @binding(14) var<storage, read_write> c_hist: array<f32>;

// 1 / (1 + c): mass damping makes the update's masses (1 + c) m (see Control.damp_c).
var<private> inv_scale: f32 = 1.0;
// dt during an active-set re-check (trial positions corrected by dt dv), else 0.
var<private> corr_dt: f32 = 0.0;

var<workgroup> sh_u: u32;
var<workgroup> sh_far: atomic<u32>;
var<workgroup> sh_lagrange: atomic<u32>;
var<workgroup> sh_new: atomic<u32>;
var<workgroup> sh_f: array<vec4<f32>, RG>;
var<workgroup> sh_m: array<f32, RG>;

fn x_n(i: u32, j: u32) -> vec2<f32> {
    return (c_ref[i].xy - c_ref[j].xy) + (pos(i).xy - pos(j).xy);
}

fn x_tr(i: u32, j: u32) -> vec2<f32> {
    return (c_ref[i].xy - c_ref[j].xy) + (pos(i).zw - pos(j).zw) + corr_dt * (dv(i) - dv(j));
}

fn along(i: u32, n: vec2<f32>) -> f32 {
    let im = c_ref[i].zw * inv_scale;
    return n.x * n.x * im.x + n.y * n.y * im.y;
}

// Signed distance to the line a -> b of the vector d = p - a along t = b - a.
fn line_gap(d: vec2<f32>, t: vec2<f32>) -> f32 {
    let l = length(t);
    if (l > 0.0) {
        return dot(d, vec2<f32>(t.y, -t.x) / l);
    }
    return 0.0;
}

fn pos(i: u32) -> vec4<f32> {
    return c_pv[2u * i];
}

fn vel(i: u32) -> vec4<f32> {
    return c_pv[2u * i + 1u];
}

fn dv(i: u32) -> vec2<f32> {
    return c_vd[i].zw;
}

fn add_dv(i: u32, d: vec2<f32>) {
    c_vd[i] = vec4<f32>(c_vd[i].xy, c_vd[i].zw + d);
}

fn acc_get(f: u32) -> vec4<f32> {
    let b = cp.row_capacity * cp.hist_stride + 4u * f;
    return vec4<f32>(c_hist[b], c_hist[b + 1u], c_hist[b + 2u], c_hist[b + 3u]);
}

fn acc_set(f: u32, a: vec4<f32>) {
    let b = cp.row_capacity * cp.hist_stride + 4u * f;
    c_hist[b] = a.x;
    c_hist[b + 1u] = a.y;
    c_hist[b + 2u] = a.z;
    c_hist[b + 3u] = a.w;
}

fn relative(c: Cons, s: u32) -> f32 {
    var r = dot(dv(s), c.n);
    if (c.a != NONE) {
        r -= (1.0 - c.xi) * dot(dv(c.a), c.n) + c.xi * dot(dv(c.b), c.n);
    }
    return r;
}

fn apply(c: Cons, s: u32, lambda: f32) {
    add_dv(s, lambda * inv_scale * c.n * c_ref[s].zw);
    if (c.a != NONE) {
        add_dv(c.a, -(1.0 - c.xi) * lambda * inv_scale * c.n * c_ref[c.a].zw);
        add_dv(c.b, -c.xi * lambda * inv_scale * c.n * c_ref[c.b].zw);
    }
}

fn penalty_impulse(k: f32, g: f32, rate: f32, g_trial: f32, w: f32, dt: f32, dtn: f32) -> f32 {
    let spring = dtn * k * max(-g, 0.0);
    var bound = max(-g_trial / w, 0.0);
    if (rate < 0.0) {
        bound = -rate * dt / w;
    }
    return min(spring, bound);
}

// A candidate segment of a slave node (crate::contact::ContactSet::qualify): whether the node is in
// contact with it, its selection key (larger is better), projection and normal.
struct Qual {
    ok: bool,
    k0: f32,
    k1: f32,
    xi: f32,
    n: vec2<f32>,
    gap: f32,
    len: f32,
}

fn qualify(s: u32, own: vec2<f32>, j: u32, penalty: bool) -> Qual {
    var r: Qual;
    r.ok = false;
    let sg = segs[j];
    let seg_t = x_n(sg.b, sg.a);
    if (dot(own, vec2<f32>(seg_t.y, -seg_t.x)) >= 0.0) {
        return r;
    }
    // Projection at the trial positions (Lagrange) or at u_n (penalty).
    var d = x_tr(s, sg.a);
    var t = x_tr(sg.b, sg.a);
    if (penalty) {
        d = x_n(s, sg.a);
        t = seg_t;
    }
    let l2 = dot(t, t);
    if (!(l2 > 0.0)) {
        return r;
    }
    let len = sqrt(l2);
    let xi = dot(d, t) / l2;
    if (xi < -XI_TOLERANCE || xi > 1.0 + XI_TOLERANCE) {
        return r;
    }
    let n = vec2<f32>(t.y, -t.x) / len;
    let gap = dot(d, n);
    if (penalty) {
        if (!(gap < 0.0 && gap > -0.5 * len)) {
            return r;
        }
        r.k0 = gap;
        r.k1 = 0.0;
    } else {
        let before = line_gap(x_n(s, sg.a), seg_t);
        if (!(gap < 0.0 && before > -0.5 * len)) {
            return r;
        }
        r.k0 = min(before, 0.0);
        r.k1 = gap;
    }
    r.ok = true;
    r.xi = clamp(xi, 0.0, 1.0);
    r.n = n;
    r.gap = gap;
    r.len = len;
    return r;
}

fn narrow_pass(k: u32, sl: Slot, dt: f32, dtn: f32) -> Cons {
    var c: Cons;
    c.kind = KIND_NONE;
    c.a = NONE;
    c.b = NONE;
    c.lambda = 0.0;
    c.pen = 0.0;
    let s = sl.s;
    let penalty = (sl.info & 0x10000u) != 0u;
    let t_own = x_n(sl.nn, sl.np);
    let own = vec2<f32>(t_own.y, -t_own.x);
    var found = false;
    var best: Qual;
    var best_j = 0u;
    let end = search[k + 1u];
    for (var q = search[k]; q < end; q++) {
        let j = search[cp.cand_base + q];
        let r = qualify(s, own, j, penalty);
        if (r.ok && (!found || r.k0 > best.k0 || (r.k0 == best.k0 && r.k1 > best.k1))) {
            found = true;
            best = r;
            best_j = j;
        }
    }
    if (!found) {
        return c;
    }
    let sg = segs[best_j];
    var best_xi = best.xi;
    var best_n = best.n;
    var best_gap = best.gap;
    // A tie with the neighbouring segment at a shared master node: contact with that node along
    // its averaged normal (crate::contact::narrow::vertex).
    for (var q = search[k]; q < end; q++) {
        let j2 = search[cp.cand_base + q];
        let s2 = segs[j2];
        var m = NONE;
        if (s2.a == sg.b && s2.b != sg.a) {
            m = sg.b;
        } else if (s2.b == sg.a && s2.a != sg.b) {
            m = sg.a;
        } else {
            continue;
        }
        let r = qualify(s, own, j2, penalty);
        if (!r.ok) {
            continue;
        }
        let tol = TIE_TOLERANCE * best.len;
        if (abs(r.k0 - best.k0) > tol || abs(r.k1 - best.k1) > tol) {
            continue;
        }
        let nsum = best.n + r.n;
        let l = length(nsum);
        if (l > 1e-6) {
            best_n = nsum / l;
            var d = x_tr(s, m);
            if (penalty) {
                d = x_n(s, m);
            }
            best_gap = dot(d, best_n);
            best_xi = select(0.0, 1.0, m == sg.b);
        }
        break;
    }
    let w = dt * (along(s, best_n) + (1.0 - best_xi) * (1.0 - best_xi) * along(sg.a, best_n)
        + best_xi * best_xi * along(sg.b, best_n));
    if (!(w > 0.0)) {
        return c;
    }
    c.a = sg.a;
    c.b = sg.b;
    c.xi = best_xi;
    c.n = best_n;
    c.g0 = best_gap;
    c.w = w;
    c.kind = KIND_LAGRANGE;
    if (penalty) {
        let vs = vel(s).xy;
        let rate = dot(vs, best_n)
            - ((1.0 - best_xi) * dot(vel(sg.a).xy, best_n) + best_xi * dot(vel(sg.b).xy, best_n));
        let g_trial = best_gap + dt * rate;
        c.lambda = penalty_impulse(sg.k, best_gap, rate, g_trial, w, dt, dtn);
        c.pen = -best_gap;
        c.kind = KIND_PENALTY;
    }
    return c;
}

fn narrow_wall(sl: Slot, dt: f32, dtn: f32) -> Cons {
    var c: Cons;
    c.kind = KIND_NONE;
    c.a = NONE;
    c.b = NONE;
    c.lambda = 0.0;
    c.pen = 0.0;
    c.xi = 0.0;
    let s = sl.s;
    let n = sl.normal;
    let x = (c_ref[s].xy - sl.point) + pos(s).xy;
    let xt = (c_ref[s].xy - sl.point) + pos(s).zw + corr_dt * dv(s);
    let g = dot(x, n);
    let g_tr = dot(xt, n);
    let w = dt * along(s, n);
    if (!(w > 0.0)) {
        return c;
    }
    c.n = n;
    c.g0 = g_tr;
    c.w = w;
    if ((sl.info & 0x10000u) == 0u) {
        if (g_tr < 0.0) {
            c.kind = KIND_LAGRANGE;
        }
    } else if (g < 0.0) {
        let rate = dot(vel(s).xy, n);
        c.lambda = penalty_impulse(sl.k, g, rate, g_tr, w, dt, dtn);
        c.pen = -g;
        c.kind = KIND_PENALTY;
    }
    return c;
}

// Projected Gauss-Seidel sweeps over the Lagrange constraints, colour by colour, until the largest
// change of a gap is below 1e-7 x margin or max_sweeps (crate::contact::ContactSet::sweep).
fn sweeps(l: u32, dt: f32) {
    let cb = cp.color_base;
    let sb = cp.slot_base;
    let tol = 1e-7 * cp.margin;
    for (var sweep = 0u; sweep < cp.max_sweeps; sweep++) {
        var change = 0.0;
        for (var col = 0u; col < cp.n_colors; col++) {
            let end = search[cb + col + 1u];
            for (var q = search[cb + col] + l; q < end; q += RG) {
                let k = search[sb + q];
                let c = cons[k];
                if (c.kind != KIND_LAGRANGE) {
                    continue;
                }
                let s = slots[k].s;
                let g = c.g0 + dt * relative(c, s);
                let lambda = max(c.lambda - g / c.w, 0.0);
                let d = lambda - c.lambda;
                if (d != 0.0) {
                    apply(c, s, d);
                    cons[k].lambda = lambda;
                    change = max(change, abs(d * c.w));
                }
            }
            storageBarrier();
        }
        sh_m[l] = change;
        workgroupBarrier();
        for (var h = RG / 2u; h > 0u; h >>= 1u) {
            if (l < h) {
                sh_m[l] = max(sh_m[l], sh_m[l + h]);
            }
            workgroupBarrier();
        }
        if (l == 0u) {
            sh_u = select(0u, 1u, sh_m[0] <= tol);
        }
        if (workgroupUniformLoad(&sh_u) != 0u) {
            break;
        }
    }
}

@compute @workgroup_size(RG)
fn main(@builtin(local_invocation_id) lid: vec3<u32>) {
    let l = lid.x;
    if (l == 0u) {
        sh_u = ctrl.state;
        atomicStore(&sh_far, 0u);
        atomicStore(&sh_lagrange, 0u);
    }
    let state = workgroupUniformLoad(&sh_u);
    if (state != STATE_RUNNING) {
        return;
    }
    let flags = ctrl.flags;
    let dt = ctrl.dt_next;
    let dtn = ctrl.dt_node;
    let moving = (flags & FLAG_END) == 0u;
    let first = ctrl.step == 0u;
    let mass_scale = 1.0 + ctrl.damp_c;
    inv_scale = 1.0 / mass_scale;
    let h2 = 0.25 * cp.margin * cp.margin;

    // 1. Positions u_n and u_n + dt v of the free update; v^{n-1/2}; search due?
    for (var i = l; i < cp.n_local; i += RG) {
        let s = nodes[c_nodes[i].x];
        let v = s.zw;
        var un = s.xy;
        var ut = s.xy;
        if (moving) {
            un = s.xy - dt * v;
        } else {
            ut = s.xy + dt * v;
        }
        c_pv[2u * i] = vec4<f32>(un, ut);
        var vo = c_vd[i].xy;
        if (first) {
            vo = 2.0 * vo - v;
        }
        c_pv[2u * i + 1u] = vec4<f32>(v, vo);
        c_vd[i] = vec4<f32>(c_vd[i].xy, 0.0, 0.0);
        let r = u_search[i];
        let d0 = un - r;
        let d1 = ut - r;
        if (cp.searched == 0u || (cp.searched == 1u && (dot(d0, d0) > h2 || dot(d1, d1) > h2))) {
            atomicOr(&sh_far, 1u);
        }
    }
    let far = workgroupUniformLoad(&sh_far);
    if (far != 0u) {
        if (l == 0u) {
            ctrl.state = STATE_SEARCH;
        }
        return;
    }

    // 2. Narrow phase, one slot per thread.
    for (var k = l; k < cp.n_slots; k += RG) {
        let sl = slots[k];
        var c: Cons;
        if ((sl.info & 0x20000u) != 0u) {
            c = narrow_wall(sl, dt, dtn);
        } else {
            c = narrow_pass(k, sl, dt, dtn);
        }
        // Warm start (as on the CPU): a Lagrange constraint of the slot that carried lambda last
        // step starts from it, scaled by the ratio of the steps; a persistent contact (a pressure
        // carried across an interface) then needs few sweeps instead of converging from zero.
        let old = cons[k];
        if (c.kind == KIND_LAGRANGE && old.kind == KIND_LAGRANGE && old.lambda > 0.0 && old.dt_warm > 0.0) {
            c.lambda = old.lambda * (dtn / old.dt_warm);
        }
        c.dt_warm = dtn;
        cons[k] = c;
        if (c.kind == KIND_LAGRANGE) {
            atomicAdd(&sh_lagrange, 1u);
        }
    }
    storageBarrier();

    // 3. Penalty impulses and the Lagrange warm starts, then the Lagrange sweeps, colour by colour.
    let cb = cp.color_base;
    let sb = cp.slot_base;
    for (var col = 0u; col < cp.n_colors; col++) {
        let end = search[cb + col + 1u];
        for (var q = search[cb + col] + l; q < end; q += RG) {
            let k = search[sb + q];
            let c = cons[k];
            if (c.kind != KIND_NONE && c.lambda > 0.0) {
                apply(c, slots[k].s, c.lambda);
            }
        }
        storageBarrier();
    }
    let lagrange = workgroupUniformLoad(&sh_lagrange);
    if (lagrange > 0u) {
        sweeps(l, dt);
        // Active-set update (crate::contact::ContactSet::recheck): the free Lagrange slots again,
        // at the trial positions corrected by dt dv; sweep again when any penetrates.
        for (var round = 0u; round < ACTIVE_SET_ROUNDS; round++) {
            if (l == 0u) {
                atomicStore(&sh_new, 0u);
            }
            workgroupBarrier();
            corr_dt = dt;
            for (var k = l; k < cp.n_slots; k += RG) {
                let sl = slots[k];
                if (cons[k].kind != KIND_NONE || (sl.info & 0x10000u) != 0u) {
                    continue;
                }
                var c: Cons;
                if ((sl.info & 0x20000u) != 0u) {
                    c = narrow_wall(sl, dt, dtn);
                } else {
                    c = narrow_pass(k, sl, dt, dtn);
                }
                if (c.kind == KIND_LAGRANGE) {
                    // The gap at the free trial positions, as for every constraint.
                    c.g0 -= dt * relative(c, sl.s);
                    c.dt_warm = dtn;
                    cons[k] = c;
                    atomicAdd(&sh_new, 1u);
                }
            }
            corr_dt = 0.0;
            storageBarrier();
            if (workgroupUniformLoad(&sh_new) == 0u) {
                break;
            }
            sweeps(l, dt);
        }
    }

    // 4. Corrected velocities, u_{n+1}, the impulses' work J (v^{n-1/2} + v^{n+1/2}) / 2 (free
    //    directions only: on a constrained one the inverse mass is 0) and kinetic sample sources.
    let sample = (flags & FLAG_SAMPLE) != 0u;
    var work = vec4<f32>(0.0);
    for (var i = l; i < cp.n_local; i += RG) {
        let vl = vel(i);
        let d = dv(i);
        let vn = vl.xy + d;
        c_vd[i] = vec4<f32>(vn, d);
        if (d.x == 0.0 && d.y == 0.0) {
            continue;
        }
        let g = c_nodes[i].x;
        let m = bitcast<f32>(c_nodes[i].y);
        let mu = mass_scale * m;
        let j = vec2<f32>(select(0.0, mu * d.x, c_ref[i].z > 0.0), select(0.0, mu * d.y, c_ref[i].w > 0.0));
        work.x += 0.5 * dot(j, vl.zw + vn);
        work.y += 0.5 * dot(j, vn);
        var s = nodes[g];
        if (moving) {
            s = vec4<f32>(s.xy + dt * d, vn);
        } else {
            s = vec4<f32>(s.xy, vn);
        }
        nodes[g] = s;
        if (sample) {
            let vq = v_prev[g];
            sample_src[g] = vec4<f32>(0.5 * m * dot(vq, vn), 0.5 * m * (vq + vn), 0.0);
        }
    }
    sh_f[l] = work;
    workgroupBarrier();
    for (var h = RG / 2u; h > 0u; h >>= 1u) {
        if (l < h) {
            sh_f[l] += sh_f[l + h];
        }
        workgroupBarrier();
    }
    let total = sh_f[0];
    workgroupBarrier();

    // 5. Interface reports: impulse on the first body, active slaves, largest penetration.
    let ni = cp.n_ifaces;
    let row = (ctrl.rows % cp.row_capacity) * cp.hist_stride;
    for (var f = 0u; f < ni; f++) {
        var imp = vec4<f32>(0.0);
        var pen = 0.0;
        for (var k = l; k < cp.n_slots; k += RG) {
            let sl = slots[k];
            if ((sl.info & 0xffffu) != f) {
                continue;
            }
            let c = cons[k];
            if (c.kind == KIND_NONE) {
                continue;
            }
            if (c.lambda > 0.0) {
                let sign = select(1.0, -1.0, (sl.info & 0x40000u) != 0u);
                imp += vec4<f32>(sign * c.lambda * c.n, 1.0, 0.0);
            }
            if (c.kind == KIND_PENALTY) {
                pen = max(pen, c.pen);
            } else {
                pen = max(pen, -(c.g0 + dt * relative(c, sl.s)));
            }
        }
        sh_f[l] = imp;
        sh_m[l] = pen;
        workgroupBarrier();
        for (var h = RG / 2u; h > 0u; h >>= 1u) {
            if (l < h) {
                sh_f[l] += sh_f[l + h];
                sh_m[l] = max(sh_m[l], sh_m[l + h]);
            }
            workgroupBarrier();
        }
        if (l == 0u) {
            var a = acc_get(f);
            a += vec4<f32>(sh_f[0].xy, dtn, 0.0);
            if (sample) {
                var force = vec2<f32>(0.0);
                if (a.z > 0.0) {
                    force = a.xy / a.z;
                }
                c_hist[row + 1u + 4u * f] = force.x;
                c_hist[row + 2u + 4u * f] = force.y;
                c_hist[row + 3u + 4u * f] = sh_m[0];
                c_hist[row + 4u + 4u * f] = sh_f[0].z;
                a = vec4<f32>(0.0);
            }
            acc_set(f, a);
        }
        workgroupBarrier();
    }
    if (l == 0u) {
        var w = acc_get(ni);
        w.x += total.x;
        w.y = total.y;
        acc_set(ni, w);
        if (sample) {
            c_hist[row] = -(w.x - w.y);
        }
    }
}
