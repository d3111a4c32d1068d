//! A garment's own size table as a size chart: what the kiosk recommends for the measured
//! person, and what the evaluation dresses each subject in.

use fitroom_body::{Gender, SizeChart};
use fitroom_garment::GarmentSource;

/// The chart of `source`'s sizes (each size's body measurements, ranges half-way to the
/// neighbouring sizes), or why it has none: a mesh garment comes in one size; a pattern may
/// state no body measurements.
pub fn garment_chart(source: &GarmentSource) -> Result<SizeChart, String> {
    let Some(pattern) = source.pattern() else {
        return Err("this garment comes in one size".into());
    };
    let sizes: Vec<_> = pattern
        .sizes
        .iter()
        .map(|s| (s.label.clone(), s.body_cm.clone()))
        .collect();
    if sizes.iter().all(|(_, m)| m.is_empty()) {
        return Err("the garment's sizes state no body measurements".into());
    }
    SizeChart::from_nominal(&pattern.name, Gender::Unisex, &[], &sizes)
        .map_err(|e| format!("the garment's sizes: {e}"))
}
