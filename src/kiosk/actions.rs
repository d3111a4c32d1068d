//! Kiosk actions as data (as leafwing-input-manager does): the keyboard, the mouse wheel,
//! touch swipes and taps, and hand gestures all produce [`KioskAction`] messages; the try-on
//! screen reads actions only, never devices.
//!
//! In `TryOn`: `Next` / `Previous` turn the carousel of the configuration's garments,
//! `Select` dresses the avatar in the garment shown, `Back` returns the carousel to the one
//! worn, `SizeUp` / `SizeDown` step through the garment's sizes, `ToggleFitMap` colours the
//! garment by its strain, `Compare` shows the avatar's twin beside it in the next size
//! ([`super::compare`]), `Photo` saves a PNG of the screen. An avatar that wears nothing
//! wears the carousel's garment (the configuration's first), from the start: the mirror in
//! `Attract` shows a dressed mannequin, not a bare one.

use std::path::PathBuf;

use bevy::input::mouse::MouseWheel;
use bevy::input::touch::Touches;
use bevy::prelude::*;
use fitroom_garment::asset::GarmentAsset;
use fitroom_garment::plugin::{ClothSettings, GarmentRequest, GarmentStatus};
use fitroom_gesture::plugin::GestureEvent;
use fitroom_gesture::swipe::SwipeDirection;

use super::KioskState;
use super::config::ActiveKioskConfig;

/// What the person asks the kiosk to do.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum KioskAction {
    Next,
    Previous,
    Select,
    Back,
    SizeUp,
    SizeDown,
    ToggleFitMap,
    Compare,
    Photo,
}

impl KioskAction {
    /// The keys of each action.
    pub const KEYS: [(KeyCode, KioskAction); 13] = [
        (KeyCode::ArrowRight, KioskAction::Next),
        (KeyCode::ArrowLeft, KioskAction::Previous),
        (KeyCode::Enter, KioskAction::Select),
        (KeyCode::Space, KioskAction::Select),
        (KeyCode::Escape, KioskAction::Back),
        (KeyCode::Backspace, KioskAction::Back),
        (KeyCode::ArrowUp, KioskAction::SizeUp),
        (KeyCode::Equal, KioskAction::SizeUp),
        (KeyCode::ArrowDown, KioskAction::SizeDown),
        (KeyCode::Minus, KioskAction::SizeDown),
        (KeyCode::KeyF, KioskAction::ToggleFitMap),
        (KeyCode::KeyV, KioskAction::Compare),
        (KeyCode::KeyC, KioskAction::Photo),
    ];
}

/// The try-on screen's state.
#[derive(Resource, Debug, Default, Clone)]
pub struct TryOn {
    /// The carousel's garment (index into the configuration's garments).
    pub shown: usize,
    /// The garment worn (index), once one is.
    pub worn: Option<usize>,
    /// Two sizes side by side: the avatar's twin wears the neighbouring size.
    pub compare: bool,
    /// The last photo saved, or why none could be.
    pub photo: Option<String>,
    /// The folder photos go to.
    pub photo_dir: PathBuf,
    /// Leave a bare avatar bare (recordings and evaluations of an undressed person); else
    /// [`dress_when_bare`] dresses it.
    pub keep_bare: bool,
}

pub fn add(app: &mut App) {
    // The wheel's and the gestures' messages exist in every app (headless ones have no
    // mouse, a kiosk without depth no gesture plugin): registering them here is a no-op
    // where their plugins did, and their readers need them.
    app.add_message::<KioskAction>()
        .add_message::<MouseWheel>()
        .add_message::<GestureEvent>()
        .insert_resource(TryOn {
            photo_dir: PathBuf::from("photos"),
            ..default()
        })
        .add_systems(
            Update,
            (
                start_actions,
                keyboard_actions,
                wheel_actions,
                touch_actions,
                gesture_actions,
            )
                .chain(),
        )
        .add_systems(
            PostUpdate,
            (
                dress_when_bare,
                apply_actions,
                super::compare::follow_compare,
            )
                .chain()
                .in_set(super::KioskSystems::Flow)
                .after(super::kiosk_transitions),
        );
}

/// Actions performed once, as soon as the avatar wears its first garment in `TryOn`
/// (`fitroom kiosk --actions`: demos and screenshots of the try-on screen's modes).
#[derive(Resource, Debug, Clone, Default)]
pub struct StartActions(pub Vec<KioskAction>);

fn start_actions(
    start: Option<ResMut<StartActions>>,
    state: Res<State<KioskState>>,
    status: Res<GarmentStatus>,
    mut out: MessageWriter<KioskAction>,
) {
    let Some(mut start) = start else { return };
    if *state.get() == KioskState::TryOn && status.worn.is_some() && !start.0.is_empty() {
        out.write_batch(start.0.drain(..));
    }
}

fn keyboard_actions(keys: Option<Res<ButtonInput<KeyCode>>>, mut out: MessageWriter<KioskAction>) {
    let Some(keys) = keys else { return };
    for (key, action) in KioskAction::KEYS {
        if keys.just_pressed(key) {
            out.write(action);
        }
    }
}

fn wheel_actions(wheel: Option<MessageReader<MouseWheel>>, mut out: MessageWriter<KioskAction>) {
    // Headless runs have no mouse.
    let Some(mut wheel) = wheel else { return };
    for w in wheel.read() {
        if w.y < 0.0 {
            out.write(KioskAction::Next);
        } else if w.y > 0.0 {
            out.write(KioskAction::Previous);
        }
    }
}

/// A touch that ends 80 px or more sideways from where it began is a swipe (the finger's
/// way), a short one a tap (select).
fn touch_actions(touches: Option<Res<Touches>>, mut out: MessageWriter<KioskAction>) {
    let Some(touches) = touches else { return };
    for t in touches.iter_just_released() {
        let moved = t.position() - t.start_position();
        if moved.x.abs() >= 80.0 && moved.x.abs() > moved.y.abs() {
            out.write(if moved.x > 0.0 {
                KioskAction::Next
            } else {
                KioskAction::Previous
            });
        } else if moved.length() < 20.0 {
            out.write(KioskAction::Select);
        }
    }
}

/// A swipe to the person's right shows the next garment, to the left the previous; a grip
/// selects.
fn gesture_actions(mut gestures: MessageReader<GestureEvent>, mut out: MessageWriter<KioskAction>) {
    for g in gestures.read() {
        match g {
            GestureEvent::Swipe(SwipeDirection::Right) => {
                out.write(KioskAction::Next);
            }
            GestureEvent::Swipe(SwipeDirection::Left) => {
                out.write(KioskAction::Previous);
            }
            GestureEvent::Press => {
                out.write(KioskAction::Select);
            }
            GestureEvent::Release => {}
        }
    }
}

/// The configuration's garment `index` as a request (its file from the configuration's
/// folder).
fn garment_request(config: &ActiveKioskConfig, index: usize) -> Option<GarmentRequest> {
    let entry = config.config.garments.get(index)?;
    Some(GarmentRequest {
        path: Some(config.folder.join(&entry.file)),
        size: entry.size.clone(),
        // The twin's size follows once the garment's sizes are known.
        compare: None,
    })
}

/// An avatar that wears nothing (and never did here) wears the carousel's garment, in any
/// state (the first visitor meets a dressed mannequin, as every later one does).
fn dress_when_bare(
    config: Res<ActiveKioskConfig>,
    mut tryon: ResMut<TryOn>,
    mut request: ResMut<GarmentRequest>,
) {
    if request.path.is_some() || tryon.worn.is_some() || tryon.keep_bare {
        return;
    }
    if let Some(r) = garment_request(&config, tryon.shown) {
        *request = r;
        tryon.worn = Some(tryon.shown);
    }
}

// A Bevy system: each parameter is what one action touches.
#[allow(clippy::too_many_arguments)]
fn apply_actions(
    mut commands: Commands,
    mut actions: MessageReader<KioskAction>,
    state: Res<State<KioskState>>,
    config: Res<ActiveKioskConfig>,
    mut tryon: ResMut<TryOn>,
    mut request: ResMut<GarmentRequest>,
    mut cloth: ResMut<ClothSettings>,
    status: Res<GarmentStatus>,
    garments: Res<Assets<GarmentAsset>>,
) {
    let count = config.config.garments.len();
    for action in actions.read() {
        if *state.get() != KioskState::TryOn {
            continue;
        }
        match action {
            KioskAction::Next if count > 0 => tryon.shown = (tryon.shown + 1) % count,
            KioskAction::Previous if count > 0 => tryon.shown = (tryon.shown + count - 1) % count,
            KioskAction::Select => {
                if let Some(r) = garment_request(&config, tryon.shown) {
                    info!("kiosk: wear garment {} ({:?})", tryon.shown + 1, r.path);
                    *request = r;
                    tryon.worn = Some(tryon.shown);
                }
            }
            KioskAction::Back => {
                if let Some(worn) = tryon.worn {
                    tryon.shown = worn;
                }
            }
            KioskAction::SizeUp | KioskAction::SizeDown => {
                let sizes = garment_sizes(&status, &garments);
                let now = size_worn(&request, &status);
                let at = now.and_then(|s| sizes.iter().position(|x| *x == s));
                let next = match (action, at) {
                    (KioskAction::SizeUp, Some(i)) => (i + 1).min(sizes.len().saturating_sub(1)),
                    (KioskAction::SizeDown, Some(i)) => i.saturating_sub(1),
                    _ => sizes.len() / 2,
                };
                if let Some(size) = sizes.get(next) {
                    request.size = Some(size.clone());
                }
            }
            KioskAction::ToggleFitMap => cloth.fit_map = !cloth.fit_map,
            KioskAction::Compare => tryon.compare = !tryon.compare,
            KioskAction::Photo => {
                let stamp = std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_secs());
                let path = tryon.photo_dir.join(format!("fitroom-{stamp}.png"));
                match std::fs::create_dir_all(&tryon.photo_dir) {
                    Ok(()) => {
                        commands
                            .spawn(bevy::render::view::screenshot::Screenshot::primary_window())
                            .observe(bevy::render::view::screenshot::save_to_disk(path.clone()));
                        tryon.photo = Some(format!("photo saved: {}", path.display()));
                    }
                    Err(e) => {
                        tryon.photo = Some(format!(
                            "no photo: cannot create '{}': {e}",
                            tryon.photo_dir.display()
                        ));
                    }
                }
            }
            _ => {}
        }
    }
}

/// The size the avatar wears or is about to: the one requested, or the one worn (the
/// garment's middle size when none was requested).
pub(super) fn size_worn(request: &GarmentRequest, status: &GarmentStatus) -> Option<String> {
    request
        .size
        .clone()
        .or_else(|| status.worn_size().map(str::to_owned))
}

/// The labels of the worn garment's sizes, smallest first (none before it is loaded).
pub(super) fn garment_sizes(
    status: &GarmentStatus,
    garments: &Assets<GarmentAsset>,
) -> Vec<String> {
    let Some(source) = status.asset.as_ref().and_then(|h| garments.get(h)) else {
        return Vec::new();
    };
    match fitroom_measure::garment_size::garment_chart(&source.0) {
        Ok(chart) => chart.sizes.into_iter().map(|s| s.label).collect(),
        Err(_) => Vec::new(),
    }
}
