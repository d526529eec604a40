//! What the viewer shows and how the keys and the mouse change it: a state with no window in it,
//! shared by the keyboard, the mouse and `--script`, so a script does exactly what a person does.

use oit_core::{Effect, Shading, Technique, View};

/// A key the viewer answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// Next technique (shift: previous).
    Technique,
    /// K of fabs, mdts and mdts64.
    K,
    /// P of bdp:P (its capture passes).
    P,
    /// M of mlp.
    M,
    /// Samples a pixel (multisampling).
    Samples,
    /// The opacity given to every object.
    Alpha,
    /// The shading.
    Shading,
    /// The effect.
    Effect,
    /// The reference comparison.
    Reference,
    /// A screenshot.
    Screenshot,
    /// The overlay.
    Overlay,
    /// Quit.
    Quit,
    /// Orbit by 5°.
    Left,
    /// Orbit by 5°.
    Right,
    /// Orbit by 5°.
    Up,
    /// Orbit by 5°.
    Down,
    /// Narrows the field of view.
    ZoomIn,
    /// Widens it.
    ZoomOut,
}

/// The key names (case-insensitive) each key answers to, as a script writes them.
const NAMES: &[(&str, Key)] = &[
    ("T", Key::Technique),
    ("K", Key::K),
    ("P", Key::P),
    ("M", Key::M),
    ("N", Key::Samples),
    ("A", Key::Alpha),
    ("S", Key::Shading),
    ("E", Key::Effect),
    ("R", Key::Reference),
    ("F12", Key::Screenshot),
    ("O", Key::Overlay),
    ("Q", Key::Quit),
    ("Escape", Key::Quit),
    ("Left", Key::Left),
    ("Right", Key::Right),
    ("Up", Key::Up),
    ("Down", Key::Down),
    ("Plus", Key::ZoomIn),
    ("=", Key::ZoomIn),
    ("Minus", Key::ZoomOut),
    ("-", Key::ZoomOut),
];

/// The key a name stands for.
pub fn lookup(name: &str) -> Option<Key> {
    let name = if name == "+" { "Plus" } else { name };
    NAMES.iter().find(|(n, _)| n.eq_ignore_ascii_case(name)).map(|&(_, k)| k)
}

/// The bindings, as `--help` and the start of a run print them.
pub const BINDINGS: &str = "\
Keys and mouse:
  left drag          orbit about the scene's centre (0.25° a pixel); arrows: 5° a press
  wheel, + / -       zoom (the field of view, 10 % a wheel line)
  T / shift+T        next / previous technique
  K / shift+K        K of fabs, mdts, mdts64 (auto, 1, 2, 4, ..., 64)
  M / shift+M        M of mlp (1, 2, 4, 8, 16)
  P / shift+P        P of bdp:P, its capture passes (1, 2, 3, 4); bdp and adp's bounds pass
                     draws the instances' bounding boxes, which the viewer gives the pass
  N / shift+N        samples a pixel: 1, 4, 8 (where the device draws 8), multisampled
                     through the embedded pass (reference, fabs, dfb, ll; no opaque parts)
  A / shift+A        alpha of every object (own, 0.1, 0.25, 0.5, 0.75, 1)
  S, E               next shading, next effect
  R                  compare with the reference at this view: EPR, and the error heat map
  F12                write a screenshot (oit-view-N.png, the image without the overlay)
  O                  overlay on / off
  Q, Escape          quit";

/// Shadings in the order S cycles them, with their names.
const SHADINGS: [(Shading, &str); 4] = [
    (Shading::Headlight, "headlight"),
    (Shading::Flat, "flat"),
    (Shading::Vertex, "vertex"),
    (Shading::Normal, "normal"),
];

/// Effects in the order E cycles them, with their names.
const EFFECTS: [(Effect, &str); 4] = [
    (Effect::Transparency, "transparency"),
    (Effect::Translucency, "translucency"),
    (Effect::Fresnel, "fresnel"),
    (Effect::Complexity, "complexity"),
];

/// The values K cycles through (`None`: sized from the frame).
const KS: [Option<u32>; 8] = [None, Some(1), Some(2), Some(4), Some(8), Some(16), Some(32), Some(64)];
/// The values M cycles through.
const MS: [u32; 5] = [1, 2, 4, 8, 16];
/// The values P cycles through.
const PS: [u32; 4] = [1, 2, 3, 4];
/// The sample counts N cycles through (8 only where the device draws it: `ViewState::max_samples`).
const SAMPLES: [u32; 3] = [1, 4, 8];
/// The values alpha cycles through (`None`: each object's own).
const ALPHAS: [Option<f32>; 6] = [None, Some(0.1), Some(0.25), Some(0.5), Some(0.75), Some(1.0)];

/// Degrees of orbit per dragged pixel.
pub const DEGREES_PER_PIXEL: f32 = 0.25;
/// Field of view limits of the zoom, in degrees.
const FOV_RANGE: (f32, f32) = (1.0, 120.0);

/// What a key asks of the window beyond a new frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Reaction {
    /// The view changed: draw again.
    Redraw,
    /// Write a screenshot.
    Screenshot,
    /// Close the window.
    Quit,
    /// Nothing changed; say why.
    Note(String),
}

/// What the viewer shows.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewState {
    /// The technique drawn.
    pub technique: Technique,
    /// The camera's angles and field of view.
    pub view: View,
    /// Opacity for every object (`None`: each object's own).
    pub alpha: Option<f32>,
    /// The shading.
    pub shading: Shading,
    /// The effect.
    pub effect: Effect,
    /// Whether the reference is rendered too and the error heat map shown.
    pub compare: bool,
    /// Whether the overlay is drawn.
    pub overlay: bool,
    /// bdp's P: what the technique cycle gives bdp, and P's value while another technique is
    /// drawn.
    pub p: u32,
    /// Samples a pixel (1: not multisampled).
    pub samples: u32,
    /// The most samples a pixel the device draws (4, or 8 where its count target takes 8), which
    /// N's cycle stops at.
    pub max_samples: u32,
}

/// Index of `value` in `list`, else 0.
fn position<T: PartialEq>(list: &[T], value: &T) -> usize {
    list.iter().position(|v| v == value).unwrap_or(0)
}

/// The entry after (or before, `back`) `value` in `list`, wrapping.
fn step<T: PartialEq + Clone>(list: &[T], value: &T, back: bool) -> T {
    let i = position(list, value);
    let n = list.len();
    list[if back { (i + n - 1) % n } else { (i + 1) % n }].clone()
}

impl ViewState {
    /// The name of the shading.
    pub fn shading_name(&self) -> &'static str {
        SHADINGS.iter().find(|(s, _)| *s == self.shading).map_or("?", |(_, n)| n)
    }

    /// The name of the effect.
    pub fn effect_name(&self) -> &'static str {
        EFFECTS.iter().find(|(e, _)| *e == self.effect).map_or("?", |(_, n)| n)
    }

    /// The techniques T cycles through: those the embeddable pass draws (mdts only with an
    /// alpha: its words hold none; bdp and adp with the scene's instance boxes the viewer gives
    /// it), parameters as set now.
    fn cycle(&self) -> Vec<Technique> {
        let k = self.k();
        let m = match self.technique {
            Technique::Mlp { m } => m,
            _ => 4,
        };
        let mut list = vec![
            Technique::Reference,
            Technique::Dp,
            Technique::Ddp,
            Technique::WeightedAverage,
            Technique::WeightedSum,
            Technique::Bdp { passes: self.p },
            Technique::Adp,
            Technique::Mdts64 { k },
            Technique::Fabs { k },
            Technique::Mlp { m },
            Technique::Dfb,
            Technique::Ll,
        ];
        if self.alpha.is_some() {
            list.push(Technique::Mdts { k });
        }
        list
    }

    /// K of the technique drawn, else the default the cycle gives (8).
    fn k(&self) -> Option<u32> {
        match self.technique {
            Technique::Fabs { k } | Technique::Mdts { k } | Technique::Mdts64 { k } => k,
            _ => Some(8),
        }
    }

    /// Answers a key press.
    pub fn key(&mut self, key: Key, shift: bool) -> Reaction {
        match key {
            Key::Technique => {
                let list = self.cycle();
                let kind = self.technique.kind();
                let i = list.iter().position(|t| t.kind() == kind);
                let n = list.len();
                self.technique = match i {
                    Some(i) => list[if shift { (i + n - 1) % n } else { (i + 1) % n }],
                    None => list[0],
                };
            }
            Key::K => {
                self.technique = match self.technique {
                    Technique::Fabs { k } => Technique::Fabs { k: step(&KS, &k, shift) },
                    Technique::Mdts { k } => Technique::Mdts { k: step(&KS, &k, shift) },
                    Technique::Mdts64 { k } => Technique::Mdts64 { k: step(&KS, &k, shift) },
                    _ => return Reaction::Note("K is the parameter of fabs, mdts and mdts64".into()),
                };
            }
            Key::M => {
                self.technique = match self.technique {
                    Technique::Mlp { m } => Technique::Mlp { m: step(&MS, &m, shift) },
                    _ => return Reaction::Note("M is the parameter of mlp".into()),
                };
            }
            Key::Samples => {
                let counts: Vec<u32> = SAMPLES.into_iter().filter(|&n| n <= self.max_samples).collect();
                self.samples = step(&counts, &self.samples, shift);
            }
            Key::P => {
                let Technique::Bdp { passes } = self.technique else {
                    return Reaction::Note("P is the parameter of bdp (bdp:P)".into());
                };
                self.p = step(&PS, &passes, shift);
                self.technique = Technique::Bdp { passes: self.p };
            }
            Key::Alpha => {
                self.alpha = step(&ALPHAS, &self.alpha, shift);
                if self.alpha.is_none() && matches!(self.technique, Technique::Mdts { .. }) {
                    // mdts stores no alpha: the embedded pass needs one
                    self.technique = Technique::Mdts64 { k: self.k() };
                }
            }
            Key::Shading => {
                let names = SHADINGS.map(|(s, _)| s);
                self.shading = step(&names, &self.shading, shift);
            }
            Key::Effect => {
                let names = EFFECTS.map(|(e, _)| e);
                self.effect = step(&names, &self.effect, shift);
            }
            Key::Reference => self.compare = !self.compare,
            Key::Overlay => self.overlay = !self.overlay,
            Key::Screenshot => return Reaction::Screenshot,
            Key::Quit => return Reaction::Quit,
            Key::Left => self.orbit(-20.0, 0.0),
            Key::Right => self.orbit(20.0, 0.0),
            Key::Up => self.orbit(0.0, -20.0),
            Key::Down => self.orbit(0.0, 20.0),
            Key::ZoomIn => self.zoom(1.0),
            Key::ZoomOut => self.zoom(-1.0),
        }
        Reaction::Redraw
    }

    /// A left-button drag of (`dx`, `dy`) pixels: the scene turns with the mouse (the camera
    /// moves the other way about the scene's centre), elevation held within ±89°.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        let azimuth = self.view.azimuth - dx * DEGREES_PER_PIXEL;
        self.view.azimuth = (azimuth + 180.0).rem_euclid(360.0) - 180.0;
        self.view.elevation = (self.view.elevation + dy * DEGREES_PER_PIXEL).clamp(-89.0, 89.0);
    }

    /// The mouse wheel, `lines` up (negative: down): each line narrows the field of view by 10 %.
    pub fn zoom(&mut self, lines: f32) {
        self.view.fov = (self.view.fov * 0.9f32.powf(lines)).clamp(FOV_RANGE.0, FOV_RANGE.1);
    }

    /// The `oit render` options that draw this view at `width × height` (floats printed so they
    /// read back exactly).
    pub fn render_options(&self, width: u32, height: u32) -> String {
        let v = &self.view;
        let mut text = format!(
            "--technique {} --size {width}x{height} --azimuth {} --elevation {} --fov {} --shading {} --effect {}",
            self.technique,
            v.azimuth,
            v.elevation,
            v.fov,
            self.shading_name(),
            self.effect_name()
        );
        for (flag, value) in [("--alpha", self.alpha), ("--near", v.near), ("--far", v.far)] {
            if let Some(x) = value {
                text.push_str(&format!(" {flag} {x}"));
            }
        }
        if self.samples > 1 {
            text.push_str(&format!(" --samples {}", self.samples));
        }
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> ViewState {
        ViewState {
            technique: Technique::Reference,
            view: View { azimuth: 30.0, elevation: 20.0, fov: 45.0, near: None, far: None },
            alpha: None,
            shading: Shading::Headlight,
            effect: Effect::Transparency,
            compare: false,
            overlay: true,
            p: 1,
            samples: 1,
            max_samples: 8,
        }
    }

    #[test]
    fn technique_cycles_both_ways_and_skips_mdts_without_alpha() {
        let mut s = state();
        let mut seen = vec![s.technique];
        for _ in 0..12 {
            s.key(Key::Technique, false);
            seen.push(s.technique);
        }
        assert_eq!(seen.first(), seen.last(), "twelve techniques, then back to the first");
        assert!(!seen.iter().any(|t| matches!(t, Technique::Mdts { .. })));
        assert!(seen.contains(&Technique::Bdp { passes: 1 }), "{seen:?}");
        assert!(seen.contains(&Technique::Adp), "{seen:?}");
        s.key(Key::Technique, true);
        assert_eq!(s.technique, Technique::Ll);
        s.key(Key::Alpha, false);
        s.key(Key::Technique, false);
        assert_eq!(s.technique, Technique::Mdts { k: Some(8) });
        // alpha back to each object's own: mdts cannot draw, mdts64 takes its place
        for _ in 0..5 {
            s.key(Key::Alpha, false);
        }
        assert_eq!(s.alpha, None);
        assert_eq!(s.technique, Technique::Mdts64 { k: Some(8) });
    }

    #[test]
    fn parameters_step_and_wrap() {
        let mut s = state();
        s.technique = Technique::Fabs { k: Some(4) };
        s.key(Key::K, false);
        assert_eq!(s.technique, Technique::Fabs { k: Some(8) });
        s.key(Key::K, true);
        s.key(Key::K, true);
        s.key(Key::K, true);
        s.key(Key::K, true);
        assert_eq!(s.technique, Technique::Fabs { k: None });
        s.key(Key::K, true);
        assert_eq!(s.technique, Technique::Fabs { k: Some(64) });
        assert!(matches!(s.key(Key::M, false), Reaction::Note(_)));
        s.technique = Technique::Mlp { m: 16 };
        s.key(Key::M, false);
        assert_eq!(s.technique, Technique::Mlp { m: 1 });
        // P changes bdp only
        assert!(matches!(s.key(Key::P, false), Reaction::Note(n) if n.contains("bdp")));
        assert_eq!(s.technique, Technique::Mlp { m: 1 });
        s.technique = Technique::Bdp { passes: 1 };
        assert_eq!(s.key(Key::P, false), Reaction::Redraw);
        assert_eq!(s.technique, Technique::Bdp { passes: 2 });
        s.key(Key::P, true);
        s.key(Key::P, true);
        assert_eq!(s.technique, Technique::Bdp { passes: 4 }, "P wraps");
        // the cycle keeps P: away and back to bdp
        s.key(Key::Technique, false);
        assert_eq!(s.technique, Technique::Adp);
        s.key(Key::Technique, true);
        assert_eq!(s.technique, Technique::Bdp { passes: 4 });
    }

    /// N steps 1 → 4 → 8 → 1 (shift: back), skipping 8 where the device does not draw it, and
    /// the printed options carry the count above one sample.
    #[test]
    fn samples_step_to_what_the_device_draws() {
        let mut s = state();
        let mut seen = vec![s.samples];
        for _ in 0..3 {
            assert_eq!(s.key(Key::Samples, false), Reaction::Redraw);
            seen.push(s.samples);
        }
        assert_eq!(seen, [1, 4, 8, 1]);
        s.key(Key::Samples, true);
        assert_eq!(s.samples, 8, "shift+N steps back");
        assert!(s.render_options(8, 8).ends_with(" --samples 8"), "{}", s.render_options(8, 8));
        s.max_samples = 4;
        s.samples = 4;
        s.key(Key::Samples, false);
        assert_eq!(s.samples, 1, "no 8 where the device does not draw it");
        assert!(!s.render_options(8, 8).contains("--samples"));
        assert_eq!(lookup("n"), Some(Key::Samples));
    }

    #[test]
    fn orbit_and_zoom_stay_in_range() {
        let mut s = state();
        s.orbit(40.0, -20.0);
        assert_eq!((s.view.azimuth, s.view.elevation), (20.0, 15.0));
        s.orbit(-1000.0, 1000.0);
        assert!((-180.0..180.0).contains(&s.view.azimuth), "{}", s.view.azimuth);
        assert_eq!(s.view.elevation, 89.0);
        s.zoom(1.0);
        assert!((s.view.fov - 40.5).abs() < 1e-4, "{}", s.view.fov);
        s.zoom(-100.0);
        assert_eq!(s.view.fov, 120.0);
    }

    #[test]
    fn render_options_name_the_view() {
        let mut s = state();
        s.alpha = Some(0.5);
        s.technique = Technique::Fabs { k: Some(8) };
        assert_eq!(
            s.render_options(64, 32),
            "--technique fabs:8 --size 64x32 --azimuth 30 --elevation 20 --fov 45 --shading headlight \
             --effect transparency --alpha 0.5"
        );
    }

    #[test]
    fn names_are_case_insensitive() {
        assert_eq!(lookup("t"), Some(Key::Technique));
        assert_eq!(lookup("escape"), Some(Key::Quit));
        assert_eq!(lookup("+"), Some(Key::ZoomIn));
        assert_eq!(lookup("F13"), None);
    }
}
