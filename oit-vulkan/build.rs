//! Compiles the GPU shader tree to SPIR-V with naga, at build time, so a shader error fails the
//! build.
//!
//! The modules and their texts are oit-shaders' (`oit_shaders::MODULES`, the one manifest oit-wgpu
//! builds its pipelines from at run time): `Module::compute_text` for each, and for a module
//! with a rasterizer also its hardware-raster twin, `Module::hardware_text`, as `<module>_hw`
//! (entry points `hw_vs`, `hw_fs` and the multisampled `hw_fs_masked`). One SPIR-V module per name holds every entry point: the
//! rasterizer's (`raster_main`, `raster_loop_main`) and the technique's kernels. What only raw
//! Vulkan needs is done here, on the SPIR-V: the image atomics' results (`atomic_results`), the
//! ordered interlock (`interlock`) and `sample_mask` as the array Vulkan requires
//! (`sample_mask_arrays`).
//!
//! naga as wgpu-hal's Vulkan backend sets it up: explicit validator capabilities (64-bit integers
//! and 64-bit atomics; naga's default has neither), `ADJUST_COORDINATE_SPACE` off (wgpu's
//! convention: the hardware path will flip with a negative viewport height), restricted bounds
//! checks, bounded loops, polyfilled workgroup zeroing. SPIR-V 1.3 (Vulkan 1.1 and later).

use std::path::PathBuf;

/// Hardware-raster modules whose fragment entry points run in an ordered interlock
/// ([`interlock`]): the single-sample `hw_fs` and the multisampled `hw_fs_masked` (docs/msaa.md).
const INTERLOCKED: &[&str] = &["kbuf_hw"];

/// Functions whose private arrays [`uninitialized_arrays`] leaves without WGSL's zero initializer:
/// each is an insertion sort that writes an element before it reads it (oit-shaders'
/// technique/short_list.wgsl and plain.wgsl say so where they declare them).
const WRITTEN_FIRST: &[&str] = &["push_short_list", "plain_push_short"];

/// The fragment entry points of an [`INTERLOCKED`] module that [`interlock`] wraps.
const INTERLOCKED_ENTRIES: &[&str] = &["hw_fs", "hw_fs_masked"];

/// SPIR-V opcodes (and the two operand values) `atomic_results` and `interlock` read and write.
mod op {
    pub const NAME: u32 = 5;
    pub const LINE: u32 = 8;
    pub const EXTENSION: u32 = 10;
    pub const ENTRY_POINT: u32 = 15;
    pub const EXECUTION_MODE: u32 = 16;
    pub const CAPABILITY: u32 = 17;
    pub const TYPE_ARRAY: u32 = 28;
    pub const TYPE_POINTER: u32 = 32;
    pub const FUNCTION: u32 = 54;
    pub const FUNCTION_END: u32 = 56;
    pub const FUNCTION_CALL: u32 = 57;
    pub const VARIABLE: u32 = 59;
    pub const IMAGE_TEXEL_POINTER: u32 = 60;
    pub const COPY_OBJECT: u32 = 83;
    /// OpAtomicExchange ..= OpAtomicXor (229 ..= 242): every atomic with a result and a pointer
    /// at word 3.
    pub const ATOMICS: std::ops::RangeInclusive<u32> = 229..=242;
    pub const LABEL: u32 = 248;
    pub const KILL: u32 = 252;
    pub const RETURN: u32 = 253;
    pub const RETURN_VALUE: u32 = 254;
    pub const NO_LINE: u32 = 317;
    pub const TERMINATE_INVOCATION: u32 = 4416;
    pub const BEGIN_INTERLOCK: u32 = 5364;
    pub const END_INTERLOCK: u32 = 5365;
    /// Execution mode `PixelInterlockOrderedEXT`.
    pub const PIXEL_INTERLOCK_ORDERED: u32 = 5366;
    /// Capability `FragmentShaderPixelInterlockEXT`.
    pub const PIXEL_INTERLOCK_CAPABILITY: u32 = 5378;
}

/// Words of a SPIR-V module's header, before its first instruction.
const HEADER: usize = 5;

/// SPIR-V's `Function` storage class (a function's own variables).
const STORAGE_FUNCTION: u32 = 7;

/// A module's instructions: (first word, opcode, word count) each; fails on a malformed one.
fn instructions(words: &[u32]) -> Result<Vec<(usize, u32, usize)>, String> {
    let mut at = HEADER;
    let mut out = Vec::new();
    while at < words.len() {
        let count = (words[at] >> 16) as usize;
        if count == 0 || at + count > words.len() {
            return Err(format!("malformed SPIR-V at word {at}"));
        }
        out.push((at, words[at] & 0xffff, count));
        at += count;
    }
    Ok(out)
}

/// A literal string operand (nul-terminated UTF-8 in little-endian words), without its nul.
fn literal(words: &[u32]) -> Vec<u8> {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    bytes.split(|&b| b == 0).next().unwrap_or_default().to_vec()
}

/// The most bytes an entry point's private arrays may take. WGSL gives every variable a value, so
/// naga writes each function variable with a zero initializer at its function's start, and a
/// driver stores the zeros wherever the function runs: in an entry point, in every invocation. On
/// an H100 the 768 bytes of a 64-entry list in the per-pixel resolves (fabs, dfb, ll) cost their
/// frames about 0.3 ms at 1024², list or no list; declared in a function that the pixels with a
/// list call (`push_short_list`, oit-shaders' technique/short_list.wgsl), only those pay.
const ENTRY_ARRAY_BYTES: u32 = 256;

/// Fails on an entry point of `module` that declares an array variable of more than `limit` bytes
/// (see [`ENTRY_ARRAY_BYTES`]), naming it.
fn entry_arrays(module: &naga::Module, limit: u32) -> Result<(), String> {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).map_err(|e| format!("type layout: {e}"))?;
    for entry in &module.entry_points {
        for (_, var) in entry.function.local_variables.iter() {
            let ty = &module.types[var.ty];
            let bytes = layouter[var.ty].size;
            if matches!(ty.inner, naga::TypeInner::Array { .. }) && bytes > limit {
                return Err(format!(
                    "entry point {} declares `{}`, an array of {bytes} bytes: every invocation stores its \
                     zero initializer; declare it in a function called where it is needed",
                    entry.name,
                    var.name.as_deref().unwrap_or("?"),
                ));
            }
        }
    }
    Ok(())
}

/// Rewrites every call of `vk_atomic_result` / `vk_atomic_result64` (oit-shaders' wgsl/core/atomic_result.wgsl)
/// into `OpCopyObject` of the result of the image atomic just before it in the same block (an
/// `OpAtomic*` on a pointer from `OpImageTexelPointer`), so WGSL's result-less `textureAtomic*`
/// give the texel's old value, as GLSL's `imageAtomic*` do. Returns the calls rewritten; fails
/// on a call with arguments, one with no image atomic before it in its block, or one whose type
/// differs from the atomic's. The words keep their length (both instructions are 4 words).
fn atomic_results(words: &mut [u32]) -> Result<usize, String> {
    let list = instructions(words)?;
    let mut markers = Vec::new();
    for &(at, opcode, count) in &list {
        if opcode == op::NAME && count >= 3 {
            let name = literal(&words[at + 2..at + count]);
            if name == b"vk_atomic_result" || name == b"vk_atomic_result64" {
                markers.push(words[at + 1]);
            }
        }
    }
    if markers.is_empty() {
        return Ok(0);
    }
    let mut texel_pointers = std::collections::HashSet::new();
    // (result type, result id) of the last image atomic of the current block
    let mut last: Option<(u32, u32)> = None;
    let mut copied = 0;
    for &(at, opcode, count) in &list {
        match opcode {
            op::FUNCTION | op::LABEL => last = None,
            op::IMAGE_TEXEL_POINTER => {
                texel_pointers.insert(words[at + 2]);
            }
            o if op::ATOMICS.contains(&o) && count >= 4 && texel_pointers.contains(&words[at + 3]) => {
                last = Some((words[at + 1], words[at + 2]));
            }
            op::FUNCTION_CALL if count >= 4 && markers.contains(&words[at + 3]) => {
                if count != 4 {
                    return Err(format!("a call of an atomic-result marker with arguments at word {at}"));
                }
                let Some((ty, result)) = last.take() else {
                    return Err(format!(
                        "a call of an atomic-result marker at word {at} with no image atomic before it in its block"
                    ));
                };
                if ty != words[at + 1] {
                    return Err(format!(
                        "an atomic-result marker at word {at} of another type than its atomic"
                    ));
                }
                words[at] = (4 << 16) | op::COPY_OBJECT;
                words[at + 3] = result;
                copied += 1;
            }
            _ => {}
        }
    }
    Ok(copied)
}

/// Puts each fragment entry point of `entries` whole body in `VK_EXT_fragment_shader_interlock`'s
/// ordered per-pixel critical section, which WGSL cannot express: the capability
/// `FragmentShaderPixelInterlockEXT` and the extension (once), the execution mode
/// `PixelInterlockOrderedEXT` for each entry, `OpBeginInvocationInterlockEXT` after the entry's
/// first block's variables and `OpEndInvocationInterlockEXT` before its one return, so each is
/// executed once, in the entry function's outermost control flow (the shape GLSL's
/// `beginInvocationInterlockARB` requires). Fails on an entry missing, one with no body, more than
/// one return, or a discard (a fragment discarded inside the section would never end it).
fn interlock(words: &[u32], entries: &[&str]) -> Result<Vec<u32>, String> {
    let list = instructions(words)?;
    let functions = entries
        .iter()
        .map(|entry| {
            list.iter()
                .find(|&&(at, o, count)| {
                    o == op::ENTRY_POINT
                        && count >= 4
                        && literal(&words[at + 3..at + count]) == entry.as_bytes()
                })
                .map(|&(at, _, _)| words[at + 2])
                .ok_or_else(|| format!("no entry point '{entry}'"))
        })
        .collect::<Result<Vec<u32>, String>>()?;
    let last_of = |o: u32| list.iter().rposition(|&(_, x, _)| x == o);
    let capability_at = last_of(op::CAPABILITY).ok_or("no OpCapability")?;
    let mode_at = last_of(op::EXECUTION_MODE).or(last_of(op::ENTRY_POINT)).ok_or("no OpEntryPoint")?;
    let extension: Vec<u32> = {
        let mut bytes = b"SPV_EXT_fragment_shader_interlock".to_vec();
        bytes.resize(bytes.len() / 4 * 4 + 4, 0);
        let text: Vec<u32> = bytes.chunks(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        let mut w = vec![((text.len() as u32 + 1) << 16) | op::EXTENSION];
        w.extend(text);
        w
    };
    let mut out = words[..HEADER].to_vec();
    // per entry: body begun, returns
    let mut seen = vec![(false, 0); entries.len()];
    let mut in_entry: Option<usize> = None;
    for (i, &(at, o, count)) in list.iter().enumerate() {
        if let Some(e) = in_entry {
            let (begun, returns) = &mut seen[e];
            if !*begun && !matches!(o, op::LABEL | op::VARIABLE | op::LINE | op::NO_LINE) {
                out.push((1 << 16) | op::BEGIN_INTERLOCK);
                *begun = true;
            }
            match o {
                op::RETURN | op::RETURN_VALUE => {
                    out.push((1 << 16) | op::END_INTERLOCK);
                    *returns += 1;
                }
                op::KILL | op::TERMINATE_INVOCATION => {
                    return Err(format!("'{}' discards inside its interlocked body", entries[e]));
                }
                op::FUNCTION_END => in_entry = None,
                _ => {}
            }
        }
        if o == op::FUNCTION && count >= 3 {
            in_entry = functions.iter().position(|&f| f == words[at + 2]);
        }
        out.extend_from_slice(&words[at..at + count]);
        if i == capability_at {
            out.extend([(2 << 16) | op::CAPABILITY, op::PIXEL_INTERLOCK_CAPABILITY]);
            out.extend(&extension);
        }
        if i == mode_at {
            for &function in &functions {
                out.extend([(3 << 16) | op::EXECUTION_MODE, function, op::PIXEL_INTERLOCK_ORDERED]);
            }
        }
    }
    for (entry, &(begun, returns)) in entries.iter().zip(&seen) {
        if !begun || returns != 1 {
            return Err(format!("'{entry}': {returns} returns (one is needed), body begun: {begun}"));
        }
    }
    Ok(out)
}

/// Drops the zero initializer (WGSL's default value, which naga writes as `OpConstantNull`) of
/// every array variable declared in a function named in `functions`, whose code writes each
/// element before reading it, so the driver stores no zeros first. Returns the module and the
/// variables rewritten. On an H100 the initializers of `push_short_list`'s two arrays (768 bytes)
/// cost the resolves of fabs, dfb and ll about 0.1 ms of a walled `planes:64` frame at 1024² and
/// 0.15 ms on `cad`, where without them the resolve takes 0.05 ms
/// (bench/results/h100/short-list-1024). wgpu compiles WGSL itself, with the initializers: there,
/// only the pixels that call the function pay for them.
fn uninitialized_arrays(words: &[u32], functions: &[&str]) -> Result<(Vec<u32>, usize), String> {
    let list = instructions(words)?;
    let mut named = std::collections::HashSet::new();
    let mut arrays = std::collections::HashSet::new();
    // the pointer types to arrays in the Function storage class
    let mut array_pointers = std::collections::HashSet::new();
    for &(at, opcode, count) in &list {
        match opcode {
            op::NAME if count >= 3 => {
                let name = literal(&words[at + 2..at + count]);
                if functions.iter().any(|f| f.as_bytes() == name) {
                    named.insert(words[at + 1]);
                }
            }
            op::TYPE_ARRAY if count >= 2 => {
                arrays.insert(words[at + 1]);
            }
            op::TYPE_POINTER
                if count == 4 && words[at + 2] == STORAGE_FUNCTION && arrays.contains(&words[at + 3]) =>
            {
                array_pointers.insert(words[at + 1]);
            }
            _ => {}
        }
    }
    let mut out = words[..HEADER].to_vec();
    let mut inside = false;
    let mut rewritten = 0;
    for &(at, opcode, count) in &list {
        match opcode {
            op::FUNCTION if count >= 3 => inside = named.contains(&words[at + 2]),
            op::FUNCTION_END => inside = false,
            _ => {}
        }
        if inside
            && opcode == op::VARIABLE
            && count == 5
            && words[at + 3] == STORAGE_FUNCTION
            && array_pointers.contains(&words[at + 1])
        {
            out.push((4 << 16) | op::VARIABLE);
            out.extend_from_slice(&words[at + 1..at + 4]);
            rewritten += 1;
        } else {
            out.extend_from_slice(&words[at..at + count]);
        }
    }
    Ok((out, rewritten))
}

/// naga declares WGSL's `@builtin(sample_mask)` (the multisampled hardware raster's
/// `hw_fs_masked`) as a scalar `u32` variable (gfx-rs/wgpu issue 7311), where Vulkan requires an
/// array of 32-bit integers (VUID-SampleMask-SampleMask-04359; drivers may misread a scalar).
/// Rewrites each variable decorated `BuiltIn SampleMask` into an array of one, and each load and
/// store of it into one through an access chain to element 0. Returns the module and the
/// variables rewritten; fails on any other use of such a variable in a function.
fn sample_mask_arrays(words: &[u32]) -> Result<(Vec<u32>, usize), String> {
    const DECORATE: u32 = 71;
    const BUILT_IN: u32 = 11;
    const SAMPLE_MASK: u32 = 20;
    const TYPE_INT: u32 = 21;
    use op::{TYPE_ARRAY, TYPE_POINTER};
    const CONSTANT: u32 = 43;
    const LOAD: u32 = 61;
    const STORE: u32 = 62;
    const ACCESS_CHAIN: u32 = 65;
    let list = instructions(words)?;
    let masks: Vec<u32> = list
        .iter()
        .filter(|&&(at, o, count)| {
            o == DECORATE && count == 4 && words[at + 2] == BUILT_IN && words[at + 3] == SAMPLE_MASK
        })
        .map(|&(at, _, _)| words[at + 1])
        .collect();
    if masks.is_empty() {
        return Ok((words.to_vec(), 0));
    }
    let find = |opcode: u32, result_at: usize, id: u32| {
        list.iter()
            .find(|&&(at, o, count)| o == opcode && count > result_at && words[at + result_at] == id)
            .copied()
    };
    let mut bound = words[3];
    // per variable: (variable, its scalar pointer type, storage class, integer type, constant 0,
    // constant 1, the array type, the pointer to it)
    let mut plans = Vec::new();
    for &var in &masks {
        let (at, _, _) = find(op::VARIABLE, 2, var).ok_or(format!("no OpVariable %{var}"))?;
        let (pointer, storage) = (words[at + 1], words[at + 3]);
        let (pt, _, _) = find(TYPE_POINTER, 1, pointer).ok_or(format!("no pointer type %{pointer}"))?;
        let int = words[pt + 3];
        let (it, _, _) = find(TYPE_INT, 1, int).ok_or(format!("%{var} is no integer"))?;
        if words[it + 2] != 32 {
            return Err(format!("%{var} is not a 32-bit integer"));
        }
        plans.push((var, pointer, storage, int, bound, bound + 1, bound + 2, bound + 3));
        bound += 4;
    }
    let mut out = words[..HEADER].to_vec();
    let mut in_function = false;
    for &(at, o, count) in &list {
        let ins = &words[at..at + count];
        if o == op::FUNCTION {
            in_function = true;
        }
        if o == op::VARIABLE
            && let Some(&(_, _, storage, int, zero, one, array, array_ptr)) =
                plans.iter().find(|p| p.0 == ins[2])
        {
            out.extend([(4 << 16) | CONSTANT, int, zero, 0]);
            out.extend([(4 << 16) | CONSTANT, int, one, 1]);
            out.extend([(4 << 16) | TYPE_ARRAY, array, int, one]);
            out.extend([(4 << 16) | TYPE_POINTER, array_ptr, storage, array]);
            out.extend([ins[0], array_ptr, ins[2]]);
            out.extend(&ins[3..]);
            continue;
        }
        if in_function {
            // the pointer operand of a load (word 3) or a store (word 1)
            let pointer_at = match o {
                LOAD => Some(3),
                STORE => Some(1),
                _ => None,
            };
            if let Some(k) = pointer_at
                && let Some(&(var, pointer, _, _, zero, ..)) = plans.iter().find(|p| p.0 == ins[k])
            {
                let element = bound;
                bound += 1;
                out.extend([(5 << 16) | ACCESS_CHAIN, pointer, element, var, zero]);
                let mut rewritten = ins.to_vec();
                rewritten[k] = element;
                out.extend(rewritten);
                continue;
            }
            if let Some(p) = plans.iter().find(|p| ins[1..].contains(&p.0)) {
                return Err(format!("%{} (a SampleMask) used by opcode {o}, which is not rewritten", p.0));
            }
        }
        out.extend_from_slice(ins);
    }
    out[3] = bound;
    Ok((out, masks.len()))
}

fn main() {
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it"));

    use naga::back::spv;
    use naga::valid::{Capabilities, ValidationFlags, Validator};
    let capabilities = Capabilities::SHADER_INT64
        | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX
        | Capabilities::SHADER_INT64_ATOMIC_ALL_OPS
        | Capabilities::TEXTURE_ATOMIC
        | Capabilities::TEXTURE_INT64_ATOMIC
        // `hw_fs_early`'s `@early_depth_test(force)` (SPIR-V's EarlyFragmentTests)
        | Capabilities::EARLY_DEPTH_TEST;
    let mut flags = spv::WriterFlags::empty();
    flags.set(spv::WriterFlags::DEBUG, true);
    flags.set(spv::WriterFlags::ADJUST_COORDINATE_SPACE, false);
    let options = spv::Options {
        lang_version: (1, 3),
        flags,
        capabilities: Some(
            [
                spv::Capability::Shader,
                spv::Capability::Int64,
                spv::Capability::Int64Atomics,
                // the bounds checks of the blend captures' textureLoad
                spv::Capability::ImageQuery,
                // R64_UINT storage images (mdts64_image only; naga asks for it where one is
                // declared, and the backend runs that module only where the device has it)
                spv::Capability::Int64ImageEXT,
            ]
            .into_iter()
            .collect(),
        ),
        bounds_check_policies: naga::proc::BoundsCheckPolicies {
            index: naga::proc::BoundsCheckPolicy::Restrict,
            buffer: naga::proc::BoundsCheckPolicy::Restrict,
            image_load: naga::proc::BoundsCheckPolicy::Restrict,
            binding_array: naga::proc::BoundsCheckPolicy::Unchecked,
        },
        zero_initialize_workgroup_memory: spv::ZeroInitializeWorkgroupMemoryMode::Polyfill,
        force_loop_bounding: true,
        ..spv::Options::default()
    };
    let mut index = String::from("// generated by build.rs: the SPIR-V of each module\n");
    let mut emit = |name: &str, text: &str| {
        let module = naga::front::wgsl::parse_str(text)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(text)));
        let info = Validator::new(ValidationFlags::all(), capabilities)
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(text)));
        if let Err(e) = entry_arrays(&module, ENTRY_ARRAY_BYTES) {
            panic!("{name}: {e}");
        }
        let mut words =
            spv::write_vec(&module, &info, &options, None).unwrap_or_else(|e| panic!("{name}: SPIR-V: {e}"));
        let copied = atomic_results(&mut words).unwrap_or_else(|e| panic!("{name}: {e}"));
        if text.contains("vk_atomic_result") && text.contains("textureAtomic") && copied == 0 {
            panic!("{name}: calls vk_atomic_result but no call was rewritten");
        }
        if INTERLOCKED.contains(&name) {
            words = interlock(&words, INTERLOCKED_ENTRIES).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
        let (arrays, rewritten) = sample_mask_arrays(&words).unwrap_or_else(|e| panic!("{name}: {e}"));
        if text.contains("@builtin(sample_mask)") && rewritten == 0 {
            panic!("{name}: uses sample_mask but no SampleMask variable was rewritten");
        }
        words = arrays;
        // each function the module declares, one at a time, so that every one is held to a rewrite
        for f in WRITTEN_FIRST.iter().filter(|f| text.contains(&format!("fn {f}("))) {
            let (arrays, rewritten) =
                uninitialized_arrays(&words, &[f]).unwrap_or_else(|e| panic!("{name}: {e}"));
            if rewritten == 0 {
                panic!("{name}: declares {f} but no array of it lost its initializer");
            }
            words = arrays;
        }
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        std::fs::write(out.join(format!("{name}.spv")), bytes).expect("write SPIR-V");
        let entries: Vec<String> = module.entry_points.iter().map(|e| format!("{:?}", e.name)).collect();
        index.push_str(&format!(
            "(\"{name}\", include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{name}.spv\")), &[{}]),\n",
            entries.join(", ")
        ));
    };
    for module in oit_shaders::MODULES {
        emit(module.name, &module.compute_text());
        if let Some(hardware) = module.hardware_text() {
            emit(&format!("{}_hw", module.name), &hardware);
        }
    }
    std::fs::write(out.join("modules.rs"), format!("&[\n{index}]\n")).expect("write the module index");
}
