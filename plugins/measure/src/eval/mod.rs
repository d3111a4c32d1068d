//! The evaluation: ANSUR II subjects made into bodies, filmed in the calibration pose by the
//! synthetic Kinect v1, measured by both methods, against the filmed body's own measurements.

pub mod record;

pub use record::{Recording, Stance, calibration_pose, record};

/// `f` of every item on `threads` threads, in the items' order (the result does not depend
/// on the number of threads).
pub fn parallel_map<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut out: Vec<Option<R>> = (0..items.len()).map(|_| None).collect();
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads.max(1))
            .map(|_| {
                scope.spawn(|| {
                    let mut done = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(item) = items.get(i) else {
                            break;
                        };
                        done.push((i, f(item)));
                    }
                    done
                })
            })
            .collect();
        for w in workers {
            if let Ok(done) = w.join() {
                for (i, r) in done {
                    out[i] = Some(r);
                }
            }
        }
    });
    out.into_iter().flatten().collect()
}

mod report;

pub use report::{
    MeasureReport, MeasureStats, PoseSource, SubjectResult, evaluate, held_out, tracked, training,
};
