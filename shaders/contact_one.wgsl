// The contact stage after the search in one workgroup (src/gpu/contact/one.rs; CPU adapters with
// a small contact set): the narrow phase, the gather, the one-workgroup Lagrange solve with its
// re-checks inside it, `finish` and the reports, the SG invocations taking each stage's items in
// turn with a storage barrier between stages. One dispatch where the per-item kernels take six
// (and `prep_one` one where `prep` and `plan` take two): on lavapipe a dispatch with work costs
// 40 to 90 us on two threads, more than these stages' work on a small set. Each item's arithmetic
// and the order of every sum are those of the per-item kernels: the same bits.
// Compiled after contact_narrow.wgsl, contact_solve.wgsl and contact_report.wgsl.

@compute @workgroup_size(SG)
fn contact_one(@builtin(local_invocation_id) lid: vec3<u32>) {
    let l = lid.x;
    if (!running_uniform(l)) {
        return;
    }
    let na = active_count();
    for (var j = l; j < na; j += SG) {
        narrow_active(j);
    }
    storageBarrier();
    let nl = cc.p.n_local;
    for (var i = l; i < nl; i += SG) {
        gather_node(i);
    }
    storageBarrier();
    solve_step(l);
    storageBarrier();
    // `finish`, its work summed in node order by whole workgroups' worth of nodes (CG), as
    // `finish`'s lane 0 sums its lanes. With as many chunks as invocations (lavapipe's 8), each
    // invocation takes whole chunks, node by node. With fewer (a GPU's 256 over a few thousand
    // nodes), every node first takes an invocation of its own, its work kept in the solve's node
    // records (fws[f_node..], nl + 1 of them, free once the solve has written dv back; the next
    // pack writes them anew), and the chunks are summed from there: the same sums in the same
    // order either way.
    let chunks = (nl + CG - 1u) / CG;
    let spread = chunks < SG;
    if (spread) {
        for (var i = l; i < nl; i += SG) {
            fws[cc.p.f_node + i] = finish_node(i);
        }
    }
    storageBarrier();
    for (var c = l; c < chunks; c += SG) {
        var t = vec4<f32>(0.0);
        for (var h = 0u; h < CG; h++) {
            let i = c * CG + h;
            var w = vec4<f32>(0.0);
            if (i < nl) {
                if (spread) {
                    w = fws[cc.p.f_node + i];
                } else {
                    w = finish_node(i);
                }
            }
            t += w;
        }
        fws[cc.p.f_wp + c] = t;
    }
    storageBarrier();
    // `report_slots`: the active slots' reports summed in runs by chunks of CG, each invocation
    // whole chunks; with fewer chunks than invocations, every slot's report first (one
    // invocation each), as for `finish`.
    let runs = (na + CG - 1u) / CG;
    let spread_runs = runs < SG;
    if (spread_runs) {
        for (var j = l; j < na; j += SG) {
            report_item(j);
        }
    }
    storageBarrier();
    for (var c = l; c < runs; c += SG) {
        let j = c * CG;
        let n = min(CG, na - j);
        if (!spread_runs) {
            for (var q = 0u; q < n; q++) {
                report_item(j + q);
            }
        }
        report_runs(j, n);
    }
    storageBarrier();
    report_end_step(l);
}
