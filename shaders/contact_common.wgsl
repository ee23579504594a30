// Shared declarations of the contact kernels (prepended after common.wgsl to each contact stage:
// contact_search.wgsl, contact_narrow.wgsl, contact_solve.wgsl, contact_report.wgsl,
// contact_one.wgsl), and the helpers several stages call (a per-item kernel's guard, a
// one-workgroup kernel's run state, the workgroup's exclusive prefix, the Lagrange update). Every
// contact kernel binds the same bind group 0 (one explicit layout, built once); the kernels that
// write indirect dispatch sizes also bind group 1. Rust mirrors: src/gpu/contact/mod.rs (the
// parameters and counters) and src/gpu/contact/tables.rs (Slot, Segment).
//
// Local contact nodes are numbered 0..n_local; a slot is one pass's slave node or one wall's node;
// segments are the master segments of every pass. Workspace arrays live in `ws` (u32 words) and
// `fws` (vec4<f32>) at the offsets of ContactParams.

const CG: u32 = 64u;                  // threads per workgroup of the per-item contact kernels
// Threads of the one-workgroup contact kernels (plan, scans, the one-workgroup solve): 256 on
// GPUs, 8 on CPU adapters (src/gpu/shader.rs Features::contact_group).
const SG: u32 = 256u;
// The contact methods of the scene (src/gpu/shader.rs Features): the code of a method that no
// slot uses folds away when the kernels are compiled (lavapipe runs a branch that none of its
// lanes takes under a mask).
const SPRINGS: bool = true;           // penalty, perturbed or augmented Lagrangian slots
const FRICTION: bool = true;          // slots with Coulomb friction
const KIND_NONE: u32 = 0u;
const KIND_LAGRANGE: u32 = 1u;
const KIND_PENALTY: u32 = 2u;
const XI_TOLERANCE: f32 = 1e-6;       // crate::contact::rules::XI_TOLERANCE
const TIE_TOLERANCE: f32 = 1e-4;      // crate::contact::rules::TIE_TOLERANCE
const STIFF_SPRING: f32 = 1.0;        // crate::contact::solve::STIFF_SPRING
const STATE_SEARCH_GROW: u32 = 4u;    // the host grows a contact buffer and resumes the step
const STATE_ERODED: u32 = 5u;         // elements eroded: the host moves the surfaces' masks and resumes the step

const SLOT_PENALTY: u32 = 0x10000u;
const SLOT_WALL: u32 = 0x20000u;
const SLOT_SECOND: u32 = 0x40000u;    // two-body pass whose slave is the interface's second body
const SLOT_GROUP: u32 = 0x80000u;     // group pass: the sign follows the body order
const SLOT_SELF: u32 = 0x100000u;     // group pass that admits the slave's own body
const SLOT_PERTURBED: u32 = 0x200000u; // perturbed Lagrangian: the spring on the consistent penetration
// Eroding contact: a candidate slot (a node that erosion may expose) or segment (an element edge)
// that is not on its surface now; the search skips it (src/gpu/contact/erosion.rs writes the mask).
const SLOT_OFF: u32 = 0x400000u;
const SEGMENT_OFF: u32 = 1u;          // Segment.off
const SEGMENT_AXIS_A: u32 = 1u;       // Segment.axis: a lies on the axis of an axisymmetric body
const SEGMENT_AXIS_B: u32 = 2u;       // Segment.axis: b does

// Grow requests (ContactCtl.grow bits).
const GROW_CANDIDATES: u32 = 1u;
const GROW_COLORS: u32 = 2u;
const GROW_ROUNDS: u32 = 4u;

struct ContactParams {
    n_local: u32,
    n_slots: u32,
    n_segs: u32,
    n_ifaces: u32,
    margin: f32,          // search margin (half the shortest segment)
    max_sweeps: u32,      // sweeps at most per solve (one-group path) or per round (per-colour path)
    multi: u32,           // 1: one dispatch per colour (many workgroups); 0: one workgroup
    hist_stride: u32,     // f32 words per contact history row: 1 + 4 n_ifaces
    row_capacity: u32,
    n_buckets: u32,       // hash-grid buckets (a power of two)
    cand_capacity: u32,   // words of `grow` for candidates; the node adjacency follows
    adj_capacity: u32,
    jp_rounds: u32,       // colouring rounds recorded
    colors_recorded: u32, // colour dispatches recorded per sweep (per-colour path)
    tolerance: f32,       // a sweep converges when no gap changes by more than this (m)
    friction: u32,        // 1: some slot has friction (history rows carry its work and ft)
    o_bcount: u32,        // ws offsets
    o_boff: u32,
    o_bcur: u32,
    o_bent: u32,
    o_ccount: u32,
    o_coff: u32,
    o_ncount: u32,
    o_noff: u32,
    o_ncur: u32,
    o_color: u32,
    o_lcount: u32,        // slots per colour (MAX_COLORS + 1)
    o_loff: u32,
    o_lcur: u32,
    o_list: u32,          // slots in colour order (per-colour path); the one-workgroup solve's
                          // colouring state per slot when it colours through storage
    o_iface: u32,         // first slot of each interface (n_ifaces + 1)
    o_act: u32,           // the step's Lagrange slots by colour (one-workgroup solve)
    o_mask: u32,          // per local node: the one-workgroup solve's tie of its references, then its packed index
    f_rf: u32,            // fws offset: friction partials per slot run (with friction)
    one: f32,             // 1.0, unknown to the compiler (report_end's compensated sums)
    n_nodes: u32,         // v_prev[n_nodes + g]: node g's velocity residual (node.wgsl)
    f_box: u32,           // fws offsets: segment boxes
    f_usearch: u32,       // u at the last search per local node (xy)
    f_rp: u32,            // report partials per slot chunk start
    f_wp: u32,            // work partials per node chunk
    // The active slots (a pass slot with candidates, a wall slot near its wall: the only ones
    // that can have a constraint until the next search), built at each search: a flag per slot,
    // their exclusive prefix (n_slots + 1 words, the last the count), the list in slot order.
    o_aflag: u32,
    o_aoff: u32,
    o_alist: u32,
    split: u32,           // 1: the one-workgroup solve's re-checks run as their own dispatches
    // The one-workgroup solve's extrapolation between sweeps (crate::contact::extrapolation):
    // (lambda, lt) after the last sweep per compacted constraint, the constraints' nodes, their
    // dv after the last sweep.
    o_lprev: u32,
    o_nlist: u32,
    o_dvp: u32,
    extrapolate: u32,     // 1: extrapolate (one-workgroup path); 0: plain sweeps
    // The one-workgroup solve's packed rows (contact_solve.wgsl `pack`): per compacted constraint
    // its nodes' packed indices and its partner's packed index or NONE (ws, 4 words), its row
    // (fws, 2 vec4) and friction row (fws, 1 vec4, with friction); the packed nodes (fws,
    // n_local + 1 vec4).
    o_cidx: u32,
    f_row: u32,
    f_frow: u32,
    f_node: u32,
    o_best: u32,          // per slot: its best partner (contact_colour.wgsl `pair_constraints`)
    o_pair: u32,          // per slot: its pair code (PAIR_LEADER / PAIR_PARTNER | the other's index)
}

// Indirect entry of the kernels over the active slots (src/gpu/contact/mod.rs ACTIVE_ENTRY).
const ACTIVE_ENTRY: u32 = 78u;        // 14 + MAX_COLORS

const MAX_COLORS: u32 = 64u;

// The contact state on the device: the parameters (written by the host), then the counters it
// reads back. The parameters live in a storage buffer, not a uniform one: lavapipe (Mesa 22)
// recompiles a kernel whose loop bounds read a uniform buffer at every dispatch.
struct ContactCtl {
    p: ContactParams,
    due: atomic<u32>,         // a search is due this step
    extent: atomic<u32>,      // f32 bits of the largest segment box side (grid cell size)
    n_cand: atomic<u32>,      // candidates of the last search
    need_cand: u32,           // candidates the last search needed (when over capacity)
    n_adj: u32,
    searching: atomic<u32>,   // 1 when this step searches
    n_colors: atomic<u32>,    // colours of the last search
    searches: u32,
    grow: atomic<u32>,        // GROW_* requests for the host
    lagrange: atomic<u32>,    // Lagrange constraints of this step
    bounded: atomic<u32>,     // penalty impulses bounded so far (constraint-steps)
    sweeps: u32,              // sweeps of this step
    sweeps_total: u32,        // sweeps over the run (steps with Lagrange constraints)
    sweeps_max: u32,
    solve_steps: u32,         // steps with Lagrange constraints
    unconverged: u32,         // steps whose last solve stopped at max_sweeps (above the tolerance)
    residual: u32,            // f32 bits: this step's residual, the largest gap change of its last sweep
    residual_max: u32,        // f32 bits: the largest residual of a step over the run
    // Per-colour path: the largest gap change of each sweep (f32 bits; 0: the sweep did not run),
    // and the constraints each active-set re-check added.
    change: array<atomic<u32>, MAX_SWEEP_SLOTS>,
    added: array<atomic<u32>, 4>,
    // f32 bits: the largest penetration of the free update among this step's Lagrange
    // constraints so far (`note_penetration`; the narrow phase and the re-checks), the measure of
    // the solve's stop (`stop_tolerance`).
    penetration: atomic<u32>,
}

const MAX_SWEEP_SLOTS: u32 = 80u;     // (1 + ACTIVE_SET_ROUNDS) x sweeps of the per-colour path

struct Slot {
    info: u32,            // interface (bits 0-15), SLOT_* flags
    s: u32,               // slave (local node)
    np: u32,              // the slave's neighbours along its own surface (passes)
    nn: u32,
    normal: vec2<f32>,    // walls: unit normal and a point
    point: vec2<f32>,
    k: f32,               // walls: penalty stiffness of the node
    pass_id: u32,          // pass index (walls: NONE)
    body: u32,            // the slave's body
    mu: f32,              // Coulomb coefficient of its contact or wall (0: none)
    kt: f32,              // penalty friction: the tangential spring over the normal one
    ps: u32,              // perturbed Lagrangian: the slots of np, nn in the same pass (NONE: none)
    ns: u32,
    ar: f32,              // augmented Lagrangian: the multipliers' update rate (1/s; 0: none)
}

struct Segment {
    a: u32,
    b: u32,
    k: f32,               // penalty stiffness
    pass_id: u32,
    body: u32,
    off: u32,             // SEGMENT_OFF: a candidate edge not on its body's surface now
    axis: u32,            // SEGMENT_AXIS_A | SEGMENT_AXIS_B: its ends on the axis
    _p2: u32,
}

struct Cons {
    kind: u32,
    a: u32,
    b: u32,
    sign: f32,            // impulse on the interface's first body = sign * lambda * n
    n: vec2<f32>,
    xi: f32,
    g0: f32,              // gap at u_{n+1} of the free update
    w: f32,               // dt (1/m_s + (1-xi)^2/m_a + xi^2/m_b) along n
    lambda: f32,
    pen: f32,             // penalty: penetration at u_n
    dt_warm: f32,         // dt_n of the step that found lambda (Lagrange: the next step's warm
                          // start); penalty: -1 where the bound acted, else 0
    mu: f32,              // Coulomb coefficient (0: frictionless)
    wt: f32,              // (1/m_s + (1-xi)^2/m_a + xi^2/m_b) along t = (-n_y, n_x); penalty
                          // before its friction: the spring stiffness
    lt: f32,              // friction impulse along t, |lt| <= mu lambda
    ft: f32,              // kept for the next step: penalty friction's tangential spring force, or
                          // the augmented Lagrangian's multiplier (a force; it has no friction)
}

@group(0) @binding(1) var<storage, read_write> ctrl: Control;
@group(0) @binding(2) var<storage, read_write> nodes: array<vec4<f32>>;   // (u, v)
@group(0) @binding(3) var<storage, read_write> v_prev: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read_write> sample_src: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> c_nodes: array<vec2<u32>>; // (global index, mass bits)
@group(0) @binding(6) var<storage, read_write> c_ref: array<vec4<f32>>;   // (X, 1/m along x, y)
@group(0) @binding(7) var<storage, read_write> slots: array<Slot>;
@group(0) @binding(8) var<storage, read_write> segs: array<Segment>;
// Per local node i: 3i: (u_n, u_n + dt v_free), 3i+1: (v_free, v^{n-1/2}),
// 3i+2: (v^{n+1/2} kept for the next step, dv).
@group(0) @binding(9) var<storage, read_write> c_pv: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> cons: array<Cons>;
@group(0) @binding(12) var<storage, read_write> cc: ContactCtl;
@group(0) @binding(15) var<storage, read_write> fws: array<vec4<f32>>;
// History rows (1 + 4 n_ifaces words each, row_capacity rows), then per interface the impulse and
// time since the last sample, then (work, this step's part after t_n).
@group(0) @binding(16) var<storage, read_write> c_hist: array<f32>;
// A small index (colouring round, sweep) per dispatch: the bind group's dynamic offset selects it.
@group(0) @binding(17) var<uniform> round_index: vec4<u32>;
// Bindings 13 (`ws`, u32 workspace) and 14 (`grow`: candidates, then the node adjacency) are
// declared by each stage, atomic where it counts.

fn pos(i: u32) -> vec4<f32> {
    return c_pv[3u * i];
}

fn vel(i: u32) -> vec4<f32> {
    return c_pv[3u * i + 1u];
}

fn dv(i: u32) -> vec2<f32> {
    return c_pv[3u * i + 2u].zw;
}

fn add_dv(i: u32, d: vec2<f32>) {
    c_pv[3u * i + 2u].z += d.x;
    c_pv[3u * i + 2u].w += d.y;
}

// Whether the contact kernels run this step.
fn contact_running() -> bool {
    return ctrl.state == STATE_RUNNING;
}

// Whether thread i of a per-item kernel over n items has an item to work on this step.
fn item_runs(i: u32, n: u32) -> bool {
    return contact_running() && i < n;
}

var<workgroup> sh_state: u32;

// contact_running() as a workgroup-uniform value (for kernels with barriers); `l` the local index.
fn running_uniform(l: u32) -> bool {
    if (l == 0u) {
        sh_state = ctrl.state;
    }
    return workgroupUniformLoad(&sh_state) == STATE_RUNNING;
}

var<workgroup> sh_prefix: array<u32, SG>;
var<workgroup> sh_total: u32;

// The exclusive prefix of the lanes' `x` in lane order for lane l; their total in sh_total after
// the call. Integer sums, so the same on every run and either way: up to 32 lanes lane 0 adds them
// up in turn (on CPU adapters each barrier switches between lane groups), more by Hillis-Steele
// steps (log2 SG barrier pairs instead of SG dependent steps in one lane). Every lane of a
// one-workgroup kernel calls it, in uniform control flow.
fn workgroup_prefix(l: u32, x: u32) -> u32 {
    sh_prefix[l] = x;
    workgroupBarrier();
    if (SG <= 32u) {
        if (l == 0u) {
            var acc = 0u;
            for (var t = 0u; t < SG; t++) {
                let y = sh_prefix[t];
                sh_prefix[t] = acc;
                acc += y;
            }
            sh_total = acc;
        }
        workgroupBarrier();
        return sh_prefix[l];
    }
    var v = x;
    for (var d = 1u; d < SG; d <<= 1u) {
        if (l >= d) {
            v += sh_prefix[l - d];
        }
        workgroupBarrier();
        sh_prefix[l] = v;
        workgroupBarrier();
    }
    if (l == SG - 1u) {
        sh_total = v;
    }
    workgroupBarrier();
    return v - x;
}

// 1 / (1 + c): mass damping makes the update's masses (1 + c) m (see Control.damp_c).
fn inv_mass_scale() -> f32 {
    return 1.0 / (1.0 + ctrl.damp_c);
}

fn along(i: u32, n: vec2<f32>, inv_scale: f32) -> f32 {
    let im = c_ref[i].zw * inv_scale;
    return n.x * n.x * im.x + n.y * n.y * im.y;
}

// Relative velocity change of constraint `c` of slave `s` along `d` from the impulses so far.
fn relative_along(c: Cons, s: u32, d: vec2<f32>) -> f32 {
    var r = dot(dv(s), d);
    if (c.a != NONE) {
        r -= (1.0 - c.xi) * dot(dv(c.a), d) + c.xi * dot(dv(c.b), d);
    }
    return r;
}

// Relative normal velocity change of constraint `c` of slave `s` from the impulses so far.
fn relative(c: Cons, s: u32) -> f32 {
    return relative_along(c, s, c.n);
}

// Relative velocity along `d` of the free update (v_free) of constraint `c` of slave `s`.
fn free_relative_along(c: Cons, s: u32, d: vec2<f32>) -> f32 {
    var r = dot(vel(s).xy, d);
    if (c.a != NONE) {
        r -= (1.0 - c.xi) * dot(vel(c.a).xy, d) + c.xi * dot(vel(c.b).xy, d);
    }
    return r;
}

// The tangent t = (-n_y, n_x) of constraint `c`'s friction impulse.
fn tangent(c: Cons) -> vec2<f32> {
    return vec2<f32>(-c.n.y, c.n.x);
}

// Applies impulse `lambda` along `d` on the slave and its reaction on the master nodes.
fn apply_impulse_along(c: Cons, s: u32, d: vec2<f32>, lambda: f32, inv_scale: f32) {
    add_dv(s, lambda * inv_scale * d * c_ref[s].zw);
    if (c.a != NONE) {
        add_dv(c.a, -(1.0 - c.xi) * lambda * inv_scale * d * c_ref[c.a].zw);
        add_dv(c.b, -c.xi * lambda * inv_scale * d * c_ref[c.b].zw);
    }
}

// Applies impulse `lambda` along c.n on the slave and its reaction on the master nodes.
fn apply_impulse(c: Cons, s: u32, lambda: f32, inv_scale: f32) {
    apply_impulse_along(c, s, c.n, lambda, inv_scale);
}

// One projected Gauss-Seidel update of slot k's Lagrange constraint; returns the gap change.
fn pgs_update(k: u32, dt: f32, inv_scale: f32) -> f32 {
    let c = cons[k];
    if (c.kind != KIND_LAGRANGE) {
        return 0.0;
    }
    let s = slots[k].s;
    let g = c.g0 + dt * relative(c, s);
    let lambda = max(c.lambda - g / c.w, 0.0);
    let d = lambda - c.lambda;
    if (d != 0.0) {
        apply_impulse(c, s, d, inv_scale);
        cons[k].lambda = lambda;
    }
    var change = abs(d * c.w);
    if (FRICTION && c.mu > 0.0) {
        // Coulomb (CPU: ContactSet::sweep): the tangential impulse that stops the relative
        // tangential velocity inside the cone |lt| <= mu lambda (stick), else on its edge.
        let t = tangent(c);
        let vt = free_relative_along(c, s, t) + relative_along(c, s, t);
        let bound = c.mu * lambda;
        let lt = clamp(c.lt - vt / c.wt, -bound, bound);
        let e = lt - c.lt;
        if (e != 0.0) {
            apply_impulse_along(c, s, t, e, inv_scale);
            cons[k].lt = lt;
            change = max(change, abs(e * c.wt * dt));
        }
    }
    return change;
}

// A hashed priority of slot k (PCG's output permutation): the order of the colourings, the
// search's Jones-Plassmann rounds (`contact_search.wgsl`, `outranks`) and the one-workgroup
// solve's (`contact_solve.wgsl`, `colour_rank`).
fn priority(k: u32) -> u32 {
    var x = k * 747796405u + 2891336453u;
    x = ((x >> ((x >> 28u) + 4u)) ^ x) * 277803737u;
    return (x >> 22u) ^ x;
}

// A new Lagrange constraint's penetration of the free update (-g0, m) into cc.penetration: an
// integer atomic on the bits of a non-negative float (which order as their bits), the same result
// in any order.
fn note_penetration(c: Cons) {
    if (c.kind == KIND_LAGRANGE) {
        atomicMax(&cc.penetration, bitcast<u32>(max(-c.g0, 0.0)));
    }
}

// The stop of the Lagrange solve's sweeps on both paths (crate::gpu::contact::solve::
// STOP_PENETRATION), and what `report_end` counts a step unconverged against: STOP_PENETRATION
// times the largest penetration of the free update among the step's constraints so far
// (cc.penetration), within [STOP_FLOOR, 1] times cc.p.tolerance (1e-4 of the search margin).
// With the margin's tolerance alone, a contact under a steady load, whose free update
// penetrates by a small part of the margin a step (the contact patch test's 8/6 mesh: 8.6e-5 m
// a step against a stop of 8e-6 m), stopped after one sweep a step with the multipliers up to a
// tenth of that step's impulse off, and in some sweep orders (the GPUs' parallel colouring, the
// per-colour path) they settled into an oscillation instead of the uniform pressure (stress
// error 1.6e-2 and 2.5e-2 p, 2026-11-28/29). Impacts, whose free update penetrates by far more,
// keep the margin's stop.
const STOP_PENETRATION: f32 = 1e-2;
const STOP_FLOOR: f32 = 0.1;
fn stop_tolerance() -> f32 {
    let largest = bitcast<f32>(atomicLoad(&cc.penetration));
    return clamp(STOP_PENETRATION * largest, STOP_FLOOR * cc.p.tolerance, cc.p.tolerance);
}
