//! The kiosk's side of measuring the person (the work is `fitroom_measure::plugin`): measure
//! when a person steps in (`Calibrate`), dress them in the recommended size of the garment
//! worn once measured, and forget them when they leave (the next person starts from the
//! configured body).

use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use fitroom_body::Shape;
use fitroom_body::plugin::AvatarShape;
use fitroom_depth::plugin::DepthFeed;
use fitroom_garment::asset::GarmentAsset;
use fitroom_garment::plugin::{GarmentRequest, GarmentStatus};
use fitroom_garment::source::GarmentSource;
use fitroom_measure::garment_size::garment_chart;
use fitroom_measure::plugin::{BodyMeasurements, Calibration, CalibrationStatus, MeasurePrior};

use super::KioskState;

/// The configured body shape, which each new person starts from.
#[derive(Resource, Debug, Clone, Default)]
pub struct ConfiguredShape(pub Shape);

/// The size recommended for the garment worn, and why.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct SizeAdvice {
    pub garment: Option<String>,
    pub size: Option<String>,
    pub reason: String,
}

/// Whether the person can be measured here, and whether they have been.
#[derive(SystemParam)]
pub struct Measuring<'w> {
    calibration: Option<Res<'w, Calibration>>,
    depth: Option<Res<'w, DepthFeed>>,
    prior: Option<Res<'w, MeasurePrior>>,
}

impl Measuring<'_> {
    /// Depth comes in and the measurement is available.
    pub fn possible(&self) -> bool {
        self.calibration.is_some()
            && self.depth.as_ref().is_some_and(|d| d.frames_received > 0)
            && self.prior.as_ref().is_some_and(|p| p.0.is_ok())
    }

    pub fn done(&self) -> bool {
        self.calibration
            .as_ref()
            .is_some_and(|c| c.status == CalibrationStatus::Done)
    }
}

pub fn add(app: &mut App) {
    let configured = app
        .world()
        .get_resource::<AvatarShape>()
        .map(|s| s.0.clone())
        .unwrap_or_default();
    app.insert_resource(ConfiguredShape(configured))
        .init_resource::<SizeAdvice>()
        .add_systems(OnEnter(KioskState::Calibrate), start)
        .add_systems(OnEnter(KioskState::Attract), forget)
        .add_systems(Update, size_garment);
}

fn start(calibration: Option<ResMut<Calibration>>) {
    if let Some(mut c) = calibration {
        c.start();
    }
}

fn forget(
    mut commands: Commands,
    calibration: Option<ResMut<Calibration>>,
    measured: Option<Res<BodyMeasurements>>,
    configured: Res<ConfiguredShape>,
    mut shape: ResMut<AvatarShape>,
    mut advice: ResMut<SizeAdvice>,
) {
    if let Some(mut c) = calibration {
        c.stop();
    }
    if measured.is_some() {
        commands.remove_resource::<BodyMeasurements>();
        shape.0 = configured.0.clone();
        *advice = SizeAdvice::default();
    }
}

/// Once measured (or when the garment changes, or its file is edited), the garment's
/// recommended size is worn.
fn size_garment(
    measured: Option<Res<BodyMeasurements>>,
    status: Res<GarmentStatus>,
    garments: Res<Assets<GarmentAsset>>,
    mut request: ResMut<GarmentRequest>,
    mut advice: ResMut<SizeAdvice>,
) {
    let Some(measured) = measured else {
        return;
    };
    let (Some(file), Some(asset)) = (&status.file, &status.asset) else {
        return;
    };
    let garment = file.display().to_string();
    if !measured.is_changed()
        && !garments.is_changed()
        && advice.garment.as_deref() == Some(garment.as_str())
    {
        return;
    }
    // Not loaded yet: sized when it is.
    let Some(source) = garments.get(asset) else {
        return;
    };
    advice.garment = Some(garment);
    let (size, reason) = recommend(&source.0, &measured);
    advice.size = size.clone();
    advice.reason = reason;
    if size.is_some() && request.size != size {
        request.size = size;
    }
}

/// The size of `garment` for `measured`, and why.
fn recommend(garment: &GarmentSource, measured: &BodyMeasurements) -> (Option<String>, String) {
    let chart = match garment_chart(garment) {
        Ok(chart) => chart,
        Err(why) => return (None, why),
    };
    let r = chart.recommend(&measured.measurements);
    let reasons: Vec<String> = r
        .measures
        .iter()
        .filter(|a| r.decided_by.contains(&a.measure))
        .map(|a| a.reason.clone())
        .collect();
    (r.size, reasons.join("; "))
}
