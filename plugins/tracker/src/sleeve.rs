//! A short sleeve's end: a witness of a shirt that bare skin does not give. A T-shirt's sleeve
//! is a tube wider than the arm it ends on, so the outer edge of a hanging upper arm's outline
//! steps inwards where the sleeve ends, by the sleeve's stand-off (2-5 cm); a bare upper arm
//! tapers smoothly from the shoulder to the elbow. The outline is the person's mask, read
//! across the rows between the tracked shoulder and elbow, whose pixels are 4-5 mm wide at
//! 2-3 m: finer than the depth's 12-28 mm steps there, in which the sleeve's stand-off is lost.
//!
//! Measured on the first three frames of the 180 bare and T-shirt recordings of the
//! acceptance set's two noises (docs/STATUS.md, session 49): the median step was 20 mm or
//! more on 78 of the 90 T-shirt recordings and on 1 of the 90 bare ones, under 10 mm on 76
//! bare and no T-shirt; the rest, and the recordings whose arms are not hanging then, are
//! left to the body fit's costs ([`crate::shape::estimate_with`]).

use fitroom_depth::{DepthFrame, HEIGHT, WIDTH};
use fitroom_sensor::KinectJoint;
use glam::Vec3;

/// Rows above and below a row whose outlines' medians are compared.
const WINDOW: usize = 6;
/// Gaps in the mask up to this many pixels wide are bridged when following an outline
/// outwards (the sensor's holes at a silhouette's edge).
const GAP: usize = 4;
/// How far from the tracked arm's line its outline is looked for, pixels.
const REACH: usize = 8;

/// What the sleeves' ends say about a shirt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sleeves {
    /// A sleeve's end is seen: the person wears a shirt.
    Seen,
    /// The upper arms are bare.
    Bare,
    /// Too few hanging arms seen, or a step between the two thresholds.
    Unsure,
}

/// The median of the steps measured (metres; [`steps`]), if there are at least three.
pub fn median_step(steps: &[f32]) -> Option<f32> {
    (steps.len() >= 3).then(|| median(steps.to_vec())).flatten()
}

/// The median step ([`median_step`]) against the thresholds: at least `seen_m` a shirt,
/// under `bare_m` bare skin.
pub fn judge(steps: &[f32], seen_m: f32, bare_m: f32) -> Sleeves {
    match median_step(steps) {
        Some(m) if m >= seen_m => Sleeves::Seen,
        Some(m) if m < bare_m => Sleeves::Bare,
        _ => Sleeves::Unsure,
    }
}

/// The inward step (metres) in the outer outline of each upper arm that hangs down in `frame`
/// (`mask`: the person's pixels; `joints`: the tracked joints, sensor space, and their
/// pixels): over the rows from the shoulder to a little below the elbow, the largest
/// difference between the outline's median over [`WINDOW`] rows and over the [`WINDOW`] rows
/// below, the arm's own taper taken off. An arm raised, held across, or
/// too short in the image gives none.
pub fn steps(frame: &DepthFrame, mask: &[bool], joints: &[(Vec3, [f32; 2])]) -> Vec<f32> {
    use KinectJoint::*;
    let mut out = Vec::new();
    if mask.len() != WIDTH * HEIGHT || joints.len() != KinectJoint::COUNT {
        return out;
    }
    for (shoulder, elbow, other) in [
        (ShoulderLeft, ElbowLeft, ShoulderRight),
        (ShoulderRight, ElbowRight, ShoulderLeft),
    ] {
        let (s, e, o) = (
            joints[shoulder.index()],
            joints[elbow.index()],
            joints[other.index()],
        );
        let [su, sv] = s.1;
        let [eu, ev] = e.1;
        let (du, dv) = (eu - su, ev - sv);
        // Hanging: the elbow well below the shoulder, not far out to a side.
        let hanging = dv >= 10.0 && du.abs() <= 0.6 * dv;
        let in_front = s.0.z > 0.0 && s.0.z.is_finite();
        if !(hanging && in_front) {
            continue;
        }
        // Outwards: away from the other shoulder.
        let outwards = if su >= o.1[0] { 1i64 } else { -1 };
        // From just below the shoulder to below the elbow: before the person's build is known
        // the tracked shoulders sit up to 4 cm high in a shirt, and rows ending at the elbow
        // missed the sleeve's end on 27 of the 90 T-shirt recordings' first frames.
        let rows = (sv + 0.1 * dv).round() as i64..(sv + 1.2 * dv).round() as i64;
        let outline: Vec<Option<f32>> = rows
            .map(|v| {
                let u = su + du * (v as f32 - sv) / dv;
                outer_edge(mask, v, u.round() as i64, outwards).map(|x| (x * outwards) as f32)
            })
            .collect();
        let missing = outline.iter().filter(|x| x.is_none()).count();
        if outline.len() < 2 * WINDOW || missing * 10 > outline.len() * 3 {
            continue;
        }
        if let Some(px) = largest_step(&outline) {
            out.push(px * s.0.z / frame.camera.fx);
        }
    }
    out
}

/// The outermost pixel (column) of the mask's run at row `v` that lies within [`REACH`] of
/// column `u`, following the run `outwards` across gaps of up to [`GAP`] pixels.
fn outer_edge(mask: &[bool], v: i64, u: i64, outwards: i64) -> Option<i64> {
    let (w, h) = (WIDTH as i64, HEIGHT as i64);
    if !(0..h).contains(&v) {
        return None;
    }
    let on = |x: i64| (0..w).contains(&x) && mask[(v * w + x) as usize];
    // The arm's pixel nearest its line, preferring the outer side.
    let reach = REACH as i64;
    let mut at = (0..=reach)
        .flat_map(|d| [u + outwards * d, u - outwards * d])
        .find(|&x| on(x))?;
    loop {
        match (1..=GAP as i64 + 1)
            .map(|d| at + outwards * d)
            .find(|&x| on(x))
        {
            Some(next) => at = next,
            None => return Some(at),
        }
    }
}

/// The largest drop of the outline over [`WINDOW`] rows (median above minus median below),
/// less the outline's own slope over as many rows (the median change over [`WINDOW`] rows,
/// pixels: the median of the changes from one row to the next is 0 on a taper of a pixel
/// every few rows, and such a taper read as a step of 2 pixels, 1 cm at 3 m).
fn largest_step(outline: &[Option<f32>]) -> Option<f32> {
    let slopes: Vec<f32> = outline
        .iter()
        .zip(&outline[WINDOW..])
        .filter_map(|(a, b)| Some((b.as_ref()? - a.as_ref()?) / WINDOW as f32))
        .collect();
    let slope = median(slopes)?;
    let window = |rows: &[Option<f32>]| median(rows.iter().flatten().copied().collect());
    (WINDOW..=outline.len() - WINDOW)
        .filter_map(|v| {
            let above = window(&outline[v - WINDOW..v])?;
            let below = window(&outline[v..v + WINDOW])?;
            Some(above - below + slope * WINDOW as f32)
        })
        .max_by(f32::total_cmp)
}

/// The median (the mean of the middle two of an even count), `None` if empty.
fn median(mut values: Vec<f32>) -> Option<f32> {
    values.retain(|v| v.is_finite());
    if values.is_empty() {
        return None;
    }
    values.sort_by(f32::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_of_an_even_count_is_the_mean_of_the_middle_two() {
        assert_eq!(median(vec![4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(vec![5.0, f32::NAN, 1.0]), Some(3.0));
        assert_eq!(median(vec![]), None);
    }

    #[test]
    fn a_step_in_an_outline_is_found_and_a_steady_taper_is_not() {
        // 30 rows tapering by one pixel every 3 rows; the second with a 5-pixel step at row 15.
        let taper: Vec<Option<f32>> = (0..30).map(|v| Some(100.0 - (v / 3) as f32)).collect();
        let stepped: Vec<Option<f32>> = taper
            .iter()
            .enumerate()
            .map(|(v, x)| x.map(|x| if v >= 15 { x - 5.0 } else { x }))
            .collect();
        let smooth = largest_step(&taper).expect("a value");
        let step = largest_step(&stepped).expect("a value");
        assert!(smooth.abs() <= 1.0, "{smooth}");
        assert!((step - 5.0).abs() <= 1.0, "{step}");
    }
}
