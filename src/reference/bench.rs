//! IDA as a method of the work-precision benchmark ([`crate::study::bench`]):
//! steps and linear-solver setups (its factorizations) map onto [`Stats`].

use crate::error::{Error, Result};
use crate::scene::friction::FrictionScene;
use crate::series::Stats;
use crate::study::bench::Solution;

/// Solves `scene` with IDA at rtol (atol = rtol, as in `anm reference ida`'s
/// default pairing) and returns it in the benchmark's shape.
pub fn bench_solution(scene: &FrictionScene, rtol: f64) -> Result<Solution> {
    let run = super::solve(scene, rtol, rtol).map_err(|e| {
        Error::study(
            "bench",
            scene.file.display().to_string(),
            format!("IDA: {e}"),
        )
    })?;
    let c = &run.counters;
    let stats = Stats {
        steps: c.steps.max(0) as usize,
        factorizations: c.linear_setups.max(0) as usize,
        solves: c.nonlinear_iters.max(0) as usize,
        residual_evaluations: (c.residual_evals + c.ls_residual_evals).max(0) as usize,
        ..Default::default()
    };
    Ok(Solution {
        columns: run.columns,
        rows: run.history,
        stats,
        wall_s: run.wall_s,
        stop: run.stop.reason,
        t_stop: run.stop.t,
    })
}
