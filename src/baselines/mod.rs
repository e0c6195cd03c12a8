//! The peers' methods, made by fsot on the same tile, the same way: the masks fsot
//! is measured against.
pub mod fast;
pub mod stbn;
pub mod swap;
