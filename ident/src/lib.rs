//! # ident — identification on top of `plant`
//!
//! - [`sweep`]: the natural frequency of a torsional rig from a sine sweep — the paper's
//!   procedure (section 3) and a modal fit of the frequency response — with uncertainties, and
//!   which mode was seen (section 4.4).
//! - [`parametrise`]: j_drive and c_short from the natural frequencies of two or more variants
//!   (sections 2.3, 3; Tables 4, 5), every real positive solution of every pair, the
//!   least-squares estimate, linearised and Monte Carlo confidence intervals.
//! - [`design`]: which additional spring and which variants make the two identifiable.
//! - [`bearing`]: bearing/seal impedances from two shake tests, the direct curve fit and the
//!   instrumental variable filter method (San Andrés 2011).
#![warn(missing_docs)]

pub mod bearing;
pub mod design;
pub mod diagnose;
pub mod error;
pub mod parametrise;
pub mod signal;
pub mod sweep;

pub use bearing::{BearingFit, Coupling, Impedances, IvfmSettings, Method, ShakeTest, Structure, R2};
pub use design::{design_spring, Design, DesignRow, DesignSettings};
pub use error::{IdentError, Result};
pub use parametrise::{
    Confidence, Estimate, Measurement, ModelChoice, MonteCarlo, PairSolution, Parametrisation, ParametriseSettings,
    MAX_MONTE_CARLO_SAMPLES,
};
pub use sweep::{FrequencyEstimate, SeenMode, Sweep, SweepAnalysis, SweepSettings};
