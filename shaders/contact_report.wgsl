// The end of the contact step (CPU reference: the end of crate::contact::ContactSet::apply and its
// reports): corrected velocities and u_{n+1}, the impulses' work, and per interface the impulse on
// its first body, the active slaves and the largest penetration. Every sum is a fixed-order
// reduction (per workgroup by lane 0 in lane order, then workgroup trees over lanes that each take
// a fixed stride): the same bits on every run. Each barrier costs lavapipe a coroutine switch per
// lane group, so the per-item kernels have one barrier each and the one-workgroup `report_end`
// runs SG lanes (8 on CPU adapters).

// Compiled after contact_narrow.wgsl (its bindings and active-slot list) and tree.wgsl (report_end's
// trees: sh_sum, and sum_tree for the work).

const TREE: u32 = SG;

var<workgroup> sh_f: array<vec4<f32>, CG>;
var<workgroup> sh_er: array<vec4<f32>, SG>;   // report_end's friction tree (sh_sum: the reports')
var<workgroup> sh_ni: u32;

// First word of interface f in a history row: after the contact energy (and with friction the
// friction work), 4 words each (fx, fy, penetration, active), 5 with friction (and ft).
fn hist_word(f: u32) -> u32 {
    if (FRICTION && cc.p.friction != 0u) {
        return 2u + 5u * f;
    }
    return 1u + 4u * f;
}

// 4. Corrected velocities, u_{n+1}, the impulses' work J (v^{n-1/2} + v^{n+1/2}) / 2 (free
//    directions only: on a constrained one the inverse mass is 0) and kinetic sample sources;
//    the work per workgroup (lane 0 sums its lanes in order) into fws[f_wp + workgroup].
@compute @workgroup_size(CG)
fn finish(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>,
          @builtin(workgroup_id) wid: vec3<u32>) {
    let i = gid.x;
    let l = lid.x;
    let running = contact_running();
    var work = vec4<f32>(0.0);
    if (running && i < cc.p.n_local) {
        work = finish_node(i);
    }
    sh_f[l] = work;
    workgroupBarrier();
    if (l == 0u && running) {
        var t = vec4<f32>(0.0);
        for (var h = 0u; h < CG; h++) {
            t += sh_f[h];
        }
        fws[cc.p.f_wp + wid.x] = t;
    }
}

// `finish` of local node i; returns its impulses' work.
fn finish_node(i: u32) -> vec4<f32> {
    var work = vec4<f32>(0.0);
    let moving = (ctrl.flags & FLAG_END) == 0u;
    let sample = (ctrl.flags & FLAG_SAMPLE) != 0u;
    let dt = ctrl.dt_next;
    let vl = vel(i);
    let d = dv(i);
    var vn = vl.xy + d;
    if (d.x != 0.0 || d.y != 0.0) {
        let g = c_nodes[i].x;
        // The correction joins node.wgsl's compensated sum: v + (d + residual), and the new
        // residual (`cc.p.one` keeps a reassociating compiler from folding it to 0).
        let y = d + v_prev[cc.p.n_nodes + g];
        vn = vl.xy + y;
        v_prev[cc.p.n_nodes + g] = y - (vn - vl.xy * cc.p.one);
    }
    c_pv[3u * i + 2u].x = vn.x;
    c_pv[3u * i + 2u].y = vn.y;
    if (d.x != 0.0 || d.y != 0.0) {
        let g = c_nodes[i].x;
        let m = bitcast<f32>(c_nodes[i].y);
        let mu = (1.0 + ctrl.damp_c) * m;
        let j = vec2<f32>(select(0.0, mu * d.x, c_ref[i].z > 0.0), select(0.0, mu * d.y, c_ref[i].w > 0.0));
        work = vec4<f32>(0.5 * dot(j, vl.zw + vn), 0.5 * dot(j, vn), 0.0, 0.0);
        var s = nodes[g];
        if (moving) {
            // (The displacement's compensated sum of node.wgsl.)
            let ru = 2u * cc.p.n_nodes + g;
            let yu = dt * d + v_prev[ru];
            let un = s.xy + yu;
            v_prev[ru] = yu - (un - s.xy * cc.p.one);
            s = vec4<f32>(un, vn);
        } else {
            s = vec4<f32>(s.xy, vn);
        }
        nodes[g] = s;
        if (sample) {
            let vq = v_prev[g];
            sample_src[g] = vec4<f32>(0.5 * m * dot(vq, vn), 0.5 * m * (vq + vn), 0.0);
        }
    }
    return work;
}

fn interface_of(k: u32) -> u32 {
    return slots[k].info & 0xffffu;
}

// (impulse on the first body, 1 if active, penetration) of slot k's constraint.
fn slot_report(k: u32, dt: f32) -> vec4<f32> {
    if (cons[k].kind == KIND_NONE) {
        return vec4<f32>(0.0);
    }
    let c = cons[k];
    var r = vec4<f32>(0.0);
    if (c.lambda > 0.0) {
        r = vec4<f32>(c.sign * c.lambda * c.n, 1.0, 0.0);
    }
    if (c.lt != 0.0) {
        r = vec4<f32>(r.xy + c.sign * c.lt * tangent(c), r.zw);
    }
    if (c.kind == KIND_PENALTY) {
        r.w = max(c.pen, 0.0);
    } else {
        r.w = max(-(c.g0 + dt * relative(c, slots[k].s)), 0.0);
    }
    return r;
}

// Slot k's friction: (its impulse along its slave's tangent (ContactSample::ft), the work of its
// impulses J (v^{n-1/2} + v^{n+1/2}) / 2 on the free directions of its nodes (as the CPU sums
// m dv_friction per node), the part after t_n, 0). After `finish`: c_pv[3i + 2].xy is v^{n+1/2}.
fn slot_friction(k: u32) -> vec4<f32> {
    if (cons[k].kind == KIND_NONE || cons[k].lt == 0.0) {
        return vec4<f32>(0.0);
    }
    let c = cons[k];
    let t = tangent(c);
    let s = slots[k].s;
    var nodes = array<u32, 3>(s, c.a, c.b);
    var share = array<f32, 3>(1.0, -(1.0 - c.xi), -c.xi);
    var before = 0.0;
    var after = 0.0;
    for (var q = 0u; q < 3u; q++) {
        let i = nodes[q];
        if (i == NONE) {
            continue;
        }
        let free = vec2<f32>(select(0.0, 1.0, c_ref[i].z > 0.0), select(0.0, 1.0, c_ref[i].w > 0.0));
        let j = share[q] * c.lt * t * free;
        let vn = c_pv[3u * i + 2u].xy;
        before += 0.5 * dot(j, vel(i).zw);
        after += 0.5 * dot(j, vn);
    }
    return vec4<f32>(c.lt, before + after, after, 0.0);
}

// Where interface f's active slots begin in the active list (f = n_ifaces: the count).
fn active_begin(f: u32) -> u32 {
    return ws[cc.p.o_aoff + ws[cc.p.o_iface + f]];
}

// 5a. Per chunk of CG active slots (in slot order), one partial per run of slots of one
//     interface, at the run's first position j in the active list: fws[f_rp + j] = (impulse,
//     active, largest penetration), summed in slot order; with friction also fws[f_rf + j] = the
//     sums of slot_friction. Dispatched over the active slots (indirect entry ACTIVE_ENTRY). Each
//     invocation puts its slot's report and interface in workgroup memory, and invocation 0 sums
//     the runs from there: through storage (as `contact_one` still does, one invocation a chunk)
//     its loop waited on two dependent loads a slot.
var<workgroup> sh_rf: array<vec4<f32>, CG>;
var<workgroup> sh_if: array<u32, CG>;

@compute @workgroup_size(CG)
fn report_slots(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let j = gid.x;
    let l = lid.x;
    // (No early return before the barrier: the kernel runs on when contact is not running,
    // doing nothing.)
    let running = contact_running();
    let na = select(0u, active_count(), running);
    var r = vec4<f32>(0.0);
    var rf = vec4<f32>(0.0);
    var f = NONE;
    if (j < na) {
        let k = active_slot(j);
        r = slot_report(k, ctrl.dt_next);
        count_bounded(k);
        if (FRICTION && cc.p.friction != 0u) {
            rf = slot_friction(k);
        }
        f = interface_of(k);
    }
    sh_f[l] = r;
    sh_rf[l] = rf;
    sh_if[l] = f;
    workgroupBarrier();
    if (l == 0u && j < na) {
        var runs = Runs(j, NONE, vec4<f32>(0.0), vec4<f32>(0.0));
        for (var q = 0u; q < min(CG, na - j); q++) {
            runs_add(&runs, j + q, sh_if[q], sh_f[q], sh_rf[q]);
        }
        runs_flush(runs);
    }
}

// A penalty slot k whose impulse was bounded this step, counted.
fn count_bounded(k: u32) {
    let c = cons[k];
    if (c.kind == KIND_PENALTY && c.dt_warm < 0.0) {
        atomicAdd(&cc.bounded, 1u);
    }
}

// Active slot j's report (and friction) into fws[f_rp + j] (and fws[f_rf + j]), for
// `report_runs`; the bounded penalty impulses counted.
fn report_item(j: u32) {
    let k = active_slot(j);
    fws[cc.p.f_rp + j] = slot_report(k, ctrl.dt_next);
    count_bounded(k);
    if (FRICTION && cc.p.friction != 0u) {
        fws[cc.p.f_rf + j] = slot_friction(k);
    }
}

// The run being summed: its first position in the active list, its interface (NONE before the
// first item) and its sums.
struct Runs {
    start: u32,
    f: u32,
    acc: vec4<f32>,
    accf: vec4<f32>,
}

// Adds the item at active position `at` (interface fq, report r, friction rf) to the runs in
// order: a new interface ends the run before it.
fn runs_add(s: ptr<function, Runs>, at: u32, fq: u32, r: vec4<f32>, rf: vec4<f32>) {
    if (fq != (*s).f) {
        runs_flush(*s);
        *s = Runs(at, fq, vec4<f32>(0.0), vec4<f32>(0.0));
    }
    let a = (*s).acc;
    (*s).acc = vec4<f32>(a.xyz + r.xyz, max(a.w, r.w));
    if (FRICTION && cc.p.friction != 0u) {
        (*s).accf += rf;
    }
}

// A run's sums into its first item's place.
fn runs_flush(s: Runs) {
    if (s.f != NONE) {
        fws[cc.p.f_rp + s.start] = s.acc;
        if (FRICTION && cc.p.friction != 0u) {
            fws[cc.p.f_rf + s.start] = s.accf;
        }
    }
}

// The runs of the n items from active position j (`report_item`), summed in order, each into its
// first item's place.
fn report_runs(j: u32, n: u32) {
    let friction = FRICTION && cc.p.friction != 0u;
    var runs = Runs(j, NONE, vec4<f32>(0.0), vec4<f32>(0.0));
    for (var q = 0u; q < n; q++) {
        var rf = vec4<f32>(0.0);
        if (friction) {
            rf = fws[cc.p.f_rf + j + q];
        }
        runs_add(&runs, j + q, interface_of(active_slot(j + q)), fws[cc.p.f_rp + j + q], rf);
    }
    runs_flush(runs);
}

fn acc_get(f: u32) -> vec4<f32> {
    let b = cc.p.row_capacity * cc.p.hist_stride + 4u * f;
    return vec4<f32>(c_hist[b], c_hist[b + 1u], c_hist[b + 2u], c_hist[b + 3u]);
}

fn acc_set(f: u32, a: vec4<f32>) {
    let b = cc.p.row_capacity * cc.p.hist_stride + 4u * f;
    c_hist[b] = a.x;
    c_hist[b + 1u] = a.y;
    c_hist[b + 2u] = a.z;
    c_hist[b + 3u] = a.w;
}

// 5b. Per interface (its slots are contiguous, and so are its active ones: active_begin(f) ..
//     active_begin(f + 1) in the active list), the partials of its runs, lane l taking runs l, l + SG, ... in order, then the tree (sums, and
//     the largest penetration); the history row on sample steps; the work (the finish partials
//     the same way); sweep counts. The whole workgroup works on each interface in turn, so that
//     an interface of many slots costs its slots / (CG SG) loads per lane, not its slots / CG.
@compute @workgroup_size(SG)
fn report_end(@builtin(local_invocation_id) lid: vec3<u32>) {
    if (running_uniform(lid.x)) {
        report_end_step(lid.x);
    }
}

// `report_end`'s work, by invocation l of its workgroup.
fn report_end_step(l: u32) {
    let sample = (ctrl.flags & FLAG_SAMPLE) != 0u;
    let dtn = ctrl.dt_node;
    let row = (ctrl.rows % cc.p.row_capacity) * cc.p.hist_stride;
    if (l == 0u) {
        sh_ni = cc.p.n_ifaces;
    }
    let ni = workgroupUniformLoad(&sh_ni);
    let friction = FRICTION && cc.p.friction != 0u;
    // With friction: the friction work of the step over all interfaces (lane 0), in order.
    var fwork = vec2<f32>(0.0);
    for (var f = 0u; f < ni; f++) {
        let lo = active_begin(f);
        let hi = active_begin(f + 1u);
        var r = vec4<f32>(0.0);
        var rf = vec4<f32>(0.0);
        if (hi > lo) {
            // Runs start at lo and at every chunk boundary after it, up to hi.
            let c0 = lo / CG;
            let runs = (hi - 1u) / CG - c0 + 1u;
            for (var j = l; j < runs; j += SG) {
                let at = select((c0 + j) * CG, lo, j == 0u);
                let p = fws[cc.p.f_rp + at];
                r = vec4<f32>(r.xyz + p.xyz, max(r.w, p.w));
                if (friction) {
                    rf += fws[cc.p.f_rf + at];
                }
            }
        }
        sh_sum[l] = r;
        sh_er[l] = rf;
        workgroupBarrier();
        for (var h = SG / 2u; h > 0u; h >>= 1u) {
            if (l < h) {
                let a = sh_sum[l];
                let b = sh_sum[l + h];
                sh_sum[l] = vec4<f32>(a.xyz + b.xyz, max(a.w, b.w));
                sh_er[l] += sh_er[l + h];
            }
            workgroupBarrier();
        }
        if (l == 0u) {
            let t = sh_sum[0];
            let tf = sh_er[0];
            fwork += tf.yz;
            // The friction impulse along the tangents also in the force (x, y), and its
            // scalar sum in a.w.
            var a = acc_get(f);
            a += vec4<f32>(t.xy, dtn, tf.x);
            if (sample) {
                var force = vec2<f32>(0.0);
                var ft = 0.0;
                if (a.z > 0.0) {
                    force = a.xy / a.z;
                    ft = a.w / a.z;
                }
                let h0 = row + hist_word(f);
                c_hist[h0] = force.x;
                c_hist[h0 + 1u] = force.y;
                c_hist[h0 + 2u] = t.w;
                c_hist[h0 + 3u] = t.z;
                if (friction) {
                    c_hist[h0 + 4u] = ft;
                }
                a = vec4<f32>(0.0);
            }
            acc_set(f, a);
        }
        workgroupBarrier();
    }
    // The impulses' work: the finish partials, lane l taking workgroups l, l + SG, ... in order.
    var part = vec4<f32>(0.0);
    let ng = (cc.p.n_local + CG - 1u) / CG;
    for (var g = l; g < ng; g += SG) {
        part += fws[cc.p.f_wp + g];
    }
    sum_tree(l, part);
    if (l != 0u) {
        return;
    }
    let total = sh_sum[0];
    var w = acc_get(cc.p.n_ifaces);
    // The running sums in compensated (Kahan) form, their residuals in the next accumulator: a
    // step adds about 1e-4 of the sum over 10^4 steps and more, the same way every step, and plain
    // f32 sums drifted by 1e-4 of it. The residual subtracts `sum * cc.p.one` (1, unknown to the
    // compiler) so that a reassociating compiler cannot fold (sum + y) - sum to y.
    var lo = acc_get(cc.p.n_ifaces + 1u);
    let yx = total.x + lo.x;
    let sx = w.x + yx;
    lo.x = yx - (sx - w.x * cc.p.one);
    w.x = sx;
    w.y = total.y;
    // The friction impulses' share (z: so far, w: this step's part after t_n), apart.
    let yz = fwork.x + lo.z;
    let sz = w.z + yz;
    lo.z = yz - (sz - w.z * cc.p.one);
    w.z = sz;
    w.w = fwork.y;
    acc_set(cc.p.n_ifaces, w);
    acc_set(cc.p.n_ifaces + 1u, lo);
    if (sample) {
        c_hist[row] = -(w.x - w.y) + (w.z - w.w);
        if (friction) {
            c_hist[row + 1u] = -(w.z - w.w);
        }
    }
    // Sweeps of this step (per-colour path: the sweeps that ran).
    if (atomicLoad(&cc.lagrange) > 0u) {
        var s = cc.sweeps;
        if (cc.p.multi != 0u) {
            // The sweeps that ran, and the change of the last of them: the step's residual.
            s = 0u;
            var last = 0u;
            for (var q = 0u; q < MAX_SWEEP_SLOTS; q++) {
                let c = atomicLoad(&cc.change[q]);
                if (c != 0u) {
                    s += 1u;
                    last = c;
                }
            }
            cc.residual = last;
        }
        // A step whose last solve stopped at max_sweeps, still above the tolerance: on both
        // paths counted once per step, as on the CPU reference.
        if (bitcast<f32>(cc.residual) > stop_tolerance()) {
            cc.unconverged += 1u;
        }
        // Non-negative floats order as their bits.
        cc.residual_max = max(cc.residual_max, cc.residual);
        cc.sweeps = s;
        cc.sweeps_total += s;
        cc.sweeps_max = max(cc.sweeps_max, s);
        cc.solve_steps += 1u;
    }
}
