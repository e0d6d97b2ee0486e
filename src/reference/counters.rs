//! The cost counters every time run reports under the same names in its
//! summary.json (`"counters"`): the ANM's friction run, SUNDIALS IDA and
//! diffsol (BDF or ESDIRK), so that the study tools compare them without
//! special cases.
//!
//! | counter | ANM (`series::Stats`) | IDA | diffsol |
//! |---|---|---|---|
//! | `steps` | accepted steps | `IDAGetNumSteps` | `number_of_steps` |
//! | `residual_evaluations` | full residual evaluations | `IDAGetNumResEvals` + `IDAGetNumLinResEvals` | calls of the right-hand side |
//! | `jacobian_evaluations` | tangents assembled (one per factorization) | `IDAGetNumJacEvals` | Jacobian matrices assembled (`number_of_matrix_evals` of the right-hand side) |
//! | `factorizations` | factorizations | `IDAGetNumLinSolvSetups` (dense LU) | `number_of_linear_solver_setups` (dense LU) |
//! | `linear_solves` | triangular solves (series orders, corrections) | Newton iterations (one dense solve each) | Newton iterations (one dense solve each) |
//! | `nonlinear_iterations` | Newton corrections after a series step | `IDAGetNumNonlinSolvIters` | `number_of_nonlinear_solver_iterations` |
//! | `error_test_failures` | step lengths halved (the ANM's rejected steps) | `IDAGetNumErrTestFails` | `number_of_error_test_failures` |
//! | `convergence_failures` | 0 (a failed correction stops the run) | `IDAGetNumNonlinSolvConvFails` | `number_of_nonlinear_solver_fails` |
//!
//! A counter a method has no event for is 0, never left out. Each solver's
//! own richer record stays beside it (the ANM's `stats`).

use serde::{Deserialize, Serialize};

/// The common counters of a time run (see the module table).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Counters {
    pub steps: u64,
    pub residual_evaluations: u64,
    pub jacobian_evaluations: u64,
    pub factorizations: u64,
    pub linear_solves: u64,
    pub nonlinear_iterations: u64,
    pub error_test_failures: u64,
    pub convergence_failures: u64,
}

impl Counters {
    /// The counter names, in the order of the fields (for tables and tests).
    pub const NAMES: [&'static str; 8] = [
        "steps",
        "residual_evaluations",
        "jacobian_evaluations",
        "factorizations",
        "linear_solves",
        "nonlinear_iterations",
        "error_test_failures",
        "convergence_failures",
    ];

    /// The ANM's counters from its [`crate::series::Stats`].
    pub fn from_anm(s: &crate::series::Stats) -> Self {
        Self {
            steps: s.steps as u64,
            residual_evaluations: s.residual_evaluations as u64,
            jacobian_evaluations: s.factorizations as u64,
            factorizations: s.factorizations as u64,
            linear_solves: s.solves as u64,
            nonlinear_iterations: s.corrections as u64,
            error_test_failures: s.step_cuts as u64,
            convergence_failures: 0,
        }
    }

    /// The ANM's counters of a shell run in time (`anm run` on a scene
    /// with `[friction]`): tangents are factorized once each, rejected
    /// implicit trials are its error-test failures.
    pub fn from_shell_time(s: &crate::shell::time_path::TimeStats) -> Self {
        Self {
            steps: s.steps as u64,
            residual_evaluations: s.residual_evaluations as u64,
            jacobian_evaluations: s.factorizations as u64,
            factorizations: s.factorizations as u64,
            linear_solves: s.solves as u64,
            nonlinear_iterations: s.corrections as u64,
            error_test_failures: s.rejected as u64,
            convergence_failures: 0,
        }
    }
}
