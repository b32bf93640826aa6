//! Mesh generators. (stub: being written)
