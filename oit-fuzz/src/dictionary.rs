//! What the generator and the mutator both draw on: the random numbers, the dictionary of
//! values that broke oit before, option values by kind, and oit's commands and options. A module
//! of its own below both, so that neither imports the other.

use clap::CommandFactory;

/// splitmix64: small, fast, and the same sequence on every machine for a seed.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x6a09_e667_f3bc_c909)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        if n == 0 { 0 } else { (self.next_u64() % n as u64) as usize }
    }

    /// True one time in `n`.
    pub fn one_in(&mut self, n: usize) -> bool {
        self.below(n) == 0
    }

    /// One of `items`.
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }

    /// `n` random bytes.
    pub fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next_u64() as u8).collect()
    }
}

/// Numbers at the edges of what oit checks: zero, signs, the u32/i32/u64 limits, the technique
/// parameter and count limits, f32's range and its edges, the coordinate limit (1e15), NaN and
/// the infinities in the spellings Rust's parser takes, and a few that are not numbers at all.
pub const NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "-1",
    "2",
    "3",
    "4",
    "7",
    "8",
    "16",
    "31",
    "32",
    "33",
    "64",
    "89",
    "90",
    "-90",
    "128",
    "129",
    "179",
    "180",
    "181",
    "255",
    "256",
    "1000",
    "4096",
    "4097",
    "16384",
    "16385",
    "36000",
    "36001",
    "65535",
    "65536",
    "65537",
    "100000",
    "100001",
    "1000000",
    "2147483647",
    "2147483648",
    "-2147483648",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "99999999999999999999999",
    "0.5",
    "0.49",
    "179.5",
    "1e-7",
    "1e-20",
    "1e-30",
    "1e-38",
    "1e-45",
    "1e-46",
    "1e15",
    "1.0000001e15",
    "1e16",
    "-1e15",
    "1e20",
    "1e37",
    "-1e37",
    "1e38",
    "3.4028235e38",
    "3.4028236e38",
    "1e39",
    "1e308",
    "1e309",
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "+inf",
    "infinity",
    "-Infinity",
    "0x10",
    "1_000",
    "1e",
    "e5",
    ".",
    "-",
    "+",
    "",
    " ",
    "1.5",
    "-0.5",
    "0.999999",
    "1.000001",
];

/// Scene names and parts of scene expressions, the files of the corpus among them.
pub const SCENE_WORDS: &[&str] = &[
    "default",
    "knot",
    "coplanar",
    "planes",
    "planes:",
    "spheres:",
    "cluster:",
    "ties:",
    "near:",
    "grid:",
    "grid:64x64:",
    "grid:1x1:",
    "grid:2x2:",
    "x",
    "X",
    ":",
    "::",
    "bunny",
    "armadillo",
    "obj/triangle.obj",
    "obj/star-10000.obj",
    "obj/lines.obj",
    "obj/huge-vertex.obj",
    "gltf/quad.glb",
    "gltf/two-scenes.glb",
    "gltf/data-uri.gltf",
    "nosuch.obj",
    "/dev/zero",
    "/dev/null",
    "@hostile/model.obj",
    "grid:2x2:@hostile/model.obj",
    "/",
    ".",
    "..",
    "obj",
    "OBJ",
    ".obj",
    "~",
    "",
];

/// Values of options, by the option's kind (the kind is chosen from the option's long name; an
/// option not listed draws from all of them).
pub fn values(option: &str) -> &'static [&'static str] {
    match option {
        "size" | "curve-size" => &[
            "512x512",
            "8x8",
            "1x1",
            "2x1",
            "0x0",
            "0x8",
            "16384x1",
            "16385x1",
            "1x16384",
            "16384x16384",
            "4294967296x1",
            "8",
            "x",
            "8x",
            "x8",
            "8x8x8",
            "-8x8",
            " 8 x 8 ",
            "8X8",
            "nanxnan",
        ],
        "curve-grids" => &["1x1,1x2,2x2", "64x64", "0x1", "4097x1", "1x1,,", ",", "2x4,x", "65536x65536"],
        "technique" | "techniques" | "curve-techniques" => &[
            "reference",
            "all",
            "auto",
            "auto:2",
            "plain",
            "plain:2",
            "dp",
            "ddp",
            "wavg",
            "wsum",
            "wboit",
            "wboit:2",
            "mboit",
            "mboit:4",
            "mboit:6",
            "mboit:5",
            "mboit:0",
            "bdp",
            "bdp2",
            "bdp:1",
            "bdp:1000",
            "bdp:65536",
            "bdp:65537",
            "bdp:0",
            "adp",
            "mdts",
            "mdts:1",
            "mdts64",
            "mdts64:65536",
            "fabs",
            "fabs:0",
            "fabs:2",
            "fabs:16",
            "mlp",
            "mlp:3",
            "mlp:65537",
            "kbuf",
            "kbuf:4",
            "kbuf:0",
            "fabs:4,kbuf:4",
            "dp,bdp2,fabs:16",
            "all,all",
            ",",
            "",
            "dp,",
            "nosuch",
            "fabs:-1",
            "fabs:1e3",
            "mdts:4294967296",
            "REFERENCE",
            "Dp",
        ],
        "scene" | "scenes" | "curves" => SCENE_WORDS,
        "azimuth" | "elevation" | "fov" | "alpha" | "near" | "far" => NUMBERS,
        "background" => &[
            "0,0,0",
            "1,1,1",
            "0.06,0.07,0.09",
            "nan,0,0",
            "inf,0,0",
            "1,2",
            "0.5,0.5,0.5,0.5",
            "-0,1e-45,1",
            "1.0000001,0,0",
            "-0.0001,0,0",
            ",,",
            "",
            "a,b,c",
        ],
        "shading" => &["headlight", "flat", "vertex", "normal", "Flat", "", "nosuch"],
        "effect" => &["transparency", "translucency", "fresnel", "complexity", "", "heat", "FRESNEL"],
        "bounds" => &["auto", "boxes", "exact", "", "box"],
        "bdp-mode" => &["color", "depth", "auto", "colour", ""],
        "hardware-capture" => &["atomics", "blend", "", "both"],
        "overflow" => &["drop", "tail", "", "Tail", "merge"],
        "max-epr" => {
            &["0", "0.01", "1", "1%", "0.5%", "100%", "101%", "-0", "-1", "1e-300", "nan", "inf", "%", ""]
        }
        "calibration" => &[
            "bench/results/cpu/calibration.json",
            "@hostile/calibration.json",
            "/dev/zero",
            "obj/triangle.obj",
            "nosuch.json",
            "",
            "/",
        ],
        "backend" => {
            &["cpu", "wgpu", "vulkan", "all", "cpu,cpu", "cpu,wgpu", "", ",", "CPU", "cpu,", "nosuch"]
        }
        "raster" => &["hardware", "compute", "cpu", "all", "", "gpu", "Compute"],
        "adapter" => &["", "nvidia", "llvmpipe", "\u{0}"],
        "output" | "sheet" => &[
            "out.png",
            "OUT.PNG",
            "out.svg",
            "out",
            "",
            ".",
            "/",
            "obj",
            "obj/",
            "nosuch/out.png",
            "/dev/null",
            "/dev/null.png",
            "obj/triangle.obj",
            "-",
            "-o",
        ],
        "plot" => &["plot.svg", "plot.SVG", "plot.png", "", "nosuch/plot.svg", "obj/"],
        "out" | "replot" => &[
            "reports/huge",
            "reports/fine",
            "reports/empty",
            "reports/missing",
            "@hostile/report",
            "obj",
            "obj/triangle.obj",
            "",
            "/",
        ],
        "model" => &["@hostile/calibration.json", "reports/fine/report.json", "nosuch.json", "/dev/zero", ""],
        "script" => &["@hostile/script.txt", "obj/triangle.obj", "nosuch.txt", "/dev/zero", "obj", ""],
        "threads" | "max-peels" | "views" | "frames" | "warmup" | "curve-depth" | "curve-frames"
        | "gltf-scene" => NUMBERS,
        _ => &[],
    }
}

/// One option of a command, from its clap definition.
#[derive(Clone, Debug)]
pub struct Opt {
    long: Option<String>,
    short: Option<char>,
    takes_value: bool,
}

/// Every command of `oit` and its options, read from oit-cli's clap definition.
#[derive(Debug)]
pub struct Vocabulary {
    pub(crate) commands: Vec<(String, Vec<Opt>)>,
}

impl Vocabulary {
    /// Reads the commands and options of `oit`.
    pub fn new() -> Vocabulary {
        let cli = oit_cli::Cli::command();
        let commands = cli
            .get_subcommands()
            .map(|sub| {
                let opts = sub
                    .get_arguments()
                    .filter(|a| !a.is_positional())
                    .map(|a| Opt {
                        long: a.get_long().map(str::to_string),
                        short: a.get_short(),
                        takes_value: a.get_action().takes_values(),
                    })
                    .collect();
                (sub.get_name().to_string(), opts)
            })
            .collect();
        Vocabulary { commands }
    }

    /// Commands and options in all.
    pub fn counts(&self) -> (usize, usize) {
        (self.commands.len(), self.commands.iter().map(|(_, o)| o.len()).sum())
    }

    /// The options of `command` (every command's when it is none of them).
    pub(crate) fn options_of(&self, command: Option<&[u8]>) -> Vec<&Opt> {
        let own = self.commands.iter().find(|(name, _)| Some(name.as_bytes()) == command);
        match own {
            Some((_, opts)) => opts.iter().collect(),
            None => self.commands.iter().flat_map(|(_, o)| o.iter()).collect(),
        }
    }

    /// The arguments of one option: the flag, and its value where it takes one (`form` picks
    /// `--name value`, `--name=value` or the short flag).
    pub(crate) fn write(opt: &Opt, value: usize, form: usize) -> Vec<String> {
        let name = opt.long.clone().unwrap_or_default();
        let list = values(&name);
        let list = if list.is_empty() { NUMBERS } else { list };
        let v = list[value % list.len()].to_string();
        let flag = match (form % 4, opt.short, &opt.long) {
            (3, Some(s), _) | (_, Some(s), None) => format!("-{s}"),
            _ => format!("--{name}"),
        };
        match (opt.takes_value, form % 4) {
            (false, _) => vec![flag],
            (true, 1) => vec![format!("{flag}={v}")],
            (true, _) => vec![flag, v],
        }
    }

    /// A random option of `command`, with a value of its kind: one or two arguments.
    pub fn option(&self, rng: &mut Rng, command: Option<&[u8]>) -> Vec<String> {
        let opts = self.options_of(command);
        let opt = *rng.pick(&opts);
        Vocabulary::write(opt, rng.below(1 << 16), rng.below(8))
    }
}
