//! Every SPIR-V module `build.rs` wrote, after its own rewrites (the image atomics' results, kbuf's
//! interlock), passes the Khronos validator `spirv-val` for Vulkan 1.2: naga validates the WGSL it
//! compiles, but nothing else checks the words `build.rs` changes afterwards, and a driver may
//! take a malformed module without a word. Without `spirv-val` (Debian's `spirv-tools`) the test
//! says so and passes; with `OIT_REQUIRE_GPU=1` (CI, which installs it) its absence fails.

use std::process::Command;

#[test]
fn every_module_passes_spirv_val() {
    let version = Command::new("spirv-val").arg("--version").output();
    if version.is_err() {
        assert!(
            !oit_vulkan::gpu_required(),
            "OIT_REQUIRE_GPU=1 but spirv-val is missing: apt-get install spirv-tools"
        );
        // to the stream itself: the test harness captures `eprintln!`
        use std::io::Write as _;
        let _ = writeln!(
            std::io::stderr(),
            "skipped every_module_passes_spirv_val: no spirv-val: `apt-get install spirv-tools` \
             (set OIT_REQUIRE_GPU=1 to make this a failure)"
        );
        return;
    }
    let dir = std::env::temp_dir().join(format!("oit-spirv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let mut checked = Vec::new();
    for (name, bytes, _) in oit_vulkan::spirv_modules() {
        let path = dir.join(format!("{name}.spv"));
        std::fs::write(&path, bytes).expect("write the module");
        let out =
            Command::new("spirv-val").args(["--target-env", "vulkan1.2"]).arg(&path).output().expect("run");
        assert!(
            out.status.success(),
            "{name}: spirv-val: {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        checked.push(name);
    }
    let _ = std::fs::remove_dir_all(&dir);
    // the rewritten modules are among them
    for rewritten in ["kbuf_hw", "fabs_image", "mdts_image", "mdts64_image"] {
        assert!(checked.contains(&rewritten), "{rewritten} not among the modules");
    }
}

/// kbuf's hardware module runs both fragment entry points in the ordered interlock: the
/// single-sample `hw_fs` and the multisampled `hw_fs_masked` (docs/msaa.md), each with the
/// execution mode `PixelInterlockOrderedEXT` and one begin and one end in its body; no other
/// module has the interlock.
#[test]
fn kbuf_interlocks_both_fragment_entry_points() {
    const ENTRY_POINT: u32 = 15;
    const EXECUTION_MODE: u32 = 16;
    const FUNCTION: u32 = 54;
    const FUNCTION_END: u32 = 56;
    const BEGIN: u32 = 5364;
    const END: u32 = 5365;
    const ORDERED: u32 = 5366;
    for (name, bytes, _) in oit_vulkan::spirv_modules() {
        let words: Vec<u32> = bytes.chunks(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        // (opcode, operands) of each instruction after the header
        let mut list = Vec::new();
        let mut at = 5;
        while at < words.len() {
            let count = (words[at] >> 16) as usize;
            assert!(count > 0, "{name}: malformed at word {at}");
            list.push((words[at] & 0xffff, &words[at + 1..at + count]));
            at += count;
        }
        let entry = |wanted: &str| {
            list.iter().find_map(|&(o, w)| {
                let text: Vec<u8> = w.get(2..)?.iter().flat_map(|x| x.to_le_bytes()).collect();
                let text = text.split(|&b| b == 0).next()?;
                (o == ENTRY_POINT && text == wanted.as_bytes()).then_some(w[1])
            })
        };
        let ordered: Vec<u32> = list
            .iter()
            .filter(|&&(o, w)| o == EXECUTION_MODE && w[1] == ORDERED)
            .map(|&(_, w)| w[0])
            .collect();
        // (begins, ends) in function `f`'s body
        let section = |f: u32| {
            let mut inside = false;
            let (mut begins, mut ends) = (0, 0);
            for &(o, w) in &list {
                match o {
                    FUNCTION => inside = w[1] == f,
                    FUNCTION_END => inside = false,
                    BEGIN if inside => begins += 1,
                    END if inside => ends += 1,
                    _ => {}
                }
            }
            (begins, ends)
        };
        if name != "kbuf_hw" {
            assert!(ordered.is_empty(), "{name}: an interlock outside kbuf");
            continue;
        }
        for wanted in ["hw_fs", "hw_fs_masked"] {
            let f = entry(wanted).unwrap_or_else(|| panic!("{name}: no entry point {wanted}"));
            assert!(ordered.contains(&f), "{name}: {wanted} without PixelInterlockOrderedEXT");
            assert_eq!(section(f), (1, 1), "{name}: {wanted}'s (begins, ends) of the interlock");
        }
    }
}
