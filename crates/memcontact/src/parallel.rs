//! The worker threads every parallel loop of the library runs on.

/// Runs `f` on one of the worker threads of rayon's pool (directly when called on one).
/// The parallel loops inside `f` then split their work among the workers from there,
/// instead of handing every loop to the pool and waking the calling thread when it is
/// done: the algebraic multigrid, with its many short loops on coarse levels, solves an
/// imported mesh of 10⁵ vertices about 15 % faster this way (10⁶ vertices: 5 %). The
/// command-line tool and the Python module run every solve through it.
pub fn on_workers<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() {
        f()
    } else {
        rayon::scope(|_| f())
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

#[cfg(test)]
mod tests {
    #[test]
    fn on_workers_runs_on_a_worker_of_the_pool_once() {
        // The test harness's threads are not workers of rayon's pool.
        assert_eq!(rayon::current_thread_index(), None);
        let (outer, inner) = super::on_workers(|| {
            let outer = rayon::current_thread_index();
            (outer, super::on_workers(rayon::current_thread_index))
        });
        assert!(outer.is_some(), "f runs on a worker");
        assert_eq!(outer, inner, "a nested call runs in place");
    }
}
