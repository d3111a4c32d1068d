//! The picture-in-picture depth view: the newest depth frame, colour-mapped (near warm, far
//! cool, black where the sensor has no reading), the person the segmentation found tinted
//! pale and the skeleton the tracker fitted drawn on them (green: tracked, yellow: inferred),
//! in the screen's bottom-right corner with its source and state. Shown or hidden with its button (and the P key); a depth source's
//! error (a vanished Kinect, an unreadable frame) is written under the last good frame.

use bevy::asset::RenderAssetUsages;
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, EguiTextureHandle, egui};
use fitroom_depth::plugin::DepthFeed;
use fitroom_depth::{HEIGHT, WIDTH};
use fitroom_sensor::KinectJoint;
use fitroom_tracker::TrackedJointOut;
use fitroom_tracker::draw::{confidence_colour, draw_skeleton};
use fitroom_tracker::plugin::{TrackedSkeleton, UserMap};

/// Whether the view is shown, and its image: one Bevy image written in place per depth
/// frame (an egui-managed texture set every frame is a new GPU texture every frame, never
/// ready when the overlay is drawn).
#[derive(Resource)]
pub struct DepthView {
    pub shown: bool,
    image: Option<(Handle<Image>, egui::TextureId)>,
    /// The feed's frame count when the image was last written.
    shown_frame: u64,
    rgb: Vec<u8>,
}

impl Default for DepthView {
    fn default() -> Self {
        Self {
            shown: true,
            image: None,
            shown_frame: u64::MAX,
            rgb: Vec::new(),
        }
    }
}

/// The depths the colours span, millimetres: the camera's range.
const NEAR_MM: u16 = 800;
const FAR_MM: u16 = 4000;

pub struct DepthViewPlugin;

impl Plugin for DepthViewPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<DepthView>()
            .add_systems(Update, toggle_with_key)
            .add_systems(EguiPrimaryContextPass, depth_view);
    }
}

fn toggle_with_key(keys: Option<Res<ButtonInput<KeyCode>>>, mut view: ResMut<DepthView>) {
    if keys.is_some_and(|k| k.just_pressed(KeyCode::KeyP)) {
        view.shown = !view.shown;
    }
}

fn depth_view(
    mut contexts: EguiContexts,
    feed: Option<Res<DepthFeed>>,
    user: Option<Res<UserMap>>,
    skeleton: Option<Res<TrackedSkeleton>>,
    mut view: ResMut<DepthView>,
    mut images: ResMut<Assets<Image>>,
) -> Result {
    let Some(feed) = feed else { return Ok(()) };
    if view.shown
        && view.shown_frame != feed.frames_received
        && let Some(frame) = &feed.latest
    {
        let view = &mut *view;
        fitroom_depth::colour::colourise(&frame.depth_mm, NEAR_MM, FAR_MM, &mut view.rgb);
        // The person the segmentation found, tinted white, when it is of this frame.
        let current_user = user.as_ref().filter(|u| u.frame == feed.frames_received);
        let mask = current_user
            .and_then(|u| u.person.as_ref())
            .map(|p| &p.mask);
        // The skeleton is of the same frame as the map (one system makes both).
        let joints = current_user
            .and(skeleton.as_ref())
            .and_then(|s| s.latest.as_ref())
            .map(|t| t.joints);
        let current = view.image.as_ref().map(|(handle, _)| handle.clone());
        let exists = current.as_ref().is_some_and(|h| images.contains(h));
        match current {
            Some(handle) if exists => {
                if let Some(mut image) = images.get_mut(&handle) {
                    // The image's own buffer, refilled: nothing allocated per frame.
                    let mut data = image.data.take().unwrap_or_default();
                    to_rgba(&view.rgb, mask, &mut data);
                    if let Some(joints) = &joints {
                        draw_tracked(joints, &mut data);
                    }
                    image.data = Some(data);
                }
            }
            _ => {
                let mut rgba = Vec::new();
                to_rgba(&view.rgb, mask, &mut rgba);
                if let Some(joints) = &joints {
                    draw_tracked(joints, &mut rgba);
                }
                let image = Image::new(
                    Extent3d {
                        width: WIDTH as u32,
                        height: HEIGHT as u32,
                        depth_or_array_layers: 1,
                    },
                    TextureDimension::D2,
                    rgba,
                    TextureFormat::Rgba8UnormSrgb,
                    RenderAssetUsages::default(),
                );
                let handle = images.add(image);
                let id = contexts.add_image(EguiTextureHandle::Strong(handle.clone()));
                view.image = Some((handle, id));
            }
        }
        view.shown_frame = feed.frames_received;
    }
    let texture = view.image.as_ref().map(|(_, id)| *id);
    let ctx = contexts.ctx_mut()?;
    egui::Area::new(egui::Id::new("depth-view"))
        // Top right: clear of the try-on panel at the bottom and of the avatars' heads.
        .anchor(egui::Align2::RIGHT_TOP, egui::vec2(-16.0, 16.0))
        .show(ctx, |ui| {
            egui::Frame::popup(ui.style()).show(ui, |ui| {
                ui.set_max_width(IMAGE.x);
                ui.horizontal_wrapped(|ui| {
                    let label = if view.shown {
                        "hide depth"
                    } else {
                        "show depth"
                    };
                    if ui.button(label).clicked() {
                        view.shown = !view.shown;
                    }
                    ui.label(format!(
                        "depth: {} ({} frames)",
                        feed.source_name, feed.frames_received
                    ));
                    if let Some(user) = user.as_ref() {
                        ui.label(match &user.person {
                            Some(p) => format!(
                                "person: {} px at {:.1} m ({:.1} ms)",
                                p.pixels, p.centroid.z, user.track_ms
                            ),
                            None => "nobody in view".into(),
                        });
                    }
                });
                if view.shown {
                    match texture {
                        Some(texture) => {
                            ui.image((texture, IMAGE));
                        }
                        None => {
                            ui.label("waiting for the first depth frame…");
                        }
                    }
                }
                if let Some(error) = &feed.error {
                    ui.colored_label(egui::Color32::from_rgb(230, 80, 60), error);
                }
            });
        });
    Ok(())
}

/// The depth image's size on screen (a quarter of the sensor's pixels: a glance, not a study).
const IMAGE: egui::Vec2 = egui::vec2(256.0, 192.0);

/// `rgb` as RGBA into `out`, the person's pixels (`mask`) tinted halfway to white.
fn to_rgba(rgb: &[u8], mask: Option<&Vec<bool>>, out: &mut Vec<u8>) {
    out.clear();
    out.reserve(rgb.len() / 3 * 4);
    let tint = |c: u8| ((u16::from(c) + 255) / 2) as u8;
    for (k, p) in rgb.chunks_exact(3).enumerate() {
        let pixel = match mask {
            Some(mask) if mask.get(k).copied().unwrap_or(false) => {
                [tint(p[0]), tint(p[1]), tint(p[2]), 255]
            }
            _ => [p[0], p[1], p[2], 255],
        };
        out.extend_from_slice(&pixel);
    }
}

/// The tracked skeleton on the RGBA depth image (green: tracked, yellow: inferred).
fn draw_tracked(joints: &[TrackedJointOut; KinectJoint::COUNT], rgba: &mut [u8]) {
    let pixels: Vec<[f32; 2]> = joints.iter().map(|j| j.pixel).collect();
    draw_skeleton(rgba, 4, &pixels, |k| {
        confidence_colour(joints[k].confidence)
    });
}
