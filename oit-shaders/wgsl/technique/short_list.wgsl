// A pixel's short list sorted in private arrays and composited: the resolve of the techniques that
// keep a list per pixel (fabs's slots, dfb's entries, ll's nodes) when it is at most SHORT_LIST
// long; a longer list is sorted in place by its technique. The includer says how its entries are
// reached, as for coverage.wgsl: `entry_key(e)` (depth bits << 32 | primitive id, one key per
// fragment, so the order is total), `entry_payload(e)` and `entry_next(e)`.
//
// The arrays are declared here, in a function the resolve calls for a list that is not empty, not
// in the resolve itself: WGSL gives every variable a value, so naga writes each function's
// variables with a zero initializer at the function's start, and a driver stores those zeros (768
// bytes) wherever the function runs. Declared in the resolve kernels, they were stored for every
// pixel of the frame, covered or not. No element is read before it is written (the insertion reads
// only below the list's end, and the push only what was inserted), so oit-vulkan's build script
// drops the initializers (`uninitialized_arrays`); wgpu compiles them in.

const SHORT_LIST: u32 = 64u;
const LIST_END: u32 = 0xffffffffu;

// Pushes into `s`, nearest first, the list of at most `n` entries that starts at entry `first`
// (fewer where `entry_next` gives LIST_END before). `farthest_first`: the list holds its entries
// mostly farthest first (each insertion then compares once; ll's lists, newest first), else
// mostly nearest first (fabs's slots and dfb's entries, in arrival order). Returns false, having
// pushed nothing, when the list is longer than SHORT_LIST.
fn push_short_list(s: ptr<function, PixelState>, first: u32, n: u32, farthest_first: bool) -> bool {
    var list: array<u64, SHORT_LIST>;
    var list_payloads: array<u32, SHORT_LIST>;
    var m = 0u;
    var e = first;
    while (m < n && e != LIST_END) {
        if (m == SHORT_LIST) {
            return false;
        }
        let v = entry_key(e);
        let p = entry_payload(e);
        // insertion: the list kept ascending (or descending, farthest first)
        var j = m;
        while (j > 0u && select(list[j - 1u] > v, list[j - 1u] < v, farthest_first)) {
            list[j] = list[j - 1u];
            list_payloads[j] = list_payloads[j - 1u];
            j -= 1u;
        }
        list[j] = v;
        list_payloads[j] = p;
        m += 1u;
        e = entry_next(e);
    }
    for (var i = 0u; i < m; i++) {
        var at = i;
        if (farthest_first) {
            at = m - 1u - i;
        }
        push_local(s, bitcast<f32>(u32(list[at] >> 32u)), list_payloads[at]);
    }
    return true;
}
