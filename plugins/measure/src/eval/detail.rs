//! Bodies with detail the fit cannot express. The evaluation's bodies come from the same
//! shape sliders the fit moves, so the fit could in principle match them exactly; real people
//! differ from every slider body in local ways (a fuller chest on a slim waist, heavier
//! thighs). These bodies take a slider body and scale its trunk and limb segments about their
//! axes independently (the body crate's segment-local morphing, seed 002 §4.4), each by a
//! factor drawn from a seed: the body measured is then one no slider setting gives.

use fitroom_body::{
    AreaBlend, BodyModel, BodySegment, BodySegmentation, Decay, Propagation, SegmentEdit,
    SegmentError, SegmentTarget,
};
use fitroom_depth::synthetic::next_unit;
use glam::Vec3;

/// The segments scaled, a left and right pair by one factor (people are nearly symmetric).
const GROUPS: [&[BodySegment]; 6] = [
    &[BodySegment::Chest],
    &[BodySegment::Waist],
    &[BodySegment::Hip],
    &[BodySegment::UpperArmLeft, BodySegment::UpperArmRight],
    &[BodySegment::ThighLeft, BodySegment::ThighRight],
    &[BodySegment::ShankLeft, BodySegment::ShankRight],
];

/// How far the morph reaches past each segment's core: Gaussian falloff over 4 hops (the
/// smoothest of the propagations measured, docs/STATUS.md's roughness row).
const PROPAGATION: Propagation = Propagation {
    depth: 4,
    decay: Decay::Gaussian,
};

/// Adds detail to slider bodies of one model.
#[derive(Clone, Debug)]
pub struct Detailer {
    segmentation: BodySegmentation,
    blend: AreaBlend,
    /// Each segment's radial scale lies within `1 ± spread`.
    spread: f32,
}

impl Detailer {
    /// Segments `model` once; `spread` is the largest relative change of a segment's girth
    /// (0.04: ±4 %).
    pub fn new(model: &BodyModel, spread: f32) -> Result<Self, SegmentError> {
        if !(spread.is_finite() && (0.0..0.5).contains(&spread)) {
            return Err(SegmentError::BadValue {
                field: "detail spread",
                value: spread,
                expected: "a relative girth change in [0, 0.5)",
            });
        }
        let segmentation = BodySegmentation::new(model)?;
        let blend = segmentation.blend(PROPAGATION)?;
        Ok(Self {
            segmentation,
            blend,
            spread,
        })
    }

    /// The largest relative change of a segment's girth.
    pub fn spread(&self) -> f32 {
        self.spread
    }

    /// The rest mesh `positions` (whole mesh, a slider body's) with each segment group
    /// scaled about its axis by a factor drawn from `seed`.
    pub fn detailed(&self, positions: &[Vec3], seed: u64) -> Result<Detailed, SegmentError> {
        let mut state = seed ^ 0xde7a_11ed;
        let mut factors = Vec::new();
        for group in GROUPS {
            let factor = 1.0 + self.spread * (2.0 * next_unit(&mut state) - 1.0);
            factors.extend(group.iter().map(|&segment| (segment, factor)));
        }
        let edits: Vec<SegmentEdit> = factors
            .iter()
            .map(|&(segment, factor)| SegmentEdit {
                segment,
                target: SegmentTarget::RadialScale { factor },
                amount: 1.0,
            })
            .collect();
        let positions = self.segmentation.morph(&self.blend, positions, &edits)?;
        Ok(Detailed { positions, factors })
    }
}

/// A body given detail.
#[derive(Clone, Debug)]
pub struct Detailed {
    /// Its rest mesh (whole mesh).
    pub positions: Vec<Vec3>,
    /// Each segment's radial scale.
    pub factors: Vec<(BodySegment, f32)>,
}
