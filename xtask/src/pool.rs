//! The pool of QEMU jobs `cargo xtask ci` runs beside its builds: each emulated run (a capture
//! through an image, a unit case, the soak, ...) is a job; jobs run on a few threads while the
//! main thread goes on compiling, and their times add up per group in the step table
//! ([`crate::steps`]). A QEMU run spends much of its time waiting on its emulated UART or on
//! wall-clock time-outs, so the pool runs more jobs than there are cores.

use crate::steps::Steps;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

/// Jobs in flight and the failures so far.
#[derive(Default)]
struct State {
    pending: usize,
    failures: Vec<String>,
}

/// A pool of job threads (rayon's), shared by the steps of one run.
#[derive(Clone)]
pub struct Pool {
    threads: Arc<rayon::ThreadPool>,
    state: Arc<(Mutex<State>, Condvar)>,
    /// Set by the first failure: jobs not yet started are skipped.
    failed: Arc<AtomicBool>,
    steps: Steps,
}

impl Pool {
    /// A pool of `threads` job threads reporting into `steps`.
    pub fn new(threads: usize, steps: Steps) -> Result<Self, String> {
        let threads = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("xtask-job-{i}"))
            .build()
            .map_err(|e| format!("cannot start the job threads: {e}"))?;
        Ok(Self {
            threads: Arc::new(threads),
            state: Arc::default(),
            failed: Arc::default(),
            steps,
        })
    }

    /// The step record the jobs report into.
    pub fn steps(&self) -> &Steps {
        &self.steps
    }

    /// Queues `job`, named `label` in messages; its time counts to the step `group`.
    pub fn spawn(
        &self,
        group: &str,
        label: String,
        job: impl FnOnce() -> Result<(), String> + Send + 'static,
    ) {
        {
            let mut s = self.state.0.lock().unwrap_or_else(|p| p.into_inner());
            s.pending += 1;
        }
        let (state, failed, steps, group) = (
            Arc::clone(&self.state),
            Arc::clone(&self.failed),
            self.steps.clone(),
            group.to_owned(),
        );
        self.threads.spawn(move || {
            let result = if failed.load(Ordering::SeqCst) {
                None
            } else {
                let t = Instant::now();
                let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(job))
                    .unwrap_or_else(|_| Err("the job panicked".to_owned()));
                steps.record(&group, t.elapsed(), r.is_ok(), true);
                Some(r)
            };
            let (lock, cvar) = &*state;
            let mut s = lock.lock().unwrap_or_else(|p| p.into_inner());
            if let Some(Err(e)) = result {
                eprintln!("xtask ci: JOB FAILED ({group}: {label}): {e}");
                failed.store(true, Ordering::SeqCst);
                s.failures.push(format!("{group}: {label}: {e}"));
            }
            s.pending -= 1;
            cvar.notify_all();
        });
    }

    /// Skips every job not yet started (a step beside the pool failed).
    pub fn cancel(&self) {
        self.failed.store(true, Ordering::SeqCst);
    }

    /// Waits for every queued job; the failures, all of them, as one error.
    pub fn wait(&self) -> Result<(), String> {
        let (lock, cvar) = &*self.state;
        let mut s = lock.lock().unwrap_or_else(|p| p.into_inner());
        while s.pending > 0 {
            s = cvar.wait(s).unwrap_or_else(|p| p.into_inner());
        }
        if s.failures.is_empty() {
            Ok(())
        } else {
            Err(format!(
                "{} QEMU job(s) failed:\n{}",
                s.failures.len(),
                s.failures.join("\n")
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_job_runs_and_every_failure_is_reported() {
        let steps = Steps::new(std::path::Path::new("/nonexistent"));
        let pool = Pool::new(2, steps).unwrap();
        let ran = Arc::new(Mutex::new(0));
        for i in 0..5 {
            let ran = Arc::clone(&ran);
            pool.spawn("g", format!("job {i}"), move || {
                *ran.lock().unwrap() += 1;
                Ok(())
            });
        }
        assert_eq!(pool.wait(), Ok(()));
        assert_eq!(*ran.lock().unwrap(), 5);
        pool.spawn("g", "bad".into(), || Err("boom".into()));
        let e = pool.wait().unwrap_err();
        assert!(e.contains("g: bad: boom"), "{e}");
        // After a failure, jobs not yet started are skipped (and are not failures).
        pool.spawn("g", "late".into(), || Err("never runs".into()));
        assert!(!pool.wait().unwrap_err().contains("never runs"));
    }
}
