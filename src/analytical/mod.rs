//! Closed-form reference solutions, one file per source.

pub mod cook;
pub mod hill;
pub mod creep;
pub mod j2;
pub mod creep_ramp;
pub mod bar_wave;
pub mod hertz;
