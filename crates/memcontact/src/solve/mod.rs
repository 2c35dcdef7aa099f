//! Solvers of the discrete problem. TODO
