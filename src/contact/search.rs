//! Contact search (being written).
