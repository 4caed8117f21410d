//! The CPU time this process has used, for `bench`'s "cores" and `LAMPSHADE_TIMINGS`' phases.

use std::time::Duration;

/// The CPU time every thread of this process has used so far: the sum of the scheduler's
/// nanosecond counts (Linux's `/proc/self/task/*/schedstat`); `None` elsewhere. Threads that
/// have ended are not counted (a render's pool lives while it is measured), nor one that ends
/// while they are read. (The process-wide `utime` and `stime` of `/proc/self/stat` count in
/// 10 ms ticks, too coarse for frames of a few milliseconds.)
pub fn process_cpu_time() -> Option<Duration> {
    // A thread that ends while the folder is read leaves an entry without a file: skipped.
    let thread_time = |task: std::fs::DirEntry| -> Option<u64> {
        let schedstat = std::fs::read_to_string(task.path().join("schedstat")).ok()?;
        schedstat.split_whitespace().next()?.parse().ok()
    };
    let tasks = std::fs::read_dir("/proc/self/task").ok()?;
    let nanoseconds: u64 = tasks.flatten().filter_map(thread_time).sum();
    Some(Duration::from_nanos(nanoseconds))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn process_cpu_time_grows_with_work() {
        let Some(before) = process_cpu_time() else {
            return; // not Linux
        };
        // Spin until the process has used 30 ms more (however loaded the machine is), but not
        // forever: a clock that does not move fails.
        let started = std::time::Instant::now();
        let mut x = 0u64;
        loop {
            for _ in 0..100_000 {
                x = std::hint::black_box(x.wrapping_add(1));
            }
            let now = process_cpu_time().expect("readable a moment ago");
            if now >= before + Duration::from_millis(30) {
                break;
            }
            assert!(
                started.elapsed() < Duration::from_secs(20),
                "CPU time stuck at {now:?}"
            );
        }
    }

    /// Finer than the 10 ms ticks of `/proc/self/stat`: while the process works, its readings
    /// advance in steps far below a tick (the smallest of many steps, so that other tests'
    /// threads and a descheduled moment do not matter).
    #[test]
    fn process_cpu_time_counts_below_a_tick() {
        let Some(mut last) = process_cpu_time() else {
            return; // not Linux
        };
        let started = std::time::Instant::now();
        let (mut steps, mut smallest) = (0, Duration::MAX);
        while steps < 50 && started.elapsed() < Duration::from_secs(20) {
            let now = process_cpu_time().expect("readable a moment ago");
            if now > last {
                smallest = smallest.min(now - last);
                steps += 1;
            }
            last = now;
        }
        assert!(
            smallest < Duration::from_millis(2),
            "smallest step {smallest:?} in {steps}"
        );
    }
}
