//! The person's build, estimated while tracking: the body the tracker fits starts as
//! MakeHuman's default sized to the person's height, but a broad man or a slight woman is not
//! that body scaled, and the joints come out where a body of the wrong build puts them (the
//! hips 5 cm off on a heavy man). So a few frames the person was tracked well in are kept,
//! and bodies of other builds (MakeHuman's macro sliders: gender, weight, muscle, height,
//! proportions) are fitted to them in turn; the build whose fits explain the frames best is
//! the person's. A coordinate search, each candidate body fitted to each kept frame from the
//! pose tracked there for a few steps, at the person's measured height.
//!
//! What comes out is a body that fits the person's surface better, not their sliders: seen
//! from the front through the sensor's noise, gender, weight and muscle trade off (a broad
//! man of weight 0.9 came out 0.27 with more gender; `tests/shape.rs`), but the trunk's
//! joints move nearer the truth (there: 25 -> 17 mm; on 9 recordings of 3 ANSUR II builds
//! walking, 42 -> 35 mm).
//!
//! A shirt stands off the skin, and a body fitted to its surface puts the trunk's joints in
//! front of the person's (the spine 6-13 cm on the T-shirt recordings). So the build is
//! found twice: bare, and under a layer of clothing on the trunk and the upper arms
//! ([`TrackBody::clothe`]); the body that explains the kept frames better by a margin is
//! kept, in its layer (docs/STATUS.md, session 39). With a [`BuildFit`] the fit's own cost
//! decides, and the body under a shirt is fitted as one inside it ([`estimate_with`]). Both
//! costs tell a shirt poorly from one look (a bare build swells into it); a short sleeve's end
//! tells it far better ([`crate::sleeve`]), so when the sleeves are seen, or the upper arms
//! seen bare, the costs are not asked (session 49).
//!
//! The first search runs on the first frames the person is tracked well in, so that their
//! build is used as soon as it can be; a second runs on frames spread over the next seconds
//! in which they stand upright, and its build replaces the first ([`ShapeSettings::looks`]):
//! a person first seen crouching is otherwise given the build of a small person for good.
//!
//! That search is the tracker's own. A better fitter of the whole body can be given instead
//! ([`BuildFit`]: the app gives the measurement's 37-slider fit of the skin, `fitroom_measure`,
//! which depends on this crate and so cannot be called from it): its body is the person's,
//! size included.

use fitroom_body::{BodyModel, Shape, ShapeError};
use fitroom_depth::DepthFrame;

use crate::fit::FitStats;
use crate::model::{ModelError, TrackBody};
use crate::sleeve::Sleeves;
use crate::tracker::{Tracked, Tracker, TrackerSettings};

/// How the build is estimated.
#[derive(Clone, Copy, Debug)]
pub struct ShapeSettings {
    /// Frames kept for the search, one every `every` frames tracked well.
    pub snapshots: usize,
    pub every: usize,
    /// Searches per person: the first from `snapshots` frames in a row as soon as the person
    /// is tracked well, each later one from `snapshots` frames `again_every` apart in which
    /// they stand upright ([`crate::Tracker`]), its build replacing the last.
    pub looks: usize,
    pub again_every: usize,
    /// Points of the person sampled per kept frame, and fit steps per candidate body and
    /// kept frame.
    pub points: usize,
    pub iterations: usize,
    /// Run the search on a thread of its own and take its answer when it is ready (the
    /// app, where a frame must not wait a second); else in the frame that completes the
    /// snapshots (evaluations, tests: the same input gives the same output).
    pub background: bool,
}

impl Default for ShapeSettings {
    fn default() -> Self {
        // Measured on 9 recordings (3 walks x 3 builds): 6 snapshots, 2,000 points and 6
        // steps gave the trunk joints 33 mm (42 with the default body); 4 steps and 1,200
        // points 35 mm; 10 snapshots no better. Then on the 45 bare recordings of the
        // acceptance set (5 s each): 3 frames in a row, against 6 five frames apart, gave
        // the trunk 40.6 mm against 44.7 with the macro search and 34.4 against 40.8 with
        // the measurement's fit (2: 35.1, 4: 35.0): the build is adopted a second sooner,
        // and a body fitted to 3 frames in a row tracked as well as one fitted to 6 spread
        // over the recording (both used from the first frame: 30.0 and 29.9 mm).
        // A second look (session 40; `fitroom track eval` on the 90 bare and T-shirt
        // recordings): the T-shirt's men measured 3-18 cm short by the first look mostly
        // within 2 cm; mean / trunk 56.3 / 39.4 -> 55.9 / 37.9 mm. A third look: the same.
        Self {
            snapshots: 3,
            every: 1,
            looks: 2,
            again_every: 15,
            points: 2000,
            iterations: 6,
            background: false,
        }
    }
}

/// A kept frame and what the tracker saw in it (the person's pixels, pose and joints).
#[derive(Clone, Debug)]
pub struct Snapshot {
    pub frame: DepthFrame,
    pub tracked: Tracked,
}

/// A fitter of the person's whole build from the frames the tracker kept: the shape of a body
/// of the person's size (not to be scaled to the tracked height). Runs on the tracker's
/// search thread in the app.
pub trait BuildFit: Send + Sync {
    /// The person's skin, under a layer of clothing `clothing_m` thick on the trunk and the
    /// upper arms ([`TrackBody::clothe`]; 0: none), and the fit's cost, comparable between
    /// layers: the lower tells whether the person wears the layer.
    fn fit(
        &self,
        model: &BodyModel,
        snapshots: &[Snapshot],
        clothing_m: f32,
    ) -> Result<BuildFitted, String>;

    /// The skin under a shirt, once the person is found to wear one, for fitters with a
    /// way of their own to find it (`None`: [`BuildFit::fit`]'s under the layer is kept).
    fn under_clothes(
        &self,
        _model: &BodyModel,
        _snapshots: &[Snapshot],
        _clothing_m: f32,
    ) -> Result<Option<Shape>, String> {
        Ok(None)
    }
}

/// A build [`BuildFit::fit`] found.
#[derive(Clone, Debug)]
pub struct BuildFitted {
    pub shape: Shape,
    /// The fit's cost (any unit, the same for every layer).
    pub cost: f64,
}

/// The build found, its body, and what the search saw.
#[derive(Clone, Debug)]
pub struct Estimate {
    pub shape: Shape,
    pub body: TrackBody,
    /// Whether the body has the person's size ([`BuildFit`]); else it is sized as the body
    /// tracked before it.
    pub sized: bool,
    /// The macro search's cost (about the mean distance of the person's points from the body,
    /// outliers counted at 3 cm) for the default build and for the one found, metres (`None`
    /// from a [`BuildFit`]).
    pub default_cost_m: Option<f32>,
    pub cost_m: Option<f32>,
    pub evaluations: usize,
    /// The clothing layer the body wears ([`TrackBody::clothe`]), metres: 0 or
    /// [`TrackerSettings::clothing_m`].
    pub clothing_m: f32,
    /// Why the body under the clothing layer ([`BuildFit::under_clothes`]) could not be
    /// fitted, if it could not: the clothed fit's own body is worn instead.
    pub under_clothes_error: Option<String>,
}

#[derive(Debug, thiserror::Error)]
pub enum ShapeSearchError {
    #[error("a candidate build cannot be made: {0}")]
    Shape(#[from] ShapeError),
    #[error("a candidate body cannot be tracked: {0}")]
    Model(#[from] ModelError),
    #[error("no snapshots to compare builds on")]
    NoSnapshots,
    #[error("no person in snapshot {0}")]
    NoPerson(usize),
    #[error("the search stopped before it ended")]
    Stopped,
    #[error("the build's fit failed: {0}")]
    Fit(String),
}

/// The macro sliders searched, in the order they are tried. (The shoulders' width and the
/// trunk's depth, tried as well, changed nothing on the 90 recordings: the search's cost
/// hardly sees them through the sensor's noise.)
const SLIDERS: [fn(&mut Shape) -> &mut f32; 5] = [
    |s| &mut s.gender,
    |s| &mut s.weight,
    |s| &mut s.muscle,
    |s| &mut s.height,
    |s| &mut s.proportions,
];

/// The search's steps along a slider, coarse to fine.
const STEPS: [f32; 3] = [0.3, 0.15, 0.075];

/// How poorly a fit explains its frame: the inliers' mean residual, each outlier and each
/// capsule sample outside the silhouette counted at 3 cm.
fn cost(fit: &FitStats) -> f32 {
    const MISS_M: f32 = 0.03;
    fit.inliers * fit.mean_residual_m + (1.0 - fit.inliers) * MISS_M + fit.outside * MISS_M
}

/// The build of the person in `snapshots`, which were tracked with `tracked_with`: a
/// coordinate search over the macro sliders from MakeHuman's default, bare and under the
/// clothing layer ([`TrackerSettings::clothing_m`]); the better explained is kept, unless
/// the `sleeves` tell ([`crate::sleeve`]).
pub fn estimate(
    model: &BodyModel,
    tracked_with: &TrackBody,
    snapshots: &[Snapshot],
    settings: &TrackerSettings,
    iterations: usize,
    sleeves: Sleeves,
) -> Result<Estimate, ShapeSearchError> {
    if snapshots.is_empty() {
        return Err(ShapeSearchError::NoSnapshots);
    }
    let fits = Refits {
        tracked_with,
        snapshots,
        settings,
        iterations,
    };
    if settings.clothing_m <= 0.0 || sleeves == Sleeves::Bare {
        return search(model, &fits, 0.0);
    }
    if sleeves == Sleeves::Seen {
        return search(model, &fits, settings.clothing_m);
    }
    let bare = search(model, &fits, 0.0)?;
    let clothed = search(model, &fits, settings.clothing_m)?;
    let evaluations = bare.evaluations + clothed.evaluations;
    let (Some(a), Some(b)) = (bare.cost_m, clothed.cost_m) else {
        return Ok(bare);
    };
    let mut kept = if b < a - CLOTHING_MARGIN_M {
        clothed
    } else {
        bare
    };
    kept.evaluations = evaluations;
    Ok(kept)
}

/// The macro search with the clothing layer `t`.
fn search(model: &BodyModel, fits: &Refits, t: f32) -> Result<Estimate, ShapeSearchError> {
    let mut evaluations = 0;
    let mut evaluate = |shape: &Shape| -> Result<(f32, TrackBody), ShapeSearchError> {
        evaluations += 1;
        let positions = model.shaped(shape)?.positions;
        let mut body = TrackBody::new(model, &positions)?;
        body.clothe(t);
        fits.cost(body)
    };
    let mut shape = Shape::default();
    let (default_cost_m, mut body) = evaluate(&shape)?;
    let mut best = default_cost_m;
    for step in STEPS {
        for slider in SLIDERS {
            for direction in [1.0f32, -1.0] {
                let mut candidate = shape.clone();
                let value = slider(&mut candidate);
                let moved = (*value + direction * step).clamp(0.0, 1.0);
                if moved == *value {
                    continue;
                }
                *value = moved;
                let (c, candidate_body) = evaluate(&candidate)?;
                if c < best {
                    (best, shape, body) = (c, candidate, candidate_body);
                    break;
                }
            }
        }
    }
    Ok(Estimate {
        shape,
        body,
        sized: false,
        default_cost_m: Some(default_cost_m),
        cost_m: Some(best),
        evaluations,
        clothing_m: t,
        under_clothes_error: None,
    })
}

/// A clothing layer is taken only when it lowers the cost by this much, metres: a bare
/// person's fit gains from the layer's extra girth now and then (by up to 2.4 mm on 14 of
/// 42 bare recordings), a T-shirt's by 0.5-3 mm on 36 of 42.
const CLOTHING_MARGIN_M: f32 = 0.0005;

/// Candidate bodies fitted to the kept frames.
struct Refits<'a> {
    tracked_with: &'a TrackBody,
    snapshots: &'a [Snapshot],
    settings: &'a TrackerSettings,
    iterations: usize,
}

impl Refits<'_> {
    /// How well `body` explains the kept frames, each fitted from the pose tracked there.
    fn cost(&self, body: TrackBody) -> Result<(f32, TrackBody), ShapeSearchError> {
        let resize = self.tracked_with.height_m / body.height_m;
        let mut tracker = Tracker::new(body, *self.settings);
        let mut total = 0.0;
        for (k, snapshot) in self.snapshots.iter().enumerate() {
            let mut pose = snapshot.tracked.pose.clone();
            // The same person: the tracked size in metres, on the body's proportions.
            pose.scale *= resize;
            let fit = tracker
                .refit(&snapshot.frame, &mut pose, self.iterations)
                .ok_or(ShapeSearchError::NoPerson(k))?;
            total += cost(&fit);
        }
        Ok((total / self.snapshots.len() as f32, tracker.body))
    }
}

/// The build of the person in `snapshots` as `fit` finds it, bare or under the clothing
/// layer ([`TrackerSettings::clothing_m`]; then the body under it is
/// [`BuildFit::under_clothes`]'s, if it gives one): as the `sleeves` say ([`crate::sleeve`]),
/// and when they do not tell, the layer is taken when the fit's own cost falls by
/// [`TrackerSettings::clothing_margin`] under it.
///
/// (The fit's cost, not the tracker's: each body is fitted to the surface it is given, so a
/// bare build swells into a shirt and explains its frames about as well as the build under
/// the layer does: by the tracker's cost the layer was taken on 23 of the 45 T-shirt
/// recordings of the acceptance set. The fit's cost, with its shape prior, sees a trunk
/// swollen on slender limbs: it fell by 1 % under the layer in 66 of 83 searches on the
/// T-shirt recordings and in 6 of 82 on the bare ones; docs/STATUS.md, session 45.)
pub fn estimate_with(
    model: &BodyModel,
    fit: &dyn BuildFit,
    snapshots: &[Snapshot],
    settings: &TrackerSettings,
    sleeves: Sleeves,
) -> Result<Estimate, ShapeSearchError> {
    if snapshots.is_empty() {
        return Err(ShapeSearchError::NoSnapshots);
    }
    let fitted = |t: f32| fit.fit(model, snapshots, t).map_err(ShapeSearchError::Fit);
    let t = settings.clothing_m;
    let bare = |bare: BuildFitted, evaluations| Clothed {
        shape: bare.shape,
        clothing_m: 0.0,
        evaluations,
        under_error: None,
    };
    // The body under the layer: a failed second fit leaves the first, which is good.
    let clothe =
        |clothed: BuildFitted, evaluations: usize| match fit.under_clothes(model, snapshots, t) {
            Ok(under) => Clothed {
                evaluations: evaluations + usize::from(under.is_some()),
                shape: under.unwrap_or(clothed.shape),
                clothing_m: t,
                under_error: None,
            },
            Err(e) => Clothed {
                shape: clothed.shape,
                clothing_m: t,
                evaluations: evaluations + 1,
                under_error: Some(e),
            },
        };
    let found = if t <= 0.0 || sleeves == Sleeves::Bare {
        bare(fitted(0.0)?, 1)
    } else if sleeves == Sleeves::Seen {
        clothe(fitted(t)?, 1)
    } else {
        let (b, clothed) = (fitted(0.0)?, fitted(t)?);
        if clothed.cost < b.cost * (1.0 - f64::from(settings.clothing_margin)) {
            clothe(clothed, 2)
        } else {
            bare(b, 2)
        }
    };
    let Clothed {
        shape,
        clothing_m,
        evaluations,
        under_error,
    } = found;
    let mut body = TrackBody::new(model, &model.shaped(&shape)?.positions)?;
    body.clothe(clothing_m);
    Ok(Estimate {
        shape,
        body,
        sized: true,
        default_cost_m: None,
        cost_m: None,
        evaluations,
        clothing_m,
        under_clothes_error: under_error,
    })
}

/// A build found by [`estimate_with`], bare or under the layer.
struct Clothed {
    shape: Shape,
    clothing_m: f32,
    evaluations: usize,
    under_error: Option<String>,
}
