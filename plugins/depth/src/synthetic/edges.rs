//! Where the device loses readings around depth edges, per pixel, as bit flags: the
//! projector's shadow, a part one pixel thin, a pixel beside a depth jump. Each is found in
//! a pass over the inverse-depth image (`1/z`, 0 = nothing) without a division; or, when
//! only some pixels' depths changed (a person moving in front of a still room), over the
//! pixels those can affect ([`mark_edges_in`], [`mark_shadow_in`]), with the same result.

use super::spans::Spans;
use crate::camera::{DepthCamera, HEIGHT, PIXELS, WIDTH};

/// Beside a jump of more than 3 cm or 2 % in depth (the device loses such pixels on a coin
/// toss: the correlation window straddles the edge).
pub const JUMP: u8 = 1;
/// Nearer than both neighbours along a row or a column, which are both beyond a jump: a part
/// one pixel thin (always lost).
pub const THIN: u8 = 2;
/// Not lit by the projector.
pub const SHADOW: u8 = 4;

/// Scratch images of the edge passes, kept between frames.
#[derive(Clone, Debug)]
pub struct EdgeFlags {
    /// Per pixel, [`JUMP`], [`THIN`] and [`SHADOW`].
    pub flags: Vec<u8>,
    /// [`pair`] of each pixel and the next along its row, and the one below it.
    across: Vec<u8>,
    down: Vec<u8>,
    /// Per pixel, the state of the shadow's sweep after it ([`mark_shadow`]), so that
    /// another sweep can start at any pixel ([`mark_shadow_in`]).
    pub(crate) run: Vec<f32>,
}

impl Default for EdgeFlags {
    fn default() -> Self {
        Self {
            flags: vec![0; PIXELS],
            across: vec![0; PIXELS],
            down: vec![0; PIXELS],
            run: vec![f32::INFINITY; PIXELS],
        }
    }
}

impl EdgeFlags {
    /// The flags of every pixel of `inverse_z`. Border pixels are never [`JUMP`] or [`THIN`].
    pub fn compute(
        &mut self,
        inverse_z: &[f32],
        camera: &DepthCamera,
        shadow: bool,
        dropouts: bool,
    ) {
        self.flags.fill(0);
        if dropouts {
            mark_edges(inverse_z, &mut self.across, &mut self.down, &mut self.flags);
        }
        if shadow {
            mark_shadow(inverse_z, camera, &mut self.flags, &mut self.run);
        }
    }
}

/// Of a neighbouring pair `(a, b)` of inverse depths: bit 0 a jump between them, bit 1 `a`
/// the nearer across it, bit 2 `b` the nearer.
#[inline]
fn pair(a: f32, b: f32) -> u8 {
    // |z1 - z2| > max(0.03, 0.02 min(z1, z2)) multiplied by (1/z1)(1/z2); nothing (0)
    // beside something is a jump.
    let lower = if a < b { a } else { b };
    let (x, y) = (0.03 * a * b, 0.02 * lower);
    let jump = (a - b).abs() > if x > y { x } else { y };
    u8::from(jump) | (u8::from(jump && a > b) << 1) | (u8::from(jump && b > a) << 2)
}

fn mark_edges(iz: &[f32], across: &mut [u8], down: &mut [u8], flags: &mut [u8]) {
    // Pairs along rows (pixel k and k + 1) and along columns (k and k + WIDTH).
    for (p, w) in across.iter_mut().zip(iz.windows(2)) {
        *p = pair(w[0], w[1]);
    }
    for ((p, &a), &b) in down.iter_mut().zip(iz).zip(&iz[WIDTH..]) {
        *p = pair(a, b);
    }
    for j in 1..HEIGHT - 1 {
        let row = j * WIDTH;
        for k in row + 1..row + WIDTH - 1 {
            let (l, r, u, d) = (across[k - 1], across[k], down[k - WIDTH], down[k]);
            flags[k] |= edge_bits(l, r, u, d);
        }
    }
}

/// [`JUMP`] or [`THIN`] of a pixel from its pairs with the pixels left, right, above and
/// below it.
#[inline]
fn edge_bits(l: u8, r: u8, u: u8, d: u8) -> u8 {
    // Nearer than the pixel before (bit 2 of the pair before) and the one after (bit 1 of
    // its own pair).
    let thin = (l & r >> 1 & 2) | (u & d >> 1 & 2);
    let jump = (l | r | u | d) & JUMP;
    if thin != 0 { THIN } else { jump }
}

for_this_cpu! {
/// [`mark_edges`] over the pixels of `spans` only (their [`SHADOW`] bits kept): the same
/// flags as a pass over the whole image where `spans` holds every pixel whose depth changed
/// and its neighbours.
pub(crate) fn mark_edges_in(iz: &[f32], spans: &Spans, flags: &mut [u8]) {
    for (j, r) in spans.iter() {
        if j == 0 || j + 1 >= HEIGHT {
            continue;
        }
        let row = j * WIDTH;
        for k in row + r.start.max(1)..row + r.end.min(WIDTH - 1) {
            let c = iz[k];
            let (l, r) = (pair(iz[k - 1], c), pair(c, iz[k + 1]));
            let (u, d) = (pair(iz[k - WIDTH], c), pair(c, iz[k + WIDTH]));
            flags[k] = (flags[k] & SHADOW) | edge_bits(l, r, u, d);
        }
    }
}
}

/// The projector looks along the same axis from `b` to the sensor's right with the same
/// intrinsics, so a point seen at `(u, v)` at depth `z` is at `(u - f b / z, v)` in the
/// projector's image: the same row. Nearer points shift further left, so only points to a
/// pixel's right can hide it from the projector; sweeping each row from the right, a pixel is
/// in shadow when a point already swept lands left of it in the projector's image (the
/// ordering constraint of stereo). Surfaces the camera does not see cannot shadow here: for a
/// person in a room they are behind what it sees.
///
/// `run` receives, per pixel, the sweep's state after it: the leftmost projector column of
/// the pixel and those right of it.
fn mark_shadow(iz: &[f32], camera: &DepthCamera, flags: &mut [u8], run: &mut [f32]) {
    let shift = camera.fx * camera.baseline_m;
    for ((row_iz, row_flags), row_run) in iz
        .chunks_exact(WIDTH)
        .zip(flags.chunks_exact_mut(WIDTH))
        .zip(run.chunks_exact_mut(WIDTH))
    {
        let mut leftmost = f32::INFINITY;
        for i in (0..WIDTH).rev() {
            let (shadowed, next) = shadow_step(row_iz[i], i, shift, leftmost);
            row_flags[i] |= SHADOW * u8::from(shadowed);
            leftmost = next;
            row_run[i] = leftmost;
        }
    }
}

/// One pixel of the shadow's sweep: whether the pixel at column `i` with inverse depth `z`
/// is in shadow with `leftmost` the sweep's state before it, and the state after it.
#[inline]
fn shadow_step(z: f32, i: usize, shift: f32, leftmost: f32) -> (bool, f32) {
    // Nothing seen (0): neither shadowed nor shadowing.
    let u = if z > 0.0 {
        i as f32 - shift * z
    } else {
        f32::INFINITY
    };
    (
        z > 0.0 && u > leftmost,
        if u < leftmost { u } else { leftmost },
    )
}

/// [`mark_shadow`] where the depths changed only within `changed`, from the sweep's state
/// `still_run` over the image before the change (whose flags `flags` holds): per row, the
/// sweep restarts at the right end of the row's span and goes left until its state is again
/// the old one, past which nothing changes. The pixels whose flag was recomputed go into
/// `swept`.
pub(crate) fn mark_shadow_in(
    iz: &[f32],
    camera: &DepthCamera,
    changed: &Spans,
    still_run: &[f32],
    flags: &mut [u8],
    swept: &mut Spans,
) {
    let shift = camera.fx * camera.baseline_m;
    for (j, r) in changed.iter() {
        let row = j * WIDTH;
        let mut leftmost = if r.end < WIDTH {
            still_run[row + r.end]
        } else {
            f32::INFINITY
        };
        let mut first = 0;
        for i in (0..r.end).rev() {
            let k = row + i;
            let (shadowed, next) = shadow_step(iz[k], i, shift, leftmost);
            flags[k] = (flags[k] & !SHADOW) | (SHADOW * u8::from(shadowed));
            leftmost = next;
            if i < r.start && leftmost == still_run[k] {
                first = i;
                break;
            }
        }
        swept.add(j, first, r.end);
    }
}
