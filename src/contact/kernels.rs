//! Contact kernels (being written).
