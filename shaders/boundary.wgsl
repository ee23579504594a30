// Velocity boundary conditions, one thread per constrained node, after the node stage: sets the
// prescribed components (a constant, or load curve k of `curves` at t_{n+1/2}), corrects u_{n+1},
// and accumulates the work of the reaction j = m (v^{n+1/2} - v_free), j (v^{n-1/2} + v^{n+1/2}) / 2
// with v^{n-1/2} the prescribed value at t_{n-1/2} (2 v_0 - v^{1/2} on the first step). Mirrors
// the VelocityBoundaries stage of CpuSolver.

struct Constraint {
    node: u32,
    mask: u32,            // bit 0: x prescribed, bit 1: y prescribed
    vx: f32,
    vy: f32,
    mass: f32,
    curve_x: u32,         // load curve of vx (NONE: the constant vx)
    curve_y: u32,
    _p0: f32,
}

override WG: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> cons: array<Constraint>;
@group(0) @binding(2) var<storage, read_write> nodes: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> v_prev: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read_write> sample_src: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> ctrl: Control;
@group(0) @binding(6) var<storage, read> curves: array<vec2<f32>>;

fn prescribed(v: f32, curve: u32, t: f32) -> f32 {
    if (curve == NONE) {
        return v;
    }
    return curve_at(curve, t);
}

@compute @workgroup_size(WG)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    if (k >= params.n_cons || ctrl.state != STATE_RUNNING) {
        return;
    }
    let c = cons[k];
    var s = nodes[c.node];
    let flags = ctrl.flags;
    let move_u = (flags & FLAG_END) == 0u;
    let dt = ctrl.dt_next;
    var work = 0.0;
    var after = 0.0;
    var vp = v_prev[c.node];
    // The reaction acts on the masses of the update ((1 + c) m with mass damping).
    let mr = c.mass * (1.0 + ctrl.damp_c);
    let t = time_now();
    let t_new = t + 0.5 * dt;
    let t_old = t - 0.5 * ctrl.dt_prev;
    let first = ctrl.step == 0u;
    // On the first step the update is a half step: the reaction's share in
    // M (v^{1/2} - v^{-1/2}) = dt f_0 + 2 j is 2 j (as on the CPU).
    let jw = select(1.0, 2.0, first) * mr;
    // Each prescribed direction a (x, then y): s[a] is u, s[2 + a] is v.
    let value = vec2<f32>(c.vx, c.vy);
    let curve = vec2<u32>(c.curve_x, c.curve_y);
    for (var a = 0u; a < 2u; a++) {
        if ((c.mask & (1u << a)) == 0u) {
            continue;
        }
        let vn = prescribed(value[a], curve[a], t_new);
        let vo = select(prescribed(value[a], curve[a], t_old), 2.0 * prescribed(value[a], curve[a], t) - vn, first);
        let j = jw * (vn - s[2u + a]);
        work += 0.5 * j * (vo + vn);
        after += j * vn;
        if (move_u) {
            s[a] += dt * (vn - s[2u + a]);
        }
        s[2u + a] = vn;
        vp[a] = vo;
    }
    nodes[c.node] = s;
    if ((flags & (FLAG_SAMPLE | FLAG_SNAPSHOT)) != 0u) {
        v_prev[c.node] = vp;
        if ((flags & FLAG_SAMPLE) != 0u) {
            sample_src[c.node] = vec4<f32>(0.5 * c.mass * dot(vp, s.zw), 0.5 * c.mass * (vp + s.zw), 0.0);
        }
    }
    // (accumulated reaction work, twice this step's share after t_n); control.wgsl takes x - y / 2.
    let slot = params.n_nodes + params.n_elems + k;
    sample_src[slot] = vec4<f32>(sample_src[slot].x + work, after, 0.0, 0.0);
}
