//! The try-on screen (egui, large enough to read from 2.5 m): the carousel of the
//! configuration's garments, the sizes with the recommended one marked and why, fit map and
//! photo; how to start in `Attract`; and feedback for every gesture (the hand cursor, its
//! grip, a swipe's arrow). Its buttons produce [`KioskAction`]s like every other input.

use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, egui};
use fitroom_garment::asset::GarmentAsset;
use fitroom_garment::plugin::{ClothSettings, GarmentRequest, GarmentStatus};
use fitroom_gesture::plugin::Gestures;
use fitroom_gesture::swipe::SwipeDirection;
use fitroom_sensor::plugin::SensorFeed;

use fitroom_body::plugin::Avatar;
use fitroom_body::twin::TwinAvatar;
use fitroom_motion::plugin::AvatarMotion;

use super::actions::{KioskAction, TryOn, garment_sizes, size_worn};
use super::config::ActiveKioskConfig;
use super::measure::SizeAdvice;
use super::thumbnails::{SIDE, Thumbnails, follow_thumbnails};
use super::{KioskState, MirrorCamera};

pub struct TryOnScreenPlugin;

impl Plugin for TryOnScreenPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Thumbnails>().add_systems(
            EguiPrimaryContextPass,
            (
                follow_thumbnails,
                try_on_screen,
                size_labels,
                gesture_feedback,
            )
                .chain(),
        );
    }
}

/// Text sizes for reading at 2.5 m on a 1280x800 mirror.
const BIG: f32 = 30.0;
const MEDIUM: f32 = 22.0;

const ACCENT: egui::Color32 = egui::Color32::from_rgb(240, 190, 90);

/// A garment's name on screen: its file's stem, words capitalised.
fn garment_name(file: &str) -> String {
    let stem = std::path::Path::new(file)
        .file_stem()
        .map_or_else(|| file.to_string(), |s| s.to_string_lossy().into_owned());
    stem.split(['_', '-'])
        .map(|w| {
            let mut c = w.chars();
            c.next().map_or_else(String::new, |f| {
                f.to_uppercase().collect::<String>() + c.as_str()
            })
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// One garment of the carousel: its thumbnail (while it is drawn, an empty square) over its
/// name; the one shown framed, the one worn named in the accent colour. True when clicked.
fn carousel_item(
    ui: &mut egui::Ui,
    name: &str,
    texture: Option<egui::TextureId>,
    shown: bool,
    worn: bool,
) -> bool {
    let side = SIDE as f32;
    let stroke = if shown {
        egui::Stroke::new(3.0, ACCENT)
    } else {
        egui::Stroke::new(1.0, egui::Color32::from_gray(90))
    };
    let frame = egui::Frame::new()
        .stroke(stroke)
        .corner_radius(6.0)
        .inner_margin(4.0)
        .fill(if shown {
            egui::Color32::from_gray(60)
        } else {
            egui::Color32::from_gray(40)
        });
    let response = frame
        .show(ui, |ui| {
            let size = egui::vec2(side + 32.0, side + MEDIUM + 8.0);
            ui.allocate_ui_with_layout(size, egui::Layout::top_down(egui::Align::Center), |ui| {
                ui.set_min_size(size);
                match texture {
                    Some(texture) => {
                        ui.image((texture, egui::vec2(side, side)));
                    }
                    None => {
                        ui.allocate_exact_size(egui::vec2(side, side), egui::Sense::hover());
                    }
                }
                let mut text = egui::RichText::new(name).size(MEDIUM);
                if worn {
                    text = text.color(ACCENT);
                }
                ui.label(text);
            });
        })
        .response;
    response.interact(egui::Sense::click()).clicked()
}

// A Bevy system: each parameter is a resource the screen shows.
#[allow(clippy::too_many_arguments)]
fn try_on_screen(
    mut contexts: EguiContexts,
    state: Res<State<KioskState>>,
    config: Res<ActiveKioskConfig>,
    mut tryon: ResMut<TryOn>,
    request: Res<GarmentRequest>,
    status: Res<GarmentStatus>,
    garments: Res<Assets<GarmentAsset>>,
    advice: Res<SizeAdvice>,
    cloth: Res<ClothSettings>,
    thumbnails: Res<Thumbnails>,
    mut actions: MessageWriter<KioskAction>,
) -> Result {
    let ctx = contexts.ctx_mut()?;
    match state.get() {
        KioskState::Attract => {
            egui::Area::new(egui::Id::new("attract"))
                .anchor(egui::Align2::CENTER_BOTTOM, egui::vec2(0.0, -60.0))
                .show(ctx, |ui| {
                    egui::Frame::popup(ui.style()).show(ui, |ui| {
                        ui.vertical_centered(|ui| {
                            ui.label(egui::RichText::new("Step in front of the mirror").size(BIG));
                            ui.label(
                                egui::RichText::new(
                                    "then raise a hand: swipe to browse, close it to choose",
                                )
                                .size(MEDIUM),
                            );
                        });
                    });
                });
        }
        KioskState::Calibrate => {}
        KioskState::TryOn => {
            let entries = &config.config.garments;
            egui::Area::new(egui::Id::new("try-on"))
                .anchor(egui::Align2::CENTER_BOTTOM, egui::vec2(0.0, -24.0))
                .show(ctx, |ui| {
                    egui::Frame::popup(ui.style()).show(ui, |ui| {
                        ui.set_max_width(1100.0);
                        // The carousel.
                        ui.horizontal(|ui| {
                            if ui.button(egui::RichText::new("◀").size(BIG)).clicked() {
                                actions.write(KioskAction::Previous);
                            }
                            for (i, entry) in entries.iter().enumerate() {
                                if carousel_item(
                                    ui,
                                    &garment_name(&entry.file),
                                    thumbnails.texture(i),
                                    i == tryon.shown,
                                    tryon.worn == Some(i),
                                ) {
                                    tryon.shown = i;
                                    actions.write(KioskAction::Select);
                                }
                            }
                            if ui.button(egui::RichText::new("▶").size(BIG)).clicked() {
                                actions.write(KioskAction::Next);
                            }
                        });
                        // The sizes of the garment worn, the recommended one marked.
                        let sizes = garment_sizes(&status, &garments);
                        if !sizes.is_empty() {
                            ui.horizontal(|ui| {
                                ui.label(egui::RichText::new("Size").size(MEDIUM));
                                let worn = size_worn(&request, &status);
                                for size in &sizes {
                                    let recommended = advice.size.as_ref() == Some(size);
                                    let label = if recommended {
                                        format!("{size} ★")
                                    } else {
                                        size.clone()
                                    };
                                    let mut text = egui::RichText::new(label).size(MEDIUM);
                                    if recommended {
                                        text = text.color(ACCENT);
                                    }
                                    let selected = worn.as_ref() == Some(size);
                                    if ui.add(egui::Button::new(text).selected(selected)).clicked()
                                    {
                                        let at = sizes.iter().position(|s| s == size);
                                        let now = worn
                                            .as_ref()
                                            .and_then(|w| sizes.iter().position(|s| s == w));
                                        if let (Some(at), Some(now)) = (at, now) {
                                            let step = if at > now {
                                                KioskAction::SizeUp
                                            } else {
                                                KioskAction::SizeDown
                                            };
                                            for _ in 0..at.abs_diff(now) {
                                                actions.write(step);
                                            }
                                        }
                                    }
                                }
                                ui.separator();
                                let fit = if cloth.fit_map {
                                    "Fit map: on"
                                } else {
                                    "Fit map"
                                };
                                if ui.button(egui::RichText::new(fit).size(MEDIUM)).clicked() {
                                    actions.write(KioskAction::ToggleFitMap);
                                }
                                let compare = egui::Button::new(
                                    egui::RichText::new("Two sizes").size(MEDIUM),
                                )
                                .selected(tryon.compare);
                                if ui.add(compare).clicked() {
                                    actions.write(KioskAction::Compare);
                                }
                                if ui
                                    .button(egui::RichText::new("Photo").size(MEDIUM))
                                    .clicked()
                                {
                                    actions.write(KioskAction::Photo);
                                }
                            });
                        }
                        if advice.size.is_some() && !advice.reason.is_empty() {
                            ui.label(
                                egui::RichText::new(format!("★ your size: {}", advice.reason))
                                    .size(16.0),
                            );
                        }
                        if let Some(photo) = &tryon.photo {
                            ui.label(egui::RichText::new(photo).size(16.0));
                        }
                        ui.label(
                            egui::RichText::new(
                                "swipe right / left: next / previous  ·  close your hand: wear it",
                            )
                            .size(16.0)
                            .weak(),
                        );
                    });
                });
        }
    }
    Ok(())
}

/// Two sizes side by side: each avatar's size above its head, the recommended one marked.
fn size_labels(
    mut contexts: EguiContexts,
    status: Res<GarmentStatus>,
    advice: Res<SizeAdvice>,
    twin: Option<Res<TwinAvatar>>,
    motion: Option<Res<AvatarMotion>>,
    avatar: Query<&Transform, With<Avatar>>,
    camera: Query<(&Camera, &GlobalTransform), With<MirrorCamera>>,
) -> Result {
    let (Some(twin), Some(motion), Some(compared)) = (twin, motion, status.compare_size()) else {
        return Ok(());
    };
    let (Ok(avatar), Ok((camera, view))) = (avatar.single(), camera.single()) else {
        return Ok(());
    };
    let Some(pelvis) = super::pelvis_world(&motion, avatar) else {
        return Ok(());
    };
    let ctx = contexts.ctx_mut()?;
    let painter = ctx.layer_painter(egui::LayerId::new(
        egui::Order::Foreground,
        egui::Id::new("size-labels"),
    ));
    // Above the heads: the pelvis is about half the body's height up.
    let above = Vec3::new(0.0, 0.95 * pelvis.y.max(0.5), 0.0);
    for (at, size) in [
        (pelvis, status.worn_size()),
        (pelvis + twin.offset, Some(compared)),
    ] {
        let (Some(size), Ok(point)) = (size, camera.world_to_viewport(view, at + above)) else {
            continue;
        };
        let recommended = advice.size.as_deref() == Some(size);
        let text = if recommended {
            format!("{size} ★")
        } else {
            size.to_string()
        };
        painter.text(
            egui::pos2(point.x, point.y),
            egui::Align2::CENTER_BOTTOM,
            text,
            egui::FontId::proportional(BIG + 10.0),
            if recommended {
                ACCENT
            } else {
                egui::Color32::WHITE
            },
        );
    }
    Ok(())
}

/// The hand cursor (a ring, a disc growing inside it as the hand closes, filled when it
/// grips) and, for half a second after a swipe, its arrow.
fn gesture_feedback(
    mut contexts: EguiContexts,
    gestures: Option<Res<Gestures>>,
    feed: Res<SensorFeed>,
) -> Result {
    let Some(gestures) = gestures else {
        return Ok(());
    };
    let ctx = contexts.ctx_mut()?;
    let screen = ctx.content_rect();
    let painter = ctx.layer_painter(egui::LayerId::new(
        egui::Order::Foreground,
        egui::Id::new("gesture-feedback"),
    ));
    if let Some(cursor) = gestures.cursor {
        let at = screen.min
            + egui::vec2(
                cursor.position.x * screen.width(),
                cursor.position.y * screen.height(),
            );
        let colour = egui::Color32::from_rgba_unmultiplied(240, 190, 90, 220);
        painter.circle_stroke(at, 28.0, egui::Stroke::new(5.0, colour));
        if cursor.pressed {
            painter.circle_filled(at, 22.0, colour);
        } else {
            // The grip's fill: the disc grows as the hand reads more closed (its probability
            // of open from 0.8 down to 0.2), so a person sees the grip coming.
            let closed = 1.0 - gestures.p_open[cursor.hand.index()];
            let fill = ((closed - 0.2) / 0.6).clamp(0.0, 1.0);
            if fill > 0.0 {
                let faint = egui::Color32::from_rgba_unmultiplied(240, 190, 90, 120);
                painter.circle_filled(at, 22.0 * fill, faint);
            }
        }
    }
    let now = feed.latest.as_ref().map(|f| f.timestamp_s);
    if let (Some(swipe), Some(now)) = (gestures.last_swipe, now)
        && (0.0..0.6).contains(&(now - swipe.time_s))
    {
        let arrow = match swipe.direction {
            SwipeDirection::Right => "▶▶",
            SwipeDirection::Left => "◀◀",
        };
        painter.text(
            screen.center(),
            egui::Align2::CENTER_CENTER,
            arrow,
            egui::FontId::proportional(96.0),
            egui::Color32::from_rgba_unmultiplied(240, 190, 90, 200),
        );
    }
    Ok(())
}
