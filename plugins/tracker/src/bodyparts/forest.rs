//! A randomised decision forest over depth-comparison features (Shotton et al. 2011): each
//! split compares the depth at two offsets from the pixel, the offsets scaled by the
//! pixel's own depth so the feature does not change with distance; each leaf holds a
//! distribution over the body parts.

use std::io::{Read, Write};

use fitroom_depth::{HEIGHT, WIDTH};
use thiserror::Error;

/// Depth given to pixels that are not the person's (background, no reading), metres: a far
/// constant, so a probe off the body reads as "much deeper".
pub const BACKGROUND_M: f32 = 10.0;

/// One split: `depth(x + u / d) - depth(x + v / d) < threshold`, `d` the pixel's depth,
/// offsets in pixel-metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Feature {
    pub u: [i16; 2],
    pub v: [i16; 2],
}

/// A node: a split with its two children (`left`, `left + 1`), or a leaf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Node {
    Split {
        feature: Feature,
        threshold: f32,
        left: u32,
    },
    Leaf(u32),
}

/// One tree: its nodes (the root first) and its leaves' part distributions.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tree {
    pub nodes: Vec<Node>,
    /// `parts` probabilities per leaf, quantised to 1/255.
    pub leaves: Vec<Vec<u8>>,
}

/// The forest: trees voting over `parts` classes.
#[derive(Clone, Debug, PartialEq)]
pub struct Forest {
    pub parts: usize,
    pub trees: Vec<Tree>,
}

/// A depth image for the features: metres, [`BACKGROUND_M`] off the person.
pub struct DepthImage<'a> {
    pub metres: &'a [f32],
    pub width: usize,
    pub height: usize,
}

impl DepthImage<'_> {
    #[inline]
    pub fn at(&self, x: i32, y: i32) -> f32 {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return BACKGROUND_M;
        }
        self.metres[y as usize * self.width + x as usize]
    }

    /// The feature's value at pixel `(x, y)` of depth `d`.
    #[inline]
    pub fn feature(&self, f: &Feature, x: i32, y: i32, d: f32) -> f32 {
        let k = 1.0 / d;
        let probe = |o: [i16; 2]| {
            self.at(
                x + (f32::from(o[0]) * k) as i32,
                y + (f32::from(o[1]) * k) as i32,
            )
        };
        probe(f.u) - probe(f.v)
    }
}

/// Why a forest file cannot be read.
#[derive(Debug, Error)]
pub enum ForestError {
    #[error("reading the body-part forest: {0}")]
    Io(#[from] std::io::Error),
    #[error(
        "not a body-part forest file (bad magic or version); grow one with `cargo run -p fitroom_tracker --release --example parts -- train F.forest`"
    )]
    Magic,
    #[error("the body-part forest is corrupt: {0}")]
    Corrupt(String),
}

const MAGIC: &[u8; 8] = b"FRFOR001";

impl Forest {
    /// Part probabilities (summed over the trees, not normalised: divide by the tree count)
    /// at pixel `(x, y)` of depth `d`, added into `out` (`parts` long).
    pub fn classify_into(&self, image: &DepthImage, x: i32, y: i32, d: f32, out: &mut [f32]) {
        for tree in &self.trees {
            let mut n = 0usize;
            loop {
                match tree.nodes[n] {
                    Node::Split {
                        feature,
                        threshold,
                        left,
                    } => {
                        let go_left = image.feature(&feature, x, y, d) < threshold;
                        n = left as usize + usize::from(!go_left);
                    }
                    Node::Leaf(leaf) => {
                        for (o, &p) in out.iter_mut().zip(&tree.leaves[leaf as usize]) {
                            *o += f32::from(p) * (1.0 / 255.0);
                        }
                        break;
                    }
                }
            }
        }
    }

    /// The forest as bytes (little-endian): magic, parts, trees; per tree its nodes (a tag
    /// byte: 0 split with offsets, threshold and left child; 1 leaf with its index) and its
    /// leaves' quantised distributions.
    pub fn write(&self, out: &mut impl Write) -> std::io::Result<()> {
        out.write_all(MAGIC)?;
        out.write_all(&(self.parts as u32).to_le_bytes())?;
        out.write_all(&(self.trees.len() as u32).to_le_bytes())?;
        for tree in &self.trees {
            out.write_all(&(tree.nodes.len() as u32).to_le_bytes())?;
            for node in &tree.nodes {
                match *node {
                    Node::Split {
                        feature,
                        threshold,
                        left,
                    } => {
                        out.write_all(&[0])?;
                        for o in [feature.u[0], feature.u[1], feature.v[0], feature.v[1]] {
                            out.write_all(&o.to_le_bytes())?;
                        }
                        out.write_all(&threshold.to_le_bytes())?;
                        out.write_all(&left.to_le_bytes())?;
                    }
                    Node::Leaf(leaf) => {
                        out.write_all(&[1])?;
                        out.write_all(&leaf.to_le_bytes())?;
                    }
                }
            }
            out.write_all(&(tree.leaves.len() as u32).to_le_bytes())?;
            for leaf in &tree.leaves {
                out.write_all(leaf)?;
            }
        }
        Ok(())
    }

    /// Reads what [`Self::write`] wrote, checking every index.
    pub fn read(input: &mut impl Read) -> Result<Self, ForestError> {
        let mut magic = [0u8; 8];
        input.read_exact(&mut magic)?;
        if &magic != MAGIC {
            return Err(ForestError::Magic);
        }
        let u32_of = |input: &mut dyn Read| -> std::io::Result<u32> {
            let mut b = [0u8; 4];
            input.read_exact(&mut b)?;
            Ok(u32::from_le_bytes(b))
        };
        let parts = u32_of(input)? as usize;
        let tree_count = u32_of(input)? as usize;
        if parts == 0 || parts > 64 || tree_count == 0 || tree_count > 16 {
            return Err(ForestError::Corrupt(format!(
                "{parts} parts, {tree_count} trees"
            )));
        }
        let mut trees = Vec::with_capacity(tree_count);
        for t in 0..tree_count {
            let node_count = u32_of(input)? as usize;
            if node_count == 0 || node_count > 1 << 22 {
                return Err(ForestError::Corrupt(format!(
                    "tree {t}: {node_count} nodes"
                )));
            }
            let mut nodes = Vec::with_capacity(node_count);
            for _ in 0..node_count {
                let mut tag = [0u8; 1];
                input.read_exact(&mut tag)?;
                nodes.push(match tag[0] {
                    0 => {
                        let mut b = [0u8; 16];
                        input.read_exact(&mut b)?;
                        let i = |k: usize| i16::from_le_bytes([b[2 * k], b[2 * k + 1]]);
                        let threshold = f32::from_le_bytes([b[8], b[9], b[10], b[11]]);
                        let left = u32::from_le_bytes([b[12], b[13], b[14], b[15]]);
                        Node::Split {
                            feature: Feature {
                                u: [i(0), i(1)],
                                v: [i(2), i(3)],
                            },
                            threshold,
                            left,
                        }
                    }
                    1 => Node::Leaf(u32_of(input)?),
                    other => {
                        return Err(ForestError::Corrupt(format!("tree {t}: node tag {other}")));
                    }
                });
            }
            let leaf_count = u32_of(input)? as usize;
            if leaf_count > node_count {
                return Err(ForestError::Corrupt(format!(
                    "tree {t}: {leaf_count} leaves"
                )));
            }
            let mut leaves = Vec::with_capacity(leaf_count);
            for _ in 0..leaf_count {
                let mut leaf = vec![0u8; parts];
                input.read_exact(&mut leaf)?;
                leaves.push(leaf);
            }
            // Every split's children and every leaf index exist, and children come after
            // their parent (so a walk always ends).
            for (n, node) in nodes.iter().enumerate() {
                let ok = match *node {
                    Node::Split {
                        left, threshold, ..
                    } => {
                        (left as usize) > n
                            && (left as usize) + 1 < node_count
                            && threshold.is_finite()
                    }
                    Node::Leaf(leaf) => (leaf as usize) < leaf_count,
                };
                if !ok {
                    return Err(ForestError::Corrupt(format!("tree {t}: node {n}")));
                }
            }
            trees.push(Tree { nodes, leaves });
        }
        Ok(Self { parts, trees })
    }
}

/// The person's depth in metres for the features: the frame's readings inside `mask`,
/// [`BACKGROUND_M`] elsewhere, full resolution.
pub fn person_depth(depth_mm: &[u16], mask: &[bool], out: &mut Vec<f32>) {
    out.clear();
    out.resize(WIDTH * HEIGHT, BACKGROUND_M);
    for ((o, &mm), &m) in out.iter_mut().zip(depth_mm).zip(mask) {
        if m && mm > 0 {
            *o = f32::from(mm) * 0.001;
        }
    }
}
