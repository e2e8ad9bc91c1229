//! (geometry: being written)
