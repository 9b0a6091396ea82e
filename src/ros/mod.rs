//! ros (placeholder)
