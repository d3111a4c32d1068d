//! Body parts per pixel, without a prior pose (Shotton, Fitzgibbon, Cook, Sharp, Finocchio,
//! Moore, Kipman & Blake 2011, "Real-time human pose recognition in parts from single depth
//! images", CVPR): a randomised decision forest over depth-comparison features labels each
//! of the person's pixels with the part of the body it sees (the skin around each of the 20
//! Kinect joints, [`labels`]); the densest place of each part's pixels, pushed into the body,
//! proposes where its joint is.
//!
//! The forest is grown on synthetic depth images of random bodies in random poses
//! ([`synth`], [`train`]; the `parts` example of this crate grows one), never on the
//! evaluation's clips.

pub mod forest;
pub mod labels;
pub mod synth;
pub mod train;

use fitroom_depth::{DepthCamera, DepthFrame, HEIGHT, WIDTH};
use glam::Vec3;

pub use forest::{Forest, ForestError};
pub use labels::PARTS;

use forest::{DepthImage, person_depth};

/// A joint proposal: where a part's pixels are densest, pushed into the body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proposal {
    /// Kinect joint index.
    pub joint: usize,
    pub position: Vec3,
    /// The part's mass within two bandwidths of the mode: each classified pixel's part
    /// probability times its depth² (its area on the body, up to a constant).
    pub weight: f32,
}

/// How proposals are made.
#[derive(Clone, Copy, Debug)]
pub struct ProposalSettings {
    /// Every `step`-th pixel in each direction is classified.
    pub step: usize,
    /// Pixels whose part probability is below this do not vote for it.
    pub min_probability: f32,
    /// Mean-shift bandwidth, metres.
    pub bandwidth_m: f32,
    /// How far behind the surface the joint is, metres.
    pub push_m: f32,
}

impl Default for ProposalSettings {
    fn default() -> Self {
        Self {
            step: 2,
            min_probability: 0.3,
            bandwidth_m: 0.06,
            push_m: 0.04,
        }
    }
}

/// Reusable buffers of the classification.
#[derive(Default)]
pub struct PartScratch {
    metres: Vec<f32>,
    votes: Vec<Vec<(Vec3, f32)>>,
}

/// Classifies the person's pixels (every `step`-th) and proposes a place for each joint
/// whose part is seen.
pub fn propose(
    forest: &Forest,
    frame: &DepthFrame,
    mask: &[bool],
    settings: ProposalSettings,
    scratch: &mut PartScratch,
) -> Vec<Proposal> {
    let cam: DepthCamera = frame.camera;
    if mask.len() != WIDTH * HEIGHT || frame.depth_mm.len() != WIDTH * HEIGHT {
        return Vec::new();
    }
    person_depth(&frame.depth_mm, mask, &mut scratch.metres);
    let image = DepthImage {
        metres: &scratch.metres,
        width: WIDTH,
        height: HEIGHT,
    };
    scratch.votes.resize_with(forest.parts, Vec::new);
    for v in &mut scratch.votes {
        v.clear();
    }
    let trees = forest.trees.len().max(1) as f32;
    let mut probs = vec![0f32; forest.parts];
    let step = settings.step.max(1);
    for y in (0..HEIGHT).step_by(step) {
        for x in (0..WIDTH).step_by(step) {
            let d = image.metres[y * WIDTH + x];
            if d >= forest::BACKGROUND_M {
                continue;
            }
            probs.fill(0.0);
            forest.classify_into(&image, x as i32, y as i32, d, &mut probs);
            let p3 = cam.unproject(x as f32, y as f32, d);
            // A pixel's area on the body grows with the square of its depth.
            let area = d * d;
            for (part, &p) in probs.iter().enumerate() {
                let p = p / trees;
                if p >= settings.min_probability {
                    scratch.votes[part].push((p3, p * area));
                }
            }
        }
    }
    let mut out = Vec::new();
    for (joint, votes) in scratch.votes.iter().enumerate() {
        if let Some((mode, weight)) = densest(votes, settings.bandwidth_m) {
            // Into the body, away from the sensor along the ray.
            let position = mode + mode.normalize_or_zero() * settings.push_m;
            out.push(Proposal {
                joint,
                position,
                weight,
            });
        }
    }
    out
}

/// The densest mode of weighted points: mean shift (Gaussian kernel) from the heaviest few
/// points, the mode with the most weight within a bandwidth kept.
fn densest(points: &[(Vec3, f32)], bandwidth: f32) -> Option<(Vec3, f32)> {
    if points.is_empty() {
        return None;
    }
    let inv = 1.0 / (2.0 * bandwidth * bandwidth);
    let mut seeds: Vec<usize> = (0..points.len()).collect();
    seeds.sort_by(|&a, &b| points[b].1.total_cmp(&points[a].1));
    // Seeds spread over the part: skip those near an earlier seed.
    let mut chosen: Vec<Vec3> = Vec::new();
    for &s in &seeds {
        let p = points[s].0;
        if chosen.iter().all(|c| c.distance(p) > 2.0 * bandwidth) {
            chosen.push(p);
            if chosen.len() == 5 {
                break;
            }
        }
    }
    let mut best: Option<(Vec3, f32)> = None;
    for mut m in chosen {
        for _ in 0..10 {
            let (mut sum, mut w) = (Vec3::ZERO, 0.0);
            for &(p, pw) in points {
                let k = pw * (-(p.distance_squared(m)) * inv).exp();
                sum += p * k;
                w += k;
            }
            if w <= 0.0 {
                break;
            }
            let next = sum / w;
            let moved = next.distance(m);
            m = next;
            if moved < 1e-3 {
                break;
            }
        }
        let mass: f32 = points
            .iter()
            .filter(|(p, _)| p.distance_squared(m) < bandwidth * bandwidth * 4.0)
            .map(|(_, w)| *w)
            .sum();
        if best.is_none_or(|b| mass > b.1) {
            best = Some((m, mass));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_densest_mode_is_the_heavier_cluster_s_centre() {
        // Two clusters of points on a grid (each symmetric about its centre): the lighter
        // one has more points, the heavier one more weight.
        let mut points = Vec::new();
        let (a, b) = (Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.5, 0.1, 2.2));
        for i in -2..=2 {
            for j in -2..=2 {
                let d = Vec3::new(i as f32, j as f32, 0.0) * 0.01;
                points.push((a + d, 1.0));
                points.push((b + d, 3.0));
                points.push((a + d * 1.5, 1.0));
            }
        }
        let (mode, mass) = densest(&points, 0.06).expect("a mode");
        assert!(
            mode.distance(b) < 0.005,
            "mode {mode} vs heavier centre {b}"
        );
        assert!(
            (mass - 75.0).abs() < 1e-3,
            "mass {mass}: the 25 heavy points"
        );
        assert!(densest(&[], 0.06).is_none());
    }
}
