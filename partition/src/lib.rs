//! Graph partitioning (stub)
