//! Propagation of a segment past its core: how many edge hops out it reaches, and how the
//! membership weight falls off with the hops (after seed 002 (Uğur 2008, parametric bodies for
//! virtual dressing) §4.3, eq. 4.1 and Figure 4.8); and the weights a propagation gives (the seed's
//! `AREAS` record).

use serde::{Deserialize, Serialize};

/// How propagation weights fall off with the graph distance from the core (seed Figure 4.8);
/// see the [module docs](super) for the formulas.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Decay {
    Linear,
    Square,
    Gaussian,
}

impl Decay {
    pub const ALL: [Decay; 3] = [Decay::Linear, Decay::Square, Decay::Gaussian];

    /// The weight `f(k, d)` of a vertex `hops` = k hops from the core in a propagation of depth
    /// `depth` = d: 1 at `k = 0`, 0 for `k > d`, decreasing in between.
    pub fn weight(self, hops: u32, depth: u32) -> f32 {
        if hops == 0 {
            return 1.0;
        }
        if hops > depth {
            return 0.0;
        }
        let x = hops as f32 / (depth as f32 + 1.0);
        match self {
            Decay::Linear => 1.0 - x,
            Decay::Square => 1.0 - x * x,
            // σ = (d + 1) / 3: k² / (2σ²) = 4.5 x².
            Decay::Gaussian => (-4.5 * x * x).exp(),
        }
    }

    /// The kebab-case name (`gaussian`).
    pub fn name(self) -> &'static str {
        match self {
            Decay::Linear => "linear",
            Decay::Square => "square",
            Decay::Gaussian => "gaussian",
        }
    }
}

impl std::fmt::Display for Decay {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Decay {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Decay::ALL
            .into_iter()
            .find(|d| d.name() == s.trim().to_ascii_lowercase())
            .ok_or_else(|| format!("unknown decay `{s}`; known: linear, square, gaussian"))
    }
}

/// A propagation: how many hops out from the core, and how the weights fall off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Propagation {
    /// Propagation depth `d` in hops (0: the hard segment, its core alone).
    pub depth: u32,
    pub decay: Decay,
}

impl Propagation {
    /// The hard segment: the core alone, weight 1.
    pub const HARD: Propagation = Propagation {
        depth: 0,
        decay: Decay::Gaussian,
    };

    pub fn new(depth: u32, decay: Decay) -> Self {
        Self { depth, decay }
    }
}

/// The weights of one segment after propagation (the seed's `AREAS` record): parallel lists,
/// sorted by vertex.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentWeights {
    pub vertices: Vec<u32>,
    /// Graph distance of each vertex from the core (0 on the core).
    pub hops: Vec<u32>,
    /// Membership weight of each vertex, `f(hops, depth)`.
    pub weights: Vec<f32>,
}

impl SegmentWeights {
    /// The weight of vertex `v` (0 if the propagation does not reach it).
    pub fn weight_of(&self, v: u32) -> f32 {
        self.vertices
            .binary_search(&v)
            .map_or(0.0, |i| self.weights[i])
    }

    /// Number of vertices reached (core included).
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }
}
