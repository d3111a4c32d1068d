//! Measuring one person: the body fitted twice, with the women's and with the men's shape
//! prior (the camera does not know the gender, and a size chart is for one), the better
//! explanation of the frames kept ([`evidence`]).

use fitroom_body::BodyModel;
use glam::Quat;

use crate::MeasureError;
use crate::fit::{BodyEstimate, FitSettings, ViewPose, fit_body};
use crate::posed::ShapeSpace;
use crate::prior::{GenderPrior, ShapePrior};

/// The person's body, as measured.
#[derive(Clone, Debug)]
pub struct PersonMeasurement {
    /// Whether the women's prior explained the frames better.
    pub female: bool,
    pub estimate: BodyEstimate,
    /// The other gender's fit, if it succeeded.
    pub other: Option<BodyEstimate>,
    /// Each fit's evidence (see [`evidence`]), women's then men's; lower is better.
    pub evidence: [f64; 2],
    /// Whether the turned view was left out: the fit could not match it (its points' RMS
    /// more than [`TURNED_RMS_RATIO`] times the front's), so the front was fitted alone.
    pub turned_dropped: bool,
}

/// A turned view whose points' RMS is this many times the front view's is not trusted (the
/// tracker lost the turned person, or placed them wrong): the front is measured alone.
pub const TURNED_RMS_RATIO: f32 = 1.5;

/// Fits `views` with both priors (at once when `settings.threads` ≥ 2) and keeps the better;
/// again on the front view alone if the fit could not match the others.
pub fn measure_person(
    model: &BodyModel,
    views: &[ViewPose],
    prior: &ShapePrior,
    settings: &FitSettings,
) -> Result<PersonMeasurement, MeasureError> {
    let both = both_genders(model, views, prior, settings)?;
    let rms = &both.estimate.view_rms_m;
    let suspect = rms.len() > 1
        && rms[1..]
            .iter()
            .any(|r| *r > TURNED_RMS_RATIO * rms[0].max(1e-4));
    if !suspect {
        return Ok(both);
    }
    Ok(PersonMeasurement {
        turned_dropped: true,
        ..both_genders(model, &views[..1], prior, settings)?
    })
}

/// Fits `views` with both priors and keeps the better.
pub(crate) fn both_genders(
    model: &BodyModel,
    views: &[ViewPose],
    prior: &ShapePrior,
    settings: &FitSettings,
) -> Result<PersonMeasurement, MeasureError> {
    let space = ShapeSpace::full();
    let one = |female: bool, views: &[ViewPose], threads: usize| {
        let p = prior.of(female);
        let start = space.shape(&p.mean);
        let s = FitSettings {
            threads,
            ..settings.clone()
        };
        fit_body(model, views, &start, Some(p), &s)
    };
    let both = |views: &[ViewPose]| {
        if settings.threads >= 2 {
            let per = settings.threads / 2;
            std::thread::scope(|scope| {
                let w = scope.spawn(|| one(true, views, per));
                let m = one(false, views, per);
                (w.join().unwrap_or(Err(MeasureError::Worker)), m)
            })
        } else {
            (one(true, views, 1), one(false, views, 1))
        }
    };
    let (mut women, mut men) = both(views);
    // Both stuck (their points' RMS above STUCK_RMS_M): the start was wrong for both (the
    // tracker folded an arm onto the body, or lost it: small women, mostly). Made again from
    // the pose the calibration asks for (the rest pose, arms a little away from the body)
    // where the tracker placed the body; each kept if better. (Only both: one gender's fit
    // alone above it is, nine times in ten, the other gender's prior failing to reach the
    // person's shape in the right pose, and made again from the other's pose it ends where
    // it was: 81 wasted refits for 6 useful on 200 subjects.)
    let worst = |fit: &Result<BodyEstimate, MeasureError>| {
        fit.as_ref().map_or(0.0, BodyEstimate::worst_view_rms_m)
    };
    if worst(&women) > STUCK_RMS_M && worst(&men) > STUCK_RMS_M {
        let rest = vec![Quat::IDENTITY; model.bones.len()];
        let restarted: Vec<ViewPose> = views
            .iter()
            .map(|v| ViewPose {
                locals: &rest,
                ..*v
            })
            .collect();
        let (w, m) = both(&restarted);
        let better = |again: Result<BodyEstimate, MeasureError>, was: &mut Result<_, _>| {
            if let Ok(a) = again
                && was.as_ref().is_ok_and(|b: &BodyEstimate| a.cost < b.cost)
            {
                *was = Ok(a);
            }
        };
        better(w, &mut women);
        better(m, &mut men);
    }
    let mu = f64::from(settings.prior);
    let score = |fit: &Result<BodyEstimate, MeasureError>, female: bool| match fit {
        Ok(e) => evidence(e, prior.of(female), mu),
        Err(_) => f64::INFINITY,
    };
    let scores = [score(&women, true), score(&men, false)];
    let (female, estimate, other) = match (women, men) {
        (Ok(w), Ok(m)) if scores[0] <= scores[1] => (true, w, Some(m)),
        (Ok(w), Ok(m)) => (false, m, Some(w)),
        (Ok(w), Err(_)) => (true, w, None),
        (Err(_), Ok(m)) => (false, m, None),
        (Err(e), Err(_)) => return Err(e),
    };
    Ok(PersonMeasurement {
        female,
        estimate,
        other,
        evidence: scores,
        turned_dropped: false,
    })
}

/// A fit whose points are this far from the skin (RMS in its worst view) is suspect, metres
/// (good fits through the tracker: 1.8-3.6 mm, 10th to 90th percentile).
pub const STUCK_RMS_M: f32 = 0.0045;

/// How badly a gender's prior explains the frames, in nats (the Laplace approximation of
/// minus the log of the frames' probability under the prior): the fit's cost in units of the
/// prior's weight (the points' error variance), plus half the log-volume the frames leave
/// the unknowns (`ln det H`), minus the prior's own (`ln det P`). The cost alone favours the
/// broader prior, which can bend further towards any frames. (On 200 subjects through the
/// tracker the volume terms differ by tens of nats, the costs by hundreds to thousands: the
/// same choices as the cost alone; kept because it is the right comparison.)
pub fn evidence(fit: &BodyEstimate, prior: &GenderPrior, weight: f64) -> f64 {
    let log_det_p = prior.log_det_precision().unwrap_or(0.0);
    let volume = if fit.log_det_h.is_finite() {
        0.5 * (fit.log_det_h - log_det_p)
    } else {
        0.0
    };
    fit.cost / weight.max(f64::MIN_POSITIVE) + volume
}
