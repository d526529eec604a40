// wboit: weighted blended OIT (McGuire & Bavoil, JCGT 2013), as oit-cpu's `technique/wboit.rs`:
// one geometry pass adds, per pixel, Σα·w·r, Σα·w·g, Σα·w·b, Σα·w (w: the depth weight of the
// paper's eq. 10 in hundredths, `wboit_weight`), the optical depth Σ−ln(1 − α) (in 1/65536, from
// the table below: the paper's revealage Π(1 − α) as a sum) and the count, as u64 integers of the
// RGBA8 colour, so the sums do not depend on arrival order; the composite kernel writes the final
// linear colour into the resolve state (front colour, zero transmittance, captured = count).
@group(0) @binding(2) var<storage, read_write> wb_sums: array<atomic<u64>>;

// oit_core::rules::WBOIT_OPTICAL_DEPTH, entry for entry (oit-gpu's tests compare the two)
const WBOIT_OPTICAL_DEPTH = array<u32, 256>(
    0u, 258u, 516u, 776u, 1036u, 1298u, 1560u, 1824u,
    2089u, 2355u, 2622u, 2890u, 3159u, 3429u, 3701u, 3973u,
    4247u, 4522u, 4797u, 5075u, 5353u, 5632u, 5913u, 6195u,
    6478u, 6762u, 7048u, 7335u, 7623u, 7912u, 8203u, 8495u,
    8788u, 9082u, 9378u, 9675u, 9974u, 10274u, 10575u, 10878u,
    11182u, 11488u, 11795u, 12103u, 12413u, 12724u, 13037u, 13351u,
    13667u, 13985u, 14303u, 14624u, 14946u, 15270u, 15595u, 15922u,
    16250u, 16580u, 16912u, 17246u, 17581u, 17918u, 18257u, 18597u,
    18939u, 19283u, 19629u, 19977u, 20326u, 20678u, 21031u, 21386u,
    21743u, 22102u, 22464u, 22827u, 23192u, 23559u, 23928u, 24299u,
    24673u, 25048u, 25426u, 25806u, 26188u, 26573u, 26959u, 27348u,
    27739u, 28133u, 28529u, 28927u, 29328u, 29732u, 30137u, 30546u,
    30957u, 31370u, 31786u, 32205u, 32626u, 33051u, 33477u, 33907u,
    34340u, 34775u, 35214u, 35655u, 36099u, 36547u, 36997u, 37451u,
    37907u, 38367u, 38830u, 39297u, 39767u, 40240u, 40716u, 41196u,
    41680u, 42167u, 42658u, 43153u, 43651u, 44154u, 44660u, 45170u,
    45684u, 46202u, 46724u, 47250u, 47781u, 48316u, 48855u, 49399u,
    49948u, 50501u, 51058u, 51621u, 52188u, 52761u, 53338u, 53921u,
    54508u, 55102u, 55700u, 56304u, 56914u, 57529u, 58150u, 58777u,
    59411u, 60050u, 60696u, 61348u, 62006u, 62672u, 63344u, 64023u,
    64709u, 65403u, 66104u, 66812u, 67529u, 68253u, 68985u, 69726u,
    70474u, 71232u, 71999u, 72774u, 73559u, 74353u, 75158u, 75972u,
    76796u, 77631u, 78477u, 79333u, 80201u, 81081u, 81973u, 82877u,
    83793u, 84723u, 85666u, 86623u, 87594u, 88579u, 89580u, 90596u,
    91628u, 92676u, 93742u, 94825u, 95927u, 97047u, 98187u, 99347u,
    100528u, 101730u, 102955u, 104204u, 105476u, 106774u, 108098u, 109449u,
    110829u, 112238u, 113679u, 115152u, 116658u, 118200u, 119780u, 121398u,
    123057u, 124759u, 126507u, 128303u, 130149u, 132049u, 134005u, 136022u,
    138102u, 140251u, 142473u, 144773u, 147156u, 149630u, 152200u, 154875u,
    157664u, 160578u, 163626u, 166824u, 170185u, 173729u, 177475u, 181448u,
    185677u, 190199u, 195056u, 200301u, 206004u, 212250u, 219155u, 226874u,
    235625u, 245727u, 257676u, 272300u, 291154u, 317726u, 363152u, 2097152u,
);

// oit_core::rules::wboit_weight: max(1, 300000·q³/1023³) with q = 1023 − ⌊d·1024⌋
fn wboit_weight(depth: f32) -> u64 {
    let d = min(bitcast<f32>(depth_bits(depth)), 1.0);
    let q = u64(1023u - min(u32(d * 1024.0), 1023u));
    return max(300000lu * q * q * q / 1070599167lu, 1lu);
}

fn capture(f: Fragment) {
    let c = pack_rgba8(f.color);
    let a = c >> 24u;
    let aw = u64(a) * wboit_weight(f.depth);
    let base = f.pixel * 6u;
    atomicAdd(&wb_sums[base], aw * u64(c & 0xffu));
    atomicAdd(&wb_sums[base + 1u], aw * u64((c >> 8u) & 0xffu));
    atomicAdd(&wb_sums[base + 2u], aw * u64((c >> 16u) & 0xffu));
    atomicAdd(&wb_sums[base + 3u], aw);
    atomicAdd(&wb_sums[base + 4u], u64(WBOIT_OPTICAL_DEPTH[a]));
    atomicAdd(&wb_sums[base + 5u], 1lu);
}

// oit_core::composite::wboit: the weighted mean colour under the exact coverage
@compute @workgroup_size(64)
fn composite_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let px = kernel_pixel(gid, groups);
    if (px >= fu.pixel_count) {
        return;
    }
    let base = px * 6u;
    let count = u32(atomicLoad(&wb_sums[base + 5u]));
    let weight = f32(atomicLoad(&wb_sums[base + 3u]));
    let bg = fu.background.xyz;
    var c = bg;
    if (count > 0u && weight > 0.0) {
        let weighted = vec3<f32>(
            f32(atomicLoad(&wb_sums[base])),
            f32(atomicLoad(&wb_sums[base + 1u])),
            f32(atomicLoad(&wb_sums[base + 2u])),
        );
        let mean = weighted / (weight * 255.0);
        let t = exp(-(f32(atomicLoad(&wb_sums[base + 4u])) / 65536.0));
        c = mean * (1.0 - t) + bg * t;
    }
    var s = state[px];
    s.fr = c.x;
    s.fg = c.y;
    s.fb = c.z;
    s.transmittance = 0.0;
    s.captured = count;
    state[px] = s;
}
