//! Errors of the library. Every variant carries the values a user needs to
//! find the problem: the file and key for input, the step and time or lambda
//! (and node, where there is one) for numerical trouble.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file system error, reading or writing (review 23: a full disk
    /// was reported as "cannot read"); the source says what failed.
    #[error("{file}: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: {message}")]
    Parse { file: PathBuf, message: String },
    #[error("{file}: key `{key}`: {problem}")]
    Invalid {
        file: PathBuf,
        key: String,
        problem: String,
    },
    #[error("{file}:{line}: {problem}")]
    Mesh {
        file: PathBuf,
        line: usize,
        problem: String,
    },
    #[error("element {element}: {problem}")]
    Element { element: usize, problem: String },
    #[error("step {step}, {param} = {at:.9e}: the tangent matrix could not be factored ({detail})")]
    SingularMatrix {
        step: usize,
        param: &'static str,
        at: f64,
        detail: String,
    },
    #[error(
        "step {step}, {param} = {at:.9e}: no convergence after {iterations} iterations (residual {residual:.3e}, tolerance {tolerance:.1e}){hint}",
        hint = floor_hint(*.residual, *.tolerance)
    )]
    NoConvergence {
        step: usize,
        param: &'static str,
        at: f64,
        iterations: usize,
        residual: f64,
        tolerance: f64,
    },
    #[error("step {step}, {param} = {at:.9e}: non-finite value in {what}")]
    NonFinite {
        step: usize,
        param: &'static str,
        at: f64,
        what: String,
    },
    /// The path goes on but no longer advances: steps many orders shorter
    /// than its first, one after another.
    #[error("{param} = {at:.9e}: {what}")]
    Stalled {
        param: &'static str,
        at: f64,
        what: String,
    },
    #[error("step {step}, {param} = {at:.9e}: step length collapsed to {length:.3e}")]
    StepCollapse {
        step: usize,
        param: &'static str,
        at: f64,
        length: f64,
    },
    /// An output file could not be written (or would hold a non-finite value).
    #[error("{file}: cannot write: {problem}")]
    Write { file: PathBuf, problem: String },
    /// A run of a study (audit, bench, stress, scaling) failed.
    #[error("{study}: {case}: {problem}")]
    Study {
        study: &'static str,
        case: String,
        problem: String,
    },
    /// A value asked of an accepted step lies on neither its series nor its
    /// correction.
    #[error("step {step}, {param} = {at:.9e}: {what}")]
    OffPath {
        step: usize,
        param: &'static str,
        at: f64,
        what: String,
    },
    /// An output folder cannot be resumed from.
    #[error("{file}: cannot resume: {problem}")]
    Resume { file: PathBuf, problem: String },
    #[error("{param} = {at:.9e}: interrupted (Ctrl-C or SIGTERM)")]
    Interrupted { param: &'static str, at: f64 },
    #[error(
        "{param} = {at:.9e}: contact node {node} came to {gap:.3e} m of obstacle {obstacle} within one step while outside the search distance {distance:.3e} m (increase contact.search_distance)"
    )]
    ContactMissed {
        param: &'static str,
        at: f64,
        node: usize,
        obstacle: usize,
        gap: f64,
        distance: f64,
    },
    /// A run in time spent its step budget, or its steps collapsed: where
    /// and what limits them.
    #[error("{param} = {at:.9e}: {what}")]
    TimeSteps {
        param: &'static str,
        at: f64,
        /// The node the diagnosis names, if any (its tag).
        node: Option<usize>,
        what: String,
    },
}

impl Error {
    /// A failed write of `file`.
    pub fn write(file: impl Into<PathBuf>, problem: impl ToString) -> Self {
        Error::Write {
            file: file.into(),
            problem: problem.to_string(),
        }
    }

    /// A failed run of a study.
    pub fn study(study: &'static str, case: impl Into<String>, problem: impl ToString) -> Self {
        Error::Study {
            study,
            case: case.into(),
            problem: problem.to_string(),
        }
    }

    /// Short machine-readable kind, used as `stop.reason` in summary.json.
    pub fn kind(&self) -> &'static str {
        match self {
            Error::Io { .. } => "io",
            Error::Parse { .. } => "parse",
            Error::Invalid { .. } => "invalid_input",
            Error::Mesh { .. } => "mesh",
            Error::Element { .. } => "element",
            Error::SingularMatrix { .. } => "singular_matrix",
            Error::NoConvergence { .. } => "no_convergence",
            Error::NonFinite { .. } => "non_finite",
            Error::StepCollapse { .. } => "step_collapse",
            Error::Stalled { .. } => "stalled",
            Error::Write { .. } => "write",
            Error::Study { .. } => "study",
            Error::OffPath { .. } => "off_path",
            Error::Resume { .. } => "resume",
            Error::ContactMissed { .. } => "contact_missed",
            Error::TimeSteps { .. } => "time_steps",
            Error::Interrupted { .. } => "interrupted",
        }
    }

    /// The time or load parameter where numerical trouble arose (None for
    /// other errors).
    pub fn at(&self) -> Option<f64> {
        match self {
            Error::SingularMatrix { at, .. }
            | Error::NoConvergence { at, .. }
            | Error::NonFinite { at, .. }
            | Error::StepCollapse { at, .. }
            | Error::Stalled { at, .. }
            | Error::OffPath { at, .. }
            | Error::Interrupted { at, .. }
            | Error::ContactMissed { at, .. }
            | Error::TimeSteps { at, .. } => Some(*at),
            _ => None,
        }
    }

    /// The node numerical trouble is located at, where the error names one:
    /// its tag (`ShellModel::node_tag`, the number the mesh file gives it).
    pub fn node(&self) -> Option<usize> {
        match self {
            Error::ContactMissed { node, .. } => Some(*node),
            Error::TimeSteps { node, .. } => *node,
            _ => None,
        }
    }

    /// Numerical trouble a shorter step may avoid (as opposed to bad input
    /// or an output failure).
    pub fn is_numerical(&self) -> bool {
        matches!(
            self,
            Error::NoConvergence { .. }
                | Error::SingularMatrix { .. }
                | Error::NonFinite { .. }
                | Error::ContactMissed { .. }
        )
    }
}

pub type Result<T> = std::result::Result<T, Error>;

/// What a Newton iteration that stalled just above its tolerance most
/// likely met: the round-off floor of the residual (fine or thin meshes,
/// stiff penalties), which `solver.residual_tol` must lie above (review
/// 14: an 800-element arch stalled at 1.9e-6 against 1e-6 and ran with
/// 1e-5).
fn floor_hint(residual: f64, tolerance: f64) -> String {
    if residual.is_finite() && residual > tolerance && residual <= 100.0 * tolerance {
        format!(
            ": it stalled within {:.0}x of solver.residual_tol, likely the round-off floor of this problem's residual; a larger solver.residual_tol lets the run go on",
            (residual / tolerance).ceil()
        )
    } else {
        String::new()
    }
}
