// Shared declarations of ricochet's kernels. Prepended to every kernel by src/gpu/shader.rs;
// the Rust mirrors live in src/gpu/layout.rs (sizes asserted there).

// Static run parameters (uniform).
struct Params {
    n_nodes: u32,
    n_elems: u32,
    n_cons: u32,
    n_bodies: u32,
    scale: f32,
    fixed_dt: f32,        // 0: stable step x scale
    end_lo: u32,          // end_time in ticks (64-bit: lo, hi)
    end_hi: u32,
    n_sample_times: u32,
    n_snapshot_times: u32,
    row_stride: u32,      // f32 words per history row
    row_capacity: u32,
    dt_groups: u32,       // workgroups of the stable-step reduction
    n_instances: u32,     // sum reductions on sample steps
    sum_groups: u32,      // workgroups of all sum reductions together
    ticks_per_second: f32, // time is kept as a 64-bit count of ticks of end_time / 2^40 (layout.rs: ticks_per_end)
    penalty_dt: f32,      // stable step of the penalty springs alone (0: none)
    mass_damping: f32,    // alpha of run.mass_damping (0: none)
    loads: u32,           // 1: pressure or damping work is summed (sample_src after the constraints)
    plastic: u32,         // 1: J2 plastic work is summed (sample_src after the loads) into word 9
    inst_groups: u32,     // workgroups of sum_instances (the second level of the sums; 0: fused)
    gravity_x: f32,       // run.gravity (m/s^2; the loads variant of the node stage applies it)
    gravity_y: f32,
    gravity_ramp: f32,    // s: linear ramp of gravity from 0 (0: none)
    one: f32,             // 1.0, unknown to the compiler (node.wgsl's compensated sum)
    failure: u32,         // 1: elements may erode (element.wgsl's failure check); the eroded
                          // count and energy in the words after the plastic work's
    failure_at: u32,      // with failure: the erosion sums' first item in sample_src (after the plastic work's)
    _p2: u32,
}

// Run control, advanced on the GPU so that a step needs no readback.
struct Control {
    t_lo: u32,            // t_n in ticks (64-bit: lo, hi): exact sums, no float reassociation
    t_hi: u32,
    dt_prev: f32,         // dt^{n-1/2}
    dt_next: f32,         // dt^{n+1/2}
    dt_node: f32,         // dt_n of the velocity update
    dt_first: f32,
    dt_min: f32,          // smallest / largest step so far
    dt_max: f32,
    step: u32,
    flags: u32,           // FLAG_* of the current step
    state: u32,           // STATE_*
    rows: u32,            // history rows written so far
    next_sample: u32,
    next_snapshot: u32,
    fail_code: u32,
    fail_index: u32,
    fail_value: f32,
    dt_elem: u32,         // element that set the last stable step
    bad_element: atomic<u32>,
    bad_node: atomic<u32>,
    damp_c: f32,          // c = alpha dt_n / 2 of mass damping this step (0 without, and on step 0):
                          // the velocity update, boundaries and contact see the masses (1 + c) m
    eroded: atomic<u32>,  // elements eroded since the contact surfaces last followed (element.wgsl;
                          // contact_search.wgsl stops the step for the host: STATE_ERODED)
}

const FLAG_SAMPLE: u32 = 1u;
const FLAG_SNAPSHOT: u32 = 2u;
const FLAG_END: u32 = 4u;

const STATE_RUNNING: u32 = 0u;
const STATE_PAUSED: u32 = 1u;
const STATE_DONE: u32 = 2u;
const STATE_FAILED: u32 = 3u;

const NONE: u32 = 0xffffffffu;

// inf or NaN, by bit pattern (WGSL does not promise NaN semantics).
fn not_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) == 0x7f800000u;
}

// A contiguous range of sample_src summed on sample steps (a body's nodes, the elements, the
// constrained nodes), and where its workgroups' partial sums go.
struct Instance {
    start: u32,
    count: u32,
    groups: u32,
    first_group: u32,
    scale: f32,           // 1 / body mass for bodies (momentum -> velocity), else 1
    _p0: u32,
    _p1: u32,
    _p2: u32,
}

// 64-bit tick arithmetic on (lo, hi) pairs.
fn to_ticks(x: f32, per_second: f32) -> vec2<u32> {
    let y = max(x * per_second, 0.0);
    let hi = floor(y / 4294967296.0);
    let lo = min(y - hi * 4294967296.0, 4294967040.0);
    return vec2<u32>(u32(lo), u32(hi));
}

fn add64(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

fn ge64(a: vec2<u32>, b: vec2<u32>) -> bool {
    return a.y > b.y || (a.y == b.y && a.x >= b.x);
}
