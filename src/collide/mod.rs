//! collide (placeholder)
