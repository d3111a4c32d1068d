//! The size recommendation: each measurement of a body placed in the chart's ranges (EN 13402 body
//! dimensions, seed 002 §4.1), the largest size any primary measure needs, and how that size fits
//! every measure, with a reason line each; the rule is in the [module docs](super).

use std::fmt;

use serde::Serialize;

use super::{RangeCm, SizeChart, compact_cm};
use crate::measure::{Measure, Measurements};

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
