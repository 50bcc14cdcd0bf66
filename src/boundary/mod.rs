//! Phase-boundary extraction.
