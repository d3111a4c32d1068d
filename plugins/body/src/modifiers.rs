//! MakeHuman's modifiers: the macro sliders (gender, age, muscle, weight, height, proportions,
//! ethnicity) and the `measure-*` sliders, turned into morph target weights exactly as
//! MakeHuman 1.1 (`apps/human.py`, `apps/humanmodifier.py`) computes them.
//!
//! # Macro rules
//!
//! Each slider value becomes a set of named factors:
//!
//! | slider | factors |
//! | --- | --- |
//! | gender g | `female` = 1 - g, `male` = g |
//! | age a < 0.5 | `baby` = max(0, 1 - 5.333a), `young` = max(0, (a - 0.1875) * 3.2), `child` = max(0, min(1, 5.333a) - young), `old` = 0 |
//! | age a >= 0.5 | `old` = 2a - 1, `young` = 1 - old, `baby` = `child` = 0 |
//! | muscle m | `maxmuscle` = max(0, 2m - 1), `minmuscle` = max(0, 1 - 2m), `averagemuscle` = 1 - (max + min) |
//! | weight w | `maxweight`, `minweight`, `averageweight` the same way |
//! | height h | `maxheight` = max(0, 2h - 1), `minheight` = max(0, 1 - 2h) (the average height has no target) |
//! | proportions p | `idealproportions` = max(0, 2p - 1), `uncommonproportions` = max(0, 1 - 2p) (regular proportions have no target) |
//! | ethnicity | `african`, `asian`, `caucasian`: the three values divided by their sum |
//!
//! Age 0 is 1 year, 0.1875 is 10, 0.5 is 25 and 1 is 90 years.
//!
//! A macro target's weight is the product of the factors named in its file name:
//!
//! - `macrodetails/{race}-{gender}-{age}` (race x gender x age),
//! - `macrodetails/universal-{gender}-{age}-{muscle}-{weight}`,
//! - `macrodetails/height/{gender}-{age}-{muscle}-{weight}-{height}`,
//! - `macrodetails/proportions/{gender}-{age}-{muscle}-{weight}-{proportions}` (MakeHuman ships
//!   no `baby` proportions targets, so a baby's share of the proportions modifier is dropped,
//!   as in MakeHuman).
//!
//! Only targets with a non-zero weight are returned. The `universal-*-young-averagemuscle-
//! averageweight` targets are empty: the base mesh is that body.
//!
//! # Measure rules
//!
//! A measure slider `name` (e.g. `waist-circ`) with value v in -1..=1 drives the pair of
//! targets `*/measure-{name}-decr` with weight -min(v, 0) and `*/measure-{name}-incr` with
//! weight max(v, 0).
//!
//! # Region scale rules
//!
//! A region scale slider (`neck-scale-horiz`, `torso-scale-depth`, `hip-scale-horiz`,
//! `upperleg-scale-horiz`...) drives the `*-scale-*-decr|incr` targets of that region the same
//! way; a limb's slider drives the left (`l-`) and right (`r-`) targets alike, as MakeHuman
//! does with symmetry on.

use std::collections::{BTreeMap, BTreeSet, HashMap};

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::model::{BodyModel, RestPose};

/// A body shape: MakeHuman's macro sliders and measure sliders. RON-friendly: every field has
/// a default (MakeHuman's), so a file names only what it changes, e.g.
/// `(gender: 1.0, weight: 0.7, measures: {"waist-circ": -0.3})`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Shape {
    /// 0 = female, 1 = male.
    pub gender: f32,
    /// 0 = 1 year, 0.1875 = 10, 0.5 = 25, 1 = 90 years.
    pub age: f32,
    /// 0..=1, 0.5 average.
    pub muscle: f32,
    /// 0..=1, 0.5 average.
    pub weight: f32,
    /// 0..=1, 0.5 average.
    pub height: f32,
    /// 0 = uncommon, 0.5 = regular, 1 = ideal proportions.
    pub proportions: f32,
    /// Ethnic mix, each 0..=1; normalised to sum 1 (at least one must be positive).
    pub african: f32,
    pub asian: f32,
    pub caucasian: f32,
    /// Measure sliders by name (`waist-circ`, `bust-circ`, `upperarm-length`...), each -1..=1;
    /// see [`Shape::measure_names`].
    pub measures: BTreeMap<String, f32>,
    /// Region scale sliders by name (`neck-scale-horiz`, `torso-scale-depth`,
    /// `upperleg-scale-horiz` for both legs...), each -1..=1; see [`Shape::region_names`].
    pub regions: BTreeMap<String, f32>,
}

impl Default for Shape {
    /// MakeHuman's default human: every macro slider at 0.5, ethnicity 1/3 each.
    fn default() -> Self {
        Self {
            gender: 0.5,
            age: 0.5,
            muscle: 0.5,
            weight: 0.5,
            height: 0.5,
            proportions: 0.5,
            african: 1.0 / 3.0,
            asian: 1.0 / 3.0,
            caucasian: 1.0 / 3.0,
            measures: BTreeMap::new(),
            regions: BTreeMap::new(),
        }
    }
}

/// Why a [`Shape`] cannot be applied.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ShapeError {
    #[error("shape field `{field}` is {value}, outside the accepted range {min}..={max}")]
    OutOfRange {
        field: String,
        value: f32,
        min: f32,
        max: f32,
    },
    #[error("shape field `{field}` is {value}, not a number; the accepted range is {min}..={max}")]
    NotFinite {
        field: String,
        value: f32,
        min: f32,
        max: f32,
    },
    #[error(
        "shape fields `african`, `asian`, `caucasian` are all 0; at least one must be positive \
         (each in 0..=1, normalised to sum 1)"
    )]
    NoEthnicity,
    #[error("unknown measure modifier `{name}` in shape field `measures`; known: {known}")]
    UnknownModifier { name: String, known: String },
    #[error("unknown region scale modifier `{name}` in shape field `regions`; known: {known}")]
    UnknownRegion { name: String, known: String },
    #[error("the body model has no morph target `{0}`, which this shape needs")]
    MissingTarget(String),
}

/// A body morphed to a [`Shape`]: everything needed to draw and pose it.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapedBody {
    /// `(target index, weight)` pairs applied.
    pub weights: Vec<(usize, f32)>,
    /// All vertices (body and helpers), metres.
    pub positions: Vec<Vec3>,
    /// Normals of the body vertices.
    pub normals: Vec<Vec3>,
    /// The skeleton's rest pose derived from the morphed mesh.
    pub rest_pose: RestPose,
}

/// The factors of a slider with a min/average/max target set.
fn min_avg_max(v: f32) -> [(&'static str, f32); 3] {
    let max = (2.0 * v - 1.0).max(0.0);
    let min = (1.0 - 2.0 * v).max(0.0);
    [("min", min), ("average", 1.0 - (max + min)), ("max", max)]
}

/// MakeHuman's age factors (`_setAgeVals`).
fn age_factors(a: f32) -> [(&'static str, f32); 4] {
    if a < 0.5 {
        let young = ((a - 0.1875) * 3.2).max(0.0);
        let baby = (1.0 - 5.333 * a).max(0.0);
        let child = ((5.333 * a).min(1.0) - young).max(0.0);
        [
            ("baby", baby),
            ("child", child),
            ("young", young),
            ("old", 0.0),
        ]
    } else {
        let old = 2.0 * a - 1.0;
        [
            ("baby", 0.0),
            ("child", 0.0),
            ("young", 1.0 - old),
            ("old", old),
        ]
    }
}

fn check(field: &str, value: f32, min: f32, max: f32) -> Result<(), ShapeError> {
    if !value.is_finite() {
        return Err(ShapeError::NotFinite {
            field: field.to_owned(),
            value,
            min,
            max,
        });
    }
    if !(min..=max).contains(&value) {
        return Err(ShapeError::OutOfRange {
            field: field.to_owned(),
            value,
            min,
            max,
        });
    }
    Ok(())
}

/// Parses a target name into its slider's name and direction (`true` for `-incr`).
type SliderTargets = fn(&str) -> Option<(&str, bool)>;

/// The target name's region scale slider and direction: `legs/l-upperleg-scale-horiz-incr` ->
/// (`upperleg-scale-horiz`, true); left and right targets share one (symmetric) slider.
fn region_target(name: &str) -> Option<(&str, bool)> {
    let file = name.rsplit('/').next()?;
    if !file.contains("-scale-") {
        return None;
    }
    let file = file
        .strip_prefix("l-")
        .or_else(|| file.strip_prefix("r-"))
        .unwrap_or(file);
    if let Some(s) = file.strip_suffix("-incr") {
        Some((s, true))
    } else {
        file.strip_suffix("-decr").map(|s| (s, false))
    }
}

/// The target name's measure slider and direction: `torso/measure-waist-circ-incr` ->
/// (`waist-circ`, true).
fn measure_target(name: &str) -> Option<(&str, bool)> {
    let file = name.rsplit('/').next()?;
    let rest = file.strip_prefix("measure-")?;
    if let Some(s) = rest.strip_suffix("-incr") {
        Some((s, true))
    } else {
        rest.strip_suffix("-decr").map(|s| (s, false))
    }
}

impl Shape {
    /// Checks every field: NaN, infinities and out-of-range values are errors naming the field
    /// and its range. Measure names are checked by [`Shape::target_weights`] (they depend on
    /// the model).
    pub fn validate(&self) -> Result<(), ShapeError> {
        for (field, v) in [
            ("gender", self.gender),
            ("age", self.age),
            ("muscle", self.muscle),
            ("weight", self.weight),
            ("height", self.height),
            ("proportions", self.proportions),
            ("african", self.african),
            ("asian", self.asian),
            ("caucasian", self.caucasian),
        ] {
            check(field, v, 0.0, 1.0)?;
        }
        if self.african + self.asian + self.caucasian <= 0.0 {
            return Err(ShapeError::NoEthnicity);
        }
        for (name, &v) in &self.measures {
            check(&format!("measures[\"{name}\"]"), v, -1.0, 1.0)?;
        }
        for (name, &v) in &self.regions {
            check(&format!("regions[\"{name}\"]"), v, -1.0, 1.0)?;
        }
        Ok(())
    }

    /// The names of the measure sliders a model offers (sorted): those with both a
    /// `measure-{name}-decr` and a `measure-{name}-incr` target.
    pub fn measure_names(model: &BodyModel) -> Vec<String> {
        let mut incr = Vec::new();
        let mut decr = Vec::new();
        for t in &model.targets {
            match measure_target(&t.name) {
                Some((n, true)) => incr.push(n),
                Some((n, false)) => decr.push(n),
                None => {}
            }
        }
        let mut names: Vec<String> = incr
            .into_iter()
            .filter(|n| decr.contains(n))
            .map(str::to_owned)
            .collect();
        names.sort();
        names.dedup();
        names
    }

    /// The names of the region scale sliders a model offers (sorted).
    pub fn region_names(model: &BodyModel) -> Vec<String> {
        let mut names: Vec<String> = model
            .targets
            .iter()
            .filter_map(|t| region_target(&t.name).map(|(n, _)| n.to_owned()))
            .collect();
        names.sort();
        names.dedup();
        names
    }

    /// The `(target index, weight)` pairs of this shape on `model` (non-zero weights only), by
    /// the rules in the [module docs](self).
    pub fn target_weights(&self, model: &BodyModel) -> Result<Vec<(usize, f32)>, ShapeError> {
        self.validate()?;
        let mut out = Vec::with_capacity(64);
        // Name lookups through a map: a linear search per target costs more than the morph.
        let macros: HashMap<&str, usize> = model
            .targets
            .iter()
            .enumerate()
            .filter(|(_, t)| t.name.starts_with("macrodetails/"))
            .map(|(i, t)| (t.name.as_str(), i))
            .collect();
        let mut push = |name: &str, w: f32| -> Result<(), ShapeError> {
            if w == 0.0 {
                return Ok(());
            }
            let index = *macros
                .get(name)
                .ok_or_else(|| ShapeError::MissingTarget(name.to_owned()))?;
            out.push((index, w));
            Ok(())
        };

        let gender = [("female", 1.0 - self.gender), ("male", self.gender)];
        let age = age_factors(self.age);
        let muscle = min_avg_max(self.muscle);
        let weight = min_avg_max(self.weight);
        let height = [
            ("minheight", (1.0 - 2.0 * self.height).max(0.0)),
            ("maxheight", (2.0 * self.height - 1.0).max(0.0)),
        ];
        let proportions = [
            (
                "uncommonproportions",
                (1.0 - 2.0 * self.proportions).max(0.0),
            ),
            ("idealproportions", (2.0 * self.proportions - 1.0).max(0.0)),
        ];
        let sum = self.african + self.asian + self.caucasian;
        let race = [
            ("african", self.african / sum),
            ("asian", self.asian / sum),
            ("caucasian", self.caucasian / sum),
        ];

        for (g, gw) in gender {
            for (a, aw) in age {
                let ga = gw * aw;
                if ga == 0.0 {
                    continue;
                }
                for (r, rw) in race {
                    push(&format!("macrodetails/{r}-{g}-{a}"), rw * ga)?;
                }
                for (m, mw) in muscle {
                    for (w, ww) in weight {
                        let gamw = ga * mw * ww;
                        if gamw == 0.0 {
                            continue;
                        }
                        let stem = format!("{g}-{a}-{m}muscle-{w}weight");
                        push(&format!("macrodetails/universal-{stem}"), gamw)?;
                        for (h, hw) in height {
                            push(&format!("macrodetails/height/{stem}-{h}"), gamw * hw)?;
                        }
                        if a != "baby" {
                            for (p, pw) in proportions {
                                push(&format!("macrodetails/proportions/{stem}-{p}"), gamw * pw)?;
                            }
                        }
                    }
                }
            }
        }

        // Measure and region sliders: a decr/incr target pair per name.
        let sliders: [(&BTreeMap<String, f32>, SliderTargets, bool); 2] = [
            (&self.measures, measure_target, false),
            (&self.regions, region_target, true),
        ];
        for (values, targets_of, is_region) in sliders {
            if values.is_empty() {
                continue;
            }
            // One pass over the targets (a pass per slider parsed every target's name 37
            // times per morph: a tenth of the measurement's time went to it).
            let mut found = BTreeSet::new();
            for (i, t) in model.targets.iter().enumerate() {
                let Some((n, incr)) = targets_of(&t.name) else {
                    continue;
                };
                let Some((name, &v)) = values.get_key_value(n) else {
                    continue;
                };
                found.insert(name.as_str());
                let w = if incr { v.max(0.0) } else { -v.min(0.0) };
                if w != 0.0 {
                    out.push((i, w));
                }
            }
            if let Some(name) = values.keys().find(|k| !found.contains(k.as_str())) {
                return Err(if is_region {
                    ShapeError::UnknownRegion {
                        name: name.clone(),
                        known: Self::region_names(model).join(", "),
                    }
                } else {
                    ShapeError::UnknownModifier {
                        name: name.clone(),
                        known: Self::measure_names(model).join(", "),
                    }
                });
            }
        }
        Ok(out)
    }
}

impl BodyModel {
    /// The body morphed to `shape`: positions, normals and the rest pose derived from the
    /// morphed mesh.
    pub fn shaped(&self, shape: &Shape) -> Result<ShapedBody, ShapeError> {
        let weights = shape.target_weights(self)?;
        let positions = self.apply_targets(&weights);
        let normals = self.body_normals(&positions);
        let rest_pose = self.rest_pose(&positions);
        Ok(ShapedBody {
            weights,
            positions,
            normals,
            rest_pose,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn age_factors_sum_to_one() {
        for i in 0..=100 {
            let a = i as f32 / 100.0;
            let s: f32 = age_factors(a).iter().map(|f| f.1).sum();
            assert!((s - 1.0).abs() < 2e-3, "age {a}: {s}");
        }
        assert_eq!(age_factors(0.5)[2].1, 1.0);
        assert_eq!(age_factors(1.0)[3].1, 1.0);
        assert!((age_factors(0.1875)[1].1 - 1.0).abs() < 1e-3);
    }

    #[test]
    fn min_avg_max_factors() {
        assert_eq!(
            min_avg_max(0.5),
            [("min", 0.0), ("average", 1.0), ("max", 0.0)]
        );
        assert_eq!(
            min_avg_max(0.0),
            [("min", 1.0), ("average", 0.0), ("max", 0.0)]
        );
        assert_eq!(
            min_avg_max(0.75),
            [("min", 0.0), ("average", 0.5), ("max", 0.5)]
        );
    }

    #[test]
    fn measure_target_names() {
        assert_eq!(
            measure_target("torso/measure-waist-circ-incr"),
            Some(("waist-circ", true))
        );
        assert_eq!(
            measure_target("arms/measure-upperarm-length-decr"),
            Some(("upperarm-length", false))
        );
        assert_eq!(measure_target("macrodetails/african-male-old"), None);
    }
}
