// Run control on the GPU, one workgroup, so that a batch of steps needs no readback.
// control_dt: second level of the stable-step reduction, checks, dt^{n+1/2} and dt_n.
// control_end: the history row from the instances' sums (reduce.wgsl's sum_instances, or here for
//   fused small models), then t_{n+1}, the flags of the next step (sample / snapshot / end, same
//   rules as step::Clock) and the indirect dispatch sizes.
// Compiled after tree.wgsl and reduce_common.wgsl (the lanes' shares and the trees, shared with
// reduce.wgsl). Its workgroup's threads, RG, are Features::control_group (8 on CPU adapters),
// which may be fewer than the first level's (reduce.wgsl's RG, Features::reduce_group).

const RG: u32 = 256u;
const TREE: u32 = RG;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> ctrl: Control;
@group(0) @binding(2) var<storage, read> dt_partial: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read> instances: array<Instance>;
@group(0) @binding(5) var<storage, read_write> history: array<f32>;
@group(0) @binding(6) var<storage, read> times: array<vec2<u32>>;   // sample, then snapshot times (ticks)
@group(0) @binding(7) var<storage, read_write> indirect: array<u32>;
// Small models on CPU adapters reduce in this one workgroup (params.dt_groups == 0 and
// params.sum_groups == 0): two dispatches fewer per step, where each dispatch costs more than the work.
@group(0) @binding(8) var<storage, read> elem_dt: array<f32>;
@group(0) @binding(9) var<storage, read> sample_src: array<vec4<f32>>;
// Each instance's sum on sample steps (bodies, elements, constraints, loads), by thread 0.
@group(0) @binding(10) var<storage, read_write> inst_res: array<vec4<f32>>;

var<workgroup> sh_u: u32;

fn fail(code: u32, index: u32, value: f32) {
    ctrl.state = STATE_FAILED;
    ctrl.fail_code = code;
    ctrl.fail_index = index;
    ctrl.fail_value = value;
}

// Fails the run with `code` when a kernel flagged `bad` (an inverted element, a node whose
// velocity is not finite; NONE: none); whether it did.
fn flagged(bad: u32, code: u32) -> bool {
    if (bad != NONE) {
        fail(code, bad, 0.0);
    }
    return bad != NONE;
}

// t_n + TIME_SLACK dt^{n-1/2} >= T (step::Clock's rule), in ticks.
fn due(when: vec2<u32>) -> bool {
    let slack = to_ticks(0.01 * ctrl.dt_prev, params.ticks_per_second);
    return ge64(add64(vec2<u32>(ctrl.t_lo, ctrl.t_hi), slack), when);
}

// Whether the run goes on (ctrl.state), as a workgroup-uniform value; `l` the local index.
fn running(l: u32) -> bool {
    if (l == 0u) {
        sh_u = ctrl.state;
    }
    return workgroupUniformLoad(&sh_u) == STATE_RUNNING;
}

@compute @workgroup_size(RG)
fn control_dt(@builtin(local_invocation_id) lid: vec3<u32>) {
    let l = lid.x;
    if (!running(l)) {
        return;
    }
    if (params.dt_groups == 0u) {
        lane_min_dt(l, 0u, RG);
    } else {
        // The first level's partials (as many as its workgroups, at most the reductions' RG,
        // which may exceed this workgroup's), each lane's share at a stride.
        var d = 3.0e38;
        var ix = NONE;
        for (var g = l; g < params.dt_groups; g += RG) {
            let p = dt_partial[g];
            if (better(d, ix, bitcast<f32>(p.x), p.y)) {
                d = bitcast<f32>(p.x);
                ix = p.y;
            }
        }
        sh_dt[l] = d;
        sh_ix[l] = ix;
    }
    min_tree(l);
    if (l != 0u) {
        return;
    }
    if (flagged(atomicLoad(&ctrl.bad_element), 1u)) {
        return;
    }
    var dt_min = sh_dt[0];
    let at = sh_ix[0];
    if (params.failure != 0u && dt_min >= 2.9e38 && ctrl.step > 0u) {
        // Every element eroded (element.wgsl's ERODED_DT): free masses, which keep the last step.
        dt_min = ctrl.dt_prev / params.scale;
    }
    if (not_finite(dt_min) || !(dt_min > 0.0)) {
        fail(5u, at, dt_min);
        return;
    }
    var dt_stable = dt_min;
    if (params.penalty_dt > 0.0) {
        // The penalty springs: 1 / dt^2 = 1 / dt_element^2 + 1 / dt_penalty^2.
        dt_stable = 1.0 / sqrt(1.0 / (dt_min * dt_min) + 1.0 / (params.penalty_dt * params.penalty_dt));
    }
    var dt_next = params.scale * dt_stable;
    if (params.fixed_dt > 0.0) {
        if (params.fixed_dt > dt_stable) {
            fail(3u, at, dt_stable);
            return;
        }
        dt_next = params.fixed_dt;
    }
    if (ctrl.step == 0u) {
        ctrl.dt_first = dt_next;
    } else if (dt_next < 1e-6 * ctrl.dt_first) {
        fail(4u, at, dt_next);
        return;
    }
    // A last step that would carry the run past its end by more than 1 % of the run lands on it
    // (step::clip_to_end).
    let now = vec2<u32>(ctrl.t_lo, ctrl.t_hi);
    let end = vec2<u32>(params.end_lo, params.end_hi);
    if ((ctrl.flags & FLAG_END) == 0u && !ge64(now, end)) {
        let borrow = select(0u, 1u, end.x < now.x);
        let r = vec2<u32>(end.x - now.x, end.y - now.y - borrow);
        let remaining = (f32(r.y) * 4294967296.0 + f32(r.x)) / params.ticks_per_second;
        let end_s = (f32(end.y) * 4294967296.0 + f32(end.x)) / params.ticks_per_second;
        if (remaining < dt_next && dt_next - remaining > 0.01 * end_s) {
            dt_next = remaining;
        }
    }
    ctrl.dt_min = min(ctrl.dt_min, dt_next);
    ctrl.dt_max = max(ctrl.dt_max, dt_next);
    if (ctrl.step == 0u) {
        ctrl.dt_node = 0.5 * dt_next;
    } else {
        ctrl.dt_node = 0.5 * (ctrl.dt_prev + dt_next);
    }
    ctrl.dt_next = dt_next;
    ctrl.dt_elem = at;
    // Mass damping from the second step on (the first half step stays undamped, as on the CPU).
    ctrl.damp_c = select(0.0, 0.5 * params.mass_damping * ctrl.dt_node, ctrl.step > 0u);
}

@compute @workgroup_size(RG)
fn control_end(@builtin(local_invocation_id) lid: vec3<u32>) {
    let l = lid.x;
    if (!running(l)) {
        return;
    }
    if (l == 0u) {
        sh_u = ctrl.flags;
    }
    let flags = workgroupUniformLoad(&sh_u);
    let sample = (flags & FLAG_SAMPLE) != 0u;
    // Fused (small models on CPU adapters): the instances' sums here; else sum_instances did them.
    if (sample && params.sum_groups == 0u) {
        for (var r = 0u; r < params.n_instances; r++) {
            sum_items(l, instances[r], 0u, RG);
            if (l == 0u) {
                inst_res[r] = sh_sum[0];
            }
            workgroupBarrier();
        }
    }
    // The bodies' velocities into the row and their kinetic energies summed, across the lanes
    // (body b on lane b % RG, each lane in body order, then the tree: a fixed order).
    let nb = params.n_bodies;
    let base = (ctrl.rows % params.row_capacity) * params.row_stride;
    // The plastic work (word 9) comes before the bodies' words in a plastic scene, and the
    // eroded count and energy after it in a scene with failure.
    let bw = base + 9u + params.plastic + 2u * params.failure;
    if (sample) {
        var ke_lane = 0.0;
        for (var b = l; b < nb; b += RG) {
            ke_lane += inst_res[b].x;
            let v = inst_res[b].yz * instances[b].scale;
            history[bw + 2u * b] = v.x;
            history[bw + 1u + 2u * b] = v.y;
        }
        sum_tree(l, vec4<f32>(ke_lane, 0.0, 0.0, 0.0));
    }
    if (l != 0u) {
        return;
    }
    if (flagged(atomicLoad(&ctrl.bad_node), 2u)) {
        return;
    }
    if (sample) {
        let ke = sh_sum[0].x;
        if (params.plastic != 0u) {
            history[base + 9u] = inst_res[params.n_instances - 1u - params.failure].x;
        }
        if (params.failure != 0u) {
            // The eroded elements' energy and count (element.wgsl), the last instance.
            let er = inst_res[params.n_instances - 1u];
            history[base + 9u + params.plastic] = er.y;
            history[base + 10u + params.plastic] = er.x;
        }
        let el = inst_res[nb];
        var ext = 0.0;
        if (params.n_cons > 0u) {
            // Accumulated reaction work minus half of this step's (shared with the next interval).
            ext = inst_res[nb + 1u].x - 0.5 * inst_res[nb + 1u].y;
        }
        var viscous = el.w;
        if (params.loads != 0u) {
            // Pressure and damping work (accumulated, and this step's part after t_n; loads.wgsl).
            let w = inst_res[nb + select(1u, 2u, params.n_cons > 0u)];
            ext += w.x - w.y;
            viscous -= w.z - w.w;
        }
        history[base + 0u] = bitcast<f32>(ctrl.t_lo);
        history[base + 1u] = bitcast<f32>(ctrl.t_hi);
        history[base + 2u] = bitcast<f32>(ctrl.step);
        history[base + 3u] = ctrl.dt_next;
        history[base + 4u] = ke;
        history[base + 5u] = el.x;
        history[base + 6u] = el.y + el.z;
        history[base + 7u] = viscous;
        history[base + 8u] = ext;
        ctrl.rows += 1u;
        while (ctrl.next_sample < params.n_sample_times && due(times[ctrl.next_sample])) {
            ctrl.next_sample += 1u;
        }
    }
    if ((flags & FLAG_SNAPSHOT) != 0u) {
        ctrl.state = STATE_PAUSED;
        while (ctrl.next_snapshot < params.n_snapshot_times
            && due(times[params.n_sample_times + ctrl.next_snapshot])) {
            ctrl.next_snapshot += 1u;
        }
    }
    if ((flags & FLAG_END) != 0u) {
        ctrl.state = STATE_DONE;
        return;
    }
    // t_{n+1} = t_n + dt^{n+1/2}, in ticks.
    let dt = ctrl.dt_next;
    let t = add64(vec2<u32>(ctrl.t_lo, ctrl.t_hi), to_ticks(dt, params.ticks_per_second));
    ctrl.t_lo = t.x;
    ctrl.t_hi = t.y;
    ctrl.dt_prev = dt;
    ctrl.step += 1u;
    // Flags of the next step.
    let at_end = due(vec2<u32>(params.end_lo, params.end_hi));
    var nf = 0u;
    if (at_end) {
        nf |= FLAG_END | FLAG_SAMPLE;
        if (params.n_snapshot_times > 0u) {
            nf |= FLAG_SNAPSHOT;
        }
    }
    if (ctrl.next_sample < params.n_sample_times && due(times[ctrl.next_sample])) {
        nf |= FLAG_SAMPLE;
    }
    if (ctrl.next_snapshot < params.n_snapshot_times
        && due(times[params.n_sample_times + ctrl.next_snapshot])) {
        nf |= FLAG_SNAPSHOT;
    }
    ctrl.flags = nf;
    let on = (nf & FLAG_SAMPLE) != 0u;
    indirect[0] = select(0u, params.sum_groups, on);
    indirect[1] = 1u;
    indirect[2] = 1u;
    indirect[3] = select(0u, params.inst_groups, on && params.sum_groups > 0u);
    indirect[4] = 1u;
    indirect[5] = 1u;
}
