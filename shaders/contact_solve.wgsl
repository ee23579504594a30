// The diagonal-mass Lagrange correction (CPU reference: crate::contact solve, ContactSet::sweep
// and ::recheck): projected Gauss-Seidel sweeps over the colours of the last search (slots of one
// colour share no node, so a colour is updated in parallel with the result of a sequential sweep:
// deterministic; in one workgroup extrapolated between sweeps as on the CPU), until no gap
// changes by more than the step's tolerance (`step_tolerance`, from cc.p.tolerance) or
// cc.p.max_sweeps; then the
// active-set update (free Lagrange slots re-checked at the corrected positions, more sweeps when
// any penetrates), ACTIVE_SET_ROUNDS rounds at most. Compiled after contact_narrow.wgsl and
// contact_colour.wgsl (the one-workgroup path's compaction and colouring, `compact`).
//
// Two paths, chosen by size on the host: `solve_one`, every sweep in one workgroup (colours
// separated by barriers; the fastest for small contact sets; with PAIR_BLOCKS, the GPUs' default
// and not the CPU adapters', the two constraints of a node pair met from both passes swept
// together as a 2 x 2 block, `block_packed`, as the CPU reference does: the striker's sweeps a
// step 2.5 x fewer), and `sweep_color` + `recheck`, one
// dispatch per colour and sweep over as many workgroups as the colour needs. With many active
// slots (cc.p.split) the one-workgroup path leaves its re-checks to `recheck_active`, one thread
// per active slot over many workgroups, dispatched between its rounds: the same constraints and
// arithmetic (the same bits on lavapipe; an H100 rounds the two kernels apart by 1e-9).

const ACTIVE_SET_ROUNDS: u32 = 4u;    // crate::contact::ACTIVE_SET_ROUNDS

var<workgroup> sh_m: array<f32, SG>;
var<workgroup> sh_w: u32;
var<workgroup> sh_nc: u32;
var<workgroup> sh_off: array<u32, 35>;   // colour offsets of the compacted slots (PARTNER + 2)
var<workgroup> sh_max: atomic<u32>;
var<workgroup> sh_split: u32;
var<workgroup> sh_nn: u32;         // nodes of the compacted constraints (ws[o_nlist..])
var<workgroup> sh_change: u32;     // f32 bits of the last sweep's largest change
var<workgroup> sh_lw: u32;         // 1 when the sweeps keep their state in workgroup memory (`pack`)

// Whether this solve's sweeps keep the packed nodes' records and the multipliers in workgroup
// memory (`pack`; the same in every invocation, set from sh_lw).
var<private> sw_local: bool;
// Whether the sweeps may keep their state in workgroup memory (host-set:
// crate::gpu::contact::local_sweeps; false on CPU adapters, where it is slower).
const LOCAL_SWEEPS: bool = true;

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
// stands for a wall's missing segment. Each constraint q its nodes' packed indices and a
// leader's partner's packed index, NONE for others (ws[o_cidx + 4q..]; the slots' packed
// indices through ws[o_best..], free after the pairing), its row (n, g0, w), (lambda, lt, xi, mu) at fws[f_row + 2q..] and, with
// friction, (wt, the free update's relative tangential velocity) at fws[f_frow + q]. With
// LOCAL_SWEEPS (GPUs), where they fit, the nodes' records and the multipliers move on into
// workgroup memory for the sweeps (`node_rec`, `row1`: the rows they read from storage are then
// read-only, but a friction row's lt). `unpack` writes dv and the multipliers back.
fn pack(l: u32) {
    let nn = sh_nn;
    let na = sh_off[PARTNER + 1u];
    // The sweeps' state in workgroup memory when it fits in what the compaction's arrays leave
    // free after it: each node's record (dv in sh_ref, 1/m in sh_key, two words each, the zero
    // record after the last included) and each constraint's multiplier (sh_cr). Between colours
    // a sweep then waits on workgroup memory only: the rows it reads from storage are read-only
    // there (but a friction row's lt, which only its own invocation touches within a sweep).
    // The nodes' records go to storage only when they stay there (`node_rec`).
    sw_local = false;
    if (LOCAL_SWEEPS) {
        if (l == 0u) {
            sh_lw = select(0u, 1u, 2u * (nn + 1u) <= 3u * CAP_SIZE && na <= CAP_SIZE);
        }
        sw_local = workgroupUniformLoad(&sh_lw) != 0u;
    }
    let in_storage = !(LOCAL_SWEEPS && sw_local);
    for (var j = l; j < nn; j += SG) {
        let i = ws[cc.p.o_nlist + j];
        if (in_storage) {
            fws[cc.p.f_node + j] = vec4<f32>(dv(i), c_ref[i].zw);
        }
        ws[cc.p.o_mask + i] = j;
    }
    if (l == 0u && in_storage) {
        fws[cc.p.f_node + nn] = vec4<f32>(0.0);
    }
    if (PAIR_BLOCKS) {
        for (var q = l; q < na; q += SG) {
            ws[cc.p.o_best + ws[cc.p.o_act + q]] = q;
        }
    }
    if (LOCAL_SWEEPS && sw_local) {
        for (var j = l; j <= nn; j += SG) {
            var rec = vec4<f32>(0.0);
            if (j < nn) {
                let i = ws[cc.p.o_nlist + j];
                rec = vec4<f32>(dv(i), c_ref[i].zw);
            }
            sh_ref[2u * j] = bitcast<u32>(rec.x);
            sh_ref[2u * j + 1u] = bitcast<u32>(rec.y);
            atomicStore(&sh_key[2u * j], bitcast<u32>(rec.z));
            atomicStore(&sh_key[2u * j + 1u], bitcast<u32>(rec.w));
        }
    }
    storageBarrier();
    for (var q = l; q < na; q += SG) {
        let k = ws[cc.p.o_act + q];
        let c = cons[k];
        let s = slots[k].s;
        let at = cc.p.o_cidx + 4u * q;
        ws[at] = ws[cc.p.o_mask + s];
        ws[at + 1u] = packed_index(c.a, nn);
        ws[at + 2u] = packed_index(c.b, nn);
        if (PAIR_BLOCKS) {
            let code = ws[cc.p.o_pair + k];
            ws[at + 3u] = select(NONE, ws[cc.p.o_best + paired_slot(code)], (code & PAIR_LEADER) != 0u);
        }
        fws[cc.p.f_row + 2u * q] = vec4<f32>(c.n, c.g0, c.w);
        fws[cc.p.f_row + 2u * q + 1u] = vec4<f32>(c.lambda, c.lt, c.xi, c.mu);
        if (LOCAL_SWEEPS && sw_local) {
            sh_cr[q] = bitcast<u32>(c.lambda);
        }
        if (FRICTION && c.mu > 0.0) {
            fws[cc.p.f_frow + q] = vec4<f32>(c.wt, free_relative_along(c, s, tangent(c)), 0.0, 0.0);
        }
    }
    storageBarrier();
    if (LOCAL_SWEEPS) {
        workgroupBarrier();
    }
}

// Packed node j's record (dv, 1/m), from workgroup memory or from fws.
fn node_rec(j: u32) -> vec4<f32> {
    if (LOCAL_SWEEPS && sw_local) {
        return vec4<f32>(
            bitcast<f32>(sh_ref[2u * j]),
            bitcast<f32>(sh_ref[2u * j + 1u]),
            bitcast<f32>(atomicLoad(&sh_key[2u * j])),
            bitcast<f32>(atomicLoad(&sh_key[2u * j + 1u])),
        );
    }
    return fws[cc.p.f_node + j];
}

// Packed node j's record written (only its dv changes in the sweeps).
fn store_node(j: u32, r: vec4<f32>) {
    if (LOCAL_SWEEPS && sw_local) {
        sh_ref[2u * j] = bitcast<u32>(r.x);
        sh_ref[2u * j + 1u] = bitcast<u32>(r.y);
    } else {
        fws[cc.p.f_node + j] = r;
    }
}

// Packed constraint q's (lambda, lt, xi, mu), its multiplier from workgroup memory or from fws.
fn row1(q: u32) -> vec4<f32> {
    var r = fws[cc.p.f_row + 2u * q + 1u];
    if (LOCAL_SWEEPS && sw_local) {
        r.x = bitcast<f32>(sh_cr[q]);
    }
    return r;
}

// Packed constraint q's (lambda, lt, xi, mu) written (in workgroup memory its multiplier, and
// with friction the rest in fws as well).
fn store_row1(q: u32, r: vec4<f32>) {
    if (LOCAL_SWEEPS && sw_local) {
        sh_cr[q] = bitcast<u32>(r.x);
        if (FRICTION) {
            fws[cc.p.f_row + 2u * q + 1u] = r;
        }
    } else {
        fws[cc.p.f_row + 2u * q + 1u] = r;
    }
}

// The packed nodes' dv and the constraints' multipliers written back; the colour masks cleared.
fn unpack(l: u32) {
    if (LOCAL_SWEEPS) {
        // (The rows' lt, written by other invocations in sweeps that end on workgroup barriers.)
        storageBarrier();
    }
    let nn = sh_nn;
    for (var j = l; j < nn; j += SG) {
        let i = ws[cc.p.o_nlist + j];
        let r = node_rec(j).xy;
        c_pv[3u * i + 2u].z = r.x;
        c_pv[3u * i + 2u].w = r.y;
        ws[cc.p.o_mask + i] = 0u;
    }
    let na = sh_off[PARTNER + 1u];
    for (var q = l; q < na; q += SG) {
        let k = ws[cc.p.o_act + q];
        let r = row1(q);
        cons[k].lambda = r.x;
        cons[k].lt = r.y;
    }
    storageBarrier();
}

// pgs_update on packed constraint q (`pack`; `dummy` the zero record): the same arithmetic.
fn pgs_packed(q: u32, dt: f32, inv_scale: f32, dummy: u32) -> f32 {
    let r0 = fws[cc.p.f_row + 2u * q];
    var r1 = row1(q);
    let at = cc.p.o_cidx + 4u * q;
    let s = ws[at];
    let a = ws[at + 1u];
    let b = ws[at + 2u];
    var ns = node_rec(s);
    var na = node_rec(a);
    var nb = node_rec(b);
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
        store_node(s, ns);
        if (a != dummy) {
            store_node(a, na);
            store_node(b, nb);
        }
        store_row1(q, r1);
    }
    return change;
}

// The packed indices of packed constraint q's nodes (slave, segment ends).
fn packed_nodes(q: u32) -> vec3<u32> {
    let at = cc.p.o_cidx + 4u * q;
    return vec3<u32>(ws[at], ws[at + 1u], ws[at + 2u]);
}

// The relative normal velocity change of packed constraint q (nodes `i`, normal n, xi) from
// the packed nodes' dv, as pgs_packed sums it.
fn packed_relative(i: vec3<u32>, n: vec2<f32>, xi: f32) -> f32 {
    var rel = dot(node_rec(i.x).xy, n);
    rel -= (1.0 - xi) * dot(node_rec(i.y).xy, n) + xi * dot(node_rec(i.z).xy, n);
    return rel;
}

// Impulse d along n on packed constraint q's nodes (as pgs_packed applies it).
fn packed_impulse(i: vec3<u32>, n: vec2<f32>, xi: f32, d: f32, inv_scale: f32) {
    let ns = node_rec(i.x);
    store_node(i.x, vec4<f32>(ns.xy + d * inv_scale * n * ns.zw, ns.zw));
    let na = node_rec(i.y);
    store_node(i.y, vec4<f32>(na.xy + -(1.0 - xi) * d * inv_scale * n * na.zw, na.zw));
    let nb = node_rec(i.z);
    store_node(i.z, vec4<f32>(nb.xy + -xi * d * inv_scale * n * nb.zw, nb.zw));
}

// Smallest determinant of a 2 x 2 block, relative to the product of its diagonal, that is solved
// as a block (f32; the CPU reference's 1e-12 is below f32's resolution). Below it the block is
// not inverted: one constraint alone (the one that carries the load first), neither, or the two
// one after the other, the first that holds.
const BLOCK_DET: f32 = 1e-3;

// ContactSet::block on packed constraint q and its partner p: the 2 x 2 linear complementarity
// problem of their multipliers solved exactly (both pushing, either alone, or neither, the first
// that holds); returns the larger change of their gaps. The same arithmetic in f32.
fn block_packed(q: u32, p: u32, dt: f32, inv_scale: f32) -> f32 {
    let r0k = fws[cc.p.f_row + 2u * q];
    var r1k = row1(q);
    let r0j = fws[cc.p.f_row + 2u * p];
    var r1j = row1(p);
    let ik = packed_nodes(q);
    let ij = packed_nodes(p);
    let nk = r0k.xy;
    let nj = r0j.xy;
    let xk = r1k.z;
    let xj = r1j.z;
    // The coupling: the change of one gap per unit impulse of the other (ContactSet::coupling).
    var wc = 0.0;
    for (var t = 0u; t < 3u; t++) {
        for (var u = 0u; u < 3u; u++) {
            if (ik[t] == ij[u]) {
                let im = node_rec(ik[t]).zw;
                wc += node_share(t, xk) * node_share(u, xj) * (nk.x * nj.x * im.x + nk.y * nj.y * im.y);
            }
        }
    }
    let wkj = dt * wc * inv_scale;
    let wk = r0k.w;
    let wj = r0j.w;
    let lk = r1k.x;
    let lj = r1j.x;
    let gk = r0k.z + dt * packed_relative(ik, nk, xk);
    let gj = r0j.z + dt * packed_relative(ij, nj, xj);
    // In increments d of the multipliers from where they are, l: the gaps there, g, are what the
    // sweeps drive to zero, and the gaps at l + d are g + W d. The rounding of the 2 x 2 inverse
    // of a nearly redundant pair then scales with g, not with the multipliers, and the fixed
    // point is g = 0 however W rounds (ContactSet::block, the same form).
    let det = wk * wj - wkj * wkj;
    var d = vec2<f32>(0.0);
    var found = false;
    if (det > BLOCK_DET * wk * wj) {
        d = vec2<f32>((-gk * wj + gj * wkj) / det, (-gj * wk + gk * wkj) / det);
        found = lk + d.x > 0.0 && lj + d.y > 0.0;
    }
    if (!found) {
        // k alone (j released, k's gap closed), j alone, neither. The gap of the released one is
        // written without the cancellation of its large terms. For a pair that rounding leaves
        // redundant (two nodes that coincide, det 0) either alone holds, and the one that carries
        // the load keeps it, so that the load does not jump between the two from sweep to sweep
        // and step to step (the contact patch test's 8/6 mesh did not settle while it did).
        let dt0 = max(det, 0.0);
        let k_alone = vec2<f32>(-(gk - wkj * lj) / wk, -lj);
        let j_alone = vec2<f32>(-lk, -(gj - wkj * lk) / wj);
        let k_holds = lk + k_alone.x > 0.0 && gj - wkj / wk * gk - lj * dt0 / wk >= 0.0;
        let j_holds = lj + j_alone.y > 0.0 && gk - wkj / wj * gj - lk * dt0 / wj >= 0.0;
        if (k_holds && (lk >= lj || !j_holds)) {
            d = k_alone;
        } else if (j_holds) {
            d = j_alone;
        } else if (gk - wk * lk - wkj * lj >= 0.0 && gj - wkj * lk - wj * lj >= 0.0) {
            d = vec2<f32>(-lk, -lj);
        } else {
            // (Round-off, or a block below BLOCK_DET: the two updates one after the other.)
            d.x = max(lk - gk / wk, 0.0) - lk;
            d.y = max(lj - (gj + wkj * d.x) / wj, 0.0) - lj;
        }
    }
    let dk = d.x;
    let dj = d.y;
    if (dk != 0.0) {
        packed_impulse(ik, nk, xk, dk, inv_scale);
        r1k.x = lk + dk;
        store_row1(q, r1k);
    }
    if (dj != 0.0) {
        packed_impulse(ij, nj, xj, dj, inv_scale);
        r1j.x = lj + dj;
        store_row1(p, r1j);
    }
    return max(abs(wk * dk + wkj * dj), abs(wkj * dk + wj * dj));
}

// Sweeps packed constraint q: with its partner as a 2 x 2 block when it leads a pair.
fn sweep_packed(q: u32, dt: f32, inv_scale: f32, dummy: u32) -> f32 {
    if (PAIR_BLOCKS) {
        let p = ws[cc.p.o_cidx + 4u * q + 3u];
        if (p != NONE) {
            return block_packed(q, p, dt, inv_scale);
        }
    }
    return pgs_packed(q, dt, inv_scale, dummy);
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
    if (LOCAL_SWEEPS) {
        // (The rows' lt, written by other invocations in colours that end on workgroup barriers.)
        storageBarrier();
    }
    let na = sh_off[PARTNER + 1u];
    for (var q = l; q < na; q += SG) {
        let r = row1(q);
        let now = r.xy;
        let at = cc.p.o_lprev + 2u * q;
        if (beta != 0.0) {
            let last = vec2<f32>(bitcast<f32>(ws[at]), bitcast<f32>(ws[at + 1u]));
            store_row1(q, vec4<f32>(now.x + beta * (now.x - last.x), now.y + beta * (now.y - last.y), r.zw));
        }
        ws[at] = bitcast<u32>(now.x);
        ws[at + 1u] = bitcast<u32>(now.y);
    }
    let nn = sh_nn;
    for (var j = l; j < nn; j += SG) {
        let r = node_rec(j);
        let now = r.xy;
        let at = cc.p.o_dvp + 2u * j;
        if (beta != 0.0) {
            let last = vec2<f32>(bitcast<f32>(ws[at]), bitcast<f32>(ws[at + 1u]));
            store_node(j, vec4<f32>(now + beta * (now - last), r.zw));
        }
        ws[at] = bitcast<u32>(now.x);
        ws[at + 1u] = bitcast<u32>(now.y);
    }
    storageBarrier();
    if (LOCAL_SWEEPS) {
        workgroupBarrier();
    }
}

// The stop of this solve's sweeps (`stop_tolerance`), the same in every invocation.
fn step_tolerance(l: u32) -> f32 {
    if (l == 0u) {
        sh_change = bitcast<u32>(stop_tolerance());
    }
    return bitcast<f32>(workgroupUniformLoad(&sh_change));
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
    // Whether `pack` put the sweeps' state in workgroup memory (then the colours end on
    // workgroup barriers: the rows in storage are read-only there, but a friction row's lt, which
    // its own invocation alone touches in the colours).
    var local = false;
    if (LOCAL_SWEEPS) {
        local = workgroupUniformLoad(&sh_lw) != 0u;
    }
    let tolerance = step_tolerance(l);
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
                change = max(change, sweep_packed(q, dt, inv_scale, dummy));
            }
            if (local) {
                workgroupBarrier();
            } else {
                storageBarrier();
            }
        }
        if (l == 0u) {
            for (var q = sh_off[SERIAL]; q < sh_off[SERIAL + 1u]; q++) {
                change = max(change, sweep_packed(q, dt, inv_scale, dummy));
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
        if (!(largest > tolerance)) {
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
    if (cons[k].kind != KIND_NONE || (SPRINGS && (slots[k].info & SLOT_PENALTY) != 0u)) {
        return false;
    }
    let sl = slots[k];
    corr_dt = dt;
    var c = narrow_slot(k, sl, dt, dtn, inv_scale, 0.0);
    corr_dt = 0.0;
    if (c.kind != KIND_LAGRANGE) {
        return false;
    }
    // The gap at the free trial positions, as for every constraint.
    c.g0 -= dt * relative(c, sl.s);
    c.dt_warm = dtn;
    cons[k] = c;
    note_penetration(c);
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
// added constraints, any other (the first of a round too) when the previous sweep ran and changed
// a gap by more than the step's tolerance (`stop_tolerance`; cc.change, cc.added). So a solve
// that reaches a round's last sweep unconverged goes on in the next round's sweeps, after that
// round's re-check: up to MAX_SWEEP_SLOTS sweeps a step where it stopped at max_sweeps (the 0.3 c
// impact of `tests/gpu/stress.rs` left 39 of its steps unconverged and 1.4e-6 m of penetration,
// 2026-11-29).
fn sweep_runs(q: u32) -> bool {
    if (q == 0u) {
        return atomicLoad(&cc.lagrange) > 0u;
    }
    if (q % cc.p.max_sweeps == 0u && atomicLoad(&cc.added[q / cc.p.max_sweeps - 1u]) > 0u) {
        return true;
    }
    let prev = atomicLoad(&cc.change[q - 1u]);
    return prev != 0u && bitcast<f32>(prev) > stop_tolerance();
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
