//! Growing the forest (Shotton et al. 2011, section 3.3): each tree from its own sample of
//! labelled pixels; at each node a few hundred random features and thresholds, the one with
//! the largest information gain (Shannon entropy of the part distribution) kept; a node with
//! few pixels, or at the deepest level, becomes a leaf with its pixels' part distribution.

use fitroom_depth::synthetic::{next_unit, splitmix64};

use super::forest::{DepthImage, Feature, Forest, Node, Tree};
use super::synth::LabelledImage;

/// How the trees are grown.
#[derive(Clone, Copy, Debug)]
pub struct TrainSettings {
    pub trees: usize,
    pub max_depth: usize,
    /// A node with fewer pixels becomes a leaf.
    pub min_pixels: usize,
    /// Candidate features per node, thresholds per feature.
    pub features: usize,
    pub thresholds: usize,
    /// At most this many of a node's pixels are used to choose its split (all are passed
    /// down).
    pub split_sample: usize,
    /// Pixels drawn from each image for each tree.
    pub pixels_per_image: usize,
    /// Largest probe offset, pixel-metres (0.35 m on the body is 200 / 0.58).
    pub max_offset: f32,
    pub seed: u64,
}

impl Default for TrainSettings {
    fn default() -> Self {
        Self {
            trees: 3,
            max_depth: 18,
            min_pixels: 24,
            features: 200,
            thresholds: 12,
            split_sample: 2000,
            pixels_per_image: 400,
            max_offset: 200.0,
            seed: 1,
        }
    }
}

/// One training pixel: its image, column and row in the image's box, part.
#[derive(Clone, Copy)]
struct Sample {
    image: u32,
    x: u16,
    y: u16,
    part: u8,
}

fn view(image: &LabelledImage) -> DepthImage<'_> {
    DepthImage {
        metres: &image.metres,
        width: image.width,
        height: image.height,
    }
}

fn value(images: &[LabelledImage], s: Sample, f: &Feature) -> f32 {
    let img = &images[s.image as usize];
    let v = view(img);
    let d = v.at(i32::from(s.x), i32::from(s.y));
    v.feature(f, i32::from(s.x), i32::from(s.y), d)
}

fn entropy(hist: &[u32], total: u32) -> f64 {
    if total == 0 {
        return 0.0;
    }
    let t = f64::from(total);
    hist.iter()
        .filter(|&&c| c > 0)
        .map(|&c| {
            let p = f64::from(c) / t;
            -p * p.ln()
        })
        .sum()
}

struct Grower<'a> {
    images: &'a [LabelledImage],
    parts: usize,
    settings: TrainSettings,
    state: u64,
    tree: Tree,
}

impl Grower<'_> {
    fn random_offset(&mut self) -> [i16; 2] {
        let r = self.settings.max_offset;
        let mut c = || ((next_unit(&mut self.state) * 2.0 - 1.0) * r) as i16;
        [c(), c()]
    }

    fn leaf(&mut self, samples: &[Sample]) -> Node {
        let mut hist = vec![0u32; self.parts];
        for s in samples {
            hist[usize::from(s.part)] += 1;
        }
        let total = samples.len().max(1) as f32;
        let leaf = hist
            .iter()
            .map(|&c| (c as f32 / total * 255.0).round() as u8)
            .collect();
        self.tree.leaves.push(leaf);
        Node::Leaf(self.tree.leaves.len() as u32 - 1)
    }

    /// The best split of `samples`, if one gains anything.
    fn best_split(&mut self, samples: &[Sample]) -> Option<(Feature, f32)> {
        let (parts, settings) = (self.parts, self.settings);
        // The pixels the split is chosen on: all, or an even spread of them.
        let step = (samples.len() / settings.split_sample).max(1);
        let chosen: Vec<Sample> = samples.iter().step_by(step).copied().collect();
        let mut parent = vec![0u32; parts];
        for s in &chosen {
            parent[usize::from(s.part)] += 1;
        }
        let n = chosen.len() as u32;
        let h_parent = entropy(&parent, n);
        let mut best: Option<(f64, Feature, f32)> = None;
        let mut values = vec![0f32; chosen.len()];
        let t = settings.thresholds;
        let mut hist = vec![0u32; (t + 1) * parts];
        for _ in 0..settings.features {
            // Half the features compare a probe with the pixel itself (v = 0).
            let u = self.random_offset();
            let v = if next_unit(&mut self.state) < 0.5 {
                [0, 0]
            } else {
                self.random_offset()
            };
            let feature = Feature { u, v };
            for (val, s) in values.iter_mut().zip(&chosen) {
                *val = value(self.images, *s, &feature);
            }
            let mut thresholds: Vec<f32> = (0..t)
                .map(|_| {
                    let k = (next_unit(&mut self.state) * values.len() as f32) as usize;
                    values[k.min(values.len() - 1)]
                })
                .collect();
            thresholds.sort_by(f32::total_cmp);
            hist.fill(0);
            for (val, s) in values.iter().zip(&chosen) {
                // The bin: how many thresholds the value reaches (value < threshold goes left
                // of that threshold).
                let bin = thresholds.iter().filter(|&&th| *val >= th).count();
                hist[bin * parts + usize::from(s.part)] += 1;
            }
            // Left of threshold i: bins 0..=i.
            let mut left = vec![0u32; parts];
            let mut n_left = 0u32;
            for (i, &th) in thresholds.iter().enumerate() {
                for p in 0..parts {
                    left[p] += hist[i * parts + p];
                    n_left += hist[i * parts + p];
                }
                let n_right = n - n_left;
                if n_left == 0 || n_right == 0 {
                    continue;
                }
                let right: Vec<u32> = parent.iter().zip(&left).map(|(a, b)| a - b).collect();
                let gain = h_parent
                    - (f64::from(n_left) * entropy(&left, n_left)
                        + f64::from(n_right) * entropy(&right, n_right))
                        / f64::from(n);
                if best.as_ref().is_none_or(|b| gain > b.0) {
                    best = Some((gain, feature, th));
                }
            }
        }
        best.filter(|b| b.0 > 1e-4).map(|(_, f, th)| (f, th))
    }

    /// Grows the subtree of `samples` into node `at` (already pushed).
    fn grow(&mut self, at: usize, samples: &mut [Sample], depth: usize) {
        let pure = samples.iter().all(|s| s.part == samples[0].part);
        let split =
            if depth >= self.settings.max_depth || samples.len() < self.settings.min_pixels || pure
            {
                None
            } else {
                self.best_split(samples)
            };
        let Some((feature, threshold)) = split else {
            self.tree.nodes[at] = self.leaf(samples);
            return;
        };
        // Partition: left first.
        let mut i = 0;
        for k in 0..samples.len() {
            if value(self.images, samples[k], &feature) < threshold {
                samples.swap(i, k);
                i += 1;
            }
        }
        let left = self.tree.nodes.len();
        self.tree.nodes.push(Node::Leaf(0));
        self.tree.nodes.push(Node::Leaf(0));
        self.tree.nodes[at] = Node::Split {
            feature,
            threshold,
            left: left as u32,
        };
        let (l, r) = samples.split_at_mut(i);
        self.grow(left, l, depth + 1);
        self.grow(left + 1, r, depth + 1);
    }
}

/// Grows a forest on `images` (each tree on its own random draw of each image's pixels), the
/// trees on threads of their own.
pub fn train(images: &[LabelledImage], parts: usize, settings: TrainSettings) -> Forest {
    let trees = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..settings.trees)
            .map(|t| {
                scope.spawn(move || {
                    let mut state = splitmix64(settings.seed ^ (t as u64).wrapping_mul(7919));
                    let mut samples: Vec<Sample> = Vec::new();
                    for (i, image) in images.iter().enumerate() {
                        let n = image.pixels.len();
                        for _ in 0..settings.pixels_per_image.min(n) {
                            let k = ((next_unit(&mut state) * n as f32) as usize).min(n - 1);
                            let (x, y, part) = image.pixels[k];
                            samples.push(Sample {
                                image: i as u32,
                                x,
                                y,
                                part,
                            });
                        }
                    }
                    let mut grower = Grower {
                        images,
                        parts,
                        settings,
                        state,
                        tree: Tree {
                            nodes: vec![Node::Leaf(0)],
                            leaves: Vec::new(),
                        },
                    };
                    grower.grow(0, &mut samples, 0);
                    grower.tree
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    });
    Forest { parts, trees }
}
