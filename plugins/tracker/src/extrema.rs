//! Head, hands and feet without a prior pose: the accumulative geodesic extrema of the
//! person's surface (Plagemann, Ganapathi, Koller & Thrun 2010, "Real-time identification
//! and localization of body parts from depth images", ICRA). The person's pixels form a
//! graph (8-neighbours joined where their depths are continuous, weighted by 3D distance);
//! from the body's centre, the point farthest along the surface is an extremity; it joins
//! the sources and the next farthest is found, five times. The tracker starts (and recovers)
//! from these: they need no previous frame.
//!
//! Run at half resolution (every second pixel each way): a quarter of the nodes, and a
//! person still has thousands of them from 1 to 4 m.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use fitroom_depth::{DepthFrame, HEIGHT, WIDTH};
use glam::Vec3;
use serde::Serialize;

use crate::segment::Segmentation;

/// Sampling step of the graph, pixels.
const STEP: usize = 2;
const W: usize = WIDTH / STEP;
const H: usize = HEIGHT / STEP;

/// Neighbours closer in depth than this plus 4 % of depth are joined (a depth jump, such as
/// an arm in front of the body, cuts the graph there).
const JOIN_M: f32 = 0.05;

/// What an extremity was taken for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Part {
    Head,
    HandLeft,
    HandRight,
    FootLeft,
    FootRight,
    /// An extremity none of the others fits (a knee, an elbow held out).
    Other,
}

/// One geodesic extremity.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Extremum {
    /// The end itself (the top of the head, a fingertip, a toe), sensor space, metres.
    pub position: Vec3,
    /// Where the part's Kinect joint is estimated: the centre of the surface within the
    /// part's radius of the end, pushed into the body along the ray by half the part's
    /// thickness (the head's centre, the hand's middle, the ball of the foot).
    pub joint: Vec3,
    /// The highest point of the surface within the part's radius of the end, sensor space
    /// (the crown of the head as seen: the end may lie on the forehead; a hand raised
    /// beside the head is not on the head's surface).
    pub top: Vec3,
    /// Its pixel.
    pub pixel: [u16; 2],
    /// Surface distance from the body's centre, metres.
    pub geodesic_m: f32,
    pub part: Part,
}

/// The five extremities of `person` in `frame`, labelled (fewer when the graph has fewer
/// distinct ends, e.g. hands on the hips).
pub fn geodesic_extrema(frame: &DepthFrame, person: &Segmentation) -> Vec<Extremum> {
    let camera = frame.camera;
    // Nodes: the person's pixels on the half-resolution grid.
    let mut points = vec![None; W * H];
    for y in 0..H {
        for x in 0..W {
            let k = (y * STEP) * WIDTH + x * STEP;
            let mm = frame.depth_mm[k];
            if person.mask.get(k).copied().unwrap_or(false) && mm > 0 {
                let z = f32::from(mm) / 1000.0;
                points[y * W + x] = Some(camera.unproject((x * STEP) as f32, (y * STEP) as f32, z));
            }
        }
    }
    // The source: the node nearest the person's centroid.
    let Some(start) = (0..W * H)
        .filter_map(|n| points[n].map(|p| (n, p.distance_squared(person.centroid))))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(n, _)| n)
    else {
        return Vec::new();
    };
    let mut distance = vec![f32::INFINITY; W * H];
    let mut sources = vec![start];
    let mut found = Vec::new();
    let mut from_centre = None;
    for _ in 0..5 {
        dijkstra(&points, &sources, &mut distance, f32::INFINITY);
        if from_centre.is_none() {
            from_centre = Some(distance.clone());
        }
        let Some((far, d)) = distance
            .iter()
            .enumerate()
            .filter(|(_, d)| d.is_finite())
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(n, &d)| (n, d))
        else {
            break;
        };
        // An end closer than 15 cm to the ones found is the same limb.
        if d < 0.15 {
            break;
        }
        let (Some(position), Some(centre)) = (points[far], from_centre.as_ref()) else {
            break;
        };
        found.push(Extremum {
            position,
            joint: position,
            top: position,
            pixel: [((far % W) * STEP) as u16, ((far / W) * STEP) as u16],
            geodesic_m: centre[far],
            part: Part::Other,
        });
        sources.push(far);
    }
    label(&mut found, person);
    for e in &mut found {
        let node = (usize::from(e.pixel[1]) / STEP) * W + usize::from(e.pixel[0]) / STEP;
        let (radius, depth) = part_size(e.part);
        dijkstra(&points, &[node], &mut distance, radius);
        let higher = |a: Vec3, b: Vec3| {
            if person.floor.height(b) > person.floor.height(a) {
                b
            } else {
                a
            }
        };
        let (sum, count, top) = (0..W * H)
            .filter(|&n| distance[n] <= radius)
            .filter_map(|n| points[n])
            .fold((Vec3::ZERO, 0usize, e.position), |(s, c, t), p| {
                (s + p, c + 1, higher(t, p))
            });
        e.top = top;
        if count > 0 {
            let centre = sum / count as f32;
            e.joint = centre + centre.normalize_or_zero() * depth;
        }
    }
    found
}

/// A part's radius on the surface around its end and half its thickness, metres: the head's
/// visible cap (12 cm, 8 cm deep: the Kinect's head joint is the head's centre), a hand to
/// its knuckles (9 cm, 2 cm), a foot's front to its ball (6 cm, 3 cm).
fn part_size(part: Part) -> (f32, f32) {
    match part {
        Part::Head => (0.12, 0.08),
        Part::HandLeft | Part::HandRight => (0.09, 0.02),
        Part::FootLeft | Part::FootRight => (0.06, 0.03),
        Part::Other => (0.05, 0.0),
    }
}

/// Dijkstra's shortest surface distances from `sources` over the 8-connected graph, up to
/// `limit` (nodes farther stay at their first estimate or infinite).
fn dijkstra(points: &[Option<Vec3>], sources: &[usize], distance: &mut [f32], limit: f32) {
    distance.fill(f32::INFINITY);
    let mut heap = BinaryHeap::new();
    for &s in sources {
        distance[s] = 0.0;
        heap.push(Reverse((Ordered(0.0), s)));
    }
    while let Some(Reverse((Ordered(d), n))) = heap.pop() {
        if d > distance[n] {
            continue;
        }
        if d > limit {
            break;
        }
        let Some(p) = points[n] else { continue };
        let (x, y) = ((n % W) as isize, (n / W) as isize);
        for (dx, dy) in [
            (-1, -1),
            (0, -1),
            (1, -1),
            (-1, 0),
            (1, 0),
            (-1, 1),
            (0, 1),
            (1, 1),
        ] {
            let (nx, ny) = (x + dx, y + dy);
            if nx < 0 || ny < 0 || nx >= W as isize || ny >= H as isize {
                continue;
            }
            let m = ny as usize * W + nx as usize;
            let Some(q) = points[m] else { continue };
            if (q.z - p.z).abs() > JOIN_M + 0.04 * p.z {
                continue;
            }
            let next = d + p.distance(q);
            if next < distance[m] {
                distance[m] = next;
                heap.push(Reverse((Ordered(next), m)));
            }
        }
    }
}

/// Names the extremities: the feet are the two lowest near the floor, the head the upper end
/// nearest the centre along the surface, the hands the outermost two of the rest that can be
/// hands ([`could_be_hand`]; left and right by the side of the body they are on: a person
/// facing the sensor has their left at -X).
fn label(found: &mut [Extremum], person: &Segmentation) {
    let (centre, floor) = (person.centroid, &person.floor);
    let height = |e: &Extremum| floor.height(e.position);
    let mut order: Vec<usize> = (0..found.len()).collect();
    order.sort_by(|&a, &b| height(&found[a]).total_cmp(&height(&found[b])));
    let centre_height = floor.height(centre);
    let mut feet: Vec<usize> = order
        .iter()
        .copied()
        .filter(|&i| height(&found[i]) < 0.45 * centre_height.max(0.5))
        .take(2)
        .collect();
    feet.sort_by(|&a, &b| found[a].position.x.total_cmp(&found[b].position.x));
    match feet.as_slice() {
        [one] => {
            found[*one].part = if found[*one].position.x < centre.x {
                Part::FootLeft
            } else {
                Part::FootRight
            }
        }
        [left, right] => {
            found[*left].part = Part::FootLeft;
            found[*right].part = Part::FootRight;
        }
        _ => {}
    }
    // The head: of the ends well above the centre, the one highest, nearest the body's axis
    // and nearest the centre along the surface (the head sits on the trunk; a raised hand is
    // off to the side and an arm's length farther round, a broad shoulder's bulge lower
    // down). Without the surface distance a hand raised beside the head of a small woman
    // took the head's name, and her height was taken from it.
    let head_score = |e: &Extremum| {
        let off = Vec3::new(e.position.x - centre.x, 0.0, e.position.z - centre.z).length();
        height(e) - 1.5 * off - e.geodesic_m
    };
    let head = order
        .iter()
        .copied()
        .filter(|&i| found[i].part == Part::Other && height(&found[i]) > centre_height + 0.3)
        .max_by(|&a, &b| head_score(&found[a]).total_cmp(&head_score(&found[b])));
    if let Some(h) = head {
        found[h].part = Part::Head;
    }
    let mut hands: Vec<usize> = (0..found.len())
        .filter(|&i| found[i].part == Part::Other && could_be_hand(&found[i], person))
        .collect();
    hands.sort_by(|&a, &b| found[a].position.x.total_cmp(&found[b].position.x));
    match hands.as_slice() {
        [one] => {
            found[*one].part = if found[*one].position.x < centre.x {
                Part::HandLeft
            } else {
                Part::HandRight
            }
        }
        [left, .., right] => {
            found[*left].part = Part::HandLeft;
            found[*right].part = Part::HandRight;
        }
        _ => {}
    }
}

/// An end nearer the body's centre along the surface than this share of the person's height
/// (the top seen over the floor) is a hand only at the height of [`HAND_NEAR_HEIGHTS`].
const HAND_NEAR: f32 = 0.5;
/// Where a hand near the centre along the surface may be, as shares of the person's height
/// over the floor: hanging beside the hips, or held before the belly.
const HAND_NEAR_HEIGHTS: std::ops::RangeInclusive<f32> = 0.33..=0.6;
/// ... or anywhere this much nearer the sensor than the person's centroid, metres: held
/// before the body (a runner's hands before the chest on CMU 09_01's first frames: 39-46 cm
/// before the spine joint, which lies behind the centroid of what is seen).
const HAND_BEFORE_M: f32 = 0.2;

/// Whether end `e` can be a hand, for [`label`] to name: a hand is an arm's length round the
/// body from its centre, unless it touches the body, and then it hangs at the hips or is held
/// before the trunk. With the arms hanging against the sides (or in a T-shirt, whose
/// sleeves join the arms to the trunk) the hands are no ends, and the ends named for them are
/// the shoulders' corners (0.70-0.84 of the height) or the knees (0.23-0.30). On the first
/// frames of the 90 bare and T-shirt recordings of the acceptance set, the 45 ends named for
/// hands 20 cm or more from either hand all lay so (at most 16 cm before the spine joint), and
/// of the 135 within 20 cm only a runner's 3 hands before the chest (39-46 cm before it).
fn could_be_hand(e: &Extremum, person: &Segmentation) -> bool {
    // (A person lower than half a metre, lying or rolled up, is measured against that.)
    let height = person.top_m.max(0.5);
    e.geodesic_m >= HAND_NEAR * height
        || HAND_NEAR_HEIGHTS.contains(&(person.floor.height(e.position) / height))
        || person.centroid.z - e.position.z >= HAND_BEFORE_M
}

/// An `f32` ordered for the heap (distances are finite and not NaN).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Ordered(f32);

impl Eq for Ordered {}

impl PartialOrd for Ordered {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ordered {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}
