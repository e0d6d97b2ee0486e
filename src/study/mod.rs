//! Studies built on runs: the independent check of friction outputs, the
//! regularization audit, the stability stress matrix, and the benchmarks
//! (work-precision, head-to-head at an error target, and their timing).

pub mod audit;
pub mod bench;
pub mod bench_shell;
pub mod check;
pub mod pool;
pub mod scaling;
pub mod stress;
pub mod target;
pub mod timing;
