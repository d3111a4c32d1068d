//! The size chart file as written (RON) and its validation into a [`SizeChart`]: sizes after
//! EN 13402 (seed 002 §4.1, Tables 4.2 and 4.3), each measure given as a range or a nominal value
//! from which the range is derived; the format is in the [module docs](super).

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::Path;

use serde::Deserialize;

use super::{ChartProblem, Gender, RangeCm, Size, SizeChart, SizeChartError, compact_cm};
use crate::measure::Measure;

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
    /// Reads and validates a chart file (RON; format in the [module docs](super)).
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

    /// A chart from one nominal body measurement per size and measure (a garment's own size
    /// table), validated and ranged as a chart file's `nominal_cm` sizes are; `primary`
    /// empty: every measure decides.
    pub fn from_nominal(
        name: &str,
        gender: Gender,
        primary: &[Measure],
        sizes: &[(String, BTreeMap<Measure, f32>)],
    ) -> Result<SizeChart, ChartProblem> {
        Self::from_file(ChartFile {
            name: name.to_owned(),
            source: String::new(),
            notes: String::new(),
            gender,
            primary: primary.iter().map(|m| m.name().to_owned()).collect(),
            sizes: sizes
                .iter()
                .map(|(label, values)| SizeFile {
                    label: label.clone(),
                    nominal_cm: Entries(
                        values
                            .iter()
                            .map(|(m, v)| (m.name().to_owned(), *v))
                            .collect(),
                    ),
                    ranges_cm: Entries::default(),
                })
                .collect(),
        })
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
/// neighbouring distinct values (see the [module docs](super)).
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
