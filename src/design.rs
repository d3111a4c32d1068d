//! Designer mode (`fitroom design G.ron`): the garment on the avatar in a window, for the
//! people who write garment and fabric files. An orbit camera (drag to turn, wheel to zoom),
//! a still pose (A-pose, T-pose) or the walking clip, size and body switches, the fit map, and
//! the last load error on screen. Saving the garment or its fabric dresses the avatar again
//! (hot reload through the asset server).

use bevy::input::mouse::{AccumulatedMouseMotion, AccumulatedMouseScroll};
use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, egui};
use fitroom_body::{
    Shape,
    plugin::{AvatarMeasurements, AvatarShape},
};
use fitroom_garment::{
    asset::GarmentAsset,
    plugin::{ClothSettings, GarmentRequest, GarmentStatus},
};
use fitroom_motion::{
    plugin::{AvatarMotion, MotionSystems},
    still_pose::{StillPose, still_pose},
};
use fitroom_schedule::FitroomSystems;
use fitroom_sensor::{SensorFrame, SensorSource, SourceError, plugin::ActiveSensor};

use crate::kiosk::KioskSystems;

/// What drives the avatar in the designer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DesignMotion {
    Still(StillPose),
    /// The configured clip, looped.
    Clip,
}

/// The designer's choices.
#[derive(Resource)]
pub struct Designer {
    pub motion: DesignMotion,
    /// Applied when it differs from what drives the avatar now.
    applied: Option<DesignMotion>,
    /// The clip's source, kept while a still pose is shown.
    parked_sensor: Option<Box<dyn SensorSource>>,
    /// The bodies to switch between: a name and its shape.
    pub bodies: Vec<(String, Shape)>,
}

impl Designer {
    pub fn new(shape: Option<Shape>) -> Self {
        let mut bodies = vec![
            ("default".to_owned(), Shape::default()),
            (
                "woman".to_owned(),
                Shape {
                    gender: 0.0,
                    ..Shape::default()
                },
            ),
            (
                "man".to_owned(),
                Shape {
                    gender: 1.0,
                    ..Shape::default()
                },
            ),
        ];
        if let Some(shape) = shape {
            bodies.insert(0, ("--shape".to_owned(), shape));
        }
        Self {
            motion: DesignMotion::Still(StillPose::APose),
            applied: None,
            parked_sensor: None,
            bodies,
        }
    }
}

/// The designer's camera: it turns around `focus` at `distance`.
#[derive(Component, Debug, Clone, Copy)]
pub struct OrbitCamera {
    pub focus: Vec3,
    pub yaw: f32,
    pub pitch: f32,
    pub distance: f32,
}

impl OrbitCamera {
    /// In front of a person standing at `focus`, a little above, turned a quarter of the way
    /// round so that the garment's side shows.
    pub fn facing(focus: Vec3) -> Self {
        Self {
            focus,
            yaw: 0.5,
            pitch: -0.12,
            distance: 3.0,
        }
    }

    pub fn transform(&self) -> Transform {
        let rotation = Quat::from_euler(EulerRot::YXZ, self.yaw, self.pitch, 0.0);
        Transform::from_translation(self.focus + rotation * Vec3::new(0.0, 0.0, self.distance))
            .looking_at(self.focus, Vec3::Y)
    }
}

/// The avatar's middle in the world, where the orbit camera looks.
pub const DESIGN_FOCUS: Vec3 = Vec3::new(0.0, 1.0, -2.5);

pub struct DesignPlugin;

impl Plugin for DesignPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(
            PostUpdate,
            (
                drive_avatar
                    .in_set(FitroomSystems::Motion)
                    .after(MotionSystems::Retarget),
                orbit
                    .in_set(FitroomSystems::Pose)
                    .after(KioskSystems::FrameCamera),
            ),
        )
        .add_systems(EguiPrimaryContextPass, design_panel);
    }
}

/// The source of a still pose: no frames.
struct Still;

impl SensorSource for Still {
    fn name(&self) -> &str {
        "still pose"
    }
    fn fps(&self) -> f32 {
        30.0
    }
    fn advance(&mut self, _dt_s: f64) -> Result<Vec<SensorFrame>, SourceError> {
        Ok(Vec::new())
    }
}

/// A still pose replaces the sensor's frames (the clip's source is parked); the clip brings
/// them back.
fn drive_avatar(
    mut designer: ResMut<Designer>,
    sensor: Option<ResMut<ActiveSensor>>,
    motion: Option<ResMut<AvatarMotion>>,
) {
    let (Some(mut motion), Some(mut sensor)) = (motion, sensor) else {
        return;
    };
    if designer.applied == Some(designer.motion) {
        return;
    }
    match designer.motion {
        DesignMotion::Still(pose) => {
            if designer.parked_sensor.is_none() {
                designer.parked_sensor = Some(std::mem::replace(&mut sensor.0, Box::new(Still)));
            }
            motion.reset();
            motion.pose = still_pose(motion.pipeline.skeleton(), pose);
        }
        DesignMotion::Clip => {
            if let Some(parked) = designer.parked_sensor.take() {
                sensor.0 = parked;
            }
            motion.reset();
        }
    }
    designer.applied = Some(designer.motion);
}

/// Drag with the left button to turn around the avatar, the wheel to come closer.
fn orbit(
    buttons: Option<Res<ButtonInput<MouseButton>>>,
    motion: Option<Res<AccumulatedMouseMotion>>,
    scroll: Option<Res<AccumulatedMouseScroll>>,
    mut contexts: EguiContexts,
    mut cameras: Query<(&mut OrbitCamera, &mut Transform)>,
) {
    let over_panel = contexts
        .ctx_mut()
        .is_ok_and(|ctx| ctx.egui_wants_pointer_input() || ctx.is_pointer_over_egui());
    for (mut orbit, mut transform) in &mut cameras {
        if !over_panel {
            if let (Some(buttons), Some(motion)) = (&buttons, &motion)
                && buttons.pressed(MouseButton::Left)
            {
                orbit.yaw -= motion.delta.x * 0.008;
                orbit.pitch = (orbit.pitch - motion.delta.y * 0.006).clamp(-1.2, 1.2);
            }
            if let Some(scroll) = &scroll {
                orbit.distance = (orbit.distance * (1.0 - 0.1 * scroll.delta.y)).clamp(0.8, 8.0);
            }
        }
        *transform = orbit.transform();
    }
}

#[allow(clippy::too_many_arguments)]
fn design_panel(
    mut contexts: EguiContexts,
    mut designer: ResMut<Designer>,
    mut request: ResMut<GarmentRequest>,
    mut shape: ResMut<AvatarShape>,
    mut cloth: ResMut<ClothSettings>,
    status: Res<GarmentStatus>,
    measured: Res<AvatarMeasurements>,
    garments: Res<Assets<GarmentAsset>>,
) -> Result {
    let ctx = contexts.ctx_mut()?;
    let sizes: Vec<String> = garments
        .iter()
        .next()
        .map(|(_, g)| g.0.size_labels())
        .unwrap_or_default();
    egui::Window::new("fitroom designer")
        .anchor(egui::Align2::LEFT_TOP, egui::vec2(12.0, 12.0))
        .resizable(false)
        .collapsible(false)
        .default_width(320.0)
        .show(ctx, |ui| {
            ui.set_max_width(320.0);
            if let Some(file) = &status.file {
                ui.label(file.display().to_string());
            }
            ui.label(match &status.worn {
                Some(worn) => format!("wearing {worn} ({} particles)", status.particles),
                None => "loading…".to_owned(),
            });
            ui.label("Save the garment or its fabric file: the avatar is dressed again.");
            if let Some(error) = &status.error {
                ui.separator();
                ui.colored_label(egui::Color32::from_rgb(230, 80, 60), "last load error:");
                ui.colored_label(egui::Color32::from_rgb(230, 80, 60), error);
            }
            ui.separator();
            ui.label("Size");
            ui.horizontal_wrapped(|ui| {
                let current = request
                    .size
                    .clone()
                    .or_else(|| sizes.get(sizes.len() / 2).cloned());
                for size in &sizes {
                    if ui
                        .selectable_label(current.as_deref() == Some(size), size)
                        .clicked()
                    {
                        request.size = Some(size.clone());
                    }
                }
            });
            ui.label("Body");
            ui.horizontal_wrapped(|ui| {
                for (name, body) in designer.bodies.clone() {
                    if ui.selectable_label(shape.0 == body, &name).clicked() {
                        shape.0 = body;
                    }
                }
            });
            if let Some(m) = &measured.measurements {
                ui.label(format!(
                    "stature {:.0} cm, bust {:.0}, waist {:.0}, hip {:.0}",
                    m.stature_cm, m.bust_cm, m.waist_cm, m.hip_cm
                ));
            }
            ui.label("Pose");
            ui.horizontal(|ui| {
                for (label, choice) in [
                    ("A-pose", DesignMotion::Still(StillPose::APose)),
                    ("T-pose", DesignMotion::Still(StillPose::TPose)),
                    ("walk", DesignMotion::Clip),
                ] {
                    if ui
                        .selectable_label(designer.motion == choice, label)
                        .clicked()
                    {
                        designer.motion = choice;
                    }
                }
            });
            ui.separator();
            ui.checkbox(
                &mut cloth.fit_map,
                "fit map (strain: blue slack, red +10 %)",
            );
            ui.label(format!("largest strain now {:.1} %", status.max_strain_pct));
            ui.label("Drag to turn around the avatar, wheel to zoom.");
        });
    Ok(())
}
