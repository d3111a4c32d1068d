//! Worker threads and the phase scheduler that runs one step in parallel.
//!
//! A step is a fixed list of *phases* (predict, each constraint colour, collide, …); each
//! phase is a fixed list of *items* (a range of particles or of constraints). Items of one
//! phase write disjoint data (particles of one colour share no particle), so they may run in
//! any order on any thread. Every thread — the caller's and the pool's workers — runs the
//! same loop: wait until the previous phase is complete, then claim items of this phase from
//! an atomic counter until none are left. Because the items and their contents do not depend
//! on which thread runs them, the result is bit-for-bit the same for any number of threads.
//!
//! A thread waits for a phase only while another thread is still inside one of its items, so
//! a worker that the OS deschedules (the machine is shared) delays the step by at most one
//! item. Waiting spins briefly and then yields. Between steps the workers sleep on a condition
//! variable.
//!
//! The workers are persistent (spawning threads per step would cost tens of microseconds and
//! allocate); the job they run borrows the solver's data for the duration of
//! `WorkerPool::run`, which does not return before every worker has left the job.

use std::cell::UnsafeCell;
use std::marker::PhantomData;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;

type Job = dyn Fn() + Sync;

#[derive(Clone, Copy)]
struct JobPtr(*const Job);
// SAFETY: the pointee is `Sync` and outlives every use (see `WorkerPool::run`).
unsafe impl Send for JobPtr {}

struct State {
    generation: u64,
    job: Option<JobPtr>,
    running: usize,
    shutdown: bool,
    panicked: bool,
}

struct Shared {
    state: Mutex<State>,
    wake: Condvar,
    finished: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, State> {
        // A poisoned lock only means a worker panicked while holding it; the state is plain
        // data that stays consistent, so carry on.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// A pool of `threads - 1` persistent workers; the caller's thread is the remaining one.
pub(crate) struct WorkerPool {
    shared: Arc<Shared>,
    workers: Vec<JoinHandle<()>>,
}

impl WorkerPool {
    pub fn new(threads: usize) -> Self {
        let shared = Arc::new(Shared {
            state: Mutex::new(State {
                generation: 0,
                job: None,
                running: 0,
                shutdown: false,
                panicked: false,
            }),
            wake: Condvar::new(),
            finished: Condvar::new(),
        });
        let workers = (1..threads.max(1))
            .filter_map(|k| {
                let shared = Arc::clone(&shared);
                std::thread::Builder::new()
                    .name(format!("cloth-worker-{k}"))
                    .spawn(move || worker_loop(&shared))
                    .ok()
            })
            .collect();
        Self { shared, workers }
    }

    /// Threads that run a job: the workers and the caller.
    pub fn threads(&self) -> usize {
        self.workers.len() + 1
    }

    /// Runs `job` on every thread of the pool (the caller included) and returns when all of
    /// them have returned from it.
    pub fn run<'job>(&self, job: &(dyn Fn() + Sync + 'job)) {
        if self.workers.is_empty() {
            job();
            return;
        }
        let ptr: *const (dyn Fn() + Sync + 'job) = job;
        // SAFETY: only the lifetime is erased. `WaitForWorkers` below does not let this
        // function return (or unwind) before every worker has finished calling the job, so the
        // borrow outlives every use.
        let ptr: *const (dyn Fn() + Sync + 'static) = unsafe { std::mem::transmute(ptr) };
        {
            let mut state = self.shared.lock();
            state.job = Some(JobPtr(ptr));
            state.generation = state.generation.wrapping_add(1);
            state.running = self.workers.len();
            state.panicked = false;
        }
        self.shared.wake.notify_all();
        let wait = WaitForWorkers(&self.shared);
        job();
        drop(wait);
        if self.shared.lock().panicked {
            panic!("a cloth worker thread panicked during the step");
        }
    }
}

struct WaitForWorkers<'a>(&'a Shared);

impl Drop for WaitForWorkers<'_> {
    fn drop(&mut self) {
        let mut state = self.0.lock();
        while state.running > 0 {
            state = self
                .0
                .finished
                .wait(state)
                .unwrap_or_else(|e| e.into_inner());
        }
        state.job = None;
    }
}

impl Drop for WorkerPool {
    fn drop(&mut self) {
        self.shared.lock().shutdown = true;
        self.shared.wake.notify_all();
        for worker in self.workers.drain(..) {
            let _ = worker.join();
        }
    }
}

fn worker_loop(shared: &Shared) {
    let mut seen = 0u64;
    loop {
        let job = {
            let mut state = shared.lock();
            while state.generation == seen && !state.shutdown {
                state = shared.wake.wait(state).unwrap_or_else(|e| e.into_inner());
            }
            if state.shutdown {
                return;
            }
            seen = state.generation;
            state.job
        };
        let ok = match job {
            // SAFETY: `WorkerPool::run` keeps the job alive until `running` reaches zero.
            Some(job) => catch_unwind(AssertUnwindSafe(|| unsafe { (*job.0)() })).is_ok(),
            None => true,
        };
        let mut state = shared.lock();
        if !ok {
            state.panicked = true;
        }
        state.running -= 1;
        if state.running == 0 {
            shared.finished.notify_all();
        }
    }
}

/// Per-phase claim and completion counters.
pub(crate) struct PhaseCounters {
    claimed: Vec<AtomicU32>,
    done: Vec<AtomicU32>,
    abort: AtomicBool,
}

impl PhaseCounters {
    pub fn new() -> Self {
        Self {
            claimed: Vec::new(),
            done: Vec::new(),
            abort: AtomicBool::new(false),
        }
    }

    /// Makes room for `phases` phases and zeroes the counters (single-threaded, before a run).
    pub fn reset(&mut self, phases: usize) {
        if self.claimed.len() < phases {
            self.claimed.resize_with(phases, || AtomicU32::new(0));
            self.done.resize_with(phases, || AtomicU32::new(0));
        }
        for c in &mut self.claimed[..phases] {
            *c.get_mut() = 0;
        }
        for c in &mut self.done[..phases] {
            *c.get_mut() = 0;
        }
        *self.abort.get_mut() = false;
    }

    /// The loop every thread runs: phases in order, items claimed dynamically.
    /// `items[p]` is the item count of phase `p`; `exec(p, k)` runs item `k` of phase `p`.
    pub fn run_phases(&self, items: &[u32], exec: &(dyn Fn(usize, u32) + Sync)) {
        for (p, &count) in items.iter().enumerate() {
            if p > 0 {
                let before = items[p - 1];
                let mut spins = 0u32;
                while self.done[p - 1].load(Ordering::Acquire) < before {
                    if self.abort.load(Ordering::Relaxed) {
                        return;
                    }
                    if spins < 2_000 {
                        std::hint::spin_loop();
                        spins += 1;
                    } else {
                        std::thread::yield_now();
                    }
                }
            }
            loop {
                let k = self.claimed[p].fetch_add(1, Ordering::Relaxed);
                if k >= count {
                    break;
                }
                let guard = AbortOnUnwind(&self.abort);
                exec(p, k);
                std::mem::forget(guard);
                self.done[p].fetch_add(1, Ordering::Release);
            }
        }
    }
}

/// Raises the abort flag if an item panics, so that other threads stop waiting for it.
struct AbortOnUnwind<'a>(&'a AtomicBool);

impl Drop for AbortOnUnwind<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

/// A slice that several threads may read and write at once, through raw accesses.
///
/// Soundness rests on the phase structure: within one phase no element is written by one
/// item and read or written by another, and phases are separated by the Release/Acquire
/// completion counters of [`PhaseCounters`]. Indices are validated when the constraints are
/// built; accesses are bounds-checked in debug builds.
pub(crate) struct SharedSlice<'a, T> {
    ptr: *mut T,
    len: usize,
    _borrow: PhantomData<&'a UnsafeCell<[T]>>,
}

// SAFETY: see the type's documentation: concurrent accesses touch disjoint elements.
unsafe impl<T: Send> Send for SharedSlice<'_, T> {}
unsafe impl<T: Send> Sync for SharedSlice<'_, T> {}

impl<'a, T: Copy> SharedSlice<'a, T> {
    pub fn new(slice: &'a mut [T]) -> Self {
        Self {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _borrow: PhantomData,
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    /// # Safety
    /// `i < len`, and no other thread writes element `i` during the current phase.
    #[inline(always)]
    pub unsafe fn get(&self, i: usize) -> T {
        debug_assert!(i < self.len);
        unsafe { *self.ptr.add(i) }
    }

    /// # Safety
    /// `i < len`, and no other thread reads or writes element `i` during the current phase.
    #[inline(always)]
    pub unsafe fn set(&self, i: usize, value: T) {
        debug_assert!(i < self.len);
        unsafe { *self.ptr.add(i) = value }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_run_in_order_on_any_thread_count() {
        for threads in [1, 2, 4] {
            let pool = WorkerPool::new(threads);
            let mut counters = PhaseCounters::new();
            let items = [7u32, 3, 11, 1, 5];
            counters.reset(items.len());
            let mut log = vec![0u32; items.iter().sum::<u32>() as usize];
            let offsets: Vec<u32> = items
                .iter()
                .scan(0, |acc, &n| {
                    let o = *acc;
                    *acc += n;
                    Some(o)
                })
                .collect();
            let shared = SharedSlice::new(&mut log);
            let counter = AtomicU32::new(0);
            let exec = |p: usize, k: u32| {
                // The order of completion must respect phases.
                let stamp = counter.fetch_add(1, Ordering::SeqCst) + 1;
                unsafe { shared.set((offsets[p] + k) as usize, stamp + 1000 * p as u32) };
            };
            pool.run(&|| counters.run_phases(&items, &exec));
            let mut last_max = 0;
            for (p, &n) in items.iter().enumerate() {
                let stamps: Vec<u32> = (0..n)
                    .map(|k| log[(offsets[p] + k) as usize] - 1000 * p as u32)
                    .collect();
                assert!(stamps.iter().all(|&s| s > last_max), "phase {p} overlapped");
                last_max = *stamps.iter().max().unwrap();
            }
            assert_eq!(pool.threads(), threads);
        }
    }
}
