//! The math both backends share: the tile (`tile`), the mask (`mask`), the
//! counter-based random numbers (`rng`), the kernels (`kernel`) with the eye's
//! spatial filter at a display (`display`: its viewing geometry; `csf`: the
//! contrast sensitivity there), a slice of the
//! stochastic step (`slice`), the exact 1-D targets (`targets`), the transport
//! rule of one slice (`transport`), the objective on fixed slices (`objective`)
//! and the update step (`step_rule`).
pub(crate) mod csf;
pub mod animate;
pub mod display;
pub mod kernel;
pub mod mask;
pub mod objective;
pub mod rng;
pub mod slice;
pub mod step_rule;
pub mod targets;
pub mod tile;
pub mod transport;
