//! Why a path ended: a typed reason instead of a string.
//!
//! [`Stop::reason`] gives the short machine-readable form written to
//! `summary.json` (`"end"`, `"max_steps"`, `"interrupted"`, or the error's
//! [`Error::kind`]); `Stop == "end"` compares that form.

use crate::error::Error;

/// How a continuation path (ANM or the Newton baseline) ended.
#[derive(Debug)]
pub enum Stop {
    /// The target load `lambda_end` was reached.
    End { lambda: f64 },
    /// `max_steps` steps were taken before the target was reached.
    MaxSteps { steps: usize, lambda: f64 },
    /// The caller stopped asking for steps (e.g. a signal, or a callback
    /// asking to stop). Produced by the caller's loop, never by
    /// [`super::path::Path`].
    Interrupted { lambda: f64 },
    /// A numerical failure (singular tangent, step collapse, no convergence,
    /// ...) or an error returned by the caller's step handler.
    Failed(Error),
}

impl Stop {
    /// Short machine-readable reason: "end", "max_steps", "interrupted", or
    /// the error's kind (e.g. "step_collapse").
    pub fn reason(&self) -> &'static str {
        match self {
            Stop::End { .. } => "end",
            Stop::MaxSteps { .. } => "max_steps",
            Stop::Interrupted { .. } => "interrupted",
            Stop::Failed(e) => e.kind(),
        }
    }

    /// The load parameter where the path stopped: for a failure, the lambda
    /// its error reports (none for input, I/O or output errors, nor for
    /// errors in time t).
    pub fn lambda(&self) -> Option<f64> {
        match self {
            Stop::End { lambda } | Stop::MaxSteps { lambda, .. } | Stop::Interrupted { lambda } => {
                Some(*lambda)
            }
            Stop::Failed(e) => match e {
                Error::SingularMatrix { param, at, .. }
                | Error::NoConvergence { param, at, .. }
                | Error::NonFinite { param, at, .. }
                | Error::StepCollapse { param, at, .. }
                | Error::ContactMissed { param, at, .. }
                | Error::TimeSteps { param, at, .. }
                    if *param == "lambda" =>
                {
                    Some(*at)
                }
                _ => None,
            },
        }
    }

    /// The error, for [`Stop::Failed`].
    pub fn error(&self) -> Option<&Error> {
        match self {
            Stop::Failed(e) => Some(e),
            _ => None,
        }
    }

    /// Whether the path reached its target.
    pub fn is_end(&self) -> bool {
        matches!(self, Stop::End { .. })
    }
}

/// A stop is repeated by every [`super::path::Path::step`] after the path
/// ended; `Error` is not `Clone` (its I/O variant holds an `io::Error`), so the
/// copy of an I/O error keeps its kind and message.
impl Clone for Stop {
    fn clone(&self) -> Self {
        match self {
            Stop::End { lambda } => Stop::End { lambda: *lambda },
            Stop::MaxSteps { steps, lambda } => Stop::MaxSteps {
                steps: *steps,
                lambda: *lambda,
            },
            Stop::Interrupted { lambda } => Stop::Interrupted { lambda: *lambda },
            Stop::Failed(e) => Stop::Failed(clone_error(e)),
        }
    }
}

/// A copy of `e` (every variant but `Io` clones field by field).
pub fn clone_error(e: &Error) -> Error {
    match e {
        Error::Io { file, source } => Error::Io {
            file: file.clone(),
            source: std::io::Error::new(source.kind(), source.to_string()),
        },
        Error::Parse { file, message } => Error::Parse {
            file: file.clone(),
            message: message.clone(),
        },
        Error::Invalid { file, key, problem } => Error::Invalid {
            file: file.clone(),
            key: key.clone(),
            problem: problem.clone(),
        },
        Error::Mesh {
            file,
            line,
            problem,
        } => Error::Mesh {
            file: file.clone(),
            line: *line,
            problem: problem.clone(),
        },
        Error::Element { element, problem } => Error::Element {
            element: *element,
            problem: problem.clone(),
        },
        Error::Interrupted { param, at } => Error::Interrupted { param, at: *at },
        Error::Stalled { param, at, what } => Error::Stalled {
            param,
            at: *at,
            what: what.clone(),
        },
        Error::SingularMatrix {
            step,
            param,
            at,
            detail,
        } => Error::SingularMatrix {
            step: *step,
            param,
            at: *at,
            detail: detail.clone(),
        },
        Error::NoConvergence {
            step,
            param,
            at,
            iterations,
            residual,
            tolerance,
        } => Error::NoConvergence {
            step: *step,
            param,
            at: *at,
            iterations: *iterations,
            residual: *residual,
            tolerance: *tolerance,
        },
        Error::NonFinite {
            step,
            param,
            at,
            what,
        } => Error::NonFinite {
            step: *step,
            param,
            at: *at,
            what: what.clone(),
        },
        Error::StepCollapse {
            step,
            param,
            at,
            length,
        } => Error::StepCollapse {
            step: *step,
            param,
            at: *at,
            length: *length,
        },
        Error::Write { file, problem } => Error::write(file.clone(), problem),
        Error::Study {
            study,
            case,
            problem,
        } => Error::study(study, case.clone(), problem),
        Error::OffPath {
            step,
            param,
            at,
            what,
        } => Error::OffPath {
            step: *step,
            param,
            at: *at,
            what: what.clone(),
        },
        Error::Resume { file, problem } => Error::Resume {
            file: file.clone(),
            problem: problem.clone(),
        },
        Error::ContactMissed {
            param,
            at,
            node,
            obstacle,
            gap,
            distance,
        } => Error::ContactMissed {
            param,
            at: *at,
            node: *node,
            obstacle: *obstacle,
            gap: *gap,
            distance: *distance,
        },
        Error::TimeSteps {
            param,
            at,
            node,
            what,
        } => Error::TimeSteps {
            param,
            at: *at,
            node: *node,
            what: what.clone(),
        },
    }
}

impl From<Error> for Stop {
    fn from(e: Error) -> Self {
        Stop::Failed(e)
    }
}

/// `stop == "end"`: compares [`Stop::reason`].
impl PartialEq<&str> for Stop {
    fn eq(&self, other: &&str) -> bool {
        self.reason() == *other
    }
}

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stop::End { lambda } => write!(f, "end at lambda = {lambda}"),
            Stop::MaxSteps { steps, lambda } => {
                write!(f, "max_steps = {steps} reached at lambda = {lambda}")
            }
            Stop::Interrupted { lambda } => write!(f, "interrupted at lambda = {lambda}"),
            Stop::Failed(e) => write!(f, "{e}"),
        }
    }
}
