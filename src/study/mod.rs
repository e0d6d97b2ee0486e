//! Studies built on runs: the independent check of friction outputs, the
//! regularization audit and the stability stress matrix.

pub mod audit;
pub mod bench;
pub mod check;
pub mod pool;
pub mod stress;
pub mod timing;
