//! Measuring the person from depth (seed 000 ch. 6, then beyond it), Bevy-free.
//!
//! The person stands still for about a second in the calibration pose (arms a little away
//! from the body) facing the mirror, then another second turned halfway to their left; each
//! view's calibration frames (depth, the person's pixels, the skeleton) are averaged per
//! pixel ([`AveragedView`]) and measured two ways:
//!
//! - [`seed`]: the seed's method as the baseline (Algorithms 6-9 and Table 6.2: the depth map
//!   smoothed, height and shoulder width read off it and estimated from the body's
//!   proportions, averaged over the frames);
//! - [`fit`]: ours: MakeHuman's body (the same sliders as the fit to typed-in measurements)
//!   fitted to the person's surface points and silhouette in both views, the pose refined
//!   from the tracked skeleton's, then measured as any body is
//!   ([`fitroom_body::BodyModel::measure`]). The camera sees the front and a flank; the back
//!   is where the shape prior puts it for what was seen.
//!
//! # Where things are
//!
//! - `calibration`: the calibration's views collected from tracked frames, each checked;
//! - `view`: the calibration frames and their per-pixel average;
//! - `seed`: the seed's method;
//! - `posed`: the shape space, the posed body and how its skin moves with each slider;
//! - `silhouette`: the distance outside the person's silhouette;
//! - `fit`: our fit; `prior`: the shape prior it leans on; `person`: both genders tried;
//! - `tracked`: the tracker's output as calibration input (frames, placement, starting pose);
//! - `build`: the same fit as the tracker's estimate of a moving person's build;
//! - `garment_size`: a garment's own size table as a chart (the size recommended);
//! - `eval`: the evaluation on ANSUR II subjects filmed by the synthetic Kinect (`dressed`:
//!   wearing a garment);
//! - `plugin` (feature `plugin`): the Bevy adapter that measures the person while the kiosk
//!   calibrates.

pub mod build;
pub mod calibration;
pub mod eval;
pub mod fit;
pub mod garment_size;
pub mod person;
#[cfg(feature = "plugin")]
pub mod plugin;
pub mod posed;
pub mod prior;
pub mod seed;
pub mod silhouette;
pub mod tracked;
pub mod view;

pub use fit::{BodyEstimate, FitSettings, ViewPose, fit_body};
pub use person::{PersonMeasurement, measure_person};
pub use posed::{Placement, PosedBody, Posing, ShapeSpace};
pub use prior::{GenderPrior, ShapePrior};
pub use view::{AveragedView, CalibrationFrame, MIN_FRAMES};

use fitroom_body::{MeasureError as BodyMeasureError, ShapeError};

/// Why a person cannot be measured from the frames given.
#[derive(Debug, thiserror::Error)]
pub enum MeasureError {
    #[error("{got} calibration frames, at least {need} are needed (stand still for a second)")]
    TooFewFrames { got: usize, need: usize },
    #[error("calibration frame {frame}: {why}")]
    BadFrame { frame: usize, why: String },
    #[error(
        "too few of the person's pixels have depth ({points}; at least {need}): too far, or mostly out of view"
    )]
    TooFewPoints { points: usize, need: usize },
    #[error("a body mesh of {got} vertices was given, the body model has {expected}")]
    MeshSize { got: usize, expected: usize },
    #[error("a body shape cannot be made: {0}")]
    Shape(#[from] ShapeError),
    #[error("the fitted body cannot be measured: {0}")]
    Body(#[from] BodyMeasureError),
    #[error("the fit's normal equations are singular (no person-shaped surface in the frames?)")]
    Singular,
    #[error("a worker thread of the fit stopped")]
    Worker,
}
