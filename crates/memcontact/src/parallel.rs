//! The worker threads every parallel loop of the library runs on, and the token that stops
//! a run from another thread.
//!
//! The pool belongs to the process that built it: a process forked from one that has
//! solved before (a `ProcessPoolExecutor`'s worker on Linux) inherits the pool's state but
//! none of its threads, so every process builds its own on first use ([`pool`], keyed by
//! the process id). Work enters the pool through [`on_workers`]; the command-line tool and
//! the Python module run everything they do through it.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// The pool of this process: its id and the pool.
static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);

/// The number of threads [`pool`] builds (0: rayon's default, one per core or
/// `RAYON_NUM_THREADS`).
static THREADS: AtomicUsize = AtomicUsize::new(0);

/// Sets the number of worker threads of the pool built from now on (the command-line
/// tool's `--threads`); results do not depend on it. Refuses 0.
pub fn set_threads(n: usize) -> crate::error::Result<()> {
    if n == 0 {
        return Err(crate::error::Error::Data(
            "the number of threads must be at least 1".into(),
        ));
    }
    THREADS.store(n, Ordering::SeqCst);
    let mut slot = POOL.lock().unwrap_or_else(|p| p.into_inner());
    *slot = None;
    Ok(())
}

/// This process's worker pool, built on first use (and built anew in a forked child, whose
/// copy of its parent's pool has no threads).
pub fn pool() -> Arc<rayon::ThreadPool> {
    let pid = std::process::id();
    let mut slot = POOL.lock().unwrap_or_else(|p| p.into_inner());
    if let Some((owner, pool)) = slot.as_ref() {
        if *owner == pid {
            return pool.clone();
        }
    }
    let threads = THREADS.load(Ordering::SeqCst);
    let pool = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("memcontact-{i}"))
            .build()
            .expect("the worker threads start"),
    );
    // A forked child's copy of the parent's pool is forgotten, not dropped: dropping it
    // would wait for threads that do not exist in this process.
    if let Some(old) = slot.replace((pid, pool.clone())) {
        std::mem::forget(old);
    }
    pool
}

/// Runs `f` on one of the worker threads of this process's pool (directly when called on
/// a worker of a pool). The parallel loops inside `f` then split their work among the
/// workers from there, instead of handing every loop to the pool and waking the calling
/// thread when it is done: the algebraic multigrid, with its many short loops on coarse
/// levels, solves an imported mesh of 10⁵ vertices about 15 % faster this way (10⁶
/// vertices: 5 %).
pub fn on_workers<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() {
        f()
    } else {
        pool().install(f)
    }
}

/// Runs `f` on a pool of `threads` worker threads (tests that check a result does not
/// depend on the number of threads).
#[cfg(test)]
pub(crate) fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}

/// A request to stop a run, shared between the run and whoever may stop it (a signal
/// handler, another thread). The run checks it between phases and iterations and inside
/// the multigrid iteration, and stops with [`crate::Error::Cancelled`].
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

impl Cancel {
    /// A token nobody has used yet.
    pub fn new() -> Cancel {
        Cancel::default()
    }

    /// Asks the runs holding this token to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether the runs holding this token were asked to stop.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// `Err(Cancelled)` once the runs holding this token were asked to stop.
    pub fn check(&self) -> crate::error::Result<()> {
        if self.is_cancelled() {
            Err(crate::error::Error::Cancelled)
        } else {
            Ok(())
        }
    }

    /// The flag itself (for a signal handler, which may only store into it).
    pub fn flag(&self) -> Arc<AtomicBool> {
        self.0.clone()
    }
}

/// A token is no data of a case: any two compare equal.
impl PartialEq for Cancel {
    fn eq(&self, _: &Cancel) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn on_workers_runs_on_a_worker_of_the_pool_once() {
        // The test harness's threads are not workers of a pool.
        assert_eq!(rayon::current_thread_index(), None);
        let (outer, inner) = super::on_workers(|| {
            let outer = rayon::current_thread_index();
            (outer, super::on_workers(rayon::current_thread_index))
        });
        assert!(outer.is_some(), "f runs on a worker");
        assert_eq!(outer, inner, "a nested call runs in place");
    }

    #[test]
    fn a_forked_child_builds_its_own_pool_and_finishes() {
        use rayon::prelude::*;
        // The parent has used its pool: its workers exist in the parent only.
        let sum: u64 = super::on_workers(|| (0..100_000u64).into_par_iter().sum());
        assert_eq!(sum, 4_999_950_000);
        // SAFETY: the child only computes with the library's pool and exits.
        let pid = unsafe { libc::fork() };
        assert!(pid >= 0, "fork");
        if pid == 0 {
            let s: u64 = super::on_workers(|| (0..100_000u64).into_par_iter().sum());
            // SAFETY: `_exit` ends the child without running the parent's destructors.
            unsafe { libc::_exit(if s == 4_999_950_000 { 0 } else { 1 }) };
        }
        // The child must finish within 20 s (before the pool was keyed by process, it hung
        // for ever waiting on workers it did not have).
        let mut status = 0;
        for _ in 0..200 {
            // SAFETY: waiting for our own child.
            let r = unsafe { libc::waitpid(pid, &mut status, libc::WNOHANG) };
            if r == pid {
                assert!(libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0);
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
        // SAFETY: killing our own hung child.
        unsafe { libc::kill(pid, libc::SIGKILL) };
        panic!("the forked child hung");
    }
}
