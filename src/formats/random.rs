//! Random particle sets (placeholder).
