//! Fabrics as data files: physical parameters in SI units with their sources, read into
//! [`fitroom_cloth::Fabric`].
//!
//! # The fabric file (RON)
//!
//! ```text
//! Fabric(
//!     name: "cotton poplin",
//!     description: "a light woven shirting cotton",   // optional
//!     areal_density_kg_m2: 0.12,      // mass per area, kg/m² (= g/m² / 1000)
//!     stretch_stiffness_n_m: 12000,   // in-plane tensile stiffness, N/m
//!     shear_stiffness_n_m: 56,        // in-plane shear stiffness, N/m
//!     bend_stiffness_n_m: 7.8e-6,     // bending rigidity per width, N·m (= N·m²/m)
//!     damping_per_s: 0.3,             // velocity decay rate, 1/s
//!     friction: 0.4,                  // Coulomb coefficient against the body
//!     drag_coefficient: 1.0,          // aerodynamic drag of a triangle facing the flow
//!     lift_coefficient: 0.3,          // aerodynamic lift
//!     sources: ["where each number comes from", ...],   // optional, free text
//! )
//! ```
//!
//! Every number is checked while it is read against the range in [`FIELD_RANGES`], so an error
//! names the file, the line and column, the field, the value and the accepted range (a density
//! typed in g/m² instead of kg/m² is caught).
//!
//! # Unit conversions used in the shipped files
//!
//! - Kawabata KES-FB2 bending rigidity `B` is given in gf·cm²/cm: 1 gf·cm²/cm = 9.80665e-3 N ×
//!   1e-4 m² / 1e-2 m = **9.807e-5 N·m**.
//! - KES-FB1 shear stiffness `G` is given in gf/(cm·degree): 1 gf/(cm·°) = 0.980665 N/m per
//!   degree = **56.19 N/m** per radian.
//! - KES-FB1 tensile: `EMT` is the strain (%) at 500 gf/cm = 490.3 N/m, so the secant tensile
//!   stiffness up to that load is **490.3 N/m / EMT**.
//! - Fabric weight: 1 oz/yd² = 33.906 g/m²; silk weight in momme: 1 mm = 4.306 g/m².

use std::path::Path;

use serde::{Deserialize, Deserializer};

use crate::error::{GarmentError, read_text, ron_error, ron_options};

/// Accepted range of each numeric field: (field, min, max, unit). Wide enough for any real
/// garment fabric, narrow enough to catch a unit mistake.
pub const FIELD_RANGES: [(&str, f32, f32, &str); 8] = [
    ("areal_density_kg_m2", 0.01, 3.0, "kg/m²"),
    ("stretch_stiffness_n_m", 10.0, 1.0e6, "N/m"),
    ("shear_stiffness_n_m", 0.1, 1.0e5, "N/m"),
    ("bend_stiffness_n_m", 1.0e-9, 1.0e-2, "N·m"),
    ("damping_per_s", 0.0, 50.0, "1/s"),
    ("friction", 0.0, 2.0, ""),
    ("drag_coefficient", 0.0, 5.0, ""),
    ("lift_coefficient", 0.0, 5.0, ""),
];

/// A fabric as read from its file: the physical parameters and where they come from.
#[derive(Debug, Clone, PartialEq)]
pub struct FabricSpec {
    pub name: String,
    pub description: String,
    /// The parameters, validated.
    pub fabric: fitroom_cloth::Fabric,
    /// Where the numbers come from (free text, one entry per source).
    pub sources: Vec<String>,
}

macro_rules! checked_fields {
    ($($fn_name:ident => $index:expr),* $(,)?) => {
        $(
            fn $fn_name<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
                checked(d, $index)
            }
        )*
    };
}

checked_fields! {
    density => 0,
    stretch => 1,
    shear => 2,
    bend => 3,
    damping => 4,
    friction => 5,
    drag => 6,
    lift => 7,
}

/// Reads an `f32` and checks it against `FIELD_RANGES[index]`; the error is raised while
/// parsing, so RON's span gives its line.
fn checked<'de, D: Deserializer<'de>>(d: D, index: usize) -> Result<f32, D::Error> {
    let (field, min, max, unit) = FIELD_RANGES[index];
    let value = f32::deserialize(d)?;
    if value.is_finite() && (min..=max).contains(&value) {
        Ok(value)
    } else {
        Err(serde::de::Error::custom(format!(
            "`{field}` is {value} {unit}, outside the accepted range {min:e}..={max:e} {unit}"
        )))
    }
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Fabric", deny_unknown_fields)]
struct FabricFile {
    name: String,
    #[serde(default)]
    description: String,
    #[serde(deserialize_with = "density")]
    areal_density_kg_m2: f32,
    #[serde(deserialize_with = "stretch")]
    stretch_stiffness_n_m: f32,
    #[serde(deserialize_with = "shear")]
    shear_stiffness_n_m: f32,
    #[serde(deserialize_with = "bend")]
    bend_stiffness_n_m: f32,
    #[serde(deserialize_with = "damping")]
    damping_per_s: f32,
    #[serde(deserialize_with = "friction")]
    friction: f32,
    #[serde(deserialize_with = "drag")]
    drag_coefficient: f32,
    #[serde(deserialize_with = "lift")]
    lift_coefficient: f32,
    #[serde(default)]
    sources: Vec<String>,
}

impl FabricSpec {
    /// Reads and validates a fabric file (format in the [module docs](self)).
    pub fn load(path: impl AsRef<Path>) -> Result<FabricSpec, GarmentError> {
        let path = path.as_ref();
        let text = read_text(path)?;
        Self::from_ron_str(&text, &path.display().to_string())
    }

    /// Parses and validates a fabric from RON text; `file` names it in errors.
    pub fn from_ron_str(text: &str, file: &str) -> Result<FabricSpec, GarmentError> {
        let raw: FabricFile = ron_options()
            .from_str(text)
            .map_err(|e| ron_error(file, text, e))?;
        if raw.name.trim().is_empty() {
            return Err(GarmentError::Invalid {
                file: file.to_owned(),
                line: crate::error::line_of(text, &["name"]),
                field: "name".into(),
                problem: "is empty; give the fabric a name".into(),
            });
        }
        let fabric = fitroom_cloth::Fabric {
            areal_density_kg_m2: raw.areal_density_kg_m2,
            stretch_stiffness_n_m: raw.stretch_stiffness_n_m,
            shear_stiffness_n_m: raw.shear_stiffness_n_m,
            bend_stiffness_n_m: raw.bend_stiffness_n_m,
            damping_per_s: raw.damping_per_s,
            friction: raw.friction,
            drag_coefficient: raw.drag_coefficient,
            lift_coefficient: raw.lift_coefficient,
        };
        // The ranges above are inside the cloth core's; this only guards against drift.
        fabric.validate().map_err(|e| GarmentError::Invalid {
            file: file.to_owned(),
            line: 1,
            field: "fabric".into(),
            problem: e.to_string(),
        })?;
        Ok(FabricSpec {
            name: raw.name,
            description: raw.description,
            fabric,
            sources: raw.sources,
        })
    }
}

/// Reads a fabric file into the cloth core's [`fitroom_cloth::Fabric`].
pub fn load_fabric(path: impl AsRef<Path>) -> Result<fitroom_cloth::Fabric, GarmentError> {
    FabricSpec::load(path).map(|s| s.fabric)
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "Fabric(
    name: \"test\",
    areal_density_kg_m2: 0.15,
    stretch_stiffness_n_m: 2000,
    shear_stiffness_n_m: 100,
    bend_stiffness_n_m: 2e-5,
    damping_per_s: 0.3,
    friction: 0.4,
    drag_coefficient: 1.0,
    lift_coefficient: 0.3,
)";

    #[test]
    fn reads_a_fabric() {
        let spec = FabricSpec::from_ron_str(GOOD, "test.ron").expect("valid fabric");
        assert_eq!(spec.fabric.areal_density_kg_m2, 0.15);
        assert_eq!(spec.fabric.stretch_stiffness_n_m, 2000.0);
    }

    #[test]
    fn out_of_range_names_line_field_and_range() {
        let bad = GOOD.replace("0.15", "150");
        let err = FabricSpec::from_ron_str(&bad, "bad.ron").expect_err("150 kg/m² is refused");
        let msg = err.to_string();
        assert!(msg.starts_with("bad.ron:3:"), "{msg}");
        assert!(msg.contains("areal_density_kg_m2"), "{msg}");
        assert!(msg.contains("1e-2..=3e0"), "{msg}");
    }
}
