//! (placeholder: filled in below)
