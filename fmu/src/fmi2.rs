//! FMI 2.0 glue (filled in below).
