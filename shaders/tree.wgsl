// Fixed-order sums over a workgroup: a tree over the lanes in shared memory, so that the sum has
// the same bits on every run. Included (by concatenation, on the Rust side) before the kernels
// that sum over lanes: reduce.wgsl and control.wgsl (TREE = RG) and contact_report.wgsl
// (TREE = SG), each of which declares TREE, its workgroup size. CPU reference: the tree of
// src/gpu/reduce.rs `sum_reference`.

var<workgroup> sh_sum: array<vec4<f32>, TREE>;

// The sum of every lane's `x` (lane l's) into sh_sum[0], adding halves in a fixed tree. Every lane
// of the workgroup calls it, in uniform control flow; sh_sum[0] holds the sum after the call.
fn sum_tree(l: u32, x: vec4<f32>) {
    sh_sum[l] = x;
    workgroupBarrier();
    for (var s = TREE / 2u; s > 0u; s >>= 1u) {
        if (l < s) {
            sh_sum[l] += sh_sum[l + s];
        }
        workgroupBarrier();
    }
}
