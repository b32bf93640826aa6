//! Mesh quality measures. (stub: being written)
