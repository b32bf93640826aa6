//! Logarithmic strain tools. (stub: being written)
