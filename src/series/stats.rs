//! Counters and timers of a run: what a step costs and where the time goes.

use serde::{Deserialize, Serialize};
use std::time::Instant;

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Stats {
    /// Accepted steps.
    pub steps: usize,
    /// Numeric factorizations of a tangent or Jacobian matrix.
    pub factorizations: usize,
    /// Triangular solves with a factorization.
    pub solves: usize,
    /// Full residual evaluations (step-end checks, Newton).
    pub residual_evaluations: usize,
    /// Series right-hand sides (one per order and step).
    pub series_terms: usize,
    /// Newton corrections (iterations) after a series step.
    pub corrections: usize,
    /// Step lengths halved because the step end was off the path.
    pub step_cuts: usize,
    /// Steps ended at a kink of a piecewise-analytic problem (super::kinks).
    #[serde(default)]
    pub kink_cuts: usize,
    /// Singular points of the geometric-series test that the path got past
    /// (complex, near the real axis: the DAE engine's look-ahead).
    #[serde(default)]
    pub singularities_passed: usize,
    /// Corrections stopped at the residual's round-off floor: the residual
    /// above the tolerance but no longer falling, and the Newton update
    /// below 16 ε of what the state is held to (correct.rs).
    #[serde(default)]
    pub round_off_stops: usize,
    /// The largest relative residual |R| / |R_lambda| at those stops.
    #[serde(default)]
    pub round_off_residual: f64,
    /// The load parameter of that largest stop.
    #[serde(default)]
    pub round_off_lambda: f64,
    /// Seconds spent assembling tangents (and residuals).
    pub assembly_s: f64,
    pub factorization_s: f64,
    /// Seconds in solves timed one by one (continuation, Newton). The DAE
    /// engine times its order loop as a whole, solves included, in `series_s`:
    /// a clock read there costs as much as a 4x4 solve.
    pub solve_s: f64,
    pub series_s: f64,
    /// Seconds in the continuation engine's steps as a whole (tangent,
    /// factorization, solves, series, step length, end check, retries):
    /// what a step costs without the run's outputs and event checks.
    #[serde(default)]
    pub step_s: f64,
    /// The linear solver: factorizations per backend, hand-overs, largest
    /// backward error, factor size, last inertia.
    #[serde(default)]
    pub linear: crate::linalg::SolverStats,
}

/// Adds the seconds elapsed since `start` to `slot`.
pub fn charge(slot: &mut f64, start: Instant) {
    *slot += start.elapsed().as_secs_f64();
}
