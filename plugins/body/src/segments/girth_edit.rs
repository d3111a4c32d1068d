//! One segment at a time, the designer's local edits (after seed 002 (Uğur 2008, parametric bodies
//! for virtual dressing) §4.4 "Local Morphing", with the girth scaling of §4.1.2 / §4.2): a segment
//! morphed with the rest of the body held, and the radial scale that brings a segment's measured
//! girth (waist, hip, bust...) to a requested value.

use glam::Vec3;
use serde::Serialize;

use super::{
    AreaBlend, BodySegment, BodySegmentation, Decay, Propagation, SegmentEdit, SegmentError,
    SegmentTarget,
};
use crate::model::BodyModel;

/// Local morphing of one segment with the rest of the body held (every other segment at
/// amount 0 in eq. 4.6), e.g. the waist alone.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentMorph {
    segmentation: BodySegmentation,
    blend: AreaBlend,
    segment: BodySegment,
    propagation: Propagation,
}

/// How close (cm) [`SegmentMorph::edit_girth`] brings the measured girth to the request.
pub const GIRTH_TOLERANCE_CM: f32 = 0.05;

/// Secant steps [`SegmentMorph::edit_girth`] takes before giving up.
const GIRTH_MAX_STEPS: u32 = 8;

impl SegmentMorph {
    /// Segments `model` and prepares morphs of `segment`, every segment propagated to `depth`
    /// hops with `decay`.
    pub fn new(
        model: &BodyModel,
        segment: BodySegment,
        depth: u32,
        decay: Decay,
    ) -> Result<Self, SegmentError> {
        Self::with_segmentation(
            BodySegmentation::new(model)?,
            segment,
            Propagation::new(depth, decay),
        )
    }

    /// The same from an existing segmentation (segmenting measures the body; do it once).
    pub fn with_segmentation(
        segmentation: BodySegmentation,
        segment: BodySegment,
        propagation: Propagation,
    ) -> Result<Self, SegmentError> {
        let blend = segmentation.blend(propagation)?;
        Ok(Self {
            segmentation,
            blend,
            segment,
            propagation,
        })
    }

    pub fn segment(&self) -> BodySegment {
        self.segment
    }

    pub fn propagation(&self) -> Propagation {
        self.propagation
    }

    pub fn segmentation(&self) -> &BodySegmentation {
        &self.segmentation
    }

    /// How far each body vertex follows the segment's target when the segment's amount is 1:
    /// the eq. 4.6 multiplier with every other segment at 0 (1 deep inside the core, falling
    /// to 0 outside the propagation).
    pub fn multipliers(&self) -> Vec<f32> {
        let mut amounts = [0.0f32; 16];
        amounts[self.segment.index()] = 1.0;
        self.blend
            .multipliers(&amounts)
            .expect("the blend has one area per body segment")
    }

    /// The body `positions` (whole mesh) with the segment morphed by `amount` towards `target`.
    pub fn apply(
        &self,
        positions: &[Vec3],
        target: &SegmentTarget,
        amount: f32,
    ) -> Result<Vec<Vec3>, SegmentError> {
        self.segmentation.morph(
            &self.blend,
            positions,
            &[SegmentEdit {
                segment: self.segment,
                target: target.clone(),
                amount,
            }],
        )
    }

    /// The designer's girth edit: scales the segment about its axis
    /// ([`SegmentTarget::RadialScale`], amount 1) by the factor that brings its girth, as
    /// [`BodyModel::measure`] reports it, to `target_girth_cm` (within
    /// [`GIRTH_TOLERANCE_CM`]). The neighbours' weights dilute the edit near the core's edges,
    /// so the factor is found by secant steps on the measured girth.
    pub fn edit_girth(
        &self,
        model: &BodyModel,
        positions: &[Vec3],
        target_girth_cm: f32,
    ) -> Result<GirthEdit, SegmentError> {
        let of = self
            .segment
            .girth()
            .ok_or(SegmentError::NoGirth(self.segment))?;
        let girth = |p: &[Vec3]| -> Result<f32, SegmentError> { Ok(of(&model.measure(p)?)) };
        if !(target_girth_cm.is_finite() && target_girth_cm > 0.0) {
            return Err(SegmentError::BadValue {
                field: "target_girth_cm",
                value: target_girth_cm,
                expected: "a finite girth > 0 cm",
            });
        }
        let before_cm = girth(positions)?;
        let ratio = target_girth_cm / before_cm;
        if !(0.5..=2.0).contains(&ratio) {
            return Err(SegmentError::GirthOutOfReach {
                segment: self.segment,
                requested_cm: target_girth_cm,
                current_cm: before_cm,
                ratio,
            });
        }
        let mut edit = GirthEdit {
            segment: self.segment,
            propagation: self.propagation,
            before_cm,
            requested_cm: target_girth_cm,
            achieved_cm: before_cm,
            scale_factor: 1.0,
            steps: 0,
            positions: positions.to_vec(),
        };
        if (before_cm - target_girth_cm).abs() <= GIRTH_TOLERANCE_CM {
            return Ok(edit);
        }
        let (mut f_prev, mut g_prev) = (1.0f32, before_cm);
        let mut f = ratio;
        for step in 1..=GIRTH_MAX_STEPS {
            let p = self.apply(positions, &SegmentTarget::RadialScale { factor: f }, 1.0)?;
            let g = girth(&p)?;
            edit.steps = step;
            edit.achieved_cm = g;
            edit.scale_factor = f;
            edit.positions = p;
            if (g - target_girth_cm).abs() <= GIRTH_TOLERANCE_CM {
                return Ok(edit);
            }
            let slope = (g - g_prev) / (f - f_prev);
            let next = f + (target_girth_cm - g) / slope;
            if !(slope.is_finite() && slope.abs() > 1e-3 && next.is_finite() && next > 0.0) {
                break;
            }
            (f_prev, g_prev, f) = (f, g, next);
        }
        Err(SegmentError::GirthNotReached {
            segment: self.segment,
            requested_cm: target_girth_cm,
            achieved_cm: edit.achieved_cm,
            factor: edit.scale_factor,
        })
    }
}

/// The result of a girth edit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GirthEdit {
    pub segment: BodySegment,
    pub propagation: Propagation,
    /// Girth of the input body.
    pub before_cm: f32,
    pub requested_cm: f32,
    /// Girth of the edited body (within [`GIRTH_TOLERANCE_CM`] of the request).
    pub achieved_cm: f32,
    /// The radial scale factor applied to the segment.
    pub scale_factor: f32,
    /// Secant steps taken (each one morph and one measurement).
    pub steps: u32,
    /// The edited body, whole mesh.
    #[serde(skip)]
    pub positions: Vec<Vec3>,
}

/// "Waist only": changes the waist girth of `positions` (whole mesh of `model`) by `change_cm`
/// (negative: slimmer), moving only the waist band and its propagation. Segments the model on
/// each call; for repeated edits make one [`SegmentMorph`] and call
/// [`SegmentMorph::edit_girth`].
pub fn edit_waist_girth(
    model: &BodyModel,
    positions: &[Vec3],
    change_cm: f32,
    propagation: Propagation,
) -> Result<GirthEdit, SegmentError> {
    if !change_cm.is_finite() {
        return Err(SegmentError::BadValue {
            field: "change_cm",
            value: change_cm,
            expected: "a finite girth change in cm",
        });
    }
    let morph = SegmentMorph::with_segmentation(
        BodySegmentation::new(model)?,
        BodySegment::Waist,
        propagation,
    )?;
    let m = model.measure(positions)?;
    morph.edit_girth(model, positions, m.waist_cm + change_cm)
}
