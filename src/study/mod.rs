//! Studies built on runs: the independent checks of friction and
//! plate-cylinder outputs, the regularization audits, the stability stress
//! matrix, and the benchmarks (work-precision, head-to-head at an error
//! target, and their timing).

pub mod audit;
pub mod bench;
pub mod bench_shell;
pub mod buckle;
pub mod check;
pub mod critical_cost;
pub mod factor;
pub mod pool;
pub mod scaling;
pub mod shell_audit;
pub mod shell_check;
pub mod stiffness;
pub mod stress;
pub mod sweep;
pub mod target;
pub mod time_audit;
pub mod timing;
