// First level of the reductions, in a fixed order that depends only on the sizes (deterministic).
// min_dt: the smallest element stable step and its element (ties to the lower index).
// sum: per instance (a contiguous range of sample_src), partial vec4 sums per workgroup.
// sum_instances: the second level of the sums, one workgroup per instance (a body, the elements,
//   the constraints, ...), so that a sample costs the same whatever the number of bodies.
// The stable step's second level runs in control.wgsl (one workgroup).

const RG: u32 = 256u;


@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> elem_dt: array<f32>;
@group(0) @binding(2) var<storage, read_write> dt_partial: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read> instances: array<Instance>;
@group(0) @binding(4) var<storage, read> sample_src: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> sum_partial: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> inst_res: array<vec4<f32>>;

var<workgroup> sh_dt: array<f32, RG>;
var<workgroup> sh_ix: array<u32, RG>;
var<workgroup> sh_sum: array<vec4<f32>, RG>;

fn better(d0: f32, i0: u32, d1: f32, i1: u32) -> bool {
    return d1 < d0 || (d1 == d0 && i1 < i0);
}

@compute @workgroup_size(RG)
fn min_dt(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>) {
    let l = lid.x;
    var d = 3.0e38;
    var ix = NONE;
    let stride = params.dt_groups * RG;
    for (var j = wid.x * RG + l; j < params.n_elems; j += stride) {
        let dj = elem_dt[j];
        if (better(d, ix, dj, j)) {
            d = dj;
            ix = j;
        }
    }
    sh_dt[l] = d;
    sh_ix[l] = ix;
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
    if (l == 0u) {
        dt_partial[wid.x] = vec2<u32>(bitcast<u32>(sh_dt[0]), sh_ix[0]);
    }
}

@compute @workgroup_size(RG)
fn sum(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>) {
    let l = lid.x;
    let g = wid.x;
    // The instance this workgroup belongs to: the last one whose first group is at most g (the
    // first groups increase strictly, every instance having at least one group).
    var lo = 0u;
    var hi = params.n_instances;
    while (hi - lo > 1u) {
        let mid = (lo + hi) / 2u;
        if (instances[mid].first_group <= g) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let inst = instances[lo];
    let local_group = g - inst.first_group;
    var acc = vec4<f32>(0.0);
    let stride = inst.groups * RG;
    for (var j = local_group * RG + l; j < inst.count; j += stride) {
        acc += sample_src[inst.start + j];
    }
    sh_sum[l] = acc;
    workgroupBarrier();
    for (var s = RG / 2u; s > 0u; s >>= 1u) {
        if (l < s) {
            sh_sum[l] += sh_sum[l + s];
        }
        workgroupBarrier();
    }
    if (l == 0u) {
        sum_partial[g] = sh_sum[0];
    }
}

// Second level: instance r's partials (one per first-level workgroup of r, fewer than RG) in the
// same tree as the first level. Workgroups take instances r = w, w + G, ... (G workgroups).
@compute @workgroup_size(RG)
fn sum_instances(
    @builtin(local_invocation_id) lid: vec3<u32>,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let l = lid.x;
    for (var r = wid.x; r < params.n_instances; r += nwg.x) {
        let inst = instances[r];
        var acc = vec4<f32>(0.0);
        if (l < inst.groups) {
            acc = sum_partial[inst.first_group + l];
        }
        sh_sum[l] = acc;
        workgroupBarrier();
        for (var s = RG / 2u; s > 0u; s >>= 1u) {
            if (l < s) {
                sh_sum[l] += sh_sum[l + s];
            }
            workgroupBarrier();
        }
        if (l == 0u) {
            inst_res[r] = sh_sum[0];
        }
        workgroupBarrier();
    }
}
