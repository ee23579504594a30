// First level of the reductions, in a fixed order that depends only on the sizes (deterministic).
// min_dt: the smallest element stable step and its element (ties to the lower index).
// sum: per instance (a contiguous range of sample_src), partial vec4 sums per workgroup.
// sum_instances: the second level of the sums, one workgroup per instance (a body, the elements,
//   the constraints, ...), so that a sample costs the same whatever the number of bodies.
// The stable step's second level runs in control.wgsl (one workgroup). Compiled after tree.wgsl
// and reduce_common.wgsl (the lanes' shares and the trees, shared with control.wgsl).

const RG: u32 = 256u;
const TREE: u32 = RG;

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> elem_dt: array<f32>;
@group(0) @binding(2) var<storage, read_write> dt_partial: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read> instances: array<Instance>;
@group(0) @binding(4) var<storage, read> sample_src: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> sum_partial: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> inst_res: array<vec4<f32>>;

@compute @workgroup_size(RG)
fn min_dt(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>) {
    let l = lid.x;
    lane_min_dt(l, wid.x * RG, params.dt_groups * RG);
    min_tree(l);
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
    sum_items(l, inst, (g - inst.first_group) * RG, inst.groups * RG);
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
        sum_tree(l, acc);
        if (l == 0u) {
            inst_res[r] = sh_sum[0];
        }
        workgroupBarrier();
    }
}
