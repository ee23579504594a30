// The diagonal-mass Lagrange correction (CPU reference: crate::contact solve, ContactSet::sweep
// and ::recheck): projected Gauss-Seidel sweeps over the colours of the last search (slots of one
// colour share no node, so a colour is updated in parallel with the result of a sequential sweep:
// deterministic), until no gap changes by more than cp.tolerance or cp.max_sweeps; then the
// active-set update (free Lagrange slots re-checked at the corrected positions, more sweeps when
// any penetrates), ACTIVE_SET_ROUNDS rounds at most. Compiled after contact_narrow.wgsl.
//
// Two paths, chosen by size on the host: `solve_one`, every sweep in one workgroup (colours
// separated by barriers; the fastest for small contact sets), and `sweep_color` + `recheck`, one
// dispatch per colour and sweep over as many workgroups as the colour needs.

const ACTIVE_SET_ROUNDS: u32 = 4u;    // crate::contact::ACTIVE_SET_ROUNDS

var<workgroup> sh_m: array<f32, SG>;
var<workgroup> sh_w: u32;
var<workgroup> sh_nc: u32;

// Whether any invocation's `x` is positive, as a workgroup-uniform value: a tree over sh_m with
// barriers, written by invocation 0 into a plain workgroup word. (Every exit of the solve loops
// is decided this way, never by a uniform load of a workgroup atomic: with the old single kernel
// on lavapipe the invocations disagreed about such a load, left the loops at different barriers,
// and the step lost its contact impulses.)
fn any_positive(l: u32, x: f32) -> bool {
    sh_m[l] = x;
    workgroupBarrier();
    for (var h = SG / 2u; h > 0u; h >>= 1u) {
        if (l < h) {
            sh_m[l] = max(sh_m[l], sh_m[l + h]);
        }
        workgroupBarrier();
    }
    if (l == 0u) {
        sh_w = select(0u, 1u, sh_m[0] > 0.0);
    }
    return workgroupUniformLoad(&sh_w) != 0u;
}

fn list_begin(c: u32) -> u32 {
    return ws[cp.o_loff + c];
}

fn list_end(c: u32) -> u32 {
    return ws[cp.o_loff + c + 1u];
}

// Sweeps in one workgroup; returns the sweeps taken.
fn sweeps_one(l: u32, dt: f32, inv_scale: f32) -> u32 {
    if (l == 0u) {
        sh_nc = atomicLoad(&cc.n_colors);
    }
    let nc = workgroupUniformLoad(&sh_nc);
    var taken = 0u;
    for (var sweep = 0u; sweep < cp.max_sweeps; sweep++) {
        var change = 0.0;
        for (var col = 0u; col < nc; col++) {
            let end = list_end(col);
            for (var q = list_begin(col) + l; q < end; q += SG) {
                change = max(change, pgs_update(ws[cp.o_list + q], dt, inv_scale));
            }
            storageBarrier();
        }
        taken += 1u;
        if (!any_positive(l, change - cp.tolerance)) {
            return taken;
        }
    }
    if (l == 0u) {
        cc.unconverged += 1u;
    }
    return taken;
}

// A free Lagrange slot re-checked at the corrected positions x_tr + dt dv (ContactSet::recheck);
// whether it now has a constraint.
fn recheck_slot(k: u32, dt: f32, dtn: f32, inv_scale: f32) -> bool {
    let sl = slots[k];
    if (cons[k].kind != KIND_NONE || (sl.info & SLOT_PENALTY) != 0u) {
        return false;
    }
    corr_dt = dt;
    var c = narrow_slot(k, dt, dtn, inv_scale);
    corr_dt = 0.0;
    if (c.kind != KIND_LAGRANGE) {
        return false;
    }
    // The gap at the free trial positions, as for every constraint.
    c.g0 -= dt * relative(c, sl.s);
    c.dt_warm = dtn;
    cons[k] = c;
    return true;
}

@compute @workgroup_size(SG)
fn solve_one(@builtin(local_invocation_id) lid: vec3<u32>) {
    let l = lid.x;
    if (!running_uniform(l)) {
        return;
    }
    if (l == 0u) {
        sh_w = select(0u, 1u, atomicLoad(&cc.lagrange) > 0u);
    }
    if (workgroupUniformLoad(&sh_w) == 0u) {
        return;
    }
    let dt = ctrl.dt_next;
    let dtn = ctrl.dt_node;
    let inv_scale = inv_mass_scale();
    var taken = sweeps_one(l, dt, inv_scale);
    for (var round = 0u; round < ACTIVE_SET_ROUNDS; round++) {
        var added = 0.0;
        for (var k = l; k < cp.n_slots; k += SG) {
            if (recheck_slot(k, dt, dtn, inv_scale)) {
                added = 1.0;
            }
        }
        storageBarrier();
        if (!any_positive(l, added)) {
            break;
        }
        taken += sweeps_one(l, dt, inv_scale);
    }
    if (l == 0u) {
        cc.sweeps = taken;
    }
}

// Per-colour path. Sweep q (of (1 + ACTIVE_SET_ROUNDS) * max_sweeps) runs when the solve is still
// going: the first sweep when there are Lagrange constraints, the first after a re-check when it
// added constraints, any other when the previous sweep ran and changed a gap by more than the
// tolerance (cc.change, cc.added).
fn sweep_runs(q: u32) -> bool {
    if (q == 0u) {
        return atomicLoad(&cc.lagrange) > 0u;
    }
    if (q % cp.max_sweeps == 0u) {
        return atomicLoad(&cc.added[q / cp.max_sweeps - 1u]) > 0u;
    }
    let prev = atomicLoad(&cc.change[q - 1u]);
    return prev != 0u && bitcast<f32>(prev) > cp.tolerance;
}

@compute @workgroup_size(CG)
fn sweep_color(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (!contact_running()) {
        return;
    }
    let col = round_index.x;
    let q = round_index.y;
    if (!sweep_runs(q)) {
        return;
    }
    let at = list_begin(col) + gid.x;
    if (at >= list_end(col)) {
        return;
    }
    let change = pgs_update(ws[cp.o_list + at], ctrl.dt_next, inv_mass_scale());
    // Mark the sweep as run (a tiny positive change) even when nothing changed here.
    atomicMax(&cc.change[q], bitcast<u32>(max(change, 1e-30)));
}

// Re-check r after the sweeps of round r: runs when the round's last sweep ran or converged
// (the solve was going), counts the constraints it adds.
@compute @workgroup_size(CG)
fn recheck(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (!contact_running()) {
        return;
    }
    let r = round_index.x;
    let q0 = r * cp.max_sweeps;
    if (atomicLoad(&cc.change[q0]) == 0u) {
        return;
    }
    let k = gid.x;
    if (k < cp.n_slots && recheck_slot(k, ctrl.dt_next, ctrl.dt_node, inv_mass_scale())) {
        atomicAdd(&cc.added[r], 1u);
    }
}
