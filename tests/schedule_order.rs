//! The order of a frame is said once (`fitroom_schedule`): no two of our systems that touch the
//! same data run in an unspecified order. Bevy's ambiguity detection lists every pair of
//! systems with conflicting access and no ordering between them; these tests fail on any pair
//! in which both systems are ours (Bevy's own internal pairs are Bevy's business).

mod common;

use std::collections::HashMap;

use bevy::ecs::schedule::{Schedules, SystemKey};
use bevy::prelude::*;
use fitroom::{AppOptions, Mode, headless};

/// `(schedule, system, system, conflicting data)` for every unordered pair of our systems.
fn our_ambiguities(app: &mut App) -> Vec<String> {
    let mut found = Vec::new();
    app.world_mut()
        .resource_scope(|world, mut schedules: Mut<Schedules>| {
            for (label, schedule) in schedules.iter_mut() {
                if let Err(e) = schedule.initialize(world) {
                    found.push(format!("{label:?} does not build: {e}"));
                    continue;
                }
                // Built, the schedule holds its systems (the graph keeps only their keys).
                let names: HashMap<SystemKey, String> = match schedule.systems() {
                    Ok(systems) => systems
                        .map(|(key, system)| (key, system.name().to_string()))
                        .collect(),
                    Err(e) => {
                        found.push(format!("{label:?}: {e}"));
                        continue;
                    }
                };
                let name = |key: &SystemKey| names.get(key).cloned().unwrap_or_default();
                for (a, b, data) in schedule.graph().conflicting_systems().iter() {
                    let (a, b) = (name(a), name(b));
                    if a.starts_with("fitroom") && b.starts_with("fitroom") {
                        let data: Vec<String> = data
                            .iter()
                            .map(|&id| {
                                world
                                    .components()
                                    .get_name(id)
                                    .map_or_else(|| format!("{id:?}"), |n| n.to_string())
                            })
                            .collect();
                        found.push(format!("{label:?}: {a} and {b} on [{}]", data.join(", ")));
                    }
                }
            }
        });
    found
}

fn assert_unambiguous(options: &AppOptions) {
    let mut app = headless::headless_app(options).expect("the app builds");
    // Run a few frames so that every schedule the app uses has been built once.
    for _ in 0..3 {
        app.update();
    }
    let found = our_ambiguities(&mut app);
    assert!(
        found.is_empty(),
        "{} unordered pairs of our systems:\n{}",
        found.len(),
        found.join("\n")
    );
}

/// The whole headless pipeline wearing a garment: sensor, motion, body, garment, kiosk flow,
/// stage timing.
#[test]
fn our_systems_run_in_a_said_order() {
    let mut options = common::clip_options(Mode::Headless { render: false });
    options.garment = Some(
        fitroom::assets::assets_dir()
            .expect("assets")
            .join("garments/skirt.ron"),
    );
    assert_unambiguous(&options);
}
