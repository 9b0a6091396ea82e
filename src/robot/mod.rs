//! robot (placeholder)
