//! Measuring one person: the body fitted twice, with the women's and with the men's shape
//! prior (the camera does not know the gender, and a size chart is for one), the better
//! explanation of the frames kept.

use fitroom_body::BodyModel;

use crate::MeasureError;
use crate::fit::{BodyEstimate, FitSettings, ViewPose, fit_body};
use crate::posed::ShapeSpace;
use crate::prior::ShapePrior;

/// The person's body, as measured.
#[derive(Clone, Debug)]
pub struct PersonMeasurement {
    /// Whether the women's prior explained the frames better.
    pub female: bool,
    pub estimate: BodyEstimate,
    /// The other gender's fit's cost (the kept one's is `estimate.cost`).
    pub other_cost: f64,
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
fn both_genders(
    model: &BodyModel,
    views: &[ViewPose],
    prior: &ShapePrior,
    settings: &FitSettings,
) -> Result<PersonMeasurement, MeasureError> {
    let space = ShapeSpace::full();
    let one = |female: bool, threads: usize| {
        let p = prior.of(female);
        let start = space.shape(&p.mean);
        let s = FitSettings {
            threads,
            ..settings.clone()
        };
        fit_body(model, views, &start, Some(p), &s)
    };
    let (women, men) = if settings.threads >= 2 {
        let per = settings.threads / 2;
        std::thread::scope(|scope| {
            let w = scope.spawn(|| one(true, per));
            let m = one(false, per);
            (w.join().unwrap_or(Err(MeasureError::Worker)), m)
        })
    } else {
        (one(true, 1), one(false, 1))
    };
    let (female, estimate, other_cost) = match (women, men) {
        (Ok(w), Ok(m)) if w.cost <= m.cost => (true, w, m.cost),
        (Ok(w), Ok(m)) => (false, m, w.cost),
        (Ok(w), Err(_)) => (true, w, f64::INFINITY),
        (Err(_), Ok(m)) => (false, m, f64::INFINITY),
        (Err(e), Err(_)) => return Err(e),
    };
    Ok(PersonMeasurement {
        female,
        estimate,
        other_cost,
        turned_dropped: false,
    })
}
