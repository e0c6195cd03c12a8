//! Evaluation: render animated integrands with a mask's samples, filter the error
//! as a display (TAA) and an eye would, and measure what is left.
pub mod anatomy;
pub mod flip;
pub mod jod;
pub mod pictures;
pub mod render;
pub mod robustness;
pub mod scenes;
pub mod spectrum;
pub mod stats;
pub mod suite;
