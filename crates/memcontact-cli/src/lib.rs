//! The parts of the `memcontact` command-line tool that its benchmarks share with it: the
//! timed runs and tables of `memcontact bench` (also printed by
//! `cargo bench -p memcontact-cli --bench tnnmg`).

pub mod bench;
