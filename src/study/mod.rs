//! Studies built on runs: the independent check of friction outputs, the
//! regularization audit, the stability stress matrix and the benchmarks.

pub mod audit;
pub mod bench;
pub mod bench_shell;
pub mod check;
pub mod pool;
pub mod scaling;
pub mod stress;
