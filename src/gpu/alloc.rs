//! The device buffers of a scene as they are allocated ([`Alloc`]): each one created once, named,
//! its size listed for the plan report ([`super::state::GpuState::allocated`]) and the buffer
//! kept in allocation order for checkpoints (`src/gpu/checkpoint.rs`). Host-side bookkeeping of
//! the GPU state and its contact buffers: no kernel, so no CPU twin.

use wgpu::util::DeviceExt;

/// The buffers of a scene as they are allocated.
pub(crate) struct Alloc<'a> {
    device: &'a wgpu::Device,
    list: Vec<(&'static str, u64)>,
    /// Every buffer allocated, for checkpoints (each is copyable both ways).
    buffers: Vec<(&'static str, wgpu::Buffer)>,
}

impl<'a> Alloc<'a> {
    /// No buffers yet, on `device`.
    pub(crate) fn new(device: &'a wgpu::Device) -> Self {
        Alloc {
            device,
            list: Vec::new(),
            buffers: Vec::new(),
        }
    }

    /// The names and sizes of the buffers allocated (with those only recorded), and the buffers.
    #[allow(clippy::type_complexity)]
    pub(crate) fn finish(self) -> (Vec<(&'static str, u64)>, Vec<(&'static str, wgpu::Buffer)>) {
        (self.list, self.buffers)
    }

    /// A buffer `name` holding `data` (16 zero bytes when empty), copyable both ways.
    pub(crate) fn init(
        &mut self,
        name: &'static str,
        data: &[u8],
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        // Storage bindings may not be empty.
        let pad = [0u8; 16];
        let contents = if data.is_empty() { &pad[..] } else { data };
        self.list.push((name, contents.len() as u64));
        let buffer = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(name),
                contents,
                usage: usage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            });
        self.buffers.push((name, buffer.clone()));
        buffer
    }

    /// Records a buffer created elsewhere.
    pub(crate) fn record(&mut self, name: &'static str, size: u64) {
        self.list.push((name, size));
    }

    /// A zeroed buffer `name` of `size` bytes (at least 16), copyable both ways.
    pub(crate) fn zeroed(
        &mut self,
        name: &'static str,
        size: u64,
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        let size = size.max(16);
        self.list.push((name, size));
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(name),
            size,
            usage: usage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.buffers.push((name, buffer.clone()));
        buffer
    }
}
