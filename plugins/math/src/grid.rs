//! A uniform grid of cubic cells over 3-D space, stored sparsely: the one spatial index for
//! "which items are near this point" (nearest body vertex of a garment particle, nearest
//! body triangle of a point, garment points within reach of the skin).

use std::collections::HashMap;

use glam::{IVec3, Vec3};

/// Items (indices into the caller's arrays) binned by the cells their point or box touches.
#[derive(Clone, Debug)]
pub struct CellGrid {
    cell: f32,
    cells: HashMap<IVec3, Vec<u32>>,
    /// The occupied cells' bounding box (empty when `lo > hi`).
    lo: IVec3,
    hi: IVec3,
}

impl CellGrid {
    /// An empty grid of cells `cell` metres wide (must be positive and finite).
    pub fn new(cell: f32) -> Self {
        debug_assert!(cell > 0.0 && cell.is_finite(), "cell size {cell}");
        Self {
            cell,
            cells: HashMap::new(),
            lo: IVec3::MAX,
            hi: IVec3::MIN,
        }
    }

    /// `points[i]` binned as item `i`; non-finite points are left out.
    pub fn of_points(points: &[Vec3], cell: f32) -> Self {
        let mut grid = Self::new(cell);
        for (i, &p) in points.iter().enumerate() {
            grid.insert(i as u32, p);
        }
        grid
    }

    pub fn cell_size(&self) -> f32 {
        self.cell
    }

    /// The cell holding `p`.
    pub fn cell_of(&self, p: Vec3) -> IVec3 {
        (p / self.cell).floor().as_ivec3()
    }

    /// Bins `item` at point `p` (ignored if `p` is not finite).
    pub fn insert(&mut self, item: u32, p: Vec3) {
        if p.is_finite() {
            self.insert_box(item, p, p);
        }
    }

    /// Bins `item` in every cell the box `lo..=hi` touches (ignored if not finite).
    pub fn insert_box(&mut self, item: u32, lo: Vec3, hi: Vec3) {
        if !(lo.is_finite() && hi.is_finite()) {
            return;
        }
        let (a, b) = (self.cell_of(lo.min(hi)), self.cell_of(lo.max(hi)));
        self.lo = self.lo.min(a);
        self.hi = self.hi.max(b);
        for x in a.x..=b.x {
            for y in a.y..=b.y {
                for z in a.z..=b.z {
                    self.cells
                        .entry(IVec3::new(x, y, z))
                        .or_default()
                        .push(item);
                }
            }
        }
    }

    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// The items of the `(2 reach + 1)³` cells centred on `p`'s cell (an item binned in
    /// several of them comes once per cell).
    pub fn around(&self, p: Vec3, reach: i32) -> impl Iterator<Item = u32> + '_ {
        let c = self.cell_of(p);
        let span = -reach..=reach;
        span.clone()
            .flat_map(move |x| {
                let span = span.clone();
                span.clone()
                    .flat_map(move |y| span.clone().map(move |z| IVec3::new(x, y, z)))
            })
            .filter_map(move |d| self.cells.get(&(c + d)))
            .flatten()
            .copied()
    }

    /// The item nearest to `p` by the caller's squared distance (`None` skips an item), with
    /// that squared distance. Exact when every item lies within the cells it is binned in
    /// (a point in its cell, a triangle in its box's cells): the search visits shells of
    /// cells around `p`'s until the best distance is below the next shell's reach. Of equal
    /// distances the lowest item wins, so the answer does not depend on the visiting order.
    pub fn nearest(
        &self,
        p: Vec3,
        mut distance2: impl FnMut(u32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        if self.is_empty() || !p.is_finite() {
            return None;
        }
        let c = self.cell_of(p);
        // Beyond this shell every occupied cell has been visited.
        let last = (c - self.lo).abs().max((self.hi - c).abs()).max_element();
        let mut best: Option<(f32, u32)> = None;
        for r in 0..=last {
            // Every point of shell r's cells is at least (r - 1) cells from p.
            if let Some((d2, _)) = best
                && d2.sqrt() < (r - 1) as f32 * self.cell
            {
                break;
            }
            // The shell's cells, clipped to the occupied box (far shells cost nothing).
            let (a, b) = ((c - r).max(self.lo), (c + r).min(self.hi));
            for x in a.x..=b.x {
                for y in a.y..=b.y {
                    let on_face = (x - c.x).abs() == r || (y - c.y).abs() == r;
                    // Off the x and y faces, only the two z faces are on the shell.
                    let zs = if on_face {
                        (a.z..=b.z).step_by(1)
                    } else {
                        (c.z - r..=c.z + r).step_by((2 * r).max(1) as usize)
                    };
                    for z in zs {
                        let Some(items) = self.cells.get(&IVec3::new(x, y, z)) else {
                            continue;
                        };
                        for &item in items {
                            let Some(d2) = distance2(item) else {
                                continue;
                            };
                            if best.is_none_or(|(bd, bi)| d2 < bd || (d2 == bd && item < bi)) {
                                best = Some((d2, item));
                            }
                        }
                    }
                }
            }
        }
        best.map(|(d2, item)| (item, d2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (no dependency for a test's scatter).
    fn scatter(n: usize, seed: u64) -> Vec<Vec3> {
        let mut s = seed;
        let mut next = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 33) as f32 / (1u64 << 31) as f32) * 2.0 - 1.0
        };
        (0..n)
            .map(|_| Vec3::new(next(), next() * 0.5, next() * 2.0))
            .collect()
    }

    /// Against a brute-force search over every point, with a cell much smaller than the
    /// spacing of some queries (far queries walk many shells) and much larger for others.
    #[test]
    fn nearest_agrees_with_brute_force() {
        let points = scatter(500, 7);
        for cell in [0.02, 0.1, 0.4] {
            let grid = CellGrid::of_points(&points, cell);
            for q in scatter(200, 99).into_iter().map(|q| q * 1.7) {
                let (item, d2) = grid
                    .nearest(q, |i| Some(points[i as usize].distance_squared(q)))
                    .expect("a nearest point");
                let brute = points
                    .iter()
                    .map(|p| p.distance_squared(q))
                    .fold(f32::INFINITY, f32::min);
                assert_eq!(d2, brute, "cell {cell}, query {q}");
                assert_eq!(points[item as usize].distance_squared(q), brute);
            }
        }
    }

    #[test]
    fn ties_go_to_the_lowest_item_and_filters_skip() {
        let points = [Vec3::X, -Vec3::X, Vec3::Y * 5.0];
        let grid = CellGrid::of_points(&points, 0.3);
        let d = |i: u32| Some(points[i as usize].distance_squared(Vec3::ZERO));
        assert_eq!(grid.nearest(Vec3::ZERO, d), Some((0, 1.0)));
        let skip_first = |i: u32| (i != 0).then(|| points[i as usize].distance_squared(Vec3::ZERO));
        assert_eq!(grid.nearest(Vec3::ZERO, skip_first), Some((1, 1.0)));
        assert_eq!(CellGrid::new(0.1).nearest(Vec3::ZERO, d), None);
        assert_eq!(grid.nearest(Vec3::NAN, d), None);
    }

    #[test]
    fn around_lists_the_neighbouring_cells_and_boxes_cover_their_cells() {
        let mut grid = CellGrid::new(1.0);
        grid.insert(0, Vec3::new(0.5, 0.5, 0.5));
        grid.insert(1, Vec3::new(1.5, 0.5, 0.5));
        grid.insert(2, Vec3::new(2.5, 0.5, 0.5));
        grid.insert(3, Vec3::NAN);
        grid.insert_box(4, Vec3::new(-3.0, 0.2, 0.2), Vec3::new(-1.5, 0.3, 0.3));
        let mut near: Vec<u32> = grid.around(Vec3::new(0.5, 0.5, 0.5), 1).collect();
        near.sort_unstable();
        assert_eq!(near, vec![0, 1]);
        let far: Vec<u32> = grid.around(Vec3::new(-2.5, 0.5, 0.5), 0).collect();
        assert_eq!(far, vec![4]);
    }
}
