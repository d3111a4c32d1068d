//! The kiosk flow (`Attract` -> `Calibrate` -> `TryOn`, back to `Attract` when the person
//! leaves), the camera that frames the person, and the egui status overlay.

use bevy::prelude::*;
use fitroom_body::plugin::Avatar;
use fitroom_body::twin::TwinAvatar;
use fitroom_motion::plugin::{AvatarMotion, MotionSystems};
use fitroom_schedule::FitroomSystems;
use fitroom_sensor::{KinectJoint, plugin::SensorFeed};

/// Kiosk screens.
#[derive(States, Default, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum KioskState {
    /// Nobody in front of the mirror.
    #[default]
    Attract,
    /// A person stepped in: hold still while we measure.
    Calibrate,
    /// Browse garments and sizes.
    TryOn,
}

impl KioskState {
    pub fn label(self) -> &'static str {
        match self {
            KioskState::Attract => "Attract: step in front of the mirror",
            KioskState::Calibrate => "Calibrate: stand still with arms slightly apart",
            KioskState::TryOn => "Try on",
        }
    }
}

/// Timing of the kiosk flow (live-editable).
#[derive(Resource, Debug, Clone, Copy, Reflect)]
#[reflect(Resource)]
pub struct KioskTimings {
    /// Seconds a person must be tracked in `Calibrate` before `TryOn`.
    pub calibrate_s: f32,
    /// Seconds without a tracked person before going back to `Attract`.
    pub lost_s: f32,
    /// Seconds `Calibrate` tries to measure the person before going on unmeasured.
    pub measure_s: f32,
}

impl Default for KioskTimings {
    fn default() -> Self {
        Self {
            calibrate_s: 2.0,
            lost_s: 3.0,
            measure_s: 12.0,
        }
    }
}

/// What the kiosk knows about the person.
#[derive(Resource, Debug, Default)]
pub struct KioskStatus {
    /// Seconds the current person has been tracked without a gap.
    pub tracked_s: f32,
    /// Seconds since the last tracked frame.
    pub untracked_s: f32,
    /// Seconds spent in the current state.
    pub in_state_s: f32,
    /// Whether the last sensor frame showed a person, and the seconds since it came.
    pub person_in_last_frame: bool,
    pub since_frame_s: f32,
}

/// Whether the raw and filtered sensor skeletons are drawn over the avatar (key D).
#[derive(Resource, Debug, Default)]
pub struct DebugSkeletons(pub bool);

fn toggle_debug_skeletons(
    keys: Option<Res<ButtonInput<KeyCode>>>,
    mut debug: ResMut<DebugSkeletons>,
) {
    if keys.is_some_and(|k| k.just_pressed(KeyCode::KeyD)) {
        debug.0 = !debug.0;
    }
}

/// Debug skeletons are drawn over the avatar, not hidden inside it.
fn skeletons_on_top(mut store: ResMut<bevy::gizmos::config::GizmoConfigStore>) {
    let (config, _) = store.config_mut::<bevy::gizmos::config::DefaultGizmoConfigGroup>();
    config.depth_bias = -1.0;
    config.line.width = 3.0;
}

/// Draws the last raw and filtered Kinect skeletons in world space.
fn draw_debug_skeletons(
    debug: Res<DebugSkeletons>,
    motion: Option<Res<AvatarMotion>>,
    avatar: Query<&Transform, With<Avatar>>,
    mut gizmos: Gizmos,
) {
    let (true, Some(motion), Ok(avatar)) = (debug.0, motion, avatar.single()) else {
        return;
    };
    let frames = [
        (motion.last_raw.as_ref(), Color::srgb(0.95, 0.25, 0.2)),
        (motion.last_filtered.as_ref(), Color::srgb(0.2, 0.9, 0.35)),
    ];
    for (frame, color) in frames {
        let Some(frame) = frame else { continue };
        for joint in KinectJoint::ALL {
            let Some(parent) = joint.parent() else {
                continue;
            };
            let a = avatar.transform_point(frame.joint(parent).position);
            let b = avatar.transform_point(frame.joint(joint).position);
            if a.is_finite() && b.is_finite() {
                gizmos.line(a, b, color);
            }
        }
    }
}

/// Marks the camera that frames the person.
#[derive(Component)]
pub struct MirrorCamera;

/// The mirrored kiosk camera's scale: -1 along its own x.
pub const MIRRORED: Vec3 = Vec3::new(-1.0, 1.0, 1.0);

/// Seen through a mirrored camera every triangle's winding is reversed, so the faces a
/// material culls as back faces are its front ones, and a double-sided material would light
/// its front faces as back faces (dark): the kiosk's materials draw both faces, lit by their
/// own normals (the body is closed and the depth test hides its inside; a garment's inside,
/// seen at a hem, is lit as its outside).
pub fn show_both_faces(
    mut events: MessageReader<AssetEvent<StandardMaterial>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    for event in events.read() {
        if let AssetEvent::Added { id } = event
            && let Some(mut material) = materials.get_mut(*id)
            && (material.cull_mode.is_some() || material.double_sided)
        {
            material.cull_mode = None;
            material.double_sided = false;
        }
    }
}

/// Systems of the kiosk plugin.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub enum KioskSystems {
    /// The camera follows the posed avatar (stage `Pose`, after the pose is applied, so the
    /// camera is propagated with it in the same frame).
    FrameCamera,
    /// Whether a person is there, and the kiosk's state transitions (stage `Ui`).
    Flow,
    /// Debug drawing (stage `Ui`, after the flow).
    Debug,
}

/// The kiosk flow, the camera, and the configuration file (`config`, read from
/// `config_path`, then followed for edits through the asset source [`config::CONFIG_SOURCE`],
/// which the app registers on the file's folder with [`config::register_config_source`]).
pub struct KioskPlugin {
    pub config: config::KioskConfig,
    pub config_path: std::path::PathBuf,
}

impl Plugin for KioskPlugin {
    fn build(&self, app: &mut App) {
        fitroom_schedule::ensure(app);
        let folder = self
            .config_path
            .parent()
            .map(std::path::Path::to_path_buf)
            .unwrap_or_default();
        let mut active = config::ActiveKioskConfig {
            config: self.config.clone(),
            folder,
            handle: None,
            error: None,
        };
        if app.world().contains_resource::<AssetServer>() {
            let (root, file) = config::config_location(&self.config_path);
            app.init_asset::<config::KioskConfig>()
                .register_asset_loader(config::KioskConfigLoader { root })
                .add_systems(
                    PostUpdate,
                    config::follow_config
                        .in_set(KioskSystems::Flow)
                        .before(track_person),
                );
            let path =
                bevy::asset::AssetPath::from_path_buf(file).with_source(config::CONFIG_SOURCE);
            active.handle = Some(app.world().resource::<AssetServer>().load(path));
        }
        app.init_state::<KioskState>()
            .insert_resource(self.config.kiosk_timings())
            .insert_resource(active)
            .register_type::<KioskTimings>()
            .init_resource::<KioskStatus>()
            .init_resource::<DebugSkeletons>()
            .configure_sets(
                PostUpdate,
                (
                    KioskSystems::FrameCamera
                        .in_set(FitroomSystems::Pose)
                        .after(MotionSystems::ApplyPose),
                    (KioskSystems::Flow, KioskSystems::Debug)
                        .chain()
                        .in_set(FitroomSystems::Ui),
                ),
            )
            .add_systems(Update, toggle_debug_skeletons)
            .add_systems(
                PostUpdate,
                (
                    frame_person.in_set(KioskSystems::FrameCamera),
                    (track_person, kiosk_transitions)
                        .chain()
                        .in_set(KioskSystems::Flow),
                ),
            );
        measure::add(app);
        actions::add(app);
        if app.is_plugin_added::<bevy::gizmos::GizmoPlugin>() {
            app.add_systems(Startup, skeletons_on_top)
                .add_systems(PostUpdate, draw_debug_skeletons.in_set(KioskSystems::Debug));
        }
    }
}

fn track_person(time: Res<Time>, feed: Res<SensorFeed>, mut status: ResMut<KioskStatus>) {
    let dt = time.delta_secs();
    // Frames come at 30 Hz and updates may be faster: between frames the last frame's word
    // holds, for as long as a frame period and a half.
    if !feed.new_frames.is_empty() {
        status.person_in_last_frame = feed.new_frames.iter().any(|f| {
            let hip = f.joint(KinectJoint::HipCenter);
            hip.confidence > 0.5 && hip.position.is_finite()
        });
        status.since_frame_s = 0.0;
    } else {
        status.since_frame_s += dt;
    }
    if status.person_in_last_frame && status.since_frame_s < 0.05 {
        status.tracked_s += dt;
        status.untracked_s = 0.0;
    } else {
        status.untracked_s += dt;
        // Only a real gap resets tracking.
        if status.untracked_s > 0.5 {
            status.tracked_s = 0.0;
        }
    }
    status.in_state_s += dt;
}

pub(crate) fn kiosk_transitions(
    state: Res<State<KioskState>>,
    mut next: ResMut<NextState<KioskState>>,
    timings: Res<KioskTimings>,
    mut status: ResMut<KioskStatus>,
    mut motion: Option<ResMut<AvatarMotion>>,
    measuring: measure::Measuring,
) {
    let person_present = status.untracked_s < timings.lost_s && status.tracked_s > 0.0;
    // With depth, Calibrate waits for the measurement (or gives up on it after
    // `measure_s`); with a skeleton only, there is nothing to measure.
    let calibrated = status.tracked_s >= timings.calibrate_s
        && (!measuring.possible() || measuring.done() || status.in_state_s >= timings.measure_s);
    let target = match state.get() {
        KioskState::Attract if person_present => Some(KioskState::Calibrate),
        KioskState::Calibrate if calibrated => Some(KioskState::TryOn),
        KioskState::Calibrate | KioskState::TryOn if status.untracked_s >= timings.lost_s => {
            Some(KioskState::Attract)
        }
        _ => None,
    };
    if let Some(target) = target {
        info!("kiosk: {:?} -> {:?}", state.get(), target);
        if target == KioskState::Attract
            && let Some(motion) = motion.as_mut()
        {
            // The next person is a new user: calibrate again (Algorithm 1, line 10).
            motion.reset();
        }
        next.set(target);
        status.in_state_s = 0.0;
    }
}

/// The avatar's pelvis in world space, if there is an avatar with a pose.
pub(super) fn pelvis_world(motion: &AvatarMotion, avatar: &Transform) -> Option<Vec3> {
    let pelvis = motion.pipeline.skeleton().index_of("pelvis")?;
    let head = *motion.pose.heads.get(pelvis)?;
    Some(avatar.transform_point(head)).filter(|p| p.is_finite())
}

/// Where the camera settles to frame a person whose pelvis is at `pelvis`: in front of them,
/// a little above, looking at their middle (between them and their twin, when it is there).
fn framing(pelvis: Vec3, twin: Option<&TwinAvatar>) -> Transform {
    let beside = twin.map_or(Vec3::ZERO, |t| 0.5 * t.offset);
    // Below the middle of the body: the person stands in the upper part of the screen,
    // clear of the try-on panel at the bottom.
    let focus = Vec3::new(pelvis.x + beside.x, 0.8, pelvis.z + beside.z);
    Transform::from_translation(focus + Vec3::new(0.0, 0.25, 3.4)).looking_at(focus, Vec3::Y)
}

/// Keeps the person framed, following them smoothly so a walk across the room stays in view.
fn frame_person(
    time: Res<Time>,
    avatar: Query<&Transform, (With<Avatar>, Without<MirrorCamera>)>,
    motion: Option<Res<AvatarMotion>>,
    twin: Option<Res<TwinAvatar>>,
    mut camera: Query<&mut Transform, With<MirrorCamera>>,
) {
    let (Some(motion), Ok(avatar)) = (motion, avatar.single()) else {
        return;
    };
    let Some(pelvis) = pelvis_world(&motion, avatar) else {
        return;
    };
    let target = framing(pelvis, twin.as_deref());
    let blend = 1.0 - (-3.0 * time.delta_secs()).exp();
    for mut transform in &mut camera {
        transform.translation = transform.translation.lerp(target.translation, blend);
        transform.rotation = transform.rotation.slerp(target.rotation, blend);
    }
}

/// Places the camera at once where [`frame_person`] would settle (used before screenshots).
pub fn snap_camera(world: &mut World) {
    let mut avatars = world.query_filtered::<&Transform, With<Avatar>>();
    let Ok(avatar) = avatars.single(world).copied() else {
        return;
    };
    let Some(pelvis) = world
        .get_resource::<AvatarMotion>()
        .and_then(|m| pelvis_world(m, &avatar))
    else {
        return;
    };
    let twin = world.get_resource::<TwinAvatar>().copied();
    let mut cameras = world.query_filtered::<&mut Transform, With<MirrorCamera>>();
    for mut transform in cameras.iter_mut(world) {
        let framed = framing(pelvis, twin.as_ref());
        transform.translation = framed.translation;
        transform.rotation = framed.rotation;
    }
}

pub mod actions;
pub mod compare;
pub mod config;
pub mod depth_view;
pub mod guide;
pub mod measure;
pub mod thumbnails;
pub mod tryon_ui;
pub mod ui;
