//! The pool behind `Threads` (`src/pool.rs`): every job exactly once over many rounds
//! and sizes, every thread taking part, a job's panic reaching the caller with the pool
//! still working after it, two callers taking turns, a nested call, an idle pool
//! asleep, and the drop joining the threads.

use std::panic::{self, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use hydrorattle::Parallel;
use hydrorattle_parallel::Threads;
use hydrorattle_parallel::pool::SPIN;

/// Rounds of the loops below (few under Miri, which checks the pool's `unsafe` and
/// atomics: `cargo +nightly miri test -p hydrorattle-parallel --test parallel pool::`, with
/// `MIRIFLAGS=-Zmiri-disable-isolation` for the clock).
const ROUNDS: usize = if cfg!(miri) { 4 } else { 300 };

/// `jobs` as the kernel hands them.
fn jobs_of<F: FnMut() + Send>(jobs: &mut [F]) -> Vec<&mut (dyn FnMut() + Send)> {
    jobs.iter_mut()
        .map(|j| j as &mut (dyn FnMut() + Send))
        .collect()
}

/// Runs `n` jobs on `pool`, job `i` adding 1 to `counts[i]` (and `pause(i)` first).
fn count_round(pool: &Threads, counts: &mut [usize], pause: impl Fn(usize) + Sync) {
    let pause = &pause;
    let mut jobs: Vec<_> = counts
        .iter_mut()
        .enumerate()
        .map(|(i, c)| {
            move || {
                pause(i);
                *c += 1;
            }
        })
        .collect();
    pool.run(&mut jobs_of(&mut jobs));
}

/// Waits until `arrived` counts `n` (each of `n` jobs adds itself first), so that the
/// round completes only if `n` threads run its jobs at once; false after 20 s.
fn meet(arrived: &AtomicUsize, n: usize) -> bool {
    arrived.fetch_add(1, Ordering::SeqCst);
    let start = Instant::now();
    while arrived.load(Ordering::SeqCst) < n {
        if start.elapsed() > Duration::from_secs(20) {
            return false;
        }
        std::thread::yield_now();
    }
    true
}

#[test]
fn every_job_runs_exactly_once() {
    for threads in [1, 2, 3, 5] {
        let pool = Threads::new(threads).unwrap();
        assert_eq!(pool.threads(), threads);
        assert_eq!(Parallel::threads(&pool), threads);
        for n in [0, 1, 2, 3, 4, 7, 16, 17, 100] {
            let mut counts = vec![0; n];
            let rounds = ROUNDS;
            for _ in 0..rounds {
                count_round(&pool, &mut counts, |_| {});
            }
            assert!(
                counts.iter().all(|&c| c == rounds),
                "{threads} threads, {n} jobs"
            );
        }
    }
}

#[test]
fn many_short_rounds() {
    // Tiny jobs back to back: threads race for each job and into the next round.
    for threads in [2, 3] {
        let pool = Threads::new(threads).unwrap();
        let mut counts = vec![0; threads + 1];
        for _ in 0..ROUNDS * 60 {
            count_round(&pool, &mut counts, |_| {});
        }
        assert!(counts.iter().all(|&c| c == ROUNDS * 60));
    }
}

#[test]
fn rounds_after_idle_gaps_and_slow_jobs() {
    // Gaps longer than the spin put the workers to sleep; a slow job puts the caller to
    // sleep waiting for it: both ways of waking are taken.
    let pool = Threads::new(3).unwrap();
    let mut counts = vec![0; 6];
    for round in 0..40 {
        let slow = round % 6;
        count_round(&pool, &mut counts, |i| {
            if i == slow && round % 2 == 0 {
                std::thread::sleep(3 * SPIN);
            }
        });
        if round % 3 == 0 {
            std::thread::sleep(2 * SPIN);
        }
    }
    assert!(counts.iter().all(|&c| c == 40));
}

#[test]
fn every_thread_takes_part() {
    // `t` jobs that each wait for all `t`: the round ends only if the caller and the
    // `t - 1` workers run one each, at once (also after the workers fell asleep).
    for threads in [2, 3, 4] {
        let pool = Threads::new(threads).unwrap();
        for _ in 0..3 {
            let arrived = AtomicUsize::new(0);
            let met = AtomicUsize::new(0);
            let mut jobs: Vec<_> = (0..threads)
                .map(|_| {
                    || {
                        if meet(&arrived, threads) {
                            met.fetch_add(1, Ordering::SeqCst);
                        }
                    }
                })
                .collect();
            pool.run(&mut jobs_of(&mut jobs));
            assert_eq!(met.load(Ordering::SeqCst), threads, "{threads} threads");
            std::thread::sleep(4 * SPIN);
        }
    }
}

#[test]
fn a_panic_reaches_the_caller_and_the_pool_goes_on() {
    let pool = Threads::new(3).unwrap();
    for bad in 0..8 {
        let mut counts = vec![0; 8];
        let caught = panic::catch_unwind(AssertUnwindSafe(|| {
            count_round(&pool, &mut counts, |i| {
                if i == bad || i == (bad + 3) % 8 {
                    panic!("job {i} fails");
                }
            })
        }));
        let payload = caught.expect_err("the panic reaches the caller");
        let message = payload.downcast_ref::<String>().unwrap();
        assert!(message.starts_with("job ") && message.ends_with(" fails"));
        // The others ran, each once; the failed ones stopped before counting.
        for (i, &c) in counts.iter().enumerate() {
            assert_eq!(c, usize::from(i != bad && i != (bad + 3) % 8), "job {i}");
        }
        let mut after = vec![0; 8];
        count_round(&pool, &mut after, |_| {});
        assert_eq!(after, [1; 8]);
    }
}

#[test]
fn two_callers_take_turns() {
    let pool = Threads::new(3).unwrap();
    std::thread::scope(|s| {
        let runs: Vec<_> = (0..2)
            .map(|k| {
                let pool = &pool;
                s.spawn(move || {
                    let mut counts = vec![0; 5 + 11 * k];
                    for _ in 0..ROUNDS {
                        count_round(pool, &mut counts, |_| {});
                    }
                    counts.iter().all(|&c| c == ROUNDS)
                })
            })
            .collect();
        for r in runs {
            assert!(r.join().unwrap());
        }
    });
}

#[test]
fn a_job_may_run_jobs_on_its_own_pool() {
    // Inside a round the pool's threads are busy: the inner jobs run on the thread that
    // asks, instead of waiting for the pool forever.
    let pool = Threads::new(2).unwrap();
    let mut outer = vec![0; 4];
    let inner = std::sync::Mutex::new(vec![0; 4 * 3]);
    let mut jobs: Vec<_> = outer
        .iter_mut()
        .enumerate()
        .map(|(k, c)| {
            let (pool, inner) = (&pool, &inner);
            move || {
                let mut mine = vec![0; 3];
                count_round(pool, &mut mine, |_| {});
                inner.lock().unwrap()[3 * k..3 * k + 3].copy_from_slice(&mine);
                *c += 1;
            }
        })
        .collect();
    pool.run(&mut jobs_of(&mut jobs));
    drop(jobs);
    assert_eq!(outer, [1; 4]);
    assert_eq!(*inner.lock().unwrap(), [1; 12]);
}

/// Threads that have left (their thread-local dropped), counted by [`leaves_count`].
static LEFT: AtomicUsize = AtomicUsize::new(0);

/// Marks this thread so that its exit adds one to [`LEFT`].
struct Leaves;

impl Drop for Leaves {
    fn drop(&mut self) {
        LEFT.fetch_add(1, Ordering::SeqCst);
    }
}

thread_local! {
    static LEAVES: std::cell::OnceCell<Leaves> = const { std::cell::OnceCell::new() };
}

#[test]
fn drop_joins_the_workers() {
    let threads = 4;
    let pool = Threads::new(threads).unwrap();
    let caller = std::thread::current().id();
    let arrived = AtomicUsize::new(0);
    let mut jobs: Vec<_> = (0..threads)
        .map(|_| {
            || {
                assert!(meet(&arrived, threads));
                if std::thread::current().id() != caller {
                    LEAVES.with(|l| {
                        l.get_or_init(|| Leaves);
                    });
                }
            }
        })
        .collect();
    pool.run(&mut jobs_of(&mut jobs));
    drop(jobs);
    assert_eq!(LEFT.load(Ordering::SeqCst), 0);
    drop(pool);
    // Each worker ran one job (all met), so each is marked; the drop returned after
    // every one of them had exited.
    assert_eq!(LEFT.load(Ordering::SeqCst), threads - 1);
}

#[cfg(all(target_os = "linux", not(miri)))]
#[test]
fn an_idle_pool_sleeps() {
    // The workers' CPU time while the pool idles for 200 ms: a bounded spin, then
    // nothing (a spinning worker would take the whole 200 ms).
    let threads = 3;
    let pool = Threads::new(threads).unwrap();
    let caller = std::thread::current().id();
    let arrived = AtomicUsize::new(0);
    let tasks = std::sync::Mutex::new(Vec::new());
    let mut jobs: Vec<_> = (0..threads)
        .map(|_| {
            || {
                assert!(meet(&arrived, threads));
                if std::thread::current().id() != caller {
                    let me = std::fs::read_link("/proc/thread-self").unwrap();
                    tasks.lock().unwrap().push(me);
                }
            }
        })
        .collect();
    pool.run(&mut jobs_of(&mut jobs));
    drop(jobs);
    let tasks = tasks.into_inner().unwrap();
    assert_eq!(tasks.len(), threads - 1);
    let cpu = || -> u64 {
        tasks
            .iter()
            .map(|t| {
                let s = std::fs::read_to_string(
                    std::path::Path::new("/proc").join(t).join("schedstat"),
                );
                s.unwrap()
                    .split_whitespace()
                    .next()
                    .unwrap()
                    .parse::<u64>()
                    .unwrap()
            })
            .sum()
    };
    std::thread::sleep(Duration::from_millis(20));
    let before = cpu();
    std::thread::sleep(Duration::from_millis(200));
    let spent = cpu() - before;
    assert!(spent < 20_000_000, "idle workers ran {spent} ns in 200 ms");
}
