//! The ANSUR II anthropometric survey (US Army, 2012; public data: 4,082 men, 1,986 women,
//! millimetres) as fitting targets, and the evaluation of [`crate::fit`] over its subjects.
//!
//! The nine measurements fitted, with ANSUR II's definitions and ours ([`crate::measure`]):
//!
//! | ANSUR II column | ANSUR II definition | ours |
//! | --- | --- | --- |
//! | `stature` | vertex to floor | [`Measure::Stature`] |
//! | `chestcircumference` | at the nipples (bust points) | [`Measure::Bust`]: largest chest girth below the armpits |
//! | `waistcircumference` | at the omphalion (navel) | [`Measure::NavelWaist`] |
//! | `buttockcircumference` | at the buttocks' maximum protrusion | [`Measure::Hip`] |
//! | `neckcircumferencebase` | neck base | [`Measure::Neck`] |
//! | `thighcircumference` | at the gluteal furrow | [`Measure::Thigh`]: largest girth below the crotch |
//! | `calfcircumference` | maximum | [`Measure::Calf`] |
//! | `biacromialbreadth` | acromion to acromion | [`Measure::ShoulderWidth`] |
//! | `crotchheight` | crotch to floor | [`Measure::InsideLeg`] |

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use fitroom_math::stats::percentile;
use serde::{Deserialize, Serialize};

use crate::fit::{FitOptions, FitReport, FitRequest, fit};
use crate::measure::Measure;
use crate::model::BodyModel;

/// The ANSUR II columns fitted and the measure each one is.
pub const ANSUR_MEASURES: [(&str, Measure); 9] = [
    ("stature", Measure::Stature),
    ("chestcircumference", Measure::Bust),
    ("waistcircumference", Measure::NavelWaist),
    ("buttockcircumference", Measure::Hip),
    ("neckcircumferencebase", Measure::Neck),
    ("thighcircumference", Measure::Thigh),
    ("calfcircumference", Measure::Calf),
    ("biacromialbreadth", Measure::ShoulderWidth),
    ("crotchheight", Measure::InsideLeg),
];

/// One surveyed person.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AnsurSubject {
    pub id: String,
    pub female: bool,
    pub age_years: f32,
    pub weight_kg: f32,
    /// The nine [`ANSUR_MEASURES`], cm.
    pub measurements: BTreeMap<Measure, f32>,
}

/// Why an ANSUR file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum AnsurError {
    #[error("cannot read '{path}': {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("'{path}': {source}")]
    Csv { path: String, source: csv::Error },
    #[error(
        "'{path}' has no column `{column}`; is it an ANSUR II Public CSV file \
         (ANSUR_II_FEMALE_Public.csv / ANSUR_II_MALE_Public.csv)?"
    )]
    MissingColumn { path: String, column: String },
    #[error("'{path}' line {line}, column `{column}`: `{value}` is not a number")]
    BadNumber {
        path: String,
        line: u64,
        column: String,
        value: String,
    },
}

/// The survey's two public files and whether each holds women.
pub const ANSUR_FILES: [(&str, bool); 2] = [
    ("ANSUR_II_FEMALE_Public.csv", true),
    ("ANSUR_II_MALE_Public.csv", false),
];

/// Reads both ANSUR II files from `dir`, each plain (`.csv`) or gzip-compressed (`.csv.gz`):
/// the women, then the men.
pub fn read_survey(dir: &Path) -> Result<[Vec<AnsurSubject>; 2], AnsurError> {
    let read = |(name, female): (&str, bool)| {
        let plain = dir.join(name);
        let compressed = dir.join(format!("{name}.gz"));
        let path = if plain.is_file() || !compressed.is_file() {
            plain
        } else {
            compressed
        };
        read_ansur(&path, female)
    };
    Ok([read(ANSUR_FILES[0])?, read(ANSUR_FILES[1])?])
}

/// Reads an ANSUR II public CSV file, plain or gzip-compressed (latin-1; the id column is
/// `SubjectId` in the female file and `subjectid` in the male one).
pub fn read_ansur(path: &Path, female: bool) -> Result<Vec<AnsurSubject>, AnsurError> {
    let p = path.display().to_string();
    let io = |source| AnsurError::Io {
        path: p.clone(),
        source,
    };
    let mut bytes = std::fs::read(path).map_err(io)?;
    if bytes.starts_with(&[0x1f, 0x8b]) {
        let mut text = Vec::with_capacity(bytes.len() * 5);
        std::io::Read::read_to_end(
            &mut flate2::read::GzDecoder::new(bytes.as_slice()),
            &mut text,
        )
        .map_err(io)?;
        bytes = text;
    }
    // Latin-1 to UTF-8: every byte is its own code point.
    let text: String = bytes.iter().map(|&b| b as char).collect();
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .map_err(|source| AnsurError::Csv {
            path: p.clone(),
            source,
        })?
        .clone();
    let column = |name: &str| -> Result<usize, AnsurError> {
        headers
            .iter()
            .position(|h| h.eq_ignore_ascii_case(name))
            .ok_or_else(|| AnsurError::MissingColumn {
                path: p.clone(),
                column: name.to_owned(),
            })
    };
    let id = column("subjectid")?;
    let age = column("Age")?;
    let weight = column("weightkg")?;
    let measures: Vec<(usize, &str, Measure)> = ANSUR_MEASURES
        .iter()
        .map(|&(c, m)| column(c).map(|i| (i, c, m)))
        .collect::<Result<_, _>>()?;
    let mut out = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|source| AnsurError::Csv {
            path: p.clone(),
            source,
        })?;
        let line = record.position().map_or(0, |pos| pos.line());
        let number = |i: usize, name: &str| -> Result<f32, AnsurError> {
            let v = record.get(i).unwrap_or("");
            v.trim()
                .parse::<f32>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| AnsurError::BadNumber {
                    path: p.clone(),
                    line,
                    column: name.to_owned(),
                    value: v.to_owned(),
                })
        };
        let mut measurements = BTreeMap::new();
        for &(i, name, m) in &measures {
            measurements.insert(m, number(i, name)? / 10.0);
        }
        out.push(AnsurSubject {
            id: record.get(id).unwrap_or("").to_owned(),
            female,
            age_years: number(age, "Age")?,
            weight_kg: number(weight, "weightkg")? / 10.0,
            measurements,
        });
    }
    Ok(out)
}

/// `count` subjects drawn without replacement by a seeded generator (splitmix64 +
/// Fisher-Yates), the same for the same seed; all of them if `count` is larger.
pub fn sample<T: Clone>(items: &[T], count: usize, seed: u64) -> Vec<T> {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let mut idx: Vec<usize> = (0..items.len()).collect();
    let n = count.min(items.len());
    for i in 0..n {
        let j = i + (next() % (items.len() - i) as u64) as usize;
        idx.swap(i, j);
    }
    idx[..n].iter().map(|&i| items[i].clone()).collect()
}

/// The fit of one subject.
#[derive(Clone, Debug, Serialize)]
pub struct SubjectFit {
    pub id: String,
    pub female: bool,
    /// Achieved minus measured, cm (NaN if the fit failed).
    pub residuals_cm: BTreeMap<Measure, f32>,
    pub reachable: bool,
    pub at_bounds: Vec<String>,
    pub time_ms: f64,
    /// The error, if the fit could not be made.
    pub error: Option<String>,
}

/// Distribution of |error| of one measure over the subjects: the one error summary of
/// fitroom's evaluations (the ANSUR fit's, the measurement from depth's).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct MeasureStats {
    pub measure: Measure,
    pub count: usize,
    /// Share of subjects with |error| <= the tolerance.
    #[serde(default)]
    pub within_tolerance: f64,
    pub mean_abs_cm: f64,
    #[serde(default)]
    pub median_abs_cm: f64,
    #[serde(default)]
    pub p90_abs_cm: f64,
    pub p95_abs_cm: f64,
    pub max_abs_cm: f64,
    /// Mean signed error (achieved - measured), cm.
    pub bias_cm: f64,
}

impl MeasureStats {
    /// The summary of `errors` (cm, signed); a non-finite error is a failure: counted, never
    /// within the tolerance, at infinity in the percentiles, left out of the means.
    pub fn of(measure: Measure, errors: &[f64], tolerance_cm: f64) -> Self {
        let abs = sorted_abs(errors);
        let finite: Vec<f64> = errors.iter().copied().filter(|e| e.is_finite()).collect();
        let per = |v: f64| v / finite.len().max(1) as f64;
        let at = |q: f64| {
            if abs.is_empty() {
                f64::NAN
            } else {
                percentile(&abs, q)
            }
        };
        Self {
            measure,
            count: abs.len(),
            within_tolerance: abs.iter().filter(|&&e| e <= tolerance_cm).count() as f64
                / abs.len().max(1) as f64,
            mean_abs_cm: per(finite.iter().map(|e| e.abs()).sum()),
            median_abs_cm: at(0.5),
            p90_abs_cm: at(0.9),
            p95_abs_cm: at(0.95),
            max_abs_cm: abs.last().copied().unwrap_or(f64::NAN),
            bias_cm: per(finite.iter().sum()),
        }
    }
}

/// `|errors|`, smallest first; a non-finite error (a failed fit) at infinity.
fn sorted_abs(errors: &[f64]) -> Vec<f64> {
    let mut abs: Vec<f64> = errors
        .iter()
        .map(|e| {
            if e.is_finite() {
                e.abs()
            } else {
                f64::INFINITY
            }
        })
        .collect();
    abs.sort_by(f64::total_cmp);
    abs
}

/// The evaluation of [`fit`] over survey subjects.
#[derive(Clone, Debug, Serialize)]
pub struct AnsurReport {
    pub subjects: usize,
    pub tolerance_cm: f32,
    /// Share of (subject, measurement) pairs within the tolerance.
    pub pairs_within_tolerance: f64,
    pub pairs: usize,
    /// Subjects every measure of which is within the tolerance.
    pub subjects_reachable: usize,
    /// Fits that failed with an error.
    pub failed_fits: usize,
    /// Per measure, worst share within tolerance first.
    pub per_measure: Vec<MeasureStats>,
    /// Histogram of |error| over all pairs: counts in bins of 0.1 cm up to 2 cm, then one bin
    /// for everything above.
    pub histogram_abs_cm: Vec<(f32, usize)>,
    pub mean_fit_ms: f64,
    pub max_fit_ms: f64,
    pub fits: Vec<SubjectFit>,
}

/// Fits every subject on `threads` worker threads (the result does not depend on their
/// number); `progress(done, total)` is called after each fit.
pub fn evaluate(
    model: &BodyModel,
    subjects: &[AnsurSubject],
    options: &FitOptions,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> AnsurReport {
    let done = AtomicUsize::new(0);
    let fits = fitroom_math::parallel_map(subjects, threads, |s| {
        let request = FitRequest {
            gender: if s.female { 0.0 } else { 1.0 },
            age_years: None,
            targets: s.measurements.clone(),
        };
        let fit = match fit(model, &request, options) {
            Ok(r) => subject_fit(s, &r),
            Err(e) => SubjectFit {
                id: s.id.clone(),
                female: s.female,
                residuals_cm: s.measurements.keys().map(|&m| (m, f32::NAN)).collect(),
                reachable: false,
                at_bounds: Vec::new(),
                time_ms: 0.0,
                error: Some(e.to_string()),
            },
        };
        progress(done.fetch_add(1, Ordering::Relaxed) + 1, subjects.len());
        fit
    });
    summarise(fits, options.tolerance_cm)
}

fn subject_fit(s: &AnsurSubject, r: &FitReport) -> SubjectFit {
    SubjectFit {
        id: s.id.clone(),
        female: s.female,
        residuals_cm: r.residuals_cm.clone(),
        reachable: r.reachable,
        at_bounds: r.at_bounds.clone(),
        time_ms: r.time_ms,
        error: None,
    }
}

/// The statistics of a set of subject fits.
pub fn summarise(fits: Vec<SubjectFit>, tolerance_cm: f32) -> AnsurReport {
    let tol = tolerance_cm as f64;
    let mut per_measure = Vec::new();
    let (mut pairs, mut within) = (0usize, 0usize);
    let mut all_abs: Vec<f64> = Vec::new();
    for &(_, measure) in &ANSUR_MEASURES {
        let errs: Vec<f64> = fits
            .iter()
            .filter_map(|f| f.residuals_cm.get(&measure))
            .map(|&e| e as f64)
            .collect();
        let abs = sorted_abs(&errs);
        let ok = abs.iter().filter(|&&e| e <= tol).count();
        pairs += abs.len();
        within += ok;
        all_abs.extend(&abs);
        per_measure.push(MeasureStats::of(measure, &errs, tol));
    }
    per_measure.sort_by(|a, b| a.within_tolerance.total_cmp(&b.within_tolerance));
    let mut histogram: Vec<(f32, usize)> = (0..20).map(|i| (i as f32 * 0.1, 0)).collect();
    histogram.push((2.0, 0));
    for e in all_abs {
        let bin = if e.is_finite() {
            ((e / 0.1).floor() as usize).min(20)
        } else {
            20
        };
        histogram[bin].1 += 1;
    }
    let times: Vec<f64> = fits
        .iter()
        .filter(|f| f.error.is_none())
        .map(|f| f.time_ms)
        .collect();
    AnsurReport {
        subjects: fits.len(),
        tolerance_cm,
        pairs_within_tolerance: within as f64 / pairs.max(1) as f64,
        pairs,
        subjects_reachable: fits.iter().filter(|f| f.reachable).count(),
        failed_fits: fits.iter().filter(|f| f.error.is_some()).count(),
        per_measure,
        histogram_abs_cm: histogram,
        mean_fit_ms: times.iter().sum::<f64>() / times.len().max(1) as f64,
        max_fit_ms: times.iter().copied().fold(0.0, f64::max),
        fits,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_is_seeded_and_without_replacement() {
        let items: Vec<u32> = (0..100).collect();
        let a = sample(&items, 30, 7);
        assert_eq!(a, sample(&items, 30, 7));
        assert_ne!(a, sample(&items, 30, 8));
        let mut d = a.clone();
        d.sort_unstable();
        d.dedup();
        assert_eq!(d.len(), 30);
        assert_eq!(sample(&items, 500, 1).len(), 100);
    }

    #[test]
    fn summary_counts_pairs_within_tolerance() {
        let fit = |errs: [f32; 9]| SubjectFit {
            id: String::new(),
            female: true,
            residuals_cm: ANSUR_MEASURES
                .iter()
                .zip(errs)
                .map(|(&(_, m), e)| (m, e))
                .collect(),
            reachable: errs.iter().all(|e| e.abs() <= 0.5),
            at_bounds: Vec::new(),
            time_ms: 1.0,
            error: None,
        };
        let r = summarise(
            vec![
                fit([0.1; 9]),
                fit([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.5, f32::NAN]),
            ],
            0.5,
        );
        assert_eq!(r.pairs, 18);
        assert!((r.pairs_within_tolerance - 16.0 / 18.0).abs() < 1e-12);
        assert_eq!(r.subjects_reachable, 1);
        assert_eq!(r.histogram_abs_cm.iter().map(|h| h.1).sum::<usize>(), 18);
        // The two failing measures come first.
        assert!(r.per_measure[0].within_tolerance < 1.0);
        assert!(r.per_measure[1].within_tolerance < 1.0);
        assert_eq!(r.per_measure[2].within_tolerance, 1.0);
    }
}
