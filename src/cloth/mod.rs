//! cloth (placeholder)
