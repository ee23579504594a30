// Node stage: gathers each node's force from its elements' slots in a fixed order (no atomics,
// deterministic), then the central-difference update v^{n+1/2} = v^{n-1/2} + dt_n f / m and
// u_{n+1} = u_n + dt^{n+1/2} v^{n+1/2}; on sample steps also the node's kinetic energy
// 1/2 m v^{n-1/2} . v^{n+1/2} and momentum. Mirrors CpuSolver::step (stages 3 to 5).
// The velocity update is a compensated sum: the increment dt_n f / m is about 1e-4 of v in a long
// run, and f32 rounds it by up to half an ulp of v every step, the same way over thousands of
// steps (a free fall drifted 2e-4 from g t in 27 000 steps); each node carries the rounding residual
// of its last update (v_prev[n_nodes + i]) into the next increment (Kahan), so that the drift
// stays at one ulp. The displacement update is compensated the same way (v_prev[2 n_nodes + i]):
// a node pressed against a contact or loaded at rest moves by a few ulps of u a step, and the
// lost rounding made the work of the forces on it (from v) part from the strain energy (from u):
// the contact patch test with penalty springs ended 1.9e-4 off balance, 1.8e-6 with it.

override WG: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> nodes: array<vec4<f32>>;   // (u, v)
@group(0) @binding(2) var<storage, read> inv_mass: array<f32>;
@group(0) @binding(3) var<storage, read> adj_offsets: array<u32>;     // n_nodes + 1
@group(0) @binding(4) var<storage, read> adj_slots: array<u32>;       // 4 e + corner
@group(0) @binding(5) var<storage, read> elem_force: array<vec2<f32>>;
@group(0) @binding(6) var<storage, read_write> v_prev: array<vec2<f32>>;  // v^{n-1/2}, then residuals
@group(0) @binding(7) var<storage, read_write> ctrl: Control;
@group(0) @binding(8) var<storage, read_write> sample_src: array<vec4<f32>>;
//#if fields
@group(0) @binding(9) var<storage, read_write> u_snap: array<vec2<f32>>;
//#endif
//#if loads
@group(0) @binding(10) var<storage, read_write> v_old: array<vec2<f32>>;  // v^{n-1/2}, for loads.wgsl
//#endif

//#if loads
// Gravity at t_n: params.gravity times min(t / gravity_ramp, 1) (CPU: Model::gravity_at).
fn gravity_now() -> vec2<f32> {
    var f = 1.0;
    if (params.gravity_ramp > 0.0) {
        let t = (f32(ctrl.t_hi) * 4294967296.0 + f32(ctrl.t_lo)) / params.ticks_per_second;
        f = clamp(t / params.gravity_ramp, 0.0, 1.0);
    }
    return f * vec2<f32>(params.gravity_x, params.gravity_y);
}
//#endif

@compute @workgroup_size(WG)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    // The step's control words, read before any lane returns (lavapipe loads an address that
    // every lane shares once while no lane has left; after that, lane by lane).
    let state = ctrl.state;
    let dt_node = ctrl.dt_node;
    let dt_next = ctrl.dt_next;
    let flags = ctrl.flags;
    if (i >= params.n_nodes || state != STATE_RUNNING) {
        return;
    }
    var f = vec2<f32>(0.0);
    let end = adj_offsets[i + 1u];
    for (var k = adj_offsets[i]; k < end; k++) {
        f += elem_force[adj_slots[k]];
    }
    let s = nodes[i];
    let vm = s.zw;
//#if loads
    // Pressure forces arrive through slots past the elements' (see loads.wgsl). Mass damping:
    // (1 + c) m v+ = (1 - c) m v- + dt_n f, c = alpha dt_n / 2 (implicit in v, stable for any alpha).
    v_old[i] = vm;
    // Gravity: the force m g (loads.wgsl sums its work with the pressure's).
    f += gravity_now() / inv_mass[i];
    let c = ctrl.damp_c;
    // v+ - v- = -2c / (1 + c) v- + dt_n f / (m (1 + c)).
    let inc = (-2.0 * c / (1.0 + c)) * vm + (dt_node * inv_mass[i] / (1.0 + c)) * f;
//#else
    let inc = (dt_node * inv_mass[i]) * f;
//#endif
    // Kahan: v+ = v- + (inc + the last residual), and the new residual y - (v+ - v-); v- enters
    // the subtraction as v- * params.one, which the compiler cannot fold away.
    let r = params.n_nodes + i;
    let y = inc + v_prev[r];
    let vp = vm + y;
    v_prev[r] = y - (vp - vm * params.one);
    if (not_finite(vp.x) || not_finite(vp.y)) {
        atomicMin(&ctrl.bad_node, i);
    }
    if ((flags & (FLAG_SAMPLE | FLAG_SNAPSHOT)) != 0u) {
        // v^{-1/2} = 2 v_0 - v^{1/2} on the first step.
        let vq = select(vm, 2.0 * vm - vp, ctrl.step == 0u);
        v_prev[i] = vq;
        if ((flags & FLAG_SAMPLE) != 0u) {
            // Kinetic energy in the conserved form, and momentum at t_n.
            let m = 1.0 / inv_mass[i];
            sample_src[i] = vec4<f32>(0.5 * m * dot(vq, vp), 0.5 * m * (vq + vp), 0.0);
        }
    }
//#if fields
    if ((flags & FLAG_SNAPSHOT) != 0u) {
        u_snap[i] = s.xy;
    }
//#endif
    var u = s.xy;
    if ((flags & FLAG_END) == 0u) {
        // The displacement update is compensated the same way (its residual in
        // v_prev[2 n_nodes + i]): late in a run dt v is a few ulps of u, and a node at rest against
        // a contact or a load would otherwise stop moving while its velocity (and the work of
        // the forces on it) does not.
        let ru = 2u * params.n_nodes + i;
        let yu = dt_next * vp + v_prev[ru];
        u = s.xy + yu;
        v_prev[ru] = yu - (u - s.xy * params.one);
    }
    nodes[i] = vec4<f32>(u, vp);
}
