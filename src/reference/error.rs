//! Errors of the reference solvers: a failed SUNDIALS call, with the return
//! flag's name, the time reached and SUNDIALS' own message; a diffsol error
//! with its message; bad input, naming the option.

/// What went wrong in an IDA run.
#[derive(Debug, Clone, thiserror::Error)]
pub enum IdaError {
    /// A SUNDIALS function returned a negative flag.
    #[error("{function} returned {name} ({flag}) at t = {t:.12e} s{}", message.as_ref().map(|m| format!(": {m}")).unwrap_or_default())]
    Flag {
        function: &'static str,
        flag: i32,
        name: String,
        t: f64,
        /// The last message SUNDIALS reported through its error handler.
        message: Option<String>,
    },
    /// A constructor returned NULL (out of memory or bad arguments).
    #[error("{function} returned NULL")]
    Null { function: &'static str },
    /// Bad input before any SUNDIALS call.
    #[error("{0}")]
    Input(String),
    /// diffsol returned an error at time t (its message says which limit or
    /// failure).
    #[error("diffsol: {message} (at t = {t:.12e} s)")]
    Diffsol { message: String, t: f64 },
    /// A non-finite value in the solution at time t.
    #[error("non-finite value in {what} at t = {t:.12e} s")]
    NonFinite { what: String, t: f64 },
}

impl IdaError {
    /// The time of a failed call (None for setup errors).
    pub fn time(&self) -> Option<f64> {
        match self {
            IdaError::Flag { t, .. }
            | IdaError::NonFinite { t, .. }
            | IdaError::Diffsol { t, .. } => Some(*t),
            _ => None,
        }
    }

    /// A short name for summary.json: the flag name, or the error kind.
    pub fn reason(&self) -> String {
        match self {
            IdaError::Flag { name, .. } => name.clone(),
            IdaError::Null { .. } => "null".into(),
            IdaError::Input(_) => "input".into(),
            IdaError::NonFinite { .. } => "non_finite".into(),
            IdaError::Diffsol { .. } => "diffsol_error".into(),
        }
    }
}
