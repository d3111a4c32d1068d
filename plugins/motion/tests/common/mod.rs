//! Helpers shared by the motion crate's tests: the committed clips, the body asset, a seeded RNG.
#![allow(dead_code)]

use std::path::Path;

use fitroom_body::BodyModel;
use fitroom_motion::AvatarSkeleton;
use fitroom_sensor::{SensorFrame, bvh_source::BvhSource};
use glam::Vec3;

/// The clip names listed in the committed `INDEX.tsv` (`data/mocap/cmu`).
pub fn cmu_index() -> Vec<String> {
    fitroom_testdata::cmu_index()
        .into_iter()
        .map(|c| c.file)
        .collect()
}

/// The clean 30 Hz stream of one loop of a clip.
pub fn clean_frames(file: &str) -> Vec<SensorFrame> {
    let source =
        BvhSource::load(fitroom_testdata::clip_path(file), Default::default()).expect(file);
    let n = (source.clip_duration_s() * 30.0).floor() as usize;
    (0..=n).map(|k| source.frame_at(k as f64 / 30.0)).collect()
}

/// The committed body asset.
pub fn body() -> BodyModel {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/bodies/makehuman.fitbody"
    );
    BodyModel::read(Path::new(path))
        .expect("body asset (create it with `fitroom import makehuman`)")
}

/// The avatar skeleton of the committed body.
pub fn skeleton() -> AvatarSkeleton {
    let model = body();
    let rest = model.rest_pose(&model.positions);
    fitroom_motion::avatar_skeleton(&model, &rest).expect("skeleton")
}

/// A small seeded generator (SplitMix64) with Gaussian samples (Box–Muller).
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1), 53 bits.
    pub fn uniform_f64(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Standard normal, f64.
    pub fn gaussian(&mut self) -> f64 {
        let (u1, u2) = (self.uniform_f64(), self.uniform_f64());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// Uniform in (0, 1), 24 bits.
    pub fn uniform(&mut self) -> f32 {
        ((self.next_u64() >> 40) as f32 + 0.5) / (1u64 << 24) as f32
    }

    /// Standard normal, f32.
    pub fn gauss(&mut self) -> f32 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f32::consts::TAU * v).cos()
    }

    pub fn gauss3(&mut self) -> Vec3 {
        Vec3::new(self.gauss(), self.gauss(), self.gauss())
    }
}
