//! effects (placeholder)
