//! The fit of [`crate::fit`] as the tracker's estimate of the person's build
//! ([`fitroom_tracker::BuildFit`]): the tracker keeps a few frames it tracked well while the
//! person moves (no calibration pose: a walk, a wave), and the body of 37 sliders is fitted
//! to them, each frame a view of its own, posed as the tracker saw it.
//!
//! Why: the tracker's own search turns MakeHuman's five macro sliders and keeps its size; a
//! body of the wrong build puts the joints where the person's are not. On the 45 bare
//! recordings of the acceptance set (3 ANSUR II builds x 15 CMU clips) the trunk's joints
//! were 44.7 mm off with the macro search, 27.7 mm with the true body; 29.9 mm with this fit.
//!
//! Under a shirt the skin is not seen: where the shirt hangs clear of the body what is seen
//! is in front of the skin. Once the tracker finds the person wearing one (by this fit's
//! cost under its clothing layer), the body under it is fitted again as a body inside the
//! shirt: a thinner layer, points outside the skin weak evidence and those inside firm,
//! and a stronger pull to the shape prior (the trunk's girths follow the limbs' and the
//! height, not the shirt's folds). On the 45 T-shirt recordings of the acceptance set all
//! taken as clothed, the trunk's joints came out 47.2 mm off with the plain fit under the
//! layer, 43.3 with this one, 37.5 with this one and the tracker's shirt points outside the
//! skin weak too (`fitroom_tracker::fit::FitSettings::cloth_gap_weight`; docs/STATUS.md,
//! session 45).

use fitroom_body::{BodyModel, Shape};
use fitroom_depth::camera::WIDTH;
use fitroom_sensor::KinectJoint;
use fitroom_tracker::denoise::denoised;
use fitroom_tracker::skirt::SkirtZone;
use fitroom_tracker::{BuildFit, BuildFitted, Snapshot};

use crate::fit::{FitSettings, ViewPose};
use crate::person::both_genders;
use crate::posed::Placement;
use crate::prior::ShapePrior;
use crate::tracked::calibration_frame;
use crate::view::AveragedView;

/// The measurement's fit of the person's build, for the tracker.
#[derive(Clone, Debug)]
pub struct TrackedBuild {
    pub prior: std::sync::Arc<ShapePrior>,
    pub settings: FitSettings,
    /// The body under a shirt ([`BuildFit::under_clothes`]): fitted under this share of
    /// the tracker's clothing layer, ...
    pub under_layer: f32,
    /// ... a point outside the skin weighing this against one inside it (over the whole
    /// body: the bare forearms, legs and head too, whose points lie on the skin), ...
    pub under_outside_weight: f32,
    /// ... and the shape prior's weight this many times [`FitSettings::prior`].
    pub under_prior: f32,
    /// Each of the person's readings in a kept frame taken as the mean of those on its
    /// surface within this many pixels ([`fitroom_tracker::denoise`]); 0: as read. A kept
    /// frame is one frame, not the calibration's average of many: at 3 m its readings are
    /// 14 mm off the surface, and the bodies fitted to three of them came out small (CMU
    /// 07_01 at 3 m: the heavy man's bust, waist, hip 115.7 / 101.9 / 111.1 cm against his
    /// 120.8 / 110.7 / 115.3; averaged over 5 x 5 pixels 120.5 / 107.7 / 114.3). On the 90
    /// bare and T-shirt recordings of the other noise set (tracked as read), the trunk's
    /// joints 25.15 -> 23.47 mm (docs/STATUS.md, session 52).
    pub denoise_px: usize,
}

impl TrackedBuild {
    pub fn new(prior: std::sync::Arc<ShapePrior>) -> Self {
        Self {
            prior,
            settings: FitSettings::default(),
            under_layer: 0.5,
            under_outside_weight: 0.3,
            under_prior: 10.0,
            denoise_px: 2,
        }
    }

    /// The build fitted to the frames the tracker kept, with `settings`.
    fn fitted(
        &self,
        model: &BodyModel,
        snapshots: &[Snapshot],
        settings: &FitSettings,
    ) -> Result<BuildFitted, String> {
        let mut views = Vec::with_capacity(snapshots.len());
        for s in snapshots {
            let frame = denoised(&s.frame, &s.tracked.person.mask, self.denoise_px);
            let mut view = AveragedView::single(&calibration_frame(&frame, &s.tracked))
                .map_err(|e| e.to_string())?;
            if let Some(skirt) = &s.tracked.skirt {
                hide_skirt(&mut view, skirt);
            }
            // The tracker's own pose (its bones are the model's): a moving person is not in
            // the calibration's stance, and its root's lean is theirs here. (From the
            // calibration's stance, aimed by the joints, the trunk's joints came out 35.8 mm
            // off on the acceptance set, against 33.3 from the tracker's pose, both sized by
            // the tracker.)
            let locals = s.tracked.pose.local.clone();
            if locals.len() != model.bones.len() {
                return Err(format!(
                    "the tracker's pose has {} bones, the body model {}",
                    locals.len(),
                    model.bones.len()
                ));
            }
            let placement = Placement {
                rotation: s.tracked.pose.rotation,
                pelvis: s.tracked.joints[KinectJoint::HipCenter.index()].position,
            };
            views.push((view, locals, placement));
        }
        let poses: Vec<ViewPose> = views
            .iter()
            .map(|(view, locals, placement)| ViewPose {
                view,
                locals,
                placement: *placement,
            })
            .collect();
        both_genders(model, &poses, &self.prior, settings)
            .map(|m| BuildFitted {
                shape: m.estimate.shape,
                cost: m.estimate.cost,
            })
            .map_err(|e| e.to_string())
    }
}

/// The points of `view` in a skirt's heights left out of the build's fit (the silhouette
/// kept): a skirt fitted as skin made the legs thick and short. The whole band, not only the
/// zone the tracker leaves out (a hand beside the skirt keeps its points there to be found
/// again; the build's single frames are ones the tracker followed well). A skirt worn but
/// not found in the frame ([`SkirtZone::seen`] false) too: its hem is the last one found
/// (the dresses 60.92 -> 60.43 mm with only this of session 55's change; docs/STATUS.md).
fn hide_skirt(view: &mut AveragedView, skirt: &SkirtZone) {
    for (i, reading) in view.readings.iter_mut().enumerate() {
        let z = view.depth_m[i];
        if *reading > 0 && z > 0.0 {
            let p = view
                .camera
                .unproject((i % WIDTH) as f32, (i / WIDTH) as f32, z);
            if skirt.in_heights(p) {
                *reading = 0;
            }
        }
    }
}

impl BuildFit for TrackedBuild {
    fn fit(
        &self,
        model: &BodyModel,
        snapshots: &[Snapshot],
        clothing_m: f32,
    ) -> Result<BuildFitted, String> {
        let settings = FitSettings {
            clothing_m,
            ..self.settings.clone()
        };
        self.fitted(model, snapshots, &settings)
    }

    fn under_clothes(
        &self,
        model: &BodyModel,
        snapshots: &[Snapshot],
        clothing_m: f32,
    ) -> Result<Option<Shape>, String> {
        let settings = FitSettings {
            clothing_m: clothing_m * self.under_layer,
            outside_weight: self.under_outside_weight,
            prior: self.settings.prior * self.under_prior,
            ..self.settings.clone()
        };
        self.fitted(model, snapshots, &settings)
            .map(|f| Some(f.shape))
    }
}
