//! Errors of the controller's construction (a running controller never errs: it falls back).

use thiserror::Error;

/// What can go wrong when a controller is built from a plant and settings.
#[derive(Debug, Error)]
pub enum MpcError {
    /// A setting is out of its range; names the setting and what was expected.
    #[error("setting `{key}`: {message}")]
    Setting {
        /// The setting's name, e.g. `inputs[1].max_Nm`.
        key: String,
        /// What was expected.
        message: String,
    },
    /// A signal name in the settings that the plant does not have.
    #[error("`{key}`: the plant has no {kind} `{name}` (it has: {available})")]
    UnknownSignal {
        /// The setting's name.
        key: String,
        /// "input" or "output".
        kind: &'static str,
        /// The name asked for.
        name: String,
        /// The names the plant has.
        available: String,
    },
    /// A numerical step failed (Riccati iteration, singular target equations, …).
    #[error("{0}")]
    Numerical(String),
    /// The plant model could not be discretised.
    #[error(transparent)]
    Plant(#[from] plant::error::PlantError),
    /// Clarabel refused the problem data.
    #[error("QP solver: {0}")]
    Solver(String),
}

/// Result with [`MpcError`].
pub type Result<T> = std::result::Result<T, MpcError>;

pub(crate) fn setting(key: impl Into<String>, message: impl Into<String>) -> MpcError {
    MpcError::Setting { key: key.into(), message: message.into() }
}
