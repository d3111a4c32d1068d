//! Worker threads and the phase scheduler that runs one step in parallel.
//!
//! A step is a fixed list of *phases* (the blocks' work of a substep, the seams, the corners,
//! …); each phase is a fixed list of *items* (a block, a seam, a range of triangles). Items of
//! one phase write disjoint data, so they may run in any order on any thread. An item waits
//! for the whole phase before it, or for the items (of earlier phases) it is given: a particle
//! group's next substep waits only for its own block and the seams that touch it, not for the
//! other blocks. Every thread — the caller's and the pool's workers — runs the same loop:
//! claim (one atomic flag each) and run the first item whose dependencies are finished,
//! looking from the earliest phase with unclaimed items a few phases ahead, at the items
//! pinned to it first. Each thread starts looking at its own place in a phase's list, so that
//! it tends to get the same blocks in every substep and finds their particles and constraints
//! in its cache. Because the items and
//! their contents do not depend on which thread runs them, and each runs after what it reads
//! has been written, the result is bit-for-bit the same for any number of threads.
//!
//! A thread waits only while nothing is ready, that is, while other threads are inside the
//! items the next ones wait for. Waiting spins briefly and then yields. Between steps the workers spin for a few tens of
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

    /// Whether no worker is asleep (each is spinning for the next job, or running one).
    pub fn awake(&self) -> bool {
        self.workers.is_empty() || self.shared.lock().sleepers == 0
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

/// What an item must wait for before it may run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Dep {
    /// Item `k` of phase `p`.
    Item(u32, u32),
    /// Every item of phase `p`.
    Phase(u32),
}

/// Per-item claim and completion flags, per-phase counters, and the items' dependencies.
///
/// By default an item waits for every item of the phase before its own (a barrier between
/// phases). A phase may instead give each of its items its own list of items (or whole
/// phases) to wait for, all in earlier phases; then a thread that finds nothing ready in the
/// earliest phase with unclaimed items looks a few phases ahead ([`LOOKAHEAD`]) for an item
/// that is ready. Which thread runs an item never changes what the item does.
pub(crate) struct PhaseCounters {
    /// One flag per item of every phase (`first[p]..first[p + 1]` for phase `p`).
    claimed: Vec<AtomicBool>,
    finished: Vec<AtomicBool>,
    first: Vec<usize>,
    /// Per phase: items claimed, items finished.
    taken: Vec<Padded>,
    done: Vec<Padded>,
    /// Per item (global index): the range of its dependencies in `deps`; `None` for an item
    /// that waits for the whole previous phase.
    dep_range: Vec<Option<(u32, u32)>>,
    deps: Vec<Dep>,
    /// Per phase: whether its items are pinned to threads ([`Self::pin`]).
    pinned: Vec<bool>,
    abort: AtomicBool,
    /// Threads that have entered [`Self::run_phases`] in this run.
    joined: AtomicUsize,
}

/// How many phases past the earliest one with unclaimed items a thread looks for a ready item.
const LOOKAHEAD: usize = 4;

impl PhaseCounters {
    pub fn new() -> Self {
        Self {
            claimed: Vec::new(),
            finished: Vec::new(),
            first: Vec::new(),
            taken: Vec::new(),
            done: Vec::new(),
            dep_range: Vec::new(),
            deps: Vec::new(),
            pinned: Vec::new(),
            abort: AtomicBool::new(false),
            joined: AtomicUsize::new(0),
        }
    }

    /// Makes room for the phases of `items` (item counts), each waiting for the whole
    /// previous phase, and clears the flags and counters (single-threaded, before a run).
    /// [`Self::set_deps`] then gives phases their own dependencies.
    pub fn reset(&mut self, items: &[u32]) {
        self.first.clear();
        self.first.push(0);
        for &count in items {
            let last = *self.first.last().expect("first holds 0");
            self.first.push(last + count as usize);
        }
        let total = *self.first.last().expect("first holds 0");
        for flags in [&mut self.claimed, &mut self.finished] {
            flags.resize_with(total, || AtomicBool::new(false));
        }
        for counters in [&mut self.taken, &mut self.done] {
            counters.resize_with(items.len(), || Padded(AtomicU32::new(0)));
        }
        self.dep_range.clear();
        self.dep_range.resize(total, None);
        self.deps.clear();
        self.pinned.clear();
        self.pinned.resize(items.len(), false);
        self.clear();
    }

    /// Clears the flags and counters for another run of the same phases and dependencies
    /// (single-threaded, before a run).
    pub fn clear(&mut self) {
        for flag in self.claimed.iter_mut().chain(&mut self.finished) {
            *flag.get_mut() = false;
        }
        for counter in self.taken.iter_mut().chain(&mut self.done) {
            *counter.0.get_mut() = 0;
        }
        *self.abort.get_mut() = false;
        *self.joined.get_mut() = 0;
    }

    /// Gives item `k` of phase `p` the dependencies `deps`, instead of the whole previous
    /// phase (after [`Self::reset`]). Every dependency must lie in a phase before `p`.
    pub fn set_deps(&mut self, p: usize, k: u32, deps: impl IntoIterator<Item = Dep>) {
        let a = self.deps.len();
        self.deps.extend(deps);
        assert!(
            self.deps[a..].iter().all(|d| match *d {
                Dep::Item(q, k) =>
                    (q as usize) < p
                        && k < (self.first[q as usize + 1] - self.first[q as usize]) as u32,
                Dep::Phase(q) => (q as usize) < p,
            }),
            "a dependency of item {k} of phase {p} is not an item of an earlier phase"
        );
        self.dep_range[self.first[p] + k as usize] = Some((a as u32, self.deps.len() as u32));
    }

    /// Pins the items of phase `p` to threads: of `count` items and `threads` threads, item
    /// `k` runs on thread `k · threads / count` only (after [`Self::reset`]).
    pub fn pin(&mut self, p: usize) {
        self.pinned[p] = true;
    }

    /// Whether item `k` of phase `p` may run.
    fn ready(&self, items: &[u32], p: usize, k: usize) -> bool {
        let i = self.first[p] + k;
        let phase_done = |q: usize| self.done[q].0.load(Ordering::Acquire) >= items[q];
        match self.dep_range[i] {
            None => p == 0 || phase_done(p - 1),
            Some((a, b)) => self.deps[a as usize..b as usize].iter().all(|d| match *d {
                Dep::Item(q, k) => {
                    self.finished[self.first[q as usize] + k as usize].load(Ordering::Acquire)
                }
                Dep::Phase(q) => phase_done(q as usize),
            }),
        }
    }

    /// The loop every thread runs until every item has been claimed: it claims and runs the
    /// first ready item it finds, looking from the earliest phase with unclaimed items on, in
    /// phase order. `items[p]` is the item count of phase `p` (as given to [`Self::reset`]);
    /// `exec(p, k)` runs item `k` of phase `p`. Thread `thread` of `threads` tries the items
    /// of a phase from `thread · count / threads` on, so that each thread tends to get the
    /// same items (the same blocks of particles, still in its cache) substep after substep,
    /// while the items left over go to whichever thread is free.
    ///
    /// A thread looks at its own items (those of pinned phases) before the shared ones: with
    /// a block per thread, the thread that finishes its block first goes on with its own
    /// particle groups that no seam touches, and the seam falls to whichever thread has run
    /// out of its own work, instead of to the one that finished its block last (which then
    /// worked 30 µs a step longer than the other on the 4,000-particle dress; session 15).
    ///
    /// Returns the longest time this thread waited at once with nothing ready, once every
    /// thread had joined (an item normally takes microseconds: a wait of milliseconds means
    /// that the operating system descheduled a thread that held an item; a worker that is
    /// still waking up holds none, and the next steps find it awake). Items are not timed:
    /// two clock reads an item cost the 4,000-particle dress's step 2 % (session 15).
    pub fn run_phases(
        &self,
        thread: usize,
        threads: usize,
        items: &[u32],
        exec: &(dyn Fn(usize, u32) + Sync),
    ) -> PhaseTimes {
        let mut times = PhaseTimes::default();
        let mut cursor = 0usize;
        self.joined.fetch_add(1, Ordering::Relaxed);
        // A wait: since when, spins so far, and whether every thread had joined when it
        // began (a wait for a thread still waking up holds no one's item: not a stall).
        let mut idle: Option<(std::time::Instant, u32, bool)> = None;
        loop {
            while cursor < items.len()
                && self.taken[cursor].0.load(Ordering::Relaxed) >= items[cursor]
            {
                cursor += 1;
            }
            if cursor == items.len() {
                break;
            }
            let mut ran = false;
            let window = cursor..items.len().min(cursor + LOOKAHEAD);
            // This thread's own (pinned) items first, then the shared ones.
            let own = window.clone().filter(|&p| self.pinned[p]);
            let shared = window.filter(|&p| !self.pinned[p]);
            'scan: for p in own.chain(shared) {
                let count = items[p] as usize;
                let flags = &self.claimed[self.first[p]..self.first[p + 1]];
                let threads = threads.max(1);
                let (lo, hi, wrap) = if self.pinned[p] {
                    // Only the items k with k · threads / count == thread.
                    let bound = |t: usize| (t * count).div_ceil(threads).min(count);
                    (bound(thread), bound(thread + 1), 0)
                } else {
                    let start = thread * count / threads;
                    (start, count, start)
                };
                for k in (lo..hi).chain(0..wrap) {
                    let flag = &flags[k];
                    if flag.load(Ordering::Relaxed) || !self.ready(items, p, k) {
                        continue;
                    }
                    if flag.swap(true, Ordering::Relaxed) {
                        continue;
                    }
                    self.taken[p].0.fetch_add(1, Ordering::Relaxed);
                    if let Some((since, _, all)) = idle.take() {
                        times.add_wait(since.elapsed(), all);
                    }
                    let guard = AbortOnUnwind(&self.abort);
                    exec(p, k as u32);
                    std::mem::forget(guard);
                    self.finished[self.first[p] + k].store(true, Ordering::Release);
                    self.done[p].0.fetch_add(1, Ordering::Release);
                    ran = true;
                    break 'scan;
                }
            }
            if ran {
                continue;
            }
            // Nothing ready: another thread holds what the next items wait for.
            if self.abort.load(Ordering::Relaxed) {
                break;
            }
            let (_, spins, _) = idle.get_or_insert_with(|| {
                let all = self.joined.load(Ordering::Relaxed) >= threads;
                (std::time::Instant::now(), 0, all)
            });
            if *spins < 4_000 {
                std::hint::spin_loop();
                *spins += 1;
            } else {
                std::thread::yield_now();
            }
        }
        if let Some((since, _, all)) = idle {
            times.add_wait(since.elapsed(), all);
        }
        times
    }
}

/// What [`PhaseCounters::run_phases`] measured on one thread.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct PhaseTimes {
    /// The longest time this thread waited at once for other threads' items, counting only
    /// waits that began once every thread had joined the run.
    pub longest_wait: std::time::Duration,
}

impl PhaseTimes {
    fn add_wait(&mut self, wait: std::time::Duration, all_joined: bool) {
        if all_joined {
            self.longest_wait = self.longest_wait.max(wait);
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
/// Soundness rests on the phase structure: no element is written by one item and read or
/// written by another that may run at the same time (an item of the same phase, or of a later
/// one that does not wait for it), and an item that waits for another sees its writes through
/// the Release/Acquire completion flags and counters of [`PhaseCounters`]. Indices are validated when the constraints are
/// built; accesses are bounds-checked in debug builds.
pub(crate) struct SharedSlice<'a, T> {
    ptr: *mut T,
    len: usize,
    _borrow: PhantomData<&'a UnsafeCell<[T]>>,
}

// SAFETY: see the type's documentation: concurrent accesses touch disjoint elements.
unsafe impl<T: Send> Send for SharedSlice<'_, T> {}
// SAFETY: as for `Send`: concurrent accesses, reads included, touch disjoint elements or are
// ordered by the phase counters (see the type's documentation).
unsafe impl<T: Send> Sync for SharedSlice<'_, T> {}

impl<'a, T: Copy> SharedSlice<'a, T> {
    pub fn new(slice: &'a mut [T]) -> Self {
        Self {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _borrow: PhantomData,
        }
    }

    /// The number of elements.
    pub fn len(&self) -> usize {
        self.len
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
        // SAFETY: the caller guarantees `i < len` (so the pointer is in the borrowed slice) and
        // that no other thread writes element `i` during this phase.
        unsafe { *self.ptr.add(i) }
    }

    /// # Safety
    /// `i < len`, and no other thread reads or writes element `i` during the current phase.
    #[inline(always)]
    pub unsafe fn set(&self, i: usize, value: T) {
        debug_assert!(i < self.len);
        // SAFETY: the caller guarantees `i < len` (so the pointer is in the borrowed slice) and
        // that no other thread reads or writes element `i` during this phase.
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
                // SAFETY: each (phase, item) pair writes its own element `offsets[p] + k`, inside
                // `log`.
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

    /// Phases: 0 (four items), 1 (item k after item k of phase 0), 2 (after all of phase 1,
    /// its item 1 also after item 3 of phase 0).
    fn dependent_phases(counters: &mut PhaseCounters) -> [u32; 3] {
        let items = [4u32, 4, 2];
        counters.reset(&items);
        for k in 0..4 {
            counters.set_deps(1, k, [Dep::Item(0, k)]);
        }
        counters.set_deps(2, 0, [Dep::Phase(1)]);
        counters.set_deps(2, 1, [Dep::Phase(1), Dep::Item(0, 3)]);
        items
    }

    #[test]
    fn items_run_after_what_they_wait_for_on_any_thread_count() {
        for threads in [1, 2, 4] {
            let pool = WorkerPool::new(threads);
            let mut counters = PhaseCounters::new();
            for _round in 0..50 {
                let items = dependent_phases(&mut counters);
                let clock = AtomicU32::new(0);
                let stamps: Vec<[AtomicU32; 2]> = (0..10)
                    .map(|_| [AtomicU32::new(0), AtomicU32::new(0)])
                    .collect();
                let index = |p: usize, k: u32| [0, 4, 8][p] + k as usize;
                let exec = |p: usize, k: u32| {
                    let s = &stamps[index(p, k)];
                    s[0].store(clock.fetch_add(1, Ordering::SeqCst) + 1, Ordering::SeqCst);
                    std::hint::black_box((0..1000).sum::<u32>());
                    s[1].store(clock.fetch_add(1, Ordering::SeqCst) + 1, Ordering::SeqCst);
                };
                pool.run(&|thread| {
                    counters.run_phases(thread, threads, &items, &exec);
                });
                let start = |p, k| stamps[index(p, k)][0].load(Ordering::SeqCst);
                let end = |p, k| stamps[index(p, k)][1].load(Ordering::SeqCst);
                for k in 0..4 {
                    assert!(end(0, k) > 0 && end(1, k) > 0, "an item did not run");
                    assert!(start(1, k) > end(0, k), "item {k} of phase 1 ran too early");
                    for q in 0..2 {
                        assert!(start(2, q) > end(1, k), "phase 2 ran before phase 1 ended");
                    }
                }
                assert!(start(2, 1) > end(0, 3));
            }
        }
    }

    #[test]
    fn a_thread_runs_a_later_phase_item_that_is_ready() {
        // Item 1 of phase 0 holds its thread until item 0 of phase 1 has run, which only a
        // thread that looks past the unfinished phase 0 can do.
        let pool = WorkerPool::new(2);
        let mut counters = PhaseCounters::new();
        let items = dependent_phases(&mut counters);
        let ran_early = AtomicBool::new(false);
        let gave_up = AtomicBool::new(false);
        let exec = |p: usize, k: u32| match (p, k) {
            (0, 1) => {
                let start = std::time::Instant::now();
                while !ran_early.load(Ordering::SeqCst) {
                    if start.elapsed() > std::time::Duration::from_secs(10) {
                        gave_up.store(true, Ordering::SeqCst);
                        return;
                    }
                    std::thread::yield_now();
                }
            }
            (1, 0) => ran_early.store(true, Ordering::SeqCst),
            _ => {}
        };
        pool.run(&|thread| {
            counters.run_phases(thread, 2, &items, &exec);
        });
        assert!(
            !gave_up.load(Ordering::SeqCst),
            "phase 1 waited for all of phase 0"
        );
    }

    #[test]
    fn a_thread_runs_its_own_items_before_shared_ones() {
        // Phase 0: one shared item; phase 1: two items pinned to the threads, waiting for
        // nothing. Each thread runs its own item first.
        for threads in [1usize, 2] {
            let pool = WorkerPool::new(threads);
            let mut counters = PhaseCounters::new();
            let items = [1u32, 2];
            counters.reset(&items);
            counters.pin(1);
            for k in 0..2 {
                counters.set_deps(1, k, []);
            }
            let clock = AtomicU32::new(0);
            let stamps: Vec<AtomicU32> = (0..3).map(|_| AtomicU32::new(0)).collect();
            let exec = |p: usize, k: u32| {
                let stamp = clock.fetch_add(1, Ordering::SeqCst) + 1;
                stamps[p + k as usize].store(stamp, Ordering::SeqCst);
            };
            pool.run(&|thread| {
                counters.run_phases(thread, threads, &items, &exec);
            });
            let stamp = |i: usize| stamps[i].load(Ordering::SeqCst);
            if threads == 1 {
                // Both pinned items are its own: the shared one runs last.
                assert!(stamp(0) > stamp(1) && stamp(0) > stamp(2), "{:?}", stamps);
            } else {
                // Whichever thread runs the shared item ran its own before.
                assert!(stamp(0) > stamp(1).min(stamp(2)), "{:?}", stamps);
            }
        }
    }

    #[test]
    fn a_thread_measures_its_longest_wait_for_another_s_item() {
        let pool = WorkerPool::new(2);
        let mut counters = PhaseCounters::new();
        // Item 0 of phase 0 holds its thread for 3 ms once both threads run; phase 1 waits
        // for it.
        let items = [1u32, 1];
        counters.reset(&items);
        let started = AtomicU32::new(0);
        let exec = |p: usize, _k: u32| {
            if p == 0 {
                while started.load(Ordering::SeqCst) < 2 {
                    std::hint::spin_loop();
                }
                std::thread::sleep(std::time::Duration::from_millis(3));
            }
        };
        let longest: Vec<AtomicU64> = (0..2).map(|_| AtomicU64::new(0)).collect();
        pool.run(&|thread| {
            started.fetch_add(1, Ordering::SeqCst);
            let times = counters.run_phases(thread, 2, &items, &exec);
            longest[thread].store(times.longest_wait.as_nanos() as u64, Ordering::SeqCst);
        });
        let waits: Vec<u64> = longest.iter().map(|w| w.load(Ordering::SeqCst)).collect();
        // The thread that did not hold the item waited for all of it.
        assert!(waits.iter().any(|&w| w >= 3_000_000), "{waits:?}");
    }

    #[test]
    fn a_wait_for_a_thread_that_has_not_joined_is_no_stall() {
        // Phase 0: an item pinned to each thread; phase 1 waits for both. The worker joins
        // 3 ms late: the caller waits for it, but that wait began before it joined.
        let pool = WorkerPool::new(2);
        let mut counters = PhaseCounters::new();
        let items = [2u32, 1];
        counters.reset(&items);
        counters.pin(0);
        let exec = |_p: usize, _k: u32| {};
        let longest: Vec<AtomicU64> = (0..2).map(|_| AtomicU64::new(0)).collect();
        pool.run(&|thread| {
            if thread == 1 {
                std::thread::sleep(std::time::Duration::from_millis(3));
            }
            let times = counters.run_phases(thread, 2, &items, &exec);
            longest[thread].store(times.longest_wait.as_nanos() as u64, Ordering::SeqCst);
        });
        let caller = longest[0].load(Ordering::SeqCst);
        assert!(caller < 1_000_000, "the caller's wait counted: {caller} ns");
    }

    #[test]
    fn pinned_items_run_on_their_own_thread_only() {
        for threads in [1usize, 2, 3] {
            let pool = WorkerPool::new(threads);
            let mut counters = PhaseCounters::new();
            // Phase 1 pinned; its items wait for phase 0's, which any thread may run.
            let items = [6u32, 5, 4];
            counters.reset(&items);
            counters.pin(1);
            for _round in 0..20 {
                counters.clear();
                let ran_on: Vec<AtomicUsize> =
                    (0..15).map(|_| AtomicUsize::new(usize::MAX)).collect();
                let first = [0usize, 6, 11];
                pool.run(&|thread| {
                    let exec = |p: usize, k: u32| {
                        ran_on[first[p] + k as usize].store(thread, Ordering::SeqCst);
                    };
                    counters.run_phases(thread, threads, &items, &exec);
                });
                for k in 0..5 {
                    // Item k of 5 belongs to thread k · threads / 5.
                    assert_eq!(
                        ran_on[6 + k].load(Ordering::SeqCst),
                        k * threads / 5,
                        "{threads} threads: pinned item {k}"
                    );
                }
                assert!(ran_on.iter().all(|t| t.load(Ordering::SeqCst) < threads));
            }
        }
    }
}
