//! `oit view --script FILE`: timed key and mouse events, so a run of the viewer can be repeated
//! (and tested) without a person at the keyboard.
//!
//! One event a line, `TIME ACTION [ARGUMENTS]`, TIME in seconds from the first frame; `#` starts a
//! comment, blank lines are skipped. Events run in file order, each no earlier than its time (a
//! slow frame delays the rest; the order and the result do not depend on the timing):
//!
//! - `key NAME`: a key press as from the keyboard (`key T`, `key shift+T`, `key F12`, `key Escape`).
//! - `drag DX DY`: a left-button drag of DX, DY pixels (orbit, 0.25° a pixel).
//! - `scroll LINES`: the mouse wheel (zoom: each line narrows the field of view by 10 %; negative
//!   widens it).
//! - `resize W H`: asks for a window of W × H pixels and waits (up to 5 s) until it has it.
//! - `minimize`: minimises the window (asks the window manager to iconify it, and unmaps it, as
//!   a window manager does; a bare X server such as Xvfb has none, so the unmap is what happens
//!   there). No frame is drawn until `restore`; keys and the mouse still change the view.
//! - `restore`: maps the window again; the next frame is drawn at the current view.
//! - `screenshot FILE.png`: renders the current view and writes it (the technique's image, never
//!   the overlay), printing the `oit render` options that reproduce it.
//! - `quit`: closes the window.

use std::path::{Path, PathBuf};

use oit_core::OitError;

/// One action of a script.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// A key press: its name (`T`, `F12`, `Escape`, ...) and whether shift is held.
    Key { name: String, shift: bool },
    /// A left-button drag by this many pixels.
    Drag { dx: f32, dy: f32 },
    /// The mouse wheel, in lines.
    Scroll { lines: f32 },
    /// A window of this inner size.
    Resize { width: u32, height: u32 },
    /// Minimise (iconify and unmap) the window.
    Minimize,
    /// Map the window again.
    Restore,
    /// Renders the view and writes it here.
    Screenshot(PathBuf),
    /// Closes the window.
    Quit,
}

/// One timed action.
#[derive(Clone, Debug, PartialEq)]
pub struct Event {
    /// Seconds from the first frame.
    pub time: f64,
    /// What happens.
    pub action: Action,
}

/// The latest time an event may have, in seconds (about 11 days).
const MAX_TIME: f64 = 1e6;

/// The largest script read, in bytes.
const MAX_SCRIPT_BYTES: u64 = 1 << 20;

/// Reads and parses the script at `path` (a file of at most 1 MiB); every error names the line.
pub fn load(path: &Path) -> Result<Vec<Event>, OitError> {
    let bad = |message: String| OitError::InvalidSettings(format!("script {}: {message}", path.display()));
    // checked before it is opened for reading: a FIFO would block in open() (issue 41.5)
    let opened = oit_core::open_regular(path).map_err(|e| bad(format!("cannot read it: {e}")))?;
    let Some((file, meta)) = opened else {
        return Err(bad("not a regular file (a pipe, device or folder)".into()));
    };
    if meta.len() > MAX_SCRIPT_BYTES {
        return Err(bad(format!("{} bytes: a script is at most 1 MiB", meta.len())));
    }
    let mut text = String::new();
    std::io::Read::read_to_string(&mut std::io::Read::take(file, MAX_SCRIPT_BYTES), &mut text)
        .map_err(|e| bad(format!("cannot read it: {e}")))?;
    parse(&text).map_err(bad)
}

/// Parses a script (see the module docs).
pub fn parse(text: &str) -> Result<Vec<Event>, String> {
    let mut events = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let n = i + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        let time: f64 =
            words[0].parse().ok().filter(|t: &f64| (0.0..=MAX_TIME).contains(t)).ok_or_else(|| {
                format!("line {n}: '{}' is not a time (seconds, from 0 to {MAX_TIME})", words[0])
            })?;
        let args = &words[2.min(words.len())..];
        let want = |count: usize, usage: &str| {
            if args.len() == count {
                Ok(())
            } else {
                Err(format!("line {n}: expected `{usage}`, got `{line}`"))
            }
        };
        let number = |word: &str| -> Result<f32, String> {
            word.parse::<f32>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("line {n}: '{word}' is not a number"))
        };
        let size = |word: &str| -> Result<u32, String> {
            word.parse::<u32>()
                .ok()
                .filter(|v| (1..=16384).contains(v))
                .ok_or_else(|| format!("line {n}: '{word}' is not a size in pixels (1 to 16384)"))
        };
        let action = match words.get(1).copied() {
            Some("key") => {
                want(1, "TIME key NAME")?;
                let (shift, name) = match args[0].split_once('+') {
                    Some((m, name)) if m.eq_ignore_ascii_case("shift") => (true, name),
                    Some(_) => {
                        return Err(format!("line {n}: only the shift modifier is known: `shift+NAME`"));
                    }
                    None => (false, args[0]),
                };
                if super::keys::lookup(name).is_none() {
                    return Err(format!("line {n}: no key '{name}' (see `oit view --help` for the keys)"));
                }
                Action::Key { name: name.to_string(), shift }
            }
            Some("drag") => {
                want(2, "TIME drag DX DY")?;
                Action::Drag { dx: number(args[0])?, dy: number(args[1])? }
            }
            Some("scroll") => {
                want(1, "TIME scroll LINES")?;
                Action::Scroll { lines: number(args[0])? }
            }
            Some("resize") => {
                want(2, "TIME resize W H")?;
                Action::Resize { width: size(args[0])?, height: size(args[1])? }
            }
            Some("minimize") => {
                want(0, "TIME minimize")?;
                Action::Minimize
            }
            Some("restore") => {
                want(0, "TIME restore")?;
                Action::Restore
            }
            Some("screenshot") => {
                want(1, "TIME screenshot FILE.png")?;
                let path = PathBuf::from(args[0]);
                crate::options::check_output(&path, "png", "screenshot")
                    .map_err(|e| format!("line {n}: {e}"))?;
                Action::Screenshot(path)
            }
            Some("quit") => {
                want(0, "TIME quit")?;
                Action::Quit
            }
            other => {
                return Err(format!(
                    "line {n}: unknown action '{}': use key, drag, scroll, resize, minimize, restore, screenshot or quit",
                    other.unwrap_or("")
                ));
            }
        };
        events.push(Event { time, action });
    }
    Ok(events)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_action() {
        let text = "# a run\n0.5 key T\n1 key shift+k  # back\n1.0 drag 10 -2.5\n\n2 scroll -1\n\
                    2.5 resize 320 200\n2.6 minimize\n2.7 restore\n3 screenshot out.png\n4 quit\n";
        let events = parse(text).unwrap();
        let actions: Vec<Action> = events.iter().map(|e| e.action.clone()).collect();
        assert_eq!(
            actions,
            [
                Action::Key { name: "T".into(), shift: false },
                Action::Key { name: "k".into(), shift: true },
                Action::Drag { dx: 10.0, dy: -2.5 },
                Action::Scroll { lines: -1.0 },
                Action::Resize { width: 320, height: 200 },
                Action::Minimize,
                Action::Restore,
                Action::Screenshot("out.png".into()),
                Action::Quit,
            ]
        );
        assert_eq!(events[0].time, 0.5);
    }

    #[test]
    fn errors_name_the_line() {
        for (text, needle) in [
            ("x key T", "line 1: 'x' is not a time"),
            ("\n1 jump", "line 2: unknown action 'jump'"),
            ("1 key", "line 1: expected `TIME key NAME`"),
            ("1 key ctrl+T", "only the shift modifier"),
            ("1 key Foo", "no key 'Foo'"),
            ("1 drag 1 nan", "'nan' is not a number"),
            ("1 resize 0 10", "'0' is not a size"),
            ("1 screenshot out.jpg", "must name a .png file"),
            ("-1 quit", "'-1' is not a time"),
            ("1e300 quit", "'1e300' is not a time"),
            ("1 quit now", "expected `TIME quit`"),
            ("1 minimize 2", "expected `TIME minimize`"),
        ] {
            let e = parse(text).unwrap_err();
            assert!(e.contains(needle), "{text:?}: {e}");
        }
    }
}
