//! What goes to the terminal: stdout that tolerates a closed pipe, the one-line error, tables and
//! number formats, and the JSON shapes shared by several commands.

use std::io::Write;

use oit_core::{Camera, View};
use serde::Serialize;

use oit_core::OitError;

/// Writes `text` to stdout. A closed pipe (`oit compare | head`) is not an error; anything else is.
pub fn print(text: &str) -> Result<(), OitError> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(OitError::Write { path: "standard output".into(), message: e.to_string() }),
    }
}

/// Writes `value` to stdout as pretty JSON and a newline.
pub fn print_json<T: Serialize + ?Sized>(value: &T) -> Result<(), OitError> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| OitError::Write { path: "standard output".into(), message: e.to_string() })?;
    print(&(text + "\n"))
}

/// The one line a failure prints on stderr (newlines in `message` folded to spaces).
pub fn error_line(message: &str) {
    eprintln!("error: {}", message.replace('\n', " "));
}

/// Bytes in KiB/MiB/GiB.
pub fn bytes(n: u64) -> String {
    const UNITS: [&str; 4] = ["B", "KiB", "MiB", "GiB"];
    let mut v = n as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 { format!("{n} B") } else { format!("{v:.1} {}", UNITS[unit]) }
}

/// A PSNR in dB, `inf` for identical images, `n/a` for the NaN of a frame that covered no pixel.
pub fn psnr(db: f64) -> String {
    if db.is_nan() {
        NOT_MEASURED.into()
    } else if db.is_infinite() {
        "inf".into()
    } else {
        format!("{db:.2}")
    }
}

/// A fraction as a percentage; `n/a` for the NaN of a frame that covered no pixel (an error rate
/// over no pixel is no score, least of all a perfect one).
pub fn percent(fraction: f64) -> String {
    if fraction.is_nan() { NOT_MEASURED.into() } else { format!("{:.3}", fraction * 100.0) }
}

/// What a table shows for an EPR or PSNR over no covered pixel.
pub const NOT_MEASURED: &str = "n/a";

/// A left-aligned first columns, right-aligned numbers table that prints row by row.
pub struct Table {
    widths: Vec<usize>,
    /// Columns aligned left (the rest are right-aligned).
    left: usize,
}

impl Table {
    /// A table with these headers and minimum widths; the first `left` columns are text.
    pub fn new(headers: &[(&str, usize)], left: usize) -> (Table, String) {
        let widths: Vec<usize> = headers.iter().map(|(h, w)| h.chars().count().max(*w)).collect();
        let table = Table { widths, left };
        let names: Vec<String> = headers.iter().map(|(h, _)| (*h).to_string()).collect();
        let mut text = table.row(&names);
        let rule: usize = table.widths.iter().sum::<usize>() + 2 * (table.widths.len() - 1);
        text.push_str(&"-".repeat(rule));
        text.push('\n');
        (table, text)
    }

    /// One row, cells padded to the column widths (a longer cell pushes the rest right).
    pub fn row(&self, cells: &[String]) -> String {
        let mut line = String::new();
        for (i, (cell, width)) in cells.iter().zip(&self.widths).enumerate() {
            if i > 0 {
                line.push_str("  ");
            }
            if i < self.left {
                line.push_str(&format!("{cell:<width$}"));
            } else {
                line.push_str(&format!("{cell:>width$}"));
            }
        }
        line.truncate(line.trim_end().len());
        line.push('\n');
        line
    }

    /// A row of the first `lead` cells and then free text (a failure).
    pub fn note(&self, lead: &[String], text: &str) -> String {
        let mut line = self.row(lead);
        line.pop();
        line.push_str("  ");
        line.push_str(text);
        line.push('\n');
        line
    }
}

/// A camera as JSON: enough for another renderer to reproduce the view.
#[derive(Serialize)]
pub struct CameraJson {
    /// World to view, column-major (a fitted camera's view space is scaled by 1/radius of the
    /// scene, and `proj` is made for that scale: `proj · view` is world to clip).
    pub view: [f32; 16],
    /// View to clip (right-handed, depth in [0, 1]), column-major.
    pub proj: [f32; 16],
    /// Eye position.
    pub eye: [f32; 3],
    /// Unit viewing direction.
    pub forward: [f32; 3],
    /// Near plane distance from the eye, in scene units.
    pub near: f32,
    /// Far plane distance from the eye, in scene units.
    pub far: f32,
    /// Degrees around the vertical axis.
    pub azimuth: f32,
    /// Degrees above the horizontal plane.
    pub elevation: f32,
    /// Vertical field of view in degrees.
    pub fov: f32,
}

impl CameraJson {
    /// The camera and the angles it was made from.
    pub fn new(camera: &Camera, view: View) -> CameraJson {
        CameraJson {
            view: camera.view.to_cols_array(),
            proj: camera.proj.to_cols_array(),
            eye: camera.eye.to_array(),
            forward: camera.forward.to_array(),
            near: camera.near,
            far: camera.far,
            azimuth: view.azimuth,
            elevation: view.elevation,
            fov: view.fov,
        }
    }
}
