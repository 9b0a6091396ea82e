//! garment (placeholder)
