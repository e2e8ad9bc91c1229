//! Work shared out over threads: independent jobs run side by side, their results kept in the jobs' order,
//! so what a caller does with them does not depend on which thread finished first.

use std::sync::atomic::{AtomicUsize, Ordering};

/// The number of threads the machine can run at once (at least 1).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// `f(index, job)` of each of `jobs` on up to `threads` threads (this one among them), each thread taking
/// the next job as it becomes free; the results in the order of `jobs`. A panic in a job is raised again
/// here once every thread has stopped.
pub fn in_job_order<J: Sync, R: Send>(
    jobs: &[J],
    threads: usize,
    f: impl Fn(usize, &J) -> R + Sync,
) -> Vec<R> {
    let threads = threads.clamp(1, jobs.len().max(1));
    if threads == 1 {
        return jobs.iter().enumerate().map(|(k, j)| f(k, j)).collect();
    }
    let next = AtomicUsize::new(0);
    let worker = || {
        let mut mine = Vec::new();
        loop {
            let k = next.fetch_add(1, Ordering::Relaxed);
            let Some(job) = jobs.get(k) else {
                break mine;
            };
            mine.push((k, f(k, job)));
        }
    };
    let mut done: Vec<(usize, R)> = std::thread::scope(|scope| {
        let others: Vec<_> = (1..threads).map(|_| scope.spawn(worker)).collect();
        let mut done = worker();
        for other in others {
            done.extend(
                other
                    .join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            );
        }
        done
    });
    done.sort_by_key(|(k, _)| *k);
    done.into_iter().map(|(_, r)| r).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jobs_run_side_by_side_come_back_in_the_order_of_the_jobs() {
        // The early jobs are the slow ones, so the threads finish them last.
        let jobs: Vec<u64> = (0..40).collect();
        let work = |k: usize, &j: &u64| -> u64 {
            let mut x = j;
            for _ in 0..(40 - j) * 20_000 {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            }
            assert_eq!(k as u64, j);
            j * 1000 + x % 1000
        };
        let one_after_the_other: Vec<u64> =
            jobs.iter().enumerate().map(|(k, j)| work(k, j)).collect();
        for threads in [2, 3, 8] {
            assert_eq!(in_job_order(&jobs, threads, work), one_after_the_other);
        }
        assert_eq!(in_job_order(&jobs[..1], 4, work), one_after_the_other[..1]);
        assert!(in_job_order(&jobs[..0], 4, work).is_empty());
    }
}
