//! The `fitroom` command: the kiosk by default, headless runs, and the data tools.

#![forbid(unsafe_code)]

use std::path::PathBuf;

use anyhow::{Context, Result};
use bevy::{
    prelude::*,
    render::view::screenshot::{Screenshot, save_to_disk},
};
use clap::{Parser, Subcommand};
use fitroom::{AppOptions, Mode, build_app, headless};

#[derive(Parser)]
#[command(
    name = "fitroom",
    version,
    about = "A virtual fitting room: a measured avatar mirrors you and wears simulated garments."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(clap::Args, Clone)]
struct Inputs {
    /// The kiosk configuration (RON; default: assets/kiosk.ron): sensor, timings, garments,
    /// display. Edits are followed while the app runs.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Converted body file (default: assets/bodies/makehuman.fitbody).
    #[arg(long)]
    body: Option<PathBuf>,
    /// BVH clip that drives the avatar (default: the embedded assets/motions/walk.bvh).
    #[arg(long)]
    motion: Option<PathBuf>,
    /// `kinect`: replay the clip through the Kinect v1 noise model (to see the filters work);
    /// `none`: the clean recording.
    #[arg(long, default_value = "none")]
    noise: String,
    /// Seed of the noise model.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The avatar's body shape (RON, e.g. from `fitroom body fit --out`); the body panel (B)
    /// saves to this file too.
    #[arg(long)]
    shape: Option<PathBuf>,
    /// Open the body panel at start.
    #[arg(long)]
    body_panel: bool,
    /// A garment for the avatar (pattern .ron, e.g. assets/garments/sundress.ron).
    #[arg(long)]
    garment: Option<PathBuf>,
    /// The garment's size (a label of its size chart; default: its middle size).
    #[arg(long)]
    size: Option<String>,
    /// Colour the garment by strain (the fit map).
    #[arg(long)]
    fit_map: bool,
}

#[derive(Subcommand)]
enum Command {
    /// The mirror kiosk (the default when no command is given).
    Kiosk {
        /// A window instead of full screen.
        #[arg(long)]
        windowed: bool,
        /// Save a screenshot of the window after `--frames` frames, then quit.
        #[arg(long)]
        screenshot: Option<PathBuf>,
        /// Frames to run before the screenshot.
        #[arg(long, default_value_t = 180)]
        frames: u32,
        /// Start with the raw and filtered sensor skeletons drawn (the D key toggles them).
        #[arg(long)]
        skeletons: bool,
        #[command(flatten)]
        inputs: Inputs,
    },
    /// The garment designer: the garment on the avatar in a window (orbit camera, poses,
    /// sizes, bodies, fit map); saving the garment or its fabric dresses the avatar again.
    Design {
        /// The garment file (pattern .ron, .obj, .glb).
        #[arg(value_name = "GARMENT")]
        file: PathBuf,
        /// Save a screenshot of the window after `--frames` frames, then quit.
        #[arg(long)]
        screenshot: Option<PathBuf>,
        /// Frames to run before the screenshot.
        #[arg(long, default_value_t = 180)]
        frames: u32,
        /// The designer's starting pose.
        #[arg(long, value_enum, default_value_t = DesignPose::APose)]
        pose: DesignPose,
        #[command(flatten)]
        inputs: Inputs,
    },
    /// Run the pipeline without a display server.
    Run {
        /// Required: no window (the only mode of `run`).
        #[arg(long)]
        headless: bool,
        /// Frames to run (1/60 s of the recording each).
        #[arg(long, default_value_t = 120)]
        frames: u32,
        /// Render the last frame offscreen (any Vulkan adapter, Mesa lavapipe included).
        #[arg(long)]
        screenshot: Option<PathBuf>,
        /// Write the JSON report here (it is printed to stdout as well).
        #[arg(long)]
        report: Option<PathBuf>,
        #[command(flatten)]
        inputs: Inputs,
    },
    /// Sensor tools.
    Sensor {
        #[command(subcommand)]
        command: SensorCommand,
    },
    /// Convert source data into the product's assets.
    Import {
        #[command(subcommand)]
        command: ImportCommand,
    },
    /// Garments on the avatar without a window: simulation, fit map, speed.
    Cloth {
        #[command(subcommand)]
        command: ClothCommand,
    },
    /// Body tools.
    Body {
        #[command(subcommand)]
        command: BodyCommand,
    },
    /// Motion pipeline tools.
    Motion {
        #[command(subcommand)]
        command: MotionCommand,
    },
}

/// The designer's poses.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum DesignPose {
    /// The avatar's rest pose: arms down and away from the body.
    APose,
    /// Arms raised sideways.
    TPose,
    /// The configured clip, looped.
    Walk,
}

#[derive(Subcommand)]
enum ClothCommand {
    /// The garment on the avatar walking a clip: per-step cost, penetration, strain, resets.
    Sim {
        /// A garment file (pattern .ron, or .obj/.glb), e.g. assets/garments/sundress.ron.
        #[arg(long)]
        garment: PathBuf,
        /// A size label of the garment (default: its middle size).
        #[arg(long)]
        size: Option<String>,
        /// BVH clip (default: the embedded walk).
        #[arg(long)]
        motion: Option<PathBuf>,
        /// Video frames (1/30 s of the clip each).
        #[arg(long, default_value_t = 120)]
        frames: usize,
        #[arg(long)]
        shape: Option<PathBuf>,
        #[arg(long)]
        threads: Option<usize>,
        #[arg(long)]
        body: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// The garment settled on the body at rest: strain, gap and the ease at bust, waist, hip.
    Fit {
        #[arg(long)]
        garment: PathBuf,
        #[arg(long)]
        size: Option<String>,
        #[arg(long)]
        shape: Option<PathBuf>,
        /// Simulated settling time, s.
        #[arg(long, default_value_t = 1.5)]
        settle: f32,
        #[arg(long)]
        body: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// The cloth step's cost: the dress on the walking avatar (as shipped and meshed to about
    /// 4,000 particles), and 1k-64k particles.
    Bench {
        #[arg(long)]
        garment: Option<PathBuf>,
        /// Motion frames (30 Hz, four steps each) the dresses walk, the clip played back and
        /// forth: 240 is about half a second of stepping for the 4,000-particle dress, so
        /// that a hiccup of the machine shorter than that does not decide the median (with
        /// 60 frames one did: 0.771 ms once).
        #[arg(long, default_value_t = 240)]
        frames: usize,
        #[arg(long)]
        body: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum MotionCommand {
    /// Replay a clean clip through the Kinect noise model and the motion pipeline; report RMSE,
    /// jitter, lag, bone-length spread, foot skating and joint-limit violations.
    Eval {
        /// The clean BVH clip.
        #[arg(long)]
        bvh: PathBuf,
        /// `kinect` (the Kinect v1 model, view limits off) or `none`.
        #[arg(long, default_value = "kinect")]
        noise: String,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// none | holt | holt-smooth | holt-very-smooth | oneeuro | oneeuro-tuned | kalman
        #[arg(long, default_value = "kalman")]
        filter: String,
        /// Draw raw, filtered and clean curves of the right elbow angle (PNG).
        #[arg(long)]
        plot: Option<PathBuf>,
        #[arg(long)]
        json: bool,
        /// Converted body file (default: assets/bodies/makehuman.fitbody).
        #[arg(long)]
        body: Option<PathBuf>,
    },
}

#[derive(Subcommand)]
enum SensorCommand {
    /// Print a BVH clip's frame count, rate, duration, joints and skeleton kind.
    Inspect {
        file: PathBuf,
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum ImportCommand {
    /// MakeHuman data folder (e.g. ../shared/data/makehuman) to a .fitbody asset.
    Makehuman {
        dir: PathBuf,
        #[arg(long, default_value = "assets/bodies/makehuman.fitbody")]
        out: PathBuf,
    },
}

#[derive(Subcommand)]
enum BodyCommand {
    /// Measure a body (default shape, or a shape file): stature, inside leg, arm length,
    /// shoulder width and the neck, bust, under-bust, waist, hip, thigh and calf girths.
    Measure {
        /// A shape file (RON), e.g. `(gender: 0.0, weight: 0.6)`.
        #[arg(long)]
        shape: Option<PathBuf>,
        #[arg(long)]
        body: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// Fit a body to measurements (cm): bounded least squares over the MakeHuman sliders.
    Fit {
        /// female or male.
        #[arg(long)]
        gender: String,
        /// Age in years (18-90; default 25).
        #[arg(long)]
        age: Option<f32>,
        #[command(flatten)]
        measurements: fitroom::body_cli::MeasurementArgs,
        /// Save the fitted shape (RON) here.
        #[arg(long)]
        out: Option<PathBuf>,
        #[arg(long)]
        body: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// Recommend a size of a size chart for a body (default shape, or a shape file).
    Size {
        /// A size chart (RON), e.g. assets/sizecharts/en13402-female-seed002.ron.
        #[arg(long)]
        chart: PathBuf,
        #[arg(long)]
        shape: Option<PathBuf>,
        #[arg(long)]
        body: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// Fit ANSUR II subjects (all, or a seeded sample per sex) and report the errors.
    Ansur {
        /// The folder with ANSUR_II_FEMALE_Public.csv and ANSUR_II_MALE_Public.csv (or their
        /// `.csv.gz`); by default the copy committed in the repository's `data/ansur2`.
        #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/data/ansur2"))]
        data: PathBuf,
        /// Subjects per sex (a seeded random sample); all 6,068 when absent.
        #[arg(long)]
        per_sex: Option<usize>,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        #[arg(long, default_value_t = 2)]
        threads: usize,
        /// Write the whole report (every subject) as JSON here.
        #[arg(long)]
        report: Option<PathBuf>,
        /// Write the summary (Markdown) here.
        #[arg(long)]
        summary: Option<PathBuf>,
        #[arg(long)]
        body: Option<PathBuf>,
    },
    /// Segment-local morphing: roughness against interpolation per propagation depth (seed
    /// 002 Figs. 7.3-7.5), as a table, JSON or a plot.
    Roughness {
        /// Draw the Gaussian-propagation curves (PNG).
        #[arg(long)]
        plot: Option<PathBuf>,
        #[arg(long)]
        body: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
    /// Write the shaped body in its rest pose (metres, +Y up) as OBJ or glb (by extension).
    Export {
        #[arg(long)]
        shape: Option<PathBuf>,
        #[arg(long)]
        out: PathBuf,
        #[arg(long)]
        body: Option<PathBuf>,
    },
    /// Cross-section area of the forearm under a twist, single bone vs split (seed 000 §4.4.3).
    TwistStudy {
        #[arg(long, default_value_t = -90.0, allow_negative_numbers = true)]
        degrees: f32,
        #[arg(long)]
        body: Option<PathBuf>,
        #[arg(long)]
        json: bool,
    },
}

fn options(mode: Mode, inputs: &Inputs) -> Result<AppOptions> {
    let defaults = match &inputs.config {
        Some(config) => AppOptions::with_config(mode.clone(), config)?,
        None => AppOptions::with_defaults(mode.clone())?,
    };
    let body = inputs.body.clone().unwrap_or(defaults.body);
    let motion = inputs.motion.clone().unwrap_or(defaults.motion);
    let noise_seed = match inputs.noise.as_str() {
        "none" => None,
        "kinect" => Some(inputs.seed),
        other => anyhow::bail!("unknown --noise '{other}': use none or kinect"),
    };
    let shape = match &inputs.shape {
        Some(path) if path.exists() => Some(fitroom::body_cli::load_shape(Some(path))?),
        Some(path) => {
            eprintln!(
                "note: the shape file '{}' does not exist yet: the default body; the body \
                 panel (B) saves there",
                path.display()
            );
            None
        }
        None => None,
    };
    Ok(AppOptions {
        mode,
        body,
        motion,
        image_size: UVec2::new(960, 720),
        noise_seed,
        shape,
        shape_path: inputs
            .shape
            .clone()
            .unwrap_or_else(|| PathBuf::from("shape.ron")),
        body_panel: inputs.body_panel,
        garment: inputs.garment.clone(),
        garment_size: inputs.size.clone(),
        fit_map: inputs.fit_map,
        config: defaults.config,
        config_path: defaults.config_path,
    })
}

fn main() -> std::process::ExitCode {
    match run(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command.unwrap_or(Command::Kiosk {
        windowed: false,
        screenshot: None,
        frames: 180,
        skeletons: false,
        inputs: Inputs {
            config: None,
            body: None,
            motion: None,
            noise: "none".into(),
            seed: 1,
            shape: None,
            body_panel: false,
            garment: None,
            size: None,
            fit_map: false,
        },
    }) {
        Command::Kiosk {
            windowed,
            screenshot,
            frames,
            skeletons,
            inputs,
        } => {
            let mut app = build_app(&options(Mode::Kiosk { windowed }, &inputs)?)?;
            app.insert_resource(fitroom::kiosk::DebugSkeletons(skeletons));
            if let Some(path) = screenshot {
                app.add_systems(Update, screenshot_then_quit(path, frames));
            }
            app.run();
        }
        Command::Design {
            file,
            screenshot,
            frames,
            pose,
            mut inputs,
        } => {
            inputs.garment = Some(file);
            let motion = match pose {
                DesignPose::APose => fitroom::design::DesignMotion::Still(
                    fitroom_motion::still_pose::StillPose::APose,
                ),
                DesignPose::TPose => fitroom::design::DesignMotion::Still(
                    fitroom_motion::still_pose::StillPose::TPose,
                ),
                DesignPose::Walk => fitroom::design::DesignMotion::Clip,
            };
            let mut app = build_app(&options(Mode::Design, &inputs)?)?;
            app.world_mut()
                .resource_mut::<fitroom::design::Designer>()
                .motion = motion;
            if let Some(path) = screenshot {
                app.add_systems(Update, screenshot_then_quit(path, frames));
            }
            app.run();
        }
        Command::Run {
            headless,
            frames,
            screenshot,
            report,
            inputs,
        } => {
            if !headless {
                anyhow::bail!(
                    "`fitroom run` runs without a window: pass --headless (for the kiosk window, run `fitroom kiosk`)"
                );
            }
            let render = screenshot.is_some();
            let result = headless::run(
                &options(Mode::Headless { render }, &inputs)?,
                frames,
                screenshot.as_deref(),
            )?;
            let json = serde_json::to_string_pretty(&result)?;
            if let Some(path) = report {
                std::fs::write(&path, &json)
                    .with_context(|| format!("cannot write the report '{}'", path.display()))?;
            }
            println!("{json}");
        }
        Command::Sensor {
            command: SensorCommand::Inspect { file, json },
        } => {
            let info = fitroom_sensor::bvh_source::inspect(&file)?;
            if json {
                println!("{}", serde_json::to_string(&info)?);
            } else {
                println!(
                    "{}: {} frames at {:.1} fps ({:.2} s), {} joints, skeleton {}",
                    file.display(),
                    info.frames,
                    info.fps,
                    info.duration_s,
                    info.joints,
                    info.skeleton
                );
            }
        }
        Command::Import {
            command: ImportCommand::Makehuman { dir, out },
        } => import_makehuman(&dir, &out)?,
        Command::Body {
            command: BodyCommand::Measure { shape, body, json },
        } => {
            let model = load_body(body)?;
            let shape = fitroom::body_cli::load_shape(shape.as_deref())?;
            let report = fitroom::body_cli::measure(&model, shape)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                let m = &report.measurements;
                println!(
                    "stature {:.1} cm, inside leg {:.1}, arm {:.1}, shoulders {:.1}\n\
                     girths: neck {:.1}, bust {:.1}, under-bust {:.1}, waist {:.1}, hip {:.1}, thigh {:.1}, calf {:.1} cm\n\
                     shape applied in {:.2} ms, measured in {:.0} ms",
                    m.stature_cm,
                    m.crotch_height_cm,
                    m.arm_length_cm,
                    m.shoulder_width_cm,
                    m.neck_cm,
                    m.bust_cm,
                    m.underbust_cm,
                    m.waist_cm,
                    m.hip_cm,
                    m.thigh_cm,
                    m.calf_cm,
                    report.shape_ms,
                    report.measure_ms
                );
            }
        }
        Command::Body {
            command: BodyCommand::Export { shape, out, body },
        } => {
            let model = load_body(body)?;
            let shape = fitroom::body_cli::load_shape(shape.as_deref())?;
            let (shaped, _) = fitroom::body_cli::shaped(&model, &shape)?;
            fitroom::body_cli::export(&model, &shaped, &out)?;
            println!("wrote {}", out.display());
        }
        Command::Body {
            command:
                BodyCommand::Fit {
                    gender,
                    age,
                    measurements,
                    out,
                    body,
                    json,
                },
        } => {
            let gender = fitroom::body_cli::parse_gender(&gender)?;
            let model = load_body(body)?;
            let report =
                fitroom::body_cli::fit(&model, gender, age, &measurements, out.as_deref())?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print!("{}", fitroom::body_cli::fit_table(&report));
                if let Some(out) = out {
                    println!("shape saved to {}", out.display());
                }
            }
        }
        Command::Body {
            command: BodyCommand::Roughness { plot, body, json },
        } => {
            let model = load_body(body)?;
            let study = fitroom::body_cli::roughness(&model)?;
            if let Some(path) = &plot {
                fitroom::body_cli::plot_roughness(&study, path)?;
            }
            if json {
                println!("{}", serde_json::to_string_pretty(&study)?);
            } else {
                print!("{}", study.table());
                if let Some(path) = plot {
                    println!("plot: {}", path.display());
                }
            }
        }
        Command::Body {
            command:
                BodyCommand::Size {
                    chart,
                    shape,
                    body,
                    json,
                },
        } => {
            let model = load_body(body)?;
            let shape = fitroom::body_cli::load_shape(shape.as_deref())?;
            let answer = fitroom::body_cli::size(&model, &chart, shape)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&answer)?);
            } else {
                println!("{}: {}", answer.chart, answer.recommendation);
            }
        }
        Command::Body {
            command:
                BodyCommand::Ansur {
                    data,
                    per_sex,
                    seed,
                    threads,
                    report,
                    summary,
                    body,
                },
        } => {
            let model = load_body(body)?;
            let r = fitroom::body_cli::ansur(&model, &data, per_sex, seed, threads)?;
            let title = match per_sex {
                Some(n) => format!("ANSUR II, {n} random subjects per sex (seed {seed})"),
                None => "ANSUR II, all subjects".to_owned(),
            };
            let md = fitroom::body_cli::ansur_markdown(&r, &title);
            if let Some(path) = report {
                std::fs::write(&path, serde_json::to_string_pretty(&r)?)
                    .with_context(|| format!("cannot write the report '{}'", path.display()))?;
            }
            if let Some(path) = summary {
                std::fs::write(&path, &md)
                    .with_context(|| format!("cannot write the summary '{}'", path.display()))?;
            }
            print!("{md}");
        }
        Command::Cloth { command } => cloth_command(command)?,
        Command::Motion {
            command:
                MotionCommand::Eval {
                    bvh,
                    noise,
                    seed,
                    filter,
                    plot,
                    json,
                    body,
                },
        } => motion_eval(&bvh, &noise, seed, &filter, plot.as_deref(), json, body)?,
        Command::Body {
            command:
                BodyCommand::TwistStudy {
                    degrees,
                    body,
                    json,
                },
        } => {
            let path = match body {
                Some(p) => p,
                None => fitroom::assets::assets_dir()?.join(fitroom::assets::DEFAULT_BODY),
            };
            let model = fitroom_body::BodyModel::read(&path)?;
            let report = fitroom_body::forearm::forearm_twist_study(&model, degrees)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                print_twist_study(&report);
            }
        }
    }
    Ok(())
}

fn import_makehuman(dir: &std::path::Path, out: &std::path::Path) -> Result<()> {
    let bar = indicatif::ProgressBar::new(1);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg:24} [{bar:40}] {pos}/{len}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let start = std::time::Instant::now();
    let (model, report) =
        fitroom_body::import_makehuman_with_report(dir, &mut |stage, done, total| {
            bar.set_message(stage.to_string());
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        })?;
    bar.finish_and_clear();
    let import_s = start.elapsed().as_secs_f64();
    if let Some(parent) = out.parent() {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create '{}'", parent.display()))?;
    }
    model.write(out)?;
    let size = std::fs::metadata(out).map(|m| m.len()).unwrap_or(0);
    let start = std::time::Instant::now();
    let back = fitroom_body::BodyModel::read(out)?;
    if back != model {
        anyhow::bail!(
            "{}: the body read back differs from the one written",
            out.display()
        );
    }
    println!("{report:#?}");
    println!(
        "wrote {} ({:.1} MB): {} vertices ({} body), {} triangles, {} bones, {} morph targets; \
         import {import_s:.1} s, reads back identical in {:.2} s",
        out.display(),
        size as f64 / 1e6,
        model.positions.len(),
        model.body_vertex_count,
        model.triangles.len(),
        model.bones.len(),
        model.targets.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

fn motion_eval(
    bvh: &std::path::Path,
    noise: &str,
    seed: u64,
    filter: &str,
    plot: Option<&std::path::Path>,
    json: bool,
    body: Option<PathBuf>,
) -> Result<()> {
    use fitroom_motion::eval::{EvalOptions, FilterChoice, evaluate_clip, evaluation_noise};
    let filter: FilterChoice = filter.parse().map_err(|e| {
        anyhow::anyhow!(
            "{e}; --filter accepts: none, holt, holt-smooth, holt-very-smooth, oneeuro, oneeuro-tuned, kalman"
        )
    })?;
    let noise = match noise {
        "kinect" => Some(evaluation_noise()),
        "none" => None,
        other => anyhow::bail!("unknown --noise '{other}': use kinect or none"),
    };
    let path = match body {
        Some(p) => p,
        None => fitroom::assets::assets_dir()?.join(fitroom::assets::DEFAULT_BODY),
    };
    let model = fitroom_body::BodyModel::read(&path)?;
    let rest = model.rest_pose(&model.positions);
    let skeleton = fitroom_motion::avatar_skeleton(&model, &rest)?;
    let options = EvalOptions {
        filter,
        noise,
        seed,
        ..EvalOptions::default()
    };
    let evaluation = evaluate_clip(bvh, &skeleton, &options)?;
    if let Some(plot) = plot {
        fitroom::motion_cli::plot_joint_angle(&evaluation, plot)?;
    }
    let r = &evaluation.report;
    if json {
        println!("{}", serde_json::to_string_pretty(r)?);
    } else {
        println!(
            "{} with {} (seed {}), {} frames\n\
             position RMSE {:.1} mm (raw {:.1}); jitter {:.1} m/s² (raw {:.1}, clean {:.1}); lag {:.0} ms\n\
             bone-length std {:.1} mm (raw {:.1}); avatar foot skating {:.1}% -> {:.1}% of frame pairs\n\
             the correction moves the ankles {:.1} mm on average (at most {:.1} mm)\n\
             joint-limit violations {}; frames rejected {}; pipeline {:.1} µs per frame",
            r.clip,
            r.filter,
            r.seed,
            r.frames,
            r.output.rmse_mm,
            r.input.rmse_mm,
            r.output.jitter_m_s2,
            r.input.jitter_m_s2,
            r.output.clean_jitter_m_s2,
            r.output.lag_ms,
            r.output.bone_std_mm,
            r.input.bone_std_mm,
            100.0 * r.avatar_foot_skate_input,
            100.0 * r.avatar_foot_skate_output,
            r.foot_correction_mean_mm,
            r.foot_correction_max_mm,
            r.joint_limit_violations,
            r.rejected_frames,
            r.pipeline_us_per_frame
        );
    }
    Ok(())
}

fn load_body(body: Option<PathBuf>) -> Result<fitroom_body::BodyModel> {
    let path = match body {
        Some(p) => p,
        None => fitroom::assets::assets_dir()?.join(fitroom::assets::DEFAULT_BODY),
    };
    Ok(fitroom_body::BodyModel::read(&path)?)
}

fn print_twist_study(r: &fitroom_body::ForearmTwistReport) {
    let place = |offset_m: f32| {
        if offset_m < 0.0 {
            format!("{:.1} cm above the elbow", -offset_m * 100.0)
        } else {
            format!("{:.1} cm below the elbow", offset_m * 100.0)
        }
    };
    println!(
        "{:.0}° twist of the {} forearm ({:.1} cm long); mid-forearm section {:.1} cm² at rest",
        r.twist_deg,
        r.side,
        r.forearm_length_m * 100.0,
        r.rest_mid_area_cm2
    );
    println!("area kept (posed / rest)     mid-forearm  closed form  worst section");
    let rows = [
        (
            "single forearm bone",
            r.mid_section.single_bone,
            r.theory_mid.single_bone,
            r.worst.single_bone,
        ),
        (
            "split, all twist distal",
            r.mid_section.split_literal,
            r.theory_mid.split_literal,
            r.worst.split_literal,
        ),
        (
            "split, twist shared (used)",
            r.mid_section.split_shared,
            r.theory_mid.split_shared,
            r.worst.split_shared,
        ),
    ];
    for (name, mid, theory, worst) in rows {
        println!(
            "{name:<28} {mid:>11.3}  {theory:>11.3}  {:.3} ({})",
            worst.ratio,
            place(worst.offset_m)
        );
    }
}

/// After `frames` frames, saves a screenshot of the primary window and quits.
fn screenshot_then_quit(
    path: PathBuf,
    frames: u32,
) -> impl FnMut(Commands, MessageWriter<AppExit>, Local<u32>) {
    move |mut commands, mut exit, mut count| {
        *count += 1;
        if *count == frames {
            commands
                .spawn(Screenshot::primary_window())
                .observe(save_to_disk(path.clone()));
        }
        // The capture is written a few frames later.
        if *count == frames + 30 {
            exit.write(AppExit::Success);
        }
    }
}

fn cloth_command(command: ClothCommand) -> Result<()> {
    let assets = fitroom::assets::assets_dir()?;
    match command {
        ClothCommand::Sim {
            garment,
            size,
            motion,
            frames,
            shape,
            threads,
            body,
            json,
        } => {
            let model = load_body(body)?;
            let shape = fitroom::body_cli::load_shape(shape.as_deref())?;
            let motion = motion.unwrap_or_else(|| assets.join(fitroom::assets::DEFAULT_MOTION));
            let (r, _, _) = fitroom::cloth_cli::sim(
                &model,
                &shape,
                &garment,
                size.as_deref(),
                &motion,
                frames,
                threads,
            )?;
            if json {
                println!("{}", serde_json::to_string_pretty(&r)?);
            } else {
                println!(
                    "{} size {} ({}): {} particles, {} attached, {} colliders; {} steps of 1/120 s, {} substeps\n\
                     step {:.2} ms mean, {:.2} p95, {:.2} max; per video frame {:.2} ms mean\n\
                     max penetration {:.2} mm, longest tether {:.3} of its rest length, max strain {:.1}%, resets {}, all finite: {}\n\
                     colliders gave up at most {:.1} mm of radius to the skinned garment",
                    r.garment,
                    r.size,
                    r.fabric,
                    r.particles,
                    r.attached,
                    r.colliders,
                    r.steps,
                    r.substeps,
                    r.step_ms.mean,
                    r.step_ms.p95,
                    r.step_ms.max,
                    r.frame_ms.mean,
                    r.max_penetration_mm,
                    r.max_tether_ratio,
                    r.max_strain_pct,
                    r.resets,
                    r.all_finite,
                    r.max_collider_shrink_mm
                );
            }
        }
        ClothCommand::Fit {
            garment,
            size,
            shape,
            settle,
            body,
            json,
        } => {
            let model = load_body(body)?;
            let shape = fitroom::body_cli::load_shape(shape.as_deref())?;
            let (r, _) =
                fitroom::cloth_cli::fit_map(&model, &shape, &garment, size.as_deref(), settle)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&r)?);
            } else {
                println!(
                    "{} size {} ({}), settled {} s: strain max {:.1}% mean {:.2}%, mean gap {:.1} mm, max penetration {:.2} mm",
                    r.garment,
                    r.size,
                    r.fabric,
                    r.settle_s,
                    r.max_strain_pct,
                    r.mean_strain_pct,
                    r.mean_gap_mm,
                    r.max_penetration_mm
                );
                for e in &r.ease {
                    match (e.garment_girth_cm, e.ease_cm) {
                        (Some(g), Some(ease)) => println!(
                            "  {:<6} body {:.1} cm, garment {:.1} cm: ease {:+.1} cm",
                            e.landmark, e.body_girth_cm, g, ease
                        ),
                        _ => println!(
                            "  {:<6} body {:.1} cm: the garment does not go round the body there",
                            e.landmark, e.body_girth_cm
                        ),
                    }
                }
            }
        }
        ClothCommand::Bench {
            garment,
            frames,
            body,
            json,
        } => {
            let model = load_body(body)?;
            let dress = garment.unwrap_or_else(|| assets.join("garments/sundress.ron"));
            let motion = assets.join(fitroom::assets::DEFAULT_MOTION);
            let r = fitroom::cloth_cli::bench(&model, &dress, &motion, frames)?;
            if json {
                println!("{}", serde_json::to_string_pretty(&r)?);
            } else {
                println!(
                    "{} ({} particles, {} colliders, {} substeps, {} threads): {:.2} ms per 120 Hz step (p95 {:.2}); goal {} ms",
                    r.dress.garment,
                    r.dress.particles,
                    r.dress.colliders,
                    r.dress.substeps,
                    r.threads,
                    r.dress.step_ms.mean,
                    r.dress.step_ms.p95,
                    r.goal_ms
                );
                if let (Some(fine), Some(edge)) = (&r.dress_4k, r.dress_4k_edge_cm) {
                    println!(
                        "  re-meshed ({edge:.2} cm edges, {} particles): {:.2} ms per step (p95 {:.2})",
                        fine.particles, fine.step_ms.mean, fine.step_ms.p95,
                    );
                }
                for (n, s) in &r.scaling {
                    println!(
                        "  {n:>6} particles: {:.2} ms per step (p95 {:.2})",
                        s.mean, s.p95
                    );
                }
            }
        }
    }
    Ok(())
}
