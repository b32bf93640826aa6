//! Closed-form reference solutions, one file per source.
