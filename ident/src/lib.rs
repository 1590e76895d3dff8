//! # ident — identification on top of `plant`
//!
//! - [`sweep`]: the natural frequency of a torsional rig from a sine sweep — the paper's
//!   procedure (section 3) and a modal fit of the frequency response — with uncertainties, and
//!   which mode was seen (section 4.4).
#![warn(missing_docs)]

pub mod error;
pub mod signal;
pub mod sweep;

pub use error::{IdentError, Result};
pub use sweep::{FrequencyEstimate, SeenMode, Sweep, SweepAnalysis, SweepSettings};
