//! Anthropometric measurement of a (morphed) body mesh, after seed 002 Table 4.1 (EN 13402)
//! and ISO 8559-1.
//!
//! A girth is the perimeter of the convex hull of a plane cross-section of the mesh (seed 002
//! §4.2: the tape measure bridges concavities), restricted to the loops of the body part being
//! measured (the torso without the arms for the chest, the left leg for the thigh...). Loops
//! are assigned to body parts by the skin weights of the vertices whose edges they cross.
//! Landmarks (heights) are searched on the mesh itself, scanning cross-sections; the rig's
//! rest pose (derived from the same mesh) only bounds the search regions, and gives the elbow
//! and wrist joint centres for the arm length.
//!
//! | measure | definition here |
//! | --- | --- |
//! | stature | top of the head to the sole (body vertices' y extent) |
//! | crotch height | lowest point of the surface in the body's mid-sagittal plane (between the legs) above the floor |
//! | arm length | left acromion -> elbow joint -> wrist joint (ISO: over the elbow to the wrist) |
//! | shoulder width | biacromial breadth: distance between the two acromion points (the corner of the frontal shoulder silhouette between the shoulder slope and the arm) |
//! | neck | neck base girth: section perpendicular to the neck (neck joint to head joint) through the neck joint, which the rig derives from the mesh at the neck's base |
//! | bust / chest | largest trunk girth between 1 cm and 35% of the trunk height (armpit to crotch) below the armpits (EN 13402-1: under the armpits, across the shoulder blades and the bust points): at the bust points on a female body, just under the armpits on a flat chest |
//! | under-bust | torso girth at the fold below the breast: the deepest point of the front profile under the chord from the bust point (the highest peak of the front profile below the armpits) to the waist |
//! | waist | smallest torso girth between the hips and the under-bust |
//! | navel waist | trunk girth at the navel (omphalion; ANSUR II's waist): the deepest pit, within ±2.5 cm, of the mid-sagittal front profile between the hip and 4 cm above the natural waist |
//! | hip | girth of the trunk (arms and hands excluded) at the buttocks' greatest posterior prominence above the crotch |
//! | thigh | largest girth of the left thigh below the crotch (just below the gluteal fold) |
//! | calf | largest girth of the left lower leg between ankle and knee |
//!
//! The convex hull is a hand-written Andrew monotone chain (O(n log n)).
//!
//! # Where things are
//!
//! - `section`: plane cross-sections of a mesh ([`cross_section`], [`SectionLoop`], [`Plane`])
//!   and the [`HeightIndex`] that makes horizontal ones fast.
//! - `hull`: the tape measure, [`convex_hull`] and [`hull_perimeter`].
//! - `landmarks`: the landmark search and the full measurement, [`BodyModel::measure`] and
//!   [`BodyModel::measure_with_probe`].
//! - `probe`: [`MeasureProbe`], the fast re-measurement at known landmarks.
//!
//! [`BodyModel::measure`]: crate::BodyModel::measure
//! [`BodyModel::measure_with_probe`]: crate::BodyModel::measure_with_probe

mod hull;
mod landmarks;
mod probe;
mod section;

pub use hull::{convex_hull, hull_perimeter};
pub use probe::MeasureProbe;
pub use section::{HeightIndex, Plane, SectionLoop, cross_section, cross_section_of};

use serde::Serialize;

/// Body measurements (centimetres), after seed 002 Table 4.1 / ISO 8559-1; see the
/// [module docs](self) for the definitions.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Measurements {
    pub stature_cm: f32,
    pub crotch_height_cm: f32,
    pub arm_length_cm: f32,
    pub shoulder_width_cm: f32,
    pub neck_cm: f32,
    pub bust_cm: f32,
    pub underbust_cm: f32,
    pub waist_cm: f32,
    pub navel_waist_cm: f32,
    pub hip_cm: f32,
    pub thigh_cm: f32,
    pub calf_cm: f32,
    pub landmarks: Landmarks,
}

/// The name of one measurement of [`Measurements`], as used on the command line, in shape
/// fits and in size charts (`stature`, `inside-leg`, `bust`...).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Measure {
    Stature,
    /// Crotch height.
    InsideLeg,
    ArmLength,
    /// Biacromial breadth.
    ShoulderWidth,
    /// Neck base girth.
    Neck,
    /// Chest (male) or bust (female) girth.
    Bust,
    Underbust,
    /// Natural waist (EN 13402): the narrowest trunk girth.
    Waist,
    /// Waist at the navel (omphalion), as ANSUR II measures it.
    NavelWaist,
    Hip,
    Thigh,
    Calf,
}

impl Measure {
    pub const ALL: [Measure; 12] = [
        Measure::Stature,
        Measure::InsideLeg,
        Measure::ArmLength,
        Measure::ShoulderWidth,
        Measure::Neck,
        Measure::Bust,
        Measure::Underbust,
        Measure::Waist,
        Measure::NavelWaist,
        Measure::Hip,
        Measure::Thigh,
        Measure::Calf,
    ];

    /// The kebab-case name (`inside-leg`).
    pub fn name(self) -> &'static str {
        match self {
            Measure::Stature => "stature",
            Measure::InsideLeg => "inside-leg",
            Measure::ArmLength => "arm-length",
            Measure::ShoulderWidth => "shoulder-width",
            Measure::Neck => "neck",
            Measure::Bust => "bust",
            Measure::Underbust => "underbust",
            Measure::Waist => "waist",
            Measure::NavelWaist => "navel-waist",
            Measure::Hip => "hip",
            Measure::Thigh => "thigh",
            Measure::Calf => "calf",
        }
    }

    /// The measure named `name` (kebab-case; `chest` is accepted for `bust`, `crotch-height`
    /// for `inside-leg`, `hips` for `hip`).
    pub fn from_name(name: &str) -> Option<Measure> {
        let n = name.trim().to_ascii_lowercase().replace('_', "-");
        match n.as_str() {
            "chest" => return Some(Measure::Bust),
            "crotch-height" => return Some(Measure::InsideLeg),
            "hips" => return Some(Measure::Hip),
            "under-bust" => return Some(Measure::Underbust),
            "omphalion-waist" => return Some(Measure::NavelWaist),
            _ => {}
        }
        Measure::ALL.into_iter().find(|m| m.name() == n)
    }

    /// All names, comma-separated, for error messages.
    pub fn names() -> String {
        Measure::ALL.map(Measure::name).join(", ")
    }

    /// This measurement of `m`, cm.
    pub fn of(self, m: &Measurements) -> f32 {
        match self {
            Measure::Stature => m.stature_cm,
            Measure::InsideLeg => m.crotch_height_cm,
            Measure::ArmLength => m.arm_length_cm,
            Measure::ShoulderWidth => m.shoulder_width_cm,
            Measure::Neck => m.neck_cm,
            Measure::Bust => m.bust_cm,
            Measure::Underbust => m.underbust_cm,
            Measure::Waist => m.waist_cm,
            Measure::NavelWaist => m.navel_waist_cm,
            Measure::Hip => m.hip_cm,
            Measure::Thigh => m.thigh_cm,
            Measure::Calf => m.calf_cm,
        }
    }

    /// Values an adult human body can have, cm: wider than the 0.1st-99.9th percentiles of the
    /// ANSUR II survey (6,068 US Army adults), so a value outside is a typing error (a 3 m
    /// waist, a girth in mm), not a rare body.
    pub fn plausible_range_cm(self) -> (f32, f32) {
        match self {
            Measure::Stature => (120.0, 230.0),
            Measure::InsideLeg => (50.0, 110.0),
            Measure::ArmLength => (40.0, 90.0),
            Measure::ShoulderWidth => (25.0, 55.0),
            Measure::Neck => (25.0, 60.0),
            Measure::Bust => (60.0, 160.0),
            Measure::Underbust => (55.0, 150.0),
            Measure::Waist | Measure::NavelWaist => (45.0, 170.0),
            Measure::Hip => (65.0, 170.0),
            Measure::Thigh => (35.0, 95.0),
            Measure::Calf => (22.0, 60.0),
        }
    }
}

impl std::fmt::Display for Measure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Measure {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Measure::from_name(s)
            .ok_or_else(|| format!("unknown measurement `{s}`; known: {}", Measure::names()))
    }
}

/// Where the measurements were taken: heights above the sole (the lowest body vertex), cm.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Landmarks {
    pub crotch_cm: f32,
    pub axilla_cm: f32,
    pub bust_cm: f32,
    /// The most anterior point of the chest (the bust point on a female body).
    pub bust_point_cm: f32,
    pub underbust_cm: f32,
    pub waist_cm: f32,
    /// The navel (omphalion).
    pub navel_cm: f32,
    pub hip_cm: f32,
    pub thigh_cm: f32,
    pub calf_cm: f32,
    /// Neck base: height of the centre of the neck base section.
    pub neck_base_cm: f32,
    /// Left and right acromion points.
    pub acromion_left_cm: f32,
    pub acromion_right_cm: f32,
    pub elbow_cm: f32,
    pub wrist_cm: f32,
}

/// Why a body cannot be measured.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeasureError {
    #[error("the rig has no bone `{0}`, which measurement uses to bound its search regions")]
    MissingBone(&'static str),
    #[error("positions has {got} vertices, the model {expected}")]
    VertexCount { got: usize, expected: usize },
    #[error("could not find the {0} on the mesh")]
    LandmarkNotFound(&'static str),
}

/// Body part of a vertex, from its dominant skin bone.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    Torso,
    Head,
    Arm,
    Leg,
}

const CM: f32 = 100.0;
