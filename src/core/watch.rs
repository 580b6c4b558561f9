//! Work that cannot stop itself, watched from outside so that the host is still heard. One call
//! of geo's polygon overlay (the outline's union, a region's repair) or one parallel sort (the
//! borders regions share) runs to its end: seconds at 10⁷ vertices, tens of seconds on a star
//! crowded with crossings. Run on a thread pool of its own, it leaves the caller free to keep
//! asking the host whether to go on; on a cancel the caller returns at once and the work's
//! result, when it comes, is dropped.

use std::panic::{self, AssertUnwindSafe};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::{Duration, Instant};

/// How often the host is asked while the work runs: well inside the 0.2 s a cancel may take.
const EVERY: Duration = Duration::from_millis(20);

/// `work`'s result, or `None` once `go_on` (asked as the work begins, then every [`EVERY`] with
/// the seconds since it began) has returned false. The work runs on a thread pool of its own of
/// `threads` threads (the caller's count for work that runs in parallel, one for work that does
/// not: a host of many cores repairing many regions at once would otherwise start that many
/// pools of that many threads), so that it may work in parallel while the caller waits without
/// taking a thread from its pool; a panic in it is raised here. If no pool can be started, the
/// work runs here, unwatched. Once cancelled, the work runs on to its end in the background,
/// holding what it was given, and nothing waits for it.
pub fn watched<T: Send + 'static>(
    threads: usize,
    work: impl FnOnce() -> T + Send + 'static,
    mut go_on: impl FnMut(f64) -> bool,
) -> Option<T> {
    let began = Instant::now();
    if !go_on(0.0) {
        return None;
    }
    // The pool's threads, joined once the work has ended: a thread still ending when the host
    // exits holds what it allocated (valgrind counts crossbeam's per-thread state as lost).
    let mut started = Vec::new();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .spawn_handler(|thread| {
            let name = format!("snakegrid-watched-{}", thread.index());
            let handle = std::thread::Builder::new()
                .name(name)
                .spawn(|| thread.run())?;
            started.push(handle);
            Ok(())
        })
        .build();
    let Ok(pool) = pool else {
        return Some(work());
    };
    let (sender, receiver) = mpsc::sync_channel(1);
    // A panic is sent back whole: one left in a job of the pool would abort the process.
    pool.spawn(move || {
        // The receiver is gone after a cancel: the result has nowhere to go.
        let _ = sender.send(panic::catch_unwind(AssertUnwindSafe(work)));
    });
    loop {
        match receiver.recv_timeout(EVERY) {
            Ok(ended) => {
                // Idle now: dropping the pool ends its threads at once.
                drop(pool);
                for thread in started {
                    let _ = thread.join();
                }
                return Some(ended.unwrap_or_else(|raised| panic::resume_unwind(raised)));
            }
            Err(RecvTimeoutError::Timeout) => {
                if !go_on(began.elapsed().as_secs_f64()) {
                    return None;
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                unreachable!("the watched work always sends what it ends with")
            }
        }
    }
}

/// The share of a watched call taken as done `seconds` into it, when it is expected to take
/// `expected` seconds: 1 − e^(−t/T), which never reaches the end, so that a bar fed with it keeps
/// moving when the call runs longer than expected, where a linear share would stop.
pub fn expected_share(seconds: f64, expected: f64) -> f64 {
    1.0 - (-seconds / expected).exp()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    #[test]
    fn the_host_is_asked_while_the_result_is_awaited() {
        // The work ends only once the host has been asked three times.
        let (release, released) = mpsc::channel();
        let mut asked = Vec::new();
        let result = watched(
            1,
            move || {
                released.recv().unwrap();
                42
            },
            |seconds| {
                asked.push(seconds);
                if asked.len() == 3 {
                    release.send(()).unwrap();
                }
                true
            },
        );
        assert_eq!(result, Some(42));
        assert!(asked.len() >= 3 && asked.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(asked[0], 0.0);
    }

    #[test]
    fn work_told_to_stop_before_it_begins_is_not_begun() {
        let begun = Arc::new(AtomicBool::new(false));
        let flag = begun.clone();
        assert_eq!(
            watched(1, move || flag.store(true, Ordering::SeqCst), |_| false),
            None
        );
        assert!(!begun.load(Ordering::SeqCst));
    }

    #[test]
    fn a_cancel_returns_at_once_and_leaves_the_work_to_end_alone() {
        // The work cannot end before the caller has returned and released it.
        let (release, released) = mpsc::channel::<()>();
        let ended = Arc::new(AtomicBool::new(false));
        let flag = ended.clone();
        // Begun, then told to stop at the first question while it runs.
        let result = watched(
            1,
            move || {
                let _ = released.recv();
                flag.store(true, Ordering::SeqCst);
            },
            |seconds| seconds == 0.0,
        );
        assert_eq!(result, None);
        assert!(!ended.load(Ordering::SeqCst));
        release.send(()).unwrap();
    }

    #[test]
    fn the_work_runs_in_parallel_on_a_pool_as_large_as_the_callers() {
        // With the caller's pool of one thread busy waiting, work sent to that pool would never
        // run.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let sum = pool.install(|| {
            watched(
                rayon::current_num_threads(),
                || {
                    use rayon::prelude::*;
                    (
                        rayon::current_num_threads(),
                        (1..=1000u64).into_par_iter().sum::<u64>(),
                    )
                },
                |_| true,
            )
        });
        assert_eq!(sum, Some((1, 500_500)));
    }

    #[test]
    fn a_panic_in_the_work_is_raised_in_the_caller() {
        let caught =
            std::panic::catch_unwind(|| watched(1, || -> u8 { panic!("overlay") }, |_| true));
        let message = caught.expect_err("the panic reaches the caller");
        assert_eq!(message.downcast_ref::<&str>(), Some(&"overlay"));
    }
}
