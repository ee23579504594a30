// Velocity boundary conditions, one thread per constrained node, after the node stage: sets the
// prescribed components, corrects u_{n+1}, and accumulates the work of the reaction
// m (v_prescribed - v_free) v_prescribed. Mirrors the VelocityBoundaries stage of CpuSolver.

struct Constraint {
    node: u32,
    mask: u32,            // bit 0: x prescribed, bit 1: y prescribed
    vx: f32,
    vy: f32,
    mass: f32,
    _p0: f32,
    _p1: f32,
    _p2: f32,
}

override WG: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> cons: array<Constraint>;
@group(0) @binding(2) var<storage, read_write> nodes: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> v_prev: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read_write> sample_src: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> ctrl: Control;

@compute @workgroup_size(WG)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    if (k >= params.n_cons) {
        return;
    }
    if (ctrl.state != STATE_RUNNING) {
        return;
    }
    let c = cons[k];
    var s = nodes[c.node];
    let flags = ctrl.flags;
    let move_u = (flags & FLAG_END) == 0u;
    let dt = ctrl.dt_next;
    var work = 0.0;
    var vp = v_prev[c.node];
    // The reaction acts on the masses of the update ((1 + c) m with mass damping).
    let mr = c.mass * (1.0 + ctrl.damp_c);
    if ((c.mask & 1u) != 0u) {
        work += mr * (c.vx - s.z) * c.vx;
        if (move_u) {
            s.x += dt * (c.vx - s.z);
        }
        s.z = c.vx;
        vp.x = c.vx;
    }
    if ((c.mask & 2u) != 0u) {
        work += mr * (c.vy - s.w) * c.vy;
        if (move_u) {
            s.y += dt * (c.vy - s.w);
        }
        s.w = c.vy;
        vp.y = c.vy;
    }
    nodes[c.node] = s;
    if ((flags & (FLAG_SAMPLE | FLAG_SNAPSHOT)) != 0u) {
        v_prev[c.node] = vp;
        if ((flags & FLAG_SAMPLE) != 0u) {
            sample_src[c.node] = vec4<f32>(0.5 * c.mass * dot(vp, s.zw), 0.5 * c.mass * (vp + s.zw), 0.0);
        }
    }
    // (accumulated reaction work, this step's share); control.wgsl takes x - y / 2.
    let slot = params.n_nodes + params.n_elems + k;
    sample_src[slot] = vec4<f32>(sample_src[slot].x + work, work, 0.0, 0.0);
}
