// The reductions' shared parts, for reduce.wgsl (the first level over many workgroups) and
// control.wgsl (the second level, and the whole reduction in its one workgroup for small models
// on CPU adapters): each lane's share of the items at a fixed stride, and the fixed trees (the
// sums' in tree.wgsl). Compiled after tree.wgsl; the kernel declares `params`, `elem_dt`,
// `instances` and `sample_src`. CPU reference: src/gpu/reduce.rs `sum_reference`.

var<workgroup> sh_dt: array<f32, RG>;
var<workgroup> sh_ix: array<u32, RG>;

fn better(d0: f32, i0: u32, d1: f32, i1: u32) -> bool {
    return d1 < d0 || (d1 == d0 && i1 < i0);
}

// Lane l's smallest element stable step, and its element (the lower index on ties), among the
// elements first + l, first + l + stride, ... into sh_dt[l], sh_ix[l].
fn lane_min_dt(l: u32, first: u32, stride: u32) {
    var d = 3.0e38;
    var ix = NONE;
    for (var j = first + l; j < params.n_elems; j += stride) {
        let dj = elem_dt[j];
        if (better(d, ix, dj, j)) {
            d = dj;
            ix = j;
        }
    }
    sh_dt[l] = d;
    sh_ix[l] = ix;
}

// The smallest of the lanes' (sh_dt[l], sh_ix[l]) into sh_dt[0], sh_ix[0], in a fixed tree. Every
// lane calls it, in uniform control flow.
fn min_tree(l: u32) {
    workgroupBarrier();
    for (var s = RG / 2u; s > 0u; s >>= 1u) {
        if (l < s) {
            if (better(sh_dt[l], sh_ix[l], sh_dt[l + s], sh_ix[l + s])) {
                sh_dt[l] = sh_dt[l + s];
                sh_ix[l] = sh_ix[l + s];
            }
        }
        workgroupBarrier();
    }
}

// The sum of instance `inst`'s items first + l, first + l + stride, ... by lane l, then over the
// lanes (sum_tree): into sh_sum[0].
fn sum_items(l: u32, inst: Instance, first: u32, stride: u32) {
    var acc = vec4<f32>(0.0);
    for (var j = first + l; j < inst.count; j += stride) {
        acc += sample_src[inst.start + j];
    }
    sum_tree(l, acc);
}
