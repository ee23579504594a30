// The one-workgroup solve's compaction of the step's Lagrange constraints and their colouring
// (`compact`; CPU reference: crate::gpu::contact::colouring), with the node list the sweeps and
// the extrapolation run on. Compiled between contact_narrow.wgsl and contact_solve.wgsl, whose
// workgroup words (sh_off, sh_nn, sh_w, sh_max) and `any_positive` it uses.

// Colours of the one-workgroup solve: at most 32 by node masks, then one serial colour.
const SERIAL: u32 = 32u;
// The "colour" of a paired constraint's partner: listed after the serial colour, swept with its
// leader (`pair_constraints`), never on its own.
const PARTNER: u32 = SERIAL + 1u;
// Pair codes per slot (ws[o_pair..], `pair_constraints`): the leader (the lower slot) or the
// partner of a pair, with the other's index in the compacted list ws[o_color..]; 0 unpaired.
const PAIR_LEADER: u32 = 0x80000000u;
const PAIR_PARTNER: u32 = 0x40000000u;
const PAIR_INDEX: u32 = 0x3fffffffu;

// Whether the constraint of slot k can be solved in a 2 x 2 block (ContactSet::pair_blocks):
// Lagrange, frictionless, against a segment.
fn pairable(k: u32) -> bool {
    let c = cons[k];
    return c.kind == KIND_LAGRANGE && c.a != NONE && c.w > 0.0 && !(c.mu > 0.0);
}

// The share of an impulse on node t of a constraint (0 its slave, 1 and 2 its segment's ends) at
// the segment coordinate xi (used by the pairing and by `block_packed`).
fn node_share(t: u32, xi: f32) -> f32 {
    if (t == 0u) {
        return 1.0;
    }
    if (t == 1u) {
        return -(1.0 - xi);
    }
    return -xi;
}

// How closely the constraints of slots k and k2 couple (ContactSet::pair_blocks' score): the
// change of one's gap per unit impulse of the other over the square root of their own (up to
// the factor dt / the mass scale, the same for every pair).
fn pair_score(k: u32, k2: u32) -> f32 {
    let c = cons[k];
    let d = cons[k2];
    var w = 0.0;
    for (var t = 0u; t < 3u; t++) {
        let i = ref_node(k, t);
        for (var u = 0u; u < 3u; u++) {
            if (ref_node(k2, u) == i) {
                let im = c_ref[i].zw;
                w += node_share(t, c.xi) * node_share(u, d.xi) * (c.n.x * d.n.x * im.x + c.n.y * d.n.y * im.y);
            }
        }
    }
    return abs(w) / sqrt(c.w * d.w);
}

// The constraint of slot k's best partner for a 2 x 2 block (NONE: none): among the pairable
// constraints of its interface whose slave is an end of its segment and whose segment has its
// slave as an end (the same contact met from both passes), the one that couples most closely,
// the lower slot on a tie. Found through the search's node adjacency of its segment's ends.
fn best_partner(k: u32) -> u32 {
    if (!pairable(k)) {
        return NONE;
    }
    let c = cons[k];
    let s = slots[k].s;
    let iface = slots[k].info & 0xffffu;
    let b = cc.p.cand_capacity;
    var best = NONE;
    var score = -1.0;
    for (var e = 1u; e < 3u; e++) {
        let m = ref_node(k, e);
        let end = ws[cc.p.o_noff + m + 1u];
        for (var q = ws[cc.p.o_noff + m]; q < end; q++) {
            let k2 = grow[b + q];
            if (k2 == k || slots[k2].s != m || (slots[k2].info & 0xffffu) != iface) {
                continue;
            }
            if (!pairable(k2) || (cons[k2].a != s && cons[k2].b != s)) {
                continue;
            }
            let x = pair_score(k, k2);
            if (x > score || (x == score && k2 < best)) {
                best = k2;
                score = x;
            }
        }
    }
    return best;
}

// The index of slot k in the compacted list ws[o_color..] of na slots (in slot order).
fn compacted_index(k: u32, na: u32) -> u32 {
    var lo = 0u;
    var hi = na;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (ws[cc.p.o_color + mid] < k) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// The 2 x 2 blocks of the sweeps (with PAIR_BLOCKS; ContactSet::pair_blocks): two constraints
// each other's best partner (`best_partner`) are a pair, its lower slot the leader, which is
// coloured with both constraints' nodes and sweeps both, its partner listed after the serial
// colour (PARTNER). Each compacted slot's pair code into ws[o_pair..] (0 when unpaired). Mutual
// best partners, where the CPU reference pairs greedily by score: the same pairs on every run,
// in any thread order, from neighbours alone.
fn pair_constraints(l: u32, na: u32) {
    if (!PAIR_BLOCKS) {
        return;
    }
    for (var j = l; j < na; j += SG) {
        let k = ws[cc.p.o_color + j];
        ws[cc.p.o_best + k] = best_partner(k);
    }
    storageBarrier();
    workgroupBarrier();
    for (var j = l; j < na; j += SG) {
        let k = ws[cc.p.o_color + j];
        var code = 0u;
        let b = ws[cc.p.o_best + k];
        if (b != NONE && ws[cc.p.o_best + b] == k) {
            code = select(PAIR_PARTNER, PAIR_LEADER, k < b) | compacted_index(b, na);
        }
        ws[cc.p.o_pair + k] = code;
    }
    storageBarrier();
    workgroupBarrier();
}

// The pair code of the constraint of slot k (0, unpaired, without PAIR_BLOCKS).
fn slot_code(k: u32) -> u32 {
    if (!PAIR_BLOCKS) {
        return 0u;
    }
    return ws[cc.p.o_pair + k];
}

// The pair code of compacted constraint j.
fn pair_code(j: u32) -> u32 {
    if (!PAIR_BLOCKS) {
        return 0u;
    }
    return slot_code(ws[cc.p.o_color + j]);
}

// The slot of the other constraint of pair code `code` (a leader's or partner's).
fn paired_slot(code: u32) -> u32 {
    return ws[cc.p.o_color + (code & PAIR_INDEX)];
}

// Reference t (0 to 5) of the colouring unit of compacted constraint j with pair code `code`:
// its own three (t < 3), then a leader's partner's (NONE when unpaired), in workgroup memory.
fn unit_key(j: u32, t: u32, code: u32) -> u32 {
    if (t < 3u) {
        return sh_ref[3u * j + t];
    }
    if ((code & PAIR_LEADER) == 0u) {
        return NONE;
    }
    return sh_ref[3u * (code & PAIR_INDEX) + t - 3u];
}

// Whether the one-workgroup solve colours in parallel rounds in a hashed order (host-set:
// crate::gpu::shader::Features::contact_parallel_colouring), or greedily in slot order.
const PARALLEL_COLOURING: bool = true;

// Whether the one-workgroup solve pairs node pairs met from both passes into 2 x 2 blocks
// (host-set: crate::gpu::shader::Features::contact_pair_blocks; GPUs); without, none of the
// pairing is compiled and a colouring unit is its constraint's three references.
const PAIR_BLOCKS: bool = true;

// References of a colouring unit: a constraint's three, and a leader's partner's three.
fn unit_refs() -> u32 {
    return select(3u, 6u, PAIR_BLOCKS);
}

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
    pair_constraints(l, na);
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

// Constraint j (`compact_local`, pair code `code`) takes the first colour free in `used`, its
// unit's keys' masks, and marks it there.
fn colour_local(j: u32, used: u32, code: u32) {
    let col = first_free(used);
    for (var t = 0u; t < unit_refs(); t++) {
        let key = unit_key(j, t, code);
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
                let code = pair_code(j);
                if ((code & PAIR_PARTNER) != 0u) {
                    sh_cr[j] = PARTNER;
                    continue;
                }
                var used = 0u;
                for (var t = 0u; t < unit_refs(); t++) {
                    let key = unit_key(j, t, code);
                    if (key != NONE) {
                        used |= atomicLoad(&sh_key[key]);
                    }
                }
                colour_local(j, used, code);
            }
        }
        workgroupBarrier();
        return true;
    }
    // (A partner's sh_cr is PARTNER from the start: neither a rank nor a colour of the sweeps.)
    for (var j = l; j < na; j += SG) {
        sh_cr[j] = select(local_rank(j), PARTNER, (pair_code(j) & PAIR_PARTNER) != 0u);
    }
    workgroupBarrier();
    loop {
        for (var j = l; j < na; j += SG) {
            if (sh_cr[j] > PARTNER) {
                let code = pair_code(j);
                for (var t = 0u; t < unit_refs(); t++) {
                    let key = unit_key(j, t, code);
                    if (key != NONE) {
                        atomicStore(&sh_key[NODE_CAP + key], 0u);
                    }
                }
            }
        }
        workgroupBarrier();
        for (var j = l; j < na; j += SG) {
            let rank = sh_cr[j];
            if (rank > PARTNER) {
                let code = pair_code(j);
                for (var t = 0u; t < unit_refs(); t++) {
                    let key = unit_key(j, t, code);
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
            if (rank <= PARTNER) {
                continue;
            }
            let code = pair_code(j);
            var first = true;
            var used = 0u;
            for (var t = 0u; t < unit_refs(); t++) {
                let key = unit_key(j, t, code);
                if (key != NONE) {
                    first = first && atomicLoad(&sh_key[NODE_CAP + key]) == rank;
                    used |= atomicLoad(&sh_key[key]);
                }
            }
            if (!first) {
                left = 1.0;
                continue;
            }
            colour_local(j, used, code);
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
            let code = pair_code(j);
            if (ws[cc.p.o_list + k] != 1u || (code & PAIR_PARTNER) != 0u) {
                continue;
            }
            // The unit: the constraint and a leader's partner, whose nodes it colours too.
            let kp = select(NONE, paired_slot(code), (code & PAIR_LEADER) != 0u);
            var ready = true;
            var used = 0u;
            for (var t = 0u; t < unit_refs() && ready; t++) {
                let u = select(kp, k, t < 3u);
                if (u == NONE) {
                    break;
                }
                let i = ref_node(u, t % 3u);
                if (i == NONE) {
                    continue;
                }
                let end = ws[cc.p.o_noff + i + 1u];
                for (var q = ws[cc.p.o_noff + i]; q < end; q++) {
                    let k2 = grow[b + q];
                    if (k2 == k || k2 == kp) {
                        continue;
                    }
                    let s2 = ws[cc.p.o_list + k2];
                    if (s2 == 0u || !touches(k2, i)) {
                        continue;
                    }
                    if (s2 == 1u) {
                        // (An uncoloured partner waits on its leader's order.)
                        let c2 = slot_code(k2);
                        let lead = select(k2, paired_slot(c2), (c2 & PAIR_PARTNER) != 0u);
                        if (coloured_before(lead, k)) {
                            ready = false;
                            break;
                        }
                    } else {
                        used |= colour_bit(s2 - 2u);
                    }
                }
            }
            if (ready) {
                let col = 2u + first_free(used);
                ws[cc.p.o_list + k] = col;
                if (kp != NONE) {
                    ws[cc.p.o_list + kp] = col;
                }
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
            let code = pair_code(j);
            if ((code & PAIR_PARTNER) != 0u) {
                continue;
            }
            let kp = select(NONE, paired_slot(code), (code & PAIR_LEADER) != 0u);
            var used = 0u;
            for (var t = 0u; t < unit_refs(); t++) {
                let u = select(kp, k, t < 3u);
                if (u != NONE) {
                    used |= mask_of(ref_node(u, t % 3u));
                }
            }
            let col = first_free(used);
            for (var t = 0u; t < unit_refs(); t++) {
                let u = select(kp, k, t < 3u);
                if (u != NONE) {
                    mark_node(ref_node(u, t % 3u), col);
                }
            }
            ws[cc.p.o_list + k] = 2u + col;
            if (kp != NONE) {
                ws[cc.p.o_list + kp] = 2u + col;
            }
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
    if ((pair_code(j) & PAIR_PARTNER) != 0u) {
        return PARTNER;
    }
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
    for (var c = 0u; c <= PARTNER; c++) {
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
        sh_off[PARTNER + 1u] = base;
        // The offsets kept in the per-colour path's list offsets, unused on this path, for the
        // test hook `GpuSolver::contact_last_colouring`.
        for (var c = 0u; c <= PARTNER + 1u; c++) {
            ws[cc.p.o_loff + c] = sh_off[c];
        }
    }
    storageBarrier();
    workgroupBarrier();
}
