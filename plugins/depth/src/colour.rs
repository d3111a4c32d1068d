//! A colour map for depth images: the contact sheet of a recording ([`crate::sheet`]) and the
//! kiosk's picture-in-picture view show depth in colour, near warm (red) to far cool (blue),
//! and a pixel without a reading black, so a hole in the readings is never mistaken for a
//! depth.
//!
//! The map is Google's Turbo (Anton Mikhailov, 2019, "Turbo, An Improved Rainbow Colormap for
//! Visualization", <https://research.google/blog/turbo-an-improved-rainbow-colormap-for-visualization/>),
//! evaluated through its published polynomial approximation (Ruofei Du, Google, Apache-2.0,
//! <https://gist.github.com/mikhailov-work/0d177465a8151eb6ede1768d51d476c7>): each channel
//! a degree-5 polynomial of the position `x` in 0-1. Turbo's hue runs in one direction from
//! blue through cyan, green and yellow to red, so colour order is depth order at a glance.
//! Only `x` in [`X_FAR`]..[`X_NEAR`] is used: Turbo's own ends are nearly black (dark
//! violet at 0, dark red at 1), which would read as "no reading".
//!
//! The map is sampled once into 256 levels, at compile time: colouring a 640x480 frame is a
//! subtraction, a multiplication and a table look-up per pixel.

/// The colour of a pixel without a reading.
pub const NO_READING: [u8; 3] = [0, 0, 0];

/// Turbo's position for the far end of the range (a saturated blue).
pub const X_FAR: f64 = 0.10;
/// Turbo's position for the near end of the range (a dark but clearly red red).
pub const X_NEAR: f64 = 0.95;

/// Colour levels between far and near.
const LEVELS: usize = 256;

/// The coefficients of `x^0..x^5` of Turbo's red, green and blue (Du's approximation; the
/// gist groups them as a `vec4` and a `vec2` per channel).
const TURBO: [[f64; 6]; 3] = [
    [
        0.135_721_38,
        4.615_392_60,
        -42.660_322_58,
        132.131_082_34,
        -152.942_393_96,
        59.286_379_43,
    ],
    [
        0.091_402_61,
        2.194_188_39,
        4.842_966_58,
        -14.185_033_33,
        4.277_298_57,
        2.829_566_04,
    ],
    [
        0.106_673_30,
        12.641_946_08,
        -60.582_048_36,
        110.362_767_71,
        -89.903_109_12,
        27.348_249_73,
    ],
];

/// Turbo at `x` (0-1), 8 bits per channel; the polynomial slightly overshoots 0-1 near the
/// ends, so each channel is clamped before rounding.
const fn turbo(x: f64) -> [u8; 3] {
    let mut rgb = [0u8; 3];
    let mut c = 0;
    while c < 3 {
        let k = &TURBO[c];
        // Horner's rule.
        let mut v = k[5];
        let mut i = 5;
        while i > 0 {
            i -= 1;
            v = v * x + k[i];
        }
        let v = if v < 0.0 {
            0.0
        } else if v > 1.0 {
            1.0
        } else {
            v
        };
        rgb[c] = (v * 255.0 + 0.5) as u8;
        c += 1;
    }
    rgb
}

/// The map's levels: index 0 the far colour, `LEVELS - 1` the near colour.
const TABLE: [[u8; 3]; LEVELS] = {
    let mut table = [[0u8; 3]; LEVELS];
    let mut i = 0;
    while i < LEVELS {
        let t = i as f64 / (LEVELS - 1) as f64;
        table[i] = turbo(X_FAR + (X_NEAR - X_FAR) * t);
        i += 1;
    }
    table
};

/// How [`depth_colour`] and [`colourise`] place a depth between `near_mm` and `far_mm`,
/// worked out once per image.
#[derive(Clone, Copy)]
struct Scale {
    far: f32,
    /// Levels per millimetre towards the near end (negative when `near_mm > far_mm`, which
    /// the arithmetic handles as it stands; 0 for `near_mm == far_mm`).
    levels_per_mm: f32,
    near_mm: u16,
    degenerate: bool,
}

impl Scale {
    fn new(near_mm: u16, far_mm: u16) -> Self {
        let span = f32::from(far_mm) - f32::from(near_mm);
        Self {
            far: f32::from(far_mm),
            levels_per_mm: if span == 0.0 {
                0.0
            } else {
                (LEVELS - 1) as f32 / span
            },
            near_mm,
            degenerate: span == 0.0,
        }
    }

    #[inline]
    fn colour(self, mm: u16) -> [u8; 3] {
        if mm == 0 {
            return NO_READING;
        }
        let level = if self.degenerate {
            // No span to spread over: at or nearer than the one depth is near, beyond it far.
            if mm <= self.near_mm { LEVELS - 1 } else { 0 }
        } else {
            // Clamped into the table: depths beyond the range take its end colours. The cast
            // of a value in 0..=255.5 truncates, rounding to the nearest level.
            ((self.far - f32::from(mm)) * self.levels_per_mm + 0.5).clamp(0.0, (LEVELS - 1) as f32)
                as usize
        };
        TABLE[level]
    }
}

/// The colour of a depth of `mm` millimetres on a map from `near_mm` (warm: red) to `far_mm`
/// (cool: blue); depths outside the range take the colour of its nearer end. `mm == 0` (no
/// reading) is [`NO_READING`], black, which no depth is given.
///
/// `near_mm` always gets the warm end, even if it is the larger number; with
/// `near_mm == far_mm`, depths up to it are red and beyond it blue.
pub fn depth_colour(mm: u16, near_mm: u16, far_mm: u16) -> [u8; 3] {
    Scale::new(near_mm, far_mm).colour(mm)
}

/// Colours a depth image (millimetres, 0 for no reading; a 640x480 frame or any other size)
/// into `out_rgb`, three bytes per pixel in the same order, as [`depth_colour`] does. The
/// buffer is cleared and refilled, so a caller colouring every frame allocates once.
pub fn colourise(frame_mm: &[u16], near_mm: u16, far_mm: u16, out_rgb: &mut Vec<u8>) {
    let scale = Scale::new(near_mm, far_mm);
    out_rgb.clear();
    out_rgb.reserve(frame_mm.len() * 3);
    out_rgb.extend(frame_mm.iter().flat_map(|&mm| scale.colour(mm)));
}

#[cfg(test)]
mod tests {
    use super::*;

    const NEAR: u16 = 800;
    const FAR: u16 = 4000;

    /// Hue in degrees (0 red, 120 green, 240 blue).
    fn hue([r, g, b]: [u8; 3]) -> f32 {
        let (r, g, b) = (f32::from(r), f32::from(g), f32::from(b));
        let max = r.max(g).max(b);
        let delta = max - r.min(g).min(b);
        assert!(delta > 0.0, "grey has no hue");
        let h = if max == r {
            ((g - b) / delta).rem_euclid(6.0)
        } else if max == g {
            (b - r) / delta + 2.0
        } else {
            (r - g) / delta + 4.0
        };
        60.0 * h
    }

    #[test]
    fn no_reading_is_black_and_no_depth_is() {
        assert_eq!(depth_colour(0, NEAR, FAR), NO_READING);
        assert_eq!(depth_colour(0, 0, 0), NO_READING);
        // Every level is clearly brighter than black.
        for level in TABLE {
            assert!(*level.iter().max().expect("three") >= 100, "{level:?}");
        }
    }

    /// Near is red, far blue: the channel order says so.
    #[test]
    fn near_is_warm_and_far_is_cool() {
        let [r, g, b] = depth_colour(NEAR, NEAR, FAR);
        assert!(r > g && g > b, "near {:?}", [r, g, b]);
        let [r, g, b] = depth_colour(FAR, NEAR, FAR);
        assert!(b > g && g > r, "far {:?}", [r, g, b]);
        assert_ne!(depth_colour(NEAR, NEAR, FAR), depth_colour(FAR, NEAR, FAR));
    }

    /// Hue rises with depth from red (about 6°) to blue (about 234°) and never falls by more
    /// than the rounding to 8 bits can make it (under half a degree).
    #[test]
    fn hue_is_monotonic_in_depth() {
        let mut last = hue(depth_colour(NEAR, NEAR, FAR));
        assert!(last < 15.0, "near hue {last}");
        for mm in NEAR..=FAR {
            let h = hue(depth_colour(mm, NEAR, FAR));
            assert!(h >= last - 0.5, "{mm} mm: hue {h} after {last}");
            last = last.max(h);
        }
        assert!(last > 225.0, "far hue {last}");
        // Every level is used: no two neighbouring levels alike.
        let mut levels = TABLE.to_vec();
        levels.dedup();
        assert_eq!(levels.len(), LEVELS);
    }

    #[test]
    fn out_of_range_depths_clamp_to_the_ends() {
        assert_eq!(depth_colour(1, NEAR, FAR), depth_colour(NEAR, NEAR, FAR));
        assert_eq!(depth_colour(500, NEAR, FAR), depth_colour(NEAR, NEAR, FAR));
        assert_eq!(depth_colour(9000, NEAR, FAR), depth_colour(FAR, NEAR, FAR));
        assert_eq!(depth_colour(u16::MAX, NEAR, FAR), TABLE[0]);
        assert_eq!(depth_colour(NEAR, NEAR, FAR), TABLE[LEVELS - 1]);
    }

    #[test]
    fn near_keeps_the_warm_end_in_any_order_and_for_an_empty_range() {
        assert_eq!(depth_colour(4000, 4000, 800), TABLE[LEVELS - 1]);
        assert_eq!(depth_colour(800, 4000, 800), TABLE[0]);
        assert_eq!(depth_colour(2000, 2000, 2000), TABLE[LEVELS - 1]);
        assert_eq!(depth_colour(2001, 2000, 2000), TABLE[0]);
    }

    #[test]
    fn colourise_matches_depth_colour_and_reuses_the_buffer() {
        let frame: Vec<u16> = (0..crate::PIXELS).map(|i| (i % 5000) as u16).collect();
        let mut rgb = Vec::new();
        colourise(&frame, NEAR, FAR, &mut rgb);
        assert_eq!(rgb.len(), crate::PIXELS * 3);
        for (mm, px) in frame.iter().zip(rgb.chunks_exact(3)) {
            assert_eq!(px, depth_colour(*mm, NEAR, FAR));
        }
        let buffer = rgb.as_ptr();
        colourise(&frame, NEAR, FAR, &mut rgb);
        assert_eq!(rgb.as_ptr(), buffer, "the buffer was reallocated");
        colourise(&frame[..10], NEAR, FAR, &mut rgb);
        assert_eq!(rgb.len(), 30);
    }
}
