//! Playing a fakenect recording as a live stream: its depth frames at their recorded pace
//! (or faster or slower), looping on request. A frame that cannot be read is reported and
//! skipped; the stream goes on with the next.

use std::path::Path;

use crate::camera::DepthCamera;
use crate::fakenect::{Entry, FakenectError, Recording};
use crate::frame::DepthFrame;

/// A recording played against a clock.
pub struct Player {
    recording: Recording,
    depth: Vec<Entry>,
    camera: DepthCamera,
    /// Seconds of recording per second of play.
    pub speed: f64,
    pub looping: bool,
    /// Play time, seconds of recording since the current pass began.
    clock_s: f64,
    /// The next frame to deliver.
    next: usize,
    /// Completed passes over the recording.
    passes: u64,
}

/// What [`Player::advance`] delivered.
#[derive(Debug)]
pub struct Delivered {
    /// The newest frame that became due (older ones due at the same time are skipped: a
    /// viewer wants the present), with its index in the recording.
    pub frame: Option<(usize, DepthFrame)>,
    /// Frames due but skipped for a newer one.
    pub skipped: usize,
}

impl Player {
    /// Opens the recording in `dir` (see [`Recording::open`] for what is checked).
    pub fn open(dir: &Path, camera: DepthCamera) -> Result<Self, FakenectError> {
        let recording = Recording::open(dir)?;
        let depth: Vec<Entry> = recording.depth_entries().cloned().collect();
        if depth.is_empty() {
            return Err(FakenectError::Empty {
                index: dir.join(crate::fakenect::INDEX),
            });
        }
        Ok(Self {
            recording,
            depth,
            camera,
            speed: 1.0,
            looping: true,
            clock_s: 0.0,
            next: 0,
            passes: 0,
        })
    }

    pub fn recording(&self) -> &Recording {
        &self.recording
    }

    /// Depth frames in the recording.
    pub fn len(&self) -> usize {
        self.depth.len()
    }

    /// Never: an empty recording is refused by [`Self::open`].
    pub fn is_empty(&self) -> bool {
        self.depth.is_empty()
    }

    /// Whether a recording that does not loop has played out.
    pub fn finished(&self) -> bool {
        !self.looping && self.next >= self.depth.len()
    }

    /// Seconds from the first depth frame to `entry`.
    fn offset_s(&self, entry: &Entry) -> f64 {
        entry.time_s - self.depth[0].time_s
    }

    /// The length of one pass: the last frame's offset plus one frame interval.
    fn pass_s(&self) -> f64 {
        let n = self.depth.len();
        let last = self.offset_s(&self.depth[n - 1]);
        last + if n > 1 {
            last / (n - 1) as f64
        } else {
            1.0 / 30.0
        }
    }

    /// Advances play by `dt_s` seconds of wall time and reads the newest frame that became
    /// due. A frame that cannot be read is an error for this call; the next call goes on
    /// after it.
    pub fn advance(&mut self, dt_s: f64) -> Result<Delivered, FakenectError> {
        self.clock_s += dt_s.max(0.0) * self.speed.max(0.0);
        let mut due = None;
        let mut skipped = 0;
        loop {
            if self.next >= self.depth.len() {
                if !self.looping {
                    break;
                }
                self.clock_s -= self.pass_s();
                self.next = 0;
                self.passes += 1;
            }
            if self.offset_s(&self.depth[self.next]) > self.clock_s {
                break;
            }
            skipped += usize::from(due.is_some());
            due = Some(self.next);
            self.next += 1;
        }
        let frame = match due {
            Some(index) => {
                let mut frame = self.recording.read_depth(&self.depth[index], self.camera)?;
                frame.time_s += self.passes as f64 * self.pass_s();
                Some((index, frame))
            }
            None => None,
        };
        Ok(Delivered { frame, skipped })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{PIXELS, RAW_NO_VALUE};
    use crate::fakenect::RecordingWriter;

    fn recording(frames: usize) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("fitroom-player-{}-{frames}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut writer = RecordingWriter::create(&dir).expect("scratch folder");
        for f in 0..frames {
            let mut raw = vec![RAW_NO_VALUE; PIXELS];
            raw[0] = 500 + f as u16;
            writer
                .write_depth(10.0 + f as f64 / 30.0, f as u32, &raw)
                .expect("written");
        }
        dir
    }

    #[test]
    fn plays_at_the_recorded_pace_and_loops() {
        let dir = recording(3);
        let mut player = Player::open(&dir, DepthCamera::default()).expect("opens");
        let index = |d: Delivered| d.frame.map(|(i, f)| (i, f.raw.expect("raw")[0]));
        // The first frame is due at once; the next 1/30 s later.
        assert_eq!(index(player.advance(0.0).expect("reads")), Some((0, 500)));
        assert_eq!(index(player.advance(0.02).expect("reads")), None);
        assert_eq!(index(player.advance(0.02).expect("reads")), Some((1, 501)));
        assert_eq!(index(player.advance(0.05).expect("reads")), Some((2, 502)));
        // Past the end: the first frame again, its time going on from the first pass (a
        // pass is 3 frames of 1/30 s).
        let (i, frame) = player.advance(0.02).expect("reads").frame.expect("due");
        assert_eq!(i, 0);
        assert!((frame.time_s - 0.1).abs() < 1e-5, "{}", frame.time_s);
        // Two frames due at once: the newer is delivered, the older counted as skipped.
        let d = player.advance(0.06).expect("reads");
        assert_eq!((d.skipped, d.frame.map(|(i, _)| i)), (1, Some(2)));
        std::fs::remove_dir_all(&dir).expect("cleaned");
    }

    #[test]
    fn without_looping_it_plays_out_and_twice_as_fast_is_twice_as_fast() {
        let dir = recording(4);
        let mut player = Player::open(&dir, DepthCamera::default()).expect("opens");
        player.looping = false;
        player.speed = 2.0;
        // Four frames 1/30 s apart are 0.1 s of recording, 0.05 s at twice the pace: six
        // steps of 1/120 s (the first frame is due at once).
        let mut got = Vec::new();
        let mut steps = 0;
        while !player.finished() && steps < 20 {
            if let Some((i, _)) = player.advance(1.0 / 120.0).expect("reads").frame {
                got.push(i);
            }
            steps += 1;
        }
        assert_eq!(got, vec![0, 1, 2, 3]);
        assert_eq!(steps, 6);
        assert!(player.finished());
        std::fs::remove_dir_all(&dir).expect("cleaned");
    }
}
