//! The sixteen anthropometric segments of the body (after seed 002 (Uğur 2008, parametric bodies
//! for virtual dressing), §4.3: one measurement area per girth or length of Table 4.1), their
//! names, and the girth of the body measurement that belongs to each.

use serde::{Deserialize, Serialize};

use crate::measure::Measurements;

/// An anthropometric segment of the body (seed §4.3: one measurement area per girth or length
/// of Table 4.1). See the [module docs](super) for how their cores are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BodySegment {
    /// Head and neck (neck girth).
    HeadNeck,
    /// Torso above the waist band, shoulders included (bust and under-bust girths).
    Chest,
    /// Torso band centred on the waist girth.
    Waist,
    /// Torso band below the middle of the waist and hip heights, down to the crotch (hip girth).
    Hip,
    UpperArmLeft,
    UpperArmRight,
    ForearmLeft,
    ForearmRight,
    HandLeft,
    HandRight,
    ThighLeft,
    ThighRight,
    /// Lower leg, knee to ankle.
    ShankLeft,
    ShankRight,
    FootLeft,
    FootRight,
}

impl BodySegment {
    pub const ALL: [BodySegment; 16] = [
        BodySegment::HeadNeck,
        BodySegment::Chest,
        BodySegment::Waist,
        BodySegment::Hip,
        BodySegment::UpperArmLeft,
        BodySegment::UpperArmRight,
        BodySegment::ForearmLeft,
        BodySegment::ForearmRight,
        BodySegment::HandLeft,
        BodySegment::HandRight,
        BodySegment::ThighLeft,
        BodySegment::ThighRight,
        BodySegment::ShankLeft,
        BodySegment::ShankRight,
        BodySegment::FootLeft,
        BodySegment::FootRight,
    ];

    /// Position in [`BodySegment::ALL`] (the area index in the body's [`AreaBlend`]).
    ///
    /// [`AreaBlend`]: super::AreaBlend
    pub fn index(self) -> usize {
        self as usize
    }

    /// The kebab-case name (`upper-arm-left`).
    pub fn name(self) -> &'static str {
        match self {
            BodySegment::HeadNeck => "head-neck",
            BodySegment::Chest => "chest",
            BodySegment::Waist => "waist",
            BodySegment::Hip => "hip",
            BodySegment::UpperArmLeft => "upper-arm-left",
            BodySegment::UpperArmRight => "upper-arm-right",
            BodySegment::ForearmLeft => "forearm-left",
            BodySegment::ForearmRight => "forearm-right",
            BodySegment::HandLeft => "hand-left",
            BodySegment::HandRight => "hand-right",
            BodySegment::ThighLeft => "thigh-left",
            BodySegment::ThighRight => "thigh-right",
            BodySegment::ShankLeft => "shank-left",
            BodySegment::ShankRight => "shank-right",
            BodySegment::FootLeft => "foot-left",
            BodySegment::FootRight => "foot-right",
        }
    }

    /// The segment named `name` (kebab-case, as [`BodySegment::name`]).
    pub fn from_name(name: &str) -> Option<BodySegment> {
        let n = name.trim().to_ascii_lowercase().replace('_', "-");
        BodySegment::ALL.into_iter().find(|s| s.name() == n)
    }

    pub(super) fn is_torso_band(self) -> bool {
        matches!(
            self,
            BodySegment::HeadNeck | BodySegment::Chest | BodySegment::Waist | BodySegment::Hip
        )
    }

    /// Which girth of [`BodyModel::measure`] belongs to this segment, if any.
    ///
    /// [`BodyModel::measure`]: crate::BodyModel::measure
    pub(super) fn girth(self) -> Option<fn(&Measurements) -> f32> {
        match self {
            BodySegment::HeadNeck => Some(|m| m.neck_cm),
            BodySegment::Chest => Some(|m| m.bust_cm),
            BodySegment::Waist => Some(|m| m.waist_cm),
            BodySegment::Hip => Some(|m| m.hip_cm),
            BodySegment::ThighLeft => Some(|m| m.thigh_cm),
            BodySegment::ShankLeft => Some(|m| m.calf_cm),
            _ => None,
        }
    }
}

impl std::fmt::Display for BodySegment {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for BodySegment {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        BodySegment::from_name(s).ok_or_else(|| {
            let known: Vec<&str> = BodySegment::ALL.iter().map(|s| s.name()).collect();
            format!("unknown body segment `{s}`; known: {}", known.join(", "))
        })
    }
}
