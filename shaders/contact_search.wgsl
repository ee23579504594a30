// Contact search on the device (CPU reference: crate::contact broad phase, parry's BVH): the
// positions of the step, whether a search is due (a contact node moved more than half the margin
// since the last one), and when it is, candidate (slot, segment) pairs from a hashed uniform grid
// over the swept segment boxes, then a colouring of the slots (slots of one colour share no node
// through any candidate) by Jones-Plassmann rounds with hashed priorities.
//
// Deterministic: counts by integer atomics, offsets by fixed-order scans; a slot's candidates are
// sorted by segment index, and the node adjacency lists by slot index, so no result depends on
// the order in which threads ran. The colouring depends only on neighbour sets and priorities.
// Every search kernel is dispatched indirectly: `plan` writes zero sizes when no search is due.
// A search whose candidates exceed the buffer stops the step (STATE_SEARCH_GROW) before anything
// changed; the host grows the buffer and resumes the step (never a silent truncation).

@group(0) @binding(13) var<storage, read_write> ws: array<atomic<u32>>;
@group(0) @binding(14) var<storage, read_write> grow: array<atomic<u32>>;
@group(1) @binding(0) var<storage, read_write> ind: array<u32>;

var<workgroup> sh_u: u32;

fn wsl(i: u32) -> u32 {
    return atomicLoad(&ws[i]);
}

fn wss(i: u32, v: u32) {
    atomicStore(&ws[i], v);
}

// 1. Positions u_n and u_n + dt v of the free update, v^{n-1/2}, dv = 0, and whether a search is due.
@compute @workgroup_size(CG)
fn prep(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (item_runs(gid.x, cc.p.n_local)) {
        prep_node(gid.x);
    }
}

// `prep` of local node i.
fn prep_node(i: u32) {
    let dt = ctrl.dt_next;
    let moving = (ctrl.flags & FLAG_END) == 0u;
    let s = nodes[c_nodes[i].x];
    let v = s.zw;
    var un = s.xy;
    var ut = s.xy;
    if (moving) {
        un = s.xy - dt * v;
    } else {
        ut = s.xy + dt * v;
    }
    c_pv[3u * i] = vec4<f32>(un, ut);
    var vo = c_pv[3u * i + 2u].xy;
    if (ctrl.step == 0u) {
        vo = 2.0 * vo - v;
    }
    c_pv[3u * i + 1u] = vec4<f32>(v, vo);
    c_pv[3u * i + 2u].z = 0.0;
    c_pv[3u * i + 2u].w = 0.0;
    let r = fws[cc.p.f_usearch + i].xy;
    let d0 = un - r;
    let d1 = ut - r;
    let h2 = 0.25 * cc.p.margin * cc.p.margin;
    if (cc.searches == 0u || dot(d0, d0) > h2 || dot(d1, d1) > h2) {
        atomicOr(&cc.due, 1u);
    }
}

fn groups(n: u32) -> u32 {
    return (n + CG - 1u) / CG;
}

fn set_ind(k: u32, n: u32) {
    ind[3u * k] = n;
    ind[3u * k + 1u] = 1u;
    ind[3u * k + 2u] = 1u;
}

// Indirect sizes of the search kernels: their sizes when a search is due, else zero; and of the
// kernels over the active slots. Per-step counters reset here.
@compute @workgroup_size(1)
fn plan() {
    if (!contact_running()) {
        return;
    }
    plan_step();
}

// `prep` and `plan` in one workgroup (the one-workgroup contact stage, contact_one.wgsl): one
// dispatch where they take two.
@compute @workgroup_size(SG)
fn prep_one(@builtin(local_invocation_id) lid: vec3<u32>) {
    let l = lid.x;
    if (!running_uniform(l)) {
        return;
    }
    let n = cc.p.n_local;
    for (var i = l; i < n; i += SG) {
        prep_node(i);
    }
    storageBarrier();
    if (l == 0u) {
        plan_step();
    }
}

// `plan`'s work. After an element eroded (eroding contact: a scene with failure and contact), the
// step stops here, before the contact stage changed anything, for the host to move the surfaces'
// masks to the edges the erosion exposed and resume the step with a search (STATE_ERODED).
fn plan_step() {
    if (atomicLoad(&ctrl.eroded) != 0u) {
        ctrl.state = STATE_ERODED;
        return;
    }
    let due = atomicExchange(&cc.due, 0u) != 0u;
    let f = select(0u, 1u, due);
    set_ind(0u, f * groups(max(max(cc.p.n_segs, cc.p.n_buckets), max(cc.p.n_local, cc.p.n_slots))));
    set_ind(1u, f * groups(cc.p.n_segs));
    set_ind(2u, f);
    set_ind(3u, f * groups(cc.p.n_segs));
    set_ind(4u, f * groups(cc.p.n_slots));
    set_ind(5u, f);
    set_ind(6u, f * groups(cc.p.n_slots));
    set_ind(7u, f * groups(cc.p.n_slots));
    set_ind(8u, f);
    set_ind(9u, f * groups(cc.p.n_slots));
    set_ind(10u, f * groups(cc.p.n_local));
    set_ind(11u, f * groups(cc.p.n_slots));
    set_ind(12u, f * groups(cc.p.n_slots));
    set_ind(13u, f * groups(cc.p.n_slots));
    // The kernels over the active slots: every slot's group when this step searches (they
    // return beyond the count the search finds), else the last search's count.
    if (due) {
        set_ind(ACTIVE_ENTRY, groups(cc.p.n_slots));
    } else {
        set_ind(ACTIVE_ENTRY, groups(wsl(cc.p.o_aoff + cc.p.n_slots)));
    }
    atomicStore(&cc.searching, f);
    if (due) {
        cc.searches += 1u;
        atomicStore(&cc.extent, 0u);
        atomicStore(&cc.n_colors, 0u);
    }
    atomicStore(&cc.lagrange, 0u);
    atomicStore(&cc.penetration, 0u);
    cc.sweeps = 0u;
    cc.residual = 0u;
    for (var q = 0u; q < MAX_SWEEP_SLOTS; q++) {
        atomicStore(&cc.change[q], 0u);
    }
    for (var r = 0u; r < 4u; r++) {
        atomicStore(&cc.added[r], 0u);
    }
}

fn node_x(i: u32) -> vec2<f32> {
    return c_ref[i].xy + pos(i).xy;
}

fn node_xt(i: u32) -> vec2<f32> {
    return c_ref[i].xy + pos(i).zw;
}

// Padding for f32 rounding on top of a box (as the CPU broad phase pads parry's f32 boxes).
fn pad(x: vec2<f32>) -> vec2<f32> {
    return 1e-6 * abs(x) + vec2<f32>(1e-30);
}

fn cell_size() -> f32 {
    return max(bitcast<f32>(atomicLoad(&cc.extent)), 1e-30);
}

fn cell_of(x: vec2<f32>, h: f32) -> vec2<i32> {
    return vec2<i32>(floor(x / h));
}

fn bucket(c: vec2<i32>) -> u32 {
    let u = bitcast<vec2<u32>>(c);
    return ((u.x * 73856093u) ^ (u.y * 19349663u)) & (cc.p.n_buckets - 1u);
}

// 2a. Swept boxes of the segments (u_n and the trial u_{n+1}) inflated by the margin, and the
// largest side (the cell size); clears the counts; keeps u at the search.
@compute @workgroup_size(CG)
fn boxes(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (contact_running()) {
        box_item(gid.x);
    }
}

// `boxes` of item i (segment, bucket, local node, slot and colour count i, those that exist).
fn box_item(i: u32) {
    if (i < cc.p.n_segs && segs[i].off == 0u) {
        let sg = segs[i];
        let lo = min(min(node_x(sg.a), node_x(sg.b)), min(node_xt(sg.a), node_xt(sg.b)));
        let hi = max(max(node_x(sg.a), node_x(sg.b)), max(node_xt(sg.a), node_xt(sg.b)));
        let l = lo - cc.p.margin - pad(lo);
        let h = hi + cc.p.margin + pad(hi);
        fws[cc.p.f_box + i] = vec4<f32>(l, h);
        let e = max(h.x - l.x, h.y - l.y);
        atomicMax(&cc.extent, bitcast<u32>(e));
    }
    if (i < cc.p.n_buckets) {
        wss(cc.p.o_bcount + i, 0u);
    }
    if (i < cc.p.n_local) {
        wss(cc.p.o_ncount + i, 0u);
        fws[cc.p.f_usearch + i] = vec4<f32>(pos(i).zw, 0.0, 0.0);
    }
    if (i < cc.p.n_slots) {
        wss(cc.p.o_color + i, NONE);
    }
    if (i <= MAX_COLORS) {
        wss(cc.p.o_lcount + i, 0u);
    }
}

// The distinct buckets of a segment's cells (at most 2 x 2: the cell is the largest box side).
fn seg_buckets(j: u32, out: ptr<function, array<u32, 4>>) -> u32 {
    let b = fws[cc.p.f_box + j];
    let h = cell_size();
    let c0 = cell_of(b.xy, h);
    let c1 = cell_of(b.zw, h);
    var n = 0u;
    for (var y = c0.y; y <= c1.y && y <= c0.y + 1; y++) {
        for (var x = c0.x; x <= c1.x && x <= c0.x + 1; x++) {
            let k = bucket(vec2<i32>(x, y));
            var seen = false;
            for (var m = 0u; m < n; m++) {
                seen = seen || (*out)[m] == k;
            }
            if (!seen) {
                (*out)[n] = k;
                n++;
            }
        }
    }
    return n;
}

// Segment j in each of its buckets: counted (fill false), or among the bucket's entries (fill
// true; in any order: the slots sort their candidates).
fn bucket_segment(j: u32, fill: bool) {
    var bs: array<u32, 4>;
    let n = seg_buckets(j, &bs);
    for (var m = 0u; m < n; m++) {
        if (fill) {
            let at = atomicAdd(&ws[cc.p.o_bcur + bs[m]], 1u);
            wss(cc.p.o_bent + at, j);
        } else {
            atomicAdd(&ws[cc.p.o_bcount + bs[m]], 1u);
        }
    }
}

// 2b. Segments per bucket.
@compute @workgroup_size(CG)
fn seg_count(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (item_runs(gid.x, cc.p.n_segs) && segs[gid.x].off == 0u) {
        bucket_segment(gid.x, false);
    }
}

// Exclusive scan of n words at `src` into `dst` (n + 1 words) and a copy at `cur` (if not NONE),
// in one workgroup, in a fixed order; returns the total.
fn scan(src: u32, dst: u32, cur: u32, n: u32, l: u32) -> u32 {
    let per = (n + SG - 1u) / SG;
    let begin = min(l * per, n);
    let end = min(begin + per, n);
    var sum = 0u;
    for (var i = begin; i < end; i++) {
        sum += wsl(src + i);
    }
    var acc = workgroup_prefix(l, sum);
    for (var i = begin; i < end; i++) {
        let x = wsl(src + i);
        wss(dst + i, acc);
        if (cur != NONE) {
            wss(cur + i, acc);
        }
        acc += x;
    }
    let total = workgroupUniformLoad(&sh_total);
    if (l == 0u) {
        wss(dst + n, total);
    }
    return total;
}

@compute @workgroup_size(SG)
fn scan_buckets(@builtin(local_invocation_id) lid: vec3<u32>) {
    if (!running_uniform(lid.x)) {
        return;
    }
    scan(cc.p.o_bcount, cc.p.o_boff, cc.p.o_bcur, cc.p.n_buckets, lid.x);
}

// 2c. Bucket entries.
@compute @workgroup_size(CG)
fn seg_fill(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (item_runs(gid.x, cc.p.n_segs) && segs[gid.x].off == 0u) {
        bucket_segment(gid.x, true);
    }
}

// The search in one workgroup (small contact sets; src/gpu/contact/search.rs `search_one_path`):
// one dispatch, empty on the steps that do not search, where the per-item kernels take eleven
// (each a barrier and an indirect dispatch even when empty). The SG invocations take each
// stage's items in turn, the per-item kernels' functions in their order, with a storage barrier
// between stages and the scans as in their kernels: the same counts, offsets and sorted lists,
// so the same bits. Not for the per-colour solve (its colouring stays per item).
@compute @workgroup_size(SG)
fn search_one(@builtin(local_invocation_id) lid: vec3<u32>) {
    let l = lid.x;
    if (!running_uniform(l)) {
        return;
    }
    if (l == 0u) {
        sh_u = atomicLoad(&cc.searching);
    }
    if (workgroupUniformLoad(&sh_u) == 0u) {
        return;
    }
    let p = cc.p;
    let nb = groups(max(max(p.n_segs, p.n_buckets), max(p.n_local, p.n_slots))) * CG;
    for (var i = l; i < nb; i += SG) {
        box_item(i);
    }
    storageBarrier();
    for (var j = l; j < p.n_segs; j += SG) {
        if (segs[j].off == 0u) {
            bucket_segment(j, false);
        }
    }
    storageBarrier();
    scan(p.o_bcount, p.o_boff, p.o_bcur, p.n_buckets, l);
    storageBarrier();
    for (var j = l; j < p.n_segs; j += SG) {
        if (segs[j].off == 0u) {
            bucket_segment(j, true);
        }
    }
    storageBarrier();
    for (var k = l; k < p.n_slots; k += SG) {
        slot_count_item(k);
    }
    storageBarrier();
    scan_slots_step(l);
    storageBarrier();
    // A search that does not fit stopped the step (STATE_SEARCH_GROW) for the host to grow the
    // buffers: nothing more (the per-item kernels find the state and return).
    if (!running_uniform(l)) {
        return;
    }
    for (var k = l; k < p.n_slots; k += SG) {
        slot_fill_item(k);
    }
    storageBarrier();
    for (var k = l; k < p.n_slots; k += SG) {
        visit_touched(k, false);
    }
    storageBarrier();
    scan_nodes_step(l);
    storageBarrier();
    for (var k = l; k < p.n_slots; k += SG) {
        visit_touched(k, true);
    }
    storageBarrier();
    for (var i = l; i < p.n_local; i += SG) {
        adj_sort_item(i);
    }
}

// Whether master segment j may be paired with slot k (crate::contact::rules::admissible, with
// the pass): the slot's pass; not a segment of the slave's own; another body, or self-contact
// without the neighbouring segments and without the segments the slave lies behind in the
// reference configuration (the far side of the same body).
fn admissible(sl: Slot, sg: Segment) -> bool {
    if (sg.pass_id != sl.pass_id || sg.a == sl.s || sg.b == sl.s) {
        return false;
    }
    if (sg.body != sl.body) {
        return true;
    }
    if ((sl.info & SLOT_SELF) == 0u) {
        return false;
    }
    if (sg.a == sl.np || sg.a == sl.nn || sg.b == sl.np || sg.b == sl.nn) {
        return false;
    }
    let xa = c_ref[sg.a].xy;
    let t = c_ref[sg.b].xy - xa;
    let d = c_ref[sl.s].xy - xa;
    let l2 = dot(t, t);
    if (!(l2 > 0.0)) {
        return false;
    }
    let xi = dot(d, t) / l2;
    let gap = dot(d, vec2<f32>(t.y, -t.x));
    return !(xi >= 0.0 && xi <= 1.0 && gap < 0.0);
}

// Visits slot k's candidates: mode 0 counts them, mode 1 writes them from `at` and sorts them.
fn visit(k: u32, mode: u32, at: u32) -> u32 {
    let sl = slots[k];
    if ((sl.info & (SLOT_WALL | SLOT_OFF)) != 0u) {
        return 0u;
    }
    let a = node_x(sl.s);
    let b = node_xt(sl.s);
    let lo = min(a, b) - pad(min(a, b));
    let hi = max(a, b) + pad(max(a, b));
    let h = cell_size();
    let c0 = cell_of(lo, h);
    let c1 = cell_of(hi, h);
    var n = 0u;
    for (var y = c0.y; y <= c1.y; y++) {
        for (var x = c0.x; x <= c1.x; x++) {
            let bk = bucket(vec2<i32>(x, y));
            let end = wsl(cc.p.o_boff + bk + 1u);
            for (var e = wsl(cc.p.o_boff + bk); e < end; e++) {
                let j = wsl(cc.p.o_bent + e);
                let bx = fws[cc.p.f_box + j];
                // Overlap, counted once: at the lowest cell common to both boxes.
                if (any(bx.xy > hi) || any(bx.zw < lo)) {
                    continue;
                }
                let s0 = cell_of(bx.xy, h);
                let first = max(c0, s0);
                if (first.x != x || first.y != y) {
                    continue;
                }
                if (!admissible(sl, segs[j])) {
                    continue;
                }
                if (mode == 1u) {
                    // Insertion in ascending segment order.
                    var p = n;
                    while (p > 0u && atomicLoad(&grow[at + p - 1u]) > j) {
                        atomicStore(&grow[at + p], atomicLoad(&grow[at + p - 1u]));
                        p--;
                    }
                    atomicStore(&grow[at + p], j);
                }
                n++;
            }
        }
    }
    return n;
}

// Whether wall slot `sl` may touch its wall before the next search: its node within the margin
// of the wall at u of this search. Until the next one the node moves less than half the margin,
// so a node farther away stays at least half the margin off the wall (the same bound as the
// segments' inflated boxes). An augmented Lagrangian slot, which may carry a multiplier beyond
// the contact, is always active; so is every slot without a margin.
fn wall_near(sl: Slot) -> bool {
    if (sl.ar > 0.0 || !(cc.p.margin > 0.0)) {
        return true;
    }
    let x = c_ref[sl.s].xy - sl.point;
    let g = min(dot(x + pos(sl.s).xy, sl.normal), dot(x + pos(sl.s).zw, sl.normal));
    return g < cc.p.margin;
}

// 2d. Candidates per slot, and whether the slot is active until the next search (see
// ContactParams.o_aflag); an inactive slot's constraint is cleared (it can have none).
@compute @workgroup_size(CG)
fn slot_count(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (item_runs(gid.x, cc.p.n_slots)) {
        slot_count_item(gid.x);
    }
}

// `slot_count` of slot k.
fn slot_count_item(k: u32) {
    let n = visit(k, 0u, 0u);
    wss(cc.p.o_ccount + k, n);
    let sl = slots[k];
    var on = n > 0u;
    if ((sl.info & SLOT_WALL) != 0u) {
        on = wall_near(sl) && (sl.info & SLOT_OFF) == 0u;
    }
    wss(cc.p.o_aflag + k, select(0u, 1u, on));
    if (!on) {
        var c: Cons;
        c.kind = KIND_NONE;
        c.a = NONE;
        c.b = NONE;
        cons[k] = c;
    }
}

// 2e. Candidate offsets and the active slots' offsets; a search that does not fit stops the step for the host to grow the buffer.
@compute @workgroup_size(SG)
fn scan_slots(@builtin(local_invocation_id) lid: vec3<u32>) {
    if (running_uniform(lid.x)) {
        scan_slots_step(lid.x);
    }
}

// `scan_slots` on lane l (every lane of the workgroup, in uniform control flow).
fn scan_slots_step(l: u32) {
    let total = scan(cc.p.o_ccount, cc.p.o_coff, NONE, cc.p.n_slots, l);
    scan(cc.p.o_aflag, cc.p.o_aoff, NONE, cc.p.n_slots, l);
    if (l == 0u) {
        atomicStore(&cc.n_cand, total);
        // The node adjacency: each slot's slave and its candidates' nodes.
        if (total > cc.p.cand_capacity || cc.p.n_slots + 2u * total > cc.p.adj_capacity) {
            cc.need_cand = total;
            atomicOr(&cc.grow, GROW_CANDIDATES);
            ctrl.state = STATE_SEARCH_GROW;
        }
    }
}

// 2f. The candidates, sorted per slot; the list of active slots.
@compute @workgroup_size(CG)
fn slot_fill(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (item_runs(gid.x, cc.p.n_slots)) {
        slot_fill_item(gid.x);
    }
}

// `slot_fill` of slot k.
fn slot_fill_item(k: u32) {
    visit(k, 1u, wsl(cc.p.o_coff + k));
    if (wsl(cc.p.o_aflag + k) != 0u) {
        wss(cc.p.o_alist + wsl(cc.p.o_aoff + k), k);
    }
}

// The nodes a slot can touch: its slave, then its candidates' nodes (a node may repeat).
fn touched(k: u32, m: u32) -> u32 {
    if (m == 0u) {
        return slots[k].s;
    }
    let j = atomicLoad(&grow[wsl(cc.p.o_coff + k) + (m - 1u) / 2u]);
    let sg = segs[j];
    return select(sg.b, sg.a, (m & 1u) == 1u);
}

fn n_touched(k: u32) -> u32 {
    return 1u + 2u * (wsl(cc.p.o_coff + k + 1u) - wsl(cc.p.o_coff + k));
}

// Whether the m-th touched node of slot k already appeared before it.
fn repeated(k: u32, m: u32, i: u32) -> bool {
    for (var q = 0u; q < m; q++) {
        if (touched(k, q) == i) {
            return true;
        }
    }
    return false;
}

// The distinct nodes slot k touches: counted (fill false), or given slot k in their adjacency
// lists (fill true).
fn visit_touched(k: u32, fill: bool) {
    let nt = n_touched(k);
    for (var m = 0u; m < nt; m++) {
        let i = touched(k, m);
        if (repeated(k, m, i)) {
            continue;
        }
        if (fill) {
            let at = atomicAdd(&ws[cc.p.o_ncur + i], 1u);
            atomicStore(&grow[cc.p.cand_capacity + at], k);
        } else {
            atomicAdd(&ws[cc.p.o_ncount + i], 1u);
        }
    }
}

// 3a. Slots per node.
@compute @workgroup_size(CG)
fn adj_count(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (item_runs(gid.x, cc.p.n_slots)) {
        visit_touched(gid.x, false);
    }
}

@compute @workgroup_size(SG)
fn scan_nodes(@builtin(local_invocation_id) lid: vec3<u32>) {
    if (running_uniform(lid.x)) {
        scan_nodes_step(lid.x);
    }
}

// `scan_nodes` on lane l (every lane of the workgroup, in uniform control flow).
fn scan_nodes_step(l: u32) {
    let total = scan(cc.p.o_ncount, cc.p.o_noff, cc.p.o_ncur, cc.p.n_local, l);
    if (l == 0u) {
        cc.n_adj = total;
    }
}

// 3b. Node adjacency entries (sorted per node next).
@compute @workgroup_size(CG)
fn adj_fill(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (item_runs(gid.x, cc.p.n_slots)) {
        visit_touched(gid.x, true);
    }
}

@compute @workgroup_size(CG)
fn adj_sort(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (item_runs(gid.x, cc.p.n_local)) {
        adj_sort_item(gid.x);
    }
}

// `adj_sort` of local node i.
fn adj_sort_item(i: u32) {
    let b = cc.p.cand_capacity + wsl(cc.p.o_noff + i);
    let n = wsl(cc.p.o_noff + i + 1u) - wsl(cc.p.o_noff + i);
    for (var p = 1u; p < n; p++) {
        let x = atomicLoad(&grow[b + p]);
        var q = p;
        while (q > 0u && atomicLoad(&grow[b + q - 1u]) > x) {
            atomicStore(&grow[b + q], atomicLoad(&grow[b + q - 1u]));
            q--;
        }
        atomicStore(&grow[b + q], x);
    }
}

fn outranks(j: u32, k: u32) -> bool {
    let pj = priority(j);
    let pk = priority(k);
    return pj > pk || (pj == pk && j > k);
}

// 3c. Colouring round r (Jones-Plassmann): an uncoloured slot that outranks every neighbour still
// uncoloured at the start of the round takes colour r. A neighbour coloured in this round reads
// as r, i.e. still uncoloured at the start: the outcome does not depend on thread order.
fn jp_round(k: u32, r: u32) {
    if (wsl(cc.p.o_color + k) != NONE) {
        return;
    }
    let nt = n_touched(k);
    for (var m = 0u; m < nt; m++) {
        let i = touched(k, m);
        let b = cc.p.cand_capacity + wsl(cc.p.o_noff + i);
        let n = wsl(cc.p.o_noff + i + 1u) - wsl(cc.p.o_noff + i);
        for (var q = 0u; q < n; q++) {
            let j = atomicLoad(&grow[b + q]);
            if (j != k && wsl(cc.p.o_color + j) >= r && outranks(j, k)) {
                return;
            }
        }
    }
    wss(cc.p.o_color + k, r);
    atomicMax(&cc.n_colors, r + 1u);
}

// One round per dispatch; the round's index is the dynamic offset of `round_index`.
@compute @workgroup_size(CG)
fn color_round(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    if (!item_runs(k, cc.p.n_slots)) {
        return;
    }
    jp_round(k, round_index.x);
}

// 3d. Slots per colour; a slot left uncoloured after the recorded rounds stops the step.
@compute @workgroup_size(CG)
fn list_count(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    if (!item_runs(k, cc.p.n_slots)) {
        return;
    }
    let c = wsl(cc.p.o_color + k);
    if (c == NONE) {
        atomicOr(&cc.grow, GROW_ROUNDS);
    } else {
        atomicAdd(&ws[cc.p.o_lcount + c], 1u);
    }
}

// Colour offsets and the per-colour dispatch sizes (indirect entries 14 + c); a direct dispatch
// (it writes the indirect sizes), idle when no search ran this step.
@compute @workgroup_size(SG)
fn scan_lists(@builtin(local_invocation_id) lid: vec3<u32>) {
    let l = lid.x;
    if (l == 0u) {
        sh_u = select(0u, 1u, contact_running() && atomicLoad(&cc.searching) != 0u);
    }
    if (workgroupUniformLoad(&sh_u) == 0u) {
        return;
    }
    scan(cc.p.o_lcount, cc.p.o_loff, cc.p.o_lcur, MAX_COLORS, l);
    if (l == 0u) {
        let nc = atomicLoad(&cc.n_colors);
        if (atomicLoad(&cc.grow) != 0u || (cc.p.multi != 0u && nc > cc.p.colors_recorded)) {
            if (cc.p.multi != 0u && nc > cc.p.colors_recorded) {
                atomicOr(&cc.grow, GROW_COLORS);
            }
            ctrl.state = STATE_SEARCH_GROW;
        }
        for (var c = 0u; c < MAX_COLORS; c++) {
            set_ind(14u + c, groups(wsl(cc.p.o_lcount + c)));
        }
    }
}

@compute @workgroup_size(CG)
fn list_fill(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = gid.x;
    if (!item_runs(k, cc.p.n_slots)) {
        return;
    }
    let c = wsl(cc.p.o_color + k);
    let at = atomicAdd(&ws[cc.p.o_lcur + c], 1u);
    wss(cc.p.o_list + at, k);
}
