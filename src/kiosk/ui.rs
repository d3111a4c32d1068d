//! The egui status overlay: frame rate, kiosk state, sensor, calibration, the garment worn
//! and the last load error.

use bevy::diagnostic::{DiagnosticsStore, FrameTimeDiagnosticsPlugin};
use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPlugin, EguiPrimaryContextPass, egui};
use fitroom_garment::plugin::GarmentStatus;
use fitroom_measure::calibration::Collecting;
use fitroom_measure::plugin::{BodyMeasurements, Calibration, CalibrationStatus};
use fitroom_motion::filter::RejectReason;
use fitroom_motion::plugin::AvatarMotion;
use fitroom_sensor::plugin::SensorFeed;

use super::{KioskState, KioskStatus};

pub struct OverlayPlugin;

impl Plugin for OverlayPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<FrameTimeDiagnosticsPlugin>() {
            app.add_plugins(FrameTimeDiagnosticsPlugin::default());
        }
        app.add_plugins(EguiPlugin::default())
            .add_systems(EguiPrimaryContextPass, status_overlay);
    }
}

// A Bevy system: each parameter is a resource it reads.
#[allow(clippy::too_many_arguments)]
fn status_overlay(
    mut contexts: EguiContexts,
    diagnostics: Res<DiagnosticsStore>,
    state: Res<State<KioskState>>,
    status: Res<KioskStatus>,
    feed: Res<SensorFeed>,
    motion: Option<Res<AvatarMotion>>,
    garment: Option<Res<GarmentStatus>>,
    config: Option<Res<super::config::ActiveKioskConfig>>,
    body_file: Option<Res<fitroom_body::reload::BodyFile>>,
    debug: Res<super::DebugSkeletons>,
    measuring: (
        Option<Res<Calibration>>,
        Option<Res<BodyMeasurements>>,
        Res<super::measure::SizeAdvice>,
    ),
) -> Result {
    let (calibration, measured, advice) = measuring;
    let fps = diagnostics
        .get(&FrameTimeDiagnosticsPlugin::FPS)
        .and_then(|d| d.smoothed())
        .unwrap_or(0.0);
    let ctx = contexts.ctx_mut()?;
    egui::Area::new(egui::Id::new("kiosk-status"))
        .anchor(egui::Align2::LEFT_TOP, egui::vec2(16.0, 16.0))
        .show(ctx, |ui| {
            egui::Frame::popup(ui.style()).show(ui, |ui| {
                // Narrow enough that the size labels over two avatars' heads stay clear.
                ui.set_max_width(400.0);
                ui.heading("fitroom");
                ui.label(format!("{fps:.0} fps"));
                ui.label(state.get().label());
                ui.label(format!(
                    "sensor: {} ({} frames)",
                    if feed.source_name.is_empty() {
                        "none"
                    } else {
                        &feed.source_name
                    },
                    feed.frames_received
                ));
                if let Some(motion) = motion.as_ref() {
                    if let Some(c) = motion.pipeline.retargeter().calibration() {
                        ui.label(format!("avatar/person leg ratio {:.2}", c.scale));
                    }
                    // Frames without a person (no hip, an empty skeleton) are an empty room,
                    // not bad data.
                    let rejected: u64 = motion
                        .pipeline
                        .gate
                        .stats()
                        .by_reason()
                        .filter(|(r, _)| {
                            !matches!(r, RejectReason::MissingHip | RejectReason::AllAtOrigin)
                        })
                        .map(|(_, n)| n)
                        .sum();
                    if rejected > 0 {
                        ui.colored_label(
                            egui::Color32::from_rgb(230, 160, 60),
                            format!("bad sensor frames ignored: {rejected}"),
                        );
                    }
                }
                ui.label(if debug.0 {
                    "skeletons: raw (red), filtered (green) — D hides"
                } else {
                    "D: show the sensor skeletons"
                });
                if *state.get() == KioskState::Calibrate {
                    match calibration.as_ref().map(|c| &c.status) {
                        // The pose guide (`guide.rs`) shows the progress and the hint.
                        Some(CalibrationStatus::Collecting(_)) => {}
                        Some(CalibrationStatus::Fitting) => {
                            ui.label("measuring: fitting your body…");
                        }
                        _ => {
                            ui.label(format!("tracking… {:.1} s", status.tracked_s));
                        }
                    }
                }
                // In Try on unmeasured (the person never stood still in Calibrate): the
                // measurement goes on, and says what it waits for.
                if *state.get() == KioskState::TryOn
                    && measured.is_none()
                    && let Some(CalibrationStatus::Collecting(Collecting { hint, .. })) =
                        calibration.as_ref().map(|c| &c.status)
                {
                    ui.colored_label(
                        egui::Color32::from_rgb(230, 160, 60),
                        format!(
                            "not measured yet{}: sizes are the middle ones",
                            hint.as_ref().map_or(String::new(), |h| format!(" ({h})"))
                        ),
                    );
                }
                if let Some(m) = measured.as_ref() {
                    let v = &m.measurements;
                    ui.label(format!(
                        "measured: height {:.0} cm, chest {:.0}, waist {:.0}, hip {:.0} cm",
                        v.stature_cm, v.bust_cm, v.waist_cm, v.hip_cm
                    ));
                    if let Some(size) = &advice.size {
                        ui.label(format!("your size: {size} ({})", advice.reason));
                    } else if !advice.reason.is_empty() {
                        ui.label(advice.reason.clone());
                    }
                }
                if let Some(error) = &feed.error {
                    ui.colored_label(egui::Color32::from_rgb(230, 80, 60), error);
                }
                let errors = [
                    config.as_ref().and_then(|c| c.error.as_ref()),
                    body_file.as_ref().and_then(|b| b.error.as_ref()),
                ];
                for error in errors.into_iter().flatten() {
                    ui.colored_label(egui::Color32::from_rgb(230, 80, 60), error);
                }
                if let Some(garment) = garment.as_ref() {
                    if let Some(worn) = &garment.worn {
                        ui.label(format!("wearing: {worn}"));
                    }
                    if let Some(error) = &garment.error {
                        // The last load error (file, line, field); what is worn stays.
                        ui.colored_label(egui::Color32::from_rgb(230, 80, 60), error);
                    }
                }
            });
        });
    Ok(())
}
