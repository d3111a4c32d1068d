//! The calibration's stillness check against the tracker changing its body: when the tracker
//! takes a new build or size for the person, every joint moves though the person does not;
//! that must not restart the view (it did, now and then, in the app: the build's search ends
//! on its own thread whenever it ends).

use std::path::Path;

use fitroom_body::{BodyModel, Shape};
use fitroom_depth::synthetic::NoiseSettings;
use fitroom_measure::calibration::{Collecting, Collector, Progress};
use fitroom_measure::eval::{Stance, record};
use fitroom_tracker::{TrackBody, Tracker, TrackerSettings};
use glam::Vec3;

/// The progress after each frame of a still person whose tracked joints all move 6 cm from
/// frame 10 on, with the tracker's body marked changed there or not.
fn progress(body_changed: bool) -> Vec<Progress> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/bodies/makehuman.fitbody");
    let model = BodyModel::read(&path).expect("the shipped body");
    let rec = record(
        &model,
        &Shape::default(),
        &Stance::drawn(8),
        36,
        NoiseSettings::default(),
        8,
        None,
    )
    .expect("a recording");
    let body = TrackBody::new(&model, &model.positions).expect("a trackable body");
    let mut tracker = Tracker::new(body, TrackerSettings::default());
    let mut collector = Collector::default();
    rec.frames
        .iter()
        .enumerate()
        .map(|(k, f)| {
            let mut tracked = tracker.track(&f.depth).expect("the person tracked");
            if k >= 10 {
                for j in &mut tracked.joints {
                    j.position += Vec3::new(0.06, 0.0, 0.0);
                }
                if body_changed {
                    tracked.body_changes += 1;
                }
            }
            collector.offer(&f.depth, Some(&tracked))
        })
        .collect()
}

#[test]
fn a_change_of_the_trackers_body_is_not_the_person_moving() {
    let changed = progress(true);
    let moved = progress(false);
    // From the frame the joints move on (the first frames have their own hints).
    let restarted = |ps: &[Progress]| {
        ps[10..].iter().any(|p| {
            matches!(p, Progress::Collecting(Collecting { hint: Some(h), .. }) if h.contains("stand still"))
        })
    };
    assert!(
        restarted(&moved),
        "joints 6 cm off with the same body: the person moved"
    );
    assert!(
        !restarted(&changed),
        "the tracker's new body taken for a move"
    );
    assert!(
        matches!(
            changed.last(),
            Some(Progress::Collecting(Collecting { view: 1, .. }))
        ),
        "the front view collected: {:?}",
        changed.last()
    );
}
