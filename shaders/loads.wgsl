// Pressure loads, mass damping and gravity (scenes with `[[pressure]]`, `run.mass_damping` or
// `run.gravity` only; gravity's work is summed with the pressure's, as external work).
// pressure_force, one thread per (load, node) entry, before the node stage: the entry's force
//   p(t_n) F_per_Pa into its slot past the element slots, which the node stage gathers after the
//   node's element slots (in the CPU's order: elements, then the loads in scene order).
// load_work, one thread per node, after the contact stage: the work of the step's pressure impulse
//   J = dt_n F_p and of the damping impulse -c m (v- + v+), J (v^{n-1/2} + v^{n+1/2}) / 2 with the
//   final v^{n+1/2}, accumulated per node (sample_src after the constraints: pressure work, its part
//   after t_n, damping work, its part after t_n). Mirrors the Pressure and MassDamping stages of
//   CpuSolver.

// A pressure entry: force per unit pressure on its node, and its load's pressure and ramp.
struct Entry {
    f: vec2<f32>,         // N/Pa
    value: f32,           // Pa
    ramp: f32,            // s (0: none; -1 - k: the pressure is load curve k of `curves`)
}

override WG: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> ctrl: Control;
@group(0) @binding(2) var<storage, read> entries: array<Entry>;
@group(0) @binding(3) var<storage, read_write> elem_force: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> inv_mass: array<f32>;
@group(0) @binding(6) var<storage, read> adj_offsets: array<u32>;
@group(0) @binding(7) var<storage, read> adj_slots: array<u32>;
@group(0) @binding(8) var<storage, read> v_old: array<vec2<f32>>;
@group(0) @binding(9) var<storage, read_write> sample_src: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> curves: array<vec2<f32>>;


// Gravity at t_n: params.gravity times min(t / gravity_ramp, 1) (CPU: Model::gravity_at).
fn gravity_now() -> vec2<f32> {
    var f = 1.0;
    if (params.gravity_ramp > 0.0) {
        f = clamp(time_now() / params.gravity_ramp, 0.0, 1.0);
    }
    return f * vec2<f32>(params.gravity_x, params.gravity_y);
}

@compute @workgroup_size(WG)
fn pressure_force(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    if (k >= arrayLength(&entries) || ctrl.state != STATE_RUNNING) {
        return;
    }
    let e = entries[k];
    var p = e.value;
    if (e.ramp > 0.0) {
        p *= clamp(time_now() / e.ramp, 0.0, 1.0);
    } else if (e.ramp < 0.0) {
        p = curve_at(u32(-e.ramp) - 1u, time_now());
    }
    elem_force[4u * params.n_elems + k] = p * e.f;
}

@compute @workgroup_size(WG)
fn load_work(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= params.n_nodes || ctrl.state != STATE_RUNNING) {
        return;
    }
    let first = ctrl.step == 0u;
    let vp = nodes[i].zw;
    // v^{-1/2} = 2 v_0 - v^{1/2} on the first step.
    let vm = select(v_old[i], 2.0 * v_old[i] - vp, first);
    var fp = vec2<f32>(0.0);
    let pressure_slots = 4u * params.n_elems;
    let end = adj_offsets[i + 1u];
    for (var k = adj_offsets[i]; k < end; k++) {
        let s = adj_slots[k];
        if (s >= pressure_slots) {
            fp += elem_force[s];
        }
    }
    // Gravity's force m g, an external force like the pressure's.
    fp += gravity_now() / inv_mass[i];
    // The pressure impulse: dt_n F_n (dt^{1/2} F_0 on the first step, with v^{-1/2} as above).
    let j = select(ctrl.dt_node, ctrl.dt_next, first) * fp;
    let pb = 0.5 * dot(j, vm);
    let pa = 0.5 * dot(j, vp);
    let c = ctrl.damp_c;
    let jd = (-c / inv_mass[i]) * (vm + vp);
    let db = 0.5 * dot(jd, vm);
    let da = 0.5 * dot(jd, vp);
    let slot = params.n_nodes + params.n_elems + params.n_cons + i;
    let w = sample_src[slot];
    sample_src[slot] = vec4<f32>(w.x + pb + pa, pa, w.z + db + da, da);
}
