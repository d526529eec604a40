//! Buffers kept between frames of a prepared scene: a [`BufferPool`] hands out buffers by size
//! and usage and takes them back when the frame ends, so a frame of the same size as an earlier
//! one creates no buffer; [`BufferPool::allocations`] counts the buffers that had to be created.

use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// Free buffers by (size, usage).
#[derive(Default)]
pub struct BufferPool {
    free: Mutex<Vec<wgpu::Buffer>>,
    allocations: AtomicU64,
}

impl BufferPool {
    /// Buffers created so far (takes that found no free buffer of that size and usage).
    pub fn allocations(&self) -> u64 {
        self.allocations.load(Relaxed)
    }

    /// A buffer of `size` bytes and `usage`, from the free list or new. Its contents are
    /// whatever the last frame left: the caller clears what it needs cleared.
    pub fn take(
        &self,
        device: &wgpu::Device,
        label: &str,
        size: u64,
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        self.take_marked(device, label, size, usage).0
    }

    /// [`BufferPool::take`], and whether the buffer is new (zeroed, as wgpu makes every buffer).
    pub fn take_marked(
        &self,
        device: &wgpu::Device,
        label: &str,
        size: u64,
        usage: wgpu::BufferUsages,
    ) -> (wgpu::Buffer, bool) {
        let found = self.free.lock().ok().and_then(|mut free| {
            let i = free.iter().position(|b| b.size() == size && b.usage() == usage)?;
            Some((free.swap_remove(i), false))
        });
        found.unwrap_or_else(|| {
            self.allocations.fetch_add(1, Relaxed);
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            });
            (buffer, true)
        })
    }

    /// Gives buffers back for the next frame.
    pub fn give_back(&self, buffers: impl IntoIterator<Item = wgpu::Buffer>) {
        if let Ok(mut free) = self.free.lock() {
            free.extend(buffers);
        }
    }
}
