//! The kiosk's configuration file (`assets/kiosk.ron`): where the frames come from, the
//! flow's timings, the garments offered, and the display.
//!
//! It is read once at start (the window and the sensor need it before the app runs) and then
//! watched through the asset server ([`KioskConfigLoader`]): an edit of the timings or of the
//! garment list takes effect while the kiosk runs; an edit that does not parse keeps the last
//! good configuration and the kiosk shows the error (file, line, field).

use std::path::{Path, PathBuf};

use bevy::asset::io::Reader;
use bevy::asset::{AssetLoadFailedEvent, AssetLoader, LoadContext};
use bevy::prelude::*;
use fitroom_garment::error::{field_at, ron_options};
use serde::Deserialize;

use super::KioskTimings;

/// The file the kiosk reads by default, relative to `assets/`.
pub const DEFAULT_CONFIG: &str = "kiosk.ron";

/// The asset source the configuration is followed through: the configuration file's folder.
pub const CONFIG_SOURCE: &str = "kiosk";

/// The folder of a configuration file and its name in it.
pub fn config_location(config: &Path) -> (PathBuf, PathBuf) {
    let absolute = std::path::absolute(config).unwrap_or_else(|_| config.to_owned());
    let dir = absolute
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let file = absolute
        .file_name()
        .map_or_else(|| PathBuf::from(DEFAULT_CONFIG), PathBuf::from);
    (dir, file)
}

/// Names the configuration file's folder as the asset source [`CONFIG_SOURCE`]; call before
/// adding the `AssetPlugin`.
pub fn register_config_source(app: &mut App, config: &Path) {
    let (dir, _) = config_location(config);
    app.register_asset_source(
        CONFIG_SOURCE,
        bevy::asset::io::AssetSourceBuilder::platform_default(&dir.to_string_lossy(), None),
    );
}

/// What the kiosk shows and how it behaves.
#[derive(Asset, TypePath, Debug, Clone, PartialEq, Deserialize)]
#[serde(rename = "KioskConfig", deny_unknown_fields)]
pub struct KioskConfig {
    /// Where frames come from: `bvh:FILE`, a recorded clip replayed as a Kinect v1 skeleton
    /// stream (FILE relative to `assets/`, or absolute); `synthetic`, the synthetic Kinect v1
    /// seeing the avatar; `performer`, the synthetic Kinect v1 filming a performer the clip
    /// drives (the tracker drives the avatar); `fakenect:DIR`, a depth recording; `kinect`, a
    /// Kinect v1 through libfreenect.
    pub sensor: String,
    /// With a clip-driven sensor (`bvh:`, `synthetic`, `performer`): replay the clip on a
    /// treadmill, the performer's hip centre kept where it is at the clip's first frame, so a
    /// walk stays in the camera's view and range (the embedded walk otherwise walks past the
    /// camera in 2 s). Read at start.
    #[serde(default)]
    pub treadmill: bool,
    pub timings: TimingsConfig,
    /// The garments offered, in order; the first is worn by default.
    pub garments: Vec<GarmentEntry>,
    pub display: DisplayConfig,
}

/// [`KioskTimings`] as written.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimingsConfig {
    /// Seconds a person must be tracked in `Calibrate` before `TryOn` (0.1-60).
    pub calibrate_s: f32,
    /// Seconds without a tracked person before going back to `Attract` (0.1-600).
    pub lost_s: f32,
    /// Seconds `Calibrate` tries to measure the person (from depth) before going on to
    /// `TryOn` unmeasured (1-600; default 12).
    #[serde(default = "default_measure_s")]
    pub measure_s: f32,
}

fn default_measure_s() -> f32 {
    12.0
}

/// One garment offered.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GarmentEntry {
    /// A garment file (pattern `.ron`, `.obj`, `.glb`), relative to `assets/`.
    pub file: String,
    /// Its size (default: the middle one, until the person is measured).
    #[serde(default)]
    pub size: Option<String>,
}

/// The window.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DisplayConfig {
    /// Borderless full screen (the mirror); `false`: a window of `width` x `height`.
    pub fullscreen: bool,
    pub width: u32,
    pub height: u32,
    /// The kiosk shows the person's mirror image (their right hand on the screen's right);
    /// `false`: as the camera sees them. Read at start. Headless runs and the designer never
    /// mirror.
    #[serde(default = "mirror_by_default")]
    pub mirror: bool,
}

fn mirror_by_default() -> bool {
    true
}

/// Why a configuration file is refused.
#[derive(Debug, thiserror::Error)]
pub enum KioskConfigError {
    #[error("cannot read '{}': {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{file}:{line}:{col}: {}{message}", .field.as_ref().map(|f| format!("in `{f}`: ")).unwrap_or_default())]
    Syntax {
        file: String,
        line: usize,
        col: usize,
        field: Option<String>,
        message: String,
    },
    #[error("{file}:{line}: `{field}`: {problem}")]
    Invalid {
        file: String,
        line: usize,
        field: String,
        problem: String,
    },
}

impl KioskConfig {
    /// Reads and checks a configuration file.
    pub fn load(path: &Path) -> Result<Self, KioskConfigError> {
        let text = std::fs::read_to_string(path).map_err(|source| KioskConfigError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::from_ron_str(&text, &path.display().to_string())
    }

    /// Parses and checks a configuration; `file` names it in errors.
    pub fn from_ron_str(text: &str, file: &str) -> Result<Self, KioskConfigError> {
        let config: KioskConfig = ron_options().from_str(text).map_err(|e| {
            let (line, col) = (e.span.start.line, e.span.start.col);
            KioskConfigError::Syntax {
                file: file.to_owned(),
                line,
                col,
                field: field_at(text, line, col),
                message: e.code.to_string(),
            }
        })?;
        let invalid = |needle: &str, field: &str, problem: String| KioskConfigError::Invalid {
            file: file.to_owned(),
            line: text
                .lines()
                .position(|l| l.trim_start().starts_with(needle))
                .map_or(1, |i| i + 1),
            field: field.to_owned(),
            problem,
        };
        let t = config.timings;
        if !(0.1..=60.0).contains(&t.calibrate_s) {
            return Err(invalid(
                "calibrate_s",
                "timings.calibrate_s",
                format!("is {} s; accepted 0.1..=60 s", t.calibrate_s),
            ));
        }
        if !(0.1..=600.0).contains(&t.lost_s) {
            return Err(invalid(
                "lost_s",
                "timings.lost_s",
                format!("is {} s; accepted 0.1..=600 s", t.lost_s),
            ));
        }
        if !(1.0..=600.0).contains(&t.measure_s) {
            return Err(invalid(
                "measure_s",
                "timings.measure_s",
                format!("is {} s; accepted 1..=600 s", t.measure_s),
            ));
        }
        let d = config.display;
        for (name, value) in [("width", d.width), ("height", d.height)] {
            if !(240..=16_384).contains(&value) {
                return Err(invalid(
                    name,
                    &format!("display.{name}"),
                    format!("is {value} pixels; accepted 240..=16384"),
                ));
            }
        }
        if let Err(error) = config.sensor.parse::<crate::sensors::SensorSpec>() {
            return Err(invalid("sensor", "sensor", error.to_string()));
        }
        if let Some(g) = config
            .garments
            .iter()
            .find(|g| fitroom_garment::GarmentFormat::of(Path::new(&g.file)).is_err())
        {
            return Err(invalid(
                "garments",
                "garments",
                format!(
                    "\"{}\" is not a garment file (.ron, .obj, .glb, .gltf)",
                    g.file
                ),
            ));
        }
        Ok(config)
    }

    /// The sensor, parsed (checked when the configuration was read).
    pub fn sensor_spec(&self) -> anyhow::Result<crate::sensors::SensorSpec> {
        self.sensor.parse()
    }

    /// The clip of a `bvh:FILE` or `performer:FILE` sensor.
    pub fn sensor_clip(&self) -> Option<&str> {
        let s = self.sensor.trim();
        s.strip_prefix("bvh:")
            .or_else(|| s.strip_prefix("performer:"))
            .map(str::trim)
            .filter(|f| !f.is_empty())
    }

    /// The timings as the kiosk's resource.
    pub fn kiosk_timings(&self) -> KioskTimings {
        KioskTimings {
            calibrate_s: self.timings.calibrate_s,
            lost_s: self.timings.lost_s,
            measure_s: self.timings.measure_s,
        }
    }
}

/// Reads [`KioskConfig`] files through the asset server; `root` is the assets folder, so that
/// errors name the file on disk.
#[derive(TypePath)]
pub struct KioskConfigLoader {
    pub root: PathBuf,
}

impl AssetLoader for KioskConfigLoader {
    type Asset = KioskConfig;
    type Settings = ();
    type Error = KioskConfigError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<KioskConfig, KioskConfigError> {
        let path = self.root.join(load_context.path().path());
        let mut bytes = Vec::new();
        reader
            .read_to_end(&mut bytes)
            .await
            .map_err(|source| KioskConfigError::Read {
                path: path.clone(),
                source,
            })?;
        KioskConfig::from_ron_str(
            &String::from_utf8_lossy(&bytes),
            &path.display().to_string(),
        )
    }
}

/// The configuration in force, the asset watched for edits, and the last edit's error.
#[derive(Resource, Debug)]
pub struct ActiveKioskConfig {
    pub config: KioskConfig,
    /// The configuration file's folder: its garment files are relative to it.
    pub folder: PathBuf,
    pub handle: Option<Handle<KioskConfig>>,
    pub error: Option<String>,
}

/// An edited configuration takes effect (timings, garment list); a broken one is reported.
pub fn follow_config(
    mut events: MessageReader<AssetEvent<KioskConfig>>,
    mut failures: MessageReader<AssetLoadFailedEvent<KioskConfig>>,
    configs: Res<Assets<KioskConfig>>,
    mut active: ResMut<ActiveKioskConfig>,
    mut timings: ResMut<KioskTimings>,
) {
    let Some(id) = active.handle.as_ref().map(Handle::id) else {
        events.clear();
        failures.clear();
        return;
    };
    for event in events.read() {
        if let AssetEvent::Modified { id: e } | AssetEvent::LoadedWithDependencies { id: e } = event
            && *e == id
            && let Some(config) = configs.get(id)
        {
            if *config != active.config {
                info!("kiosk configuration changed");
                *timings = config.kiosk_timings();
                active.config = config.clone();
            }
            active.error = None;
        }
    }
    for failure in failures.read() {
        if failure.id == id {
            let message = failure.error.to_string();
            // The loader's message is one line; what follows (a backtrace when
            // RUST_BACKTRACE is set) is not for the screen.
            let message = message.lines().next().unwrap_or_default().to_owned();
            warn!("the kiosk keeps its configuration: {message}");
            active.error = Some(message);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHIPPED: &str = include_str!("../../assets/kiosk.ron");

    #[test]
    fn the_shipped_configuration_reads() {
        let config = KioskConfig::from_ron_str(SHIPPED, "kiosk.ron").expect("valid");
        // The embedded default is the whole real chain: the synthetic camera films the
        // embedded clip's performer on a treadmill, the tracker drives the avatar.
        assert_eq!(
            config.sensor_spec().expect("a sensor"),
            crate::sensors::SensorSpec::Performer(None)
        );
        assert_eq!(config.sensor_clip(), None);
        assert!(config.treadmill);
        assert!(config.garments.len() >= 3);
        assert!(config.timings.calibrate_s > 0.0);
    }

    #[test]
    fn errors_name_file_line_and_field() {
        let bad = SHIPPED.replacen("lost_s: 3.0", "lost_s: \"long\"", 1);
        assert_ne!(bad, SHIPPED);
        let e = KioskConfig::from_ron_str(&bad, "kiosk.ron").expect_err("a string is no time");
        let line = bad
            .lines()
            .position(|l| l.contains("lost_s"))
            .expect("line")
            + 1;
        let message = e.to_string();
        assert!(
            message.starts_with(&format!("kiosk.ron:{line}:")),
            "{message}"
        );
        assert!(message.contains("lost_s"), "{message}");

        let bad = SHIPPED.replacen("lost_s: 3.0", "lost_s: -1.0", 1);
        let message = KioskConfig::from_ron_str(&bad, "kiosk.ron")
            .expect_err("negative time")
            .to_string();
        assert!(
            message.starts_with(&format!("kiosk.ron:{line}: `timings.lost_s`")),
            "{message}"
        );

        let bad = SHIPPED.replacen("\"performer\"", "\"webcam\"", 1);
        let message = KioskConfig::from_ron_str(&bad, "kiosk.ron")
            .expect_err("unknown sensor")
            .to_string();
        assert!(
            message.contains("`sensor`") && message.contains("bvh:FILE"),
            "{message}"
        );
    }
}
