//! rigtwin: the command-line tool's library side — the rig file format and the reports the
//! commands print. The physics is in the `plant` crate.
pub mod bearing;
pub mod bundle;
pub mod control;
pub mod diagnosis;
pub mod files;
pub mod fmu_package;
pub mod identification;
pub mod plot;
pub mod progress;
pub mod report;
pub mod units;
