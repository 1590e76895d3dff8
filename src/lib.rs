//! rigtwin: the command-line tool's library side — file formats and reports.
pub mod rigfile;
