//! What the tests that run one WGSL kernel of their own over storage buffers share: a storage
//! binding's layout entry, and one dispatch of a kernel over `invocations` (workgroups of 64,
//! laid out by `oit_gpu::dispatch_size`), submitted.

/// A compute stage's storage-buffer binding.
pub fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Records and submits one dispatch of `pipeline` with `group` over `invocations` invocations.
pub fn dispatch(
    gpu: &oit_wgpu::Gpu,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    invocations: u64,
) {
    let (x, y) = oit_gpu::dispatch_size(invocations);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
    gpu.queue.submit([encoder.finish()]);
}
