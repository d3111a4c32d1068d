//! Worker threads and the phase scheduler that runs one step in parallel.
//!
//! A step is a fixed list of *phases* (the blocks' work of a substep, the seams, the corners,
//! …); each phase is a fixed list of *items* (a block, a seam, a range of triangles). Items of
//! one phase write disjoint data, so they may run in any order on any thread. Every thread —
//! the caller's and the pool's workers — runs the same loop: wait until the previous phase is
//! complete, then claim items of this phase (one atomic flag each) until none are left. Each
//! thread starts claiming at its own place in the list, so that it tends to get the same
//! blocks in every substep and finds their particles and constraints in its cache. Because
//! the items and their contents do not depend on which thread runs them, the result is
//! bit-for-bit the same for any number of threads.
//!
//! A thread waits for a phase only while another thread is still inside one of its items.
//! Waiting spins briefly and then yields. Between steps the workers spin for a few tens of
//! microseconds (steps often follow each other closely) and then sleep on a condition
//! variable; the solver wakes them at the start of a step (`WorkerPool::prewake`), so that
//! their wake-up overlaps its serial preparations. Waking a thread is a system call, made only
//! when one is blocked (the pool counts them), so steps that follow each other closely make
//! none.
//!
//! The workers are persistent (spawning threads per step would cost tens of microseconds and
//! allocate); the job they run borrows the solver's data for the duration of
//! `WorkerPool::run`, which does not return before every worker has left the job.

use std::cell::UnsafeCell;
use std::marker::PhantomData;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;

type Job = dyn Fn(usize) + Sync;

/// How long a thread spins for the next job, or for the workers to finish, before it blocks.
const SPIN_TIME: std::time::Duration = std::time::Duration::from_micros(50);

#[derive(Clone, Copy)]
struct JobPtr(*const Job);
// SAFETY: the pointee is `Sync` and outlives every use (see `WorkerPool::run`).
unsafe impl Send for JobPtr {}

struct State {
    generation: u64,
    /// Bumped by [`WorkerPool::prewake`]: sleeping workers wake up and spin for the next job.
    alarm: u64,
    job: Option<JobPtr>,
    running: usize,
    shutdown: bool,
    panicked: bool,
    /// Workers blocked on `Shared::wake` (a wake-up is a system call: skipped when none).
    sleepers: usize,
    /// Whether the caller is blocked on `Shared::finished`.
    caller_waiting: bool,
}

struct Shared {
    state: Mutex<State>,
    wake: Condvar,
    finished: Condvar,
    /// Copies of `State::generation` and `State::running` that threads spin on before they
    /// block on the condition variables.
    generation_hint: AtomicU64,
    running_hint: AtomicUsize,
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
                alarm: 0,
                job: None,
                running: 0,
                shutdown: false,
                panicked: false,
                sleepers: 0,
                caller_waiting: false,
            }),
            wake: Condvar::new(),
            finished: Condvar::new(),
            generation_hint: AtomicU64::new(0),
            running_hint: AtomicUsize::new(0),
        });
        let workers = (1..threads.max(1))
            .filter_map(|k| {
                let shared = Arc::clone(&shared);
                std::thread::Builder::new()
                    .name(format!("cloth-worker-{k}"))
                    .spawn(move || worker_loop(&shared, k))
                    .ok()
            })
            .collect();
        Self { shared, workers }
    }

    /// Threads that run a job: the workers and the caller.
    pub fn threads(&self) -> usize {
        self.workers.len() + 1
    }

    /// Wakes sleeping workers ahead of the next [`Self::run`], so that waking them (tens of
    /// microseconds) overlaps the caller's preparations.
    pub fn prewake(&self) {
        if self.workers.is_empty() {
            return;
        }
        let mut state = self.shared.lock();
        state.alarm += 1;
        if state.sleepers > 0 {
            self.shared.wake.notify_all();
        }
    }

    /// Runs `job(thread)` on every thread of the pool (the caller is thread 0, the workers
    /// 1, 2, …) and returns when all of them have returned from it.
    pub fn run<'job>(&self, job: &(dyn Fn(usize) + Sync + 'job)) {
        if self.workers.is_empty() {
            job(0);
            return;
        }
        let ptr: *const (dyn Fn(usize) + Sync + 'job) = job;
        // SAFETY: only the lifetime is erased. `WaitForWorkers` below does not let this
        // function return (or unwind) before every worker has finished calling the job, so the
        // borrow outlives every use.
        let ptr: *const (dyn Fn(usize) + Sync + 'static) = unsafe { std::mem::transmute(ptr) };
        {
            let mut state = self.shared.lock();
            state.job = Some(JobPtr(ptr));
            state.generation = state.generation.wrapping_add(1);
            state.running = self.workers.len();
            state.panicked = false;
            self.shared
                .running_hint
                .store(state.running, Ordering::Relaxed);
            self.shared
                .generation_hint
                .store(state.generation, Ordering::Release);
            // A worker that is not blocked yet sees the new generation before it would block
            // (both happen under the lock).
            if state.sleepers > 0 {
                self.shared.wake.notify_all();
            }
        }
        let wait = WaitForWorkers(&self.shared);
        job(0);
        drop(wait);
        if self.shared.lock().panicked {
            panic!("a cloth worker thread panicked during the step");
        }
    }
}

struct WaitForWorkers<'a>(&'a Shared);

impl Drop for WaitForWorkers<'_> {
    fn drop(&mut self) {
        // The workers usually finish within microseconds of the caller: spin first.
        spin_until(|| self.0.running_hint.load(Ordering::Acquire) == 0);
        let mut state = self.0.lock();
        while state.running > 0 {
            state.caller_waiting = true;
            state = self
                .0
                .finished
                .wait(state)
                .unwrap_or_else(|e| e.into_inner());
        }
        state.caller_waiting = false;
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

/// Spins until `done()` or for about [`SPIN_TIME`], whichever comes first.
fn spin_until(done: impl Fn() -> bool) -> bool {
    let start = std::time::Instant::now();
    loop {
        for _ in 0..64 {
            if done() {
                return true;
            }
            std::hint::spin_loop();
        }
        if start.elapsed() > SPIN_TIME {
            return false;
        }
    }
}

fn worker_loop(shared: &Shared, thread: usize) {
    let mut seen = 0u64;
    let mut alarm = 0u64;
    loop {
        // Steps often follow each other closely (several cloths, or several steps per frame):
        // spin a little before sleeping, so that the next step finds this worker awake.
        spin_until(|| shared.generation_hint.load(Ordering::Acquire) != seen);
        let job = {
            let mut state = shared.lock();
            while state.generation == seen && state.alarm == alarm && !state.shutdown {
                state.sleepers += 1;
                state = shared.wake.wait(state).unwrap_or_else(|e| e.into_inner());
                state.sleepers -= 1;
            }
            if state.shutdown {
                return;
            }
            if state.generation == seen {
                // Woken ahead of a job: spin for it.
                alarm = state.alarm;
                continue;
            }
            alarm = state.alarm;
            seen = state.generation;
            state.job
        };
        let ok = match job {
            // SAFETY: `WorkerPool::run` keeps the job alive until `running` reaches zero.
            Some(job) => catch_unwind(AssertUnwindSafe(|| unsafe { (*job.0)(thread) })).is_ok(),
            None => true,
        };
        let mut state = shared.lock();
        if !ok {
            state.panicked = true;
        }
        state.running -= 1;
        shared.running_hint.store(state.running, Ordering::Release);
        if state.running == 0 && state.caller_waiting {
            shared.finished.notify_all();
        }
    }
}

/// A counter alone on its cache line, so that threads spinning on one phase's counter do not
/// slow down the claims of another.
#[repr(align(64))]
struct Padded(AtomicU32);

/// Per-item claim flags and per-phase completion counters.
pub(crate) struct PhaseCounters {
    /// One flag per item of every phase (`first[p]..first[p + 1]` for phase `p`).
    claimed: Vec<AtomicBool>,
    first: Vec<usize>,
    done: Vec<Padded>,
    abort: AtomicBool,
}

impl PhaseCounters {
    pub fn new() -> Self {
        Self {
            claimed: Vec::new(),
            first: Vec::new(),
            done: Vec::new(),
            abort: AtomicBool::new(false),
        }
    }

    /// Makes room for the phases of `items` (item counts) and clears the flags and counters
    /// (single-threaded, before a run).
    pub fn reset(&mut self, items: &[u32]) {
        self.first.clear();
        self.first.push(0);
        for &count in items {
            let last = *self.first.last().expect("first holds 0");
            self.first.push(last + count as usize);
        }
        let total = *self.first.last().expect("first holds 0");
        if self.claimed.len() < total {
            self.claimed.resize_with(total, || AtomicBool::new(false));
        }
        for c in &mut self.claimed[..total] {
            *c.get_mut() = false;
        }
        if self.done.len() < items.len() {
            self.done
                .resize_with(items.len(), || Padded(AtomicU32::new(0)));
        }
        for c in &mut self.done[..items.len()] {
            *c.0.get_mut() = 0;
        }
        *self.abort.get_mut() = false;
    }

    /// The loop every thread runs: phases in order, items claimed dynamically.
    /// `items[p]` is the item count of phase `p` (as given to [`Self::reset`]); `exec(p, k)`
    /// runs item `k` of phase `p`. Thread `thread` of `threads` tries the items of a phase
    /// from `thread · count / threads` on, so that each thread tends to get the same items
    /// (the same blocks of particles, still in its cache) substep after substep, while the
    /// items left over go to whichever thread is free.
    ///
    /// Returns how long this thread waited for other threads to finish phases, and (with more
    /// than one thread) the longest it spent in one item (an item normally takes microseconds; one that took
    /// milliseconds was descheduled by the operating system while the thread held it).
    pub fn run_phases(
        &self,
        thread: usize,
        threads: usize,
        items: &[u32],
        exec: &(dyn Fn(usize, u32) + Sync),
    ) -> PhaseTimes {
        let mut times = PhaseTimes::default();
        for (p, &count) in items.iter().enumerate() {
            if p > 0 && self.done[p - 1].0.load(Ordering::Acquire) < items[p - 1] {
                let before = items[p - 1];
                let start = std::time::Instant::now();
                let mut spins = 0u32;
                while self.done[p - 1].0.load(Ordering::Acquire) < before {
                    if self.abort.load(Ordering::Relaxed) {
                        times.waited += start.elapsed();
                        return times;
                    }
                    if spins < 4_000 {
                        std::hint::spin_loop();
                        spins += 1;
                    } else {
                        std::thread::yield_now();
                    }
                }
                times.waited += start.elapsed();
            }
            // Items this thread completed; published once, when no item is left to claim.
            let mut completed = 0u32;
            let flags = &self.claimed[self.first[p]..self.first[p + 1]];
            let count = count as usize;
            let start = thread * count / threads.max(1);
            for k in (start..count).chain(0..start) {
                let flag = &flags[k];
                if flag.load(Ordering::Relaxed) || flag.swap(true, Ordering::Relaxed) {
                    continue;
                }
                let guard = AbortOnUnwind(&self.abort);
                // Only a thread that others may wait for is timed (two clock reads an item).
                let start = (threads > 1).then(std::time::Instant::now);
                exec(p, k as u32);
                if let Some(start) = start {
                    times.longest_item = times.longest_item.max(start.elapsed());
                }
                std::mem::forget(guard);
                completed += 1;
            }
            if completed > 0 {
                self.done[p].0.fetch_add(completed, Ordering::Release);
            }
        }
        times
    }
}

/// What [`PhaseCounters::run_phases`] measured on one thread.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct PhaseTimes {
    /// Time spent waiting for other threads to finish a phase.
    pub waited: std::time::Duration,
    /// The longest time spent in one item.
    pub longest_item: std::time::Duration,
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

    /// The first element, for raw accesses under the same contract as [`Self::get`] and
    /// [`Self::set`].
    pub fn as_ptr(&self) -> *mut T {
        self.ptr
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
            counters.reset(&items);
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
            pool.run(&|thread| {
                counters.run_phases(thread, threads, &items, &exec);
            });
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
