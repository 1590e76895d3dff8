//! The one error type of the crate: what was wrong with which input.

use thiserror::Error;

/// Setup error: an input that cannot describe a physical system.
///
/// `field` names the offending parameter the way a rig file spells it
/// (`model.j_m2`, `chain.bodies[3].j_kgm2`), so a caller can pass it on unchanged.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlantError {
    /// A quantity that must be strictly positive and finite was not.
    #[error("`{field}` must be a positive, finite number of {unit}, got {value}")]
    NotPositive {
        /// Parameter name.
        field: String,
        /// Offending value.
        value: f64,
        /// SI unit of the parameter.
        unit: &'static str,
    },
    /// A quantity that must be non-negative and finite was not.
    #[error("`{field}` must be a non-negative, finite number of {unit}, got {value}")]
    Negative {
        /// Parameter name.
        field: String,
        /// Offending value.
        value: f64,
        /// SI unit of the parameter.
        unit: &'static str,
    },
    /// A 1-based position outside its list.
    #[error("`{field}` = {index} is out of range: expected a position from {min} to {max}")]
    OutOfRange {
        /// Parameter name.
        field: String,
        /// Offending position.
        index: usize,
        /// Smallest allowed position.
        min: usize,
        /// Largest allowed position.
        max: usize,
    },
    /// Any other inconsistency, described in words.
    #[error("{0}")]
    Invalid(String),
    /// A numerical procedure failed (e.g. an inertia matrix that is not positive definite).
    #[error("numerical failure: {0}")]
    Numerical(String),
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, PlantError>;

// The key names below are closures: they are formatted only when the check fails, so a hot
// loop that validates candidate parameters pays nothing for them.

/// `value` must be > 0 and finite.
pub(crate) fn positive<K: Into<String>>(field: impl FnOnce() -> K, value: f64, unit: &'static str) -> Result<f64> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(PlantError::NotPositive { field: field().into(), value, unit })
    }
}

/// `value` must be >= 0 and finite.
pub(crate) fn non_negative<K: Into<String>>(field: impl FnOnce() -> K, value: f64, unit: &'static str) -> Result<f64> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(PlantError::Negative { field: field().into(), value, unit })
    }
}

/// A 1-based `index` must lie in `min..=max`.
pub(crate) fn in_range<K: Into<String>>(
    field: impl FnOnce() -> K,
    index: usize,
    min: usize,
    max: usize,
) -> Result<usize> {
    if (min..=max).contains(&index) {
        Ok(index)
    } else {
        Err(PlantError::OutOfRange { field: field().into(), index, min, max })
    }
}
