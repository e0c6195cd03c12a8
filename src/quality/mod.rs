//! How good a mask is as an eye would see it: the perceptual filter (`eye`),
//! the animated integrands it is judged on (`integrands`), a mask's perceived
//! error (`perceived`) and the relative errors of a render (`metric`).
pub mod eye;
pub(crate) mod integrands;
pub mod metric;
pub mod perceived;
