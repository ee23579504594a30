//! The GPU backend (WGSL compute kernels through wgpu).
