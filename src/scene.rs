//! (scene: being written)
