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
//!
//! # Where things are
//!
//! - this module: the chart's types ([`SizeChart`], [`Size`], [`RangeCm`]) and its errors;
//! - `chart_file`: reading and validating the RON file ([`SizeChart::load`]);
//! - `recommendation`: [`recommend`] and the [`Recommendation`] with its reasons.

mod chart_file;
mod recommendation;

pub use recommendation::{
    FitAtSize, MeasureAdvice, Placement, Recommendation, SizeRange, recommend, recommend_with,
};

use std::collections::BTreeMap;
use std::fmt;
use std::path::PathBuf;

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

impl SizeChart {
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
}

/// `94`, `62.5`, `86.25`: centimetres with at most two decimals and no trailing zeros.
fn compact_cm(value: f32) -> String {
    if !value.is_finite() {
        return value.to_string();
    }
    let s = format!("{value:.2}");
    s.trim_end_matches('0').trim_end_matches('.').to_owned()
}
