//! Row spans: per image row, one half-open range of columns. The rasteriser records in them
//! which pixels the moving meshes can have touched, and the camera which pixels of its images
//! differ from the still part of the scene, so that a frame recomputes and copies only those
//! (a person covers a fifth of the frame; the room behind does not move).

use std::ops::Range;

use crate::camera::{HEIGHT, WIDTH};

/// Per row `j`, the columns `lo..hi` (none when `lo >= hi`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Spans {
    rows: Vec<(u16, u16)>,
}

const NONE: (u16, u16) = (WIDTH as u16, 0);

impl Default for Spans {
    fn default() -> Self {
        Self::empty()
    }
}

impl Spans {
    /// No pixel.
    pub fn empty() -> Self {
        Self {
            rows: vec![NONE; HEIGHT],
        }
    }

    /// Every pixel.
    pub fn all() -> Self {
        Self {
            rows: vec![(0, WIDTH as u16); HEIGHT],
        }
    }

    pub fn clear(&mut self) {
        self.rows.fill(NONE);
    }

    /// Widens row `j`'s span to hold `lo..hi` (the hull of the two: one range per row).
    #[inline]
    pub fn add(&mut self, j: usize, lo: usize, hi: usize) {
        if lo >= hi {
            return;
        }
        if let Some(r) = self.rows.get_mut(j) {
            r.0 = r.0.min(lo.min(WIDTH) as u16);
            r.1 = r.1.max(hi.min(WIDTH) as u16);
        }
    }

    /// Row `j`'s columns (empty for a row without any, or out of the image).
    #[inline]
    pub fn row(&self, j: usize) -> Range<usize> {
        match self.rows.get(j) {
            Some(&(lo, hi)) if lo < hi => usize::from(lo)..usize::from(hi),
            _ => 0..0,
        }
    }

    /// The rows with a span, and their columns.
    pub fn iter(&self) -> impl Iterator<Item = (usize, Range<usize>)> + '_ {
        (0..HEIGHT)
            .map(|j| (j, self.row(j)))
            .filter(|(_, r)| !r.is_empty())
    }

    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.iter().next().is_none()
    }

    /// Every pixel of `self` or `other`, row by row (hulls).
    pub fn union(&mut self, other: &Spans) {
        for (j, r) in other.iter() {
            self.add(j, r.start, r.end);
        }
    }

    /// `self` with each pixel's 8 neighbours, clipped to the image, into `out`.
    pub fn grown_into(&self, out: &mut Spans) {
        out.clear();
        for (j, r) in self.iter() {
            let (lo, hi) = (r.start.saturating_sub(1), (r.end + 1).min(WIDTH));
            for jj in j.saturating_sub(1)..(j + 2).min(HEIGHT) {
                out.add(jj, lo, hi);
            }
        }
    }

    /// Pixels in all spans.
    #[cfg(test)]
    pub fn pixels(&self) -> usize {
        self.iter().map(|(_, r)| r.len()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spans_grow_merge_and_clip() {
        let mut s = Spans::empty();
        assert!(s.is_empty());
        s.add(0, 5, 9);
        s.add(0, 2, 3);
        s.add(HEIGHT, 0, 4);
        assert_eq!(s.row(0), 2..9);
        let mut g = Spans::empty();
        s.grown_into(&mut g);
        assert_eq!((g.row(0), g.row(1), g.row(2)), (1..10, 1..10, 0..0));
        let mut t = Spans::empty();
        t.add(HEIGHT - 1, WIDTH - 1, WIDTH);
        t.grown_into(&mut g);
        assert_eq!(g.row(HEIGHT - 2), WIDTH - 2..WIDTH);
        t.union(&s);
        assert_eq!(t.pixels(), 8);
    }
}
