//! fitroom: a virtual fitting room. This crate wires the plugins into an `App` for each mode
//! (the kiosk window, headless runs with or without offscreen rendering) and holds the CLI's
//! commands; the logic lives in the `plugins/` crates.

#![forbid(unsafe_code)]

pub mod assets;
pub mod body_panel;
pub mod cli;
pub mod depth_scene;
pub mod design;
pub mod headless;
pub mod kiosk;
pub mod performer;
pub mod sensors;
pub mod thumbnail;
pub mod timing;

use std::{path::PathBuf, sync::Arc, time::Duration};

use anyhow::{Context, Result, bail};
use bevy::{
    app::ScheduleRunnerPlugin,
    prelude::*,
    state::app::StatesPlugin,
    time::TimeUpdateStrategy,
    window::{ExitCondition, WindowMode},
    winit::WinitPlugin,
};
use fitroom_body::{
    BodyModel, Shape,
    plugin::{AvatarBody, AvatarShape, BodyPlugin, SensorPlacement},
};
use fitroom_garment::plugin::{ClothSettings, GarmentPlugin, GarmentRequest};
use fitroom_gesture::script::{GestureScript, ScriptedPerson};
use fitroom_motion::{
    AvatarPipeline, MotionPipeline,
    plugin::{AvatarMotion, FilterSettings, MotionPlugin},
};
use fitroom_sensor::{
    SensorSource,
    bvh::BvhClip,
    bvh_source::{BvhSource, BvhSourceOptions},
    noise::NoisySource,
    plugin::{ActiveSensor, SensorFeed, SensorPlugin},
};

/// How the app runs.
#[derive(Clone, Debug, PartialEq)]
pub enum Mode {
    /// The mirror kiosk in a window (full screen unless `windowed`).
    Kiosk { windowed: bool },
    /// No window. With `render`, an offscreen camera renders on any Vulkan adapter.
    Headless { render: bool },
    /// The garment designer in a window: an orbit camera and the design panel.
    Design,
}

/// What to load.
#[derive(Clone, Debug)]
pub struct AppOptions {
    pub mode: Mode,
    /// The converted body (`assets/bodies/makehuman.fitbody` by default).
    pub body: PathBuf,
    /// Where frames come from (the kiosk configuration's `sensor` by default).
    pub sensor: sensors::SensorSpec,
    /// The motion clip that drives the avatar with a `bvh:` or `synthetic` sensor (the
    /// configuration's clip, else `assets/motions/walk.bvh`).
    pub motion: PathBuf,
    /// Seed of the synthetic depth camera's noise.
    pub depth_seed: u64,
    /// The performer's distance from the sensor at the clip's first frame, metres.
    pub distance_m: f32,
    /// Replay the clip on the spot (the hip centre kept at its first-frame x and z): see
    /// [`BvhSourceOptions::treadmill`].
    pub treadmill: bool,
    /// How a `fakenect:DIR` recording is played.
    pub replay: sensors::Replay,
    /// What else the synthetic camera sees (a box, a second person).
    pub extras: depth_scene::Extras,
    /// Offscreen image size for headless rendering.
    pub image_size: UVec2,
    /// Replay the motion through the Kinect v1 noise model with this seed (`None`: clean).
    pub noise_seed: Option<u64>,
    /// The avatar's body shape (`None`: MakeHuman's default body).
    pub shape: Option<Shape>,
    /// Where the body panel saves the shape (`shape.ron` by default).
    pub shape_path: PathBuf,
    /// Open the body panel at start.
    pub body_panel: bool,
    /// The garment the avatar wears (a pattern `.ron`), and its size.
    pub garment: Option<PathBuf>,
    pub garment_size: Option<String>,
    /// Colour the garment by strain.
    pub fit_map: bool,
    /// The kiosk configuration (`assets/kiosk.ron` by default) and where it was read from.
    pub config: kiosk::config::KioskConfig,
    pub config_path: PathBuf,
}

impl AppOptions {
    /// The options of the kiosk configuration `assets/kiosk.ron` (its clip drives the
    /// avatar).
    pub fn with_defaults(mode: Mode) -> Result<Self> {
        let assets = assets::assets_dir()?;
        Self::with_config(mode, &assets.join(kiosk::config::DEFAULT_CONFIG))
    }

    /// The options of a kiosk configuration file.
    pub fn with_config(mode: Mode, config_path: &std::path::Path) -> Result<Self> {
        let assets = assets::assets_dir()?;
        let config = kiosk::config::KioskConfig::load(config_path)?;
        let motion = config.sensor_clip().map_or_else(
            || assets.join(assets::DEFAULT_MOTION),
            |clip| assets.join(clip),
        );
        // The clip, resolved against the assets folder.
        let sensor = config.sensor_spec()?.with_clip(&motion);
        Ok(Self {
            mode,
            body: assets.join(assets::DEFAULT_BODY),
            sensor,
            motion,
            depth_seed: 1,
            distance_m: BvhSourceOptions::default().start_distance_m,
            treadmill: config.treadmill,
            replay: sensors::Replay::default(),
            extras: depth_scene::Extras::default(),
            image_size: UVec2::new(960, 720),
            noise_seed: None,
            shape: None,
            shape_path: PathBuf::from("shape.ron"),
            body_panel: false,
            garment: None,
            garment_size: None,
            fit_map: false,
            config,
            config_path: config_path.to_owned(),
        })
    }
}

/// Whether `motion` names a gesture script (a `.ron` file) rather than a clip.
pub fn is_gesture_script(motion: &std::path::Path) -> bool {
    motion
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ron"))
}

/// The background colour of the room (used by the screenshot test to find the avatar).
pub const BACKGROUND: Color = Color::srgb(0.10, 0.11, 0.14);

/// Loads the body and motion named by `options` and builds the app.
pub fn build_app(options: &AppOptions) -> Result<App> {
    let load_start = std::time::Instant::now();
    let model = BodyModel::read(&options.body).with_context(|| {
        format!(
            "cannot load the body '{}'; run `fitroom import makehuman DIR` (DIR: the MakeHuman data, e.g. MakeHuman's MPFB2 asset folder) to create it",
            options.body.display()
        )
    })?;
    let body_load_ms = load_start.elapsed().as_secs_f64() * 1e3;
    let source_options = BvhSourceOptions {
        start_distance_m: options.distance_m,
        treadmill: options.treadmill,
        ..BvhSourceOptions::default()
    };
    // A gesture script (`.ron`) is performed by the `performer` sensor; a clip is replayed.
    let script = if is_gesture_script(&options.motion) {
        if !matches!(options.sensor, sensors::SensorSpec::Performer(_)) {
            bail!(
                "'{}' is a gesture script: only the performer performs one (`--sensor performer:{}`); `bvh:` and `synthetic` replay a .bvh clip",
                options.motion.display(),
                options.motion.display()
            );
        }
        Some(GestureScript::load(&options.motion)?)
    } else {
        None
    };
    let source = match script {
        Some(_) => None,
        None => {
            let clip = BvhClip::load(&options.motion).with_context(|| {
                format!("cannot load the motion '{}'", options.motion.display())
            })?;
            Some(
                BvhSource::from_clip(clip, source_options)
                    .with_context(|| format!("cannot replay '{}'", options.motion.display()))?,
            )
        }
    };
    let model = Arc::new(model);
    let shape = options.shape.clone().unwrap_or_default();
    let body = match &options.shape {
        Some(s) => AvatarBody::shaped(
            model.clone(),
            model
                .shaped(s)
                .context("cannot shape the body with the given shape")?,
        ),
        None => AvatarBody::unshaped(model.clone()),
    };
    let skeleton = fitroom_motion::avatar_skeleton(&model, &body.rest)?;
    let sensor_height_m = source.as_ref().map_or(source_options.sensor_height_m, |s| {
        s.options().sensor_height_m
    });
    let floor_y = -sensor_height_m;
    let motion = AvatarMotion::new(MotionPipeline::new(
        AvatarPipeline::new(&skeleton, floor_y)?,
        FilterSettings::default().filter.build(),
    ));

    let placement = SensorPlacement { sensor_height_m };
    let source: Option<Box<dyn SensorSource>> = source.map(|source| match options.noise_seed {
        Some(seed) => Box::new(NoisySource::new(
            source,
            &fitroom_motion::eval::evaluation_noise(),
            seed,
        )) as Box<dyn SensorSource>,
        None => Box::new(source),
    });
    // A depth-only source (a recording, a Kinect) has no skeleton of its own: the tracker
    // finds it in the depth (`SkeletonFromDepth` below).
    let (skeleton_source, performer_clip, sensor_name) = match &options.sensor {
        sensors::SensorSpec::Bvh(_) => (source, None, String::new()),
        sensors::SensorSpec::Synthetic => (
            source,
            None,
            format!(
                "synthetic (ground-truth skeleton of {}{})",
                options.motion.display(),
                if options.treadmill {
                    ", on a treadmill"
                } else {
                    ""
                }
            ),
        ),
        // The performer takes the clip: the camera films it, the avatar follows the tracker.
        sensors::SensorSpec::Performer(_) => (
            None,
            source,
            format!(
                "performer (the synthetic Kinect filming {}; skeleton: the tracker)",
                options.motion.display()
            ),
        ),
        other => (
            None,
            None,
            format!("{} (skeleton: the tracker)", other.name()),
        ),
    };
    let performer = match (performer_clip, &script) {
        (Some(clip), _) => Some(performer::Performer::clip(
            clip,
            MotionPipeline::new(
                AvatarPipeline::new(&skeleton, floor_y)?,
                FilterSettings::default().filter.build(),
            ),
            body.clone(),
        )),
        (None, Some(script)) => Some(performer::Performer::script(
            ScriptedPerson::new(
                model.clone(),
                body.positions.clone(),
                body.rest.clone(),
                script,
                floor_y,
            )
            .with_context(|| format!("cannot perform '{}'", options.motion.display()))?,
        )),
        (None, None) => None,
    };
    let depth = match performer {
        Some(performer) => Some(sensors::ActiveDepth::performer(
            &placement,
            options.depth_seed,
            (&body, options.extras),
            performer,
        )),
        None => sensors::ActiveDepth::open(
            &options.sensor,
            &placement,
            options.depth_seed,
            options.replay,
            (&body, options.extras),
        )?,
    };
    let mut app = App::new();
    // Garments, fabrics and size charts are assets of the garment folder (hot-reloaded):
    // registered before the `AssetPlugin` comes with the default plugins.
    let garment_root = garment_root(options)?;
    fitroom_garment::asset::register_garment_source(&mut app, &garment_root);
    kiosk::config::register_config_source(&mut app, &options.config_path);
    fitroom_body::reload::register_body_source(&mut app, &options.body);
    // Bevy's asset server reads the product's assets folder (the kiosk configuration).
    let asset_plugin = AssetPlugin {
        file_path: assets::assets_dir()?.to_string_lossy().into_owned(),
        ..default()
    };
    let display = options.config.display;
    let render = match options.mode {
        Mode::Kiosk { .. } | Mode::Design => {
            let windowed = match options.mode {
                Mode::Kiosk { windowed } => windowed,
                _ => true,
            };
            let window = Window {
                title: "fitroom".into(),
                mode: if windowed || !display.fullscreen {
                    WindowMode::Windowed
                } else {
                    WindowMode::BorderlessFullscreen(MonitorSelection::Primary)
                },
                resolution: (display.width, display.height).into(),
                ..default()
            };
            app.add_plugins(
                DefaultPlugins
                    .set(WindowPlugin {
                        primary_window: Some(window),
                        ..default()
                    })
                    .set(asset_plugin),
            );
            true
        }
        Mode::Headless { render: true } => {
            app.add_plugins(
                DefaultPlugins
                    .set(WindowPlugin {
                        primary_window: None,
                        exit_condition: ExitCondition::DontExit,
                        ..default()
                    })
                    .set(asset_plugin)
                    .disable::<WinitPlugin>(),
            )
            .add_plugins(ScheduleRunnerPlugin::run_loop(Duration::ZERO));
            true
        }
        Mode::Headless { render: false } => {
            app.add_plugins((
                MinimalPlugins,
                TransformPlugin,
                StatesPlugin,
                asset_plugin,
                bevy::log::LogPlugin::default(),
            ));
            false
        }
    };
    if matches!(options.mode, Mode::Headless { .. }) {
        // Headless runs step time exactly: one frame is 1/60 s of the recording.
        app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
            1.0 / 60.0,
        )));
    }

    app.insert_resource(LoadTimings { body_load_ms })
        .insert_resource(body)
        .insert_resource(AvatarShape(shape))
        .insert_resource(body_panel::BodyPanel {
            open: options.body_panel,
            shape_path: options.shape_path.clone(),
            ..Default::default()
        })
        .insert_resource(SensorFeed {
            source_name: sensor_name,
            ..default()
        })
        .insert_resource(motion)
        .insert_resource(placement)
        .add_plugins((
            SensorPlugin,
            MotionPlugin,
            BodyPlugin {
                render_mesh: render,
            },
            kiosk::KioskPlugin {
                config: options.config.clone(),
                config_path: options.config_path.clone(),
            },
            timing::TimingPlugin,
            GarmentPlugin { root: garment_root },
        ))
        .add_plugins((
            sensors::DepthPlugin {
                source_name: options.sensor.name(),
            },
            fitroom_tracker::plugin::TrackerPlugin,
            fitroom_measure::plugin::MeasurePlugin,
            fitroom_gesture::plugin::GesturePlugin,
        ))
        .add_plugins(fitroom_body::reload::BodyFilePlugin {
            file: options.body.clone(),
        })
        .insert_resource(GarmentRequest {
            path: options.garment.clone(),
            size: options.garment_size.clone(),
            compare: None,
        })
        .insert_resource(ClothSettings {
            fit_map: options.fit_map,
            ..Default::default()
        });

    match skeleton_source {
        Some(source) => {
            app.insert_resource(ActiveSensor(source));
        }
        // Depth alone (a recording, a Kinect): the tracker's skeletons drive the avatar.
        None => {
            app.insert_resource(fitroom_tracker::plugin::SkeletonFromDepth);
        }
    }
    if let Some(depth) = depth {
        app.insert_resource(depth);
    }
    if render {
        app.insert_resource(ClearColor(BACKGROUND))
            .insert_resource(GlobalAmbientLight {
                brightness: 350.0,
                ..default()
            });
        let image_target = match options.mode {
            Mode::Headless { render: true } => Some(options.image_size),
            _ => None,
        };
        let orbit = options.mode == Mode::Design;
        // The kiosk is a mirror: its camera draws the scene mirrored (the person's right hand
        // on the screen's right); headless runs and the designer show the sensor's view.
        let mirror = matches!(options.mode, Mode::Kiosk { .. }) && options.config.display.mirror;
        let view = RoomView {
            image_target,
            orbit,
            mirror,
        };
        app.add_systems(
            Startup,
            move |commands: Commands,
                  images: ResMut<Assets<Image>>,
                  meshes: ResMut<Assets<Mesh>>,
                  materials: ResMut<Assets<StandardMaterial>>| {
                spawn_room(commands, images, meshes, materials, view)
            },
        );
        if mirror {
            app.add_systems(Update, kiosk::show_both_faces);
        }
    }
    match options.mode {
        Mode::Kiosk { .. } => {
            app.add_plugins((
                kiosk::ui::OverlayPlugin,
                kiosk::tryon_ui::TryOnScreenPlugin,
                kiosk::guide::PoseGuidePlugin,
                body_panel::BodyPanelPlugin,
            ));
            if !matches!(options.sensor, sensors::SensorSpec::Bvh(_)) {
                app.add_plugins(kiosk::depth_view::DepthViewPlugin);
            }
        }
        Mode::Design => {
            app.add_plugins((bevy_egui::EguiPlugin::default(), design::DesignPlugin))
                .insert_resource(design::Designer::new(options.shape.clone()));
        }
        Mode::Headless { .. } => {}
    }
    Ok(app)
}

/// The garment folder: the assets folder, or for a garment file outside it, the folder above
/// the garment's own (the product's layout: `garments/`, `fabrics/`, `sizecharts/` side by side).
fn garment_root(options: &AppOptions) -> Result<PathBuf> {
    let assets = assets::assets_dir()?;
    let Some(garment) = &options.garment else {
        return Ok(assets);
    };
    let garment = std::path::absolute(garment)
        .with_context(|| format!("cannot resolve the garment path '{}'", garment.display()))?;
    if garment.starts_with(std::path::absolute(&assets).unwrap_or(assets.clone())) {
        return Ok(assets);
    }
    garment
        .parent()
        .and_then(|dir| dir.parent())
        .map(PathBuf::from)
        .with_context(|| {
            format!(
                "the garment '{}' has no folder above its own",
                garment.display()
            )
        })
}

/// How long loading the inputs took.
#[derive(Resource, Debug, Clone, Copy)]
pub struct LoadTimings {
    /// Reading, inflating, checking and decoding the `.fitbody` asset, milliseconds.
    pub body_load_ms: f64,
}

/// Offscreen render target of a headless run.
#[derive(Resource, Clone)]
pub struct OffscreenTarget(pub Handle<Image>);

/// How the room is seen: offscreen (headless), by the designer's orbit camera, or by the
/// kiosk's camera, mirrored or not.
#[derive(Clone, Copy, Debug)]
struct RoomView {
    image_target: Option<UVec2>,
    orbit: bool,
    mirror: bool,
}

fn spawn_room(
    mut commands: Commands,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
    view: RoomView,
) {
    let RoomView {
        image_target,
        orbit,
        mirror,
    } = view;
    // Floor: a large matte disc.
    commands.spawn((
        Mesh3d(meshes.add(Circle::new(6.0))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgb(0.32, 0.33, 0.36),
            perceptual_roughness: 0.9,
            ..default()
        })),
        Transform::from_rotation(Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2))
            .with_translation(Vec3::new(0.0, 0.0, -2.5)),
    ));
    // Key light from the front left, fill from the right.
    commands.spawn((
        DirectionalLight {
            illuminance: 9000.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(-2.0, 4.0, 3.0).looking_at(Vec3::new(0.0, 1.0, -2.5), Vec3::Y),
    ));
    commands.spawn((
        PointLight {
            intensity: 600_000.0,
            range: 20.0,
            ..default()
        },
        Transform::from_xyz(2.5, 2.5, 0.5),
    ));

    let camera_transform =
        Transform::from_xyz(0.0, 1.2, 0.9).looking_at(Vec3::new(0.0, 0.95, -2.5), Vec3::Y);
    match image_target {
        Some(size) => {
            let image = Image::new_target_texture(
                size.x,
                size.y,
                bevy::render::render_resource::TextureFormat::Rgba8UnormSrgb,
                None,
            );
            let handle = images.add(image);
            commands.insert_resource(OffscreenTarget(handle.clone()));
            commands.spawn((
                Camera3d::default(),
                bevy::camera::RenderTarget::Image(handle.into()),
                camera_transform,
                kiosk::MirrorCamera,
            ));
        }
        None if orbit => {
            let orbit = design::OrbitCamera::facing(design::DESIGN_FOCUS);
            commands.spawn((Camera3d::default(), orbit.transform(), orbit));
        }
        None => {
            // A camera scaled -1 along its own x draws the mirror image (the kiosk's framing
            // moves it, keeping the scale).
            let camera_transform = if mirror {
                camera_transform.with_scale(kiosk::MIRRORED)
            } else {
                camera_transform
            };
            commands.spawn((Camera3d::default(), camera_transform, kiosk::MirrorCamera));
        }
    }
}
