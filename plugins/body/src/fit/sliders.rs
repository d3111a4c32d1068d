//! The MakeHuman sliders a fit may move (after seed 002 §4.2, calibration by the modifiers): the
//! macros, the `measure-*` sliders and the region scale sliders, their bounds and rest values,
//! which measures each one moves, and the age slider for an age in years.

use crate::measure::Measure;
use crate::modifiers::Shape;

/// One free slider.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Param {
    /// Not moved by the fit to measurements (gender is given there); the fit to depth
    /// moves it.
    Gender,
    Height,
    Weight,
    Muscle,
    Proportions,
    Slider(&'static str),
    Region(&'static str),
}

impl Param {
    pub fn bounds(self) -> (f32, f32) {
        match self {
            Param::Slider(_) | Param::Region(_) => (-1.0, 1.0),
            _ => (0.0, 1.0),
        }
    }

    pub fn rest(self) -> f32 {
        match self {
            Param::Slider(_) | Param::Region(_) => 0.0,
            _ => 0.5,
        }
    }

    pub fn name(self) -> String {
        match self {
            Param::Gender => "gender".into(),
            Param::Height => "height".into(),
            Param::Weight => "weight".into(),
            Param::Muscle => "muscle".into(),
            Param::Proportions => "proportions".into(),
            Param::Slider(s) => format!("measures[\"{s}\"]"),
            Param::Region(s) => format!("regions[\"{s}\"]"),
        }
    }

    /// This slider's value in `shape` (its rest value where `shape` does not set it).
    pub fn get(self, shape: &Shape) -> f32 {
        match self {
            Param::Gender => shape.gender,
            Param::Height => shape.height,
            Param::Weight => shape.weight,
            Param::Muscle => shape.muscle,
            Param::Proportions => shape.proportions,
            Param::Slider(s) => shape.measures.get(s).copied().unwrap_or(0.0),
            Param::Region(s) => shape.regions.get(s).copied().unwrap_or(0.0),
        }
    }

    pub fn set(self, shape: &mut Shape, v: f32) {
        match self {
            Param::Gender => shape.gender = v,
            Param::Height => shape.height = v,
            Param::Weight => shape.weight = v,
            Param::Muscle => shape.muscle = v,
            Param::Proportions => shape.proportions = v,
            Param::Slider(s) => {
                shape.measures.insert(s.to_owned(), v);
            }
            Param::Region(s) => {
                shape.regions.insert(s.to_owned(), v);
            }
        }
    }

    /// The measures this slider moves (from a sensitivity scan of the MakeHuman targets:
    /// each slider at -1 and +1 on the default female and male bodies, effects above 0.3 cm).
    pub fn moves(self, m: Measure) -> bool {
        use Measure::*;
        match self {
            Param::Gender | Param::Height | Param::Weight | Param::Muscle | Param::Proportions => {
                true
            }
            Param::Slider(s) => match s {
                "bust-circ" | "frontchest-dist" => matches!(m, Bust | Underbust | Waist | Neck),
                "underbust-circ" => matches!(m, Bust | Underbust | Waist | NavelWaist),
                "waist-circ" => matches!(m, Bust | Underbust | Waist | NavelWaist),
                "hips-circ" => matches!(m, Hip | Thigh | NavelWaist),
                "thigh-circ" => matches!(m, Thigh),
                "calf-circ" | "knee-circ" => matches!(m, Calf),
                "neck-circ" => matches!(m, Neck),
                "neck-height" => matches!(m, Neck | Stature),
                "shoulder-dist" => matches!(m, ShoulderWidth | Bust | Neck),
                "upperleg-height" | "lowerleg-height" => matches!(m, Stature | InsideLeg),
                "napetowaist-dist" | "waisttohip-dist" => {
                    matches!(m, Stature | Neck | Bust | Underbust | Hip | NavelWaist)
                }
                "upperarm-length" | "lowerarm-length" => matches!(m, ArmLength),
                _ => false,
            },
            Param::Region(s) => match s {
                "neck-scale-depth" | "neck-scale-horiz" | "neck-back-scale-depth" => {
                    matches!(m, Neck)
                }
                "neck-scale-vert" => matches!(m, Neck | Stature),
                "torso-scale-depth" | "torso-scale-horiz" => matches!(
                    m,
                    ShoulderWidth | Neck | Bust | Underbust | Waist | NavelWaist
                ),
                "torso-scale-vert" => matches!(m, Stature | NavelWaist),
                "hip-scale-depth" | "hip-scale-horiz" => {
                    matches!(m, Underbust | Waist | NavelWaist | Hip | Thigh)
                }
                "upperleg-scale-depth" | "upperleg-scale-horiz" => matches!(m, Hip | Thigh),
                "lowerleg-scale-depth" | "lowerleg-scale-horiz" => matches!(m, Calf),
                "lowerleg-scale-vert" => matches!(m, Stature | InsideLeg),
                "upperarm-scale-horiz" | "lowerarm-scale-horiz" => matches!(m, ArmLength),
                _ => false,
            },
        }
    }
}

/// The measure sliders the fit may use.
pub const SLIDERS: [&str; 17] = [
    "bust-circ",
    "underbust-circ",
    "frontchest-dist",
    "waist-circ",
    "hips-circ",
    "thigh-circ",
    "calf-circ",
    "knee-circ",
    "neck-circ",
    "neck-height",
    "shoulder-dist",
    "upperleg-height",
    "lowerleg-height",
    "napetowaist-dist",
    "waisttohip-dist",
    "upperarm-length",
    "lowerarm-length",
];

/// The region scale sliders the fit may use (MakeHuman's `*-scale-*` targets of the neck,
/// torso, hip and limbs; the ones with an effect on a measurement).
pub const REGIONS: [&str; 15] = [
    "neck-scale-depth",
    "neck-scale-horiz",
    "neck-back-scale-depth",
    "neck-scale-vert",
    "torso-scale-depth",
    "torso-scale-horiz",
    "torso-scale-vert",
    "hip-scale-depth",
    "hip-scale-horiz",
    "upperleg-scale-depth",
    "upperleg-scale-horiz",
    "lowerleg-scale-depth",
    "lowerleg-scale-horiz",
    "upperarm-scale-horiz",
    "lowerarm-scale-horiz",
];

/// MakeHuman's age slider for an age in years (0.5 = 25, 1 = 90; linear in between, as
/// MakeHuman's `setAgeYears`).
pub fn age_slider(years: f32) -> f32 {
    if years < 25.0 {
        0.1875 + (years - 10.0) / (25.0 - 10.0) * (0.5 - 0.1875)
    } else {
        0.5 + (years - 25.0) / (90.0 - 25.0) * 0.5
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn age_slider_matches_makehuman_anchors() {
        assert!((age_slider(25.0) - 0.5).abs() < 1e-6);
        assert!((age_slider(90.0) - 1.0).abs() < 1e-6);
        assert!((age_slider(10.0) - 0.1875).abs() < 1e-6);
    }
}
