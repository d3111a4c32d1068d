//! The calibration's pose guide: while the kiosk measures the person, an outline of the
//! pose asked for (standing facing the mirror, arms a hand's width from the body; then turned
//! halfway to the left), the view's progress under it, and the hint when a frame was not good.

use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, egui};
use fitroom_measure::calibration::Collecting;
use fitroom_measure::plugin::{Calibration, CalibrationStatus};

use super::KioskState;

pub struct PoseGuidePlugin;

impl Plugin for PoseGuidePlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(EguiPrimaryContextPass, pose_guide);
    }
}

/// The figure's joints in units of its height (x right, y down, the head's top at 0),
/// turned by `turn` (0: facing the viewer, 1: a quarter turn): the far side's widths shrink
/// with the cosine, as a turned person's silhouette does.
fn figure(turn: f32) -> Vec<[egui::Pos2; 2]> {
    let c = (turn * std::f32::consts::FRAC_PI_2).cos();
    let p = |x: f32, y: f32| egui::pos2(x * c, y);
    vec![
        // Trunk and neck.
        [p(0.0, 0.13), p(0.0, 0.52)],
        // Shoulders and hips.
        [p(-0.13, 0.19), p(0.13, 0.19)],
        [p(-0.08, 0.52), p(0.08, 0.52)],
        // Arms a hand's width from the body (about 20° out).
        [p(-0.13, 0.19), p(-0.19, 0.36)],
        [p(-0.19, 0.36), p(-0.24, 0.52)],
        [p(0.13, 0.19), p(0.19, 0.36)],
        [p(0.19, 0.36), p(0.24, 0.52)],
        // Legs a little apart.
        [p(-0.08, 0.52), p(-0.09, 0.76)],
        [p(-0.09, 0.76), p(-0.1, 1.0)],
        [p(0.08, 0.52), p(0.09, 0.76)],
        [p(0.09, 0.76), p(0.1, 1.0)],
    ]
}

fn pose_guide(
    mut contexts: EguiContexts,
    state: Res<State<KioskState>>,
    calibration: Option<Res<Calibration>>,
) -> Result {
    if *state.get() != KioskState::Calibrate {
        return Ok(());
    }
    let Some(calibration) = calibration else {
        return Ok(());
    };
    let CalibrationStatus::Collecting(Collecting {
        view, views, hint, ..
    }) = &calibration.status
    else {
        return Ok(());
    };
    let ctx = contexts.ctx_mut()?;
    egui::Area::new(egui::Id::new("pose-guide"))
        .anchor(egui::Align2::RIGHT_TOP, egui::vec2(-24.0, 24.0))
        .show(ctx, |ui| {
            egui::Frame::popup(ui.style()).show(ui, |ui| {
                ui.set_width(240.0);
                ui.label(if *view == 0 {
                    "Face the mirror, arms a little away, and stand still"
                } else {
                    "Now turn halfway to your left and hold still"
                });
                let (rect, _) =
                    ui.allocate_exact_size(egui::vec2(240.0, 300.0), egui::Sense::hover());
                let painter = ui.painter_at(rect);
                let height = rect.height() - 40.0;
                let origin = egui::pos2(rect.center().x, rect.top() + 24.0);
                let at = |p: egui::Pos2| origin + egui::vec2(p.x * height, p.y * height);
                let turn = if *view == 0 { 0.0 } else { 0.5 };
                let stroke = egui::Stroke::new(5.0, egui::Color32::from_rgb(90, 200, 140));
                for [a, b] in figure(turn) {
                    painter.line_segment([at(a), at(b)], stroke);
                }
                painter.circle_stroke(at(egui::pos2(0.0, 0.065)), 0.065 * height, stroke);
                if *view > 0 {
                    // An arrow round the figure's feet: turn to the left.
                    let y = at(egui::pos2(0.0, 1.03)).y;
                    let (l, r) = (origin.x - 70.0, origin.x + 70.0);
                    let arrow = egui::Stroke::new(3.0, egui::Color32::from_rgb(230, 160, 60));
                    painter.line_segment([egui::pos2(r, y), egui::pos2(l, y)], arrow);
                    painter.line_segment([egui::pos2(l, y), egui::pos2(l + 14.0, y - 8.0)], arrow);
                    painter.line_segment([egui::pos2(l, y), egui::pos2(l + 14.0, y + 8.0)], arrow);
                }
                ui.add(
                    egui::ProgressBar::new(calibration.progress())
                        .text(format!("view {} of {views}", view + 1)),
                );
                if let Some(hint) = hint {
                    ui.colored_label(egui::Color32::from_rgb(230, 160, 60), hint);
                }
            });
        });
    Ok(())
}
