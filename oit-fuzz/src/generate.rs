//! Structured generation with `arbitrary`: random bytes read as an OBJ file's lines, a scene
//! expression's tree or a command line's options, then written out as the text oit reads. The
//! options come from oit-cli's own clap definition, so every option of every command is drawn,
//! including ones added after this was written.

use arbitrary::{Arbitrary, Unstructured};

use crate::Target;
use crate::dictionary::{NUMBERS, Rng, Vocabulary};

/// A number as an OBJ file or an option writes it.
#[derive(Arbitrary, Debug)]
enum Num {
    Small(i8),
    Fraction(i16),
    Float(f32),
    Edge(u8),
    Int(u32),
}

impl Num {
    fn text(&self) -> String {
        match self {
            Num::Small(i) => i.to_string(),
            Num::Fraction(i) => (f32::from(*i) / 256.0).to_string(),
            Num::Float(f) => f.to_string(),
            Num::Edge(i) => NUMBERS[*i as usize % NUMBERS.len()].to_string(),
            Num::Int(u) => u.to_string(),
        }
    }
}

/// A face corner.
#[derive(Arbitrary, Debug)]
enum Corner {
    Index(i8),
    Huge(u64),
    Edge(u8),
    Texture(i8, i8),
    Normal(i8, i8),
    Full(i8, i8, i8),
}

impl Corner {
    fn text(&self) -> String {
        match self {
            Corner::Index(i) => i.to_string(),
            Corner::Huge(u) => u.to_string(),
            Corner::Edge(i) => NUMBERS[*i as usize % NUMBERS.len()].to_string(),
            Corner::Texture(v, t) => format!("{v}/{t}"),
            Corner::Normal(v, n) => format!("{v}//{n}"),
            Corner::Full(v, t, n) => format!("{v}/{t}/{n}"),
        }
    }
}

/// One line of an OBJ file, or a few for the shapes that take several.
#[derive(Arbitrary, Debug)]
enum ObjLine {
    Vertex(Num, Num, Num),
    VertexW(Num, Num, Num, Num),
    VertexRgb(Num, Num, Num, Num, Num, Num),
    Normal(Num, Num, Num),
    Texture(Num, Num),
    Face(Vec<Corner>),
    Line(Vec<Corner>),
    Point(Vec<Corner>),
    Object(u8),
    Group(u8),
    Smooth(bool),
    Comment,
    MaterialLibrary,
    UseMaterial,
    Blank,
    /// A star polygon of that many corners (concave), its vertices and its one face.
    Star(u16),
    /// A polygon whose corners wind back and forth (self-crossing).
    Zigzag(u8),
    Raw(String),
}

impl ObjLine {
    fn write(&self, out: &mut String) {
        use std::fmt::Write;
        let corners = |c: &[Corner]| c.iter().map(Corner::text).collect::<Vec<_>>().join(" ");
        let _ = match self {
            ObjLine::Vertex(x, y, z) => writeln!(out, "v {} {} {}", x.text(), y.text(), z.text()),
            ObjLine::VertexW(x, y, z, w) => {
                writeln!(out, "v {} {} {} {}", x.text(), y.text(), z.text(), w.text())
            }
            ObjLine::VertexRgb(x, y, z, r, g, b) => writeln!(
                out,
                "v {} {} {} {} {} {}",
                x.text(),
                y.text(),
                z.text(),
                r.text(),
                g.text(),
                b.text()
            ),
            ObjLine::Normal(x, y, z) => writeln!(out, "vn {} {} {}", x.text(), y.text(), z.text()),
            ObjLine::Texture(u, v) => writeln!(out, "vt {} {}", u.text(), v.text()),
            ObjLine::Face(c) => writeln!(out, "f {}", corners(c)),
            ObjLine::Line(c) => writeln!(out, "l {}", corners(c)),
            ObjLine::Point(c) => writeln!(out, "p {}", corners(c)),
            ObjLine::Object(i) => writeln!(out, "o object{i}"),
            ObjLine::Group(i) => writeln!(out, "g group{i}"),
            ObjLine::Smooth(on) => writeln!(out, "s {}", if *on { "1" } else { "off" }),
            ObjLine::Comment => writeln!(out, "# a comment"),
            ObjLine::MaterialLibrary => writeln!(out, "mtllib nosuch.mtl"),
            ObjLine::UseMaterial => writeln!(out, "usemtl glass"),
            ObjLine::Blank => writeln!(out),
            ObjLine::Star(n) => {
                let n = 3 + usize::from(*n) % 4000;
                for i in 0..n {
                    let a = i as f64 / n as f64 * std::f64::consts::TAU;
                    let r = if i % 2 == 0 { 1.0 } else { 0.4 };
                    let _ = writeln!(out, "v {} {} 0", r * a.cos(), r * a.sin());
                }
                let face: Vec<String> = (1..=n).map(|i| format!("-{i}")).collect();
                writeln!(out, "f {}", face.join(" "))
            }
            ObjLine::Zigzag(n) => {
                let n = 4 + usize::from(*n);
                for i in 0..n {
                    let _ = writeln!(out, "v {} {} {}", i, (i % 2) * 3, i % 3);
                }
                let face: Vec<String> = (1..=n).map(|i| format!("-{i}")).collect();
                writeln!(out, "f {}", face.join(" "))
            }
            ObjLine::Raw(s) => writeln!(out, "{s}"),
        };
    }
}

/// A count in a scene expression.
#[derive(Arbitrary, Debug)]
enum Count {
    Small(u8),
    Any(u32),
    Edge(u8),
}

impl Count {
    fn text(&self) -> String {
        match self {
            Count::Small(n) => n.to_string(),
            Count::Any(n) => n.to_string(),
            Count::Edge(i) => NUMBERS[*i as usize % NUMBERS.len()].to_string(),
        }
    }
}

/// A scene expression.
#[derive(Arbitrary, Debug)]
enum SceneExpr {
    Default,
    Knot,
    Coplanar,
    Planes(Option<Count>),
    Spheres(Option<Count>),
    Cluster(Option<Count>),
    Ties(Option<Count>),
    Near(Option<Count>),
    Grid(Count, Count, Box<SceneExpr>),
    File(u8),
    Raw(String),
}

/// Files a scene may name, relative to the corpus folder (the worker's working folder).
const FILES: &[&str] = &[
    "obj/triangle.obj",
    "obj/quad-colours.obj",
    "obj/lines.obj",
    "obj/star-10000.obj",
    "obj/huge-vertex.obj",
    "obj/nan.obj",
    "obj/negative-index.obj",
    "nosuch.obj",
    "/dev/zero",
    "obj",
    "scene/default.txt",
    "@hostile/model.obj",
];

impl SceneExpr {
    fn text(&self) -> String {
        let with = |name: &str, n: &Option<Count>| match n {
            None => name.to_string(),
            Some(n) => format!("{name}:{}", n.text()),
        };
        match self {
            SceneExpr::Default => "default".into(),
            SceneExpr::Knot => "knot".into(),
            SceneExpr::Coplanar => "coplanar".into(),
            SceneExpr::Planes(n) => with("planes", n),
            SceneExpr::Spheres(n) => with("spheres", n),
            SceneExpr::Cluster(n) => with("cluster", n),
            SceneExpr::Ties(n) => with("ties", n),
            SceneExpr::Near(n) => with("near", n),
            SceneExpr::Grid(r, c, inner) => format!("grid:{}x{}:{}", r.text(), c.text(), inner.text()),
            SceneExpr::File(i) => FILES[*i as usize % FILES.len()].into(),
            SceneExpr::Raw(s) => s.clone(),
        }
    }
}

/// One argument of a command line.
#[derive(Arbitrary, Debug)]
enum ArgItem {
    /// The option at this index of the command's options, with the value at this index of its
    /// values, written as `--name value`, `--name=value` or `-n value`.
    Option {
        index: u16,
        value: u8,
        form: u8,
    },
    /// An option of another command.
    Foreign {
        index: u16,
        value: u8,
    },
    Number(u8),
    Raw(String),
    Help,
    Dashes,
}

/// A command line.
#[derive(Arbitrary, Debug)]
struct ArgsInput {
    command: u8,
    items: Vec<ArgItem>,
}

/// The arguments an [`ArgsInput`] spells, in `vocabulary`'s commands and options.
fn args(vocabulary: &Vocabulary, input: &ArgsInput) -> Vec<String> {
    let n = vocabulary.commands.len();
    let mut out = vec![match input.command as usize % (n + 3) {
        i if i < n => vocabulary.commands[i].0.clone(),
        i if i == n => "help".into(),
        i if i == n + 1 => String::new(),
        _ => "--version".into(),
    }];
    let own = vocabulary.options_of(Some(out[0].as_bytes()));
    let all = vocabulary.options_of(None);
    for item in &input.items {
        match item {
            ArgItem::Option { index, value, form } => {
                let opt = own[*index as usize % own.len()];
                out.extend(Vocabulary::write(opt, usize::from(*value), usize::from(*form)));
            }
            ArgItem::Foreign { index, value } => {
                let opt = all[*index as usize % all.len()];
                out.extend(Vocabulary::write(opt, usize::from(*value), 0));
            }
            ArgItem::Number(i) => out.push(NUMBERS[*i as usize % NUMBERS.len()].to_string()),
            ArgItem::Raw(s) => out.push(s.clone()),
            ArgItem::Help => out.push("--help".into()),
            ArgItem::Dashes => out.push("--".into()),
        }
    }
    out
}

/// A new input for `target`, generated from `rng`'s bytes.
pub fn generate(rng: &mut Rng, target: Target, vocabulary: &Vocabulary) -> Vec<u8> {
    let most = if rng.one_in(4) { 2048 } else { 256 };
    let len = 1 + rng.below(most);
    let bytes = rng.bytes(len);
    let mut u = Unstructured::new(&bytes);
    match target {
        // issue 41.3: one OBJ in 512 a lone random star of 16,384 to 65,537 corners (the last over
        // the limit a face may have)
        Target::Obj if rng.one_in(512) => {
            let n =
                [16_384, 32_768, oit_core::MAX_FACE_CORNERS, oit_core::MAX_FACE_CORNERS + 1][rng.below(4)];
            crate::hostile::random_star(n, rng.next_u64()).into_bytes()
        }
        Target::Obj => {
            let lines: Vec<ObjLine> = Vec::arbitrary_take_rest(u).unwrap_or_default();
            let mut text = String::new();
            for line in &lines {
                line.write(&mut text);
            }
            text.into_bytes()
        }
        Target::Scene => SceneExpr::arbitrary(&mut u).map(|s| s.text()).unwrap_or_default().into_bytes(),
        Target::Args => {
            let args = ArgsInput::arbitrary_take_rest(u).map(|a| args(vocabulary, &a)).unwrap_or_default();
            args.join("\n").into_bytes()
        }
        // the selftest's inputs are its corpus alone
        Target::Selftest => b"fine".to_vec(),
        // a seed the harness writes, edited where the loader checks, a few times over
        Target::Gltf => {
            let seeds = crate::gltf::seeds();
            let mut input = rng.pick(&seeds).1.clone();
            for _ in 0..1 + rng.below(6) {
                crate::gltf::edit(rng, &mut input);
            }
            input
        }
    }
}
