// Contact narrow phase, one thread per slot (CPU reference: crate::contact::narrow and
// ContactSet::collect_passes / collect_walls): each slot's constraint against its best candidate
// segment (or its wall), the corner rule, the penalty impulse, and the warm start of the Lagrange
// multiplier; then the penalty and warm-start impulses gathered per node in a fixed order.
// Also compiled into the solve module, whose active-set re-check calls the same functions.

@group(0) @binding(13) var<storage, read_write> ws: array<u32>;
@group(0) @binding(14) var<storage, read_write> grow: array<u32>;

// dt during an active-set re-check (trial positions corrected by dt dv), else 0.
var<private> corr_dt: f32 = 0.0;

// What x_n and x_tr read of a local node: its reference position, its positions at u_n and at
// the trial u_{n+1}, and its dv. A loop over candidates reads its slave's once and each
// segment's ends once (lavapipe loads storage lane by lane, and a read_write buffer's repeated
// loads are not merged).
struct At {
    r: vec2<f32>,
    n: vec2<f32>,
    tr: vec2<f32>,
    dv: vec2<f32>,
}

fn node_at(i: u32) -> At {
    let p = pos(i);
    return At(c_ref[i].xy, p.xy, p.zw, dv(i));
}

// i - j at u_n and at the trial positions, from their reads.
fn xn(i: At, j: At) -> vec2<f32> {
    return (i.r - j.r) + (i.n - j.n);
}

fn xt(i: At, j: At) -> vec2<f32> {
    return (i.r - j.r) + (i.tr - j.tr) + corr_dt * (i.dv - j.dv);
}

// Local node i - local node j at u_n and at the trial positions.
fn x_n(i: u32, j: u32) -> vec2<f32> {
    return xn(node_at(i), node_at(j));
}

fn x_tr(i: u32, j: u32) -> vec2<f32> {
    return xt(node_at(i), node_at(j));
}

// Signed distance to the line a -> b of the vector d = p - a along t = b - a.
fn line_gap(d: vec2<f32>, t: vec2<f32>) -> f32 {
    let l = length(t);
    if (l > 0.0) {
        return dot(d, vec2<f32>(t.y, -t.x) / l);
    }
    return 0.0;
}

// A node at d = p - a against the segment t = b - a whose ends on the axis of an axisymmetric
// body are `axis` (SEGMENT_AXIS_A, SEGMENT_AXIS_B) (crate::contact::rules::project): the
// parameter clamped to [0, 1], the outward normal and the gap; not ok when the segment is
// degenerate or the node projects outside it, except past an end on the axis, where it meets the
// vertex of the segment and its mirror image: the parameter at that end, the normal along the
// axis (none when the segment is parallel to it).
struct Proj {
    ok: bool,
    xi: f32,
    n: vec2<f32>,
    gap: f32,
    len: f32,
}

fn project(d: vec2<f32>, t: vec2<f32>, axis: u32) -> Proj {
    var r: Proj;
    r.ok = false;
    let l2 = dot(t, t);
    if (!(l2 > 0.0)) {
        return r;
    }
    r.len = sqrt(l2);
    let xi = dot(d, t) / l2;
    let n = vec2<f32>(t.y, -t.x) / r.len;
    if (xi < -XI_TOLERANCE || xi > 1.0 + XI_TOLERANCE) {
        var bit = SEGMENT_AXIS_A;
        var dm = d;
        r.xi = 0.0;
        if (xi > 0.0) {
            bit = SEGMENT_AXIS_B;
            dm = d - t;
            r.xi = 1.0;
        }
        // The vertex's normal: (n + its mirror (-n.x, n.y)) normalised, none when that sum's
        // length |2 n.y| is 1e-6 or less (crate::contact::rules::vertex).
        if ((axis & bit) == 0u || !(abs(2.0 * n.y) > 1e-6)) {
            return r;
        }
        r.n = vec2<f32>(0.0, sign(n.y));
        r.gap = dot(dm, r.n);
        r.ok = true;
        return r;
    }
    r.xi = clamp(xi, 0.0, 1.0);
    r.n = n;
    r.gap = dot(d, n);
    r.ok = true;
    return r;
}

// (impulse, 1 if the bound acted) (crate::contact::penalty_impulse): the spring unchanged while
// it is soft for the step ((omega dt)^2 = k dtn w <= STIFF_SPRING), else bounded by the perfectly
// plastic impulse.
fn penalty_impulse(k: f32, g: f32, rate: f32, g_trial: f32, w: f32, dt: f32, dtn: f32) -> vec2<f32> {
    let spring = dtn * k * max(-g, 0.0);
    if (k * dtn * w <= STIFF_SPRING) {
        return vec2<f32>(spring, 0.0);
    }
    var bound = max(-g_trial / w, 0.0);
    if (rate < 0.0) {
        bound = -rate * dt / w;
    }
    return vec2<f32>(min(spring, bound), select(0.0, 1.0, bound < spring));
}

// The augmented Lagrangian's impulse (crate::contact::solve::augmented_impulse): for a spring k at
// gap g carrying the multiplier `lambda` of the last step, (impulse, next multiplier, 1 where the
// spring's bound acted, 1 in contact); not in contact (the multiplier dropped) while
// lambda - k g <= 0. The next multiplier is Uzawa's update at the rate r: lambda + r dt_n k (-g).
fn augmented_impulse(k: f32, g: f32, rate: f32, g_trial: f32, lambda: f32, w: f32, dt: f32, dtn: f32,
                     r: f32) -> vec4<f32> {
    if (!(lambda - k * g > 0.0)) {
        return vec4<f32>(0.0);
    }
    var spring = vec2<f32>(-dtn * k * g, 0.0);
    if (g < 0.0) {
        spring = penalty_impulse(k, g, rate, g_trial, w, dt, dtn);
    }
    let next = max(lambda - r * dtn * k * g, 0.0);
    return vec4<f32>(dtn * lambda + spring.x, next, spring.y, 1.0);
}

// A spring method's constraint `c0` (its w set) for stiffness k at the gap g (the perturbed
// Lagrangian's consistent one) and trial gap g_trial: the penalty's impulse, or the augmented
// Lagrangian's with the multiplier `carried` of the last step and its next multiplier in `ft`
// (no constraint where the node has left); the penetration `pen` (m), the stiffness in `wt`.
fn spring(c0: Cons, sl: Slot, k: f32, g: f32, rate: f32, g_trial: f32, carried: f32, dt: f32, dtn: f32,
          pen: f32) -> Cons {
    var c = c0;
    if (sl.ar > 0.0) {
        let a = augmented_impulse(k, g, rate, g_trial, carried, c.w, dt, dtn, sl.ar);
        if (a.w == 0.0) {
            return no_constraint();
        }
        c.lambda = a.x;
        c.ft = a.y;
        c.dt_warm = -a.z;
    } else {
        let imp = penalty_impulse(k, g, rate, g_trial, c.w, dt, dtn);
        c.lambda = imp.x;
        c.dt_warm = -imp.y;
    }
    c.pen = max(pen, 0.0);
    c.kind = KIND_PENALTY;
    c.wt = k;
    return c;
}

// The perturbed Lagrangian's penetration of a slave node (crate::contact::consistent_penetration):
// its penetration a (> 0) and, per surface segment, (length, the other end's penetration along
// the node's normal); the N_I-weighted mean of the linear penetration over the contact support.
fn consistent_penetration(a: f32, s0: vec2<f32>, s1: vec2<f32>) -> f32 {
    var num = 0.0;
    var den = 0.0;
    for (var i = 0u; i < 2u; i++) {
        var side = s0;
        if (i == 1u) {
            side = s1;
        }
        let l = side.x;
        let b = side.y;
        if (!(l > 0.0) || !(a > 0.0)) {
            continue;
        }
        if (b >= 0.0) {
            num += l * (2.0 * a + b) / 6.0;
            den += l * 0.5;
        } else {
            let s = a / (a - b);
            let c = b - a;
            num += l * (a * s + (c - a) * s * s / 2.0 - c * s * s * s / 3.0);
            den += l * (s - s * s / 2.0);
        }
    }
    if (den > 0.0) {
        return num / den;
    }
    return a;
}

// The perturbed Lagrangian's gap of slot `sl`'s node at gap g (< 0) along n
// (ContactSet::consistent_gap): each neighbour's penetration measured along the same normal, at u_n.
fn consistent_gap(sl: Slot, n: vec2<f32>, g: f32) -> f32 {
    var side = array<vec2<f32>, 2>(vec2<f32>(0.0), vec2<f32>(0.0));
    for (var i = 0u; i < 2u; i++) {
        var j = sl.np;
        if (i == 1u) {
            j = sl.nn;
        }
        if (j != sl.s) {
            let d = x_n(j, sl.s);
            side[i] = vec2<f32>(length(d), -g - dot(d, n));
        }
    }
    return -consistent_penetration(-g, side[0], side[1]);
}

// The signed gap at u_n of the pass slot `k`'s node to the closest of its candidate segments that
// face its surface and that it projects onto, within half a segment behind it (ContactSet::
// slave_gap); x: the gap, y: 1 if found.
fn slave_gap(k: u32) -> vec2<f32> {
    let sl = slots[k];
    let t_own = x_n(sl.nn, sl.np);
    let own = vec2<f32>(t_own.y, -t_own.x);
    var best = vec2<f32>(0.0, 0.0);
    let begin = ws[cc.p.o_coff + k];
    let end = ws[cc.p.o_coff + k + 1u];
    for (var q = begin; q < end; q++) {
        let sg = segs[grow[q]];
        let seg_t = x_n(sg.b, sg.a);
        if (dot(own, vec2<f32>(seg_t.y, -seg_t.x)) >= 0.0) {
            continue;
        }
        let pr = project(x_n(sl.s, sg.a), seg_t, sg.axis);
        if (!pr.ok) {
            continue;
        }
        let gap = pr.gap;
        let len = pr.len;
        if (gap > -0.5 * len && (best.y == 0.0 || abs(gap) < abs(best.x))) {
            best = vec2<f32>(gap, 1.0);
        }
    }
    return best;
}

// The perturbed Lagrangian's gap of pass slot `sl`'s node at gap g (< 0): each neighbour's
// penetration its own gap (slave_gap of its slot), as on the CPU (ContactSet::collect_passes).
fn consistent_pass_gap(sl: Slot, g: f32) -> f32 {
    var side = array<vec2<f32>, 2>(vec2<f32>(0.0), vec2<f32>(0.0));
    for (var i = 0u; i < 2u; i++) {
        var ks = sl.ps;
        if (i == 1u) {
            ks = sl.ns;
        }
        if (ks == NONE) {
            continue;
        }
        let gj = slave_gap(ks);
        if (gj.y > 0.0) {
            side[i] = vec2<f32>(length(x_n(slots[ks].s, sl.s)), -gj.x);
        }
    }
    return -consistent_penetration(-g, side[0], side[1]);
}

// A candidate segment of a slave node (crate::contact::narrow::qualify): whether the node is in
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

// Slave `s` (its reads) against candidate segment j.
fn qualify(s: At, own: vec2<f32>, j: u32, penalty: bool, carried: f32) -> Qual {
    var r: Qual;
    r.ok = false;
    let sg = segs[j];
    let a = node_at(sg.a);
    let b = node_at(sg.b);
    let seg_t = xn(b, a);
    if (dot(own, vec2<f32>(seg_t.y, -seg_t.x)) >= 0.0) {
        return r;
    }
    // Projection at the trial positions (Lagrange) or at u_n (penalty).
    var d = xt(s, a);
    var t = xt(b, a);
    if (penalty) {
        d = xn(s, a);
        t = seg_t;
    }
    let pr = project(d, t, sg.axis);
    if (!pr.ok) {
        return r;
    }
    let len = pr.len;
    let n = pr.n;
    let gap = pr.gap;
    if (penalty) {
        // (The augmented Lagrangian's node stays in contact up to the gap carried / k.)
        var reach = 0.0;
        if (carried > 0.0) {
            reach = carried / sg.k;
        }
        if (!(gap < reach && gap > -0.5 * len)) {
            return r;
        }
        r.k0 = gap;
        r.k1 = 0.0;
    } else {
        let before = line_gap(xn(s, a), seg_t);
        if (!(gap < 0.0 && before > -0.5 * len)) {
            return r;
        }
        r.k0 = min(before, 0.0);
        r.k1 = gap;
    }
    r.ok = true;
    r.xi = pr.xi;
    r.n = n;
    r.gap = gap;
    r.len = len;
    return r;
}

// Impulse sign on the interface's first body for slot `sl` against segment `sg`.
fn pass_sign(sl: Slot, sg: Segment) -> f32 {
    if ((sl.info & SLOT_GROUP) != 0u) {
        if (sl.body < sg.body) {
            return 1.0;
        }
        if (sl.body > sg.body) {
            return -1.0;
        }
        return 0.0;
    }
    return select(1.0, -1.0, (sl.info & SLOT_SECOND) != 0u);
}

fn no_constraint() -> Cons {
    var c: Cons;
    c.kind = KIND_NONE;
    c.a = NONE;
    c.b = NONE;
    c.sign = 0.0;
    c.xi = 0.0;
    c.lambda = 0.0;
    c.pen = 0.0;
    c.dt_warm = 0.0;
    c.mu = 0.0;
    c.wt = 0.0;
    c.lt = 0.0;
    c.ft = 0.0;
    return c;
}

// Penalty friction (CPU: ContactSet::penalty_friction, the Curnier-Mroz regularization): a
// tangential spring of the normal spring's stiffness (c.wt on entry) times sl.kt, its force `old.ft` of the
// slot's last step incremented by -k dt v_t and returned onto |f_t| <= mu lambda / dt_n.
fn penalty_friction(c0: Cons, sl: Slot, old: Cons, dt: f32, dtn: f32, inv_scale: f32) -> Cons {
    var c = c0;
    let k = c.wt * sl.kt;
    c.wt = 0.0;
    let t = tangent(c);
    var wt = along(sl.s, t, inv_scale);
    if (c.a != NONE) {
        wt += (1.0 - c.xi) * (1.0 - c.xi) * along(c.a, t, inv_scale) + c.xi * c.xi * along(c.b, t, inv_scale);
    }
    if (!(wt > 0.0) || !(c.lambda > 0.0) || !(dtn > 0.0)) {
        return c;
    }
    var prev = 0.0;
    if (old.kind == KIND_PENALTY) {
        prev = old.ft;
    }
    let limit = sl.mu * c.lambda / dtn;
    let ft = clamp(prev - k * dt * free_relative_along(c, sl.s, t), -limit, limit);
    c.mu = sl.mu;
    c.wt = wt;
    c.lt = dtn * ft;
    c.ft = ft;
    return c;
}

// Friction of a Lagrange constraint of slot `sl` (no friction where no node can move along t).
fn with_friction(c0: Cons, sl: Slot, inv_scale: f32) -> Cons {
    var c = c0;
    if (FRICTION && sl.mu > 0.0 && c.kind == KIND_LAGRANGE) {
        let t = tangent(c);
        var wt = along(sl.s, t, inv_scale);
        if (c.a != NONE) {
            wt += (1.0 - c.xi) * (1.0 - c.xi) * along(c.a, t, inv_scale) + c.xi * c.xi * along(c.b, t, inv_scale);
        }
        if (wt > 0.0) {
            c.wt = wt;
            c.mu = sl.mu;
        }
    }
    return c;
}

fn narrow_pass(k: u32, sl: Slot, dt: f32, dtn: f32, inv_scale: f32, carried: f32) -> Cons {
    var c = no_constraint();
    let s = sl.s;
    let penalty = SPRINGS && (sl.info & SLOT_PENALTY) != 0u;
    let t_own = x_n(sl.nn, sl.np);
    let own = vec2<f32>(t_own.y, -t_own.x);
    let sa = node_at(s);
    var found = false;
    var best: Qual;
    var best_j = 0u;
    let begin = ws[cc.p.o_coff + k];
    let end = ws[cc.p.o_coff + k + 1u];
    for (var q = begin; q < end; q++) {
        let j = grow[q];
        let r = qualify(sa, own, j, penalty, carried);
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
    // Over a convex corner of the segment, outside the master body (the node came from behind
    // the segment's line, it is on the corner's half of it, the corner turns left, and the node
    // is on or in front of the neighbour's line, to TIE_TOLERANCE of the lengths): no contact
    // (crate::contact::rules::outside_convex_corner). Positions as in qualify.
    let came_from_behind = !penalty && best.k0 < -TIE_TOLERANCE * best.len;
    for (var q = begin; came_from_behind && q < end; q++) {
        let s2 = segs[grow[q]];
        var c0 = NONE;
        var c2 = NONE;
        var near = false;
        if (s2.a == sg.b && s2.b != sg.a) {
            c0 = sg.a;
            c2 = s2.b;
            near = best.xi >= 0.5;
        } else if (s2.b == sg.a && s2.a != sg.b) {
            c0 = s2.a;
            c2 = sg.b;
            near = best.xi <= 0.5;
        } else {
            continue;
        }
        let c1 = select(sg.a, sg.b, c2 == s2.b);
        var t1 = x_tr(c1, c0);
        var t2 = x_tr(c2, c1);
        var d = x_tr(s, s2.a);
        var t = x_tr(s2.b, s2.a);
        if (penalty) {
            t1 = x_n(c1, c0);
            t2 = x_n(c2, c1);
            d = x_n(s, s2.a);
            t = x_n(s2.b, s2.a);
        }
        if (!near || !(t1.x * t2.y - t1.y * t2.x > 0.0)) {
            continue;
        }
        if (line_gap(d, t) > -TIE_TOLERANCE * length(t)) {
            return c;
        }
    }
    var best_xi = best.xi;
    var best_n = best.n;
    var best_gap = best.gap;
    // A tie with the neighbouring segment at a shared master node: contact with that node along
    // its averaged normal (crate::contact::rules::vertex).
    for (var q = begin; q < end; q++) {
        let j2 = grow[q];
        let s2 = segs[j2];
        var m = NONE;
        if (s2.a == sg.b && s2.b != sg.a) {
            m = sg.b;
        } else if (s2.b == sg.a && s2.a != sg.b) {
            m = sg.a;
        } else {
            continue;
        }
        let r = qualify(sa, own, j2, penalty, carried);
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
    let w = dt * (along(s, best_n, inv_scale)
        + (1.0 - best_xi) * (1.0 - best_xi) * along(sg.a, best_n, inv_scale)
        + best_xi * best_xi * along(sg.b, best_n, inv_scale));
    if (!(w > 0.0)) {
        return c;
    }
    c.a = sg.a;
    c.b = sg.b;
    c.sign = pass_sign(sl, sg);
    c.xi = best_xi;
    c.n = best_n;
    c.g0 = best_gap;
    c.w = w;
    c.kind = KIND_LAGRANGE;
    if (penalty) {
        let vs = vel(s).xy;
        let rate = dot(vs, best_n)
            - ((1.0 - best_xi) * dot(vel(sg.a).xy, best_n) + best_xi * dot(vel(sg.b).xy, best_n));
        var g = best_gap;
        if ((sl.info & SLOT_PERTURBED) != 0u) {
            g = consistent_pass_gap(sl, best_gap);
        }
        c = spring(c, sl, sg.k, g, rate, g + dt * rate, carried, dt, dtn, -best_gap);
    }
    return c;
}

fn narrow_wall(sl: Slot, dt: f32, dtn: f32, inv_scale: f32, carried: f32) -> Cons {
    var c = no_constraint();
    let s = sl.s;
    let n = sl.normal;
    let x = (c_ref[s].xy - sl.point) + pos(s).xy;
    let xt = (c_ref[s].xy - sl.point) + pos(s).zw + corr_dt * dv(s);
    let g = dot(x, n);
    let g_tr = dot(xt, n);
    let w = dt * along(s, n, inv_scale);
    if (!(w > 0.0)) {
        return c;
    }
    c.n = n;
    c.g0 = g_tr;
    c.w = w;
    c.sign = 1.0;
    if (!SPRINGS || (sl.info & SLOT_PENALTY) == 0u) {
        if (g_tr < 0.0) {
            c.kind = KIND_LAGRANGE;
        }
    } else if (g < select(0.0, carried / sl.k, carried > 0.0)) {
        let rate = dot(vel(s).xy, n);
        var gs = g;
        var gs_tr = g_tr;
        if ((sl.info & SLOT_PERTURBED) != 0u) {
            gs = consistent_gap(sl, n, g);
            gs_tr = gs + dt * rate;
        }
        c = spring(c, sl, sl.k, gs, rate, gs_tr, carried, dt, dtn, -g);
    }
    return c;
}

// `carried`: the augmented Lagrangian's multiplier of the slot's last step (0: none).
fn narrow_slot(k: u32, sl: Slot, dt: f32, dtn: f32, inv_scale: f32, carried: f32) -> Cons {
    if ((sl.info & SLOT_WALL) != 0u) {
        return with_friction(narrow_wall(sl, dt, dtn, inv_scale, carried), sl, inv_scale);
    }
    return with_friction(narrow_pass(k, sl, dt, dtn, inv_scale, carried), sl, inv_scale);
}

// The active slots of the last search (the others have no constraint, cleared at the search).
fn active_count() -> u32 {
    return ws[cc.p.o_aoff + cc.p.n_slots];
}

fn active_slot(j: u32) -> u32 {
    return ws[cc.p.o_alist + j];
}

// The narrow phase of every active slot, with the warm start (as on the CPU): a Lagrange
// constraint of a slot that carried lambda last step starts from it, scaled by the ratio of the
// steps. Dispatched over the active slots (indirect entry ACTIVE_ENTRY).
@compute @workgroup_size(CG)
fn narrow(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (!contact_running() || gid.x >= active_count()) {
        return;
    }
    narrow_active(gid.x);
}

// The narrow phase of the j-th active slot.
fn narrow_active(j: u32) {
    let k = active_slot(j);
    let dt = ctrl.dt_next;
    let dtn = ctrl.dt_node;
    let old = cons[k];
    let sl = slots[k];
    var carried = 0.0;
    if (SPRINGS && sl.ar > 0.0 && old.kind == KIND_PENALTY) {
        carried = old.ft;
    }
    var c = narrow_slot(k, sl, dt, dtn, inv_mass_scale(), carried);
    if (SPRINGS && FRICTION && c.kind == KIND_PENALTY && sl.mu > 0.0) {
        c = penalty_friction(c, sl, old, dt, dtn, inv_mass_scale());
    }
    if (c.kind == KIND_LAGRANGE && old.kind == KIND_LAGRANGE && old.lambda > 0.0 && old.dt_warm > 0.0) {
        c.lambda = old.lambda * (dtn / old.dt_warm);
    }
    if (c.kind != KIND_PENALTY) {
        c.dt_warm = dtn;
    }
    cons[k] = c;
    if (c.kind == KIND_LAGRANGE) {
        atomicAdd(&cc.lagrange, 1u);
        note_penetration(c);
    }
}

// The velocity change of local node i from the impulses of its slots (penalty and warm start),
// summed in slot order (its adjacency list is sorted): the same bits on every run.
@compute @workgroup_size(CG)
fn gather(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (item_runs(gid.x, cc.p.n_local)) {
        gather_node(gid.x);
    }
}

// `gather` of local node i.
fn gather_node(i: u32) {
    let inv_scale = inv_mass_scale();
    var d = vec2<f32>(0.0);
    let b = cc.p.cand_capacity;
    let end = ws[cc.p.o_noff + i + 1u];
    for (var q = ws[cc.p.o_noff + i]; q < end; q++) {
        let k = grow[b + q];
        // Only the slots with an impulse load their constraint (lavapipe loads storage per lane,
        // skipping only the lanes that do not run).
        if (cons[k].kind == KIND_NONE || !(cons[k].lambda > 0.0)) {
            continue;
        }
        let c = cons[k];
        var share = 0.0;
        if (slots[k].s == i) {
            share = 1.0;
        } else if (c.a == i) {
            share = -(1.0 - c.xi);
        } else if (c.b == i) {
            share = -c.xi;
        }
        // (Penalty friction: its tangential impulse too; 0 for a warm start.)
        d += share * inv_scale * (c.lambda * c.n + c.lt * tangent(c));
    }
    let dm = d * c_ref[i].zw;
    c_pv[3u * i + 2u].z = dm.x;
    c_pv[3u * i + 2u].w = dm.y;
}
