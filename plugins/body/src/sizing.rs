//! Size charts as data files, and a size recommendation from a body's measurements.
//!
//! A size chart follows EN 13402 (seed 002 §4.1, Tables 4.2 and 4.3): each size is described by
//! the body dimensions it is made for (ISO 8559-1 / EN 13402-1 girths and lengths, in cm), not
//! by garment dimensions. The seed tables give one *nominal* value per size; a retailer's chart
//! usually gives a *range* (`M: bust 88-92 cm`). Both can be written in the same file format.
//!
//! # The chart file (RON)
//!
//! ```text
//! (
//!     name: "Example tops",                  // shown in the recommendation
//!     source: "where the numbers come from", // optional
//!     notes: "anything else",                // optional
//!     gender: female,                        // female | male | unisex
//!     primary: ["bust"],                     // optional: the measures that decide the size
//!     sizes: [                               // smallest first
//!         (label: "S", ranges_cm: {"bust": (84, 88), "waist": (66, 70)}),
//!         (label: "M", ranges_cm: {"bust": (88, 92), "waist": (70, 74)}),
//!     ],
//! )
//! ```
//!
//! - `label` is any text (`"S"`, `"40"`, `"W32/L34"`), unique within the chart.
//! - `ranges_cm` maps a measure name to `(min, max)` in cm, both included.
//! - `nominal_cm` maps a measure name to one nominal value, as in the EN 13402 tables. The
//!   range is derived: centred on the nominal value, half as wide as the smaller step to the
//!   neighbouring (different) nominal values, the first and last sizes using their only step.
//!   With the seed's 4 cm bust steps, bust 96 becomes 94-98; where the steps change
//!   (waist 98 then 104) the ranges keep their centres and leave a gap (96-100, then 101-107).
//!   Sizes sharing a nominal value (arm length 63, 63) share its range.
//! - A measure is given in one form throughout the chart (all `nominal_cm` or all `ranges_cm`),
//!   and may be left out of sizes that do not state it, except a primary measure, which every
//!   size must give.
//! - Measure names are those of [`Measure`] ([`Measure::name`], and the aliases
//!   [`Measure::from_name`] accepts): `stature`, `inside-leg`, `arm-length`, `shoulder-width`,
//!   `neck`, `bust` (or `chest`), `underbust`, `waist`, `hip`, `thigh`, `calf`...
//! - Without `primary` (or with `primary: []`), every measure of the chart decides.
//!
//! [`SizeChart::load`] validates everything: unknown fields and measure names are refused with
//! the list of known ones; values must be finite and inside [`Measure::plausible_range_cm`]
//! (so a 3 m waist or a girth typed in mm is caught); `min < max`; labels unique; ranges of
//! consecutive sizes ordered (each size's min and max at least the previous size's).
//!
//! # The recommendation
//!
//! [`recommend`] places each measurement of the body in the chart: the size(s) whose range
//! contains it, or between two sizes (a gap in the chart), or below the smallest or above the
//! largest size (with the distance in cm). Each primary measure *needs* a size: the smallest
//! size containing it, the larger neighbour in a gap, the smallest size below the chart, the
//! largest above it. **The recommended size is the largest size any primary measure needs**, so
//! the garment is not too small anywhere that matters; the other measures (and the primary
//! ones that needed a smaller size) are then reported as fitting, tight or loose in the
//! recommended size. Each measure gets a reason line such as `bust 96.0 cm: 48 (94-98)`.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::measure::{Measure, Measurements};

/// A short picture of the format, appended to syntax errors.
const FORMAT_HINT: &str = "a size chart is a RON struct `(name: \"...\", gender: female, \
primary: [\"bust\"], sizes: [(label: \"S\", ranges_cm: {\"bust\": (84, 88)}), ...])`; \
see the docs of `fitroom_body::sizing`";

/// Who a chart is made for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Gender {
    Female,
    Male,
    Unisex,
}

impl fmt::Display for Gender {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Gender::Female => "female",
            Gender::Male => "male",
            Gender::Unisex => "unisex",
        })
    }
}

/// A body measurement range of one size, cm, both ends included.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RangeCm {
    pub min_cm: f32,
    pub max_cm: f32,
}

impl RangeCm {
    /// Whether `value_cm` is inside (ends included).
    pub fn contains(&self, value_cm: f32) -> bool {
        self.min_cm <= value_cm && value_cm <= self.max_cm
    }

    /// The middle of the range, cm.
    pub fn centre_cm(&self) -> f32 {
        0.5 * (self.min_cm + self.max_cm)
    }
}

impl fmt::Display for RangeCm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}-{}", compact_cm(self.min_cm), compact_cm(self.max_cm))
    }
}

/// One size of a chart.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Size {
    /// The label printed on the garment (`"M"`, `"40"`, `"W32/L34"`).
    pub label: String,
    /// The body range of each measure this size states (given, or derived from the nominal
    /// value).
    pub ranges_cm: BTreeMap<Measure, RangeCm>,
    /// The nominal values, for measures given as `nominal_cm` in the file.
    pub nominal_cm: BTreeMap<Measure, f32>,
}

/// A validated size chart: sizes in order, smallest first.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SizeChart {
    pub name: String,
    pub source: String,
    pub notes: String,
    pub gender: Gender,
    /// The measures that decide the size (every measure of the chart when the file names none).
    pub primary: Vec<Measure>,
    pub sizes: Vec<Size>,
}

/// Why a size chart cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum SizeChartError {
    #[error("cannot read the size chart '{}': {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{file}:{line}:{col}: {message} ({FORMAT_HINT})")]
    Syntax {
        file: String,
        line: usize,
        col: usize,
        message: String,
    },
    #[error("{file}: {problem}")]
    Invalid {
        file: String,
        problem: Box<ChartProblem>,
    },
}

/// What is wrong with the content of a (syntactically valid) chart.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ChartProblem {
    #[error("`sizes` is empty; list at least one size, smallest first")]
    NoSizes,
    #[error("size number {number} has an empty label; give it the text printed on the garment")]
    EmptyLabel { number: usize },
    #[error("sizes number {first} and {second} are both labelled `{label}`; labels must be unique")]
    DuplicateLabel {
        label: String,
        first: usize,
        second: usize,
    },
    #[error("{place}: unknown measure `{name}`; known: {}", Measure::names())]
    UnknownMeasure { place: String, name: String },
    #[error("{place}: measure `{measure}` is given twice; give each measure once")]
    DuplicateMeasure { place: String, measure: Measure },
    #[error(
        "size `{size}` gives no measure; give `ranges_cm` or `nominal_cm` with at least one of: {}",
        Measure::names()
    )]
    NoMeasures { size: String },
    #[error(
        "size `{size}`, {measure}: {field} is {value}, not a number; accepted: {} to {} cm",
        compact_cm(*lo_cm), compact_cm(*hi_cm)
    )]
    NotFinite {
        size: String,
        measure: Measure,
        field: &'static str,
        value: f32,
        lo_cm: f32,
        hi_cm: f32,
    },
    #[error(
        "size `{size}`, {measure}: {field} {} cm is outside the accepted {} to {} cm for {measure} \
         (values in cm; a typing error, or mm?)",
        compact_cm(*value_cm), compact_cm(*lo_cm), compact_cm(*hi_cm)
    )]
    Implausible {
        size: String,
        measure: Measure,
        field: &'static str,
        value_cm: f32,
        lo_cm: f32,
        hi_cm: f32,
    },
    #[error(
        "size `{size}`, {measure}: the range ({}, {}) has min not below max; write it as (min, max) \
         with min < max",
        compact_cm(*min_cm), compact_cm(*max_cm)
    )]
    MinNotBelowMax {
        size: String,
        measure: Measure,
        min_cm: f32,
        max_cm: f32,
    },
    #[error(
        "{measure} is a nominal value in size `{nominal_size}` but a range in size \
         `{range_size}`; give a measure in one form (`nominal_cm` or `ranges_cm`) in every size"
    )]
    MixedForms {
        measure: Measure,
        nominal_size: String,
        range_size: String,
    },
    #[error(
        "{measure}: the nominal value {} cm is the same in every size that gives it, so no range \
         can be derived; give `ranges_cm` for {measure} instead",
        compact_cm(*value_cm)
    )]
    SingleNominal { measure: Measure, value_cm: f32 },
    #[error(
        "{measure}: size `{size}` ({this}) comes after size `{previous}` ({previous_value}) but is \
         smaller; list sizes smallest first, each size's {measure} at least the previous one's"
    )]
    Unordered {
        measure: Measure,
        previous: String,
        previous_value: String,
        size: String,
        this: String,
    },
    #[error(
        "primary measure {measure} is not given in size `{size}`; every size must give the \
         measures that decide the size (or remove {measure} from `primary`)"
    )]
    PrimaryMissing { measure: Measure, size: String },
}

// ---------------------------------------------------------------------------------------------
// The file as written.

/// A RON map kept as a list, so a measure given twice is reported instead of silently
/// overwritten.
#[derive(Debug)]
struct Entries<T>(Vec<(String, T)>);

impl<T> Default for Entries<T> {
    fn default() -> Self {
        Self(Vec::new())
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Entries<T> {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct EntriesVisitor<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for EntriesVisitor<T> {
            type Value = Entries<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map from measure names to values, e.g. {\"bust\": ...}")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Self::Value, A::Error> {
                let mut entries = Vec::new();
                while let Some(entry) = map.next_entry::<String, T>()? {
                    entries.push(entry);
                }
                Ok(Entries(entries))
            }
        }
        deserializer.deserialize_map(EntriesVisitor(std::marker::PhantomData))
    }
}

#[derive(Debug, Deserialize)]
#[serde(rename = "SizeChart", deny_unknown_fields)]
struct ChartFile {
    name: String,
    #[serde(default)]
    source: String,
    #[serde(default)]
    notes: String,
    gender: Gender,
    #[serde(default)]
    primary: Vec<String>,
    sizes: Vec<SizeFile>,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Size", deny_unknown_fields)]
struct SizeFile {
    label: String,
    #[serde(default)]
    nominal_cm: Entries<f32>,
    #[serde(default)]
    ranges_cm: Entries<(f32, f32)>,
}

/// How a measure is given in one size, as written.
#[derive(Clone, Copy, Debug)]
enum Given {
    Nominal(f32),
    Range(RangeCm),
}

impl SizeChart {
    /// Reads and validates a chart file (RON; format in the [module docs](self)).
    pub fn load(path: impl AsRef<Path>) -> Result<SizeChart, SizeChartError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| SizeChartError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::from_ron_str(&text, &path.display().to_string())
    }

    /// Parses and validates a chart from RON text; `file` names it in errors.
    pub fn from_ron_str(text: &str, file: &str) -> Result<SizeChart, SizeChartError> {
        let raw: ChartFile = ron::from_str(text).map_err(|e| SizeChartError::Syntax {
            file: file.to_owned(),
            line: e.span.start.line,
            col: e.span.start.col,
            message: e.code.to_string(),
        })?;
        Self::from_file(raw).map_err(|problem| SizeChartError::Invalid {
            file: file.to_owned(),
            problem: Box::new(problem),
        })
    }

    /// The size labelled `label`.
    pub fn size(&self, label: &str) -> Option<&Size> {
        self.sizes.iter().find(|s| s.label == label)
    }

    /// The measures stated by at least one size, primary ones first (in their order), then
    /// the others in [`Measure::ALL`] order.
    pub fn measures(&self) -> Vec<Measure> {
        let mut out = self.primary.clone();
        for m in Measure::ALL {
            if !out.contains(&m) && self.sizes.iter().any(|s| s.ranges_cm.contains_key(&m)) {
                out.push(m);
            }
        }
        out
    }

    /// Recommends a size for `measurements`; see [`recommend`].
    pub fn recommend(&self, measurements: &Measurements) -> Recommendation {
        recommend(self, measurements)
    }

    fn from_file(raw: ChartFile) -> Result<SizeChart, ChartProblem> {
        if raw.sizes.is_empty() {
            return Err(ChartProblem::NoSizes);
        }
        // Per size: labels and the measures as written.
        let mut labels: Vec<String> = Vec::with_capacity(raw.sizes.len());
        let mut given: Vec<BTreeMap<Measure, Given>> = Vec::with_capacity(raw.sizes.len());
        for (i, size) in raw.sizes.iter().enumerate() {
            let label = size.label.trim().to_owned();
            if label.is_empty() {
                return Err(ChartProblem::EmptyLabel { number: i + 1 });
            }
            if let Some(first) = labels.iter().position(|l| *l == label) {
                return Err(ChartProblem::DuplicateLabel {
                    label,
                    first: first + 1,
                    second: i + 1,
                });
            }
            let mut this: BTreeMap<Measure, Given> = BTreeMap::new();
            let mut insert = |field: &str, name: &str, g: Given| {
                let place = format!("size `{label}`, {field}");
                let measure =
                    Measure::from_name(name).ok_or_else(|| ChartProblem::UnknownMeasure {
                        place: place.clone(),
                        name: name.to_owned(),
                    })?;
                if this.insert(measure, g).is_some() {
                    return Err(ChartProblem::DuplicateMeasure {
                        place: format!("size `{label}`"),
                        measure,
                    });
                }
                check_given(&label, measure, g)
            };
            for (name, v) in &size.nominal_cm.0 {
                insert("nominal_cm", name, Given::Nominal(*v))?;
            }
            for (name, (min_cm, max_cm)) in &size.ranges_cm.0 {
                let range = RangeCm {
                    min_cm: *min_cm,
                    max_cm: *max_cm,
                };
                insert("ranges_cm", name, Given::Range(range))?;
            }
            if this.is_empty() {
                return Err(ChartProblem::NoMeasures { size: label });
            }
            labels.push(label);
            given.push(this);
        }

        // Per measure: one form, ordered sizes, ranges derived from nominal values.
        let mut ranges: Vec<BTreeMap<Measure, RangeCm>> = vec![BTreeMap::new(); labels.len()];
        let mut nominals: Vec<BTreeMap<Measure, f32>> = vec![BTreeMap::new(); labels.len()];
        for measure in Measure::ALL {
            let column: Vec<(usize, Given)> = given
                .iter()
                .enumerate()
                .filter_map(|(i, g)| g.get(&measure).map(|g| (i, *g)))
                .collect();
            let first_nominal = column.iter().find(|(_, g)| matches!(g, Given::Nominal(_)));
            let first_range = column.iter().find(|(_, g)| matches!(g, Given::Range(_)));
            match (first_nominal, first_range) {
                (Some((n, _)), Some((r, _))) => {
                    return Err(ChartProblem::MixedForms {
                        measure,
                        nominal_size: labels[*n].clone(),
                        range_size: labels[*r].clone(),
                    });
                }
                (Some(_), None) => {
                    let values: Vec<(usize, f32)> = column
                        .iter()
                        .filter_map(|(i, g)| match g {
                            Given::Nominal(v) => Some((*i, *v)),
                            Given::Range(_) => None,
                        })
                        .collect();
                    for w in values.windows(2) {
                        let ((p, pv), (s, sv)) = (w[0], w[1]);
                        if sv < pv {
                            return Err(ChartProblem::Unordered {
                                measure,
                                previous: labels[p].clone(),
                                previous_value: format!("nominal {} cm", compact_cm(pv)),
                                size: labels[s].clone(),
                                this: format!("nominal {} cm", compact_cm(sv)),
                            });
                        }
                    }
                    for (i, range) in ranges_from_nominal(measure, &values)? {
                        ranges[i].insert(measure, range);
                    }
                    for (i, v) in values {
                        nominals[i].insert(measure, v);
                    }
                }
                (None, Some(_)) => {
                    let mut previous: Option<(usize, RangeCm)> = None;
                    for (i, g) in &column {
                        let Given::Range(range) = *g else { continue };
                        if let Some((p, pr)) = previous
                            && (range.min_cm < pr.min_cm || range.max_cm < pr.max_cm)
                        {
                            return Err(ChartProblem::Unordered {
                                measure,
                                previous: labels[p].clone(),
                                previous_value: format!("{pr} cm"),
                                size: labels[*i].clone(),
                                this: format!("{range} cm"),
                            });
                        }
                        previous = Some((*i, range));
                        ranges[*i].insert(measure, range);
                    }
                }
                (None, None) => {}
            }
        }

        // The deciding measures.
        let mut primary: Vec<Measure> = Vec::new();
        for name in &raw.primary {
            let measure = Measure::from_name(name).ok_or_else(|| ChartProblem::UnknownMeasure {
                place: "primary".to_owned(),
                name: name.clone(),
            })?;
            if primary.contains(&measure) {
                return Err(ChartProblem::DuplicateMeasure {
                    place: "primary".to_owned(),
                    measure,
                });
            }
            primary.push(measure);
        }
        if primary.is_empty() {
            let stated: BTreeSet<Measure> = ranges.iter().flat_map(|r| r.keys().copied()).collect();
            primary = Measure::ALL
                .into_iter()
                .filter(|m| stated.contains(m))
                .collect();
        }
        for &measure in &primary {
            if let Some(i) = ranges.iter().position(|r| !r.contains_key(&measure)) {
                return Err(ChartProblem::PrimaryMissing {
                    measure,
                    size: labels[i].clone(),
                });
            }
        }

        let sizes = labels
            .into_iter()
            .zip(ranges)
            .zip(nominals)
            .map(|((label, ranges_cm), nominal_cm)| Size {
                label,
                ranges_cm,
                nominal_cm,
            })
            .collect();
        Ok(SizeChart {
            name: raw.name,
            source: raw.source,
            notes: raw.notes,
            gender: raw.gender,
            primary,
            sizes,
        })
    }
}

/// Checks one value as written: finite, plausible, min < max.
fn check_given(size: &str, measure: Measure, given: Given) -> Result<(), ChartProblem> {
    let (lo_cm, hi_cm) = measure.plausible_range_cm();
    let values: &[(&'static str, f32)] = match given {
        Given::Nominal(v) => &[("nominal value", v)],
        Given::Range(r) => &[("min", r.min_cm), ("max", r.max_cm)],
    };
    for &(field, value) in values {
        if !value.is_finite() {
            return Err(ChartProblem::NotFinite {
                size: size.to_owned(),
                measure,
                field,
                value,
                lo_cm,
                hi_cm,
            });
        }
        if !(lo_cm..=hi_cm).contains(&value) {
            return Err(ChartProblem::Implausible {
                size: size.to_owned(),
                measure,
                field,
                value_cm: value,
                lo_cm,
                hi_cm,
            });
        }
    }
    if let Given::Range(r) = given
        && r.min_cm >= r.max_cm
    {
        return Err(ChartProblem::MinNotBelowMax {
            size: size.to_owned(),
            measure,
            min_cm: r.min_cm,
            max_cm: r.max_cm,
        });
    }
    Ok(())
}

/// Ranges centred on ordered nominal values, half as wide as the smaller step to the
/// neighbouring distinct values (see the [module docs](self)).
fn ranges_from_nominal(
    measure: Measure,
    values: &[(usize, f32)],
) -> Result<Vec<(usize, RangeCm)>, ChartProblem> {
    let mut distinct: Vec<f32> = values.iter().map(|&(_, v)| v).collect();
    distinct.dedup();
    if distinct.len() < 2 {
        return Err(ChartProblem::SingleNominal {
            measure,
            value_cm: distinct.first().copied().unwrap_or(f32::NAN),
        });
    }
    let mut out = Vec::with_capacity(values.len());
    let mut k = 0;
    for &(i, v) in values {
        while distinct[k] != v {
            k += 1;
        }
        let below = (k > 0).then(|| v - distinct[k - 1]);
        let above = distinct.get(k + 1).map(|next| next - v);
        let step = match (below, above) {
            (Some(b), Some(a)) => b.min(a),
            (Some(s), None) | (None, Some(s)) => s,
            (None, None) => unreachable!("two distinct values give each one a neighbour"),
        };
        out.push((
            i,
            RangeCm {
                min_cm: v - 0.5 * step,
                max_cm: v + 0.5 * step,
            },
        ));
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// The recommendation.

/// A size and its range for one measure.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SizeRange {
    pub label: String,
    pub min_cm: f32,
    pub max_cm: f32,
}

impl fmt::Display for SizeRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ({}-{})",
            self.label,
            compact_cm(self.min_cm),
            compact_cm(self.max_cm)
        )
    }
}

/// Where one measurement falls in the chart.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Placement {
    /// Inside the range of these sizes (several when ranges touch or overlap), smallest first.
    Within { sizes: Vec<SizeRange> },
    /// In a gap of the chart, above `smaller`'s range and below `larger`'s.
    Between {
        smaller: SizeRange,
        larger: SizeRange,
    },
    /// Below the smallest size stating the measure, by `by_cm`.
    BelowSmallest { size: SizeRange, by_cm: f32 },
    /// Above the largest size stating the measure, by `by_cm`.
    AboveLargest { size: SizeRange, by_cm: f32 },
    /// The value is not a number or not a plausible body measurement; it is not used.
    Unusable { why: String },
}

/// How the recommended size fits one measurement.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum FitAtSize {
    /// Inside the size's range.
    Fits,
    /// Above the size's range by `by_cm`.
    Tight { by_cm: f32 },
    /// Below the size's range by `by_cm`.
    Loose { by_cm: f32 },
    /// The size does not state this measure.
    NotStated,
    /// No size was recommended, or the value is unusable.
    Unknown,
}

/// One measurement against the chart.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeasureAdvice {
    pub measure: Measure,
    pub value_cm: f32,
    /// Whether this measure decides the size.
    pub primary: bool,
    pub placement: Placement,
    /// The size this measure alone asks for (see [`recommend`]); `None` if unusable.
    pub needs: Option<String>,
    /// How the recommended size fits this measurement.
    pub at_recommended: FitAtSize,
    /// E.g. `bust 96.0 cm: 48 (94-98)`.
    pub reason: String,
}

/// A size recommendation with its reasons.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Recommendation {
    /// The chart's name.
    pub chart: String,
    /// The recommended size; `None` only when no primary measurement is usable.
    pub size: Option<String>,
    /// The primary measures.
    pub primary: Vec<Measure>,
    /// The primary measures that ask for the recommended size.
    pub decided_by: Vec<Measure>,
    /// Other sizes inside whose ranges every usable primary measurement also falls.
    pub also_fits: Vec<String>,
    /// Primary measures above even the largest size: the recommended size is too small there.
    pub too_small_for: Vec<Measure>,
    /// Every measure of the chart, primary ones first.
    pub measures: Vec<MeasureAdvice>,
}

/// Recommends a size of `chart` for a body with `measurements`.
///
/// Rule: each primary measure asks for the smallest size whose range contains it (the larger
/// neighbour when it falls in a gap, the smallest size below the chart, the largest above it);
/// the recommendation is the largest size asked for, so the garment is not too small for any
/// primary measure. Measurements that are not finite or outside
/// [`Measure::plausible_range_cm`] are reported as unusable and do not decide.
pub fn recommend(chart: &SizeChart, measurements: &Measurements) -> Recommendation {
    recommend_with(chart, |m| m.of(measurements))
}

/// [`recommend`] for measurements given one by one (typed by a customer, say): `value_cm`
/// gives each measure in cm, `f32::NAN` for one that is not known.
pub fn recommend_with(chart: &SizeChart, value_cm: impl Fn(Measure) -> f32) -> Recommendation {
    struct Placed {
        measure: Measure,
        value_cm: f32,
        primary: bool,
        placement: Placement,
        needs: Option<usize>,
    }
    let range_of = |i: usize, m: Measure| -> Option<SizeRange> {
        let size = &chart.sizes[i];
        size.ranges_cm.get(&m).map(|r| SizeRange {
            label: size.label.clone(),
            min_cm: r.min_cm,
            max_cm: r.max_cm,
        })
    };
    let placed: Vec<Placed> = chart
        .measures()
        .into_iter()
        .map(|measure| {
            let value_cm = value_cm(measure);
            let primary = chart.primary.contains(&measure);
            let column: Vec<(usize, RangeCm)> = chart
                .sizes
                .iter()
                .enumerate()
                .filter_map(|(i, s)| s.ranges_cm.get(&measure).map(|r| (i, *r)))
                .collect();
            let (placement, needs) = place(measure, value_cm, &column, &range_of);
            Placed {
                measure,
                value_cm,
                primary,
                placement,
                needs,
            }
        })
        .collect();

    let recommended: Option<usize> = placed
        .iter()
        .filter(|p| p.primary)
        .filter_map(|p| p.needs)
        .max();
    let usable_primary: Vec<&Placed> = placed
        .iter()
        .filter(|p| p.primary && p.needs.is_some())
        .collect();
    let also_fits: Vec<String> = match recommended {
        None => Vec::new(),
        Some(r) => (0..chart.sizes.len())
            .filter(|&i| i != r)
            .filter(|&i| {
                usable_primary.iter().all(|p| {
                    chart.sizes[i]
                        .ranges_cm
                        .get(&p.measure)
                        .is_some_and(|range| range.contains(p.value_cm))
                })
            })
            .map(|i| chart.sizes[i].label.clone())
            .collect(),
    };
    let decided_by = usable_primary
        .iter()
        .filter(|p| p.needs == recommended)
        .map(|p| p.measure)
        .collect();
    let too_small_for = usable_primary
        .iter()
        .filter(|p| matches!(p.placement, Placement::AboveLargest { .. }))
        .map(|p| p.measure)
        .collect();

    let measures = placed
        .into_iter()
        .map(|p| {
            let at_recommended = match (recommended, &p.placement) {
                (None, _) | (_, Placement::Unusable { .. }) => FitAtSize::Unknown,
                (Some(r), _) => match chart.sizes[r].ranges_cm.get(&p.measure) {
                    None => FitAtSize::NotStated,
                    Some(range) if p.value_cm > range.max_cm => FitAtSize::Tight {
                        by_cm: p.value_cm - range.max_cm,
                    },
                    Some(range) if p.value_cm < range.min_cm => FitAtSize::Loose {
                        by_cm: range.min_cm - p.value_cm,
                    },
                    Some(_) => FitAtSize::Fits,
                },
            };
            let reason = reason_line(p.measure, p.value_cm, &p.placement);
            MeasureAdvice {
                measure: p.measure,
                value_cm: p.value_cm,
                primary: p.primary,
                placement: p.placement,
                needs: p.needs.map(|i| chart.sizes[i].label.clone()),
                at_recommended,
                reason,
            }
        })
        .collect();

    Recommendation {
        chart: chart.name.clone(),
        size: recommended.map(|i| chart.sizes[i].label.clone()),
        primary: chart.primary.clone(),
        decided_by,
        also_fits,
        too_small_for,
        measures,
    }
}

/// Places `value_cm` among the ranges `column` (size index, range; ordered) of `measure`;
/// returns the placement and the size index the value asks for.
fn place(
    measure: Measure,
    value_cm: f32,
    column: &[(usize, RangeCm)],
    range_of: &dyn Fn(usize, Measure) -> Option<SizeRange>,
) -> (Placement, Option<usize>) {
    let (lo_cm, hi_cm) = measure.plausible_range_cm();
    if !value_cm.is_finite() {
        let why = "not measured (not a number)".to_owned();
        return (Placement::Unusable { why }, None);
    }
    if !(lo_cm..=hi_cm).contains(&value_cm) {
        let why = format!(
            "outside the plausible {}-{} cm",
            compact_cm(lo_cm),
            compact_cm(hi_cm)
        );
        return (Placement::Unusable { why }, None);
    }
    let sr = |i: usize| range_of(i, measure);
    let (Some(&(first, first_range)), Some(&(last, last_range))) = (column.first(), column.last())
    else {
        let why = "no size of the chart states it".to_owned();
        return (Placement::Unusable { why }, None);
    };
    let within: Vec<usize> = column
        .iter()
        .filter(|(_, r)| r.contains(value_cm))
        .map(|&(i, _)| i)
        .collect();
    if let Some(&smallest) = within.first() {
        let sizes = within.iter().filter_map(|&i| sr(i)).collect();
        return (Placement::Within { sizes }, Some(smallest));
    }
    if value_cm < first_range.min_cm
        && let Some(size) = sr(first)
    {
        let by_cm = first_range.min_cm - value_cm;
        return (Placement::BelowSmallest { size, by_cm }, Some(first));
    }
    if value_cm > last_range.max_cm
        && let Some(size) = sr(last)
    {
        let by_cm = value_cm - last_range.max_cm;
        return (Placement::AboveLargest { size, by_cm }, Some(last));
    }
    // In a gap: ranges are ordered, so the first size starting above the value has the
    // previous one ending below it.
    if let Some(k) = column.iter().position(|(_, r)| r.min_cm > value_cm)
        && k > 0
        && let (Some(smaller), Some(larger)) = (sr(column[k - 1].0), sr(column[k].0))
    {
        return (Placement::Between { smaller, larger }, Some(column[k].0));
    }
    let why = "the chart's ranges for it are not ordered".to_owned();
    (Placement::Unusable { why }, None)
}

/// `bust 96.0 cm: 48 (94-98)`.
fn reason_line(measure: Measure, value_cm: f32, placement: &Placement) -> String {
    let where_ = match placement {
        Placement::Within { sizes } => sizes
            .iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join(" or "),
        Placement::Between { smaller, larger } => format!("between {smaller} and {larger}"),
        Placement::BelowSmallest { size, by_cm } => {
            format!("below the smallest size {size} by {by_cm:.1} cm")
        }
        Placement::AboveLargest { size, by_cm } => {
            format!("above the largest size {size} by {by_cm:.1} cm")
        }
        Placement::Unusable { why } => format!("not used, {why}"),
    };
    format!("{measure} {value_cm:.1} cm: {where_}")
}

impl fmt::Display for Recommendation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names = |ms: &[Measure]| ms.iter().map(|m| m.name()).collect::<Vec<_>>().join(", ");
        match &self.size {
            Some(size) => writeln!(f, "Recommended size: {size} (chart \"{}\")", self.chart)?,
            None => writeln!(
                f,
                "No size recommended (chart \"{}\"): none of the deciding measures ({}) is usable",
                self.chart,
                names(&self.primary)
            )?,
        }
        if self.size.is_some() {
            writeln!(
                f,
                "Decided by {}: the largest size any deciding measure ({}) needs, so the garment \
                 is not too small.",
                names(&self.decided_by),
                names(&self.primary)
            )?;
        }
        if let Some(size) = &self.size {
            for advice in &self.measures {
                let role = if advice.primary { " [decides]" } else { "" };
                let fit = match &advice.at_recommended {
                    FitAtSize::Tight { by_cm } => format!("; {size} is tight by {by_cm:.1} cm"),
                    FitAtSize::Loose { by_cm } => format!("; {size} is loose by {by_cm:.1} cm"),
                    FitAtSize::NotStated => format!("; {size} does not state it"),
                    FitAtSize::Fits | FitAtSize::Unknown => String::new(),
                };
                writeln!(f, "  {}{fit}{role}", advice.reason)?;
            }
        } else {
            for advice in &self.measures {
                writeln!(f, "  {}", advice.reason)?;
            }
        }
        if !self.also_fits.is_empty() {
            writeln!(f, "Also fits: {}", self.also_fits.join(", "))?;
        }
        if !self.too_small_for.is_empty() {
            writeln!(
                f,
                "Warning: even the largest size is too small for: {}",
                names(&self.too_small_for)
            )?;
        }
        Ok(())
    }
}

/// `94`, `62.5`, `86.25`: centimetres with at most two decimals and no trailing zeros.
fn compact_cm(value: f32) -> String {
    if !value.is_finite() {
        return value.to_string();
    }
    let s = format!("{value:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_owned()
}
