// The diagonal-mass Lagrange correction (CPU reference: crate::contact solve, ContactSet::sweep
// and ::recheck): projected Gauss-Seidel sweeps over the colours of the last search (slots of one
// colour share no node, so a colour is updated in parallel with the result of a sequential sweep:
// deterministic; in one workgroup extrapolated between sweeps as on the CPU), until no gap
// changes by more than cc.p.tolerance or cc.p.max_sweeps; then the
// active-set update (free Lagrange slots re-checked at the corrected positions, more sweeps when
// any penetrates), ACTIVE_SET_ROUNDS rounds at most. Compiled after contact_narrow.wgsl.
//
// Two paths, chosen by size on the host: `solve_one`, every sweep in one workgroup (colours
// separated by barriers; the fastest for small contact sets), and `sweep_color` + `recheck`, one
// dispatch per colour and sweep over as many workgroups as the colour needs. With many active
// slots (cc.p.split) the one-workgroup path leaves its re-checks to `recheck_active`, one thread
// per active slot over many workgroups, dispatched between its rounds: the same constraints and
// arithmetic (the same bits on lavapipe; an H100 rounds the two kernels apart by 1e-9).

const ACTIVE_SET_ROUNDS: u32 = 4u;    // crate::contact::ACTIVE_SET_ROUNDS

var<workgroup> sh_m: array<f32, SG>;
var<workgroup> sh_w: u32;
var<workgroup> sh_nc: u32;
var<workgroup> sh_off: array<u32, 34>;   // colour offsets of the compacted slots (SERIAL + 2)
var<workgroup> sh_max: atomic<u32>;
var<workgroup> sh_split: u32;
var<workgroup> sh_nn: u32;         // nodes of the compacted constraints (ws[o_nlist..])
var<workgroup> sh_change: u32;     // f32 bits of the last sweep's largest change

// Whether any invocation's `x` is positive, as a workgroup-uniform value: a tree over sh_m with
// barriers, written by invocation 0 into a plain workgroup word. (Every exit of the solve loops
// is decided this way or by a plain word written by invocation 0, never by a uniform load of a
// workgroup atomic: with the old single kernel on lavapipe the invocations disagreed about such
// a load, left the loops at different barriers, and the step lost its contact impulses.)
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
    return ws[cc.p.o_loff + c];
}

fn list_end(c: u32) -> u32 {
    return ws[cc.p.o_loff + c + 1u];
}

// Colours of the one-workgroup solve: at most 32 by node masks, then one serial colour.
const SERIAL: u32 = 32u;

// Whether the one-workgroup solve colours in parallel rounds in a hashed order (host-set:
// crate::gpu::shader::Features::contact_parallel_colouring), or greedily in slot order.
const PARALLEL_COLOURING: bool = true;

// The colour a constraint takes: the first colour none of `used` (its coloured neighbours'
// colours, bit 31 standing for 31 and the serial colour) holds, the serial colour when all 32
// are taken.
fn first_free(used: u32) -> u32 {
    if (used == 0xffffffffu) {
        return SERIAL;
    }
    return firstTrailingBit(~used);
}

fn colour_bit(col: u32) -> u32 {
    return 1u << min(col, 31u);
}

// The order of the colouring: slot k2 is coloured before slot k when its hashed priority's high
// 20 bits are larger, or equal and k2 < k. (In workgroup memory a constraint's rank is those
// bits with 0xfff - j below them, j its index in slot order: the same order, one word.)
fn colour_rank(k: u32) -> u32 {
    return priority(k) & 0xfffff000u;
}

fn coloured_before(k2: u32, k: u32) -> bool {
    let a = colour_rank(k2);
    let b = colour_rank(k);
    return a > b || (a == b && k2 < k);
}

// The step's Lagrange constraints coloured by their own nodes (slave and segment ends) and
// gathered by colour into ws[o_act..] (sh_off: offsets; in slot order within a colour); their
// nodes listed in ws[o_nlist..] (sh_nn) in the order of their first appearance in slot order.
//
// The colouring is the greedy one in the order of `coloured_before` (each constraint the first
// colour its neighbours earlier in that order left free), computed in Jones-Plassmann rounds: a
// constraint is coloured in the round where every neighbour before it has been, so its colour
// depends only on theirs, never on thread order or on the round in which a thread saw them. The
// hashed order keeps the chains of constraints waiting on each other short (a few rounds);
// colouring greedily in slot order, as before 2026-11-28, had to run in one invocation (a fit of
// the NVIDIA H200 profiles of 2026-11-27 put about 0.5 us a step per constraint, most of the
// 10^5 and 10^6 strikers' solve, in work proportional to the constraints, which that loop was).
//
// On CPU adapters (PARALLEL_COLOURING false, `crate::gpu::contact::ContactOptions`) the greedy
// colouring in slot order, in invocation 0, stays: lavapipe runs a workgroup on one core, where
// the rounds cost more than the loop (the striker on lavapipe 5-11 % fewer steps a second, with
// 7-12 % more sweeps in the hashed order, 2026-11-28).
//
// The same on every run and at every workgroup size: up to CAP constraints by `compact_local`
// (in workgroup memory), more by `compact_global` (through storage, on the search's node
// adjacency), with the same result. A constraint that finds all 32 colours taken goes to the
// serial colour, which invocation 0 sweeps alone.
fn compact(l: u32) {
    // The Lagrange slots in slot order into ws[o_color..]: each invocation a contiguous chunk
    // of the active slots, offsets by a prefix over the invocations.
    let n = active_count();
    let chunk = (n + SG - 1u) / SG;
    let begin = min(l * chunk, n);
    let end = min(begin + chunk, n);
    var mine = 0u;
    for (var j = begin; j < end; j++) {
        if (cons[active_slot(j)].kind == KIND_LAGRANGE) {
            mine += 1u;
        }
    }
    var at = workgroup_prefix(l, mine);
    for (var j = begin; j < end; j++) {
        let k = active_slot(j);
        if (cons[k].kind == KIND_LAGRANGE) {
            ws[cc.p.o_color + at] = k;
            at += 1u;
        }
    }
    storageBarrier();
    let na = workgroupUniformLoad(&sh_total);
    var local = na <= CAP;
    if (local) {
        local = compact_local(l, na);
    }
    if (!local) {
        compact_global(l, na);
    }
    scatter_by_colour(l, na, local);
    if (!local) {
        // The slots' colouring state back to zero (`compact_global`).
        for (var j = l; j < na; j += SG) {
            ws[cc.p.o_list + ws[cc.p.o_color + j]] = 0u;
        }
    }
    storageBarrier();
    workgroupBarrier();
}

// Constraints `compact_local` holds in workgroup memory, 28 bytes each (host-set from the
// device's workgroup storage: crate::gpu::contact::local_constraints), and their distinct nodes
// at most NODE_CAP (3 CAP / 2; a two-pass interface has about one node per constraint).
const CAP: u32 = 1024u;
const CAP_SIZE: u32 = 1024u;    // CAP, at least 1 (the arrays' size)
const NODE_CAP: u32 = 3u * CAP / 2u;
// Per reference 3j + t of constraint j (slave, segment ends): its node (NONE for a wall's
// missing segment), then its node's key: the node's index in the node list ws[o_nlist..].
var<workgroup> sh_ref: array<u32, 3u * CAP_SIZE>;
// Per reference: the least reference to the same node; then per key the node's colour mask (at
// the key) and, in a colouring round, the largest rank of its constraints still uncoloured (at
// NODE_CAP + the key).
var<workgroup> sh_key: array<atomic<u32>, 3u * CAP_SIZE>;
// Per constraint: its rank (`local_rank`, above SERIAL) until coloured, then its colour.
var<workgroup> sh_cr: array<u32, CAP_SIZE>;

// The node of reference t (0 slave, 1 and 2 segment ends) of constraint slot k.
fn ref_node(k: u32, t: u32) -> u32 {
    if (t == 0u) {
        return slots[k].s;
    }
    if (t == 1u) {
        return cons[k].a;
    }
    return cons[k].b;
}

// Constraint j (`compact_local`) takes the first colour free in `used`, its keys' masks, and
// marks it there.
fn colour_local(j: u32, used: u32) {
    let col = first_free(used);
    for (var t = 0u; t < 3u; t++) {
        let key = sh_ref[3u * j + t];
        if (key != NONE) {
            atomicOr(&sh_key[key], colour_bit(col));
        }
    }
    sh_cr[j] = col;
}

// Constraint j's rank in workgroup memory (see `colour_rank`; j < CAP <= 2048, so at least
// 2048: above any colour).
fn local_rank(j: u32) -> u32 {
    return colour_rank(ws[cc.p.o_color + j]) | (0xfffu - j);
}

// `compact`'s colouring and node list for na <= CAP constraints; false, with nothing of it left
// behind, when they have more than NODE_CAP nodes (then `compact_global`). Each node's references
// are first tied together through ws[o_mask + i] (every reference writes its own index there;
// whichever write stays, all references of the node read the same one, and the least reference
// to the node, found by an integer atomicMin, does not depend on which); the nodes are listed by
// a scan over the references that are their node's first, and each reference takes its node's
// place in the list as its key (through ws[o_mask + i] again), so that the colouring reads and
// writes per node in workgroup memory by key: in each round every uncoloured constraint puts its
// rank on its keys by an integer atomicMax, and one that holds the largest on all of them takes
// the first colour free in their masks and marks it there (two such constraints share no node).
fn compact_local(l: u32, na: u32) -> bool {
    let nr = 3u * na;
    for (var r = l; r < nr; r += SG) {
        let i = ref_node(ws[cc.p.o_color + r / 3u], r % 3u);
        sh_ref[r] = i;
        atomicStore(&sh_key[r], NONE);
        if (i != NONE) {
            ws[cc.p.o_mask + i] = r;
        }
    }
    storageBarrier();
    workgroupBarrier();
    for (var r = l; r < nr; r += SG) {
        let i = sh_ref[r];
        if (i != NONE) {
            atomicMin(&sh_key[ws[cc.p.o_mask + i]], r);
        }
    }
    workgroupBarrier();
    // The nodes listed by their first reference: each invocation a contiguous chunk.
    let chunk = (nr + SG - 1u) / SG;
    let begin = min(l * chunk, nr);
    let end = min(begin + chunk, nr);
    var firsts = 0u;
    for (var r = begin; r < end; r++) {
        let i = sh_ref[r];
        if (i != NONE && atomicLoad(&sh_key[ws[cc.p.o_mask + i]]) == r) {
            firsts += 1u;
        }
    }
    var at = workgroup_prefix(l, firsts);
    for (var r = begin; r < end; r++) {
        let i = sh_ref[r];
        if (i != NONE && atomicLoad(&sh_key[ws[cc.p.o_mask + i]]) == r) {
            ws[cc.p.o_nlist + at] = i;
            at += 1u;
        }
    }
    let nn = workgroupUniformLoad(&sh_total);
    if (l == 0u) {
        sh_nn = nn;
    }
    storageBarrier();
    workgroupBarrier();
    // Each node's place in the list, through ws[o_mask + i], as its references' key.
    for (var d = l; d < nn; d += SG) {
        ws[cc.p.o_mask + ws[cc.p.o_nlist + d]] = select(d, 0u, nn > NODE_CAP);
    }
    storageBarrier();
    workgroupBarrier();
    if (nn > NODE_CAP) {
        // (ws[o_mask..] of the listed nodes back to zero, as `compact_global` takes it.)
        return false;
    }
    for (var r = l; r < nr; r += SG) {
        let i = sh_ref[r];
        if (i != NONE) {
            sh_ref[r] = ws[cc.p.o_mask + i];
        }
    }
    for (var d = l; d < nn; d += SG) {
        atomicStore(&sh_key[d], 0u);
    }
    workgroupBarrier();
    if (!PARALLEL_COLOURING) {
        // Greedy in slot order, in invocation 0.
        if (l == 0u) {
            for (var j = 0u; j < na; j++) {
                var used = 0u;
                for (var t = 0u; t < 3u; t++) {
                    let key = sh_ref[3u * j + t];
                    if (key != NONE) {
                        used |= atomicLoad(&sh_key[key]);
                    }
                }
                colour_local(j, used);
            }
        }
        workgroupBarrier();
        return true;
    }
    for (var j = l; j < na; j += SG) {
        sh_cr[j] = local_rank(j);
    }
    workgroupBarrier();
    loop {
        for (var j = l; j < na; j += SG) {
            if (sh_cr[j] > SERIAL) {
                for (var t = 0u; t < 3u; t++) {
                    let key = sh_ref[3u * j + t];
                    if (key != NONE) {
                        atomicStore(&sh_key[NODE_CAP + key], 0u);
                    }
                }
            }
        }
        workgroupBarrier();
        for (var j = l; j < na; j += SG) {
            let rank = sh_cr[j];
            if (rank > SERIAL) {
                for (var t = 0u; t < 3u; t++) {
                    let key = sh_ref[3u * j + t];
                    if (key != NONE) {
                        atomicMax(&sh_key[NODE_CAP + key], rank);
                    }
                }
            }
        }
        workgroupBarrier();
        var left = 0.0;
        for (var j = l; j < na; j += SG) {
            let rank = sh_cr[j];
            if (rank <= SERIAL) {
                continue;
            }
            var first = true;
            var used = 0u;
            for (var t = 0u; t < 3u; t++) {
                let key = sh_ref[3u * j + t];
                if (key != NONE) {
                    first = first && atomicLoad(&sh_key[NODE_CAP + key]) == rank;
                    used |= atomicLoad(&sh_key[key]);
                }
            }
            if (!first) {
                left = 1.0;
                continue;
            }
            colour_local(j, used);
        }
        if (!any_positive(l, left)) {
            break;
        }
    }
    return true;
}

// Whether the constraint of slot k touches node i.
fn touches(k: u32, i: u32) -> bool {
    return slots[k].s == i || cons[k].a == i || cons[k].b == i;
}

// `compact`'s colouring and node list for more than CAP constraints, through storage: the state
// of each slot in ws[o_list..] (zero on entry, cleared again by `compact`: 1 uncoloured, 2 + its
// colour once coloured), each constraint's neighbours read from the search's node adjacency
// (the slots whose slave or candidates touch the node, in slot order; those whose constraint
// touches it). Each round, an uncoloured constraint with no uncoloured neighbour before it takes
// the first colour its coloured neighbours left free (a neighbour coloured in the same round and
// read as uncoloured only delays it by a round). The same colours as `compact_local`.
fn compact_global(l: u32, na: u32) {
    if (!PARALLEL_COLOURING) {
        compact_global_serial(l, na);
        return;
    }
    for (var j = l; j < na; j += SG) {
        ws[cc.p.o_list + ws[cc.p.o_color + j]] = 1u;
    }
    storageBarrier();
    workgroupBarrier();
    let b = cc.p.cand_capacity;
    loop {
        var left = 0.0;
        for (var j = l; j < na; j += SG) {
            let k = ws[cc.p.o_color + j];
            if (ws[cc.p.o_list + k] != 1u) {
                continue;
            }
            var ready = true;
            var used = 0u;
            for (var t = 0u; t < 3u && ready; t++) {
                let i = ref_node(k, t);
                if (i == NONE) {
                    continue;
                }
                let end = ws[cc.p.o_noff + i + 1u];
                for (var q = ws[cc.p.o_noff + i]; q < end; q++) {
                    let k2 = grow[b + q];
                    if (k2 == k) {
                        continue;
                    }
                    let s2 = ws[cc.p.o_list + k2];
                    if (s2 == 0u || !touches(k2, i)) {
                        continue;
                    }
                    if (s2 == 1u) {
                        if (coloured_before(k2, k)) {
                            ready = false;
                            break;
                        }
                    } else {
                        used |= colour_bit(s2 - 2u);
                    }
                }
            }
            if (ready) {
                ws[cc.p.o_list + k] = 2u + first_free(used);
            } else {
                left = 1.0;
            }
        }
        storageBarrier();
        if (!any_positive(l, left)) {
            break;
        }
    }
    // The nodes by their first reference in slot order: reference t of constraint k is its
    // node's first when no constraint of an earlier slot and no earlier reference of k touch it.
    let nr = 3u * na;
    let chunk = (nr + SG - 1u) / SG;
    let begin = min(l * chunk, nr);
    let end = min(begin + chunk, nr);
    var firsts = 0u;
    for (var r = begin; r < end; r++) {
        if (first_reference(r)) {
            firsts += 1u;
        }
    }
    var at = workgroup_prefix(l, firsts);
    for (var r = begin; r < end; r++) {
        if (first_reference(r)) {
            ws[cc.p.o_nlist + at] = ref_node(ws[cc.p.o_color + r / 3u], r % 3u);
            at += 1u;
        }
    }
    if (l == 0u) {
        sh_nn = sh_total;
    }
}

fn mask_of(i: u32) -> u32 {
    if (i == NONE) {
        return 0u;
    }
    return ws[cc.p.o_mask + i];
}

// Marks node i with colour bit c; a node seen for the first time joins the list of the
// constraints' nodes (ws[o_nlist..], sh_nn of them).
fn mark_node(i: u32, c: u32) {
    if (i == NONE) {
        return;
    }
    if (ws[cc.p.o_mask + i] == 0u) {
        ws[cc.p.o_nlist + sh_nn] = i;
        sh_nn += 1u;
    }
    ws[cc.p.o_mask + i] |= colour_bit(c);
}

// `compact_global` greedy in slot order (!PARALLEL_COLOURING), in invocation 0, on the colour
// masks of the nodes in ws[o_mask..] (zero on entry, cleared again by `unpack`).
fn compact_global_serial(l: u32, na: u32) {
    if (l == 0u) {
        sh_nn = 0u;
        for (var j = 0u; j < na; j++) {
            let k = ws[cc.p.o_color + j];
            let c = cons[k];
            let s = slots[k].s;
            let col = first_free(mask_of(s) | mask_of(c.a) | mask_of(c.b));
            mark_node(s, col);
            mark_node(c.a, col);
            mark_node(c.b, col);
            ws[cc.p.o_list + k] = 2u + col;
        }
    }
    storageBarrier();
    workgroupBarrier();
}

// Whether reference r = 3j + t of the compacted constraints is its node's first (`compact_global`).
fn first_reference(r: u32) -> bool {
    let k = ws[cc.p.o_color + r / 3u];
    let t = r % 3u;
    let i = ref_node(k, t);
    if (i == NONE) {
        return false;
    }
    for (var t2 = 0u; t2 < t; t2++) {
        if (ref_node(k, t2) == i) {
            return false;
        }
    }
    let b = cc.p.cand_capacity;
    let end = ws[cc.p.o_noff + i + 1u];
    for (var q = ws[cc.p.o_noff + i]; q < end; q++) {
        let k2 = grow[b + q];
        if (k2 >= k) {
            break;
        }
        if (ws[cc.p.o_list + k2] != 0u && touches(k2, i)) {
            return false;
        }
    }
    return true;
}

// Constraint j's colour after `compact_local` (local) or `compact_global`.
fn colour_of(j: u32, local: bool) -> u32 {
    if (local) {
        return sh_cr[j];
    }
    return ws[cc.p.o_list + ws[cc.p.o_color + j]] - 2u;
}

// The compacted constraints gathered by colour into ws[o_act..], in slot order within a colour
// (sh_off: the colours' offsets, also kept in ws[o_loff..]): a prefix over the invocations'
// contiguous chunks per colour present.
fn scatter_by_colour(l: u32, na: u32, local: bool) {
    if (l == 0u) {
        atomicStore(&sh_max, 0u);
    }
    workgroupBarrier();
    let chunk = (na + SG - 1u) / SG;
    let begin = min(l * chunk, na);
    let end = min(begin + chunk, na);
    var top = 0u;
    for (var j = begin; j < end; j++) {
        top = max(top, colour_of(j, local) + 1u);
    }
    atomicMax(&sh_max, top);
    workgroupBarrier();
    if (l == 0u) {
        sh_w = atomicLoad(&sh_max);
    }
    let colours = workgroupUniformLoad(&sh_w);
    var base = 0u;
    for (var c = 0u; c <= SERIAL; c++) {
        if (l == 0u) {
            sh_off[c] = base;
        }
        if (c >= colours) {
            continue;
        }
        var mine = 0u;
        for (var j = begin; j < end; j++) {
            if (colour_of(j, local) == c) {
                mine += 1u;
            }
        }
        var at = base + workgroup_prefix(l, mine);
        for (var j = begin; j < end; j++) {
            if (colour_of(j, local) == c) {
                ws[cc.p.o_act + at] = ws[cc.p.o_color + j];
                at += 1u;
            }
        }
        base += workgroupUniformLoad(&sh_total);
    }
    if (l == 0u) {
        sh_off[SERIAL + 1u] = base;
        // The offsets kept in the per-colour path's list offsets, unused on this path, for the
        // test hook `GpuSolver::contact_last_colouring`.
        for (var c = 0u; c <= SERIAL + 1u; c++) {
            ws[cc.p.o_loff + c] = sh_off[c];
        }
    }
    storageBarrier();
    workgroupBarrier();
}

// The packed index of node i (`pack`): `dummy` (the zero record) for a wall's missing segment.
fn packed_index(i: u32, dummy: u32) -> u32 {
    if (i == NONE) {
        return dummy;
    }
    return ws[cc.p.o_mask + i];
}

// The compacted constraints packed for the sweeps, which then read and write nothing else
// (on lavapipe a sweep's update had cost about 280 ns, most of it in loads of Cons, Slot, c_ref
// and c_pv): each node of theirs (ws[o_nlist..], sh_nn) a record (dv, 1/m) at fws[f_node + j],
// and in place of its colour mask its packed index j; the record after the last stays zero and
// stands for a wall's missing segment. Each constraint q its nodes' packed indices
// (ws[o_cidx + 3q..]), its row (n, g0, w), (lambda, lt, xi, mu) at fws[f_row + 2q..] and, with
// friction, (wt, the free update's relative tangential velocity) at fws[f_frow + q]. `unpack`
// writes dv and the multipliers back.
fn pack(l: u32) {
    let nn = sh_nn;
    for (var j = l; j < nn; j += SG) {
        let i = ws[cc.p.o_nlist + j];
        fws[cc.p.f_node + j] = vec4<f32>(dv(i), c_ref[i].zw);
        ws[cc.p.o_mask + i] = j;
    }
    if (l == 0u) {
        fws[cc.p.f_node + nn] = vec4<f32>(0.0);
    }
    storageBarrier();
    let na = sh_off[SERIAL + 1u];
    for (var q = l; q < na; q += SG) {
        let k = ws[cc.p.o_act + q];
        let c = cons[k];
        let s = slots[k].s;
        let at = cc.p.o_cidx + 3u * q;
        ws[at] = ws[cc.p.o_mask + s];
        ws[at + 1u] = packed_index(c.a, nn);
        ws[at + 2u] = packed_index(c.b, nn);
        fws[cc.p.f_row + 2u * q] = vec4<f32>(c.n, c.g0, c.w);
        fws[cc.p.f_row + 2u * q + 1u] = vec4<f32>(c.lambda, c.lt, c.xi, c.mu);
        if (FRICTION && c.mu > 0.0) {
            fws[cc.p.f_frow + q] = vec4<f32>(c.wt, free_relative_along(c, s, tangent(c)), 0.0, 0.0);
        }
    }
    storageBarrier();
}

// The packed nodes' dv and the constraints' multipliers written back; the colour masks cleared.
fn unpack(l: u32) {
    let nn = sh_nn;
    for (var j = l; j < nn; j += SG) {
        let i = ws[cc.p.o_nlist + j];
        c_pv[3u * i + 2u] = vec4<f32>(c_pv[3u * i + 2u].xy, fws[cc.p.f_node + j].xy);
        ws[cc.p.o_mask + i] = 0u;
    }
    let na = sh_off[SERIAL + 1u];
    for (var q = l; q < na; q += SG) {
        let k = ws[cc.p.o_act + q];
        let r = fws[cc.p.f_row + 2u * q + 1u];
        cons[k].lambda = r.x;
        cons[k].lt = r.y;
    }
    storageBarrier();
}

// pgs_update on packed constraint q (`pack`; `dummy` the zero record): the same arithmetic.
fn pgs_packed(q: u32, dt: f32, inv_scale: f32, dummy: u32) -> f32 {
    let r0 = fws[cc.p.f_row + 2u * q];
    var r1 = fws[cc.p.f_row + 2u * q + 1u];
    let at = cc.p.o_cidx + 3u * q;
    let s = cc.p.f_node + ws[at];
    let a = cc.p.f_node + ws[at + 1u];
    let b = cc.p.f_node + ws[at + 2u];
    var ns = fws[s];
    var na = fws[a];
    var nb = fws[b];
    let n = r0.xy;
    let xi = r1.z;
    var rel = dot(ns.xy, n);
    rel -= (1.0 - xi) * dot(na.xy, n) + xi * dot(nb.xy, n);
    let g = r0.z + dt * rel;
    let lambda = max(r1.x - g / r0.w, 0.0);
    let d = lambda - r1.x;
    var moved = false;
    if (d != 0.0) {
        ns = vec4<f32>(ns.xy + d * inv_scale * n * ns.zw, ns.zw);
        na = vec4<f32>(na.xy + -(1.0 - xi) * d * inv_scale * n * na.zw, na.zw);
        nb = vec4<f32>(nb.xy + -xi * d * inv_scale * n * nb.zw, nb.zw);
        r1.x = lambda;
        moved = true;
    }
    var change = abs(d * r0.w);
    if (FRICTION && r1.w > 0.0) {
        // Coulomb, as in pgs_update.
        let fr = fws[cc.p.f_frow + q];
        let t = vec2<f32>(-n.y, n.x);
        var vt = dot(ns.xy, t);
        vt -= (1.0 - xi) * dot(na.xy, t) + xi * dot(nb.xy, t);
        vt = fr.y + vt;
        let bound = r1.w * lambda;
        let lt = clamp(r1.y - vt / fr.x, -bound, bound);
        let e = lt - r1.y;
        if (e != 0.0) {
            ns = vec4<f32>(ns.xy + e * inv_scale * t * ns.zw, ns.zw);
            na = vec4<f32>(na.xy + -(1.0 - xi) * e * inv_scale * t * na.zw, na.zw);
            nb = vec4<f32>(nb.xy + -xi * e * inv_scale * t * nb.zw, nb.zw);
            r1.y = lt;
            change = max(change, abs(e * fr.x * dt));
            moved = true;
        }
    }
    if (moved) {
        fws[s] = ns;
        if (a != cc.p.f_node + dummy) {
            fws[a] = na;
            fws[b] = nb;
        }
        fws[cc.p.f_row + 2u * q + 1u] = r1;
    }
    return change;
}

// The factor before the k-th sweep since the sweeps (re)started (crate::contact::extrapolation):
// 0 for the first two, then EXTRAPOLATION.
const EXTRAPOLATION: f32 = 0.9;       // crate::contact::EXTRAPOLATION
fn extrapolation(k: u32) -> f32 {
    if (k < 2u) {
        return 0.0;
    }
    return EXTRAPOLATION;
}

// ContactSet::extrapolate on the packed rows and nodes: each compacted constraint's (lambda, lt)
// and each of their nodes' dv moved on by beta times their change since the last call (no
// impulse: dv is linear in the multipliers, and a negative multiplier is projected by its own
// update in the sweep); the values reached are kept for the next call. beta = 0 only keeps them.
fn extrapolate(l: u32, beta: f32) {
    let na = sh_off[SERIAL + 1u];
    for (var q = l; q < na; q += SG) {
        let row = cc.p.f_row + 2u * q + 1u;
        let r = fws[row];
        let now = r.xy;
        let at = cc.p.o_lprev + 2u * q;
        if (beta != 0.0) {
            let last = vec2<f32>(bitcast<f32>(ws[at]), bitcast<f32>(ws[at + 1u]));
            fws[row] = vec4<f32>(now.x + beta * (now.x - last.x), now.y + beta * (now.y - last.y), r.zw);
        }
        ws[at] = bitcast<u32>(now.x);
        ws[at + 1u] = bitcast<u32>(now.y);
    }
    let nn = sh_nn;
    for (var j = l; j < nn; j += SG) {
        let r = fws[cc.p.f_node + j];
        let now = r.xy;
        let at = cc.p.o_dvp + 2u * j;
        if (beta != 0.0) {
            let last = vec2<f32>(bitcast<f32>(ws[at]), bitcast<f32>(ws[at + 1u]));
            fws[cc.p.f_node + j] = vec4<f32>(now + beta * (now - last), r.zw);
        }
        ws[at] = bitcast<u32>(now.x);
        ws[at + 1u] = bitcast<u32>(now.y);
    }
    storageBarrier();
}

// Sweeps in one workgroup over the compacted Lagrange slots, extrapolated between sweeps when
// cc.p.extrapolate (the count restarts when a sweep changes a gap more than the one before);
// returns the sweeps taken.
fn sweeps_one(l: u32, dt: f32, inv_scale: f32) -> u32 {
    compact(l);
    pack(l);
    let dummy = sh_nn;
    if (l == 0u) {
        var nc = 0u;
        for (var c = 0u; c < SERIAL; c++) {
            if (sh_off[c + 1u] > sh_off[c]) {
                nc = c + 1u;
            }
        }
        sh_nc = nc;
    }
    let nc = workgroupUniformLoad(&sh_nc);
    if (l == 0u) {
        sh_w = cc.p.extrapolate;
    }
    let extrapolating = workgroupUniformLoad(&sh_w) != 0u;
    var taken = 0u;
    var run = 0u;
    var last = 3.0e38;
    for (var sweep = 0u; sweep < cc.p.max_sweeps; sweep++) {
        // (At the start of a run, before sweep 0 and the first sweep after a restart, the values
        // kept would not be used: the next factor is 0 as well, and its call keeps them again.)
        if (extrapolating && sweep > 0u) {
            if (run > 0u) {
                extrapolate(l, extrapolation(run));
            }
            run += 1u;
        }
        if (l == 0u) {
            atomicStore(&sh_max, 0u);
        }
        var change = 0.0;
        for (var col = 0u; col < nc; col++) {
            let end = sh_off[col + 1u];
            for (var q = sh_off[col] + l; q < end; q += SG) {
                change = max(change, pgs_packed(q, dt, inv_scale, dummy));
            }
            storageBarrier();
        }
        if (l == 0u) {
            for (var q = sh_off[SERIAL]; q < sh_off[SERIAL + 1u]; q++) {
                change = max(change, pgs_packed(q, dt, inv_scale, dummy));
            }
        }
        taken += 1u;
        // The largest change by an integer atomic on its bits (non-negative floats order as
        // their bits): one barrier, the same result in any order.
        atomicMax(&sh_max, bitcast<u32>(change));
        workgroupBarrier();
        if (l == 0u) {
            sh_change = atomicLoad(&sh_max);
        }
        let largest = bitcast<f32>(workgroupUniformLoad(&sh_change));
        if (largest > last) {
            run = 0u;
        }
        last = largest;
        if (!(largest > cc.p.tolerance)) {
            break;
        }
    }
    if (l == 0u) {
        // The step's residual is its last solve's (a re-check's sweeps overwrite it); above the
        // tolerance when that solve stopped at max_sweeps (`report_end` counts the step).
        cc.residual = bitcast<u32>(last);
    }
    unpack(l);
    return taken;
}

// A free Lagrange slot re-checked at the corrected positions x_tr + dt dv (ContactSet::recheck);
// whether it now has a constraint.
fn recheck_slot(k: u32, dt: f32, dtn: f32, inv_scale: f32) -> bool {
    let sl = slots[k];
    if (cons[k].kind != KIND_NONE || (SPRINGS && (sl.info & SLOT_PENALTY) != 0u)) {
        return false;
    }
    corr_dt = dt;
    var c = narrow_slot(k, dt, dtn, inv_scale, 0.0);
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

// Whether round r of the split one-workgroup solve (and the re-check after it) runs: round 0
// when the step has Lagrange constraints, round r > 0 when re-check r - 1 added some.
fn split_round_runs(r: u32) -> bool {
    if (r == 0u) {
        return atomicLoad(&cc.lagrange) > 0u;
    }
    return atomicLoad(&cc.added[r - 1u]) > 0u;
}

// The one-workgroup solve. Split (cc.p.split), this dispatch is round r = round_index.x of it:
// round 0 the first sweeps, round r > 0 the sweeps after `recheck_active` r - 1 when that added
// constraints; unsplit, every round here, each re-check over the active slots in this workgroup.
@compute @workgroup_size(SG)
fn solve_one(@builtin(local_invocation_id) lid: vec3<u32>) {
    if (running_uniform(lid.x)) {
        solve_step(lid.x);
    }
}

// `solve_one`'s work, by invocation l of its workgroup.
fn solve_step(l: u32) {
    if (l == 0u) {
        sh_split = cc.p.split;
        // Unsplit, the one dispatch is round 0.
        sh_w = select(0u, 1u, split_round_runs(select(0u, round_index.x, cc.p.split != 0u)));
    }
    if (workgroupUniformLoad(&sh_w) == 0u) {
        return;
    }
    let split = workgroupUniformLoad(&sh_split) != 0u;
    let dt = ctrl.dt_next;
    let dtn = ctrl.dt_node;
    let inv_scale = inv_mass_scale();
    var taken = sweeps_one(l, dt, inv_scale);
    for (var round = 0u; round < ACTIVE_SET_ROUNDS && !split; round++) {
        var added = 0.0;
        let na = active_count();
        for (var j = l; j < na; j += SG) {
            if (recheck_slot(active_slot(j), dt, dtn, inv_scale)) {
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
        cc.sweeps += taken;
    }
}

// Re-check r = round_index.x of the split one-workgroup solve, one thread per active slot:
// runs when round r of `solve_one` swept (r = 0: the step has Lagrange constraints; r > 0:
// re-check r - 1 added some), and counts the constraints it adds for round r + 1.
@compute @workgroup_size(CG)
fn recheck_active(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (!contact_running()) {
        return;
    }
    let r = round_index.x;
    if (!split_round_runs(r)) {
        return;
    }
    let j = gid.x;
    if (j < active_count() && recheck_slot(active_slot(j), ctrl.dt_next, ctrl.dt_node, inv_mass_scale())) {
        atomicAdd(&cc.added[r], 1u);
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
    if (q % cc.p.max_sweeps == 0u) {
        return atomicLoad(&cc.added[q / cc.p.max_sweeps - 1u]) > 0u;
    }
    let prev = atomicLoad(&cc.change[q - 1u]);
    return prev != 0u && bitcast<f32>(prev) > cc.p.tolerance;
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
    let change = pgs_update(ws[cc.p.o_list + at], ctrl.dt_next, inv_mass_scale());
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
    let q0 = r * cc.p.max_sweeps;
    if (atomicLoad(&cc.change[q0]) == 0u) {
        return;
    }
    let k = gid.x;
    if (k < cc.p.n_slots && recheck_slot(k, ctrl.dt_next, ctrl.dt_node, inv_mass_scale())) {
        atomicAdd(&cc.added[r], 1u);
    }
}
