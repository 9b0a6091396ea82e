//! integrate (placeholder)
