// Probes of what a device reaches through wgpu (`ricochet bench --probe`; the Rust room is
// src/gpu/probe.rs, whose CPU reference is `probe::fill_reference`: after `fill` and `copy`, dst
// holds that pattern). No part of a simulation step.
// fill: writes the pattern into dst (so that the copy moves data that is not all zeros).
// copy: one vec4<f32> a thread from src to dst, over a 2D grid of workgroups (a 512 MB copy
//   needs more workgroups than one dimension allows): the streaming bandwidth of a kernel.
// chained: a dispatch that does nothing, with a read-write binding, so that wgpu puts a barrier
//   between two of them as between the dependent dispatches of a step: the dispatch floor.
// empty: a dispatch that does nothing and binds nothing (no barrier between two of them).

override WG: u32 = 256u;

@group(0) @binding(0) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> dst: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> flag: array<u32>;

// The index of the thread in the 2D grid (rows of nwg.x workgroups).
fn flat(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return gid.y * nwg.x * WG + gid.x;
}

// The pattern of element i (probe::fill_reference): exact in f32 for any u32 i.
fn pattern(i: u32) -> vec4<f32> {
    return vec4<f32>(f32(i & 0xffffu), f32(i >> 16u), 1.0, -1.0);
}

@compute @workgroup_size(WG)
fn fill(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = flat(gid, nwg);
    if (i < arrayLength(&dst)) {
        dst[i] = pattern(i);
    }
}

@compute @workgroup_size(WG)
fn copy(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = flat(gid, nwg);
    if (i < arrayLength(&dst)) {
        dst[i] = src[i];
    }
}

@compute @workgroup_size(64)
fn chained(@builtin(num_workgroups) nwg: vec3<u32>) {
    // Never true (one workgroup is dispatched), but the binding is used, so it stays bound.
    if (nwg.x == 0u) {
        flag[0] = 1u;
    }
}

@compute @workgroup_size(64)
fn empty() {
}
