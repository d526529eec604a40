//! Mutations: byte-level (bit flips, insertions, deletions, copies, splices with another input)
//! and token-level (an OBJ file's lines and numbers, a scene expression's `:`-separated parts, an
//! argument list's arguments), each drawing on a dictionary of the values that broke oit before
//! (issue 13) and the edges of every range it checks.

use crate::Target;
use crate::dictionary::{NUMBERS, Rng, SCENE_WORDS, Vocabulary, values};

/// Words of OBJ files: the element keywords tobj reads and the ones it skips, and corner forms.
const OBJ_WORDS: &[&str] = &[
    "v",
    "vt",
    "vn",
    "vp",
    "f",
    "l",
    "p",
    "o",
    "g",
    "s",
    "off",
    "usemtl",
    "mtllib",
    "#",
    "\\",
    "1/1/1",
    "1//1",
    "-1/-1",
    "//",
    "/",
    "0",
    "-1",
    "-4",
    "2/",
    "1/2/3/4",
    "\t",
    "\r",
    "\n",
    "f 1 2 3\n",
    "v 0 0 0\n",
    "l 1 2\n",
    "p 1\n",
    "vn 0 0 1\n",
    "vt 0 0\n",
    "mtllib nosuch.mtl\n",
    "o x\n",
];

/// The dictionary of `target`.
fn words(target: Target) -> &'static [&'static str] {
    match target {
        Target::Obj => OBJ_WORDS,
        Target::Scene => SCENE_WORDS,
        Target::Args => {
            &["--", "-", "--help", "-h", "--version", "=", "render", "compare", "sweep", "info", "bench"]
        }
        Target::Selftest => &[],
        Target::Gltf => &[
            "\"count\":",
            "\"byteOffset\":",
            "\"byteStride\":4,",
            "\"sparse\":{},",
            "\"children\":[0],",
            "\"uri\":\"missing.bin\",",
            "glTF",
            "JSON",
            "BIN\0",
            "5126",
            "4294967295",
        ],
    }
}

/// Mutates `input` in place by one to four random edits, within `max_len` bytes; `other` is
/// another input of the same target, for splices.
pub fn mutate(
    rng: &mut Rng,
    target: Target,
    input: &mut Vec<u8>,
    other: &[u8],
    max_len: usize,
    args: &Vocabulary,
) {
    let rounds = 1 + rng.below(4);
    // a glTF file's byte edits mostly break its JSON: one edit in four, the rest the format's own
    let bytes = if target == Target::Gltf { 4 } else { 2 };
    for _ in 0..rounds {
        if rng.one_in(bytes) {
            byte_edit(rng, target, input, other);
        } else {
            match target {
                Target::Obj => obj_edit(rng, input),
                Target::Scene => scene_edit(rng, input),
                Target::Args => args_edit(rng, input, args),
                Target::Selftest => {}
                Target::Gltf => crate::gltf::edit(rng, input),
            }
        }
    }
    input.truncate(max_len);
}

/// A random range of `len` bytes (possibly empty).
fn range(rng: &mut Rng, len: usize) -> (usize, usize) {
    let start = rng.below(len + 1);
    let end = start + rng.below((len - start).min(64) + 1);
    (start, end)
}

/// One byte-level edit.
fn byte_edit(rng: &mut Rng, target: Target, input: &mut Vec<u8>, other: &[u8]) {
    let len = input.len();
    match rng.below(9) {
        0 if len > 0 => {
            let i = rng.below(len);
            input[i] ^= 1 << rng.below(8);
        }
        1 if len > 0 => {
            let i = rng.below(len);
            input[i] = *rng.pick(b"\n \t:x,-+./e09\x00\xff\xc3");
        }
        2 => {
            let at = rng.below(len + 1);
            let n = 1 + rng.below(8);
            input.splice(at..at, rng.bytes(n));
        }
        3 => {
            let (a, b) = range(rng, len);
            input.drain(a..b);
        }
        4 => {
            // copy a range somewhere else (repeats lines, faces, nested grids)
            let (a, b) = range(rng, len);
            let piece = input[a..b].to_vec();
            let at = rng.below(len + 1);
            input.splice(at..at, piece);
        }
        5 => {
            // splice in a piece of another input
            let (a, b) = range(rng, other.len());
            let at = rng.below(len + 1);
            input.splice(at..at, other[a..b].iter().copied());
        }
        6 if !words(target).is_empty() => {
            let at = rng.below(len + 1);
            let word = rng.pick(words(target)).as_bytes();
            input.splice(at..at, word.iter().copied());
        }
        7 => replace_number(rng, input),
        _ => {
            let at = rng.below(len + 1);
            input.truncate(at);
        }
    }
}

/// Replaces one run of number-like bytes (digits, signs, dots, exponents) by a number of
/// [`NUMBERS`]; inserts one where there is none.
fn replace_number(rng: &mut Rng, input: &mut Vec<u8>) {
    let is_num = |b: u8| b.is_ascii_digit() || b == b'.' || b == b'-' || b == b'+' || b == b'e';
    let starts: Vec<usize> =
        (0..input.len()).filter(|&i| is_num(input[i]) && (i == 0 || !is_num(input[i - 1]))).collect();
    let new = rng.pick(NUMBERS).as_bytes().to_vec();
    if starts.is_empty() {
        let at = rng.below(input.len() + 1);
        input.splice(at..at, new);
        return;
    }
    let start = *rng.pick(&starts);
    let end = (start..input.len()).find(|&i| !is_num(input[i])).unwrap_or(input.len());
    input.splice(start..end, new);
}

/// Splits `input` into its lines (without the newlines).
fn lines(input: &[u8]) -> Vec<Vec<u8>> {
    input.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect()
}

fn join(parts: &[Vec<u8>], sep: u8) -> Vec<u8> {
    let mut out = Vec::new();
    for (i, p) in parts.iter().enumerate() {
        if i > 0 {
            out.push(sep);
        }
        out.extend_from_slice(p);
    }
    out
}

/// One edit of an OBJ file by its lines and words.
fn obj_edit(rng: &mut Rng, input: &mut Vec<u8>) {
    let mut ls = lines(input);
    let n = ls.len();
    let i = rng.below(n);
    match rng.below(8) {
        0 => {
            let copy = ls[i].clone();
            ls.insert(rng.below(n + 1), copy);
        }
        1 if n > 1 => {
            ls.remove(i);
        }
        2 => {
            let j = rng.below(n);
            ls.swap(i, j);
        }
        3 => {
            // another keyword for the line
            let mut words: Vec<Vec<u8>> = ls[i].split(|&b| b == b' ').map(<[u8]>::to_vec).collect();
            words[0] =
                rng.pick(&["v", "vt", "vn", "f", "l", "p", "o", "g", "s", "#", ""]).as_bytes().to_vec();
            ls[i] = join(&words, b' ');
        }
        4 => {
            // a face over random existing vertices, one corner possibly out of range
            let vertices = ls.iter().filter(|l| l.starts_with(b"v ")).count().max(1);
            let most = if rng.one_in(8) { 300 } else { 5 };
            let corners = 3 + rng.below(most);
            let mut face = b"f".to_vec();
            for _ in 0..corners {
                let c = match rng.below(12) {
                    0 => rng.pick(NUMBERS).to_string(),
                    1 => format!("-{}", 1 + rng.below(vertices)),
                    2 => format!("{}/{}/{}", 1 + rng.below(vertices), rng.below(3), rng.below(3)),
                    _ => (1 + rng.below(vertices)).to_string(),
                };
                face.push(b' ');
                face.extend_from_slice(c.as_bytes());
            }
            ls.insert(rng.below(n + 1), face);
        }
        5 => {
            let v = format!(
                "v {} {} {}",
                rng.pick(NUMBERS),
                if rng.one_in(2) { rng.pick(NUMBERS).to_string() } else { rng.below(10).to_string() },
                rng.below(10)
            );
            ls.insert(rng.below(n + 1), v.into_bytes());
        }
        6 => replace_number(rng, &mut ls[i]),
        _ => {
            // one word of a line repeated: more corners, more coordinates
            let words: Vec<Vec<u8>> = ls[i].split(|&b| b == b' ').map(<[u8]>::to_vec).collect();
            let w = words[rng.below(words.len())].clone();
            let times = 1 + rng.below(16);
            for _ in 0..times {
                ls[i].push(b' ');
                ls[i].extend_from_slice(&w);
            }
        }
    }
    *input = join(&ls, b'\n');
}

/// One edit of a scene expression by its `:`-separated parts.
fn scene_edit(rng: &mut Rng, input: &mut Vec<u8>) {
    let mut parts: Vec<Vec<u8>> = input.split(|&b| b == b':').map(<[u8]>::to_vec).collect();
    let n = parts.len();
    let i = rng.below(n);
    match rng.below(6) {
        0 => {
            // wrapped in another grid
            let dims = format!("grid:{}x{}:", rng.pick(NUMBERS), rng.pick(NUMBERS));
            let mut out = if rng.one_in(2) { dims.into_bytes() } else { b"grid:2x2:".to_vec() };
            out.extend_from_slice(input);
            *input = out;
            return;
        }
        1 => parts[i] = rng.pick(SCENE_WORDS).trim_end_matches(':').as_bytes().to_vec(),
        2 => parts[i] = rng.pick(NUMBERS).as_bytes().to_vec(),
        3 => parts[i] = format!("{}x{}", rng.pick(NUMBERS), rng.pick(NUMBERS)).into_bytes(),
        4 if n > 1 => {
            parts.remove(i);
        }
        _ => {
            let copy = parts[i].clone();
            parts.insert(i, copy);
        }
    }
    *input = join(&parts, b':');
}

/// One edit of an argument list (one argument a line) by its arguments.
fn args_edit(rng: &mut Rng, input: &mut Vec<u8>, vocabulary: &Vocabulary) {
    let mut args = lines(input);
    let n = args.len();
    let i = rng.below(n);
    match rng.below(7) {
        0 => {
            // an option of the command (or of another command), with a value for it
            let option = vocabulary.option(rng, args.first().map(Vec::as_slice));
            let at = (1 + rng.below(n)).min(args.len());
            args.splice(at..at, option.into_iter().map(String::into_bytes));
        }
        1 if n > 1 => {
            args.remove(i);
        }
        2 => {
            // the value of an option replaced by another of its kind
            let name = if i > 0 {
                String::from_utf8_lossy(&args[i - 1]).trim_start_matches('-').to_string()
            } else {
                String::new()
            };
            let list = values(&name);
            args[i] = if list.is_empty() { rng.pick(NUMBERS) } else { rng.pick(list) }.as_bytes().to_vec();
        }
        3 => {
            args[0] = rng
                .pick(&["render", "compare", "sweep", "info", "bench", "help", "", "-h"])
                .as_bytes()
                .to_vec()
        }
        4 => {
            let j = rng.below(n);
            args.swap(i, j);
        }
        5 => {
            let copy = args[i].clone();
            args.insert(i, copy);
        }
        _ => replace_number(rng, &mut args[i]),
    }
    *input = join(&args, b'\n');
}
