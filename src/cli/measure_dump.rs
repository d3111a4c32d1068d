//! `fitroom measure record` films a held-out ANSUR II subject's calibration into a fakenect
//! dump; `fitroom measure dump` measures the person in a dump (a Kinect's recording, or one
//! of those), through the tracker and the calibration's checks as the kiosk does.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use fitroom_body::ansur::sample;
use fitroom_body::{FitOptions, FitRequest, Measure, SizeChart, fit};
use fitroom_depth::DepthCamera;
use fitroom_depth::fakenect::{Recording, RecordingWriter};
use fitroom_depth::synthetic::NoiseSettings;
use fitroom_measure::calibration::{Collecting, Collector, Progress};
use fitroom_measure::eval::{Stance, TURN_DEG, held_out, record};
use fitroom_measure::tracked::tracked_views;
use fitroom_measure::{FitSettings, ShapePrior, ViewPose, measure_person};
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};
use serde::Serialize;

use super::measure::{SurveyArgs, chart, survey};

#[derive(clap::Args)]
pub struct RecordArgs {
    /// The dump folder to write (fakenect's format: INDEX.txt and one file per frame).
    pub out: PathBuf,
    #[command(flatten)]
    pub survey: SurveyArgs,
    /// Which of the held-out subjects (a seeded sample: `--seed`).
    #[arg(long, default_value_t = 0)]
    pub index: usize,
    /// Frames facing the sensor and frames turned (30 Hz).
    #[arg(long, default_value_t = 40)]
    pub frames: usize,
}

#[derive(clap::Args)]
pub struct DumpArgs {
    /// The dump folder (fakenect's format).
    pub dump: PathBuf,
    #[command(flatten)]
    pub body: super::BodyArg,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
    /// Threads for the fit (both genders at once with 2).
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Print each frame's calibration progress (and what was wrong with it) to stderr.
    #[arg(long)]
    pub verbose: bool,
}

/// What `record` writes beside the frames: who was filmed, and their true measurements.
#[derive(Serialize)]
struct Filmed {
    subject: String,
    female: bool,
    stance: Stance,
    turn_deg: f32,
    measurements_cm: Vec<(Measure, f32)>,
}

/// `fitroom measure record`: the subject standing facing the sensor, then turned.
pub fn record_calibration(args: RecordArgs) -> Result<()> {
    let model = args.survey.body.load()?;
    let all = survey(&args.survey.data)?;
    let pool = held_out(&all);
    let picked = sample(&pool, args.index + 1, args.survey.seed);
    let Some(subject) = picked.get(args.index) else {
        bail!(
            "--index {} is beyond the {} held-out subjects",
            args.index,
            pool.len()
        );
    };
    let request = FitRequest {
        gender: if subject.female { 0.0 } else { 1.0 },
        age_years: None,
        targets: subject.measurements.clone(),
    };
    let shape = fit(&model, &request, &FitOptions::default())?.shape;
    let stance = Stance::drawn(args.survey.seed ^ args.index as u64);
    let mut writer = RecordingWriter::create(&args.out)
        .with_context(|| format!("cannot write the dump '{}'", args.out.display()))?;
    let mut truth = None;
    let mut time_s = 0.0;
    for (i, st) in [stance, stance.turned(TURN_DEG)].iter().enumerate() {
        let rec = record(
            &model,
            &shape,
            st,
            args.frames,
            NoiseSettings::default(),
            args.survey.seed ^ (i as u64) << 40,
            None,
        )?;
        truth.get_or_insert(model.measure(&rec.body.positions)?);
        for f in &rec.frames {
            let Some(raw) = &f.depth.raw else {
                bail!("the synthetic camera gave no raw values");
            };
            writer.write_depth(time_s, (time_s * 30.0) as u32, raw)?;
            time_s += 1.0 / 30.0;
        }
    }
    let truth = truth.context("nothing was filmed")?;
    let filmed = Filmed {
        subject: subject.id.clone(),
        female: subject.female,
        stance,
        turn_deg: TURN_DEG,
        measurements_cm: Measure::ALL.iter().map(|&m| (m, m.of(&truth))).collect(),
    };
    let path = args.out.join("truth.json");
    std::fs::write(&path, serde_json::to_string_pretty(&filmed)?)
        .with_context(|| format!("cannot write '{}'", path.display()))?;
    println!(
        "ANSUR II subject {} ({}) filmed: {} frames facing the sensor, {} turned {TURN_DEG:.0}°, in {}; the truth in {}",
        subject.id,
        if subject.female { "woman" } else { "man" },
        args.frames,
        args.frames,
        args.out.display(),
        path.display()
    );
    Ok(())
}

/// What `dump` reports.
#[derive(Serialize)]
struct Measured {
    dump: String,
    /// Frames read, and the frames the measurement used.
    frames_read: usize,
    frames_used: usize,
    female: bool,
    /// Per measure: value and one standard deviation, cm.
    measurements_cm: Vec<(Measure, f32, f32)>,
    /// EN 13402 size of the found gender's chart, and why.
    size: Option<String>,
    size_reason: String,
    fit_ms: f64,
}

/// `fitroom measure dump`: the recording's frames through the tracker and the calibration's
/// checks until both views are collected, then measured.
pub fn measure_dump(args: DumpArgs) -> Result<()> {
    let model = args.body.load()?;
    let prior = ShapePrior::shipped()?;
    let recording = Recording::open(&args.dump)
        .with_context(|| format!("cannot read the dump '{}'", args.dump.display()))?;
    let body = TrackBody::new(&model, &model.positions)?;
    let mut tracker = Tracker::new(body, TrackerSettings::default());
    let mut collector = Collector::default();
    let (mut read, mut last) = (0, None);
    for frame in recording.depth_frames(DepthCamera::default()) {
        let frame = frame.with_context(|| format!("{}: frame {read}", args.dump.display()))?;
        read += 1;
        let tracked = tracker.track(&frame);
        let progress = collector.offer(&frame, tracked.as_ref());
        if args.verbose {
            eprintln!("frame {}: {progress:?}", read - 1);
        }
        if progress == Progress::Complete {
            last = None;
            break;
        }
        last = Some(progress);
    }
    if let Some(Progress::Collecting(Collecting {
        view,
        views,
        frames,
        need,
        hint,
    })) = last
    {
        bail!(
            "the recording ended before the calibration was complete ({read} frames read; view {} of {views}: {frames} of {need} frames{}): record a person standing still a second facing the sensor, then a second turned halfway to the side",
            view + 1,
            hint.map_or(String::new(), |h| format!(
                "; the last frame's problem: {h}"
            ))
        );
    }
    let seen = collector
        .take_views()
        .context("the recording has no frames")?;
    let used = seen.iter().map(|(f, _)| f.len()).sum();
    let began = Instant::now();
    let views = tracked_views(&model, &seen)?;
    let poses: Vec<ViewPose> = views.iter().map(|v| v.as_view_pose()).collect();
    let settings = FitSettings {
        threads: args.threads.max(1),
        ..FitSettings::default()
    };
    let person = measure_person(&model, &poses, &prior, &settings)?;
    let fit_ms = began.elapsed().as_secs_f64() * 1e3;
    let chart: SizeChart = chart(if person.female {
        "en13402-female-seed002.ron"
    } else {
        "en13402-male-seed002.ron"
    })?;
    let r = chart.recommend(&person.estimate.measurements);
    let reason = r
        .measures
        .iter()
        .filter(|a| r.decided_by.contains(&a.measure))
        .map(|a| a.reason.clone())
        .collect::<Vec<_>>()
        .join("; ");
    let sd = |m: Measure| {
        person
            .estimate
            .uncertainty_cm
            .iter()
            .find(|(k, _)| *k == m)
            .map_or(f32::NAN, |(_, s)| *s)
    };
    let out = Measured {
        dump: args.dump.display().to_string(),
        frames_read: read,
        frames_used: used,
        female: person.female,
        measurements_cm: Measure::ALL
            .iter()
            .map(|&m| (m, m.of(&person.estimate.measurements), sd(m)))
            .collect(),
        size: r.size.clone(),
        size_reason: reason,
        fit_ms,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        print_measured(&out, &args.dump);
    }
    Ok(())
}

fn print_measured(m: &Measured, dump: &Path) {
    println!(
        "{}: {} frames read, {} used; {}; fitted in {:.0} ms",
        dump.display(),
        m.frames_read,
        m.frames_used,
        if m.female { "a woman" } else { "a man" },
        m.fit_ms
    );
    for (measure, value, sd) in &m.measurements_cm {
        println!("  {:<14} {value:6.1} cm ± {sd:.1}", measure.name());
    }
    match &m.size {
        Some(size) => println!("EN 13402 size {size} ({})", m.size_reason),
        None => println!("no EN 13402 size fits ({})", m.size_reason),
    }
}
