//! The body panel (egui, toggled with B): MakeHuman sliders that reshape the avatar live, the
//! avatar's measurements, a fit to typed-in measurements (seed 002 calibration), and saving
//! the shape as RON for `--shape`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, egui};
use fitroom_body::{
    FitOptions, FitRequest, Measure, Shape,
    plugin::{AvatarBody, AvatarMeasurements, AvatarShape},
};

/// State of the body panel.
#[derive(Resource, Debug, Clone)]
pub struct BodyPanel {
    pub open: bool,
    /// Where "Save" writes the shape.
    pub shape_path: PathBuf,
    /// The measurements typed in for a fit (cm), and which of them to use.
    pub targets: BTreeMap<Measure, (bool, f32)>,
    /// The last message (fit result, save, error).
    pub message: Option<(bool, String)>,
}

impl Default for BodyPanel {
    fn default() -> Self {
        let targets = [
            (Measure::Stature, 165.0),
            (Measure::Bust, 92.0),
            (Measure::Waist, 74.0),
            (Measure::Hip, 100.0),
            (Measure::Neck, 36.0),
            (Measure::Thigh, 56.0),
            (Measure::Calf, 36.0),
            (Measure::ShoulderWidth, 38.0),
            (Measure::InsideLeg, 76.0),
            (Measure::ArmLength, 58.0),
            (Measure::Underbust, 78.0),
            (Measure::NavelWaist, 80.0),
        ]
        .into_iter()
        .map(|(m, v)| {
            let used = matches!(
                m,
                Measure::Stature | Measure::Bust | Measure::Waist | Measure::Hip
            );
            (m, (used, v))
        })
        .collect();
        Self {
            open: false,
            shape_path: PathBuf::from("shape.ron"),
            targets,
            message: None,
        }
    }
}

pub struct BodyPanelPlugin;

impl Plugin for BodyPanelPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<BodyPanel>()
            .add_systems(Update, toggle_panel)
            .add_systems(EguiPrimaryContextPass, body_panel);
    }
}

fn toggle_panel(keys: Option<Res<ButtonInput<KeyCode>>>, mut panel: ResMut<BodyPanel>) {
    if keys.is_some_and(|k| k.just_pressed(KeyCode::KeyB)) {
        panel.open = !panel.open;
    }
}

/// Sliders whose change is worth a reshape; `Shape` compares by value, so an unchanged slider
/// does not trigger one.
fn slider(ui: &mut egui::Ui, label: &str, value: &mut f32, range: std::ops::RangeInclusive<f32>) {
    ui.add(egui::Slider::new(value, range).text(label));
}

fn body_panel(
    mut contexts: EguiContexts,
    mut panel: ResMut<BodyPanel>,
    mut shape: ResMut<AvatarShape>,
    measured: Res<AvatarMeasurements>,
    body: Option<Res<AvatarBody>>,
) -> Result {
    if !panel.open {
        return Ok(());
    }
    let Some(body) = body else {
        return Ok(());
    };
    let ctx = contexts.ctx_mut()?;
    let mut edited = shape.0.clone();
    let mut fit_now = false;
    let mut save_now = false;
    egui::Window::new("Body")
        .anchor(egui::Align2::RIGHT_TOP, egui::vec2(-16.0, 16.0))
        .default_width(330.0)
        .resizable(false)
        .show(ctx, |ui| {
            egui::ScrollArea::vertical()
                .max_height(ctx_height(ui) * 0.8)
                .show(ui, |ui| {
                    ui.label("Shape (MakeHuman modifiers)");
                    slider(
                        ui,
                        "gender (0 female, 1 male)",
                        &mut edited.gender,
                        0.0..=1.0,
                    );
                    slider(ui, "age (0.5 = 25 y)", &mut edited.age, 0.0..=1.0);
                    slider(ui, "height", &mut edited.height, 0.0..=1.0);
                    slider(ui, "weight", &mut edited.weight, 0.0..=1.0);
                    slider(ui, "muscle", &mut edited.muscle, 0.0..=1.0);
                    slider(ui, "proportions", &mut edited.proportions, 0.0..=1.0);
                    egui::CollapsingHeader::new("measure sliders").show(ui, |ui| {
                        for name in Shape::measure_names(&body.model) {
                            let mut v = edited.measures.get(&name).copied().unwrap_or(0.0);
                            slider(ui, &name, &mut v, -1.0..=1.0);
                            if v == 0.0 {
                                edited.measures.remove(&name);
                            } else {
                                edited.measures.insert(name, v);
                            }
                        }
                    });
                    egui::CollapsingHeader::new("region scale sliders").show(ui, |ui| {
                        for name in Shape::region_names(&body.model) {
                            let mut v = edited.regions.get(&name).copied().unwrap_or(0.0);
                            slider(ui, &name, &mut v, -1.0..=1.0);
                            if v == 0.0 {
                                edited.regions.remove(&name);
                            } else {
                                edited.regions.insert(name, v);
                            }
                        }
                    });
                    if ui.button("reset to the default body").clicked() {
                        edited = Shape::default();
                    }
                    ui.separator();
                    ui.label("Measurements of the avatar (cm)");
                    if let Some(m) = &measured.measurements {
                        egui::Grid::new("measured").num_columns(2).show(ui, |ui| {
                            for q in Measure::ALL {
                                ui.label(q.name());
                                ui.label(format!("{:.1}", q.of(m)));
                                ui.end_row();
                            }
                        });
                    }
                    if let Some(e) = &measured.error {
                        ui.colored_label(egui::Color32::from_rgb(230, 80, 60), e);
                    }
                    ui.separator();
                    ui.label("Fit to a person's measurements (cm)");
                    egui::Grid::new("targets").num_columns(2).show(ui, |ui| {
                        for (q, (used, v)) in panel.targets.iter_mut() {
                            ui.checkbox(used, q.name());
                            let (lo, hi) = q.plausible_range_cm();
                            ui.add_enabled(
                                *used,
                                egui::DragValue::new(v)
                                    .range(lo..=hi)
                                    .speed(0.1)
                                    .suffix(" cm"),
                            );
                            ui.end_row();
                        }
                    });
                    ui.horizontal(|ui| {
                        fit_now = ui.button("Fit").clicked();
                        save_now = ui
                            .button(format!("Save {}", panel.shape_path.display()))
                            .clicked();
                    });
                    if let Some((ok, text)) = &panel.message {
                        let color = if *ok {
                            egui::Color32::from_rgb(120, 200, 120)
                        } else {
                            egui::Color32::from_rgb(230, 160, 60)
                        };
                        ui.colored_label(color, text);
                    }
                });
        });

    if fit_now {
        let targets: BTreeMap<Measure, f32> = panel
            .targets
            .iter()
            .filter(|(_, (used, _))| *used)
            .map(|(q, (_, v))| (*q, *v))
            .collect();
        let request = FitRequest {
            gender: edited.gender,
            age_years: None,
            targets,
        };
        panel.message = Some(
            match fitroom_body::fit(&body.model, &request, &FitOptions::default()) {
                Ok(r) => {
                    let worst = r
                        .residuals_cm
                        .iter()
                        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
                        .map(|(q, e)| format!("{q} {e:+.1} cm"))
                        .unwrap_or_default();
                    let text = if r.reachable {
                        format!("fitted in {:.0} ms (worst: {worst})", r.time_ms)
                    } else {
                        format!(
                            "out of the model's reach; the closest body (worst: {worst}; at \
                             limits: {})",
                            r.at_bounds.join(", ")
                        )
                    };
                    edited = r.shape;
                    (r.reachable, text)
                }
                Err(e) => (false, e.to_string()),
            },
        );
    }
    if save_now {
        panel.message = Some(
            match ron::ser::to_string_pretty(&edited, ron::ser::PrettyConfig::default()) {
                Ok(text) => match std::fs::write(&panel.shape_path, text + "\n") {
                    Ok(()) => (true, format!("saved {}", panel.shape_path.display())),
                    Err(e) => (
                        false,
                        format!("cannot write {}: {e}", panel.shape_path.display()),
                    ),
                },
                Err(e) => (false, format!("cannot write the shape: {e}")),
            },
        );
    }
    if edited != shape.0 {
        shape.0 = edited;
    }
    Ok(())
}

fn ctx_height(ui: &egui::Ui) -> f32 {
    ui.ctx().content_rect().height()
}
