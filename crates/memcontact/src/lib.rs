//! # memcontact
//!
//! Contact between a stretched membrane and an elastic (tensionless Winkler) obstacle,
//! discretised exactly as in A. Maceri & F. Maceri, "Analysis of a discrete model for the
//! contact problem between a membrane and an elastic obstacle", Rend. Lincei 80 (1986).
//!
//! Data flows one way: [`field`] data and a [`mesh::Mesh`] build a [`model::Model`]
//! (S, L, D, φₙ of the paper's §2), a [`solve`] method returns a [`solve::Solution`],
//! and [`results`] derives the physical fields that the [`io`] writers store.

pub mod bench;
pub mod certificate;
pub mod checks;
pub mod convergence;
pub mod error;
pub mod errors;
pub mod exact;
pub mod expr;
pub mod fem;
pub mod field;
pub mod io;
pub mod mesh;
pub mod model;
pub mod nodal;
pub mod output;
pub mod problem;
pub mod quadrature;
pub mod resources;
pub mod results;
pub mod run;
pub mod solve;
pub mod sparse;
pub mod summary;
pub mod sweep;

pub use error::{Error, Result};
pub use problem::{Case, Problem};
pub use run::{run, Discretization, Outcome, Report};
pub use solve::{Method, Observer, Settings, Status};
pub use summary::Summary;

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
