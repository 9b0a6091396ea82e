//! mesh (placeholder)
