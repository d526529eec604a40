//! Multisampling (issue 40): the sample counts oit takes and the standard sample positions of
//! the graphics APIs, defined once here for every backend.
//!
//! With `Settings::samples` above 1 a triangle gives a pixel a fragment where it covers any of
//! the pixel's samples, and the fragment carries its coverage mask (bit `i` set where sample
//! `i` is covered). Shading and depth stay one evaluation at the pixel's centre (MSAA, not
//! supersampling). See docs/msaa.md.

use crate::OitError;

/// The sample counts `--samples` takes.
pub const SAMPLE_COUNTS: [u32; 3] = [1, 4, 8];

/// Positions are given in 1/16 pixel from the pixel's top-left corner (x right, y down): the
/// grid the standard patterns lie on, exact in oit's 1/256-pixel fixed point.
pub const POSITION_UNITS: u32 = 16;

/// The single sample: the pixel's centre.
pub const POSITIONS_1: [(u8, u8); 1] = [(8, 8)];

/// Vulkan's and Direct3D's standard 4× pattern (the Vulkan spec's "standard sample locations"
/// table), in 1/16 pixel: (0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875).
pub const POSITIONS_4: [(u8, u8); 4] = [(6, 2), (14, 6), (2, 10), (10, 14)];

/// The standard 8× pattern, in 1/16 pixel: (0.5625, 0.3125), (0.4375, 0.6875), (0.8125, 0.5625),
/// (0.3125, 0.1875), (0.1875, 0.8125), (0.0625, 0.4375), (0.6875, 0.9375), (0.9375, 0.0625).
pub const POSITIONS_8: [(u8, u8); 8] = [(9, 5), (7, 11), (13, 9), (5, 3), (3, 13), (1, 7), (11, 15), (15, 1)];

/// Checks a sample count: 1, 4 or 8.
pub fn check_samples(samples: u32) -> Result<(), OitError> {
    if SAMPLE_COUNTS.contains(&samples) {
        Ok(())
    } else {
        Err(OitError::InvalidSettings(format!(
            "--samples {samples} is not a sample count oit takes: use 1, 4 or 8 (the standard patterns)"
        )))
    }
}

/// The sample positions of `samples` samples a pixel, in 1/16 pixel from its top-left corner
/// ([`POSITION_UNITS`]); the centre alone for 1 or any count [`check_samples`] refuses.
pub fn positions(samples: u32) -> &'static [(u8, u8)] {
    match samples {
        4 => &POSITIONS_4,
        8 => &POSITIONS_8,
        _ => &POSITIONS_1,
    }
}

/// The sample positions in pixels from the top-left corner, as floats (exact).
pub fn positions_f32(samples: u32) -> Vec<(f32, f32)> {
    positions(samples)
        .iter()
        .map(|&(x, y)| (f32::from(x) / POSITION_UNITS as f32, f32::from(y) / POSITION_UNITS as f32))
        .collect()
}

/// The mask of every sample of a pixel: `samples` low bits set.
pub fn full_mask(samples: u32) -> u8 {
    match samples {
        8.. => u8::MAX,
        n => ((1u16 << n) - 1) as u8,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_are_the_standard_ones() {
        let p4 = positions_f32(4);
        assert_eq!(p4, vec![(0.375, 0.125), (0.875, 0.375), (0.125, 0.625), (0.625, 0.875)]);
        let p8 = positions_f32(8);
        assert_eq!(p8[0], (0.5625, 0.3125));
        assert_eq!(p8[7], (0.9375, 0.0625));
        assert_eq!(positions_f32(1), vec![(0.5, 0.5)]);
        assert_eq!((full_mask(1), full_mask(4), full_mask(8)), (1, 0xF, 0xFF));
        assert!(check_samples(2).is_err() && check_samples(0).is_err() && check_samples(16).is_err());
    }
}
