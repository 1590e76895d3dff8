//! The crate's error type.

use thiserror::Error;

/// Why an identification could not be done.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum IdentError {
    /// The plant rejected a parameter.
    #[error(transparent)]
    Plant(#[from] plant::PlantError),
    /// The signals cannot carry the analysis (too short, not excited, not finite ...).
    #[error("{0}")]
    Data(String),
    /// Inputs that contradict each other.
    #[error("{0}")]
    Invalid(String),
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, IdentError>;
