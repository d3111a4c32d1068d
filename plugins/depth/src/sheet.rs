//! A recording's contact sheet: a grid of its depth frames, evenly spread over it, coloured
//! with [`crate::colour`] on one depth range, so a recording can be judged at a glance (is
//! the person in view, how much has no reading, does anything change) before it is replayed.
//!
//! The sheet is an RGB8 image in memory; writing it (as PNG) is the caller's business, so
//! this crate needs no image codec.

use std::sync::Arc;

use crate::camera::{DepthCamera, HEIGHT, WIDTH};
use crate::colour;
use crate::fakenect::{FakenectError, INDEX, Recording};

/// Pixels between two thumbnails and around the grid.
pub const GAP: u32 = 4;
/// The colour of the gaps and of the empty cells of the last row: dark grey, distinct from
/// the black of "no reading".
pub const GAP_COLOUR: [u8; 3] = [40, 40, 40];

/// Share of the readings left out at each end of the sheet's depth range, so a few stray
/// readings do not squeeze everything else into a couple of colours.
const RANGE_TAIL: f64 = 0.01;

/// A contact sheet: an RGB8 image, row-major from the top-left pixel.
#[derive(Clone, Debug)]
pub struct Sheet {
    pub width: u32,
    pub height: u32,
    /// `width * height * 3` bytes.
    pub rgb: Vec<u8>,
    /// The depth frames shown, left to right and top to bottom, as indices into the
    /// recording's depth frames (0 the first depth line of `INDEX.txt`).
    pub frames: Vec<usize>,
    /// The depth range coloured, millimetres: `near_mm` red, `far_mm` blue (for a legend).
    pub near_mm: u16,
    pub far_mm: u16,
}

/// Lays out up to `max_frames` depth frames of `recording`, evenly spread from its first to
/// its last, in a grid `columns` wide, each shrunk by `scale` (1: 640x480, 2: 320x240, ...;
/// each thumbnail pixel the mean colour of its `scale x scale` block, so a hole of no
/// readings stays black and an edge blends), with [`GAP`] pixels of [`GAP_COLOUR`] between
/// and around them.
///
/// One depth range for the whole sheet, so a colour means the same depth in every thumbnail:
/// the 1st to 99th percentile of the shown frames' readings (the camera's range if they have
/// none).
///
/// `columns`, `max_frames` and `scale` of 0 count as 1; `scale` is at most 480 (a one-pixel
/// thumbnail). Fails when a frame cannot be read, or when the recording has no depth frame
/// ([`FakenectError::NoDepth`]).
pub fn contact_sheet(
    recording: &Recording,
    camera: DepthCamera,
    columns: usize,
    max_frames: usize,
    scale: u32,
) -> Result<Sheet, FakenectError> {
    let entries: Vec<_> = recording.depth_entries().collect();
    if entries.is_empty() {
        return Err(FakenectError::NoDepth {
            index: recording.dir().join(INDEX),
        });
    }
    let frames = spread(entries.len(), max_frames.max(1));
    let depths = frames
        .iter()
        .map(|&i| Ok(recording.read_depth(entries[i], camera)?.depth_mm))
        .collect::<Result<Vec<Arc<[u16]>>, FakenectError>>()?;
    let (near_mm, far_mm) = depth_range(&depths).unwrap_or((
        (camera.min_m * 1000.0).round() as u16,
        (camera.max_m * 1000.0).round() as u16,
    ));

    let scale = scale.clamp(1, HEIGHT as u32) as usize;
    let (tile_w, tile_h) = (WIDTH / scale, HEIGHT / scale);
    let columns = columns.max(1).min(frames.len());
    let rows = frames.len().div_ceil(columns);
    let gap = GAP as usize;
    let width = columns * (tile_w + gap) + gap;
    let height = rows * (tile_h + gap) + gap;

    let mut rgb: Vec<u8> = GAP_COLOUR
        .iter()
        .copied()
        .cycle()
        .take(width * height * 3)
        .collect();
    let mut full = Vec::new();
    let mut tile = Vec::new();
    for (n, depth) in depths.iter().enumerate() {
        colour::colourise(depth, near_mm, far_mm, &mut full);
        shrink(&full, scale, &mut tile);
        let (x0, y0) = (
            gap + (n % columns) * (tile_w + gap),
            gap + (n / columns) * (tile_h + gap),
        );
        for (y, row) in tile.chunks_exact(tile_w * 3).enumerate() {
            let start = ((y0 + y) * width + x0) * 3;
            rgb[start..start + row.len()].copy_from_slice(row);
        }
    }
    Ok(Sheet {
        width: width as u32,
        height: height as u32,
        rgb,
        frames,
        near_mm,
        far_mm,
    })
}

/// `k` (at most `n`) indices into `0..n`, evenly spread, the first and the last included;
/// distinct because the step is at least one.
fn spread(n: usize, k: usize) -> Vec<usize> {
    let k = k.min(n);
    if k <= 1 {
        return (0..k).collect();
    }
    (0..k)
        .map(|i| (i * (n - 1) + (k - 1) / 2) / (k - 1))
        .collect()
}

/// The 1st and 99th percentiles of the readings (millimetres, 0 for none) of `frames`,
/// through a histogram; `None` when there is no reading. The far end is kept beyond the near
/// one, so the range is never empty.
fn depth_range(frames: &[Arc<[u16]>]) -> Option<(u16, u16)> {
    let mut histogram = vec![0u64; usize::from(u16::MAX) + 1];
    for &mm in frames.iter().flat_map(|f| f.iter()) {
        histogram[usize::from(mm)] += 1;
    }
    histogram[0] = 0;
    let count: u64 = histogram.iter().sum();
    if count == 0 {
        return None;
    }
    let tail = (count as f64 * RANGE_TAIL) as u64;
    // The depth of the reading at `rank` (0-based) in depth order.
    let at_rank = |rank: u64| {
        let mut seen = 0;
        histogram
            .iter()
            .position(|&c| {
                seen += c;
                seen > rank
            })
            .map_or(u16::MAX, |mm| mm as u16)
    };
    let near = at_rank(tail);
    let far = at_rank(count - 1 - tail);
    Some((near, far.max(near.saturating_add(1))))
}

/// Shrinks a 640x480 RGB8 image by `scale` in both directions into `out`, each pixel the
/// mean of its block (the right and bottom remainders, when `scale` does not divide the
/// size, are dropped).
fn shrink(rgb: &[u8], scale: usize, out: &mut Vec<u8>) {
    out.clear();
    if scale == 1 {
        out.extend_from_slice(rgb);
        return;
    }
    let (w, h) = (WIDTH / scale, HEIGHT / scale);
    let mut sums = vec![0u32; w * 3];
    let area = (scale * scale) as u32;
    for ty in 0..h {
        sums.fill(0);
        for y in ty * scale..(ty + 1) * scale {
            let row = &rgb[y * WIDTH * 3..][..w * scale * 3];
            for (x, px) in row.chunks_exact(3).enumerate() {
                let sum = &mut sums[(x / scale) * 3..][..3];
                for c in 0..3 {
                    sum[c] += u32::from(px[c]);
                }
            }
        }
        out.extend(sums.iter().map(|&s| ((s + area / 2) / area) as u8));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_spread_from_first_to_last() {
        assert_eq!(spread(5, 4), [0, 1, 3, 4]);
        assert_eq!(spread(100, 3), [0, 50, 99]);
        assert_eq!(spread(3, 10), [0, 1, 2]);
        assert_eq!(spread(7, 1), [0]);
        assert_eq!(spread(1, 1), [0]);
        for n in 1..40 {
            for k in 1..=n {
                let picked = spread(n, k);
                assert_eq!(picked.len(), k);
                assert!(
                    picked.windows(2).all(|w| w[0] < w[1]),
                    "{n} {k}: {picked:?}"
                );
                assert_eq!(picked.last(), Some(&(n - 1)).filter(|_| k > 1).or(Some(&0)));
            }
        }
    }

    #[test]
    fn the_range_leaves_out_stray_readings() {
        let mut frame = vec![2000u16; 1000];
        frame[..5].fill(500); // 0.5 %: stray
        frame[5..100].fill(1000);
        frame[900..].fill(3000);
        frame[999] = 9000; // stray
        frame[500..600].fill(0); // no readings: not counted
        let range = depth_range(&[frame.into()]);
        assert_eq!(range, Some((1000, 3000)));
        assert_eq!(depth_range(&[vec![0u16; 10].into()]), None);
        assert_eq!(depth_range(&[vec![1500u16; 10].into()]), Some((1500, 1501)));
    }

    #[test]
    fn shrinking_averages_blocks() {
        let rgb: Vec<u8> = (0..crate::PIXELS)
            .flat_map(|i| {
                let (u, v) = (i % WIDTH, i / WIDTH);
                [(u % 2) as u8 * 100, (v % 2) as u8 * 50, 7]
            })
            .collect();
        let mut out = Vec::new();
        shrink(&rgb, 2, &mut out);
        assert_eq!(out.len(), 320 * 240 * 3);
        assert!(out.chunks_exact(3).all(|px| px == [50, 25, 7]));
        shrink(&rgb, 3, &mut out);
        assert_eq!(out.len(), 213 * 160 * 3);
        shrink(&rgb, 1, &mut out);
        assert_eq!(out, rgb);
    }
}
