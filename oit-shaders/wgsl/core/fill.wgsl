// module fill (kernels): core/fill.wgsl
// Fills a buffer with one 32-bit pattern (param), 64 words per invocation-group row.
@group(0) @binding(2) var<storage, read_write> target_words: array<u32>;

@compute @workgroup_size(64)
fn fill_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = kernel_pixel(gid, groups);
    if (i < arrayLength(&target_words)) {
        target_words[i] = fu.param;
    }
}
