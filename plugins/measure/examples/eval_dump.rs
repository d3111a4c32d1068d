//! Development loop for the tracker, without building the app: one recording with ground
//! truth, the evaluation as JSON (as `fitroom track eval --json` gives: the person's build
//! from the measurement's body fit), and on request:
//!
//! * `VERBOSE=1`: per frame, whether the fit (re)started, its statistics and each joint's error;
//! * `SIGNED=1`: each joint's mean signed error (a bias shows here, not in the mean distance);
//! * `SAVE_SHAPE=F.ron`: the estimated build written out;
//! * `JOINTS=F.jsonl`: per frame tracked, the tracked and the true joints, the
//!   confidences and the fit's figures (`fit`: share of points near the body, share of the
//!   body outside the silhouette, mean residual in metres, share of outliers) and the skirt
//!   found (`skirt`: its top and hem heights, the floor's normal, and whether it was found
//!   in the frame or is worn from the last frames), for analyses the
//!   report does not make;
//! * `PPM_FRAME=N`: frame N as a picture (`/tmp/frame.ppm`: depth, the person, the true and
//!   the tracked skeletons);
//! * `SHAPE=F.ron`, `SCALE=S`: track with a given body shape and size (to see what not knowing
//!   them costs); `FIXED=1`: the default body throughout (no estimate of the build);
//!   `OWN_SEARCH=1`: the build from the tracker's own macro search (the tracker crate alone,
//!   without the measurement's fit);
//!   `START_PULLED=1`: a start pulls the arms to the hands' ends only (no hanging arms tried);
//!   `NO_RECOVER=1`: no second hypothesis for limbs the fit seems to have lost; `NO_WALL=1`:
//!   the wall behind the person not taken out; `DENOISE`, `BUILD_DENOISE` (pixels about each
//!   reading averaged, by the tracker and by the build's fit; 0: none); `SKIRT_FORK`,
//!   `SKIRT_CREASE` (a skirt's least length below the hip joints, 0: none looked for; the
//!   crease that parts two legs, metres), `SKIRT_WIDTH`, `SKIRT_FLARE` (the zone's half-width
//!   in half hip spacings, its flare per metre down), `SKIRT_MEM_S`, `SKIRT_MEM_SHARE` (a
//!   skirt is worn if found in this share of the frames of the last seconds; 0 s: frame by
//!   frame), `SKIRT_WORN` (the weight of its points outside the body where it is worn but
//!   not found);
//!   `ITER`, `POINTS`, `DAMP`, `FREE`, `HUBER`, `OUTLIER`, `SCALE_STIFF`,
//!   `SNAPS`, `LOOKS` (looks at the build per person), `EVERY`, `CARRY_TURN`, `TURN_MARGIN`, `PMINW`, `ARM_FRONT_CAP`, `CLOTH_GAP`, `CLOTH_MARGIN` (the share by which the build fit's cost must fall under the layer), `SLEEVE_SEEN`, `SLEEVE_BARE` (the sleeves' steps that decide the layer, metres), `CONTACT`, `CONTACT_TOL` (the weight and tolerance of the forearms' contact with the trunk), `UNDER_LAYER`, `UNDER_OUTSIDE`, `UNDER_PRIOR` (the body under a shirt: its share of the layer, the weight of points outside the skin, the prior's weight), `CLOTHING` (the
//!   clothing layer tried, metres; 0: none), `TURN_CHECK` (frames between checks of a body
//!   turned away; 0: none), `LOST` (the share of points near the body under which a frame is
//!   reported lost; 0: never): override the settings; `FOLDED_AT_REST=1`: a folded arm also tried
//!   at rest; `INFLATE=T`: the given
//!   `SHAPE` in a clothing layer T metres thick;
//! * `MAXFRAMES=N`: the first N frames only (the build's looks are over by frame 70 when
//!   the person stands upright);
//! * `PARTS=F.forest`: a body-part forest's joint proposals as one more hypothesis for a
//!   limb suspected lost (grow one with the tracker's `parts` example).
//!
//! CPU time per frame (this thread's, from `/proc/thread-self/schedstat`: this host's wall
//! time is noisier) goes to stderr.
//!
//! `cargo run -p fitroom_measure --no-default-features --release --example eval_dump -- DIR`

use std::path::{Path, PathBuf};

use fitroom_body::BodyModel;
use fitroom_depth::DepthCamera;
use fitroom_depth::fakenect::Recording;
use fitroom_depth::truth::read_truth;
use fitroom_tracker::eval::Evaluation;
use fitroom_tracker::kinect::facing_degrees;
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};
use glam::Vec3;

type Error = Box<dyn std::error::Error>;

fn env(key: &str) -> Option<f32> {
    std::env::var(key).ok().and_then(|v| v.parse().ok())
}

fn settings() -> TrackerSettings {
    let mut s = TrackerSettings::default();
    if let Some(v) = env("ITER") {
        s.iterations = v as usize;
    }
    if let Some(v) = env("POINTS") {
        s.points = v as usize;
    }
    if let Some(v) = env("SNAPS") {
        s.shape.snapshots = v as usize;
    }
    if let Some(v) = env("LOOKS") {
        s.shape.looks = v as usize;
    }
    if let Some(v) = env("EVERY") {
        s.shape.every = v as usize;
    }
    if let Some(v) = env("TURN_CHECK") {
        s.turn_check_every = v as usize;
    }
    // The settings in metres or weights, each overridden by its variable if set.
    for (key, field) in [
        ("DAMP", &mut s.fit.damping),
        ("FREE", &mut s.fit.free_space_weight),
        ("HUBER", &mut s.fit.huber_m),
        ("SCALE_STIFF", &mut s.fit.scale_stiffness),
        ("OUTLIER", &mut s.fit.outlier_m),
        ("ARM_FRONT_CAP", &mut s.fit.arm_front_cap_m),
        ("CLOTH_GAP", &mut s.fit.cloth_gap_weight),
        ("SKIRT_WORN", &mut s.fit.skirt_worn_weight),
        ("SKIRT_MEM_S", &mut s.skirt.memory_s),
        ("SKIRT_MEM_SHARE", &mut s.skirt.memory_share),
        ("CONTACT", &mut s.fit.contact_weight),
        ("CONTACT_TOL", &mut s.fit.contact_tolerance_m),
        ("CARRY_TURN", &mut s.carry_turn),
        ("TURN_MARGIN", &mut s.turn_margin),
        ("SLEEVE_SEEN", &mut s.sleeve_seen_m),
        ("SLEEVE_BARE", &mut s.sleeve_bare_m),
        ("CLOTH_MARGIN", &mut s.clothing_margin),
        ("CLOTHING", &mut s.clothing_m),
        ("PMINW", &mut s.parts_min_weight),
        ("LOST", &mut s.lost_inliers),
        ("SKIRT_FORK", &mut s.skirt.fork_m),
        ("SKIRT_CREASE", &mut s.skirt.crease_m),
        ("SKIRT_WIDTH", &mut s.skirt.width),
        ("SKIRT_FLARE", &mut s.skirt.flare),
    ] {
        if let Some(v) = env(key) {
            *field = v;
        }
    }
    s.start_arms_hanging = std::env::var("START_PULLED").is_err();
    s.recover_folded_at_rest = std::env::var("FOLDED_AT_REST").is_ok();
    s.segment.wall = std::env::var("NO_WALL").is_err();
    s.scale = env("SCALE");
    if let Some(v) = env("DENOISE") {
        s.denoise_px = v as usize;
    }
    s.recover = std::env::var("NO_RECOVER").is_err();
    s
}

fn main() -> Result<(), Error> {
    let dir = PathBuf::from(std::env::args().nth(1).ok_or("usage: eval_dump DIR")?);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    let model = BodyModel::read(&path)?;
    let positions = match std::env::var("SHAPE") {
        Ok(path) => {
            let shape: fitroom_body::Shape = ron::from_str(&std::fs::read_to_string(path)?)?;
            model.shaped(&shape)?.positions
        }
        Err(_) => model.positions.clone(),
    };
    // A given shape is kept; else the person's build is estimated while tracking, unless
    // FIXED is set (the default body throughout).
    let mut tracker = if std::env::var("SHAPE").is_ok() || std::env::var("FIXED").is_ok() {
        let mut body = TrackBody::new(&model, &positions)?;
        // A given body in the clothing layer (`TrackBody::clothe`), e.g. the true shape.
        if let Some(t) = env("INFLATE") {
            body.clothe(t);
        }
        Tracker::new(body, settings())
    } else if std::env::var("OWN_SEARCH").is_ok() {
        Tracker::estimating(std::sync::Arc::new(model.clone()), settings())?
    } else {
        let prior = std::sync::Arc::new(fitroom_measure::ShapePrior::shipped()?);
        let mut build = fitroom_measure::build::TrackedBuild::new(prior);
        if let Some(v) = env("UNDER_LAYER") {
            build.under_layer = v;
        }
        if let Some(v) = env("UNDER_PRIOR") {
            build.under_prior = v;
        }
        if let Some(v) = env("UNDER_OUTSIDE") {
            build.under_outside_weight = v;
        }
        if let Some(v) = env("BUILD_DENOISE") {
            build.denoise_px = v as usize;
        }
        Tracker::estimating(std::sync::Arc::new(model.clone()), settings())?
            .with_build_fit(std::sync::Arc::new(build))
    };
    if let Ok(path) = std::env::var("PARTS") {
        let forest = fitroom_tracker::bodyparts::Forest::read(&mut std::fs::File::open(path)?)?;
        tracker = tracker.with_parts(std::sync::Arc::new(forest));
    }
    let recording = Recording::open(&dir)?;
    let truth = read_truth(&dir)?.ok_or("the recording has no ground truth")?;
    let picture_at: Option<usize> = std::env::var("PPM_FRAME").ok().and_then(|v| v.parse().ok());
    let mut eval = Evaluation::new();
    let mut signed = [(Vec3::ZERO, 0usize); 20];
    let mut cpu_ms: Vec<f64> = Vec::new();
    let mut last_size = None;
    let mut joints_out = match std::env::var("JOINTS") {
        Ok(path) => Some(std::io::BufWriter::new(std::fs::File::create(path)?)),
        Err(_) => None,
    };
    let max_frames = env("MAXFRAMES").map(|v| v as usize).unwrap_or(usize::MAX);
    for (entry, line) in recording.depth_entries().zip(&truth).take(max_frames) {
        let frame = recording.read_depth(entry, DepthCamera::default())?;
        let joints: Vec<Vec3> = line.joints.iter().map(|j| Vec3::from_array(*j)).collect();
        let start = cpu_ns();
        let out = eval.step(&mut tracker, &frame, &joints);
        cpu_ms.push(cpu_ns().saturating_sub(start) as f64 / 1e6);
        if picture_at == Some(line.frame) {
            let mut bytes = b"P6 640 480 255\n".to_vec();
            bytes.extend(fitroom_tracker::draw::picture(
                &frame,
                out.as_ref(),
                &joints,
            ));
            std::fs::write("/tmp/frame.ppm", bytes)?;
        }
        let Some(t) = out else { continue };
        last_size = Some(t.pose.scale * tracker.body.height_m);
        if let Some(out) = joints_out.as_mut() {
            use std::io::Write;
            let line = serde_json::json!({
                "frame": line.frame,
                "started": t.started,
                "tracked": t.joints.iter().map(|j| j.position.to_array()).collect::<Vec<_>>(),
                "truth": joints.iter().map(|j| j.to_array()).collect::<Vec<_>>(),
                "confidence": t.joints.iter().map(|j| format!("{:?}", j.confidence)).collect::<Vec<_>>(),
                "fit": [t.fit.inliers, t.fit.outside, t.fit.mean_residual_m, t.fit.outliers],
                // The skirt found: its top and hem, heights along the floor's normal, and
                // that normal (sensor space).
                "skirt": t.skirt.as_ref().map(|z| (z.top, z.hem, z.up.to_array(), z.seen)),
            });
            writeln!(out, "{line}")?;
        }
        for ((sum, j), g) in signed.iter_mut().zip(&t.joints).zip(&joints) {
            sum.0 += j.position - *g;
            sum.1 += 1;
        }
        if std::env::var("VERBOSE").is_ok() {
            let errors: Vec<String> = t
                .joints
                .iter()
                .zip(&joints)
                .map(|(j, g)| format!("{:.0}", j.position.distance(*g) * 1000.0))
                .collect();
            let tracked: Vec<Vec3> = t.joints.iter().map(|j| j.position).collect();
            println!(
                "frame {} start {} inliers {:.2} outside {:.2} residual {:.1} mm scale {:.3} yaw {:.0} true {:.0} | {}",
                line.frame,
                t.started,
                t.fit.inliers,
                t.fit.outside,
                t.fit.mean_residual_m * 1000.0,
                t.pose.scale,
                facing_degrees(&tracked),
                facing_degrees(&joints),
                errors.join(" ")
            );
        }
    }
    cpu_ms.sort_by(f64::total_cmp);
    if let (Some(median), Some(p95)) = (
        cpu_ms.get(cpu_ms.len() / 2),
        cpu_ms.get(cpu_ms.len() * 95 / 100),
    ) {
        eprintln!("cpu ms per frame: median {median:.2}, p95 {p95:.2}");
    }
    if let Some(size) = last_size {
        eprintln!("height (the body's, as sized in the last frame tracked): {size:.4} m");
    }
    if let Some(step) = tracker.sleeve_step_m() {
        eprintln!("sleeve step (median): {:.1} mm", step * 1000.0);
    }
    if let Some(e) = &tracker.shape_error {
        eprintln!("build: {e}");
    }
    if let Some(e) = &tracker.shape {
        eprintln!(
            "build: gender {:.2} weight {:.2} muscle {:.2} height {:.2} proportions {:.2} (cost {:.2} mm, default {:.2} mm, {} bodies tried), clothing {:.1} cm",
            e.shape.gender,
            e.shape.weight,
            e.shape.muscle,
            e.shape.height,
            e.shape.proportions,
            e.cost_m.unwrap_or(f32::NAN) * 1000.0,
            e.default_cost_m.unwrap_or(f32::NAN) * 1000.0,
            e.evaluations,
            e.clothing_m * 100.0
        );
        if let Ok(path) = std::env::var("SAVE_SHAPE") {
            let text = ron::ser::to_string_pretty(&e.shape, ron::ser::PrettyConfig::default())?;
            std::fs::write(path, text)?;
        }
    }
    if std::env::var("SIGNED").is_ok() {
        for (k, (sum, n)) in signed.iter().enumerate() {
            let m = *sum / (*n).max(1) as f32 * 1000.0;
            println!(
                "joint {k:>2} mean signed error ({:>5.0}, {:>5.0}, {:>5.0}) mm",
                m.x, m.y, m.z
            );
        }
    }
    println!(
        "{}",
        serde_json::to_string_pretty(&eval.report(tracker.starts))?
    );
    Ok(())
}

/// This thread's CPU time, ns.
fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}
