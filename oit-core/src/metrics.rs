//! Accuracy against the reference: error pixel rate, PSNR, max error.

use serde::Serialize;

use crate::{Frame, Image, OitError};

/// How far an image is from the reference, over covered pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Accuracy {
    /// Error pixel rate (HPG 2009 section 5.2): the share of covered pixels whose 8-bit colour
    /// differs from the reference by more than 1 in any channel.
    pub epr: f64,
    /// Peak signal-to-noise ratio in dB over covered pixels (infinite when identical).
    pub psnr: f64,
    /// The largest channel difference, in [0, 1] (8-bit difference / 255).
    pub max_error: f64,
    /// Covered pixels counted.
    pub covered: u64,
    /// Of those, pixels counted as errors.
    pub error_pixels: u64,
}

/// Compares `image` with the reference frame, over the pixels the reference covers (all pixels if
/// it did not record coverage).
pub fn accuracy(reference: &Frame, image: &Image) -> Result<Accuracy, OitError> {
    let r = &reference.image;
    if r.width != image.width || r.height != image.height {
        return Err(OitError::InvalidSettings(format!(
            "cannot compare a {}x{} image with a {}x{} reference",
            image.width, image.height, r.width, r.height
        )));
    }
    let mut acc = Accuracy::default();
    let mut squared = 0.0f64;
    let mut max = 0u8;
    for (i, (a, b)) in r.pixels.iter().zip(&image.pixels).enumerate() {
        if reference.layers.as_ref().is_some_and(|l| l[i] == 0) {
            continue;
        }
        acc.covered += 1;
        let mut worst = 0u8;
        for c in 0..3 {
            let d = a[c].abs_diff(b[c]);
            worst = worst.max(d);
            squared += f64::from(d) * f64::from(d);
        }
        max = max.max(worst);
        if worst > 1 {
            acc.error_pixels += 1;
        }
    }
    if acc.covered > 0 {
        acc.epr = acc.error_pixels as f64 / acc.covered as f64;
        let mse = squared / (acc.covered as f64 * 3.0);
        acc.psnr = if mse == 0.0 { f64::INFINITY } else { 10.0 * (255.0f64 * 255.0 / mse).log10() };
    } else {
        acc.psnr = f64::INFINITY;
    }
    acc.max_error = f64::from(max) / 255.0;
    Ok(acc)
}

/// An image of the per-pixel error, amplified ×8 (covered pixels only; uncovered are dark grey).
pub fn error_image(reference: &Frame, image: &Image) -> Image {
    let r = &reference.image;
    let mut out = Image::new(r.width, r.height, [40, 40, 40, 255]);
    for (i, (a, b)) in r.pixels.iter().zip(&image.pixels).enumerate() {
        if reference.layers.as_ref().is_some_and(|l| l[i] == 0) {
            continue;
        }
        let worst = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0);
        let t = (f32::from(worst) * 8.0 / 255.0).min(1.0);
        let h = crate::composite::heat(t);
        out.pixels[i] = [(h.x * 255.0) as u8, (h.y * 255.0) as u8, (h.z * 255.0) as u8, 255];
        if worst <= 1 {
            out.pixels[i] = [0, 0, 0, 255];
        }
    }
    out
}
